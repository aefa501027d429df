//! Criterion benches for Gaussian evaluation and PSD blur methods (closed form, mixture fit,
//! Gauss–Hermite, adaptive), f32 and f64, with seeded inputs through `black_box`.
//!
//! Each blur setting also prints (to stderr, once) its achieved relative error against the
//! adaptive reference at tol 1e-13, maximised over the seeded inputs, so time and error can be read
//! side by side. Run: `cargo bench --bench gaussian_psd -- --warm-up-time 0.5 --measurement-time 1`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::gaussian::Gaussian;
use gmueller::psd::{
    Adaptive, BlurMethod, ClosedForm, GaussHermite, GaussianPsd, Grating, KCorrelation,
    OrderCutoff, Psd,
};
use nalgebra::{Matrix2, Matrix3, SVector, Vector2};

/// A small LCG so the inputs are reproducible without a dependency.
fn seeded<const N: usize>(count: usize, scale: f64, seed: u64) -> Vec<SVector<f64, N>> {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * scale
    };
    (0..count)
        .map(|_| SVector::<f64, N>::from_fn(|_, _| next()))
        .collect()
}

fn cast<T: Real, const N: usize>(v: &[SVector<f64, N>]) -> Vec<SVector<T, N>> {
    v.iter().map(|x| x.map(T::lit)).collect()
}

fn gaussian_eval_for<T: Real>(c: &mut Criterion, name: &str) {
    let mut group = c.benchmark_group(format!("gaussian_value/{name}"));
    let g2 = Gaussian::new(Matrix2::new(2.0, 0.5, 0.5, 1.0).map(T::lit)).unwrap();
    let g3 =
        Gaussian::new(Matrix3::new(1.0, 0.3, -0.2, 0.3, 0.7, 0.15, -0.2, 0.15, 0.5).map(T::lit))
            .unwrap();
    let x2 = cast::<T, 2>(&seeded::<2>(64, 2.0, 1));
    let x3 = cast::<T, 3>(&seeded::<3>(64, 2.0, 2));
    group.bench_function(BenchmarkId::new("value", "n2"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(g2.value(black_box(&x2[i])))
        });
    });
    group.bench_function(BenchmarkId::new("value", "n3"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(g3.value(black_box(&x3[i])))
        });
    });
    group.bench_function(BenchmarkId::new("log_value", "n3"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(g3.log_value(black_box(&x3[i])))
        });
    });
    // Degenerate: anisotropy 1e6 and an argument far in the tail (underflow to 0).
    let thin = Gaussian::new(Matrix2::new(1.0, 0.0, 0.0, 1e-6).map(T::lit)).unwrap();
    let far = Vector2::new(T::lit(0.0), T::lit(1e3));
    group.bench_function(BenchmarkId::new("value_underflow", "n2"), |b| {
        b.iter(|| black_box(thin.value(black_box(&far))));
    });
    group.finish();
}

fn gaussian_eval(c: &mut Criterion) {
    gaussian_eval_for::<f32>(c, "f32");
    gaussian_eval_for::<f64>(c, "f64");
}

fn blur_closed_form_for<T: Real>(c: &mut Criterion, name: &str) {
    let mut group = c.benchmark_group(format!("blur_closed_form/{name}"));
    let cov = Gaussian::new(Matrix2::new(0.2, 0.05, 0.05, 0.1).map(T::lit)).unwrap();
    let hs = cast::<T, 2>(&seeded::<2>(64, 2.0, 3));
    let gpsd = GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(1.5)).unwrap();
    group.bench_function("gaussian_psd", |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(ClosedForm.blur(&gpsd, &cov, black_box(&hs[i])))
        });
    });
    let grating = Grating::<T, 2>::sinusoidal(
        T::lit(1.0),
        &Vector2::new(T::one(), T::zero()),
        T::lit(1.5),
        OrderCutoff {
            max_frequency: T::lit(30.0),
            tail: T::lit(1e-6),
        },
    )
    .unwrap();
    group.bench_function(
        BenchmarkId::new("grating_sinusoidal", grating.orders().len()),
        |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 63;
                black_box(ClosedForm.blur(&grating, &cov, black_box(&hs[i])))
            });
        },
    );
    // Degenerate: h far outside the lobe (underflow) and a near-delta blur.
    let tiny = Gaussian::new(Matrix2::new(1e-12, 0.0, 0.0, 1e-12).map(T::lit)).unwrap();
    let far = Vector2::new(T::lit(1e3), T::lit(-1e3));
    group.bench_function("gaussian_psd_degenerate", |b| {
        b.iter(|| black_box(ClosedForm.blur(&gpsd, black_box(&tiny), black_box(&far))));
    });
    group.finish();
}

