//! Criterion benches for locally-stationary matter and far-field propagation: the angular
//! spectrum S2.14 in closed form (f32, f64) against its quadrature, the random-field generator
//! (2-D and 3-D grids), a realization of a Jones field, and the S2.2 double integral.
//! Inputs are seeded and pass through `black_box`. Run:
//! `cargo bench --bench matter -- --warm-up-time 0.5 --measurement-time 1.5`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::jones::JonesMatrix;
use gmueller::matter::{
    Fluctuation, GaussianWindow, JonesFieldGenerator, MeanField, StationaryField,
};
use gmueller::mueller::Mueller;
use gmueller::propagation::{FarFieldPair, RegionNode, propagate_csd, smythe_projection};
use gmueller::verify::quadrature::gauss_legendre;
use gmueller::verify::rng::SplitMix64;
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use num_complex::Complex;

/// Seeded scattering vectors `q` (rad/µm) of size up to `scale`.
fn seeded_q(count: usize, scale: f64) -> Vec<Vector3<f64>> {
    let mut rng = SplitMix64(9);
    (0..count)
        .map(|_| Vector3::new(rng.signed(), rng.signed(), rng.signed()) * scale)
        .collect()
}

fn angular_spectrum_for<T: Real>(c: &mut Criterion, name: &str) {
    let mut group = c.benchmark_group(format!("angular_spectrum/{name}"));
    let w = Matrix3::new(0.16, 0.05, 0.0, 0.05, 0.09, 0.02, 0.0, 0.02, 0.25).map(T::lit);
    let window = GaussianWindow::new(
        Vector3::new(0.2, -0.1, 0.3).map(T::lit),
        w,
        Mueller::from_jones(&JonesMatrix::linear_retarder(T::lit(0.4), T::lit(0.9))),
    )
    .unwrap();
    let qs: Vec<Vector3<T>> = seeded_q(64, 3.0).iter().map(|q| q.map(T::lit)).collect();
    group.bench_function(BenchmarkId::new("closed_form", "gaussian"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(window.angular_spectrum(black_box(&qs[i])))
        });
    });
    // The degenerate input: q = 0 (S2.14's approximation M̃(0), i.e. |P| M₀).
    group.bench_function(BenchmarkId::new("closed_form", "q0"), |b| {
        b.iter(|| black_box(window.angular_spectrum(black_box(&Vector3::zeros()))));
    });
    group.finish();
}

/// The same transform by tensor Gauss–Legendre quadrature over ±4.5 µm (f64): what S2.14's
/// closed form replaces.
fn angular_spectrum_quadrature(c: &mut Criterion) {
    let mut group = c.benchmark_group("angular_spectrum/quadrature");
    group.sample_size(10);
    let w = Matrix3::new(0.16, 0.05, 0.0, 0.05, 0.09, 0.02, 0.0, 0.02, 0.25);
    let w_inv = w.try_inverse().unwrap();
    let qs = seeded_q(8, 3.0);
    for n in [24usize, 48] {
        let rule = gauss_legendre(n);
        group.bench_function(BenchmarkId::new("gauss_legendre", n), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & 7;
                let q = black_box(qs[i]);
                let mut sum = Complex::new(0.0, 0.0);
                for (x, wx) in rule.nodes.iter().zip(&rule.weights) {
                    for (y, wy) in rule.nodes.iter().zip(&rule.weights) {
                        for (z, wz) in rule.nodes.iter().zip(&rule.weights) {
                            let p = Vector3::new(*x, *y, *z) * 4.5;
                            let g = (-0.5 * p.dot(&(w_inv * p))).exp();
                            sum += Complex::new(0.0, -q.dot(&p)).exp() * (g * wx * wy * wz);
                        }
                    }
                }
                black_box(sum * 4.5f64.powi(3))
            });
        });
    }
    group.finish();
}

fn generator(c: &mut Criterion) {
    let mut group = c.benchmark_group("stationary_field");
    group.sample_size(20);
    let f2 = StationaryField::new([64, 64], [0.1, 0.1], |xi: &Vector2<f64>| {
        (-0.5 * xi.norm_squared() / 0.09).exp()
    })
    .unwrap();
    let f3 = StationaryField::new([32, 32, 32], [0.1; 3], |xi: &Vector3<f64>| {
        (-0.5 * xi.norm_squared() / 0.09).exp()
    })
    .unwrap();
    let mut rng = SplitMix64(1);
    let mut u2 = vec![Complex::new(0.0, 0.0); f2.len()];
    let mut u3 = vec![Complex::new(0.0, 0.0); f3.len()];
    group.bench_function(BenchmarkId::new("sample_complex", "64x64"), |b| {
        b.iter(|| f2.sample_complex(&mut || rng.unit(), black_box(&mut u2)));
    });
    group.bench_function(BenchmarkId::new("sample_complex", "32x32x32"), |b| {
        b.iter(|| f3.sample_complex(&mut || rng.unit(), black_box(&mut u3)));
    });
    let terms = [
        JonesMatrix::linear_retarder(0.3, 1.1),
        JonesMatrix::linear_polarizer(0.7),
    ];
    let mut jones = JonesFieldGenerator::new(
        f3.clone(),
        2,
        move |t, p| terms[t].scaled(Complex::from((-0.25 * p.norm_squared() / 0.25).exp())),
        Fluctuation::Real,
    )
    .unwrap();
    let mut out = vec![JonesMatrix::identity(); jones.len()];
    group.bench_function(BenchmarkId::new("jones_field", "32x32x32, 2 terms"), |b| {
        b.iter(|| jones.sample(&mut || rng.unit(), black_box(&mut out)));
    });
    group.finish();
}

fn double_integral(c: &mut Criterion) {
    let mut group = c.benchmark_group("propagate_csd");
    group.sample_size(10);
    let incident = Frame::sp(Vector3::new(0.3, 0.0, 1.0), Vector3::z()).unwrap();
    let r_hat = Vector3::new(0.5, 0.2, 0.8).normalize();
    let exit = Frame::sp(r_hat, Vector3::z()).unwrap();
    let p = smythe_projection(&incident, &exit, &Vector3::z());
    let pair = FarFieldPair::at_distance(1e4, &r_hat, &r_hat).unwrap();
    let k = std::f64::consts::TAU / 0.5;
    for side in [16i32, 32] {
        let d = 0.1;
        let nodes: Vec<RegionNode<f64>> = (0..side * side)
            .map(|i| RegionNode {
                position: Vector3::new(
                    f64::from(i % side - side / 2) * d,
                    f64::from(i / side - side / 2) * d,
                    0.0,
                ),
                weight: d * d,
            })
            .collect();
        let c0 = Matrix2::new(1.0, 0.2, 0.2, 0.5).map(Complex::from);
        let csd = |a: &Vector3<f64>, b: &Vector3<f64>| {
            let xi = a - b;
            let phase = Complex::new(0.0, k * incident.k().dot(&xi)).exp();
            c0 * (phase
                * (-0.5 * xi.norm_squared() / 0.09 - 0.5 * (a.norm_squared() + b.norm_squared()))
                    .exp())
        };
        group.bench_function(BenchmarkId::new("nodes", side * side), |b| {
            b.iter(|| black_box(propagate_csd(0.5, &pair, &p, black_box(&nodes), csd).unwrap()));
        });
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    angular_spectrum_for::<f64>(c, "f64");
    angular_spectrum_for::<f32>(c, "f32");
    angular_spectrum_quadrature(c);
    generator(c);
    double_integral(c);
}

criterion_group!(matter_benches, benches);
criterion_main!(matter_benches);
