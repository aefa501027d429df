//! Criterion benches of the S2.20 kernel (`gmueller::interaction`): every model level
//! (Intensity/OneShape/Full × PlaneWave/Partial/Incoherent) with a Gaussian PSD and the closed-form
//! blur, Partial with a K-correlation PSD through Gauss–Hermite (orders 3, 5, 8) and through a
//! Gaussian-mixture fit (8 and 16 components), f32 and f64; a classical incoherent polarized
//! baseline (Fresnel Mueller × PSD at the half vector × Stokes, geometry precomputed the same
//! way); `Geometry` construction and `Kernel::prepare` alone. Each level is timed per evaluation (`seeded`), per
//! exit direction of a prepared packet (`prepared`: `Kernel::prepare` outside the loop) and
//! from direction cosines (`with-geometry`: `Geometry::for_packet` inside the loop). Inputs are
//! seeded (an LCG) and pass through `black_box`; each group also times one degenerate case
//! (normal incidence, exact specular). `kernel_batch/{f64,f32}`: the SIMD batch path per exit
//! against the per-direction kernel on the same 1024 exits. `kernel_interface/{f64,f32}`: every
//! level at a rough glass interface, reflection against transmission, same scenes, same run.
//! `kernel_batch_partial/{f64,f32}`: `Kernel::<Full, Partial>::evaluate_batch` (both lobes, exit
//! frames, geometry included) against the per-direction prepared kernel, same 1024 exits.
//! `kernel_batch_interface/{f64,f32}`: the same at a rough glass interface, exits around
//! Snell's direction, or alternating with the mirror direction, against the per-direction one.
//! `kernel_batch_levels/{f64,f32}`: `evaluate_batch` at the Intensity and Full levels at a rough
//! glass interface, exits near the lobes and over both hemispheres; at Intensity also without
//! the exit frames.
//! `kernel_batch_spectral/{f64,f32}`: `evaluate_batch_spectral` on 4 wavelengths × the same
//! 1024 exits against 4 `evaluate_batch` calls, at first order and (`-series`) with the
//! Kirchhoff series at `vσ ≈ 1`.
//! `kernel_pairs/{f64,f32}`: `evaluate_pairs` on 1024 (light, exit) pairs against the same
//! pairs one at a time (renderer layer, kernel); `evaluate_pairs_mueller` against
//! `Bsdf::prepare_surface` + `evaluate_mueller_prepared` one at a time.
//!
//! Run: `cargo bench --bench kernel -- --warm-up-time 0.5 --measurement-time 1`.
use std::hint::black_box;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, criterion_group, criterion_main};
use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::fresnel;
use gmueller::interaction::batch::{
    DirectionsSoa, ExitFramesSoa, LobesSoa, MuellerLobesSoa, MuellerSoa, StokesSoa,
    plane_wave_rayleigh_rice,
};
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::level::LevelVisitor;
use gmueller::interaction::pbsdf::{FresnelReflection, Pbsdf, RayleighRice};
use gmueller::interaction::polarization::PolarizationModel;
use gmueller::interaction::roughness::{FirstOrder, KirchhoffSeries, RoughnessWeights};
use gmueller::interaction::{
    Full, Geometry, Intensity, Kernel, Level, OneShape, Partial, PlaneWave, RoughDielectric,
    RoughSurface,
};
use gmueller::mueller::Mueller;
use gmueller::mueller::batch::padded_stride;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussHermite, GaussianPsd, KCorrelation, Psd};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;

use gmueller::verify::rng::Lcg;

const N: usize = 64;

/// One seeded scene: a packet and its geometry for an exit direction near the specular one
/// (within ~15°), incidence up to 70°, packet frame turned from s/p, `Θ_x ≠ Θ_y`, realizable μ.
struct Scene<T: Real> {
    packet: WavePacket<T>,
    geometry: Geometry<T>,
}

fn surface<T: Real>() -> Frame<T> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}

fn scene<T: Real>(theta_i: f64, theta_o: f64, phi_o: f64, psi: f64, w: f64) -> Scene<T> {
    scene_with(theta_i, theta_o, phi_o, psi, w, 1.2)
}

/// [`scene`] with `Θ_y = ratio² Θ_x` (`ratio = 1`: one shape for both components).
fn scene_with<T: Real>(
    theta_i: f64,
    theta_o: f64,
    phi_o: f64,
    psi: f64,
    w: f64,
    ratio: f64,
) -> Scene<T> {
    let travel = Vector3::new(theta_i.sin(), 0.0, -theta_i.cos()).map(T::lit);
    let exit = Vector3::new(
        theta_o.sin() * phi_o.cos(),
        theta_o.sin() * phi_o.sin(),
        theta_o.cos(),
    )
    .map(T::lit);
    let frame = Frame::sp(travel, Vector3::z())
        .unwrap()
        .rotated(T::lit(psi));
    let sx = CoherenceShape::new(Matrix2::new(w * w, 0.0, 0.0, w * w).map(T::lit)).unwrap();
    let wy = ratio * w;
    let sy = CoherenceShape::new(Matrix2::new(wy * wy, 0.0, 0.0, wy * wy).map(T::lit)).unwrap();
    let stokes = Stokes::new(T::lit(1.0), T::lit(0.3), T::lit(0.2), T::lit(-0.3)).unwrap();
    let packet = WavePacket::new(stokes, sx, sy, frame, T::lit(0.5)).unwrap();
    let geometry = Geometry::for_packet(&packet, &surface(), exit).unwrap();
    Scene { packet, geometry }
}

fn scenes<T: Real>() -> Vec<Scene<T>> {
    scenes_with(1.2)
}

/// [`scenes`] with `Θ_y = ratio² Θ_x`.
fn scenes_with<T: Real>(ratio: f64) -> Vec<Scene<T>> {
    let mut rng = Lcg(0x5eed);
    (0..N)
        .map(|_| {
            let ti = rng.uniform() * 70f64.to_radians();
            let to = (ti + (rng.uniform() - 0.5) * 30f64.to_radians())
                .abs()
                .min(1.4);
            let po = (rng.uniform() - 0.5) * 0.6;
            let psi = (rng.uniform() - 0.5) * 6.0;
            let w = 1.0 + 20.0 * rng.uniform();
            scene_with(ti, to, po, psi, w, ratio)
        })
        .collect()
}

