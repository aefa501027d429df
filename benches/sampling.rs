//! Criterion benches for the wave-BSDF importance sampler: `sample` and `pdf` of the Gaussian
//! and K-correlation (mixture) samplers, f32 and f64, seeded inputs through `black_box`, plus
//! construction (the adaptive angular table) and a degenerate grazing case (80°, wide lobe).
//! Run: `cargo bench --bench sampling -- --warm-up-time 0.5 --measurement-time 1`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::sampling::ScatterSampler;
use gmueller::psd::{GaussianPsd, KCorrelation};
use nalgebra::Vector3;

/// A small LCG so the inputs are reproducible without a dependency.
fn uniforms(count: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..count).map(|_| [next(), next()]).collect()
}

fn setup<T: Real>(deg: f64) -> (Frame<T>, Vector3<T>, T) {
    let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let t = deg.to_radians();
    let to_source = Vector3::new(T::lit(-t.sin()), T::zero(), T::lit(t.cos()));
    (surface, to_source, T::lit(core::f64::consts::TAU / 0.5))
}

fn samplers<T: Real>() -> Vec<(&'static str, ScatterSampler<T>)> {
    let (surface, src, k) = setup::<T>(30.0);
    let (_, graze, _) = setup::<T>(80.0);
    let g = GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(2.0)).unwrap();
    let kc = KCorrelation::<T, 2>::new(T::lit(1e-4), T::lit(1.0), T::lit(2.0)).unwrap();
    vec![
        (
            "gaussian",
            ScatterSampler::gaussian(&g, &surface, &src, k, T::lit(1.0)).unwrap(),
        ),
        (
            "k_correlation",
            ScatterSampler::k_correlation(&kc, &surface, &src, k, T::lit(1.0)).unwrap(),
        ),
        (
            "gaussian_grazing",
            ScatterSampler::gaussian(&g, &surface, &graze, k, T::lit(0.15)).unwrap(),
        ),
    ]
}

fn bench_for<T: Real>(c: &mut Criterion, name: &str) {
    let mut group = c.benchmark_group(format!("sampling/{name}"));
    let us: Vec<[T; 2]> = uniforms(256, 42)
        .iter()
        .map(|u| [T::lit(u[0]), T::lit(u[1])])
        .collect();
    for (label, sampler) in samplers::<T>() {
        let dirs: Vec<Vector3<T>> = us.iter().map(|u| sampler.sample(*u).direction).collect();
        eprintln!(
            "{name}/{label}: {} table panels, masses {:?}",
            sampler
                .components()
                .map(|(_, l)| l.table_size())
                .sum::<usize>(),
            sampler
                .components()
                .map(|(_, l)| l.truncated_mass().to_f64())
                .collect::<Vec<_>>()
        );
        group.bench_function(BenchmarkId::new("sample", label), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 255;
                black_box(sampler.sample(black_box(us[i])))
            });
        });
        group.bench_function(BenchmarkId::new("pdf", label), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 255;
                black_box(sampler.pdf(black_box(&dirs[i])))
            });
        });
    }
    let (surface, src, k) = setup::<T>(30.0);
    let g = GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(2.0)).unwrap();
    group.bench_function(BenchmarkId::new("construct", "gaussian"), |b| {
        b.iter(|| ScatterSampler::gaussian(black_box(&g), &surface, &src, k, T::lit(1.0)).unwrap());
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    bench_for::<f32>(c, "f32");
    bench_for::<f64>(c, "f64");
}

criterion_group!(sampling, benches);
criterion_main!(sampling);
