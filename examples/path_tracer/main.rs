//! A polarized spectral path tracer written only against `gmueller::bsdf` (the renderer
//! layer): rough glass in reflection and transmission, gold, an aluminium height grating, a
//! polished black-glass ground, the sun and a polarized sky; `f32`, the `Full · Partial` kernel.
//!
//! ```sh
//! cargo run --release --example path_tracer                 # 320×200, 4 spp, 32 λ → target/path_tracer/
//! cargo run --release --example path_tracer -- --help       # options
//! cargo run --release --example path_tracer -- --tradeoff   # the coherence-per-sample measurements
//! ```
//!
//! **Integrator.** Backward (camera) paths, one wavelength each. Each pixel traces `spp`
//! camera samples of `wavelengths/spp` wavelengths each, stratified over 32 bins of
//! 0.40–0.70 µm (every pixel sees every bin, jittered inside it). At each vertex:
//! 1. `Bsdf::new(&material, Kernel::<Full, Partial>, frame, λ)`;
//! 2. next-event estimation of the sun: `bsdf.distant_packet` (one packet along the disk's
//!    centre with the whole disk's coherence: the coherent specular lobe is the sun's blurred
//!    mirror image), `prepare`, `eval` toward the previous vertex, and a shadow ray;
//! 3. the direction the light comes from: `bsdf.incident_sampler(r̂, &sky_coherence)`,
//!    `sample`, `bsdf.incident_weight` (`M/p`, evaluated in the physical direction). A ray that
//!    leaves the scene picks up the sky. The sun is reached only by step 2 (it is not in the
//!    sky's radiance), so no MIS is needed.
//!
//! The path's throughput is a Mueller matrix `t` from the frame the light arrives in at the
//! last vertex to the camera frame (`x̂` = the image's right, `k̂` toward the camera), chained
//! with `frame_change_mueller(exit_sp, previous incident_sp)` — the same ray in two frames.
//! Pixels hold S0 as CIE XYZ (Wyman–Sloan–Shirley fit) and the ȳ-weighted Stokes vector.
//!
//! `--sun-solid-angle 0.1` replaces the sun by an equally bright disk of low coherence (its
//! lobes widen, the grating's rainbow washes out); `--sky-coherence`, `--sun-split` change
//! the coherence one sample carries (`--tradeoff` measures both). The black-glass ground draws
//! reflection only (`with_part_probabilities`): what it transmits is absorbed. Russian
//! roulette on the throughput's `M₀₀` ends paths; contributions below 1e-30 are dropped.
//!
//! `--rough-gold σ` renders the gold sphere with rms height `σ` (µm) beyond first order: the
//! tangent-plane scatterer (`KirchhoffConductor`) and `Kernel::with_roughness(KirchhoffSeries)`,
//! whose samplers propose the series' orders.
//!
//! `--uniform` replaces step 3 by uniform sampling of the sphere (dielectrics) or hemisphere
//! (metals) with the same coherence: the brute-force reference of the example's test.

mod color;
mod scene;

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use gmueller::prelude::*;
use gmueller::verify::rng::SplitMix64;
use nalgebra::Vector4;

use color::Pixel;
use scene::{Materials, SUN_SOLID_ANGLE, Scene, V3};

const LAMBDA_MIN: f32 = 0.40;
const LAMBDA_MAX: f32 = 0.70;

/// How step 3 draws the direction the light comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sampling {
    /// `Bsdf::incident_sampler` and `incident_weight`.
    Lobes,
    /// Uniform on the sphere or hemisphere, weighted by `eval / p` (brute force).
    Uniform,
}