/// Normal incidence, exact specular exit.
fn degenerate<T: Real>() -> Scene<T> {
    scene(0.0, 0.0, 0.0, 0.0, 5.0)
}

fn glass<T: Real, P>(psd: P) -> RoughSurface<P, FresnelReflection<T>, RayleighRice<T>> {
    let eta = Complex::new(T::lit(1.5), T::zero());
    RoughSurface {
        psd,
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    }
}

fn bench_level<T, Pol, Coh, P>(
    c: &mut Criterion,
    group: &str,
    name: &str,
    kernel: Kernel<Pol, Coh>,
    material: &RoughSurface<P, FresnelReflection<T>, RayleighRice<T>>,
) where
    T: Real,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, P>,
    P: Psd<T, 2>,
{
    let mut g = c.benchmark_group(group);
    let sc = scenes::<T>();
    g.bench_function(BenchmarkId::new(name, "seeded"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (N - 1);
            let s = &sc[i];
            black_box(kernel.evaluate(
                black_box(material),
                black_box(&s.packet),
                black_box(&s.geometry),
            ))
        });
    });
    // Per exit direction once the packet is prepared (`Kernel::prepare` outside the loop).
    let prepared: Vec<_> = sc
        .iter()
        .map(|s| kernel.prepare(&s.packet, &surface()).unwrap())
        .collect();
    g.bench_function(BenchmarkId::new(name, "prepared"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (N - 1);
            black_box(kernel.evaluate_prepared(
                black_box(material),
                black_box(&prepared[i]),
                black_box(&sc[i].geometry),
            ))
        });
    });
    // From direction cosines: the geometry built inside the loop too.
    g.bench_function(BenchmarkId::new(name, "with-geometry"), |b| {
        let mut i = 0;
        let surf = surface::<T>();
        b.iter(|| {
            i = (i + 1) & (N - 1);
            let s = &sc[i];
            let geo =
                Geometry::for_packet(black_box(&s.packet), &surf, black_box(s.geometry.exit()))
                    .unwrap();
            black_box(kernel.evaluate(black_box(material), black_box(&s.packet), &geo))
        });
    });
    let d = degenerate::<T>();
    g.bench_function(BenchmarkId::new(name, "normal-specular"), |b| {
        b.iter(|| {
            black_box(kernel.evaluate(
                black_box(material),
                black_box(&d.packet),
                black_box(&d.geometry),
            ))
        });
    });
    g.finish();
}

/// `Full` against `OneShape` on single-shape packets (`Θ_x = Θ_y`, polarized), where `Full`
/// takes the `OneShape` path: the two should cost the same.
fn single_shape_for<T: Real>(c: &mut Criterion, prec: &str) {
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let m = glass(psd);
    let sc = scenes_with::<T>(1.0);
    let mut g = c.benchmark_group(format!("kernel_single_shape/{prec}"));
    macro_rules! one {
        ($pol:ty) => {{
            let kernel = Kernel::<$pol, Partial>::default();
            let prepared: Vec<_> = sc
                .iter()
                .map(|s| kernel.prepare(&s.packet, &surface()).unwrap())
                .collect();
            g.bench_function(BenchmarkId::new(stringify!($pol), "prepared"), |b| {
                let mut i = 0;
                b.iter(|| {
                    i = (i + 1) & (N - 1);
                    black_box(kernel.evaluate_prepared(
                        black_box(&m),
                        black_box(&prepared[i]),
                        black_box(&sc[i].geometry),
                    ))
                });
            });
            g.bench_function(BenchmarkId::new(stringify!($pol), "seeded"), |b| {
                let mut i = 0;
                b.iter(|| {
                    i = (i + 1) & (N - 1);
                    let s = &sc[i];
                    black_box(kernel.evaluate(
                        black_box(&m),
                        black_box(&s.packet),
                        black_box(&s.geometry),
                    ))
                });
            });
        }};
    }
    one!(OneShape);
    one!(Full);
    g.finish();
}

fn levels_for<T: Real>(c: &mut Criterion, prec: &str) {
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let m = glass(psd);
    let group = format!("kernel_gaussian/{prec}");
    // Every level, chosen at run time by the library's one dispatch (`Level::dispatch`); the
    // benchmark names are `{polarization}x{coherence}`.
    struct Bench<'a, T: Real, P> {
        c: &'a mut Criterion,
        group: &'a str,
        material: &'a RoughSurface<P, FresnelReflection<T>, RayleighRice<T>>,
    }
    impl<T: Real, P: Psd<T, 2>> LevelVisitor<T, P> for Bench<'_, T, P> {
        type Output = ();
        fn visit<Pol, Coh>(self, level: Level, kernel: Kernel<Pol, Coh>)
        where
            Pol: PolarizationModel,
            Coh: CoherenceWeights<T, P>,
        {
            let name = level.name().replace('/', "x");
            bench_level(self.c, self.group, &name, kernel, self.material);
        }
    }
    for level in Level::ALL {
        level.dispatch(
            ClosedForm,
            Bench {
                c,
                group: &group,
                material: &m,
            },
        );
    }

    // K-correlation (T = 4 µm², γ = 2.5) at the Full×Partial level.
    let kc = KCorrelation::<T, 2>::new(T::lit(4e-4), T::lit(4.0), T::lit(2.5)).unwrap();
    let mk = glass(kc);
    let group = format!("kernel_kcorrelation/{prec}");
    for order in [3usize, 5, 8] {
        bench_level::<T, Full, _, _>(
            c,
            &group,
            &format!("FullxPartial/GaussHermite{order}"),
            Kernel::new(Partial(GaussHermite::<T>::new(order).unwrap())),
            &mk,
        );
    }
    for comps in [8usize, 16] {
        let (mix, err) = kc.mixture_fit(comps).unwrap();
        eprintln!("K-correlation mixture fit, {comps} components: sup error / p(0) = {err:.2e}");
        bench_level::<T, Full, Partial, _>(
            c,
            &group,
            &format!("FullxPartial/Mixture{comps}"),
            Kernel::new(Partial(ClosedForm)),
            &glass(mix),
        );
    }
}

