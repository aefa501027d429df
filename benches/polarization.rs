//! Criterion benches for the polarization hot paths: Jones → Mueller (closed form and the literal
//! S1.7 formula), Mueller × Stokes, Mueller × Mueller, a frame rotation of a Stokes vector, Fresnel
//! reflection → Mueller (dielectric and conductor), the s/p frame of a direction (`Frame::sp`) and
//! the Mueller matrix of a frame change (`frame_change_mueller`), in f32 and f64. Inputs are seeded
//! and pass through `black_box`. Run:
//! `cargo bench --bench polarization -- --warm-up-time 0.5 --measurement-time 1`.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::frame::{Frame, frame_change_mueller, rotation_mueller};
use gmueller::fresnel;
use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::real::Real;
use gmueller::stack::kron;
use gmueller::stokes::{Stokes, a_mul, a_mul_inv};
use nalgebra::{Matrix2, Matrix4, Vector3};
use num_complex::Complex;

/// The tests' deterministic generator (`SplitMix64`) so every run benches the same inputs.
use gmueller::verify::rng::SplitMix64 as SplitMix;

/// This bench's draw: uniform in `[-1, 1)` (the shared generator's `signed`).
trait NextF64 {
    fn next_f64(&mut self) -> f64;
}
impl NextF64 for SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.signed()
    }
}

fn jones<T: Real>(rng: &mut SplitMix) -> JonesMatrix<T> {
    let mut c = || Complex::new(T::lit(rng.next_f64()), T::lit(rng.next_f64()));
    JonesMatrix::from_matrix(Matrix2::new(c(), c(), c(), c())).expect("finite by construction")
}

/// The literal S1.7 formula `A_mül (J* ⊗ J) A_mül⁻¹`, the oracle the closed form is tested against.
fn literal<T: Real>(j: &JonesMatrix<T>) -> Matrix4<T> {
    let m = j.matrix();
    let full = a_mul::<T>() * kron(&m.map(|z| z.conj()), &m) * a_mul_inv::<T>();
    full.map(|z| z.re)
}

fn bench_precision<T: Real>(c: &mut Criterion, name: &str) {
    let mut rng = SplitMix(0x5EED);
    let js: Vec<JonesMatrix<T>> = (0..64).map(|_| jones(&mut rng)).collect();
    let zero = JonesMatrix::<T>::from_matrix(Matrix2::zeros()).expect("finite");

    let mut g = c.benchmark_group(format!("jones_to_mueller/{name}"));
    g.bench_function(BenchmarkId::new("closed_form", "random"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            Mueller::from_jones(black_box(&js[i]))
        })
    });
    g.bench_function(BenchmarkId::new("literal_kronecker", "random"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            literal(black_box(&js[i]))
        })
    });
    g.bench_function(BenchmarkId::new("closed_form", "zero_matrix"), |b| {
        b.iter(|| Mueller::from_jones(black_box(&zero)))
    });
    g.finish();

    let ms: Vec<Mueller<T>> = js.iter().map(Mueller::from_jones).collect();
    let s = Stokes::new(T::one(), T::lit(0.3), T::lit(-0.2), T::lit(0.5)).expect("valid");
    let mut g = c.benchmark_group(format!("mueller_ops/{name}"));
    g.bench_function(BenchmarkId::new("mueller_times_stokes", "random"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(ms[i]) * black_box(s)
        })
    });
    g.bench_function(BenchmarkId::new("mueller_times_mueller", "random"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(ms[i]) * black_box(ms[(i + 7) & 63])
        })
    });
    g.bench_function(BenchmarkId::new("rotate_stokes", "random_angle"), |b| {
        let mut x = T::zero();
        b.iter(|| {
            x += T::lit(0.01);
            rotation_mueller(black_box(x)) * black_box(s)
        })
    });
    g.bench_function(BenchmarkId::new("rotate_stokes", "zero_angle"), |b| {
        b.iter(|| rotation_mueller(black_box(T::zero())) * black_box(s))
    });
    g.finish();

    // Fresnel reflection → Mueller at seeded cos θ_i ∈ (0, 1].
    let cosines: Vec<T> = (0..64)
        .map(|_| T::lit(0.5 + 0.499 * rng.next_f64()))
        .collect();
    let mut g = c.benchmark_group(format!("fresnel_mueller/{name}"));
    for (label, eta) in [
        ("glass", Complex::new(T::lit(1.5), T::zero())),
        ("aluminium", Complex::new(T::lit(0.96), T::lit(6.69))),
    ] {
        g.bench_function(BenchmarkId::new("reflection_to_mueller", label), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 63;
                Mueller::from_jones(&fresnel::reflection(black_box(cosines[i]), black_box(eta)))
            })
        });
    }
    g.finish();

    // Frames: the s/p frame of a direction, and the Mueller matrix between two frames.
    let normal = Vector3::new(T::zero(), T::zero(), T::one());
    let dirs: Vec<Vector3<T>> = (0..64)
        .map(|_| {
            Vector3::new(
                T::lit(rng.next_f64()),
                T::lit(rng.next_f64()),
                T::lit(-0.2 - 0.8 * rng.next_f64().abs()),
            )
        })
        .collect();
    let frames: Vec<Frame<T>> = dirs
        .iter()
        .map(|d| Frame::sp(*d, normal).expect("valid direction"))
        .collect();
    let rotated: Vec<Frame<T>> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| f.rotated(T::lit(0.1 * i as f64)))
        .collect();
    let reversed: Vec<Frame<T>> = frames.iter().map(Frame::reversed).collect();
    let mut g = c.benchmark_group(format!("frames/{name}"));
    g.bench_function(BenchmarkId::new("frame_sp", "random"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            Frame::sp(black_box(dirs[i]), black_box(normal))
        })
    });
    g.bench_function(BenchmarkId::new("frame_change_mueller", "same_k"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            frame_change_mueller(black_box(&frames[i]), black_box(&rotated[i]))
        })
    });
    g.bench_function(
        BenchmarkId::new("frame_change_mueller", "reversed_k"),
        |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 63;
                frame_change_mueller(black_box(&frames[i]), black_box(&reversed[i]))
            })
        },
    );
    g.finish();
}