/// Render settings.
#[derive(Clone, Debug)]
pub(crate) struct Options {
    pub(crate) width: usize,
    pub(crate) height: usize,
    pub(crate) spp: usize,
    pub(crate) wavelengths: usize,
    pub(crate) max_depth: usize,
    /// Surface coherence width (µm) assumed for sky and indirect light.
    pub(crate) sky_coherence: f32,
    /// Widen it near the horizon by `SurfaceCoherence`'s horizon rule (the default); `false`
    /// keeps the width fixed (`SurfaceCoherence::fixed`).
    pub(crate) horizon_rule: bool,
    /// The sun's disk is split into this many packets per vertex (1: one packet along the
    /// centre with the whole disk's coherence).
    pub(crate) sun_split: usize,
    /// The sun's solid angle (sr): 6.8·10⁻⁵ for the sun; larger is a brighter-area, less
    /// coherent disk of the same irradiance.
    pub(crate) sun_solid_angle: f32,
    pub(crate) sampling: Sampling,
    pub(crate) threads: usize,
    pub(crate) seed: u64,
    pub(crate) progress: bool,
    /// One wavelength (µm) for every path instead of the spectrum (the trade-off measurements:
    /// no spectral noise).
    pub(crate) lambda: Option<f32>,
    /// A factor on every BSDF-sampling weight: 1 for a correct render (the test's negative
    /// control sets another).
    pub(crate) weight_scale: f32,
    /// `--rough-gold σ`: the gold sphere with rms height `σ` (µm), the tangent-plane scatterer
    /// and the Kirchhoff series (tolerance 1e-3) instead of the first-order kernel.
    pub(crate) rough_gold: Option<f32>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            width: 320,
            height: 200,
            spp: 4,
            wavelengths: 32,
            max_depth: 5,
            sky_coherence: 20.0,
            horizon_rule: true,
            sun_split: 1,
            sun_solid_angle: SUN_SOLID_ANGLE,
            sampling: Sampling::Lobes,
            threads: std::thread::available_parallelism().map_or(2, |n| n.get()),
            seed: 1,
            progress: true,
            weight_scale: 1.0,
            rough_gold: None,
            lambda: None,
        }
    }
}

/// Per pixel: sums over its paths of `(X, Y, Z, ȳS0, ȳS1, ȳS2, ȳS3)` and of their squares.
#[derive(Clone, Copy, Default)]
pub(crate) struct PixelSums {
    pub(crate) n: u32,
    pub(crate) sum: [f64; 7],
    pub(crate) sum_sq: [f64; 7],
}

impl PixelSums {
    pub(crate) fn mean(&self, c: usize) -> f64 {
        self.sum[c] / f64::from(self.n.max(1))
    }
    /// The standard error of the mean of channel `c`.
    pub(crate) fn std_error(&self, c: usize) -> f64 {
        let n = f64::from(self.n.max(2));
        let m = self.sum[c] / n;
        ((self.sum_sq[c] / n - m * m).max(0.0) / (n - 1.0)).sqrt()
    }
    fn pixel(&self) -> Pixel {
        let m = |c| self.mean(c) as f32;
        Pixel {
            xyz: [m(0), m(1), m(2)],
            stokes: [m(3), m(4), m(5), m(6)],
        }
    }
}

/// What a render returns.
pub(crate) struct Render {
    pub(crate) pixels: Vec<PixelSums>,
    /// Contributions that were not finite or not a valid Stokes vector (S0 ≥ |S|, 1e-4 slack).
    pub(crate) invalid: usize,
    /// Paths that left the renderer layer with an error (a direction in a surface's plane).
    pub(crate) errors: usize,
    pub(crate) seconds: f64,
}

/// A small seeded generator for reproducible pixels: the verification kit's `SplitMix64`, one
/// stream per pixel (a renderer brings its own; the example borrows the kit's to stay short).
struct Rng(SplitMix64);

impl Rng {
    fn new(seed: u64, a: u64, b: u64) -> Self {
        let mut r = Rng(SplitMix64(
            seed ^ a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xC2B2_AE3D_27D4_EB4F),
        ));
        r.0.next_u64();
        r
    }
    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.0.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// The per-path state: radiance so far (camera frame) and the path's throughput and frame.
struct Path {
    radiance: Vector4<f32>,
    t: PathThroughput<f32>,
    invalid: usize,
}

