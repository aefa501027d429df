"""Mitsuba 3 peer: the polarized `path` integrator on a small rough-gold scene, mi.render(scene, spp=1).

Variant llvm_ad_spectral_polarized (f32), dr.set_thread_count(1) before the first kernel (checked;
the process CPU time during the timing is also compared with the wall time).
Scene (mi.load_dict):
  * a rough gold plane (rectangle scaled to 20 x 20 at z = 0) that fills the whole view, and a rough
    gold sphere (radius 0.5, centre (0, 0, 0.5)) standing on it; both roughconductor
    {'distribution': 'beckmann', 'alpha': 0.1, 'material': 'Au'} (as mitsuba_rough_conductor.py);
  * a constant environment emitter (radiance 1), hidden (hide_emitters = true; every camera ray hits
    the plane or the sphere anyway);
  * a perspective camera at (0, -3, 3) looking at (0, 0, 0.3), fov 40 deg, hdrfilm 256 x 256 with a
    box reconstruction filter, independent sampler, 1 spp: 65536 paths per render, each with 4
    wavelengths (Mitsuba's spectral variants);
  * integrator path, max_depth = 3: at most max_depth - 1 = 2 shaded surface interactions per path
    (each: emitter sampling with one shadow ray, BSDF eval_pdf + sample, one continuation ray);
    rr_depth = 5 (the default) > max_depth, so no Russian roulette.
Timed: one call mi.render(scene, spp=1, seed=0) with dr.eval(image) + dr.sync_thread() inside the
timing (Python-side tracing of the integrator, kernel cache lookup, launch and the film's
development included), after an untimed first render and two warm-up renders. The first render,
which compiles the kernels, is timed separately in a child process (this script with
--first-render) whose HOME is an empty temporary directory under target/peers, so that Dr.Jit's
on-disk kernel cache (~/.drjit) is empty and the LLVM compilation really happens; its row gives the
wall time, the LLVM back-end time from Dr.Jit's kernel history and the second render's time.
Bounces: "path-bounce" = one shaded surface interaction. Their number is counted in an untimed
replay of the same scene: camera rays from the same sensor (same pixels, other random numbers),
scene.ray_intersect, bsdf.sample, spawn_ray, for max_depth - 1 interactions, a path continuing only
while its sampled weight is non-zero (as the integrator's throughput test does). Also reported: the
upper bound paths x (max_depth - 1), and the kernels' own execution time (Dr.Jit's kernel history)
per path-bounce, i.e. without Python-side tracing and launch.
Before timing: the image (sRGB) is finite, its mean > 0 and its minimum > -0.1 x its maximum (the
sRGB of a spectral sample of gold can be slightly negative in one channel).
Run by validation/peers/run.sh.
"""

import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from _timing import bench, row, skip

PEER = "Mitsuba 3"
VARIANT = "llvm_ad_spectral_polarized"
# The child process's empty HOME (hence empty ~/.drjit) is made under the workspace's target/peers.
COLD_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "target", "peers")
RES = 256
MAX_DEPTH = 3
N_WL = 4
OP = (f"path integrator, mi.render spp=1, rough gold (Beckmann alpha 0.1, Au) plane + sphere, "
      f"constant env, {RES}x{RES}, max_depth {MAX_DEPTH}")

try:
    import drjit as dr
    import mitsuba as mi
except Exception as e:  # noqa: BLE001
    skip(PEER, OP, f"import failed: {e!r}")
    sys.exit(0)


def scene_dict():
    gold = {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.1, "material": "Au"}
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": MAX_DEPTH, "hide_emitters": True},
        "sensor": {
            "type": "perspective",
            "fov": 40.0,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, -3, 3], target=[0, 0, 0.3],
                                                       up=[0, 0, 1]),
            "sampler": {"type": "independent", "sample_count": 1},
            "film": {"type": "hdrfilm", "width": RES, "height": RES,
                     "rfilter": {"type": "box"}},
        },
        "env": {"type": "constant", "radiance": {"type": "spectrum", "value": 1.0}},
        "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([10, 10, 1]),
                  "bsdf": dict(gold)},
        "sphere": {"type": "sphere", "center": [0, 0, 0.5], "radius": 0.5, "bsdf": dict(gold)},
    }


