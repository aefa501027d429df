//! The white furnace of lossless interfaces, 0–89°, forward and backward, as a renderer sees
//! it: the samplers of `gmueller::bsdf` and their Monte Carlo weights, `f32`, `Full · Partial`.
//!
//! Run with `cargo run --release -p gmueller-validation --bin furnace` (200 000 samples per
//! cell, about a minute on 2 cores), or `-- --quick` (20 000). Prints a markdown table (the one
//! in `docs/renderer.md`, "Energy near the horizon") and writes it to the workspace's
//! `target/furnace/furnace.md`.
//!
//! **Materials.** A near-perfect conductor (`η = 0.01 + 100i`, `R ≥ 1 − 4·10⁻⁶`) and lossless
//! glass (`η = 1.5`, lit from the air: `R + T = 1`), both smooth, at λ = 0.55 µm.
//!
//! **Forward** (light tracing): the mean of `Bsdf::sample_exit`'s weight `M₀₀ cos θ_o/(cos θ_i p)`
//! for unpolarized light, the albedo; lossless: 1. Coherences: the surface coherence
//! `SurfaceCoherence::new(w)` (the horizon rule) for w = 2, 5, 20, 100 µm, the same widths fixed
//! (`SurfaceCoherence::fixed`), and the sun's packet (`Bsdf::distant_packet`, Ω = 6.8·10⁻⁵ sr).
//!
//! **Backward** (path tracing): the mean of `Bsdf::sample_incident`'s weight `M₀₀/p` under
//! uniform radiance (1 above, `η²` below: the equilibrium of the two media), the white furnace;
//! lossless: 1. The same widths, with the horizon rule and fixed.
//!
//! Each cell is `mean (s.e.)`, the standard error in units of the last digit shown.

use std::fmt::Write as _;

