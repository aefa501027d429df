//! A wavefront path-tracing loop over the renderer layer (`gmueller::bsdf::Material<f32>`), one
//! thread, timed next to Mitsuba 3's polarized `path` integrator on a comparable scene
//! (`validation/peers/mitsuba_path.py`; issue 39).
//!
//! ```sh
//! cargo run --release --example wavefront                      # 256×256, the comparable size
//! cargo run --release --example wavefront -- --quick           # 64×64 (a smoke run)
//! cargo run --release --example wavefront -- --size 128 --only full --reps 3
//! # Mitsuba's side, in the same session (venv made by `bash validation/peers/run.sh mitsuba`):
//! cd validation/peers && DRJIT_LIBLLVM_PATH=/lib/x86_64-linux-gnu/libLLVM.so.19.1 \
//!     ../../target/peers-venv/bin/python mitsuba_path.py
//! ```
//!
//! **Scene** (as `mitsuba_path.py`): a rough gold plane `z = 0`, `|x|, |y| ≤ 10`, filling the
//! view, and a rough gold sphere of radius 0.5 centred at `(0, 0, 0.5)`; a constant,
//! unpolarized environment of radiance 1, hidden from camera rays (every camera ray hits the
//! plane or the sphere anyway); a pinhole camera at `(0, −3, 3)` looking at `(0, 0, 0.3)`, up
//! `+z`, horizontal field of view 40°, 256×256 pixels, one path per pixel jittered uniformly in
//! its pixel (Mitsuba's box filter and independent sampler): 65 536 paths per render. Ray–plane
//! and ray–sphere intersection are the few lines of analytic code below. One wavelength,
//! 0.55 µm, per path (Mitsuba's spectral variant carries 4 wavelengths per path: its work per
//! path·bounce is 4 spectral samples wide).
//!
//! **Material.** Gold at 0.55 µm (`Metal::Au.index`, the crate's tabulated index) as a
//! `Material<f32>` — the one run-time-dispatched material type a renderer holds — built from a
//! `RoughConductor` (first-order Rayleigh–Rice scatter plus the attenuated coherent specular
//! lobe) with an isotropic Gaussian PSD. Mitsuba's Beckmann `α = 0.1` has slopes of variance
//! `α²/2` per axis (rms slope `α/√2 ≈ 0.071` per axis). `GaussianPsd::isotropic(σ, ℓ)` has
//! `R(r) = σ² exp(−r²/(2ℓ²))`, whose slope variance per axis is `−R''(0) = σ²/ℓ²`: so
//! `σ/ℓ = α/√2`. The first-order lobe is the PSD read at `Δ(sin θ)/λ`, `∝ exp(−2π²ℓ²Δ²/λ²)`,
//! while Beckmann's is `∝ exp(−Δ²/(4α²))` near the normal (half-vector slope `Δ/2`): equal
//! widths ask `ℓ = λ/(2√2 π α) = 0.619 µm`, hence `σ = 0.0438 µm`. Both conditions together
//! put the surface at `4πσ/λ = 1.0`, past the first-order model's stated validity
//! (`vσ ≲ 0.3`): the lobe's shape and width match Beckmann's, its energy split (specular
//! `e^{−(vσ)²}` vs scattered) is the first-order one. A third row renders the same PSD at the
//! geometric-optics roughness level (`KirchhoffConductor` with `Roughness::Geometric`: the slope
//! distribution, the true analog of a microfacet model). Levels: `Full · Partial`
//! (`Level::ALL[7]`) and `Intensity · Partial` (`Level::ALL[1]`), the backward sampler
//! (`Material::sample_incident`), and the surface coherence of sunlight
//! (`SurfaceCoherence::new(w)` with `w = λ/√(πΩ☉) = 37.6 µm`, `Ω☉ = 6.8·10⁻⁵ sr`: the sun's
//! van Cittert–Zernike width at 0.55 µm, horizon rule on).
//!
//! **Integrator** (Mitsuba's `path` with `max_depth = 3`): at most two shaded interactions per
//! path. The live paths sit in one `Vec` of path states (and one `Vec` of hits), allocated once
//! before the timed renders and reused; per bounce step:
//! 1. intersect every live path's ray (a path whose ray leaves the scene after a bounce picks up
//!    the environment, weighted by the power heuristic against the light sampler's density,
//!    1 after a Dirac lobe);
//! 2. for every hit, from one build of the backward sampler (`Material::incident_vertex`, the
//!    shape of Mitsuba's `eval_pdf` + `sample`): next-event estimation of the environment — a
//!    cosine-weighted direction about the normal, the BSDF's value and its sampler's density
//!    for it (for the power heuristic), one shadow ray against the sphere and the plane, and
//!    the Stokes contribution `PathThroughput::contribution` of the unpolarized radiance 1,
//!    gathered into the path — and the continuation: the drawn direction (weight `M/p`, pdf,
//!    lobe), `PathThroughput::advance`, the continuation ray (the same answers, bit for bit,
//!    as `eval_incident`, `pdf_incident` and `sample_incident`, which build the sampler twice);
//! 3. the paths that ended (their ray left, the sampler returned `None` or a direction below
//!    the surface, the throughput died) add their `S0` to their pixel and the rest are
//!    compacted in place (`Vec::retain_mut`).
//!
//! After the second interaction one more intersection step lets the continuation rays pick up
//! the environment; then every path adds its `S0` to the image. No Russian roulette (Mitsuba's
//! `rr_depth = 5` exceeds `max_depth`).
//!
//! **Counted bounces**: one path·bounce is one shaded interaction (steps 2 and 3 on a hit), the
//! same count as `mitsuba_path.py`'s "path-bounce"; the example prints how many it processed
//! (at most 2 per path).
//!
//! **Timed**: the whole render (camera-ray generation, the steps above, the image's
//! accumulation) with `std::time::Instant`, after one untimed warm-up render, repeated 5 times
//! (`--reps`); printed: median and minimum ns per path, ns per path·bounce, and path·bounces
//! per second on the one core. Each render uses the same random numbers (the work is the same
//! every repetition). Also printed: the thread's CPU time over the wall time of the timed renders
//! (Linux's `/proc/thread-self/schedstat`; below 1 when other jobs shared the core, as
//! `mitsuba_path.py` reports for its process). After the timing, the image's `S0` is written to
//! `target/wavefront/<row>.pgm` (gamma 2.2, clamped to 1) and its mean printed (a sanity check:
//! finite and positive; the contributions the path throughput rejected as not finite and the
//! crate's errors are counted and printed too).