fn blur_closed_form(c: &mut Criterion) {
    blur_closed_form_for::<f32>(c, "f32");
    blur_closed_form_for::<f64>(c, "f64");
}

/// Max relative error of `method` over the inputs, against the adaptive reference (f64).
fn achieved<M: BlurMethod<f64, 2, P>, P: Psd<f64, 2>>(
    method: &M,
    psd: &P,
    cov: &Gaussian<f64, 2>,
    hs: &[Vector2<f64>],
    reference: &[f64],
) -> f64 {
    hs.iter()
        .zip(reference)
        .map(|(h, r)| ((method.blur(psd, cov, h) - r) / r).abs())
        .fold(0.0, f64::max)
}

fn blur_methods(c: &mut Criterion) {
    let k = KCorrelation::<f64, 2>::new(0.01, 4.0, 2.2).unwrap();
    let k32 = KCorrelation::<f32, 2>::new(0.01, 4.0, 2.2).unwrap();
    let cov = Gaussian::new(Matrix2::new(0.2, 0.05, 0.05, 0.1)).unwrap();
    let cov32 = Gaussian::new(Matrix2::new(0.2_f32, 0.05, 0.05, 0.1)).unwrap();
    let hs = seeded::<2>(8, 1.5, 4);
    let hs32 = cast::<f32, 2>(&hs);
    let reference: Vec<f64> = hs
        .iter()
        .map(|h| Adaptive::new(1e-13).unwrap().blur(&k, &cov, h))
        .collect();

    let mut group = c.benchmark_group("blur_kcorrelation_mixture");
    for tol in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10] {
        let (mix, m, sup) = k.mixture_fit_to(tol).unwrap();
        let (mix32, _) = k32.mixture_fit(m).unwrap();
        eprintln!(
            "[achieved] mixture tol {tol:e}: m = {m}, sup|p−p_m|/p(0) = {sup:e}, max rel blur err = {:e}",
            achieved(&ClosedForm, &mix, &cov, &hs, &reference)
        );
        group.bench_function(BenchmarkId::new("f64_m", m), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 7;
                black_box(ClosedForm.blur(&mix, &cov, black_box(&hs[i])))
            });
        });
        group.bench_function(BenchmarkId::new("f32_m", m), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 7;
                black_box(ClosedForm.blur(&mix32, &cov32, black_box(&hs32[i])))
            });
        });
    }
    group.finish();

    let mut group = c.benchmark_group("blur_kcorrelation_gauss_hermite");
    for order in [4, 8, 16, 32] {
        let gh = GaussHermite::<f64>::new(order).unwrap();
        let gh32 = GaussHermite::<f32>::new(order).unwrap();
        eprintln!(
            "[achieved] Gauss–Hermite order {order}: max rel blur err = {:e}",
            achieved(&gh, &k, &cov, &hs, &reference)
        );
        group.bench_function(BenchmarkId::new("f64_order", order), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 7;
                black_box(gh.blur(&k, &cov, black_box(&hs[i])))
            });
        });
        group.bench_function(BenchmarkId::new("f32_order", order), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 7;
                black_box(gh32.blur(&k32, &cov32, black_box(&hs32[i])))
            });
        });
    }
    // Degenerate: a near-delta blur (the coherent limit).
    let tiny = Gaussian::new(Matrix2::new(1e-12, 0.0, 0.0, 1e-12)).unwrap();
    let gh = GaussHermite::<f64>::new(8).unwrap();
    group.bench_function("f64_order8_degenerate", |b| {
        b.iter(|| black_box(gh.blur(&k, black_box(&tiny), black_box(&hs[0]))));
    });
    group.finish();

    let mut group = c.benchmark_group("blur_kcorrelation_adaptive");
    group.sample_size(10);
    for tol in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10] {
        let ad = Adaptive::new(tol).unwrap();
        eprintln!(
            "[achieved] adaptive tol {tol:e}: max rel blur err = {:e}",
            achieved(&ad, &k, &cov, &hs, &reference)
        );
        group.bench_function(BenchmarkId::new("f64_tol", format!("{tol:e}")), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 7;
                black_box(ad.blur(&k, &cov, black_box(&hs[i])))
            });
        });
    }
    let ad32 = Adaptive::new(1e-4_f32).unwrap();
    group.bench_function("f32_tol_1e-4", |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 7;
            black_box(ad32.blur(&k32, &cov32, black_box(&hs32[i])))
        });
    });
    group.finish();
}

criterion_group!(benches, gaussian_eval, blur_closed_form, blur_methods);
criterion_main!(benches);