def render_once(scene):
    img = mi.render(scene, spp=1, seed=0)
    dr.eval(img)
    dr.sync_thread()
    return img


def count_bounces(scene, n):
    """Untimed replay: shaded surface interactions per path, as the path integrator traces them."""
    sensor = scene.sensors()[0]
    res = sensor.film().crop_size()
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(7, n)
    idx = dr.arange(mi.UInt32, n)
    pos = mi.Vector2f(mi.Float(idx % int(res[0])), mi.Float(idx // int(res[0]))) + sampler.next_2d()
    ray, _ = sensor.sample_ray(0.0, sampler.next_1d(), pos / mi.ScalarVector2f(res),
                               mi.Point2f(0.5))
    ctx = mi.BSDFContext()
    active = mi.Bool(True)
    si = scene.ray_intersect(ray, active)
    primary_hits = int(np.count_nonzero(np.asarray(si.is_valid())))
    shaded = []
    for _ in range(MAX_DEPTH - 1):
        valid = active & si.is_valid()
        shaded.append(int(np.count_nonzero(np.asarray(valid))))
        bsdf = si.bsdf(ray)
        bs, w = bsdf.sample(ctx, si, sampler.next_1d(valid), sampler.next_2d(valid), valid)
        w00 = np.asarray(w[0, 0]).reshape(N_WL, -1)
        nonzero = mi.Bool(np.any(w00 > 0.0, axis=0))
        active = valid & nonzero
        ray = si.spawn_ray(si.to_world(bs.wo))
        si = scene.ray_intersect(ray, active)
    return shaded, primary_hits


def first_render():
    """Child process (HOME = an empty directory): the first render's wall time and compile time."""
    op = OP + f" [{VARIANT}, 1 thread], first render, empty kernel cache"
    try:
        mi.set_variant(VARIANT)
        dr.set_thread_count(1)
        scene = mi.load_dict(scene_dict())
        with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
            t0 = time.perf_counter()
            render_once(scene)
            t = time.perf_counter() - t0
            hist = [h for h in dr.kernel_history() if h["type"] == dr.KernelType.JIT]
        backend_s = sum(h["backend_time"] for h in hist) / 1e3
        cached = sum(1 for h in hist if h["cache_disk"] or h["cache_hit"])
        t0 = time.perf_counter()
        render_once(scene)
        t2 = time.perf_counter() - t0
        row(PEER, op, "f32", "1 render", t * 1e9, t * 1e9,
            f"ns per render = {t:.2f} s: Python tracing + LLVM compile + one run, one sample; "
            f"{len(hist)} JIT kernels, LLVM back-end {backend_s:.2f} s, {cached} found in a kernel "
            f"cache; the second render in the same process took {t2:.3f} s")
    except Exception as e:  # noqa: BLE001
        skip(PEER, op, repr(e))


if "--first-render" in sys.argv[1:]:
    first_render()
    sys.exit(0)

try:
    mi.set_variant(VARIANT)
    dr.set_thread_count(1)
    if dr.thread_count() != 1:
        raise RuntimeError(f"dr.thread_count() = {dr.thread_count()} after set_thread_count(1)")
    scene = mi.load_dict(scene_dict())
    n_paths = RES * RES

    # --- first render: tracing + compilation + one run, in a child process with an empty ------
    # --- on-disk kernel cache (else Dr.Jit loads the kernels from ~/.drjit of an earlier run) ----
    os.makedirs(COLD_DIR, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="drjit-cold-home-", dir=COLD_DIR) as home:
        env = dict(os.environ, HOME=home)
        out = subprocess.run([sys.executable, os.path.abspath(__file__), "--first-render"], env=env,
                             capture_output=True, text=True, timeout=1800)
    first_rows = [ln for ln in out.stdout.splitlines() if ln.startswith("ROW|")]
    if out.returncode != 0 or not first_rows:
        tail = " ".join((out.stdout + out.stderr).split())[-300:]
        skip(PEER, OP + f" [{VARIANT}, 1 thread], first render", f"child process failed: {tail}")
    for ln in first_rows:
        print(ln)
    sys.stdout.flush()
    img = render_once(scene)  # untimed; compiles here too if ~/.drjit does not have the kernels
    a = np.asarray(img)
    # sRGB of a spectral sample of gold can be slightly negative in one channel.
    if not (np.all(np.isfinite(a)) and a.mean() > 0.0 and a.min() > -0.1 * a.max()):
        raise RuntimeError(f"image not finite, or mean {a.mean()} / min {a.min()} / max {a.max()}")

    # --- bounce count (untimed replay) ----------------------------------------------------------
    shaded, primary = count_bounces(scene, n_paths)
    if primary != n_paths:
        raise RuntimeError(f"{n_paths - primary} camera rays miss the scene")
    bounces = sum(shaded)
    upper = n_paths * (MAX_DEPTH - 1)
    count_note = (f"{bounces / n_paths:.4f} shaded interactions per path counted in an untimed replay "
                  f"(depth 1: {shaded[0]}, depth 2: {shaded[1]} of {n_paths} paths)")

    # --- timing ---------------------------------------------------------------------------------
    def call():
        render_once(scene)

    c0, w0 = time.process_time(), time.perf_counter()
    med, lo = bench(call, 1, warmup=2, samples=21, min_sample_s=0.02, max_total_s=15.0)
    cpu_ratio = (time.process_time() - c0) / (time.perf_counter() - w0)
    common = (f"{N_WL} wavelengths per path; dr.eval inside timing; process CPU / wall time "
              f"{cpu_ratio:.2f} during timing")
    row(PEER, OP + f" [{VARIANT}, 1 thread]", "f32", n_paths, med / n_paths, lo / n_paths,
        f"per path; {common}")
    row(PEER, OP + f" [{VARIANT}, 1 thread]", "f32", f"{bounces} path-bounces", med / bounces,
        lo / bounces, f"per path-bounce (shaded surface interaction), i.e. "
        f"{1e3 / med * bounces:.3g} M path-bounces/s median; {count_note}; {common}")
    row(PEER, OP + f" [{VARIANT}, 1 thread]", "f32", f"{upper} path-bounces (upper bound)",
        med / upper, lo / upper,
        f"per path-bounce with the upper bound paths x (max_depth - 1) = {n_paths} x "
        f"{MAX_DEPTH - 1}; {common}")

    # --- kernel-only time (Dr.Jit kernel history) -------------------------------------------------
    kernel_ms = []
    for _ in range(7):
        with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
            render_once(scene)
            h = dr.kernel_history()
        kernel_ms.append(sum(x["execution_time"] for x in h if x["type"] == dr.KernelType.JIT))
    kmed, klo = float(np.median(kernel_ms)), min(kernel_ms)
    n_kernels = sum(1 for x in h if x["type"] == dr.KernelType.JIT)
    row(PEER, OP + f" [{VARIANT}, 1 thread], kernel execution only", "f32",
        f"{bounces} path-bounces", kmed * 1e6 / bounces, klo * 1e6 / bounces,
        f"per path-bounce (counted as above); sum of execution_time of the {n_kernels} JIT kernels "
        f"of one render from Dr.Jit's kernel history (no Python tracing / launch), 7 renders; "
        f"per path: {kmed * 1e6 / n_paths:.4g} ns median")
except Exception as e:  # noqa: BLE001
    skip(PEER, OP + f" [{VARIANT}]", repr(e))