/// The classical incoherent polarized evaluation: `cos θ_o/λ² · M_Fresnel · S · 2π p(h_t)` with
/// the Fresnel Mueller matrix at the same geometry (what a renderer without coherence computes).
fn baseline_for<T: Real>(c: &mut Criterion, prec: &str) {
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let eta = Complex::new(T::lit(1.5), T::zero());
    let sc = scenes::<T>();
    let mut g = c.benchmark_group(format!("baseline/{prec}"));
    let eval = |s: &Scene<T>| {
        let geo = &s.geometry;
        let m = Mueller::from_jones(&fresnel::reflection(geo.cos_i(), eta));
        let lambda = geo.wavelength();
        let f = geo.cos_o() / (lambda * lambda) * T::two_pi() * psd.value(&geo.h_t());
        (m * s.packet.stokes()).vector() * f
    };
    g.bench_function(BenchmarkId::new("classical_fresnel_psd", "seeded"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (N - 1);
            black_box(eval(black_box(&sc[i])))
        });
    });
    let d = degenerate::<T>();
    g.bench_function(
        BenchmarkId::new("classical_fresnel_psd", "normal-specular"),
        |b| b.iter(|| black_box(eval(black_box(&d)))),
    );
    g.finish();
}

fn geometry_for<T: Real>(c: &mut Criterion, prec: &str) {
    let sc = scenes::<T>();
    let surf = surface::<T>();
    let mut g = c.benchmark_group(format!("geometry/{prec}"));
    // The per-packet work of the kernel (`Kernel::prepare`): three sections at `Full`, one
    // below, none for a plane wave.
    macro_rules! prepare {
        ($pol:ty, $coh:ty) => {{
            let kernel = Kernel::<$pol, $coh>::default();
            g.bench_function(
                BenchmarkId::new("prepare", concat!(stringify!($pol), "x", stringify!($coh))),
                |b| {
                    let mut i = 0;
                    b.iter(|| {
                        i = (i + 1) & (N - 1);
                        black_box(kernel.prepare(black_box(&sc[i].packet), &surf))
                    });
                },
            );
        }};
    }
    prepare!(Full, Partial);
    prepare!(OneShape, Partial);
    prepare!(Full, PlaneWave);
    g.bench_function(BenchmarkId::new("for_packet", "seeded"), |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (N - 1);
            let s = &sc[i];
            black_box(Geometry::for_packet(
                black_box(&s.packet),
                black_box(&surf),
                black_box(s.geometry.exit()),
            ))
        });
    });
    let d = degenerate::<T>();
    g.bench_function(BenchmarkId::new("for_packet", "normal-specular"), |b| {
        b.iter(|| {
            black_box(Geometry::for_packet(
                black_box(&d.packet),
                black_box(&surf),
                black_box(d.geometry.exit()),
            ))
        });
    });
    g.finish();
}

/// The SIMD batch path (`interaction::batch::plane_wave_rayleigh_rice`) against the scalar
/// `Kernel::<Full, PlaneWave>` per exit (geometry included in both), on 1024 exits within ~15°
/// of the specular direction of one packet (30° incidence, polarized, frame turned), laid out in
/// one buffer with `padded_stride`; time per exit through the throughput. Degenerate case:
/// normal incidence, exits within ~8° of the normal (the re-orthogonalised s/p band).
fn batch_for<T: Real>(c: &mut Criterion, prec: &str) {
    const M: usize = 1024;
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let material = glass::<T, _>(psd);
    let kernel = Kernel::<Full, PlaneWave>::default();
    let surf = surface::<T>();
    let mut g = c.benchmark_group(format!("kernel_batch/{prec}"));
    g.throughput(criterion::Throughput::Elements(M as u64));
    for (case, theta_i, spread) in [
        ("lobe-1024", 30f64.to_radians(), 0.26),
        ("normal-1024", 0.0, 0.14),
    ] {
        let packet = scene::<T>(theta_i, theta_i, 0.0, 0.7, 5.0).packet;
        let mut rng = Lcg(0xba7c);
        let exits: Vec<Vector3<T>> = (0..M)
            .map(|_| {
                let to = (theta_i + (rng.uniform() - 0.5) * spread).abs();
                let po = (rng.uniform() - 0.5) * spread * 2.0;
                Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos()).map(T::lit)
            })
            .collect();
        let stride = padded_stride::<T>(M);
        let mut dirs = vec![T::zero(); 3 * stride];
        for (i, e) in exits.iter().enumerate() {
            for k in 0..3 {
                dirs[k * stride + i] = e[k];
            }
        }
        let mut buf = vec![T::zero(); 4 * stride];
        let soa = DirectionsSoa::from_strided(&dirs, M, stride).unwrap();
        let mut out = StokesSoa::from_strided(&mut buf, M, stride).unwrap();
        g.bench_function(BenchmarkId::new("batch", case), |b| {
            b.iter(|| {
                plane_wave_rayleigh_rice(
                    black_box(&material),
                    black_box(&packet),
                    black_box(&surf),
                    black_box(&soa),
                    &mut out,
                )
                .unwrap();
                black_box(out.s[0][M - 1])
            });
        });
        g.bench_function(BenchmarkId::new("per-direction-prepared", case), |b| {
            b.iter(|| {
                let prepared = kernel.prepare(black_box(&packet), &surf).unwrap();
                for e in &exits {
                    let geo = Geometry::for_packet(&packet, &surf, *e).unwrap();
                    black_box(
                        kernel
                            .evaluate_prepared(black_box(&material), &prepared, &geo)
                            .scattered,
                    );
                }
            });
        });
        g.bench_function(BenchmarkId::new("per-direction-evaluate", case), |b| {
            b.iter(|| {
                for e in &exits {
                    let geo = Geometry::for_packet(black_box(&packet), &surf, *e).unwrap();
                    black_box(
                        kernel
                            .evaluate(black_box(&material), &packet, &geo)
                            .scattered,
                    );
                }
            });
        });
    }
    g.finish();
}