/// The structure-of-arrays batch path, per iteration one call on `n` matrices (time per matrix =
/// time / n; criterion also prints the rate). Inputs and outputs each live in one buffer, slices
/// `padded_stride(n)` apart: `soa/1024` (the figure of merit: 1024 matrices, in L2), `soa/128`
/// (all 24 slices in L1), `soa/7` (shorter than one f32 vector: the masked remainder only, the
/// degenerate case), and `soa_stride_n/1024` (slices exactly `n` apart, so all start at one
/// address modulo 4 KiB: the layout `padded_stride` avoids).
fn bench_batch<T: Real>(c: &mut Criterion, name: &str) {
    use gmueller::mueller::batch::{JonesSoa, MuellerSoa, mueller_from_jones_soa, padded_stride};
    let mut rng = SplitMix(0xBA7C);
    let mut g = c.benchmark_group(format!("jones_to_mueller_batch/{name}"));
    for (label, n, stride) in [
        ("soa", 1024, padded_stride::<T>(1024)),
        ("soa", 128, padded_stride::<T>(128)),
        ("soa", 7, padded_stride::<T>(7)),
        ("soa_stride_n", 1024, 1024),
    ] {
        let inputs: Vec<T> = (0..8 * stride).map(|_| T::lit(rng.next_f64())).collect();
        let mut buf: Vec<T> = std::iter::repeat_n(T::zero(), 16 * stride).collect();
        g.throughput(criterion::Throughput::Elements(n as u64));
        let soa = JonesSoa::from_strided(&inputs, n, stride).expect("fits");
        let mut out = MuellerSoa::from_strided(&mut buf, n, stride).expect("fits");
        g.bench_function(BenchmarkId::new(label, n), |b| {
            b.iter(|| {
                mueller_from_jones_soa(black_box(&soa), black_box(&mut out))
                    .expect("equal lengths");
            })
        });
    }
    g.finish();
}

fn benches(c: &mut Criterion) {
    bench_batch::<f32>(c, "f32");
    bench_batch::<f64>(c, "f64");
    bench_precision::<f32>(c, "f32");
    bench_precision::<f64>(c, "f64");
}

criterion_group!(polarization, benches);
criterion_main!(polarization);
