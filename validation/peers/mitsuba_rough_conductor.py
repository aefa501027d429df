"""Mitsuba 3 peer: polarized rough-conductor BSDF, bsdf.eval(ctx, si, wo), vectorised over lanes.

Variant llvm_ad_spectral_polarized (f32), dr.set_thread_count(1) before the first kernel (checked).
BSDF: mi.load_dict({'type': 'roughconductor', 'distribution': 'beckmann', 'alpha': 0.1,
'material': 'Au'}), i.e. isotropic Beckmann microfacets (sample_visible is irrelevant to eval) and
Mitsuba's built-in gold: eta and k are 56-node tabulated spectra (IrregularSpectrum) interpolated
at each lane's wavelengths inside the timed kernel.
Input, one SurfaceInteraction3f with N lanes (N = 1024 and 65536): shading normal +z
(sh_frame = Frame3f(+z)), si.wi fixed at theta_i = 30 deg (phi = 0), si.wavelengths random in
[400, 700] nm. Mitsuba's spectral variants carry 4 wavelengths per lane (checked), so each lane
yields a 4x4 Mueller matrix per wavelength (4 matrices per lane). wo: N precomputed random
directions, uniform on the upper hemisphere (local frame), as an evaluated mi.Vector3f.
ctx = mi.BSDFContext(). One call bsdf.eval(ctx, si, wo) is timed with dr.eval(result) +
dr.sync_thread() inside the timing; the kernel is compiled in the warm-up calls and taken from
Dr.Jit's kernel cache afterwards (tracing and launch are still timed). Reported per lane.
Before timing: M00 is checked to be finite and positive at the specular direction for all 4
wavelengths, and at least 1e6 times smaller at the retro-reflection direction wo = wi (60 deg away);
M00 of the timed batch must be finite and >= 0.
Run by validation/peers/run.sh.
"""

import math
import sys

import numpy as np

from _timing import bench, row, skip

PEER = "Mitsuba 3"
OP = "polarized rough conductor BSDF eval (Beckmann, alpha 0.1, Au), roughconductor"
VARIANT = "llvm_ad_spectral_polarized"
THETA_I = math.radians(30.0)

try:
    import drjit as dr
    import mitsuba as mi
except Exception as e:  # noqa: BLE001
    skip(PEER, OP, f"import failed: {e!r}")
    sys.exit(0)

rng = np.random.default_rng(5)


def make_si(n, wavelengths):
    """SurfaceInteraction3f with n lanes, normal +z, wi at THETA_I, the given (4, n) wavelengths."""
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    si.wi = mi.Vector3f(math.sin(THETA_I), 0.0, math.cos(THETA_I))
    wl_type = type(si.wavelengths)
    si.wavelengths = wl_type(*[mi.Float(w) for w in wavelengths])
    dr.eval(si)
    return si


def m00(result):
    """M00 of an eval result as a numpy array of shape (wavelengths, lanes)."""
    return np.asarray(result[0, 0]).reshape(4, -1)


try:
    mi.set_variant(VARIANT)
    dr.set_thread_count(1)
    if dr.thread_count() != 1:
        raise RuntimeError(f"dr.thread_count() = {dr.thread_count()} after set_thread_count(1)")
    bsdf = mi.load_dict({"type": "roughconductor", "distribution": "beckmann", "alpha": 0.1,
                         "material": "Au"})
    ctx = mi.BSDFContext()

    # --- sanity check: lane 0 specular, lane 1 retro-reflection --------------------------------
    si = make_si(2, rng.uniform(400.0, 700.0, (4, 2)).astype(np.float32))
    n_wl = len(si.wavelengths)
    if n_wl != 4:
        raise RuntimeError(f"{n_wl} wavelengths per lane, expected 4")
    s, c = math.sin(THETA_I), math.cos(THETA_I)
    wo = mi.Vector3f(mi.Float([-s, s]), mi.Float([0.0, 0.0]), mi.Float([c, c]))
    r = bsdf.eval(ctx, si, wo)
    dr.eval(r)
    v = m00(r)
    spec, retro = v[:, 0], v[:, 1]
    if not (np.all(np.isfinite(v)) and np.all(spec > 0.0) and np.all(np.abs(retro) < 1e-6 * spec)):
        raise RuntimeError(f"M00 specular {spec}, retro-reflection {retro}")

    for n in (1024, 65536):
        si = make_si(n, rng.uniform(400.0, 700.0, (4, n)).astype(np.float32))
        # Uniform on the upper hemisphere: cos(theta) uniform in (0, 1], phi uniform.
        cos_t = 1.0 - rng.uniform(0.0, 1.0, n)
        sin_t = np.sqrt(1.0 - cos_t * cos_t)
        phi = rng.uniform(0.0, 2.0 * np.pi, n)
        wo = mi.Vector3f(mi.Float((sin_t * np.cos(phi)).astype(np.float32)),
                         mi.Float((sin_t * np.sin(phi)).astype(np.float32)),
                         mi.Float(cos_t.astype(np.float32)))
        dr.eval(wo)
        r = bsdf.eval(ctx, si, wo)
        dr.eval(r)
        v = m00(r)
        if not (np.all(np.isfinite(v)) and np.all(v >= 0.0)):
            raise RuntimeError(f"M00 not finite / negative on the random batch (N = {n})")

        def call():
            res = bsdf.eval(ctx, si, wo)
            dr.eval(res)
            dr.sync_thread()

        med, lo = bench(call, n, warmup=5, samples=21, max_total_s=6.0)
        row(PEER, OP + f" [{VARIANT}, 1 thread]", "f32", n, med, lo,
            "per lane (4 wavelengths per lane, a 4x4 Mueller matrix per wavelength); "
            "dr.eval inside timing")
except Exception as e:  # noqa: BLE001
    skip(PEER, OP + f" [{VARIANT}]", repr(e))
