//! Criterion benches of the roughness levels (`gmueller::interaction::roughness::{FirstOrder,
//! KirchhoffSeries, Geometric}`): the cost per exit direction of a prepared packet against
//! the first-order kernel, as a function of `g = (vσ)²` at the specular direction (10⁻², 1, 10,
//! 100, 10³, 10⁴), for `Intensity/Partial` with the phase screen and `Full/Partial` with the
//! tangent-plane pBSDF on glass (a polarized two-shape packet: three channels, each a series).
//! The series at tolerances 10⁻⁴ and 10⁻⁶ (the default; both hand over to the geometric limit
//! from `g = 2.5/tolerance`); the exits are 64 seeded directions around the lobe (within its
//! width `√g/ℓ` in `h_t`), through `black_box`; the degenerate case is the exact specular
//! direction. f64 and f32.
//!
//! Run: `cargo bench --bench roughness -- --warm-up-time 0.5 --measurement-time 1`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::pbsdf::{FresnelReflection, PhaseScreen, TangentPlane};
use gmueller::interaction::polarization::PolarizationModel;
use gmueller::interaction::roughness::{FirstOrder, Geometric, KirchhoffSeries, RoughnessWeights};
use gmueller::interaction::{Full, Geometry, Intensity, Kernel, Partial, RoughSurface};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussianPsd};
use gmueller::stokes::Stokes;
use gmueller::verify::rng::SplitMix64;
use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;

const N: usize = 64;
const LAMBDA: f64 = 0.5;
const ELL: f64 = 1.0;

fn surface<T: Real>() -> Frame<T> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}

/// A polarized packet at 30° with two coherence shapes (widths ~0.7–1 µm).
fn packet<T: Real>() -> WavePacket<T> {
    let l = T::lit;
    let travel = Vector3::new(0.5, 0.0, -(0.75f64).sqrt()).map(l);
    WavePacket::new(
        Stokes::new(l(1.0), l(0.3), l(0.2), l(-0.1)).unwrap(),
        CoherenceShape::new(Matrix2::new(0.5, 0.05, 0.05, 0.7).map(l)).unwrap(),
        CoherenceShape::new(Matrix2::new(0.55, 0.0, 0.0, 0.6).map(l)).unwrap(),
        Frame::sp(travel, Vector3::z()).unwrap(),
        l(LAMBDA),
    )
    .unwrap()
}

/// `σ` for `g` at the specular direction, and 64 seeded exits within the lobe (`h_t` within
/// `√(g + 1)/ℓ`, inside the horizon), the first one exactly specular.
fn exits<T: Real>(pk: &WavePacket<T>, g: f64) -> (f64, Vec<Geometry<T>>) {
    let k = std::f64::consts::TAU / LAMBDA;
    let v0 = 2.0 * k * (0.75f64).sqrt();
    let sigma = g.sqrt() / v0;
    let width = ((g + 1.0).sqrt() / ELL).min(0.4 * k);
    let mut rng = SplitMix64(0x5eed_1800 ^ g.to_bits());
    let mut out = Vec::with_capacity(N);
    while out.len() < N {
        let (hx, hy) = if out.is_empty() {
            (0.0, 0.0)
        } else {
            (rng.signed() * width, rng.signed() * width)
        };
        let rt = (0.5 + hx / k, hy / k);
        let s2 = rt.0 * rt.0 + rt.1 * rt.1;
        if s2 >= 0.96 {
            continue;
        }
        let exit = Vector3::new(rt.0, rt.1, (1.0 - s2).sqrt()).map(T::lit);
        out.push(Geometry::for_packet(pk, &surface(), exit).unwrap());
    }
    (sigma, out)
}

/// Times `kernel` over the exits of one `g` (per exit direction, prepared packet).
fn time<T, Pol, R, Sp, Sc>(
    c: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    g: f64,
    kernel: Kernel<Pol, Partial, R>,
    material: &RoughSurface<GaussianPsd<T, 2>, Sp, Sc>,
    pk: &WavePacket<T>,
    geometries: &[Geometry<T>],
) where
    T: Real,
    Pol: PolarizationModel,
    Partial: CoherenceWeights<T, GaussianPsd<T, 2>>,
    R: RoughnessWeights<T, GaussianPsd<T, 2>, Partial>,
    Sp: gmueller::interaction::pbsdf::Pbsdf<T>,
    Sc: gmueller::interaction::pbsdf::Pbsdf<T>,
{
    let prepared = kernel.prepare(pk, &surface()).unwrap();
    c.bench_with_input(BenchmarkId::new(name, format!("g={g:e}")), &g, |b, _| {
        b.iter(|| {
            for geo in geometries {
                black_box(kernel.evaluate_prepared(material, &prepared, black_box(geo)));
            }
        });
    });
    c.bench_with_input(
        BenchmarkId::new(format!("{name}/specular"), format!("g={g:e}")),
        &g,
        |b, _| {
            b.iter(|| {
                black_box(kernel.evaluate_prepared(material, &prepared, black_box(&geometries[0])))
            });
        },
    );
}

fn bench_precision<T: Real>(c: &mut Criterion, label: &str) {
    let pk = packet::<T>();
    let mut group = c.benchmark_group(format!("roughness/{label}"));
    group.throughput(criterion::Throughput::Elements(N as u64));
    for g in [1e-2, 1.0, 10.0, 100.0, 1e3, 1e4] {
        let (sigma, geos) = exits::<T>(&pk, g);
        let psd = GaussianPsd::<T, 2>::isotropic(T::lit(sigma), T::lit(ELL)).unwrap();
        let screen = RoughSurface {
            psd,
            specular: PhaseScreen::new(T::one()).unwrap(),
            scatter: PhaseScreen::new(T::one()).unwrap(),
        };
        let eta = Complex::new(T::lit(1.5), T::zero());
        let glass = RoughSurface {
            psd,
            specular: FresnelReflection::new(eta).unwrap(),
            scatter: TangentPlane::new(FresnelReflection::new(eta).unwrap()),
        };
        let intensity = Kernel::<Intensity, Partial>::new(Partial(ClosedForm));
        let full = Kernel::<Full, Partial>::new(Partial(ClosedForm));
        let tol4 = KirchhoffSeries::new(1e-4).unwrap();
        let tol6 = KirchhoffSeries::new(1e-6).unwrap();
        time(
            &mut group,
            "intensity/first-order",
            g,
            intensity.with_roughness(FirstOrder),
            &screen,
            &pk,
            &geos,
        );
        time(
            &mut group,
            "intensity/series-1e-4",
            g,
            intensity.with_roughness(tol4),
            &screen,
            &pk,
            &geos,
        );
        time(
            &mut group,
            "intensity/series-1e-6",
            g,
            intensity.with_roughness(tol6),
            &screen,
            &pk,
            &geos,
        );
        time(
            &mut group,
            "intensity/geometric",
            g,
            intensity.with_roughness(Geometric),
            &screen,
            &pk,
            &geos,
        );
        time(
            &mut group,
            "full/first-order",
            g,
            full.with_roughness(FirstOrder),
            &glass,
            &pk,
            &geos,
        );
        time(
            &mut group,
            "full/series-1e-6",
            g,
            full.with_roughness(tol6),
            &glass,
            &pk,
            &geos,
        );
        time(
            &mut group,
            "full/geometric",
            g,
            full.with_roughness(Geometric),
            &glass,
            &pk,
            &geos,
        );
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    bench_precision::<f64>(c, "f64");
    bench_precision::<f32>(c, "f32");
}

criterion_group!(roughness, benches);
criterion_main!(roughness);