impl Path {
    /// Adds light `s` through the vertex throughput `m` of geometry `g`; contributions below
    /// 1e-30 (30 orders under the image) are dropped, non-finite ones counted.
    fn add(&mut self, m: &Mueller<f32>, g: &Geometry<f32>, s: &Stokes<f32>) {
        let c = self.t.contribution(m, g, s).vector();
        if c[0].abs() < 1e-30 {
        } else if c.iter().all(|x| x.is_finite()) {
            self.radiance += c;
        } else {
            self.invalid += 1;
        }
    }
}

/// What one vertex needs besides its material: the hit, the wavelength, the exit direction r̂
/// (toward the previous vertex) and the render's settings.
struct At<'a> {
    scene: &'a Scene,
    hit: &'a scene::Hit,
    lambda: f32,
    r: V3,
    opts: &'a Options,
    coherence: &'a SurfaceCoherence<f32>,
}

/// One vertex on `material`: sun NEE into `path`, then the next direction (or `None`).
fn vertex(
    material: &Material<f32>,
    at: &At<'_>,
    path: &mut Path,
    rng: &mut Rng,
) -> Result<Option<V3>, Error> {
    let At {
        scene,
        hit,
        lambda,
        r,
        opts,
        coherence,
    } = *at;
    let sp = ShadingPoint::new(scene.shading_frame(hit), lambda)?;
    let n = hit.normal;

    // 2. The sun.
    let lit = !(material.is_opaque() && scene.sun.dot(&n) * r.dot(&n) <= 0.0)
        && scene.sees_sun(&hit.point, &n);
    if lit {
        let k = opts.sun_split.max(1);
        let irradiance = Stokes::unpolarized(1.0 / k as f32)?;
        for _ in 0..k {
            let (dir, omega) = if k == 1 {
                (scene.sun, opts.sun_solid_angle)
            } else {
                (
                    sun_point(scene.sun, opts.sun_solid_angle, rng),
                    opts.sun_solid_angle / k as f32,
                )
            };
            let packet = material.distant_packet(&sp, irradiance, omega, dir)?;
            let v = material.eval(&sp, &packet, r)?;
            path.add(&v.response.total(), &v.geometry, &packet.stokes());
        }
    }

    // 3. The direction the light comes from.
    let (weight, g, s) = match opts.sampling {
        Sampling::Lobes => {
            let u = [rng.f(), rng.f(), rng.f()];
            let Some(s) = material.sample_incident(&sp, r, coherence, u[0], [u[1], u[2]])? else {
                return Ok(None);
            };
            (s.weight, s.geometry, s.sample.direction)
        }
        Sampling::Uniform => {
            let (u1, u2) = (rng.f(), rng.f());
            let (z, pdf) = if material.is_opaque() {
                (u1 * r.dot(&n).signum(), 1.0 / std::f32::consts::TAU)
            } else {
                (1.0 - 2.0 * u1, 0.25 / std::f32::consts::PI)
            };
            let rho = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u2;
            let f = sp.frame();
            let s = f.x() * (rho * phi.cos()) + f.y() * (rho * phi.sin()) + n * z;
            if z.abs() < 1e-6 {
                return Ok(None);
            }
            let v = material.eval_incident(&sp, r, coherence, s)?;
            (v.response.total().scaled(1.0 / pdf), v.geometry, s)
        }
    };
    path.t.advance(&weight.scaled(opts.weight_scale), &g);
    Ok(Some(s))
}

/// A direction uniformly inside the sun's disk (a cone of solid angle Ω about `sun`).
fn sun_point(sun: V3, solid_angle: f32, rng: &mut Rng) -> V3 {
    let cos_max = 1.0 - solid_angle / std::f32::consts::TAU;
    let z = 1.0 - rng.f() * (1.0 - cos_max);
    let rho = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * rng.f();
    let f = Frame::from_normal(sun).expect("sun frame");
    f.x() * (rho * phi.cos()) + f.y() * (rho * phi.sin()) + sun * z
}