use gmueller::bsdf::{Bsdf, Interface, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::pbsdf::Pbsdf;
use gmueller::interaction::{
    Full, Kernel, Partial, RoughSurface, SmoothConductor, SmoothDielectric,
};
use gmueller::psd::Psd;
use gmueller::stokes::Stokes;
use gmueller::verify::rng::SplitMix64;
use nalgebra::Vector3;
use num_complex::Complex;

const LAMBDA: f32 = 0.55;
const SUN: f32 = 6.8e-5;
const ANGLES: [f64; 9] = [0.0, 30.0, 60.0, 75.0, 80.0, 85.0, 87.0, 88.0, 89.0];
const WIDTHS: [f32; 4] = [2.0, 5.0, 20.0, 100.0];

/// The light's coherence in a row.
#[derive(Clone, Copy)]
enum Light {
    Rule(f32),
    Fixed(f32),
    Sun,
}

impl Light {
    fn name(self) -> String {
        match self {
            Self::Rule(w) => format!("{w} µm"),
            Self::Fixed(w) => format!("{w} µm fixed"),
            Self::Sun => "sun".into(),
        }
    }
    fn surface(self) -> SurfaceCoherence<f32> {
        match self {
            Self::Rule(w) => SurfaceCoherence::new(w).unwrap(),
            Self::Fixed(w) => SurfaceCoherence::fixed(w).unwrap(),
            Self::Sun => unreachable!("the sun is a distant packet"),
        }
    }
}

/// A direction at `deg` from the normal of `f` (azimuth 30°).
fn dir(f: &Frame<f32>, deg: f64) -> Vector3<f32> {
    let (t, p) = (deg.to_radians(), 30f64.to_radians());
    let (x, y, k) = (
        f.x().map(f64::from),
        f.y().map(f64::from),
        f.k().map(f64::from),
    );
    (x * (t.sin() * p.cos()) + y * (t.sin() * p.sin()) + k * t.cos()).map(|v| v as f32)
}

/// `mean (s.e.)` of `n` seeded draws, formatted.
fn cell(n: usize, seed: u64, draw: &mut dyn FnMut(&mut SplitMix64) -> f64) -> (f64, String) {
    let mut rng = SplitMix64(seed);
    let (mut s, mut s2) = (0.0, 0.0);
    for _ in 0..n {
        let v = draw(&mut rng);
        s += v;
        s2 += v * v;
    }
    let m = s / n as f64;
    let se = ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt();
    (m, format!("{m:.4} ({:.0})", (se * 1e4).ceil()))
}

/// One row: the forward albedo or the backward furnace at every angle.
fn row<P, Sp, Sc>(
    b: &Bsdf<'_, f32, RoughSurface<P, Sp, Sc>, Kernel<Full, Partial>>,
    light: Light,
    forward: bool,
    eta: f64,
    n: usize,
    worst: &mut f64,
) -> String
where
    P: Psd<f32, 2>,
    Sp: Interface<f32>,
    Sc: Pbsdf<f32>,
    Partial: CoherenceWeights<f32, P>,
{
    let f = *b.surface();
    let u = Stokes::unpolarized(1.0f32).unwrap();
    let mut out = String::new();
    for (i, &deg) in ANGLES.iter().enumerate() {
        let d = dir(&f, deg);
        let seed = 1000 * i as u64 + 7;
        let (m, text) = if forward {
            let packet = match light {
                Light::Sun => b.distant_packet(u, SUN, d),
                _ => b.surface_packet(u, d, &light.surface()),
            }
            .unwrap();
            let inc = b.prepare(&packet).unwrap();
            cell(n, seed, &mut |rng| {
                b.sample_exit(
                    &inc,
                    rng.unit() as f32,
                    [rng.unit() as f32, rng.unit() as f32],
                )
                .unwrap()
                .map_or(0.0, |s| f64::from(s.weight.m00()))
            })
        } else {
            let c = light.surface();
            cell(n, seed, &mut |rng| {
                b.sample_incident(
                    d,
                    &c,
                    rng.unit() as f32,
                    [rng.unit() as f32, rng.unit() as f32],
                )
                .unwrap()
                .map_or(0.0, |s| {
                    let l = if s.sample.direction.dot(&f.k()) > 0.0 {
                        1.0
                    } else {
                        eta * eta
                    };
                    f64::from(s.weight.m00()) * l
                })
            })
        };
        if deg <= 89.0 && !matches!(light, Light::Fixed(_)) {
            *worst = worst.max((m - 1.0).abs());
        }
        let _ = write!(out, " {text} |");
    }
    out
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let n = if quick { 20_000 } else { 200_000 };
    let f = Frame::from_normal(Vector3::new(0.2f32, -0.1, 1.0)).unwrap();
    let metal: SmoothConductor<f32> = SmoothConductor::smooth(Complex::new(0.01, 100.0)).unwrap();
    let glass: SmoothDielectric<f32> = SmoothDielectric::smooth(1.5).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let bm = Bsdf::new(&metal, kernel, f, LAMBDA).unwrap();
    let bg = Bsdf::new(&glass, kernel, f, LAMBDA).unwrap();
    let mut table = String::new();
    let head: String = ANGLES.iter().map(|a| format!(" {a}° |")).collect();
    let _ = writeln!(table, "| | material | light |{head}");
    let _ = writeln!(table, "|---|---|---|{}", "---|".repeat(ANGLES.len()));
    let mut lights: Vec<Light> = WIDTHS.iter().map(|&w| Light::Rule(w)).collect();
    lights.push(Light::Sun);
    lights.extend(WIDTHS.iter().map(|&w| Light::Fixed(w)));
    let (mut worst_forward, mut worst_backward) = (0.0, 0.0);
    for forward in [true, false] {
        for &light in &lights {
            if !forward && matches!(light, Light::Sun) {
                continue;
            }
            let worst = if forward {
                &mut worst_forward
            } else {
                &mut worst_backward
            };
            let dirn = if forward { "forward" } else { "backward" };
            for (name, is_metal) in [("conductor", true), ("glass", false)] {
                let cells = if is_metal {
                    row(&bm, light, forward, 1.0, n, worst)
                } else {
                    row(&bg, light, forward, 1.5, n, worst)
                };
                let line = format!("| {dirn} | {name} | {} |{cells}", light.name());
                println!("{line}");
                let _ = writeln!(table, "{line}");
            }
        }
    }
    let summary = format!(
        "\n{n} samples per cell, f32, Full·Partial. Largest |estimate − 1| with the recommended \
         coherences (the horizon rule, the sun): forward {worst_forward:.4}, backward \
         {worst_backward:.4}.\n"
    );
    println!("{summary}");
    table.push_str(&summary);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/furnace");
    if std::fs::create_dir_all(&dir).is_ok() {
        let _ = std::fs::write(dir.join("furnace.md"), table);
    }
}