use std::io::Write;
use std::time::Instant;

use gmueller::verify::rng::SplitMix64;

use gmueller::prelude::*;
use nalgebra::Vector3;

type V3 = Vector3<f32>;

/// The wavelength (µm).
const LAMBDA: f32 = 0.55;
/// Mitsuba's Beckmann roughness.
const ALPHA: f32 = 0.1;
/// Shaded interactions per path (Mitsuba's `max_depth − 1`).
const MAX_INTERACTIONS: usize = 2;
/// The sun's solid angle (sr), for the coherence width of sunlight.
const SUN_SOLID_ANGLE: f32 = 6.8e-5;
/// Offset of a spawned ray's origin along the normal (scene units).
const RAY_EPS: f32 = 1e-4;
const SPHERE_CENTRE: [f32; 3] = [0.0, 0.0, 0.5];
const SPHERE_RADIUS: f32 = 0.5;
const PLANE_HALF: f32 = 10.0;

/// One stream per path of the crate's `SplitMix64` (Steele, Lea & Flood 2014).
#[derive(Clone)]
struct Rng(SplitMix64);

impl Rng {
    fn new(seed: u64, stream: u64) -> Self {
        let mut r = SplitMix64(seed ^ stream.wrapping_mul(0xC2B2_AE3D_27D4_EB4F));
        r.next_u64();
        Rng(r)
    }
    /// Uniform in [0, 1) (24 bits: never rounds up to 1 in `f32`).
    fn f(&mut self) -> f32 {
        (self.0.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// The pinhole camera (Mitsuba's `look_at` and `fov` along x).
struct Camera {
    origin: V3,
    forward: V3,
    right: V3,
    up: V3,
    tan_half: f32,
}

impl Camera {
    fn new() -> Self {
        let origin = V3::new(0.0, -3.0, 3.0);
        let forward = (V3::new(0.0, 0.0, 0.3) - origin).normalize();
        let right = forward.cross(&V3::z()).normalize();
        let up = right.cross(&forward);
        Self {
            origin,
            forward,
            right,
            up,
            tan_half: (20f32).to_radians().tan(),
        }
    }
    /// The unit direction through image point `(x, y)` in `[0, 1)²` (y down).
    fn ray(&self, x: f32, y: f32) -> V3 {
        let (sx, sy) = (
            (2.0 * x - 1.0) * self.tan_half,
            (1.0 - 2.0 * y) * self.tan_half,
        );
        (self.forward + self.right * sx + self.up * sy).normalize()
    }
}

/// A ray's nearest hit: point and outward unit normal.
#[derive(Clone, Copy)]
struct Hit {
    point: V3,
    normal: V3,
}

/// The nearest hit of the ray `o + t d` (`t > 0`), `d` a unit vector.
fn intersect(o: &V3, d: &V3) -> Option<Hit> {
    let mut best = f32::INFINITY;
    let mut normal = V3::z();
    // The plane z = 0, |x|, |y| ≤ 10.
    if d.z != 0.0 {
        let t = -o.z / d.z;
        if t > 0.0 {
            let p = o + d * t;
            if p.x.abs() <= PLANE_HALF && p.y.abs() <= PLANE_HALF {
                best = t;
            }
        }
    }
    // The sphere.
    let c = V3::from(SPHERE_CENTRE);
    let oc = o - c;
    let b = oc.dot(d);
    let disc = b * b - (oc.norm_squared() - SPHERE_RADIUS * SPHERE_RADIUS);
    if disc >= 0.0 {
        let q = disc.sqrt();
        let t = if -b - q > 0.0 { -b - q } else { -b + q };
        if t > 0.0 && t < best {
            best = t;
            normal = (o + d * t - c) / SPHERE_RADIUS;
        }
    }
    best.is_finite().then(|| Hit {
        point: o + d * best,
        normal,
    })
}

/// One live path.
#[derive(Clone)]
struct PathState {
    pixel: u32,
    rng: Rng,
    origin: V3,
    dir: V3,
    t: PathThroughput<f32>,
    /// The BSDF sampler's density of `dir` (solid angle), and whether it came from a Dirac lobe.
    bsdf_pdf: f32,
    delta: bool,
    /// The light sampler's density of `dir` at the previous vertex (cosine-weighted).
    light_pdf: f32,
    alive: bool,
}

/// The power heuristic (Mitsuba's `mis_weight`).
fn mis(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// The buffers of the wavefront, allocated once.
struct Wavefront {
    paths: Vec<PathState>,
    hits: Vec<Option<Hit>>,
    image: Vec<f32>,
    /// The batched step 2: every hit's query, what it keeps, and the vertices.
    queries: Vec<VertexQuery<f32>>,
    pending: Vec<Pending>,
    vertices: Vec<Result<IncidentVertex<f32>, Error>>,
}

#[derive(Default, Clone, Copy)]
struct Stats {
    /// Shaded interactions processed (path·bounces).
    bounces: u64,
    rejected: u64,
    errors: u64,
}

/// What step 2 keeps of one hit between the vertex's query and its answer.
struct Pending {
    /// The path's index in the wavefront.
    path: usize,
    hit: Hit,
    to_light: V3,
    /// The light sampler's density of `to_light` (cosine-weighted); 0: no light sample.
    light_pdf: f32,
}

/// Step 2's query at one hit (`Material::incident_vertex`'s arguments): a cosine-weighted
/// direction about the normal for next-event estimation of the environment, and the uniforms
/// of the continuation, from the path's random numbers.
fn query(p: &mut PathState, hit: &Hit) -> Result<(VertexQuery<f32>, V3, f32), Error> {
    let sp = ShadingPoint::new(Frame::from_normal(hit.normal)?, LAMBDA)?;
    let exit = -p.dir;
    let f = sp.frame();
    let (u1, u2) = (p.rng.f(), p.rng.f());
    let (r, cos) = (u1.sqrt(), (1.0 - u1).max(0.0).sqrt());
    let (sin_phi, cos_phi) = (std::f32::consts::TAU * u2).sin_cos();
    let to_light = f.x() * (r * cos_phi) + f.y() * (r * sin_phi) + f.k() * cos;
    let light_pdf = cos * std::f32::consts::FRAC_1_PI;
    let u = [p.rng.f(), p.rng.f(), p.rng.f()];
    let q = VertexQuery {
        at: sp,
        exit,
        to_light: (light_pdf > 0.0).then_some(to_light),
        u_lobe: u[0],
        u: [u[1], u[2]],
    };
    Ok((q, to_light, light_pdf))
}

/// Steps 2 and 3 at one hit from its vertex (`Material::incident_vertex` or a lane of
/// `Material::incident_vertices`): NEE of the environment gathered into the path, then the
/// direction the light comes from, the throughput and the next ray; ends the path
/// (`alive = false`) when it cannot continue.
fn finish(
    p: &mut PathState,
    (hit, to_light): (&Hit, V3),
    v: IncidentVertex<f32>,
    light_pdf: f32,
    sky: &Stokes<f32>,
) -> Result<(), Error> {
    if let Some(light) = v.light {
        let light = light?;
        let (value, bsdf_pdf) = (light.value, light.pdf);
        let origin = hit.point + hit.normal * RAY_EPS;
        if intersect(&origin, &to_light).is_none() {
            let w = mis(light_pdf, bsdf_pdf) / light_pdf;
            let c =
                p.t.contribution(&value.response.total().scaled(w), &value.geometry, sky);
            p.t.gather(c);
        }
    }
    let Some(s) = v.sample else {
        p.alive = false;
        return Ok(());
    };
    let cos = s.sample.direction.dot(&hit.normal);
    if cos <= 0.0 {
        p.alive = false;
        return Ok(());
    }
    p.t.advance(&s.weight, &s.geometry);
    p.alive = p.t.is_alive();
    p.origin = hit.point + hit.normal * RAY_EPS;
    p.dir = s.sample.direction;
    p.bsdf_pdf = s.sample.pdf;
    p.delta = s.sample.lobe.delta;
    p.light_pdf = cos * std::f32::consts::FRAC_1_PI;
    Ok(())
}

/// Steps 2 and 3 at one hit, from one build of the backward sampler
/// (`Material::incident_vertex`), one hit at a time.
fn shade(
    p: &mut PathState,
    hit: &Hit,
    mat: &Material<f32>,
    coh: &SurfaceCoherence<f32>,
    sky: &Stokes<f32>,
) -> Result<(), Error> {
    let (q, to_light, light_pdf) = query(p, hit)?;
    let v = mat.incident_vertex(&q.at, q.exit, coh, q.to_light, q.u_lobe, q.u)?;
    finish(p, (hit, to_light), v, light_pdf, sky)
}

/// One render of `res × res` paths into `wf.image` (cleared first).
fn render(
    wf: &mut Wavefront,
    res: usize,
    cam: &Camera,
    mat: &Material<f32>,
    coh: &SurfaceCoherence<f32>,
    (seed, batch): (u64, bool),
) -> Stats {
    let mut stats = Stats::default();
    let sky = Stokes::unpolarized(1.0).expect("radiance 1");
    let Wavefront {
        paths,
        hits,
        image,
        queries,
        pending,
        vertices,
    } = wf;
    image.iter_mut().for_each(|x| *x = 0.0);
    paths.clear();
    let inv = 1.0 / res as f32;
    for i in 0..res * res {
        let mut rng = Rng::new(seed, i as u64);
        let (x, y) = (
            ((i % res) as f32 + rng.f()) * inv,
            ((i / res) as f32 + rng.f()) * inv,
        );
        let dir = cam.ray(x, y);
        // The camera reads Stokes vectors in its frame: k̂ toward the eye, x̂ the image's right.
        let frame = Frame::from_direction_and_x(-dir, cam.right).expect("camera frame");
        paths.push(PathState {
            pixel: i as u32,
            rng,
            origin: cam.origin,
            dir,
            t: PathThroughput::new(frame),
            bsdf_pdf: 0.0,
            delta: false,
            light_pdf: 0.0,
            alive: true,
        });
    }
    for depth in 0..=MAX_INTERACTIONS {
        // Step 1: intersect every live path.
        hits.clear();
        hits.extend(paths.iter().map(|p| intersect(&p.origin, &p.dir)));
        let shade_now = depth < MAX_INTERACTIONS;
        // Steps 2 and 3: the environment seen by escaping rays; at every hit, NEE and the
        // continuation from one build of the sampler.
        queries.clear();
        pending.clear();
        for (i, (p, h)) in paths.iter_mut().zip(hits.iter()).enumerate() {
            match h {
                None => {
                    if depth > 0 {
                        let w = if p.delta {
                            1.0
                        } else {
                            mis(p.bsdf_pdf, p.light_pdf)
                        };
                        let frame = *p.t.frame();
                        p.t.gather_arriving(&frame, &Stokes::unpolarized(w).expect("w ≥ 0"));
                    }
                    p.alive = false;
                }
                Some(h) if shade_now => {
                    stats.bounces += 1;
                    let done = if batch {
                        query(p, h).map(|(q, to_light, light_pdf)| {
                            queries.push(q);
                            pending.push(Pending {
                                path: i,
                                hit: *h,
                                to_light,
                                light_pdf,
                            });
                        })
                    } else {
                        shade(p, h, mat, coh, &sky)
                    };
                    if done.is_err() {
                        stats.errors += 1;
                        p.alive = false;
                    }
                }
                Some(_) => p.alive = false,
            }
        }
        if batch && !queries.is_empty() {
            // Step 2 for every hit at once.
            vertices.resize_with(queries.len(), || {
                Ok(IncidentVertex {
                    light: None,
                    sample: None,
                })
            });
            mat.incident_vertices(coh, queries, vertices)
                .expect("an output as long as the queries");
            for (pd, v) in pending.iter().zip(vertices.drain(..)) {
                let p = &mut paths[pd.path];
                let done = v.and_then(|v| finish(p, (&pd.hit, pd.to_light), v, pd.light_pdf, &sky));
                if done.is_err() {
                    stats.errors += 1;
                    p.alive = false;
                }
            }
        }
        // Compaction: ended paths add S0 to their pixel.
        paths.retain_mut(|p| {
            if !p.alive {
                image[p.pixel as usize] += p.t.radiance().s0();
                stats.rejected += p.t.rejected() as u64;
            }
            p.alive
        });
    }
    debug_assert!(paths.is_empty());
    stats
}

/// One material row of the table.
struct Row {
    name: &'static str,
    key: &'static str,
    material: Material<f32>,
}

fn rows() -> Vec<Row> {
    // σ/ℓ = α/√2 (equal slopes), ℓ = λ/(2√2 π α) (equal first-order lobe width): module docs.
    let ell = LAMBDA / (2.0 * std::f32::consts::SQRT_2 * std::f32::consts::PI * ALPHA);
    let sigma = ell * ALPHA / std::f32::consts::SQRT_2;
    let psd = GaussianPsd::isotropic(sigma, ell).expect("PSD");
    let au = Metal::Au.index(LAMBDA);
    let first = |level| Material::new(RoughConductor::new(psd, au).expect("gold"), level);
    vec![
        Row {
            name: "Full·Partial, first order",
            key: "full",
            material: first(Level::ALL[7]),
        },
        Row {
            name: "Intensity·Partial, first order",
            key: "intensity",
            material: first(Level::ALL[1]),
        },
        Row {
            name: "Full·Partial, geometric",
            key: "geometric",
            material: Material::with_roughness(
                KirchhoffConductor::new(psd, au).expect("gold"),
                Level::ALL[7],
                Roughness::Geometric,
            ),
        },
    ]
}

/// The image's `S0` as an 8-bit PGM (gamma 2.2, clamped to 1).
fn write_pgm(path: &std::path::Path, res: usize, image: &[f32]) -> std::io::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    write!(out, "P5\n{res} {res}\n255\n")?;
    let bytes: Vec<u8> = image
        .iter()
        .map(|&v| (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0 + 0.5) as u8)
        .collect();
    out.write_all(&bytes)?;
    out.flush()
}

/// The time this thread has spent on a CPU (ns), from Linux's `/proc/thread-self/schedstat`;
/// `None` elsewhere. Compared with the wall time, it tells how much other jobs took the core.
fn cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() {
    let mut res = 256usize;
    let mut reps = 5usize;
    let mut only: Option<String> = None;
    let mut batch = true;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |what| {
            args.next()
                .unwrap_or_else(|| panic!("{a} needs {what}"))
                .to_string()
        };
        match a.as_str() {
            "--quick" => res = 64,
            "--size" => res = value("a size").parse().expect("--size N"),
            "--reps" => reps = value("a count").parse().expect("--reps N"),
            "--only" => only = Some(value("full, intensity or geometric")),
            "--vertex" => {
                batch = match value("one or batch").as_str() {
                    "one" => false,
                    "batch" => true,
                    v => panic!("--vertex one|batch, not {v}"),
                };
            }
            "--help" | "-h" => {
                println!(
                    "usage: wavefront [--quick | --size N] [--reps N] \
                     [--only full|intensity|geometric] [--vertex batch|one]"
                );
                return;
            }
            other => panic!("unknown argument {other} (try --help)"),
        }
    }
    assert!(res > 0 && reps > 0, "size and reps must be positive");
    let cam = Camera::new();
    let width = LAMBDA / (std::f32::consts::PI * SUN_SOLID_ANGLE).sqrt();
    let coh = SurfaceCoherence::new(width).expect("coherence width");
    let n = res * res;
    let mut wf = Wavefront {
        paths: Vec::with_capacity(n),
        hits: Vec::with_capacity(n),
        image: vec![0.0; n],
        queries: Vec::with_capacity(n),
        pending: Vec::with_capacity(n),
        vertices: Vec::with_capacity(n),
    };
    println!(
        "wavefront: {res}x{res} paths, ≤ {MAX_INTERACTIONS} shaded interactions each, f32, \
         λ = {LAMBDA} µm, 1 thread, coherence width {width:.1} µm, {reps} timed renders \
         after 1 warm-up, vertices {}",
        if batch {
            "batched (Material::incident_vertices)"
        } else {
            "one at a time (Material::incident_vertex)"
        }
    );
    for row in rows() {
        if only.as_deref().is_some_and(|k| k != row.key) {
            continue;
        }
        let seed = 7;
        let stats = render(&mut wf, res, &cam, &row.material, &coh, (seed, batch));
        let mut secs = Vec::with_capacity(reps);
        let cpu0 = cpu_ns();
        for _ in 0..reps {
            let t0 = Instant::now();
            let s = render(&mut wf, res, &cam, &row.material, &coh, (seed, batch));
            secs.push(t0.elapsed().as_secs_f64());
            assert_eq!(s.bounces, stats.bounces, "the same work every render");
        }
        let cpu = cpu_ns().zip(cpu0).map(|(a, b)| (a - b) as f64 * 1e-9);
        let cpu_share = cpu.map_or_else(
            || "process CPU / wall n/a".to_string(),
            |c| format!("CPU / wall {:.2}", c / secs.iter().sum::<f64>()),
        );
        let mean = wf.image.iter().map(|&v| f64::from(v)).sum::<f64>() / n as f64;
        let (med, min) = (
            median(secs.clone()),
            secs.iter().copied().fold(f64::MAX, f64::min),
        );
        let b = stats.bounces as f64;
        let pgm = std::path::PathBuf::from(format!("target/wavefront/{}.pgm", row.key));
        let wrote = write_pgm(&pgm, res, &wf.image).map_or_else(
            |e| format!("(not written: {e})"),
            |()| pgm.display().to_string(),
        );
        println!(
            "{:<31} {n} paths, {} path·bounces ({:.3}/path): median {:.1} ns/path·bounce \
             (min {:.1}), {:.1} ns/path (min {:.1}), {:.3} M path·bounces/s/core; \
             {cpu_share}; mean S0 {mean:.4}; rejected {}, errors {}; image {wrote}",
            row.name,
            stats.bounces,
            b / n as f64,
            med * 1e9 / b,
            min * 1e9 / b,
            med * 1e9 / n as f64,
            min * 1e9 / n as f64,
            b / med * 1e-6,
            stats.rejected,
            stats.errors,
        );
    }
}
