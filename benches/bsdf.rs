//! Criterion benches of the renderer layer (`gmueller::bsdf`) against the kernel it wraps, per
//! model level (all nine) and precision, on rough glass (Gaussian PSD σ = 10 nm, ℓ = 2 µm,
//! η = 1.5) at 64 seeded shading configurations (incidence 0–70° from either side, exits near
//! the mirror or Snell direction, sunlight or 3–30 µm of surface coherence):
//! - `evaluate_prepared`: `Kernel::evaluate_prepared` with the packet prepared and the
//!   geometry built outside the loop (the baseline);
//! - `eval`: `Bsdf::eval` (the geometry built inside, the BSDF form);
//! - `evaluate_prepared_far`, `eval_far`: the same with the exits uniform over the exit
//!   hemisphere (reflection side for 3 of 4 cases, as near the lobe) instead of near the mirror
//!   or Snell direction: off the lobe, where the coherent part is dark and skipped;
//! - `exit_build+sample+pdf`: `Bsdf::exit_sampler` + `LobeSampler::sample` + `LobeSampler::pdf`
//!   (forward: what a light tracer pays per bounce before evaluating);
//! - `incident_build+sample+pdf`: `Bsdf::incident_sampler` + `sample` + `pdf` (backward);
//! - `pdf`: `LobeSampler::pdf` of a built sampler (what MIS pays per light sample);
//! - `prepare_surface`: `Bsdf::prepare_surface` (the light of a direction, as the backward
//!   weight prepares it);
//! - `exit_sample+weight`: `Bsdf::sample_exit` (build, draw, weight: a forward bounce);
//! - `incident_sample+weight`: `Bsdf::sample_incident` (build, draw, weight: a backward
//!   bounce; the sample carries its pdf for MIS).
//!
//! Issue 37's budget: a backward bounce (`incident_sample+weight`) at most 2 × `eval` at
//! Full · Partial `f32`, 2.5 × at the intensity levels. Each group also has one degenerate case (normal incidence).
//!
//! - `bsdf_batch/*`: `LobeSampler::sample_batch` against `LobeSampler::sample` one draw at a
//!   time, and the forward bounce `Bsdf::sample_exit_batch` against `Bsdf::sample_exit` (its
//!   weight applied to the packet's Stokes vector), 4096 draws per iteration (throughput in
//!   draws).
//!
//! Run: `cargo bench --bench bsdf -- --warm-up-time 0.5 --measurement-time 1.5`.
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::bsdf::{Bsdf, Incident, SurfaceCoherence};
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::level::LevelVisitor;
use gmueller::interaction::polarization::PolarizationModel;
use gmueller::interaction::{Geometry, Kernel, Level, RoughDielectric};
use gmueller::psd::{ClosedForm, GaussianPsd};
use gmueller::stokes::Stokes;
use nalgebra::Vector3;

use gmueller::verify::rng::SplitMix64;

const N: usize = 64;

/// One seeded shading configuration.
struct Case<T: Real> {
    to_source: Vector3<T>,
    exit: Vector3<T>,
    sun: bool,
    width: f64,
}

#[path = "common/shading.rs"]
mod shading;
use shading::{dir, frame};

fn cases<T: Real>() -> Vec<Case<T>> {
    let f = frame::<T>();
    let mut rng = SplitMix64(0xb5df);
    let mut out: Vec<Case<T>> = (0..N)
        .map(|i| {
            let below = i % 4 == 3;
            let side = if below { -1.0 } else { 1.0 };
            let ti = rng.unit() * 70f64.to_radians();
            let phi = rng.unit() * std::f64::consts::TAU;
            let to_source = dir(&f, ti, phi, side);
            // Reflection (3 of 4) near the mirror direction, else transmission near Snell's.
            let dt = (rng.unit() - 0.5) * 0.2;
            let exit = if i % 3 != 2 {
                dir(
                    &f,
                    (ti + dt).abs().min(1.4),
                    phi + std::f64::consts::PI,
                    side,
                )
            } else {
                let n = if below { 1.5 } else { 1.0 / 1.5 };
                let tt = (ti.sin() * n).min(0.99).asin();
                dir(
                    &f,
                    (tt + dt).abs().min(1.4),
                    phi + std::f64::consts::PI,
                    -side,
                )
            };
            Case {
                to_source,
                exit,
                sun: i % 2 == 0,
                width: 3.0 + 27.0 * rng.unit(),
            }
        })
        .collect();
    // The degenerate case: normal incidence, normal exit.
    out[0] = Case {
        to_source: f.k(),
        exit: f.k(),
        sun: true,
        width: 10.0,
    };
    out
}