/// The Stokes radiance (camera frame) of one path at `lambda` through image point `(x, y)`.
fn trace(
    scene: &Scene,
    mats: &Materials,
    lambda: f32,
    (x, y): (f32, f32),
    opts: &Options,
    rng: &mut Rng,
) -> (Vector4<f32>, usize, usize) {
    let cam = &scene.camera;
    let mut d = cam.direction(x, y, opts.width as f32 / opts.height as f32);
    let mut o = cam.origin;
    let coherence = if opts.horizon_rule {
        SurfaceCoherence::new(opts.sky_coherence)
    } else {
        SurfaceCoherence::fixed(opts.sky_coherence)
    }
    .expect("coherence width");
    let mut path = Path {
        radiance: Vector4::zeros(),
        t: PathThroughput::new(cam.frame(&d)),
        invalid: 0,
    };
    let mut errors = 0;
    for _ in 0..opts.max_depth {
        let Some(hit) = scene.intersect(&o, &d) else {
            let (s, f) = scene.sky(&d, lambda);
            path.radiance += path.t.arriving(&f, &s).vector();
            break;
        };
        let r = -d;
        let at = At {
            scene,
            hit: &hit,
            lambda,
            r,
            opts,
            coherence: &coherence,
        };
        let step = vertex(mats.of(hit.material), &at, &mut path, rng);
        match step {
            Ok(Some(s)) => {
                d = s;
                o = hit.point + hit.normal * (1e-4 * s.dot(&hit.normal).signum());
            }
            Ok(None) => break,
            Err(_) => {
                errors += 1;
                break;
            }
        }
        // Russian roulette on the throughput's M00 (unbiased; it also keeps f32 throughputs
        // out of the subnormal range).
        let survive = (path.t.matrix().m00() / 0.05).min(1.0);
        if survive.is_nan() || survive <= 0.0 || rng.f() >= survive {
            break;
        }
        path.t.scale(1.0 / survive);
    }
    (path.radiance, path.invalid, errors)
}

