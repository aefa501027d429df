//! A fixed workload for counting the instructions of one scalar bounce of the renderer layer
//! with callgrind: `Bsdf::sample_incident` (a backward bounce: build the sampler, draw, weigh),
//! `Bsdf::sample_exit` (a forward bounce), `Bsdf::eval` (of a prepared light) or
//! `Bsdf::eval_stokes` (its Stokes form), on rough glass (Gaussian PSD σ = 10 nm, ℓ = 2 µm,
//! η = 1.5, a tilted shading frame) at `Full · Partial`, `OneShape · Partial` or
//! `Intensity · Partial`, `f32`, over 20 000 seeded configurations (exits 0–69° on either side,
//! 3–30 µm of surface coherence): the scene of the `bsdf` bench. The cost of one call is the
//! difference of two runs over 20 000 × (the difference of their `reps`):
//!
//! ```text
//! cargo build --release --example bounce_count
//! valgrind --tool=callgrind target/release/examples/bounce_count incident full 1
//! valgrind --tool=callgrind target/release/examples/bounce_count incident full 2
//! ```
//!
//! (`incident | exit | eval | stokes`, `full | oneshape | intensity`, passes). It prints a
//! checksum so that the work is not optimised away.

use std::hint::black_box;

use gmueller::bsdf::{Bsdf, BsdfKernel, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::polarization::{KernelOutput, Throughput};
use gmueller::interaction::{Full, Intensity, Kernel, OneShape, Partial, RoughDielectric};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::verify::rng::SplitMix64;
use nalgebra::Vector3;

/// Configurations per pass.
const N: usize = 20_000;

type Glass = RoughDielectric<f32, GaussianPsd<f32, 2>>;

/// `reps` passes of `call` over the `N` configurations; the sum of what it returns.
fn run<K: BsdfKernel<f32, GaussianPsd<f32, 2>>>(
    glass: &Glass,
    kernel: K,
    call: &str,
    reps: usize,
) -> f64 {
    let f = Frame::from_normal(Vector3::new(0.1f32, -0.2, 1.0)).unwrap();
    let b = Bsdf::new(glass, kernel, f, 0.55).unwrap();
    let mut rng = SplitMix64(7);
    let local = |t: f64, p: f64, side: f64| {
        let v = Vector3::new(t.sin() * p.cos(), t.sin() * p.sin(), side * t.cos());
        f.x() * v.x as f32 + f.y() * v.y as f32 + f.k() * v.z as f32
    };
    let cases: Vec<_> = (0..N)
        .map(|i| {
            let side = if i % 4 == 3 { -1.0 } else { 1.0 };
            let exit = local(rng.unit() * 1.2, rng.unit() * std::f64::consts::TAU, side);
            let source = local(rng.unit() * 1.2, rng.unit() * std::f64::consts::TAU, side);
            let coherence = SurfaceCoherence::new(3.0 + 27.0 * rng.unit() as f32).unwrap();
            let u = [rng.unit() as f32, rng.unit() as f32, rng.unit() as f32];
            (exit, source, coherence, u)
        })
        .collect();
    let unpolarized = Stokes::unpolarized(1.0).unwrap();
    let lights: Vec<_> = cases
        .iter()
        .map(|(_, s, c, _)| {
            b.prepare(&b.surface_packet(unpolarized, *s, c).unwrap())
                .unwrap()
        })
        .collect();
    let mut sum = 0.0;
    for _ in 0..reps {
        sum = 0.0;
        for ((exit, _, coherence, u), light) in cases.iter().zip(&lights) {
            let v = match call {
                "incident" => b
                    .sample_incident(black_box(*exit), coherence, u[0], [u[1], u[2]])
                    .ok()
                    .flatten()
                    .map_or(0.0, |s| s.weight.to_mueller().matrix()[(0, 0)]),
                "exit" => b
                    .sample_exit(black_box(light), u[0], [u[1], u[2]])
                    .ok()
                    .flatten()
                    .map_or(0.0, |s| s.weight.to_mueller().matrix()[(0, 0)]),
                "stokes" => b
                    .eval_stokes(black_box(light), *exit)
                    .map_or(0.0, |v| v.total_intensity()),
                _ => b
                    .eval(black_box(light), *exit)
                    .map_or(0.0, |v| v.response.total().to_mueller().matrix()[(0, 0)]),
            };
            sum += f64::from(v);
        }
    }
    sum
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let call = args.get(1).map_or("incident", String::as_str);
    let level = args.get(2).map_or("full", String::as_str);
    let reps = args.get(3).and_then(|r| r.parse().ok()).unwrap_or(1);
    let glass = RoughDielectric::new(GaussianPsd::isotropic(0.01, 2.0).unwrap(), 1.5).unwrap();
    let sum = if level == "oneshape" {
        run(&glass, Kernel::<OneShape, Partial>::default(), call, reps)
    } else if level == "intensity" {
        run(&glass, Kernel::<Intensity, Partial>::default(), call, reps)
    } else {
        run(&glass, Kernel::<Full, Partial>::default(), call, reps)
    };
    println!("{call} {level} x{reps}: checksum {sum:.6e}");
}