/// [`cases`] with the exits drawn uniformly (in solid angle) over the hemisphere of the
/// case's side, `θ_o` up to 87°: mostly far from the mirror and Snell directions.
fn far_cases<T: Real>() -> Vec<Case<T>> {
    let f = frame::<T>();
    let mut rng = SplitMix64(0xfa7);
    let mut out = cases::<T>();
    for (i, c) in out.iter_mut().enumerate() {
        let source_side = if c.to_source.dot(&f.k()) > T::zero() {
            1.0
        } else {
            -1.0
        };
        let side = if i % 3 != 2 {
            source_side
        } else {
            -source_side
        };
        let cos = 0.05 + 0.95 * rng.unit();
        let phi = rng.unit() * std::f64::consts::TAU;
        c.exit = dir(&f, cos.acos(), phi, side);
    }
    out
}

struct Bench<'a, T: Real> {
    c: &'a mut Criterion,
    prec: &'a str,
    glass: &'a RoughDielectric<T, GaussianPsd<T, 2>>,
    cases: &'a [Case<T>],
    far: &'a [Case<T>],
}

impl<T: Real> LevelVisitor<T, GaussianPsd<T, 2>> for Bench<'_, T> {
    type Output = ();
    fn visit<Pol, Coh>(self, level: Level, kernel: Kernel<Pol, Coh>)
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, GaussianPsd<T, 2>>,
    {
        let f = frame::<T>();
        let b = Bsdf::new(self.glass, kernel.clone(), f, T::lit(0.55)).unwrap();
        let stokes = Stokes::unpolarized(T::one()).unwrap();
        let coherence: Vec<SurfaceCoherence<T>> = self
            .cases
            .iter()
            .map(|c| SurfaceCoherence::new(T::lit(c.width)).unwrap())
            .collect();
        let incidents: Vec<Incident<T, Pol, Coh>> = self
            .cases
            .iter()
            .zip(&coherence)
            .map(|(c, coh)| {
                let p = if c.sun {
                    b.distant_packet(stokes, T::lit(6.8e-5), c.to_source)
                } else {
                    b.surface_packet(stokes, c.to_source, coh)
                };
                b.prepare(&p.unwrap()).unwrap()
            })
            .collect();
        let geometries: Vec<Geometry<T>> = self
            .cases
            .iter()
            .map(|c| b.geometry(c.to_source, c.exit).unwrap())
            .collect();
        let samplers: Vec<_> = incidents
            .iter()
            .map(|inc| b.exit_sampler(inc).unwrap())
            .collect();
        let mut rng = SplitMix64(7);
        let uniforms: Vec<[T; 3]> = (0..N)
            .map(|_| [rng.unit(), rng.unit(), rng.unit()].map(T::lit))
            .collect();
        let probes: Vec<Vector3<T>> = self.cases.iter().map(|c| c.exit).collect();
        let name = level.name().replace('/', "x");
        let mut g = self.c.benchmark_group(format!("bsdf/{}", self.prec));
        g.bench_function(BenchmarkId::new("evaluate_prepared", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                black_box(kernel.evaluate_prepared(
                    black_box(self.glass),
                    black_box(incidents[i].prepared()),
                    black_box(&geometries[i]),
                ))
            });
        });
        g.bench_function(BenchmarkId::new("eval", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                black_box(b.eval(black_box(&incidents[i]), black_box(self.cases[i].exit)))
            });
        });
        let far_geometries: Vec<Geometry<T>> = self
            .far
            .iter()
            .map(|c| b.geometry(c.to_source, c.exit).unwrap())
            .collect();
        g.bench_function(BenchmarkId::new("evaluate_prepared_far", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                black_box(kernel.evaluate_prepared(
                    black_box(self.glass),
                    black_box(incidents[i].prepared()),
                    black_box(&far_geometries[i]),
                ))
            });
        });
        g.bench_function(BenchmarkId::new("eval_far", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                black_box(b.eval(black_box(&incidents[i]), black_box(self.far[i].exit)))
            });
        });
        g.bench_function(BenchmarkId::new("exit_build+sample+pdf", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                let s = b.exit_sampler(black_box(&incidents[i])).unwrap();
                let u = uniforms[i];
                let d = s.sample(u[0], [u[1], u[2]]);
                black_box((d, s.pdf(black_box(&probes[i]))))
            });
        });
        g.bench_function(
            BenchmarkId::new("incident_build+sample+pdf", &name),
            |bench| {
                let mut i = 0;
                bench.iter(|| {
                    i = (i + 1) & (N - 1);
                    let s = b
                        .incident_sampler(black_box(self.cases[i].exit), &coherence[i])
                        .unwrap();
                    let u = uniforms[i];
                    let d = s.sample(u[0], [u[1], u[2]]);
                    black_box((d, s.pdf(black_box(&self.cases[i].to_source))))
                });
            },
        );
        g.bench_function(BenchmarkId::new("exit_sample+weight", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                let u = uniforms[i];
                black_box(b.sample_exit(black_box(&incidents[i]), u[0], [u[1], u[2]]))
            });
        });
        g.bench_function(BenchmarkId::new("incident_sample+weight", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                let u = uniforms[i];
                black_box(b.sample_incident(
                    black_box(self.cases[i].exit),
                    &coherence[i],
                    u[0],
                    [u[1], u[2]],
                ))
            });
        });
        g.bench_function(BenchmarkId::new("prepare_surface", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                black_box(b.prepare_surface(black_box(self.cases[i].to_source), &coherence[i]))
            });
        });
        g.bench_function(BenchmarkId::new("pdf", &name), |bench| {
            let mut i = 0;
            bench.iter(|| {
                i = (i + 1) & (N - 1);
                black_box(samplers[i].pdf(black_box(&probes[i])))
            });
        });
        g.finish();
    }
}