/// `Kernel::<Full, Partial>::evaluate_batch` (both lobes and the exit frames, geometry
/// included) against the per-direction kernel (`prepare` once, `Geometry::for_packet` and
/// `evaluate_prepared` per exit) on the same 1024 exits around the mirror direction of a
/// two-shape packet (`Θ_y = 1.44 Θ_x`), Gaussian PSD, Fresnel + Rayleigh–Rice.
fn batch_partial_for<T: Real>(c: &mut Criterion, prec: &str) {
    const M: usize = 1024;
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let material = glass::<T, _>(psd);
    let kernel = Kernel::<Full, Partial>::default();
    let surf = surface::<T>();
    let theta_i = 30f64.to_radians();
    let packet = scene::<T>(theta_i, theta_i, 0.0, 0.7, 5.0).packet;
    let mut rng = Lcg(0xba7c);
    let exits: Vec<Vector3<T>> = (0..M)
        .map(|_| {
            let to = (theta_i + (rng.uniform() - 0.5) * 0.26).abs();
            let po = (rng.uniform() - 0.5) * 0.52;
            Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos()).map(T::lit)
        })
        .collect();
    let mut g = c.benchmark_group(format!("kernel_batch_partial/{prec}"));
    g.throughput(criterion::Throughput::Elements(M as u64));
    let batch = BatchScene {
        kernel: &kernel,
        material: &material,
        packet: &packet,
        surface: &surf,
        interface: None,
    };
    batch.bench(&mut g, "lobe-1024", &exits);
    per_direction(
        &mut g,
        BenchmarkId::new("per-direction-prepared", "lobe-1024"),
        (&kernel, &material),
        (&packet, &surf),
        &exits,
    );
    g.finish();
}

/// The Kirchhoff series in lanes against first order (issue 39): `evaluate_batch` of
/// `Kernel::<Full, Partial, KirchhoffSeries>` (tolerance 10⁻⁶, the default) and of the
/// first-order kernel on the scene of [`batch_partial_for`] (1024 exits within ±7.5° of the
/// mirror direction of 30° incidence, two shapes, rough glass, ℓ = 2 µm) at `vσ ≈ 1` and
/// `3` in the mirror direction (`σ = 0.046, 0.138` µm at λ = 0.5 µm), the same at the
/// `Intensity` level (one channel instead of three), and the per-direction series
/// (`evaluate_prepared`) at `vσ ≈ 1`.
fn batch_series_for<T: Real>(c: &mut Criterion, prec: &str) {
    const M: usize = 1024;
    let theta_i = 30f64.to_radians();
    let packet = scene::<T>(theta_i, theta_i, 0.0, 0.7, 5.0).packet;
    let surf = surface::<T>();
    let mut rng = Lcg(0xba7c);
    let exits: Vec<Vector3<T>> = (0..M)
        .map(|_| {
            let to = (theta_i + (rng.uniform() - 0.5) * 0.26).abs();
            let po = (rng.uniform() - 0.5) * 0.52;
            Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos()).map(T::lit)
        })
        .collect();
    let first = Kernel::<Full, Partial>::default();
    let series = first.with_roughness(KirchhoffSeries::default());
    let first_i = Kernel::<Intensity, Partial>::default();
    let series_i = first_i.with_roughness(KirchhoffSeries::default());
    let mut g = c.benchmark_group(format!("kernel_batch_series/{prec}"));
    g.throughput(criterion::Throughput::Elements(M as u64));
    for (name, sigma) in [("vs1", 0.046), ("vs3", 0.138)] {
        let psd = GaussianPsd::<T, 2>::isotropic(T::lit(sigma), T::lit(2.0)).unwrap();
        let material = glass::<T, _>(psd);
        BatchScene {
            kernel: &first,
            material: &material,
            packet: &packet,
            surface: &surf,
            interface: None,
        }
        .bench(&mut g, &format!("first-order-{name}"), &exits);
        BatchScene {
            kernel: &series,
            material: &material,
            packet: &packet,
            surface: &surf,
            interface: None,
        }
        .bench(&mut g, &format!("series-{name}"), &exits);
        BatchScene {
            kernel: &first_i,
            material: &material,
            packet: &packet,
            surface: &surf,
            interface: None,
        }
        .bench(&mut g, &format!("intensity-first-order-{name}"), &exits);
        BatchScene {
            kernel: &series_i,
            material: &material,
            packet: &packet,
            surface: &surf,
            interface: None,
        }
        .bench(&mut g, &format!("intensity-series-{name}"), &exits);
        if name == "vs1" {
            per_direction(
                &mut g,
                BenchmarkId::new("per-direction-series", name),
                (&series, &material),
                (&packet, &surf),
                &exits,
            );
            // Small batches: the series' constants are built once per call (`SeriesPrep`,
            // 7.7 KB in f64), against the per-direction series on the same few exits.
            for n in [1, 2, 3, 4, 16, 64] {
                BatchScene {
                    kernel: &series,
                    material: &material,
                    packet: &packet,
                    surface: &surf,
                    interface: None,
                }
                .bench(&mut g, &format!("series-{name}-n{n}"), &exits[..n]);
                per_direction(
                    &mut g,
                    BenchmarkId::new("per-direction-series", format!("{name}-n{n}")),
                    (&series, &material),
                    (&packet, &surf),
                    &exits[..n],
                );
            }
        }
    }
    g.finish();
}

/// Times `prepare` once and `Geometry::for_packet` + `evaluate_prepared` per exit, as `id`.
fn per_direction<T: Real, Pol: PolarizationModel, Rough, P, Sp, Sc>(
    g: &mut BenchmarkGroup<'_, WallTime>,
    id: BenchmarkId,
    (kernel, material): (&Kernel<Pol, Partial, Rough>, &RoughSurface<P, Sp, Sc>),
    (packet, surf): (&WavePacket<T>, &Frame<T>),
    exits: &[Vector3<T>],
) where
    P: Psd<T, 2> + 'static,
    Partial: CoherenceWeights<T, P>,
    Rough: RoughnessWeights<T, P, Partial>,
    Sp: Pbsdf<T> + 'static,
    Sc: Pbsdf<T> + 'static,
{
    g.bench_function(id, |bch| {
        bch.iter(|| {
            let prepared = kernel.prepare(black_box(packet), surf).unwrap();
            for e in exits {
                let geo = Geometry::for_packet(packet, surf, *e).unwrap();
                black_box(kernel.evaluate_prepared(black_box(material), &prepared, &geo));
            }
        });
    });
}

