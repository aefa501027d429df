//! Criterion benches of the random medium (`gmueller::medium`) per model level and precision,
//! on a Gaussian medium (rms δε 1e-3, ℓ = 0.5 µm, the dipole scatterer) at 64 seeded packets
//! (any direction, λ = 0.5 µm, coherence widths 2–50 µm, `σ_zz` 5–50 µm; every other packet
//! polarized with two shapes `Θ_y = 1.3² Θ_x`) and exit directions (case 0: exactly forward,
//! the degenerate case):
//! - `prepare/axial`: `PhaseFunction::prepare` (`σ_s` by quadrature over the sphere, the sampler)
//!   with isotropic transverse shapes (4 azimuths of the rule); `prepare/anisotropic`: the same
//!   packets with anisotropic shapes (condition 4, 32 azimuths);
//! - `eval`: the phase matrix of a prepared packet; `differential`: `dI/dV` (no `σ_s`);
//! - `sample`: a draw with its pdf and weight `F/pdf` (one `eval` included); `pdf`: the
//!   density alone.
//!
//! Run: `cargo bench --bench medium -- --warm-up-time 0.5 --measurement-time 1.5`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::polarization::PolarizationModel;
use gmueller::interaction::{Full, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave};
use gmueller::medium::{Dipole, PhaseFunction, RandomMedium, VolumeCoherence, VolumeIncident};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::verify::rng::SplitMix64;
use nalgebra::{Matrix2, Vector3};

const N: usize = 64;

type Medium<T> = RandomMedium<GaussianPsd<T, 3>, Dipole>;

struct Cases<T: Real> {
    axial: Vec<WavePacket<T>>,
    anisotropic: Vec<WavePacket<T>>,
    exits: Vec<Vector3<T>>,
    uniforms: Vec<[T; 3]>,
}

fn unit(rng: &mut SplitMix64) -> Vector3<f64> {
    let z = 2.0 * rng.unit() - 1.0;
    let p = std::f64::consts::TAU * rng.unit();
    let s = (1.0 - z * z).sqrt();
    Vector3::new(s * p.cos(), s * p.sin(), z)
}

fn cases<T: Real>() -> Cases<T> {
    let mut rng = SplitMix64(0x3d3d);
    let (mut axial, mut anisotropic, mut exits, mut uniforms) = (vec![], vec![], vec![], vec![]);
    for i in 0..N {
        let d = unit(&mut rng);
        let f = Frame::from_direction_and_x(d.map(T::lit), unit(&mut rng).map(T::lit)).unwrap();
        let w = 2.0 + 48.0 * rng.unit();
        let zz = 5.0 + 45.0 * rng.unit();
        let (stokes, ratio) = if i % 2 == 0 {
            (Stokes::unpolarized(T::one()).unwrap(), 1.0)
        } else {
            (
                Stokes::new(T::one(), T::lit(0.3), T::lit(0.2), T::lit(-0.1)).unwrap(),
                1.69,
            )
        };
        let make = |shape: Matrix2<f64>| {
            WavePacket::new(
                stokes,
                CoherenceShape::new(shape.map(T::lit)).unwrap(),
                CoherenceShape::new((shape * ratio).map(T::lit)).unwrap(),
                f,
                T::lit(0.5),
            )
            .unwrap()
            .with_longitudinal_coherence(T::lit(zz))
            .unwrap()
        };
        axial.push(make(Matrix2::identity() * (w * w)));
        anisotropic.push(make(Matrix2::new(2.0, 0.8, 0.8, 0.7) * (w * w)));
        // Exits: mostly within the forward lobe (kℓ ≈ 6), case 0 exactly forward.
        let e = if i == 0 {
            d
        } else {
            (d + unit(&mut rng) * (0.05 + 1.5 * rng.unit())).normalize()
        };
        exits.push(e.map(T::lit));
        uniforms.push([rng.unit(), rng.unit(), rng.unit()].map(T::lit));
    }
    Cases {
        axial,
        anisotropic,
        exits,
        uniforms,
    }
}

fn level<T, Pol, Coh>(
    c: &mut Criterion,
    prec: &str,
    name: &str,
    m: &Medium<T>,
    kernel: Kernel<Pol, Coh>,
    cases: &Cases<T>,
) where
    T: Real,
    Pol: PolarizationModel,
    Coh: VolumeCoherence<T, GaussianPsd<T, 3>>,
{
    let phase = PhaseFunction::new(m, kernel);
    let incidents: Vec<VolumeIncident<T, Pol, Coh>> = cases
        .axial
        .iter()
        .map(|p| phase.prepare(p).unwrap())
        .collect();
    let mut g = c.benchmark_group(format!("medium/{prec}"));
    for (kind, packets) in [
        ("prepare/axial", &cases.axial),
        ("prepare/anisotropic", &cases.anisotropic),
    ] {
        g.bench_function(BenchmarkId::new(kind, name), |b| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) & (N - 1);
                black_box(phase.prepare(black_box(&packets[i])).unwrap())
            });
        });
    }
    g.bench_function(BenchmarkId::new("eval", name), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (N - 1);
            black_box(
                phase
                    .eval(black_box(&incidents[i]), black_box(cases.exits[i]))
                    .unwrap(),
            )
        });
    });
    g.bench_function(BenchmarkId::new("differential", name), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (N - 1);
            black_box(
                phase
                    .differential_scattering(black_box(&incidents[i]), black_box(cases.exits[i]))
                    .unwrap(),
            )
        });
    });
    g.bench_function(BenchmarkId::new("sample", name), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (N - 1);
            let u = cases.uniforms[i];
            black_box(phase.sample(black_box(&incidents[i]), u[0], [u[1], u[2]]))
        });
    });
    g.bench_function(BenchmarkId::new("pdf", name), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (N - 1);
            black_box(phase.pdf(black_box(&incidents[i]), black_box(&cases.exits[i])))
        });
    });
    g.finish();
}

fn for_precision<T: Real>(c: &mut Criterion, prec: &str) {
    let m = RandomMedium::new(
        GaussianPsd::<T, 3>::isotropic(T::lit(1e-3), T::lit(0.5)).unwrap(),
        Dipole,
    );
    let cases = cases::<T>();
    level(
        c,
        prec,
        "Full·Partial",
        &m,
        Kernel::<Full, Partial>::default(),
        &cases,
    );
    level(
        c,
        prec,
        "OneShape·Partial",
        &m,
        Kernel::<OneShape, Partial>::default(),
        &cases,
    );
    level(
        c,
        prec,
        "Intensity·Partial",
        &m,
        Kernel::<Intensity, Partial>::default(),
        &cases,
    );
    level(
        c,
        prec,
        "Full·PlaneWave",
        &m,
        Kernel::<Full, PlaneWave>::default(),
        &cases,
    );
    level(
        c,
        prec,
        "Full·Incoherent",
        &m,
        Kernel::<Full, Incoherent>::default(),
        &cases,
    );
}

fn benches(c: &mut Criterion) {
    for_precision::<f64>(c, "f64");
    for_precision::<f32>(c, "f32");
}

criterion_group!(medium, benches);
criterion_main!(medium);
