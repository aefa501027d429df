"""Mitsuba 3 peer: polarized BSDF sampling, bsdf.sample(ctx, si, sample1, sample2), and the matching
eval + pdf, bsdf.eval_pdf(ctx, si, wo), vectorised over lanes, for a rough conductor and a rough
dielectric.

Variant llvm_ad_spectral_polarized (f32), dr.set_thread_count(1) before the first kernel (checked).
BSDFs (mi.load_dict):
  * roughconductor: {'distribution': 'beckmann', 'alpha': 0.1, 'material': 'Au'} (as
    mitsuba_rough_conductor.py: Mitsuba's tabulated gold eta/k, interpolated per wavelength inside
    the timed kernel; sample_visible = true, the default);
  * roughdielectric: {'distribution': 'beckmann', 'alpha': 0.1, 'int_ior': 1.5, 'ext_ior': 1.0}
    (sample_visible = true). NOTE: Mitsuba 3.9.1's roughdielectric is not polarization-aware: it
    uses the unpolarized Fresnel reflectance and returns depolarizer(weight), i.e. a Mueller
    matrix with only M00 non-zero (checked below), so it does less work than a polarized rough
    dielectric would.
Input, one SurfaceInteraction3f with N = 65536 lanes: shading normal +z (sh_frame = Frame3f(+z)),
si.wi random, uniform on the upper hemisphere (local frame; cos theta in (0, 1]), si.wavelengths
random in [400, 700] nm; Mitsuba's spectral variants carry 4 wavelengths per lane (checked).
sample1 (Float) and sample2 (Point2f) uniform in [0, 1). ctx = mi.BSDFContext() (radiance
transport, all components). Seeded numpy RNG; all inputs are evaluated before timing.
Timed, each as one call on all lanes with dr.eval(result) + dr.sync_thread() inside the timing
(tracing and launch included; the kernel is compiled in the warm-up calls and taken from
Dr.Jit's kernel cache afterwards):
  * sample: bsdf.sample(ctx, si, sample1, sample2) -> (BSDFSample3f, Mueller weight); both
    evaluated;
  * eval_pdf: bsdf.eval_pdf(ctx, si, wo) -> (Mueller value, pdf), with wo = the directions that
    sample() returned for these lanes (so reflection and, for the dielectric, transmission
    directions in the proportions the BSDF samples them).
Reported per lane and per lane-wavelength (= per lane / 4). Each lane of sample() yields one
direction, one pdf and four 4x4 Mueller weights (one per wavelength).
Before timing: the result of the timed batch is checked: weight M00 and pdf finite and >= 0;
for the conductor, the weight is zero wherever the sampled wo is below the surface; for the dielectric,
both reflection and transmission are sampled; and weight M00 equals eval M00 / pdf at the sampled
wo (rtol 1e-3 for >= 99% of the lanes with pdf > 0).
Run by validation/peers/run.sh.
"""

import sys

import numpy as np

from _timing import bench, row, skip

PEER = "Mitsuba 3"
VARIANT = "llvm_ad_spectral_polarized"
N = 65536
N_WL = 4
MATERIALS = [
    ("rough conductor (Beckmann, alpha 0.1, Au), roughconductor",
     {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.1, "material": "Au"},
     "polarized (full Mueller)"),
    ("rough dielectric (Beckmann, alpha 0.1, n 1.5/1.0), roughdielectric",
     {"type": "roughdielectric", "distribution": "beckmann", "alpha": 0.1, "int_ior": 1.5,
      "ext_ior": 1.0},
     "NOT polarization-aware in Mitsuba 3.9.1: unpolarized Fresnel, Mueller = depolarizer (only M00)"),
]

try:
    import drjit as dr
    import mitsuba as mi
except Exception as e:  # noqa: BLE001
    skip(PEER, "polarized BSDF sample / eval_pdf", f"import failed: {e!r}")
    sys.exit(0)

rng = np.random.default_rng(11)


def f32(a):
    return mi.Float(np.ascontiguousarray(a, dtype=np.float32))


def make_si(n):
    """SurfaceInteraction3f with n lanes, normal +z, random upper-hemisphere wi, random wavelengths."""
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    cos_t = 1.0 - rng.uniform(0.0, 1.0, n)
    sin_t = np.sqrt(1.0 - cos_t * cos_t)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    si.wi = mi.Vector3f(f32(sin_t * np.cos(phi)), f32(sin_t * np.sin(phi)), f32(cos_t))
    wl_type = type(si.wavelengths)
    si.wavelengths = wl_type(*[f32(w) for w in rng.uniform(400.0, 700.0, (N_WL, n))])
    dr.eval(si)
    return si


def m00(result):
    """M00 of a Mueller-valued result as a numpy array of shape (wavelengths, lanes)."""
    return np.asarray(result[0, 0]).reshape(N_WL, -1)