/// One `Kernel::<Pol, Partial>::evaluate_batch` scene of the batch benches.
struct BatchScene<'a, T: Real, P, Sp, Sc, Pol = Full, Rough = FirstOrder> {
    kernel: &'a Kernel<Pol, Partial, Rough>,
    material: &'a RoughSurface<P, Sp, Sc>,
    packet: &'a WavePacket<T>,
    surface: &'a Frame<T>,
    interface: Option<T>,
}

impl<T: Real, P, Sp, Sc, Pol: PolarizationModel, Rough> BatchScene<'_, T, P, Sp, Sc, Pol, Rough>
where
    P: Psd<T, 2> + 'static,
    Partial: CoherenceWeights<T, P>,
    Rough: RoughnessWeights<T, P, Partial>,
    Sp: Pbsdf<T> + 'static,
    Sc: Pbsdf<T> + 'static,
{
    /// Times `evaluate_batch` (both lobes and the exit frames) on `exits`, as `case`.
    fn bench(&self, g: &mut BenchmarkGroup<'_, WallTime>, case: &str, exits: &[Vector3<T>]) {
        self.bench_with(g, case, exits, true);
    }

    /// [`BatchScene::bench`], with the exit frames only when `with_frames`.
    fn bench_with(
        &self,
        g: &mut BenchmarkGroup<'_, WallTime>,
        case: &str,
        exits: &[Vector3<T>],
        with_frames: bool,
    ) {
        let columns = |k: usize| exits.iter().map(|e| e[k]).collect::<Vec<T>>();
        let (x, y, z) = (columns(0), columns(1), columns(2));
        let n = exits.len();
        let mut buf = vec![vec![T::zero(); n]; 11];
        let [a, b, cc, d, e, f, gg, h, sx, sy, sz] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, cc, d] },
            scattered: StokesSoa { s: [e, f, gg, h] },
        };
        let mut frames = ExitFramesSoa { s: [sx, sy, sz] };
        g.bench_function(BenchmarkId::new("evaluate_batch", case), |bch| {
            bch.iter(|| {
                let dirs = DirectionsSoa {
                    x: &x,
                    y: &y,
                    z: &z,
                };
                self.kernel
                    .evaluate_batch(
                        black_box(self.material),
                        black_box(self.packet),
                        self.surface,
                        self.interface,
                        dirs,
                        &mut out,
                        with_frames.then_some(&mut frames),
                    )
                    .unwrap();
                black_box(out.scattered.s[0][n - 1])
            });
        });
    }
}

/// [`batch_partial_for`] at a rough glass interface (η = 1.5, `RoughDielectric`, lit from the
/// air): 1024 exits around Snell's direction (`transmission-1024`), and the same alternating
/// with 1024 around the mirror direction (`mixed-1024`: every vector of lanes holds both
/// sides, the lanes compute both), against the per-direction prepared kernel on the mixed set.
fn batch_interface_for<T: Real>(c: &mut Criterion, prec: &str) {
    const M: usize = 1024;
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let eta = T::lit(1.5);
    let material = RoughDielectric::new(psd, eta).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let surf = surface::<T>();
    let theta_i = 30f64.to_radians();
    let theta_t = (theta_i.sin() / 1.5).asin();
    let packet = scene::<T>(theta_i, theta_i, 0.0, 0.7, 5.0).packet;
    let mut rng = Lcg(0xba7d);
    let mut exit = |centre: f64, side: f64| {
        let to = (centre + (rng.uniform() - 0.5) * 0.26).abs();
        let po = (rng.uniform() - 0.5) * 0.52;
        Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), side * to.cos()).map(T::lit)
    };
    let below: Vec<Vector3<T>> = (0..M).map(|_| exit(theta_t, -1.0)).collect();
    let mixed: Vec<Vector3<T>> = (0..M)
        .map(|i| {
            if i % 2 == 0 {
                exit(theta_i, 1.0)
            } else {
                exit(theta_t, -1.0)
            }
        })
        .collect();
    let mut g = c.benchmark_group(format!("kernel_batch_interface/{prec}"));
    g.throughput(criterion::Throughput::Elements(M as u64));
    let batch = BatchScene {
        kernel: &kernel,
        material: &material,
        packet: &packet,
        surface: &surf,
        interface: Some(eta),
    };
    batch.bench(&mut g, "transmission-1024", &below);
    batch.bench(&mut g, "mixed-1024", &mixed);
    g.bench_function(
        BenchmarkId::new("per-direction-prepared", "mixed-1024"),
        |bch| {
            bch.iter(|| {
                let prepared = kernel.prepare(black_box(&packet), &surf).unwrap();
                for e in &mixed {
                    let geo = Geometry::for_packet_at_interface(&packet, &surf, eta, *e).unwrap();
                    black_box(kernel.evaluate_prepared(black_box(&material), &prepared, &geo));
                }
            });
        },
    );
    g.finish();
}

