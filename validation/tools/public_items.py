#!/usr/bin/env python3
"""Counts the public items of the `gmueller` API per module, from the rustdoc HTML.

Run `cargo doc --no-deps` first (without features: the `verify` kit is not counted), then
`python3 validation/tools/public_items.py [target/doc/gmueller]`. An item is a page rustdoc
writes for it (struct, enum, trait, fn, type, constant, static, macro, union): items reached
through a `pub use` of a public module are counted once, where they are defined; items of
private modules that are re-exported are counted where rustdoc inlines them. Methods are not
items here (they live on their type's page).
"""
import collections
import os
import sys

KINDS = ("struct.", "enum.", "trait.", "fn.", "type.", "constant.", "static.", "macro.", "union.")


def main() -> None:
    root = sys.argv[1] if len(sys.argv) > 1 else "target/doc/gmueller"
    counts = collections.Counter()
    for dirpath, _dirs, files in os.walk(root):
        module = os.path.relpath(dirpath, root).replace(os.sep, "::")
        top = "(root)" if module == "." else module.split("::")[0]
        for f in files:
            if f.endswith(".html") and f.startswith(KINDS):
                counts[top] += 1
    total = sum(counts.values())
    for module, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])):
        print(f"{module:14} {n:4}")
    print(f"{'total':14} {total:4}")


if __name__ == "__main__":
    main()
