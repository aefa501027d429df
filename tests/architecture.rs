//! The module graph of `docs/architecture.md`, checked against the source: every `crate::…`
//! (and, inside `interaction`, `super::…`) path in code — not in comments or docs — must point
//! to a module *below* the one that uses it in the documented order. A new import that runs up
//! the stack, or a cycle, fails here with the file and the line.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The crate's top-level modules, bottom first (`docs/architecture.md`).
const LAYERS: &[&str] = &[
    "simd",
    "real",
    "error",
    "numerics",
    "stack",
    "jones",
    "stokes",
    "mueller",
    "frame",
    "fresnel",
    "spectral",
    "gaussian",
    "packet",
    "propagation",
    "psd",
    "matter",
    "interaction",
    "bsdf",
    "medium",
    "verify",
    "prelude",
    "guide",
];

/// The submodules of `interaction`, bottom first.
const INTERACTION: &[&str] = &[
    "geometry",
    "section",
    "attenuation",
    "coherence",
    "roughness",
    "pbsdf",
    "material",
    "prepared",
    "polarization",
    "kernel",
    "level",
    "exitant",
    "sampling",
    "batch",
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("readable src dir") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The code of a line: `None` for comment and doc lines, the part before a trailing `//` else.
fn code(line: &str) -> Option<&str> {
    let t = line.trim_start();
    if t.starts_with("//") || t.starts_with("#![doc") || t.starts_with("#[doc") {
        return None;
    }
    Some(line.split("//").next().unwrap_or(line))
}

/// Every identifier that follows `prefix` in `code` (`crate::psd::Psd` → `psd`), including
/// the names of a brace group right after the prefix (`super::{coherence, geometry}`).
fn targets(code: &str, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        // Not part of a longer path segment such as `my_crate::`.
        let before = rest[..i].chars().last();
        rest = &rest[i + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
    }
    out
}

/// The top-level module and (for `interaction`) the submodule a source file belongs to.
fn owner(src: &Path, file: &Path) -> (String, Option<String>) {
    let rel = file.strip_prefix(src).expect("file under src");
    let parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_owned())
        .collect();
    let top = parts[0].clone();
    let sub = if top == "interaction" && parts.len() > 1 && parts[1] != "mod" {
        Some(parts[1].clone())
    } else {
        None
    };
    (top, sub)
}

fn rank(order: &[&str], name: &str) -> Option<usize> {
    order.iter().position(|m| *m == name)
}

#[test]
fn every_import_points_down_the_documented_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut violations = Vec::new();
    let mut edges: BTreeMap<(String, String), usize> = BTreeMap::new();
    for file in &files {
        let (top, sub) = owner(&src, file);
        if top == "lib" {
            continue; // the crate root declares the modules
        }
        let Some(from) = rank(LAYERS, &top) else {
            violations.push(format!(
                "{}: module `{top}` is not in LAYERS",
                file.display()
            ));
            continue;
        };
        let text = fs::read_to_string(file).expect("readable source");
        for (n, line) in text.lines().enumerate() {
            let Some(code) = code(line) else { continue };
            for target in targets(code, "crate::") {
                let Some(to) = rank(LAYERS, &target) else {
                    continue; // an item of the crate root (`crate::Error`) or a macro path
                };
                *edges.entry((top.clone(), target.clone())).or_default() += 1;
                if to > from {
                    violations.push(format!(
                        "{}:{}: `{top}` imports `{target}`, which is above it",
                        file.display(),
                        n + 1
                    ));
                }
            }
            // Inside `interaction`, sibling imports go through `super::` (or
            // `crate::interaction::`): check them against the submodule order.
            let Some(sub) = &sub else { continue };
            let Some(from_sub) = rank(INTERACTION, sub) else {
                violations.push(format!(
                    "{}: submodule `{sub}` is not in INTERACTION",
                    file.display()
                ));
                continue;
            };
            let depth = file
                .strip_prefix(src.join("interaction"))
                .map_or(0, |p| p.iter().count());
            // `super::` from interaction/x.rs is `interaction`; from interaction/x/y.rs it is
            // `x` (its own module): only the former names siblings.
            let siblings = if depth == 1 {
                targets(code, "super::")
            } else {
                targets(code, "super::super::")
            };
            for target in siblings
                .into_iter()
                .chain(targets(code, "crate::interaction::"))
            {
                let Some(to) = rank(INTERACTION, &target) else {
                    continue; // a re-exported item (`super::Geometry`)
                };
                if to > from_sub {
                    violations.push(format!(
                        "{}:{}: `interaction::{sub}` imports `interaction::{target}`, which is \
                         above it",
                        file.display(),
                        n + 1
                    ));
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "imports against the layers of docs/architecture.md:\n{}",
        violations.join("\n")
    );
    // The check saw the crate's real structure (a parser that found nothing would pass).
    for (from, to) in [
        ("interaction", "psd"),
        ("psd", "gaussian"),
        ("mueller", "jones"),
    ] {
        assert!(
            edges.contains_key(&(from.to_owned(), to.to_owned())),
            "expected an import {from} → {to}; found {edges:?}"
        );
    }
}

#[test]
fn the_parser_sees_groups_and_ignores_comments() {
    assert_eq!(
        targets("use super::{coherence::X, geometry};", "super::"),
        ["coherence", "geometry"]
    );
    assert_eq!(targets("let x = crate::psd::two_pi();", "crate::"), ["psd"]);
    assert_eq!(
        targets("use my_crate::psd;", "crate::"),
        Vec::<String>::new()
    );
    assert_eq!(code("    /// see [`crate::interaction`]"), None);
    assert_eq!(code("let a = 1; // crate::x"), Some("let a = 1; "));
}