fn for_precision<T: Real>(c: &mut Criterion, prec: &str) {
    let glass = RoughDielectric::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(2.0)).unwrap(),
        T::lit(1.5),
    )
    .unwrap();
    let cases = cases::<T>();
    let far = far_cases::<T>();
    for level in Level::ALL {
        level.dispatch(
            ClosedForm,
            Bench {
                c,
                prec,
                glass: &glass,
                cases: &cases,
                far: &far,
            },
        );
    }
}

/// `sample_batch`: one sampler (Full · Partial, 3 µm of surface coherence), 4096 seeded draws
/// per iteration, in lanes (`sample_batch`) and one at a time (`sample` in a loop over the
/// same uniforms); rough glass backward with the exit above (40°) and gold backward (50°), and
/// a rougher gold (σ = 0.1 µm, `vσ ≈ 2` at 35°) with the Kirchhoff series (its order lobes).
fn batch_sampling<T: Real>(c: &mut Criterion, prec: &str) {
    use gmueller::bsdf::{SamplesSoa, UniformsSoa};
    use gmueller::interaction::{Full, Partial, RoughConductor};
    const M: usize = 4096;
    let f = frame::<T>();
    let glass = RoughDielectric::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(2.0)).unwrap(),
        T::lit(1.5),
    )
    .unwrap();
    let gold = RoughConductor::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.03), T::lit(1.2)).unwrap(),
        gmueller::spectral::Metal::Au.index(T::lit(0.5)),
    )
    .unwrap();
    let rough_gold = RoughConductor::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.1), T::lit(1.2)).unwrap(),
        gmueller::spectral::Metal::Au.index(T::lit(0.5)),
    )
    .unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let bg = Bsdf::new(&glass, kernel, f, T::lit(0.5)).unwrap();
    let bc = Bsdf::new(&gold, kernel, f, T::lit(0.5)).unwrap();
    let series =
        kernel.with_roughness(gmueller::interaction::roughness::KirchhoffSeries::default());
    let bs = Bsdf::new(&rough_gold, series, f, T::lit(0.5)).unwrap();
    let sky = SurfaceCoherence::new(T::lit(3.0)).unwrap();
    let samplers = [
        (
            "glass_backward",
            bg.incident_sampler(
                dir::<T>(&f, 40f64.to_radians(), -50f64.to_radians(), 1.0),
                &sky,
            )
            .unwrap(),
        ),
        (
            "gold_backward",
            bc.incident_sampler(
                dir::<T>(&f, 50f64.to_radians(), 10f64.to_radians(), 1.0),
                &sky,
            )
            .unwrap(),
        ),
        (
            "gold_series_backward",
            bs.incident_sampler(
                dir::<T>(&f, 50f64.to_radians(), 10f64.to_radians(), 1.0),
                &sky,
            )
            .unwrap(),
        ),
    ];
    let mut rng = SplitMix64(0x5a3b);
    let u: [Vec<T>; 3] = core::array::from_fn(|_| (0..M).map(|_| T::lit(rng.unit())).collect());
    let mut out: [Vec<T>; 5] = core::array::from_fn(|_| vec![T::zero(); M]);
    let mut code = vec![0u8; M];
    let mut g = c.benchmark_group(format!("bsdf_batch/{prec}"));
    g.throughput(criterion::Throughput::Elements(M as u64));
    for (name, s) in &samplers {
        g.bench_function(BenchmarkId::new("sample_batch", name), |bench| {
            bench.iter(|| {
                let [x, y, z, pdf, dw] = &mut out;
                s.sample_batch(
                    UniformsSoa {
                        lobe: &u[0],
                        u0: &u[1],
                        u1: &u[2],
                    },
                    SamplesSoa {
                        x,
                        y,
                        z,
                        pdf,
                        delta_weight: dw,
                        lobe: &mut code,
                    },
                )
                .unwrap();
                black_box(&out[3]);
            });
        });
        g.bench_function(BenchmarkId::new("sample_loop", name), |bench| {
            bench.iter(|| {
                let mut acc = T::zero();
                for ((&l, &a), &b) in u[0].iter().zip(&u[1]).zip(&u[2]) {
                    if let Some(d) = s.sample(black_box(l), [a, b]) {
                        acc += d.pdf;
                    }
                }
                black_box(acc)
            });
        });
    }
    // The forward bounce (draw + weight applied to the packet's Stokes vector), the light
    // from 35° above.
    bounce(&mut g, "glass_forward", &bg, &sky, &u);
    bounce(&mut g, "gold_forward", &bc, &sky, &u);
    bounce(&mut g, "gold_series_forward", &bs, &sky, &u);
    g.finish();
}

