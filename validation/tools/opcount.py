#!/usr/bin/env python3
"""Per-call counts of chosen machine instructions (divisions, square roots, the most frequent
ones) of a counting example, from two callgrind runs that differ only in their repetitions.

    cargo build --release --example batch_count
    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=/tmp/c1 \
        target/release/examples/batch_count f32 1
    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=/tmp/c2 \
        target/release/examples/batch_count f32 2
    python3 validation/tools/opcount.py target/release/examples/batch_count /tmp/c1 /tmp/c2 65536

The last argument is the number of calls the second run adds (65,536 exits per pass of
`batch_count`). Only instructions of the example's own binary are counted (not libm's).
Addresses are matched to `objdump -d` of the binary, which valgrind loads at 0x108000 (a
position-independent executable) or at its link address. Used for issue 39 (2026-12-06):
under valgrind (AVX2) the f32 batch kernel took 2.27 `vdivps` and 0.52 `vsqrtps` per
direction, that is 18 and 4 per 8-lane vector.
"""
import sys, re, subprocess, collections
binp, cg1, cg2, n = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
dis = {}
out = subprocess.run(["objdump", "-d", "--no-show-raw-insn", binp], capture_output=True, text=True).stdout
for line in out.splitlines():
    m = re.match(r"\s*([0-9a-f]+):\s+(\S+)", line)
    if m: dis[int(m.group(1), 16)] = m.group(2)
def counts(f):
    c = collections.Counter(); addr = 0; ob = ""; skip = False; obs = {}
    for line in open(f):
        m = re.match(r"(c?ob)=\((\d+)\)\s*(.*)", line.strip())
        if m:
            if m.group(3): obs[m.group(2)] = m.group(3)
            if m.group(1) == "ob": ob = obs.get(m.group(2), "")
            continue
        if line.startswith("calls="): skip = True; continue
        if not line or line[0] not in "0123456789+-*": continue
        parts = line.split()
        a = parts[0]
        if a.startswith("0x"): addr = int(a, 16)
        elif a.startswith("+"): addr += int(a[1:])
        elif a.startswith("-"): addr -= int(a[1:])
        if skip: skip = False; continue
        if len(parts) >= 3 and "batch_count" in ob:
            c[addr] += int(parts[2])
    return c
c1, c2 = counts(cg1), counts(cg2)
agg = collections.Counter()
for a in set(c1) | set(c2):
    agg[dis.get(a - 0x108000, dis.get(a, "?"))] += c2.get(a, 0) - c1.get(a, 0)
print(f"instr/dir {sum(agg.values())/n:.1f}")
for k in sorted(agg):
    if re.match(r"v?(div|sqrt)[sp][sd]", k) and agg[k]: print(k, f"{agg[k]/n:.3f} per dir")
print(" ".join(f"{k}:{v/n:.1f}" for k, v in agg.most_common(14)))