/// `evaluate_batch` at the Intensity level against the Full level (`Kernel::<Pol, Partial>`,
/// both lobes and the exit frames) at a rough glass interface lit from the air at 30° by the
/// two-shape packet of [`batch_partial_for`]: 1024 exits alternating around the mirror and Snell
/// directions (`lobe-1024`, as `mixed-1024` of [`batch_interface_for`]), and 1024 exits uniform
/// in solid angle over both hemispheres, `θ_o` up to 87° (`hemisphere-1024`: mostly off the
/// lobes). `Intensity-no-frames-*` asks for `S0` alone, without the exit frames.
fn batch_levels_for<T: Real>(c: &mut Criterion, prec: &str) {
    const M: usize = 1024;
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let eta = T::lit(1.5);
    let material = RoughDielectric::new(psd, eta).unwrap();
    let surf = surface::<T>();
    let theta_i = 30f64.to_radians();
    let theta_t = (theta_i.sin() / 1.5).asin();
    let packet = scene::<T>(theta_i, theta_i, 0.0, 0.7, 5.0).packet;
    let mut rng = Lcg(0xba7d);
    let mut exit = |centre: f64, side: f64| {
        let to = (centre + (rng.uniform() - 0.5) * 0.26).abs();
        let po = (rng.uniform() - 0.5) * 0.52;
        Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), side * to.cos()).map(T::lit)
    };
    let lobe: Vec<Vector3<T>> = (0..M)
        .map(|i| {
            if i % 2 == 0 {
                exit(theta_i, 1.0)
            } else {
                exit(theta_t, -1.0)
            }
        })
        .collect();
    let mut rng = Lcg(0x4e31);
    let hemisphere: Vec<Vector3<T>> = (0..M)
        .map(|i| {
            let cos = 0.05 + 0.95 * rng.uniform();
            let sin = (1.0 - cos * cos).sqrt();
            let phi = rng.uniform() * std::f64::consts::TAU;
            let side = if i % 2 == 0 { 1.0 } else { -1.0 };
            Vector3::new(sin * phi.cos(), sin * phi.sin(), side * cos).map(T::lit)
        })
        .collect();
    let mut g = c.benchmark_group(format!("kernel_batch_levels/{prec}"));
    g.throughput(criterion::Throughput::Elements(M as u64));
    let full = Kernel::<Full, Partial>::default();
    let intensity = Kernel::<Intensity, Partial>::default();
    for (case, exits) in [("lobe-1024", &lobe), ("hemisphere-1024", &hemisphere)] {
        BatchScene {
            kernel: &full,
            material: &material,
            packet: &packet,
            surface: &surf,
            interface: Some(eta),
        }
        .bench(&mut g, &format!("Full-{case}"), exits);
        let scene = BatchScene {
            kernel: &intensity,
            material: &material,
            packet: &packet,
            surface: &surf,
            interface: Some(eta),
        };
        scene.bench(&mut g, &format!("Intensity-{case}"), exits);
        // What a renderer that ignores polarization asks for: S0, no exit frames.
        scene.bench_with(&mut g, &format!("Intensity-no-frames-{case}"), exits, false);
    }
    g.finish();
}

/// Four wavelengths of one path (λ = 0.45–0.60 µm, the index and the packet's shapes per
/// wavelength) on the 1024 exits of [`batch_partial_for`]: `evaluate_batch_spectral` (the exit
/// geometry once per vector of exits) against four `evaluate_batch` calls, both lobes and the
/// exit frames. Throughput counts direction–wavelength pairs.
fn batch_spectral_for<T: Real>(c: &mut Criterion, prec: &str) {
    let mut g = c.benchmark_group(format!("kernel_batch_spectral/{prec}"));
    g.throughput(criterion::Throughput::Elements(
        (SPECTRAL_EXITS * SPECTRAL_W) as u64,
    ));
    // First order (σ = 20 nm), and the Kirchhoff series at `vσ ≈ 1` (σ = 40 nm, tol 10⁻⁶).
    spectral_case::<T, _>(&mut g, "", 0.02, Kernel::<Full, Partial>::default());
    let series = KirchhoffSeries::new(1e-6).unwrap();
    let kernel = Kernel::<Full, Partial>::default().with_roughness(series);
    spectral_case::<T, _>(&mut g, "-series", 0.04, kernel);
    g.finish();
}

const SPECTRAL_EXITS: usize = 1024;
const SPECTRAL_W: usize = 4;

/// One case of [`batch_spectral_for`]: the PSD's rms height `sigma` (µm) and the kernel.
fn spectral_case<T: Real, Rough>(
    g: &mut criterion::BenchmarkGroup<'_, WallTime>,
    suffix: &str,
    sigma: f64,
    kernel: Kernel<Full, Partial, Rough>,
) where
    Rough: RoughnessWeights<T, GaussianPsd<T, 2>, Partial>,
{
    use gmueller::interaction::batch::Wavelength;
    const M: usize = SPECTRAL_EXITS;
    const W: usize = SPECTRAL_W;
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(sigma), T::lit(2.0)).unwrap();
    let materials: Vec<_> = (0..W)
        .map(|w| {
            let eta = Complex::new(T::lit(1.52 - 0.01 * w as f64), T::zero());
            RoughSurface {
                psd,
                specular: FresnelReflection::new(eta).unwrap(),
                scatter: RayleighRice::new(eta).unwrap(),
            }
        })
        .collect();
    let theta_i = 30f64.to_radians();
    let base = scene::<T>(theta_i, theta_i, 0.0, 0.7, 5.0).packet;
    let packets: Vec<_> = (0..W)
        .map(|w| {
            let lambda = T::lit(0.45 + 0.05 * w as f64);
            // The scene's shapes (Θ_x = w², Θ_y = (1.2 w)², w = 5), grown with λ.
            let wx = 5.0 * (1.0 + 0.05 * w as f64);
            let wy = 1.2 * wx;
            let shape = |v: f64| {
                CoherenceShape::new(Matrix2::new(v * v, 0.0, 0.0, v * v).map(T::lit)).unwrap()
            };
            WavePacket::new(base.stokes(), shape(wx), shape(wy), *base.frame(), lambda).unwrap()
        })
        .collect();
    let wavelengths: Vec<_> = (0..W)
        .map(|w| Wavelength {
            material: &materials[w],
            packet: &packets[w],
            interface: None,
        })
        .collect();
    let surf = surface::<T>();
    let mut rng = Lcg(0xba7c);
    let exits: Vec<Vector3<T>> = (0..M)
        .map(|_| {
            let to = (theta_i + (rng.uniform() - 0.5) * 0.26).abs();
            let po = (rng.uniform() - 0.5) * 0.52;
            Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos()).map(T::lit)
        })
        .collect();
    let columns = |k: usize| exits.iter().map(|e| e[k]).collect::<Vec<T>>();
    let (x, y, z) = (columns(0), columns(1), columns(2));
    let mut buf = vec![vec![vec![T::zero(); M]; 8]; W];
    let mut fbuf = vec![vec![T::zero(); M]; 3];
    let [sx, sy, sz] = &mut fbuf[..] else {
        unreachable!()
    };
    let mut frames = ExitFramesSoa { s: [sx, sy, sz] };
    let mut outs: Vec<_> = buf
        .iter_mut()
        .map(|cols| {
            let [a, b, cc, d, e, f, gg, h] = &mut cols[..] else {
                unreachable!()
            };
            LobesSoa {
                specular: StokesSoa { s: [a, b, cc, d] },
                scattered: StokesSoa { s: [e, f, gg, h] },
            }
        })
        .collect();
    let dirs = DirectionsSoa {
        x: &x,
        y: &y,
        z: &z,
    };
    g.bench_function(
        BenchmarkId::new(format!("evaluate_batch_spectral{suffix}"), "4x1024"),
        |bch| {
            bch.iter(|| {
                kernel
                    .evaluate_batch_spectral(
                        black_box(&wavelengths),
                        &surf,
                        dirs,
                        &mut outs,
                        Some(&mut frames),
                    )
                    .unwrap();
                black_box(outs[W - 1].scattered.s[0][M - 1])
            });
        },
    );
    g.bench_function(
        BenchmarkId::new(format!("evaluate_batch-per-wavelength{suffix}"), "4x1024"),
        |bch| {
            bch.iter(|| {
                for (w, out) in wavelengths.iter().zip(outs.iter_mut()) {
                    kernel
                        .evaluate_batch(
                            black_box(w.material),
                            black_box(w.packet),
                            &surf,
                            None,
                            dirs,
                            out,
                            Some(&mut frames),
                        )
                        .unwrap();
                }
                black_box(outs[W - 1].scattered.s[0][M - 1])
            });
        },
    );
}