/// `exit_bounce_batch` (`Bsdf::sample_exit_batch`) against `exit_bounce_loop` (`prepare` once,
/// then `Bsdf::sample_exit` per draw, its weight applied to the packet's Stokes vector).
fn bounce<T: Real, S, R>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    b: &Bsdf<'_, T, S, Kernel<gmueller::interaction::Full, gmueller::interaction::Partial, R>>,
    sky: &SurfaceCoherence<T>,
    u: &[Vec<T>; 3],
) where
    S: gmueller::bsdf::BsdfSurface<T>,
    gmueller::interaction::Partial: CoherenceWeights<T, S::Psd>,
    R: gmueller::interaction::roughness::RoughnessWeights<
            T,
            S::Psd,
            gmueller::interaction::Partial,
        >,
{
    use gmueller::bsdf::{SamplesSoa, UniformsSoa};
    use gmueller::interaction::batch::StokesSoa;
    let m = u[0].len();
    let f = frame::<T>();
    let packet = b
        .surface_packet(
            Stokes::unpolarized(T::one()).unwrap(),
            dir::<T>(&f, 35f64.to_radians(), 30f64.to_radians(), 1.0),
            sky,
        )
        .unwrap();
    let mut out: [Vec<T>; 5] = core::array::from_fn(|_| vec![T::zero(); m]);
    let mut code = vec![0u8; m];
    let mut w: [Vec<T>; 4] = core::array::from_fn(|_| vec![T::zero(); m]);
    g.bench_function(BenchmarkId::new("exit_bounce_batch", name), |bench| {
        bench.iter(|| {
            let [x, y, z, pdf, dw] = &mut out;
            let [w0, w1, w2, w3] = &mut w;
            b.sample_exit_batch(
                &packet,
                UniformsSoa {
                    lobe: &u[0],
                    u0: &u[1],
                    u1: &u[2],
                },
                SamplesSoa {
                    x,
                    y,
                    z,
                    pdf,
                    delta_weight: dw,
                    lobe: &mut code,
                },
                StokesSoa {
                    s: [w0, w1, w2, w3],
                },
            )
            .unwrap();
            black_box(&w[0]);
        });
    });
    g.bench_function(BenchmarkId::new("exit_bounce_loop", name), |bench| {
        bench.iter(|| {
            let inc = b.prepare(&packet).unwrap();
            let light = packet.stokes();
            let mut acc = T::zero();
            for ((&l, &a), &c) in u[0].iter().zip(&u[1]).zip(&u[2]) {
                if let Some(s) = b.sample_exit(&inc, black_box(l), [a, c]).unwrap() {
                    acc += s.weight.apply(&light).s0();
                }
            }
            black_box(acc)
        });
    });
}

fn benches(c: &mut Criterion) {
    for_precision::<f64>(c, "f64");
    for_precision::<f32>(c, "f32");
    batch_sampling::<f64>(c, "f64");
    batch_sampling::<f32>(c, "f32");
}

criterion_group!(bsdf, benches);
criterion_main!(bsdf);
