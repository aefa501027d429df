"""py-pol peer: Jones -> Mueller for a vectorised batch of N random Jones matrices.

Builds a py_pol Jones_matrix object holding N matrices (components uniform in [-1, 1) + i[-1, 1),
complex128), then times `Mueller().from_Jones(J)` (py-pol's numpy-vectorised conversion, which
also computes the global phase of J) for N = 1, 1024, 65536. Input construction is outside the
timing. Before timing, py-pol's M00 and M11 are checked against 1/2 sum |J_ij|^2 and
1/2 (|a|^2 - |b|^2 - |c|^2 + |d|^2), which hold in every Pauli ordering.
Run by validation/peers/run.sh.
"""

import sys

import numpy as np

from _timing import bench, row, skip

PEER = "py-pol"
OP = "Jones->Mueller, Mueller().from_Jones(J)"

try:
    from py_pol.jones_matrix import Jones_matrix
    from py_pol.mueller import Mueller
except Exception as e:  # noqa: BLE001 - report any import failure as a skip
    skip(PEER, OP, f"import failed: {e!r}")
    sys.exit(0)

rng = np.random.default_rng(20240601)

for n in (1, 1024, 65536):
    comps = [rng.uniform(-1, 1, n) + 1j * rng.uniform(-1, 1, n) for _ in range(4)]
    jm = Jones_matrix("J").from_components(comps)
    m = Mueller("M").from_Jones(jm)
    mm = np.asarray(m.M).reshape(4, 4, n)
    a, b, c, d = comps
    m00 = 0.5 * (abs(a) ** 2 + abs(b) ** 2 + abs(c) ** 2 + abs(d) ** 2)
    m11 = 0.5 * (abs(a) ** 2 - abs(b) ** 2 - abs(c) ** 2 + abs(d) ** 2)
    if not (np.allclose(mm[0, 0], m00, rtol=1e-12, atol=1e-14)
            and np.allclose(mm[1, 1], m11, rtol=1e-12, atol=1e-14)):
        skip(PEER, OP, f"py-pol result failed the M00/M11 check at N={n}")
        continue
    med, lo = bench(lambda: Mueller("M").from_Jones(jm), n,
                    samples=21 if n < 65536 else 11, max_total_s=8.0)
    row(PEER, OP, "f64", n, med, lo, "numpy-vectorised; per matrix" if n > 1 else "one call")
