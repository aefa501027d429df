//! Criterion bench of wavelength bundles (`bsdf::Bundle`, issue 37) against the
//! single-wavelength calls they replace: per iteration 64 seeded backward draws
//! (`sample_incident`: the hero's draw and weight, every other wavelength's pdf and weight)
//! - `bundle8` / `bundle4`: one `Bundle::sample_incident` of 8 or 4 wavelengths (hero chosen
//!   by `Bundle::choose_hero`);
//! - `single8` / `single4`: `Material::sample_incident` once per wavelength (8 or 4 draws);
//! - `single1`: one `Material::sample_incident` (the unit of the per-wavelength ratio
//!   `bundle time / (N × single1 time)`);
//! - `bundle8_normal`: the degenerate exit along the normal (the s/p frames' special case).
//!
//! Rough N-BK7 glass (Gaussian PSD σ = 10 nm, ℓ = 2 µm, `spectral::Glass::NBk7` per
//! wavelength) and rough gold (σ = 12 nm, ℓ = 1.5 µm, `spectral::Metal::Au`), Full · Partial and
//! Intensity · Partial, f32 and f64, wavelengths stratified over 0.4–0.75 µm.
//!
//! Run: `cargo bench --bench bundle -- --warm-up-time 0.5 --measurement-time 1.5`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::bsdf::{Bundle, Material, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::{Level, RoughConductor, RoughDielectric};
use gmueller::psd::GaussianPsd;
use gmueller::spectral::{Glass, Metal};
use gmueller::verify::rng::SplitMix64;
use nalgebra::Vector3;

const CASES: usize = 64;

/// Exit directions (both sides for glass) and uniforms (hero, lobe, point).
fn cases<T: Real>(f: &Frame<T>, both_sides: bool) -> Vec<(Vector3<T>, [T; 4])> {
    let mut rng = SplitMix64(0xb4d1e);
    (0..CASES)
        .map(|i| {
            let t = rng.unit() * 70f64.to_radians();
            let p = rng.unit() * std::f64::consts::TAU;
            let side = if both_sides && i % 3 == 2 { -1.0 } else { 1.0 };
            let exit = (f.x() * T::lit(t.sin() * p.cos())
                + f.y() * T::lit(t.sin() * p.sin())
                + f.k() * T::lit(side * t.cos()))
            .normalize();
            (
                exit,
                [rng.unit(), rng.unit(), rng.unit(), rng.unit()].map(T::lit),
            )
        })
        .collect()
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Glass,
    Gold,
}

fn material<T: Real>(kind: Kind, lambda: T, level: Level) -> Material<T> {
    match kind {
        Kind::Glass => {
            let psd = GaussianPsd::isotropic(T::lit(0.01), T::lit(2.0)).unwrap();
            Material::new(
                RoughDielectric::new(psd, Glass::NBk7.index(lambda)).unwrap(),
                level,
            )
        }
        Kind::Gold => {
            let psd = GaussianPsd::isotropic(T::lit(0.012), T::lit(1.5)).unwrap();
            Material::new(
                RoughConductor::new(psd, Metal::Au.index(lambda)).unwrap(),
                level,
            )
        }
    }
}

/// The wavelengths of a bundle of `N`, stratified over 0.4–0.75 µm.
fn lambdas<T: Real, const N: usize>() -> [T; N] {
    core::array::from_fn(|i| T::lit(0.4 + 0.35 * (i as f64 + 0.5) / N as f64))
}

fn group<T: Real, const N: usize>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    kind: Kind,
    level: Level,
    f: Frame<T>,
    sky: &SurfaceCoherence<T>,
    cases: &[(Vector3<T>, [T; 4])],
) {
    let lambdas = lambdas::<T, N>();
    let m: [Material<T>; N] = lambdas.map(|l| material(kind, l, level));
    let refs: [&Material<T>; N] = core::array::from_fn(|i| &m[i]);
    let bundle = Bundle::new(refs, f, lambdas).unwrap();
    g.bench_function(
        BenchmarkId::new(format!("bundle{N}"), "sample_incident"),
        |b| {
            b.iter(|| {
                let mut acc = T::zero();
                for (exit, u) in cases {
                    let bb = black_box(&bundle).choose_hero(u[0]);
                    if let Ok(Some(s)) = bb.sample_incident(*exit, sky, u[1], [u[2], u[3]]) {
                        acc += s.pdf + s.weights[N - 1].m00();
                    }
                }
                black_box(acc)
            });
        },
    );
    g.bench_function(
        BenchmarkId::new(format!("single{N}"), "sample_incident"),
        |b| {
            b.iter(|| {
                let mut acc = T::zero();
                for (exit, u) in cases {
                    for (i, material) in m.iter().enumerate() {
                        let at = bundle.point(i);
                        if let Ok(Some(s)) =
                            black_box(material).sample_incident(at, *exit, sky, u[1], [u[2], u[3]])
                        {
                            acc += s.sample.pdf + s.weight.m00();
                        }
                    }
                }
                black_box(acc)
            });
        },
    );
    if N == 8 {
        let normal = f.k();
        g.bench_function(BenchmarkId::new("bundle8_normal", "sample_incident"), |b| {
            b.iter(|| {
                let mut acc = T::zero();
                for (_, u) in cases {
                    let bb = black_box(&bundle).choose_hero(u[0]);
                    if let Ok(Some(s)) = bb.sample_incident(normal, sky, u[1], [u[2], u[3]]) {
                        acc += s.pdf;
                    }
                }
                black_box(acc)
            });
        });
    }
}

fn run<T: Real>(c: &mut Criterion, kind: Kind, level: Level) {
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0).map(T::lit)).unwrap();
    let sky = SurfaceCoherence::new(T::lit(20.0)).unwrap();
    let cases = cases(&f, kind == Kind::Glass);
    let name = if kind == Kind::Glass { "glass" } else { "gold" };
    let precision = core::any::type_name::<T>();
    let mut g = c.benchmark_group(format!("bundle/{name}/{}/{precision}", level.name()));
    // The unit: one single-wavelength draw per case, at the middle of the range.
    let one = material(kind, T::lit(0.575), level);
    let at = gmueller::bsdf::ShadingPoint::new(f, T::lit(0.575)).unwrap();
    g.bench_function(BenchmarkId::new("single1", "sample_incident"), |b| {
        b.iter(|| {
            let mut acc = T::zero();
            for (exit, u) in &cases {
                if let Ok(Some(s)) =
                    black_box(&one).sample_incident(&at, *exit, &sky, u[1], [u[2], u[3]])
                {
                    acc += s.sample.pdf + s.weight.m00();
                }
            }
            black_box(acc)
        });
    });
    group::<T, 8>(&mut g, kind, level, f, &sky, &cases);
    group::<T, 4>(&mut g, kind, level, f, &sky, &cases);
    g.finish();
}

fn benches(c: &mut Criterion) {
    fn all<T: Real>(c: &mut Criterion) {
        for kind in [Kind::Glass, Kind::Gold] {
            run::<T>(c, kind, Level::ALL[7]); // Full · Partial
            run::<T>(c, kind, Level::ALL[1]); // Intensity · Partial
        }
    }
    all::<f32>(c);
    all::<f64>(c);
}

criterion_group!(bundle, benches);
criterion_main!(bundle);