/// Reflection against transmission at a rough glass interface (`RoughDielectric`, η = 1.5, the
/// same Gaussian PSD), every level, per exit of a prepared packet, same run: the seeded scenes
/// of [`scenes`] with the exits either within ~15° of the mirror direction or within ~15° of
/// Snell's direction below the surface.
fn interface_for<T: Real>(c: &mut Criterion, prec: &str) {
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let glass = RoughDielectric::new(psd, T::lit(1.5)).unwrap();
    let mut rng = Lcg(0x5eed);
    let mut cases = Vec::new();
    for _ in 0..N {
        let ti = rng.uniform() * 70f64.to_radians();
        let dt = (rng.uniform() - 0.5) * 30f64.to_radians();
        let po = (rng.uniform() - 0.5) * 0.6;
        let psi = (rng.uniform() - 0.5) * 6.0;
        let w = 1.0 + 20.0 * rng.uniform();
        let s = scene::<T>(ti, ti, 0.0, psi, w);
        let dir = |t: f64, z: f64| {
            Vector3::new(t.sin() * po.cos(), t.sin() * po.sin(), z * t.cos()).map(T::lit)
        };
        let refl = dir((ti + dt).abs().min(1.4), 1.0);
        let snell = (ti.sin() / 1.5).asin();
        let trans = dir((snell + dt).abs().min(1.4), -1.0);
        let g = |e| glass.geometry_for_packet(&s.packet, &surface(), e).unwrap();
        cases.push((s.packet, g(refl), g(trans)));
    }
    let group = format!("kernel_interface/{prec}");
    struct Bench<'a, T: Real> {
        c: &'a mut Criterion,
        group: &'a str,
        glass: &'a RoughDielectric<T, GaussianPsd<T, 2>>,
        cases: &'a [(WavePacket<T>, Geometry<T>, Geometry<T>)],
    }
    impl<T: Real> LevelVisitor<T, GaussianPsd<T, 2>> for Bench<'_, T> {
        type Output = ();
        fn visit<Pol, Coh>(self, level: Level, kernel: Kernel<Pol, Coh>)
        where
            Pol: PolarizationModel,
            Coh: CoherenceWeights<T, GaussianPsd<T, 2>>,
        {
            let mut g = self.c.benchmark_group(self.group);
            let prepared: Vec<_> = self
                .cases
                .iter()
                .map(|(p, _, _)| kernel.prepare(p, &surface()).unwrap())
                .collect();
            let name = level.name().replace('/', "x");
            for (side, pick) in [("reflection", 0usize), ("transmission", 1)] {
                g.bench_function(BenchmarkId::new(&name, side), |b| {
                    let mut i = 0;
                    b.iter(|| {
                        i = (i + 1) & (N - 1);
                        let (_, r, t) = &self.cases[i];
                        let geo = if pick == 0 { r } else { t };
                        black_box(kernel.evaluate_prepared(
                            black_box(self.glass),
                            black_box(&prepared[i]),
                            black_box(geo),
                        ))
                    });
                });
            }
            g.finish();
        }
    }
    for level in Level::ALL {
        level.dispatch(
            ClosedForm,
            Bench {
                c,
                group: &group,
                glass: &glass,
                cases: &cases,
            },
        );
    }
}