/// Renders the scene.
pub(crate) fn render(scene: &Scene, opts: &Options) -> Render {
    let start = Instant::now();
    let bins = if opts.lambda.is_some() {
        1
    } else {
        opts.wavelengths.max(1)
    };
    let width_bin = (LAMBDA_MAX - LAMBDA_MIN) / bins as f32;
    let mats: Vec<Materials> = (0..bins)
        .map(|b| {
            let centre = LAMBDA_MIN + (b as f32 + 0.5) * width_bin;
            Materials::at(opts.lambda.unwrap_or(centre), opts.rough_gold)
        })
        .collect();
    let white = color::cmf_integral(LAMBDA_MIN, LAMBDA_MAX);
    let per_sample = (bins / opts.spp.max(1)).max(1);
    let bar = if opts.progress {
        let b = indicatif::ProgressBar::new(opts.height as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rows  {elapsed_precise}")
                .expect("template"),
        );
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let next = AtomicUsize::new(0);
    let rows: Vec<(usize, Vec<PixelSums>, usize, usize)> = std::thread::scope(|sc| {
        let workers: Vec<_> = (0..opts.threads.max(1))
            .map(|_| {
                sc.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let j = next.fetch_add(1, Ordering::Relaxed);
                        if j >= opts.height {
                            break out;
                        }
                        let (mut invalid, mut errors) = (0, 0);
                        let row = (0..opts.width)
                            .map(|i| {
                                let mut px = PixelSums::default();
                                for s in 0..opts.spp {
                                    let mut rng =
                                        Rng::new(opts.seed, (j * opts.width + i) as u64, s as u64);
                                    let (jx, jy) = (rng.f(), rng.f());
                                    let xy = (
                                        (i as f32 + jx) / opts.width as f32,
                                        (j as f32 + jy) / opts.height as f32,
                                    );
                                    for w in 0..per_sample {
                                        let bin = (s * per_sample + w) % bins;
                                        let jitter =
                                            LAMBDA_MIN + (bin as f32 + rng.f()) * width_bin;
                                        let lambda = opts.lambda.unwrap_or(jitter);
                                        let (l, bad, err) =
                                            trace(scene, &mats[bin], lambda, xy, opts, &mut rng);
                                        invalid += bad;
                                        errors += err;
                                        let c = color::cmf(lambda);
                                        let span = LAMBDA_MAX - LAMBDA_MIN;
                                        let v = [
                                            l[0] * c[0] * span / white[0],
                                            l[0] * c[1] * span / white[1],
                                            l[0] * c[2] * span / white[2],
                                            l[0] * c[1] * span / white[1],
                                            l[1] * c[1] * span / white[1],
                                            l[2] * c[1] * span / white[1],
                                            l[3] * c[1] * span / white[1],
                                        ];
                                        px.n += 1;
                                        for (k, x) in v.iter().enumerate() {
                                            let x = f64::from(*x);
                                            px.sum[k] += x;
                                            px.sum_sq[k] += x * x;
                                        }
                                    }
                                }
                                px
                            })
                            .collect();
                        out.push((j, row, invalid, errors));
                        bar.inc(1);
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("worker"))
            .collect()
    });
    bar.finish_and_clear();
    let mut pixels = vec![PixelSums::default(); opts.width * opts.height];
    let (mut invalid, mut errors) = (0, 0);
    for (j, row, bad, err) in rows {
        pixels[j * opts.width..(j + 1) * opts.width].copy_from_slice(&row);
        invalid += bad;
        errors += err;
    }
    Render {
        pixels,
        invalid,
        errors,
        seconds: start.elapsed().as_secs_f64(),
    }
}

fn usage() -> ! {
    eprintln!(
        "path_tracer [--width N] [--height N] [--spp N] [--wavelengths N] [--depth N]\n\
         \x20           [--sky-coherence µm] [--sun-split N] [--sun-solid-angle sr] [--rough-gold σ/µm]\n\
         \x20           [--uniform] [--threads N] [--seed N] [--out DIR]\n\
         path_tracer --tradeoff [--out DIR]"
    );
    std::process::exit(2)
}

fn main() {
    let mut opts = Options::default();
    // The workspace's target directory wherever the example is run from (was `./target`).
    let mut out = option_env!("CARGO_TARGET_DIR").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"),
        PathBuf::from,
    );
    out.push("path_tracer");
    let mut tradeoff = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().unwrap_or_else(|| usage());
        let mut num = || value().parse::<usize>().unwrap_or_else(|_| usage());
        match a.as_str() {
            "--width" => opts.width = num(),
            "--height" => opts.height = num(),
            "--spp" => opts.spp = num(),
            "--wavelengths" => opts.wavelengths = num(),
            "--depth" => opts.max_depth = num(),
            "--sun-split" => opts.sun_split = num(),
            "--threads" => opts.threads = num(),
            "--seed" => opts.seed = num() as u64,
            "--sun-solid-angle" => {
                opts.sun_solid_angle = value().parse().unwrap_or_else(|_| usage());
            }
            "--sky-coherence" => {
                opts.sky_coherence = value().parse().unwrap_or_else(|_| usage());
            }
            "--rough-gold" => {
                opts.rough_gold = Some(value().parse().unwrap_or_else(|_| usage()));
            }
            "--uniform" => opts.sampling = Sampling::Uniform,
            "--tradeoff" => tradeoff = true,
            "--out" => out = PathBuf::from(value()),
            _ => usage(),
        }
    }
    let scene = Scene::new();
    if tradeoff {
        tradeoff::run(&scene, &out);
        return;
    }
    let r = render(&scene, &opts);
    let pixels: Vec<Pixel> = r.pixels.iter().map(PixelSums::pixel).collect();
    color::write_images(&out, opts.width, opts.height, &pixels).expect("write images");
    println!(
        "{}×{}, {} spp, {} wavelengths, f32 Full·Partial, {} threads: {:.2} s; \
         invalid contributions {}, errors {}; images in {}/{{s0,dop,aop}}.png",
        opts.width,
        opts.height,
        opts.spp,
        opts.wavelengths,
        opts.threads,
        r.seconds,
        r.invalid,
        r.errors,
        out.display()
    );
}

mod tradeoff;

#[cfg(test)]
mod tests;