def per_lane_rows(op, med, lo, note):
    row(PEER, op + f" [{VARIANT}, 1 thread]", "f32", N, med, lo,
        f"per lane ({N_WL} wavelengths per lane, a 4x4 Mueller matrix per wavelength); {note}")
    row(PEER, op + f" [{VARIANT}, 1 thread]", "f32", f"{N * N_WL} ({N} lanes x {N_WL} wavelengths)",
        med / N_WL, lo / N_WL, f"per lane-wavelength (= per lane / {N_WL}); {note}")


try:
    mi.set_variant(VARIANT)
    dr.set_thread_count(1)
    if dr.thread_count() != 1:
        raise RuntimeError(f"dr.thread_count() = {dr.thread_count()} after set_thread_count(1)")
    ctx = mi.BSDFContext()
    si = make_si(N)
    if len(si.wavelengths) != N_WL:
        raise RuntimeError(f"{len(si.wavelengths)} wavelengths per lane, expected {N_WL}")
    sample1 = f32(rng.uniform(0.0, 1.0, N))
    sample2 = mi.Point2f(f32(rng.uniform(0.0, 1.0, N)), f32(rng.uniform(0.0, 1.0, N)))
    dr.eval(sample1, sample2)
except Exception as e:  # noqa: BLE001
    skip(PEER, f"polarized BSDF sample / eval_pdf [{VARIANT}]", repr(e))
    sys.exit(0)

for name, desc, polar_note in MATERIALS:
    op_s = f"BSDF sample, bsdf.sample(ctx, si, sample1, sample2), {name}"
    op_e = f"BSDF eval + pdf, bsdf.eval_pdf(ctx, si, wo), {name}"
    try:
        bsdf = mi.load_dict(desc)

        # --- run once and check -----------------------------------------------------------------
        bs, weight = bsdf.sample(ctx, si, sample1, sample2)
        dr.eval(bs, weight)
        wo = mi.Vector3f(bs.wo)
        dr.eval(wo)
        w00 = m00(weight)
        pdf = np.asarray(bs.pdf)
        wo_z = np.asarray(bs.wo.z)
        ok = pdf > 0.0
        if not (np.all(np.isfinite(w00)) and np.all(w00 >= 0.0) and np.all(np.isfinite(pdf))
                and np.all(pdf >= 0.0) and ok.mean() > 0.9):
            raise RuntimeError(f"sample: non-finite/negative weight or pdf, or pdf > 0 on only "
                               f"{ok.mean():.3f} of the lanes")
        if desc["type"] == "roughconductor":
            # Mitsuba keeps pdf > 0 but zeroes the weight when reflect(wi, m) points below the
            # surface (grazing wi).
            if np.any(w00[:, wo_z <= 0.0] != 0.0):
                raise RuntimeError("conductor: non-zero weight for a direction below the surface")
            frac_t = 0.0
        else:
            frac_t = float(np.mean(wo_z[ok] < 0.0))
            if not 0.5 < frac_t < 0.999:
                raise RuntimeError(f"dielectric: transmitted fraction {frac_t}")
            others = [np.asarray(weight[i, j]) for i in range(4) for j in range(4) if (i, j) != (0, 0)]
            if any(np.any(o != 0.0) for o in others):
                raise RuntimeError("roughdielectric weight is not a depolarizer: update the note")
        value, pdf_e = bsdf.eval_pdf(ctx, si, wo)
        dr.eval(value, pdf_e)
        v00, pdf_e = m00(value), np.asarray(pdf_e)
        if not (np.all(np.isfinite(v00)) and np.all(np.isfinite(pdf_e))):
            raise RuntimeError("eval_pdf: non-finite value or pdf")
        good = ok & (pdf_e > 0.0)
        ratio = v00[:, good] / pdf_e[good]
        close = np.isclose(ratio, w00[:, good], rtol=1e-3, atol=1e-6)
        if close.mean() < 0.99:
            raise RuntimeError(f"weight != eval/pdf on {1.0 - close.mean():.3%} of lane-wavelengths")
        check = (f"checked weight = eval/pdf on {close.mean():.2%} of lane-wavelengths"
                 + (f", {frac_t:.1%} transmitted" if frac_t else ""))

        # --- timing -----------------------------------------------------------------------------
        def call_sample():
            b, w = bsdf.sample(ctx, si, sample1, sample2)
            dr.eval(b, w)
            dr.sync_thread()

        def call_eval_pdf():
            v, p = bsdf.eval_pdf(ctx, si, wo)
            dr.eval(v, p)
            dr.sync_thread()

        med, lo = bench(call_sample, N, warmup=5, samples=21, max_total_s=6.0)
        per_lane_rows(op_s, med, lo, f"{polar_note}; dr.eval of sample and weight inside timing; "
                      + check)
        med, lo = bench(call_eval_pdf, N, warmup=5, samples=21, max_total_s=6.0)
        per_lane_rows(op_e, med, lo, f"{polar_note}; wo = the sampled directions; dr.eval of "
                      "value and pdf inside timing")
    except Exception as e:  # noqa: BLE001
        skip(PEER, op_s + f" [{VARIANT}]", repr(e))
