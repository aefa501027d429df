"""Mitsuba 3 peer: Fresnel-reflection Mueller matrix, mi.mueller.specular_reflection(cos_theta_i, eta).

The PyPI wheels ship no *_rgb_polarized variant; the polarized ones are scalar_spectral_polarized,
llvm_ad_mono_polarized and llvm_ad_spectral_polarized (and CUDA ones), all single precision. So:
  * scalar_spectral_polarized: one Python call per matrix (a Python float cos_theta_i), cycling
    through 1024 precomputed cosines in [0.01, 1];
  * llvm_ad_mono_polarized: one call on a batch of N lanes (N = 1024 and 65536; cos_theta_i an
    evaluated mi.Float), the result forced with dr.eval + dr.sync_thread inside the timing, with
    dr.set_thread_count(1) before the first kernel. Reported per lane. The kernel is compiled in
    the warm-up calls and taken from Dr.Jit's kernel cache afterwards (tracing is still timed).
eta = 1.5 + 0i (glass; Mitsuba takes a complex eta, so a conductor costs the same).
Before timing, M00 is checked against the Fresnel reflectance (|r_s|^2 + |r_p|^2)/2 computed here.
Run by validation/peers/run.sh.
"""

import cmath
import sys

import numpy as np

from _timing import bench, row, skip

PEER = "Mitsuba 3"
OP = "Fresnel reflection Mueller, mi.mueller.specular_reflection"
ETA = 1.5


def fresnel_m00(cos_i, eta):
    """(|r_s|^2 + |r_p|^2) / 2 for a real eta, from Snell's law and the Fresnel equations."""
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = cmath.sqrt(1.0 - sin2_t)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (abs(rs) ** 2 + abs(rp) ** 2)


try:
    import drjit as dr
    import mitsuba as mi
except Exception as e:  # noqa: BLE001
    skip(PEER, OP, f"import failed: {e!r}")
    sys.exit(0)

rng = np.random.default_rng(3)
cosines = [float(c) for c in rng.uniform(0.01, 1.0, 1024)]

# --- scalar -------------------------------------------------------------------------------------
try:
    mi.set_variant("scalar_spectral_polarized")
    fn = mi.mueller.specular_reflection
    m = fn(0.6, ETA)
    m00 = m[0, 0]
    m00 = float(m00[0] if hasattr(m00, "__len__") else m00)
    if abs(m00 - fresnel_m00(0.6, ETA)) > 1e-6:
        raise RuntimeError(f"M00 = {m00}, expected {fresnel_m00(0.6, ETA)}")

    def sweep():
        for c in cosines:
            fn(c, ETA)

    med, lo = bench(sweep, len(cosines), warmup=1, samples=11, max_total_s=6.0)
    row(PEER, OP + " [scalar_spectral_polarized]", "f32", 1, med, lo, "per Python call")
except Exception as e:  # noqa: BLE001
    skip(PEER, OP + " [scalar_spectral_polarized]", repr(e))

# --- LLVM ---------------------------------------------------------------------------------------
try:
    mi.set_variant("llvm_ad_mono_polarized")
    dr.set_thread_count(1)
    if dr.thread_count() != 1:
        raise RuntimeError(f"dr.thread_count() = {dr.thread_count()} after set_thread_count(1)")
    fn = mi.mueller.specular_reflection
    eta = mi.Complex2f(ETA, 0.0) if hasattr(mi, "Complex2f") else ETA
    for n in (1024, 65536):
        c_np = rng.uniform(0.01, 1.0, n).astype(np.float32)
        x = mi.Float(c_np)
        dr.eval(x)
        m = fn(x, eta)
        dr.eval(m)
        got = np.asarray(m[0, 0]).ravel()[:8]
        want = [fresnel_m00(float(c), ETA) for c in c_np[:8]]
        if not np.allclose(got, want, rtol=1e-5, atol=1e-6):
            raise RuntimeError(f"M00 {got} != {want}")

        def call():
            r = fn(x, eta)
            dr.eval(r)
            dr.sync_thread()

        med, lo = bench(call, n, warmup=5, samples=21, max_total_s=6.0)
        row(PEER, OP + " [llvm_ad_mono_polarized, 1 thread]", "f32", n, med, lo,
            "per lane; dr.eval inside timing")
except Exception as e:  # noqa: BLE001
    skip(PEER, OP + " [llvm_ad_mono_polarized]", repr(e))