/// The batch of pairs (issue 39, the wavefront case): `Kernel::<Full, Partial>::evaluate_pairs`
/// on 1024 pairs, every one its own direction to the light and exit (`Lcg::light_and_exit`:
/// half the exits near the mirror direction, half anywhere above) with the surface coherence of
/// sunlight (37.6 µm), on rough gold at 0.55 µm (the wavefront example's material), against
/// the same pairs one at a time through the renderer layer (`Bsdf::prepare_surface` then
/// `Bsdf::eval_stokes`, which also computes the coherent lobe's mass) and through the kernel
/// (`Kernel::prepare` of each pair's `SurfaceCoherence` packet, built outside the timing, then
/// `evaluate_prepared`); and the one material type's batch (`Material::eval_incident_pairs`,
/// `Full · Partial`, each coherent lobe divided by its light's mass, as the renderer layer);
/// and both lobes' Mueller matrices (`evaluate_pairs_mueller`, the backward weight's value)
/// against `Bsdf::prepare_surface` + `evaluate_mueller_prepared` one pair at a time.
fn pairs_for<T: Real>(c: &mut Criterion, prec: &str) {
    use gmueller::bsdf::{Bsdf, Material, ShadingPoint, SurfaceCoherence};
    use gmueller::interaction::Level;
    use gmueller::interaction::RoughConductor;
    use gmueller::interaction::batch::PairsSoa;
    use gmueller::spectral::Metal;
    use gmueller::stokes::Stokes;
    const M: usize = 1024;
    let lambda = T::lit(0.55);
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.0438), T::lit(0.619)).unwrap();
    let gold = RoughConductor::new(psd, Metal::Au.index(lambda)).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let surf = surface::<T>();
    let sun = SurfaceCoherence::fixed(T::lit(37.6)).unwrap();
    let bsdf = Bsdf::new(&gold, kernel, surf, lambda).unwrap();
    let mut rng = Lcg(0x9a1e);
    let mut cols: Vec<Vec<T>> = vec![Vec::new(); 7];
    let mut packets = Vec::with_capacity(M);
    for i in 0..M {
        let (s, r) = rng.light_and_exit(i);
        let (s, r) = (Vector3::from(s).map(T::lit), Vector3::from(r).map(T::lit));
        for (col, v) in cols.iter_mut().zip([s.x, s.y, s.z, r.x, r.y, r.z]) {
            col.push(v);
        }
        let w = bsdf.surface_width(&s, &sun).unwrap();
        cols[6].push(w.recip());
        let packet = SurfaceCoherence::fixed(w)
            .unwrap()
            .packet(Stokes::unpolarized(T::one()).unwrap(), s, &surf, lambda)
            .unwrap();
        packets.push((packet, s, r));
    }
    let k = T::two_pi() / lambda;
    let mut buf = vec![vec![T::zero(); M]; 8];
    let mut g = c.benchmark_group(format!("kernel_pairs/{prec}"));
    g.throughput(criterion::Throughput::Elements(M as u64));
    g.bench_function("evaluate_pairs-1024", |bch| {
        let [a, b, cc, d, e, f, gg, h] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, cc, d] },
            scattered: StokesSoa { s: [e, f, gg, h] },
        };
        bch.iter(|| {
            let pairs = PairsSoa {
                to_source: DirectionsSoa {
                    x: &cols[0],
                    y: &cols[1],
                    z: &cols[2],
                },
                exit: DirectionsSoa {
                    x: &cols[3],
                    y: &cols[4],
                    z: &cols[5],
                },
                inverse_width: &cols[6],
            };
            kernel
                .evaluate_pairs(black_box(&gold), k, &surf, pairs, &mut out, None)
                .unwrap();
        });
    });
    let material = Material::new(gold.clone(), Level::ALL[7]);
    let at = ShadingPoint::new(surf, lambda).unwrap();
    g.bench_function("material-eval_incident_pairs-1024", |bch| {
        let [a, b, cc, d, e, f, gg, h] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, cc, d] },
            scattered: StokesSoa { s: [e, f, gg, h] },
        };
        bch.iter(|| {
            let to_source = DirectionsSoa {
                x: &cols[0],
                y: &cols[1],
                z: &cols[2],
            };
            let exits = DirectionsSoa {
                x: &cols[3],
                y: &cols[4],
                z: &cols[5],
            };
            black_box(&material)
                .eval_incident_pairs(&at, &sun, to_source, exits, &mut out, None)
                .unwrap();
        });
    });
    g.bench_function("bsdf-prepare_surface-eval_stokes-1024", |bch| {
        bch.iter(|| {
            for (_, s, r) in &packets {
                let light = bsdf.prepare_surface(black_box(*s), &sun).unwrap();
                black_box(bsdf.eval_stokes(&light, *r).unwrap());
            }
        });
    });
    g.bench_function("kernel-prepare-evaluate-1024", |bch| {
        bch.iter(|| {
            for (packet, s, r) in &packets {
                let prepared = kernel.prepare(black_box(packet), &surf).unwrap();
                let geo = Geometry::new(k, &surf, *s, *r).unwrap();
                black_box(kernel.evaluate_prepared(&gold, &prepared, &geo));
            }
        });
    });
    let mut mbuf = vec![vec![T::zero(); M]; 32];
    g.bench_function("evaluate_pairs_mueller-1024", |bch| {
        let (sp, sc) = mbuf.split_at_mut(16);
        let mut sp = sp.iter_mut().map(Vec::as_mut_slice);
        let mut sc = sc.iter_mut().map(Vec::as_mut_slice);
        let mut out = MuellerLobesSoa {
            specular: MuellerSoa {
                m: core::array::from_fn(|_| sp.next().unwrap()),
            },
            scattered: MuellerSoa {
                m: core::array::from_fn(|_| sc.next().unwrap()),
            },
        };
        bch.iter(|| {
            let pairs = PairsSoa {
                to_source: DirectionsSoa {
                    x: &cols[0],
                    y: &cols[1],
                    z: &cols[2],
                },
                exit: DirectionsSoa {
                    x: &cols[3],
                    y: &cols[4],
                    z: &cols[5],
                },
                inverse_width: &cols[6],
            };
            kernel
                .evaluate_pairs_mueller(black_box(&gold), k, &surf, pairs, &mut out, None)
                .unwrap();
        });
    });
    g.bench_function(
        "bsdf-prepare_surface-evaluate_mueller_prepared-1024",
        |bch| {
            bch.iter(|| {
                for (_, s, r) in &packets {
                    let light = bsdf.prepare_surface(black_box(*s), &sun).unwrap();
                    let geo = Geometry::new(k, &surf, *s, *r).unwrap();
                    black_box(kernel.evaluate_mueller_prepared(&gold, light.prepared(), &geo));
                }
            });
        },
    );
    g.finish();
}

fn benches(c: &mut Criterion) {
    interface_for::<f64>(c, "f64");
    interface_for::<f32>(c, "f32");
    single_shape_for::<f64>(c, "f64");
    single_shape_for::<f32>(c, "f32");
    levels_for::<f64>(c, "f64");
    levels_for::<f32>(c, "f32");
    baseline_for::<f64>(c, "f64");
    baseline_for::<f32>(c, "f32");
    geometry_for::<f64>(c, "f64");
    geometry_for::<f32>(c, "f32");
    batch_for::<f64>(c, "f64");
    batch_for::<f32>(c, "f32");
    batch_partial_for::<f64>(c, "f64");
    batch_partial_for::<f32>(c, "f32");
    batch_interface_for::<f64>(c, "f64");
    batch_interface_for::<f32>(c, "f32");
    batch_levels_for::<f64>(c, "f64");
    batch_levels_for::<f32>(c, "f32");
    batch_spectral_for::<f64>(c, "f64");
    batch_spectral_for::<f32>(c, "f32");
    batch_series_for::<f64>(c, "f64");
    batch_series_for::<f32>(c, "f32");
    pairs_for::<f64>(c, "f64");
    pairs_for::<f32>(c, "f32");
}

criterion_group!(kernel, benches);
criterion_main!(kernel);
