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
//! 0.36–0.83 µm, the CIE 1931 table's range (every pixel sees every bin, jittered inside it;
//! the materials are built once per bin, at its centre). At each vertex (`adapter.rs`):
//! 1. the hit's `ShadingPoint` and its `Material` (one type for every surface);
//! 2. next-event estimation of the sun: `Material::distant_packet` (one packet along the
//!    disk's centre with the whole disk's coherence: the coherent specular lobe is the sun's
//!    blurred mirror image), `eval` toward the previous vertex, `PathThroughput::gather_light`,
//!    and a shadow ray;
//! 3. the direction the light comes from: `Material::sample_incident(r̂, &sky_coherence, …)`,
//!    whose weight `M/p` `PathThroughput::advance` chains. A ray that leaves the scene picks
//!    up the sky. The sun is reached only by step 2 (it is not in the sky's radiance), so no
//!    MIS is needed.
//!
//! `adapter.rs` is all the code between the scene and image code and the crate (frames,
//! material dispatch, the vertex, the path state, spectral and colour conversions);
//! `materials.rs` declares the materials. Pixels hold S0 as CIE XYZ
//! (`spectral::cie1931_normalized`) and the ȳ-weighted Stokes vector in the camera frame
//! (`x̂` = the image's right, `k̂` toward the camera).
//!
//! `--sun-solid-angle 0.1` replaces the sun by an equally bright disk of low coherence (its
//! lobes widen, the grating's rainbow washes out); `--sky-coherence`, `--sun-split` change
//! the coherence one sample carries (`--tradeoff` measures both). The black-glass ground draws
//! reflection only (an opaque interface of real index): what it transmits is absorbed.
//! Russian roulette on the throughput's `M₀₀` (`PathThroughput::roulette`) ends paths.
//!
//! `--rough-gold σ` renders the gold sphere with rms height `σ` (µm) beyond first order: the
//! tangent-plane scatterer (`KirchhoffConductor`) and `Kernel::with_roughness(KirchhoffSeries)`,
//! whose samplers propose the series' orders.
//!
//! `--uniform` replaces step 3 by `Material::sample_incident_uniform` (the sphere for
//! dielectrics, the hemisphere for metals, the same coherence): the brute-force reference of
//! the example's test.

mod adapter;
mod color;
mod materials;
mod scene;

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use adapter::{Materials, Path};
use color::Pixel;
use scene::{SUN_SOLID_ANGLE, Scene};

/// The wavelengths traced (µm): the CIE 1931 table's range.
const LAMBDA_MIN: f32 = 0.36;
const LAMBDA_MAX: f32 = 0.83;

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

/// A small seeded generator for reproducible pixels: `SplitMix64` (Steele, Lea & Flood 2014),
/// one stream per pixel.
pub(crate) struct Rng(u64);

impl Rng {
    fn new(seed: u64, a: u64, b: u64) -> Self {
        let mut r = Rng(seed
            ^ a.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ b.wrapping_mul(0xC2B2_AE3D_27D4_EB4F));
        r.next_u64();
        r
    }
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub(crate) fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// One path at `lambda` through image point `(x, y)`: `(X, Y, Z, ȳS0, ȳS1, ȳS2, ȳS3)`,
/// invalid contributions and errors.
fn trace(
    scene: &Scene,
    mats: &Materials,
    lambda: f32,
    (x, y): (f32, f32),
    opts: &Options,
    rng: &mut Rng,
) -> ([f32; 7], usize, usize) {
    let cam = &scene.camera;
    let mut d = cam.direction(x, y, opts.width as f32 / opts.height as f32);
    let mut o = cam.origin;
    let mut path = Path::new(scene, &d, lambda, opts);
    let mut errors = 0;
    for _ in 0..opts.max_depth {
        let Some(hit) = scene.intersect(&o, &d) else {
            path.sky(scene, &d);
            break;
        };
        match path.vertex(scene, mats, &hit, -d, rng) {
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
    }
    let (v, invalid) = path.xyz_stokes(LAMBDA_MAX - LAMBDA_MIN);
    (v, invalid, errors)
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
            materials::at(opts.lambda.unwrap_or(centre), opts.rough_gold)
        })
        .collect();
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
                                        let (v, bad, err) =
                                            trace(scene, &mats[bin], lambda, xy, opts, &mut rng);
                                        invalid += bad;
                                        errors += err;
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
