//! Criterion benches of the renderer layer (`gmueller::bsdf`) beyond first order in the heights:
//! rough glass with the tangent-plane scatterer (`KirchhoffDielectric`, Gaussian PSD, ℓ = 2 µm,
//! η = 1.5) at `vσ ≈ 1, 3, 10` (σ = 0.04, 0.12, 0.4 µm at 0.5 µm, normal incidence), `Full ·
//! Partial`, `f64` and `f32`, at the roughness levels `FirstOrder`, `KirchhoffSeries::new(1e-4)`
//! and `Geometric`, over 64 seeded shading configurations (incidence 0–70° from either side,
//! exits spread over the rough lobe, 3 µm of surface coherence or sunlight):
//! - `eval`: `Bsdf::eval` (the geometry built inside);
//! - `exit_build+sample+pdf`: `Bsdf::exit_sampler` + `LobeSampler::sample` + `LobeSampler::pdf`
//!   (forward);
//! - `incident_build+sample+pdf`: `Bsdf::incident_sampler` + `sample` + `pdf` (backward).
//!
//! Run: `cargo bench --bench bsdf_rough -- --warm-up-time 0.5 --measurement-time 1.5`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::bsdf::{Bsdf, SurfaceCoherence};
use gmueller::interaction::roughness::{Geometric, KirchhoffSeries, RoughnessWeights};
use gmueller::interaction::{Full, Kernel, KirchhoffDielectric, Partial};
use gmueller::psd::{ClosedForm, GaussianPsd};
use gmueller::stokes::Stokes;
use gmueller::verify::rng::SplitMix64;
use nalgebra::Vector3;

const N: usize = 64;

type Glass<T> = KirchhoffDielectric<T, GaussianPsd<T, 2>>;

/// One seeded shading configuration: toward the source, an exit, sunlight or surface coherence.
struct Case<T: Real> {
    to_source: Vector3<T>,
    exit: Vector3<T>,
    sun: bool,
}

#[path = "common/shading.rs"]
mod shading;
use shading::{dir, frame};

/// Exits within ±0.4 rad of the mirror direction (3 of 4) or anywhere in the other hemisphere
/// up to 80°: the rough lobes are wide, so the exits are too.
fn cases<T: Real>() -> Vec<Case<T>> {
    let f = frame::<T>();
    let mut rng = SplitMix64(0x5eed_b5df);
    (0..N)
        .map(|i| {
            let side = if i % 4 == 3 { -1.0 } else { 1.0 };
            let ti = rng.unit() * 70f64.to_radians();
            let phi = rng.unit() * std::f64::consts::TAU;
            let exit = if i % 3 == 2 {
                dir(
                    &f,
                    rng.unit() * 80f64.to_radians(),
                    rng.unit() * std::f64::consts::TAU,
                    -side,
                )
            } else {
                let t = (ti + (rng.unit() - 0.5) * 0.8).abs().min(1.4);
                dir(&f, t, phi + std::f64::consts::PI, side)
            };
            Case {
                to_source: dir(&f, ti, phi, side),
                exit,
                sun: i % 2 == 0,
            }
        })
        .collect()
}

fn bench_level<T, R>(
    c: &mut Criterion,
    group: &str,
    name: &str,
    glass: &Glass<T>,
    kernel: Kernel<Full, Partial<ClosedForm>, R>,
) where
    T: Real,
    R: RoughnessWeights<T, GaussianPsd<T, 2>, Partial<ClosedForm>>,
{
    let cases = cases::<T>();
    let b = Bsdf::new(glass, kernel, frame::<T>(), T::lit(0.5)).unwrap();
    let stokes = Stokes::unpolarized(T::one()).unwrap();
    let coherence = SurfaceCoherence::new(T::lit(3.0)).unwrap();
    let incidents: Vec<_> = cases
        .iter()
        .map(|c| {
            let p = if c.sun {
                b.distant_packet(stokes, T::lit(6.8e-5), c.to_source)
            } else {
                b.surface_packet(stokes, c.to_source, &coherence)
            };
            b.prepare(&p.unwrap()).unwrap()
        })
        .collect();
    let mut rng = SplitMix64(7);
    let uniforms: Vec<[T; 3]> = (0..N)
        .map(|_| [rng.unit(), rng.unit(), rng.unit()].map(T::lit))
        .collect();
    let mut g = c.benchmark_group(group);
    g.bench_function(BenchmarkId::new("eval", name), |bench| {
        let mut i = 0;
        bench.iter(|| {
            i = (i + 1) & (N - 1);
            black_box(b.eval(black_box(&incidents[i]), black_box(cases[i].exit)))
        });
    });
    g.bench_function(BenchmarkId::new("exit_build+sample+pdf", name), |bench| {
        let mut i = 0;
        bench.iter(|| {
            i = (i + 1) & (N - 1);
            let s = b.exit_sampler(black_box(&incidents[i])).unwrap();
            let u = uniforms[i];
            let d = s.sample(u[0], [u[1], u[2]]);
            black_box((d, s.pdf(black_box(&cases[i].exit))))
        });
    });
    g.bench_function(
        BenchmarkId::new("incident_build+sample+pdf", name),
        |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                let s = b
                    .incident_sampler(black_box(cases[i].exit), &coherence)
                    .unwrap();
                let u = uniforms[i];
                let d = s.sample(u[0], [u[1], u[2]]);
                black_box((d, s.pdf(black_box(&cases[i].to_source))))
            });
        },
    );
    g.finish();
}

fn for_precision<T: Real>(c: &mut Criterion, prec: &str) {
    for (sigma, step) in [(0.04, "vs1"), (0.12, "vs3"), (0.4, "vs10")] {
        let glass = Glass::<T>::new(
            GaussianPsd::isotropic(T::lit(sigma), T::lit(2.0)).unwrap(),
            T::lit(1.5),
        )
        .unwrap();
        let group = format!("bsdf_rough/{prec}");
        let first = Kernel::<Full, Partial<ClosedForm>>::default();
        bench_level(c, &group, &format!("{step}/first_order"), &glass, first);
        let series = first.with_roughness(KirchhoffSeries::new(1e-4).unwrap());
        bench_level(c, &group, &format!("{step}/series_1e-4"), &glass, series);
        let geometric = first.with_roughness(Geometric);
        bench_level(c, &group, &format!("{step}/geometric"), &glass, geometric);
    }
}

fn benches(c: &mut Criterion) {
    for_precision::<f64>(c, "f64");
    for_precision::<f32>(c, "f32");
}

criterion_group!(bsdf_rough, benches);
criterion_main!(bsdf_rough);
