//! Criterion bench of the type-erased material (`bsdf::Material`) against the static `Bsdf`
//! of the same choice, per call a renderer makes at a vertex (issue 37: the erased form may
//! cost at most 5 % more):
//! - `sample_incident`: build the `Bsdf` at the shading point, draw the direction the light
//!   comes from and weigh it (backward BSDF sampling);
//! - `eval_incident`: build, prepare the light of a direction (`Bsdf::prepare_surface`), eval
//!   (light sampling and MIS).
//!
//! Rough glass (Gaussian PSD σ = 10 nm, ℓ = 2 µm, η = 1.5) and rough gold (η = 0.2 + 3.5i) at
//! 64 seeded configurations, Full · Partial and Intensity · Partial, f32 and f64.
//!
//! Run: `cargo bench --bench material -- --warm-up-time 0.5 --measurement-time 1.5`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::bsdf::{Bsdf, Material, ShadingPoint, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::polarization::PolarizationModel;
use gmueller::interaction::polarization::Throughput;
use gmueller::interaction::{
    Full, Intensity, Kernel, Level, Partial, RoughConductor, RoughDielectric, RoughSurface,
};
use gmueller::psd::GaussianPsd;
use gmueller::verify::rng::SplitMix64;
use nalgebra::Vector3;
use num_complex::Complex;

const N: usize = 64;

/// One call's inputs: shading point, exit, direction to the source, uniforms.
type Call<T> = (ShadingPoint<T>, Vector3<T>, Vector3<T>, [T; 3]);

/// Per call, as a renderer makes them: a shading point of its own (a tilted frame, a
/// wavelength in 0.4–0.7 µm), an exit direction, a direction to the source and uniforms.
/// (With one shading point for all calls the compiler could hoist the static form's per-point
/// work out of the loop, which a renderer never sees.)
fn cases<T: Real>() -> Vec<Call<T>> {
    let mut rng = SplitMix64(0x3a7e);
    (0..N)
        .map(|_| {
            let n = Vector3::new(rng.unit() - 0.5, rng.unit() - 0.5, 2.0).map(T::lit);
            let f = Frame::from_normal(n).unwrap();
            let at = ShadingPoint::new(f, T::lit(0.4 + 0.3 * rng.unit())).unwrap();
            let mut d = |side: f64| {
                let t = rng.unit() * 70f64.to_radians();
                let p = rng.unit() * std::f64::consts::TAU;
                (f.x() * T::lit(t.sin() * p.cos())
                    + f.y() * T::lit(t.sin() * p.sin())
                    + f.k() * T::lit(side * t.cos()))
                .normalize()
            };
            let (exit, source) = (d(1.0), d(1.0));
            let u = [rng.unit(), rng.unit(), rng.unit()].map(T::lit);
            (at, exit, source, u)
        })
        .collect()
}

fn run<T: Real, Sp, Pol>(
    c: &mut Criterion,
    name: &str,
    surface: &RoughSurface<GaussianPsd<T, 2>, Sp, gmueller::interaction::pbsdf::RayleighRice<T>>,
    level: Level,
) where
    Sp: gmueller::bsdf::Interface<T> + Clone + std::fmt::Debug + Send + Sync + 'static,
    Pol: PolarizationModel,
    gmueller::psd::ClosedForm: gmueller::psd::BlurMethod<T, 2, GaussianPsd<T, 2>>,
{
    let sky = SurfaceCoherence::new(T::lit(20.0)).unwrap();
    let cases = cases::<T>();
    let kernel = Kernel::<Pol, Partial>::default();
    let material = Material::new(surface.clone(), level);
    let precision = core::any::type_name::<T>();
    let mut g = c.benchmark_group(format!("material/{name}/{}/{precision}", level.name()));
    g.bench_function(BenchmarkId::new("sample_incident", "static"), |b| {
        b.iter(|| {
            let mut acc = T::zero();
            for (at, exit, _, u) in &cases {
                let bsdf = Bsdf::new(surface, kernel, *at.frame(), at.wavelength()).unwrap();
                if let Ok(Some(s)) = bsdf.sample_incident(*exit, &sky, u[0], [u[1], u[2]]) {
                    // The whole sample is used (a pdf alone would let the compiler drop the
                    // inlined weight of the static form).
                    acc += s.sample.pdf + Throughput::m00(&black_box(&s).weight);
                }
            }
            black_box(acc)
        });
    });
    g.bench_function(BenchmarkId::new("sample_incident", "erased"), |b| {
        b.iter(|| {
            let mut acc = T::zero();
            for (at, exit, _, u) in &cases {
                if let Ok(Some(s)) = material.sample_incident(at, *exit, &sky, u[0], [u[1], u[2]]) {
                    acc += s.sample.pdf + black_box(&s).weight.m00();
                }
            }
            black_box(acc)
        });
    });
    g.bench_function(BenchmarkId::new("eval_incident", "static"), |b| {
        b.iter(|| {
            let mut acc = T::zero();
            for (at, exit, source, _) in &cases {
                let bsdf = Bsdf::new(surface, kernel, *at.frame(), at.wavelength()).unwrap();
                let v = bsdf
                    .eval(&bsdf.prepare_surface(*source, &sky).unwrap(), *exit)
                    .unwrap();
                // The whole value is used, as in the erased form (whose call boundary keeps
                // the compiler from dropping what the sum does not read).
                acc += gmueller::interaction::polarization::Throughput::m00(
                    &black_box(&v).response.total(),
                );
            }
            black_box(acc)
        });
    });
    g.bench_function(BenchmarkId::new("eval_incident", "erased"), |b| {
        b.iter(|| {
            let mut acc = T::zero();
            for (at, exit, source, _) in &cases {
                let v = material.eval_incident(at, *exit, &sky, *source).unwrap();
                acc += black_box(&v).response.total().m00();
            }
            black_box(acc)
        });
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    fn all<T: Real>(c: &mut Criterion)
    where
        gmueller::psd::ClosedForm: gmueller::psd::BlurMethod<T, 2, GaussianPsd<T, 2>>,
    {
        let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(2.0)).unwrap();
        let glass = RoughDielectric::new(psd, T::lit(1.5)).unwrap();
        let gold = RoughConductor::new(psd, Complex::new(T::lit(0.2), T::lit(3.5))).unwrap();
        run::<T, _, Full>(c, "glass", &glass, Level::ALL[7]);
        run::<T, _, Intensity>(c, "glass", &glass, Level::ALL[1]);
        run::<T, _, Full>(c, "gold", &gold, Level::ALL[7]);
    }
    all::<f32>(c);
    all::<f64>(c);
}

criterion_group!(material, benches);
criterion_main!(material);
