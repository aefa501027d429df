//! Verifies that the S2.20 kernel allocates nothing per evaluation: a counting global allocator
//! (wrapping `std::alloc::System`) counts heap allocations across many evaluations at every
//! level (Intensity/OneShape/Full × PlaneWave/Partial/Incoherent) with a Gaussian PSD + `ClosedForm`
//! and with a K-correlation PSD + Gauss–Hermite blur, on an opaque surface and at a glass
//! interface in reflection and transmission, plus `Mueller::from_jones`, frame changes and
//! `Geometry::for_packet`; and the renderer layer (`gmueller::bsdf`: light helpers, `prepare`,
//! `eval` in both forms, both samplers with their draws, densities and weights, the batched
//! draws `LobeSampler::sample_batch` and `pdf_batch`, and the batched forward bounce
//! `Bsdf::sample_exit_batch`)
//! at every level
//! on rough glass and a grating, and beyond first order (`Level::dispatch_rough`: every level ×
//! first order, the Kirchhoff series, the geometric limit) on tangent-plane glass; and `Kernel::evaluate_batch` at every level (lanes and one
//! exit at a time) and `plane_wave_rayleigh_rice`; and the spectral data (`gmueller::spectral`);
//! the count must be zero.
//!
//! The counting allocator needs `unsafe impl GlobalAlloc`: the crate's `[lints]` deny
//! `unsafe_code` for every target and the library forbids it in `src/lib.rs`; this test file alone
//! allows it, for an allocator that only forwards to `System` and counts per thread (the test
//! harness's own threads allocate).
#![allow(
    unsafe_code,
    reason = "a counting global allocator for this test only; it forwards to System"
)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::hint::black_box;

use gmueller::Real;
use gmueller::frame::{Frame, frame_change_mueller, stokes_to_frame};
use gmueller::fresnel;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::level::LevelVisitor;
use gmueller::interaction::pbsdf::{FresnelReflection, RayleighRice};
use gmueller::interaction::polarization::{KernelOutput, PolarizationModel};
use gmueller::interaction::roughness::RoughnessWeights;
use gmueller::interaction::{Geometry, Kernel, Level, RoughDielectric, RoughSurface};
use gmueller::mueller::Mueller;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussHermite, GaussianPsd, KCorrelation, Psd};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;

struct Counting;

thread_local! {
    /// Allocations made by this thread (the harness's other threads allocate concurrently).
    static THREAD_ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn record() {
    // `try_with`: no count during thread-local destruction.
    let _ = THREAD_ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: forwards every call unchanged to `System`, which upholds the `GlobalAlloc` contract;
// the counter is a thread-local `Cell` with no effect on the returned memory.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        record();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        record();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        record();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f` on the calling thread.
pub(crate) fn count<R>(f: impl FnOnce() -> R) -> (usize, R) {
    let before = THREAD_ALLOCATIONS.with(Cell::get);
    let r = f();
    let after = THREAD_ALLOCATIONS.with(Cell::get);
    (after - before, r)
}

struct Scene<T: Real> {
    packet: WavePacket<T>,
    surface: Frame<T>,
    exits: Vec<Vector3<T>>,
}

fn scene<T: Real>() -> Scene<T> {
    let ti = 0.6f64;
    let travel = Vector3::new(ti.sin(), 0.0, -ti.cos()).map(T::lit);
    let frame = Frame::sp(travel, Vector3::z())
        .unwrap()
        .rotated(T::lit(0.4));
    let sx = CoherenceShape::new(Matrix2::new(9.0, 1.0, 1.0, 4.0).map(T::lit)).unwrap();
    let sy = CoherenceShape::new(Matrix2::new(12.0, 0.0, 0.0, 6.0).map(T::lit)).unwrap();
    let stokes = Stokes::new(T::lit(1.0), T::lit(0.2), T::lit(0.1), T::lit(-0.2)).unwrap();
    let packet = WavePacket::new(stokes, sx, sy, frame, T::lit(0.5)).unwrap();
    let exits = (0..50)
        .map(|i| {
            let t = 0.02 * i as f64;
            let (to, po) = (0.3 + t, -0.5 + t);
            Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos()).map(T::lit)
        })
        .collect();
    Scene {
        packet,
        surface: Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap(),
        exits,
    }
}

fn run_level<T, Pol, Coh, P, Sp, Sc>(
    name: &str,
    kernel: &Kernel<Pol, Coh>,
    material: &RoughSurface<P, Sp, Sc>,
    s: &Scene<T>,
    geometries: &[Geometry<T>],
) where
    T: Real,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, P>,
    P: Psd<T, 2>,
    Sp: gmueller::interaction::pbsdf::Pbsdf<T>,
    Sc: gmueller::interaction::pbsdf::Pbsdf<T>,
{
    let (n, sum) = count(|| {
        let mut acc = T::zero();
        for _ in 0..20 {
            for g in geometries {
                let r = kernel.evaluate(black_box(material), black_box(&s.packet), black_box(g));
                acc += r.total_intensity();
            }
        }
        acc
    });
    assert!(sum.is_finite(), "{name}: finite results");
    assert_eq!(n, 0, "{name}: {n} heap allocations in 1000 evaluations");
    // The prepared path: one `prepare`, then the exits.
    let (n, sum) = count(|| {
        let prepared = kernel.prepare(black_box(&s.packet), &s.surface).unwrap();
        let mut acc = T::zero();
        for g in geometries {
            let r = kernel.evaluate_prepared(black_box(material), black_box(&prepared), g);
            acc += r.total_intensity();
        }
        acc
    });
    assert!(sum.is_finite(), "{name}: finite prepared results");
    assert_eq!(
        n, 0,
        "{name}: {n} heap allocations in prepare + 50 evaluations"
    );
}

/// [`run_level`] for the kernel of a level chosen at run time.
struct RunLevel<'a, T: Real, P, Sp, Sc> {
    name: &'a str,
    material: &'a RoughSurface<P, Sp, Sc>,
    scene: &'a Scene<T>,
    geometries: &'a [Geometry<T>],
}

impl<T, P, Sp, Sc> LevelVisitor<T, P> for RunLevel<'_, T, P, Sp, Sc>
where
    T: Real,
    P: Psd<T, 2>,
    Sp: gmueller::interaction::pbsdf::Pbsdf<T>,
    Sc: gmueller::interaction::pbsdf::Pbsdf<T>,
{
    type Output = ();
    fn visit<Pol, Coh>(self, level: Level, kernel: Kernel<Pol, Coh>)
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P>,
    {
        let name = format!("{} {}", level.name(), self.name);
        run_level(&name, &kernel, self.material, self.scene, self.geometries);
    }
}

fn all_levels<T: Real>() {
    let s = scene::<T>();
    let eta = Complex::new(T::lit(1.5), T::zero());
    let gaussian = RoughSurface {
        psd: GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap(),
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    };
    let kc = RoughSurface {
        psd: KCorrelation::<T, 2>::new(T::lit(4e-4), T::lit(4.0), T::lit(2.5)).unwrap(),
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    };
    let gh = GaussHermite::<T>::new(6).unwrap();
    let opaque: Vec<_> = s
        .exits
        .iter()
        .map(|e| Geometry::for_packet(&s.packet, &s.surface, *e).unwrap())
        .collect();
    // A glass interface: the same exits reflected and mirrored below the surface (transmitted).
    let glass = RoughDielectric::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap(),
        T::lit(1.5),
    )
    .unwrap();
    let interface: Vec<_> = s
        .exits
        .iter()
        .flat_map(|e| [*e, Vector3::new(e.x, e.y, -e.z)])
        .map(|e| glass.geometry_for_packet(&s.packet, &s.surface, e).unwrap())
        .collect();
    for level in Level::ALL {
        level.dispatch(
            ClosedForm,
            RunLevel {
                name: "Gaussian/ClosedForm",
                material: &gaussian,
                scene: &s,
                geometries: &opaque,
            },
        );
        level.dispatch(
            gh.clone(),
            RunLevel {
                name: "KCorrelation/GaussHermite",
                material: &kc,
                scene: &s,
                geometries: &opaque,
            },
        );
        level.dispatch(
            ClosedForm,
            RunLevel {
                name: "glass interface (reflection and transmission)",
                material: &glass,
                scene: &s,
                geometries: &interface,
            },
        );
    }

    // The building blocks on their own.
    let g0 = Geometry::for_packet(&s.packet, &s.surface, s.exits[3]).unwrap();
    let (n, ok) = count(|| {
        let mut ok = true;
        for e in &s.exits {
            ok &= Geometry::for_packet(black_box(&s.packet), &s.surface, *e).is_ok();
            let m = Mueller::from_jones(&fresnel::reflection(black_box(g0.cos_i()), eta));
            let t = frame_change_mueller(s.packet.frame(), black_box(g0.incident_sp()));
            let st = stokes_to_frame(&s.packet.stokes(), s.packet.frame(), g0.incident_sp());
            ok &= (m * t).matrix()[(0, 0)].is_finite() && st.s0().is_finite();
            ok &= s.packet.rotated(black_box(T::lit(0.3))).sx().is_finite();
        }
        ok
    });
    assert!(ok);
    assert_eq!(
        n, 0,
        "{n} allocations in geometry / from_jones / frame changes"
    );
}

#[test]
fn kernel_evaluation_allocates_nothing() {
    // Sanity: the counter sees allocations.
    let (n, v) = count(|| black_box(vec![1u8; 16]));
    assert!(n >= 1 && v.len() == 16, "the counting allocator counts");
    all_levels::<f64>();
    all_levels::<f32>();
}

/// The renderer layer at `kernel` on `material`: `Bsdf::new`, the light helpers, `prepare`,
/// `eval`, both samplers with `sample`, `pdf` and their weights, counted.
fn exercise_bsdf<T, P, Sp, Sc, Pol, Coh, Rough>(
    material: &RoughSurface<P, Sp, Sc>,
    kernel: Kernel<Pol, Coh, Rough>,
    name: &str,
) where
    T: Real,
    P: gmueller::psd::Psd<T, 2>,
    Sp: gmueller::bsdf::Interface<T>,
    Sc: gmueller::interaction::pbsdf::Pbsdf<T>,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, P>,
    Rough: RoughnessWeights<T, P, Coh>,
{
    use gmueller::bsdf::{Bsdf, SamplesSoa, SurfaceCoherence, UniformsSoa};
    use gmueller::interaction::batch::StokesSoa;
    use gmueller::interaction::polarization::Throughput;
    let frame = Frame::from_normal(Vector3::new(0.1, 0.2, 1.0).map(T::lit)).unwrap();
    let coherence = SurfaceCoherence::new(T::lit(8.0)).unwrap();
    let stokes = Stokes::unpolarized(T::one()).unwrap();
    let dirs = [
        Vector3::new(-0.4, 0.1, 0.9),
        Vector3::new(0.3, -0.2, -0.93),
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(0.6, 0.5, 0.2),
    ]
    .map(|v| v.map(T::lit));
    let (n, ok) = count(|| {
        let b = Bsdf::new(material, kernel.clone(), frame, T::lit(0.55)).unwrap();
        let mut ok = true;
        for (i, s) in dirs.iter().enumerate() {
            let exit = dirs[(i + 1) % dirs.len()];
            let p = if i % 2 == 0 {
                b.distant_packet(stokes, T::lit(6.8e-5), *s)
            } else {
                b.surface_packet(stokes, *s, &coherence)
            };
            let p_packet = p.unwrap();
            let inc = b.prepare(&p_packet).unwrap();
            ok &= b.eval(black_box(&inc), exit).is_ok();
            ok &= b.eval_stokes(&inc, exit).is_ok();
            let fwd = b.exit_sampler(&inc).unwrap();
            let bwd = b.incident_sampler(exit, &coherence).unwrap();
            // The batch forms (37 draws: whole vectors and a remainder), buffers on the stack.
            let uni: [[T; 37]; 3] = core::array::from_fn(|k| {
                core::array::from_fn(|j| T::lit(((j * 7 + k * 3) % 37) as f64 / 37.0))
            });
            let [mut x, mut y, mut z, mut pdf, mut dw] = [[T::zero(); 37]; 5];
            let mut code = [0u8; 37];
            let [mut w0, mut w1, mut w2, mut w3] = [[T::zero(); 37]; 4];
            let us = UniformsSoa {
                lobe: &uni[0],
                u0: &uni[1],
                u1: &uni[2],
            };
            ok &= bwd
                .sample_batch(
                    us,
                    SamplesSoa {
                        x: &mut x,
                        y: &mut y,
                        z: &mut z,
                        pdf: &mut pdf,
                        delta_weight: &mut dw,
                        lobe: &mut code,
                    },
                )
                .is_ok();
            ok &= b
                .sample_exit_batch(
                    &p_packet,
                    us,
                    SamplesSoa {
                        x: &mut x,
                        y: &mut y,
                        z: &mut z,
                        pdf: &mut pdf,
                        delta_weight: &mut dw,
                        lobe: &mut code,
                    },
                    StokesSoa {
                        s: [&mut w0, &mut w1, &mut w2, &mut w3],
                    },
                )
                .is_ok();
            ok &= w0.iter().all(|w| w.is_finite());
            let mut p = [T::zero(); 37];
            let dirs = gmueller::interaction::batch::DirectionsSoa {
                x: &x,
                y: &y,
                z: &z,
            };
            ok &= fwd.pdf_batch(dirs, &mut p).is_ok();
            ok &= p.iter().all(|p| p.is_finite());
            for u in [0.1, 0.5, 0.97] {
                let u = T::lit(u);
                if let Some(d) = fwd.sample(u, [u, T::lit(0.3)]) {
                    ok &= fwd.pdf(&d.direction) == d.pdf || d.lobe.delta;
                    ok &= b.exit_weight(&inc, &d).unwrap().0.m00().is_finite();
                }
                if let Some(d) = bwd.sample(u, [T::lit(0.7), u]) {
                    ok &= bwd.pdf(&d.direction) == d.pdf || d.lobe.delta;
                    let w = b.incident_weight(exit, &coherence, &d).unwrap().0;
                    ok &= w.m00().is_finite();
                }
            }
        }
        ok
    });
    assert!(ok, "{name}");
    assert_eq!(n, 0, "{n} allocations in the renderer layer at {name}");
}

/// The renderer layer at every level on rough glass (both sides) and a grating (first order),
/// and on tangent-plane glass at `vσ ≈ 3` at every level × every run-time roughness level
/// (`Level::dispatch_rough`).
fn renderer_layer<T: Real>() {
    use gmueller::interaction::level::RoughLevelVisitor;
    use gmueller::interaction::roughness::{KirchhoffSeries, RoughnessLevel};
    use gmueller::interaction::{KirchhoffDielectric, Roughness};
    use gmueller::psd::Grating;
    use gmueller::psd::Psd;

    struct RunBsdf<'a, T: Real, P> {
        material:
            &'a RoughSurface<P, gmueller::interaction::pbsdf::FresnelInterface<T>, RayleighRice<T>>,
    }
    impl<T: Real, P: Psd<T, 2>> LevelVisitor<T, P> for RunBsdf<'_, T, P> {
        type Output = ();
        fn visit<Pol, Coh>(self, level: Level, kernel: Kernel<Pol, Coh>)
        where
            Pol: PolarizationModel,
            Coh: CoherenceWeights<T, P>,
        {
            exercise_bsdf(self.material, kernel, level.name());
        }
    }
    struct RunRough<'a, T: Real> {
        material: &'a KirchhoffDielectric<T, GaussianPsd<T, 2>>,
    }
    impl<T: Real> RoughLevelVisitor<T, GaussianPsd<T, 2>> for RunRough<'_, T> {
        type Output = RoughnessLevel;
        fn visit<Pol, Coh, Rough>(
            self,
            level: Level,
            kernel: Kernel<Pol, Coh, Rough>,
        ) -> RoughnessLevel
        where
            Pol: PolarizationModel,
            Coh: CoherenceWeights<T, GaussianPsd<T, 2>>,
            Rough: RoughnessWeights<T, GaussianPsd<T, 2>, Coh>,
        {
            exercise_bsdf(
                self.material,
                kernel,
                &format!("{} · {:?}", level.name(), Rough::LEVEL),
            );
            Rough::LEVEL
        }
    }
    let glass = RoughDielectric::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(2.0)).unwrap(),
        T::lit(1.5),
    )
    .unwrap();
    let grating = RoughDielectric::new(
        Grating::<T, 2>::sinusoidal_height(
            T::lit(0.02),
            T::lit(3.0),
            &nalgebra::Vector2::new(T::one(), T::lit(0.3)),
        )
        .unwrap(),
        T::lit(1.5),
    )
    .unwrap();
    let rough = KirchhoffDielectric::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.12), T::lit(2.0)).unwrap(),
        T::lit(1.5),
    )
    .unwrap();
    for level in Level::ALL {
        level.dispatch(ClosedForm, RunBsdf { material: &glass });
        level.dispatch(ClosedForm, RunBsdf { material: &grating });
        for roughness in [
            Roughness::FirstOrder,
            Roughness::Series(KirchhoffSeries::new(1e-4).unwrap()),
            Roughness::Geometric,
        ] {
            let ran = level.dispatch_rough(ClosedForm, roughness, RunRough { material: &rough });
            assert_eq!(ran, roughness.level());
        }
    }
}

#[test]
fn renderer_layer_allocates_nothing() {
    renderer_layer::<f64>();
    renderer_layer::<f32>();
}

/// `Kernel::evaluate_batch` at every level (the lane path on a Gaussian-PSD and a
/// two-component mixture-PSD rough conductor, one exit at a time on a glass interface in
/// reflection and transmission) and
/// `plane_wave_rayleigh_rice`, with the exit frames: 200 exits per call, buffers allocated
/// before counting.
fn batches<T: Real>() {
    use gmueller::interaction::batch::{
        DirectionsSoa, ExitFramesSoa, LobesSoa, StokesSoa, plane_wave_rayleigh_rice,
    };
    use gmueller::interaction::{
        Full, Incoherent, Intensity, OneShape, Partial, PlaneWave, RoughConductor,
    };
    let s = scene::<T>();
    let n = 200;
    let mut d: [Vec<T>; 3] = Default::default();
    for i in 0..n {
        let e = s.exits[i % s.exits.len()];
        // Every other pass mirrored below the surface (transmission at the interface).
        let z = if (i / s.exits.len()) % 2 == 1 {
            -e.z
        } else {
            e.z
        };
        for (c, v) in d.iter_mut().zip([e.x, e.y, z]) {
            c.push(v);
        }
    }
    let above: [Vec<T>; 3] = [
        d[0].clone(),
        d[1].clone(),
        d[2].iter().map(|z| z.abs()).collect(),
    ];
    let gold = RoughConductor::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap(),
        Complex::new(T::lit(0.2), T::lit(3.4)),
    )
    .unwrap();
    let glass = RoughDielectric::new(
        GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap(),
        T::lit(1.5),
    )
    .unwrap();
    let mixture = RoughConductor::new(
        gmueller::psd::GaussianMixturePsd::new(vec![
            GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap(),
            GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(0.7)).unwrap(),
        ])
        .unwrap(),
        Complex::new(T::lit(0.2), T::lit(3.4)),
    )
    .unwrap();
    let mut buf = vec![vec![T::zero(); n]; 11];
    macro_rules! level {
        ($pol:ty, $coh:ty) => {{
            let kernel = Kernel::<$pol, $coh>::default();
            let [a, b, c, e, f, g, h, i, sx, sy, sz] = &mut buf[..] else {
                unreachable!()
            };
            let mut out = LobesSoa {
                specular: StokesSoa { s: [a, b, c, e] },
                scattered: StokesSoa { s: [f, g, h, i] },
            };
            let mut frames = ExitFramesSoa { s: [sx, sy, sz] };
            let (count, ok) = count(|| {
                let lanes = DirectionsSoa {
                    x: &above[0],
                    y: &above[1],
                    z: &above[2],
                };
                let both = DirectionsSoa {
                    x: &d[0],
                    y: &d[1],
                    z: &d[2],
                };
                let a = kernel.evaluate_batch(
                    black_box(&gold),
                    &s.packet,
                    &s.surface,
                    None,
                    lanes,
                    &mut out,
                    Some(&mut frames),
                );
                let lit = out.scattered.s[0].iter().any(|v| *v > T::zero());
                let m = kernel.evaluate_batch(
                    black_box(&mixture),
                    &s.packet,
                    &s.surface,
                    None,
                    lanes,
                    &mut out,
                    Some(&mut frames),
                );
                let b = kernel.evaluate_batch(
                    black_box(&glass),
                    &s.packet,
                    &s.surface,
                    Some(T::lit(1.5)),
                    both,
                    &mut out,
                    Some(&mut frames),
                );
                a.is_ok() && m.is_ok() && b.is_ok() && lit
            });
            let name = stringify!($pol, $coh);
            assert!(ok, "{name}: the batches ran and lit something");
            assert_eq!(
                count, 0,
                "{name}: {count} allocations in two batches of {n}"
            );
        }};
    }
    level!(Intensity, PlaneWave);
    level!(Intensity, Partial);
    level!(Intensity, Incoherent);
    level!(OneShape, PlaneWave);
    level!(OneShape, Partial);
    level!(OneShape, Incoherent);
    level!(Full, PlaneWave);
    level!(Full, Partial);
    level!(Full, Incoherent);
    let plane = RoughSurface {
        psd: GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap(),
        specular: FresnelReflection::new(Complex::new(T::lit(1.5), T::zero())).unwrap(),
        scatter: RayleighRice::new(Complex::new(T::lit(1.5), T::zero())).unwrap(),
    };
    let [a, b, c, e, ..] = &mut buf[..] else {
        unreachable!()
    };
    let mut out = StokesSoa { s: [a, b, c, e] };
    let (count, r) = count(|| {
        let exits = DirectionsSoa {
            x: &above[0],
            y: &above[1],
            z: &above[2],
        };
        plane_wave_rayleigh_rice(black_box(&plane), &s.packet, &s.surface, &exits, &mut out)
    });
    assert!(r.is_ok() && out.s[0].iter().any(|v| *v > T::zero()));
    assert_eq!(count, 0, "{count} allocations in plane_wave_rayleigh_rice");
}

#[test]
fn batch_evaluation_allocates_nothing() {
    batches::<f64>();
    batches::<f32>();
}

/// The random medium (`gmueller::medium`): `prepare` (`σ_s` quadrature, sampler), `eval`,
/// `differential_scattering`, `sample`, `pdf` at the Full·Partial, OneShape·PlaneWave and
/// Intensity·Incoherent levels, Gaussian (closed form) and K-correlation (Gauss–Hermite) PSDs.
fn medium_levels<T: Real>() {
    use gmueller::interaction::polarization::Throughput;
    use gmueller::medium::{Dipole, PhaseFunction, RandomMedium, VolumeCoherence};
    use gmueller::psd::{GaussianPsd as G, KCorrelation as K};
    fn run<T, P, Pol, Coh>(
        name: &str,
        m: &RandomMedium<P, Dipole>,
        kernel: Kernel<Pol, Coh>,
        s: &Scene<T>,
    ) where
        T: Real,
        P: Psd<T, 3>,
        Pol: PolarizationModel,
        Coh: VolumeCoherence<T, P>,
    {
        let packet = s.packet.with_longitudinal_coherence(T::lit(2.0)).unwrap();
        let phase = PhaseFunction::new(m, kernel);
        let (n, ok) = count(|| {
            let mut ok = true;
            for i in 0..5 {
                let inc = phase.prepare(black_box(&packet)).unwrap();
                for (j, r) in s.exits.iter().enumerate() {
                    let v = phase.eval(&inc, *r).unwrap();
                    let d = phase.differential_scattering(&inc, *r).unwrap();
                    let u = T::lit((i * 50 + j) as f64 / 251.0);
                    let smp = phase.sample(&inc, u, [T::lit(0.3), u]);
                    ok &= v.phase.is_finite()
                        && smp.weight.is_finite()
                        && phase.pdf(&inc, r).is_finite()
                        && <Pol::Throughput<T> as Throughput<T>>::intensity(&d.light).is_finite();
                }
            }
            ok
        });
        assert!(ok, "{name}: finite results");
        assert_eq!(n, 0, "{name}: {n} heap allocations");
    }
    let g = RandomMedium::new(
        G::<T, 3>::isotropic(T::lit(1e-3), T::lit(0.3)).unwrap(),
        Dipole,
    );
    let k = RandomMedium::new(
        K::<T, 3>::new(T::lit(1e-6), T::lit(0.2), T::lit(3.0)).unwrap(),
        Dipole,
    );
    let s = scene::<T>();
    run(
        "medium Full·Partial",
        &g,
        Kernel::<gmueller::interaction::Full, gmueller::interaction::Partial>::default(),
        &s,
    );
    run(
        "medium OneShape·PlaneWave",
        &g,
        Kernel::<gmueller::interaction::OneShape, gmueller::interaction::PlaneWave>::default(),
        &s,
    );
    run(
        "medium Intensity·Incoherent",
        &g,
        Kernel::<gmueller::interaction::Intensity, gmueller::interaction::Incoherent>::default(),
        &s,
    );
    run(
        "medium K-correlation Full·Partial(GH)",
        &k,
        Kernel::<gmueller::interaction::Full, _>::new(gmueller::interaction::Partial(
            GaussHermite::<T>::new(4).unwrap(),
        )),
        &s,
    );
}

#[test]
fn medium_allocates_nothing() {
    medium_levels::<f64>();
    medium_levels::<f32>();
}

/// `gmueller::spectral`: the colour-matching functions, XYZ ↔ sRGB and its transfer function,
/// every metal's index (inside, outside and refused), every glass and user-built formulas.
fn spectral_data<T: Real>() -> T {
    use gmueller::spectral::{
        Cauchy, Glass, Metal, Sellmeier, cie1931_integral, cie1931_normalized, linear_srgb_to_xyz,
        srgb_decode, srgb_encode, xyz_to_linear_srgb,
    };
    let mut acc = T::zero();
    for i in 0..200 {
        let l = T::lit(0.25 + 0.004 * f64::from(i));
        let rgb = xyz_to_linear_srgb(cie1931_normalized(black_box(l)));
        let xyz = linear_srgb_to_xyz(rgb.map(|c| srgb_decode(srgb_encode(c.abs()))));
        acc += xyz[1] + cie1931_integral::<T>()[0];
        for metal in Metal::ALL {
            acc += metal.index(l).im + metal.try_index(l).map_or(T::zero(), |z| z.re);
        }
        for glass in Glass::ALL {
            acc += glass.index(l) + glass.try_index(l).unwrap_or(T::zero());
        }
        let s = Sellmeier::new([T::one()], [T::lit(0.01)]).unwrap();
        let c = Cauchy::new([T::lit(1.5), T::lit(0.004)]).unwrap();
        acc += s.index(l) + c.index(l);
    }
    acc
}

#[test]
fn spectral_data_allocates_nothing() {
    let (n, acc) = count(spectral_data::<f64>);
    assert!(acc.is_finite());
    assert_eq!(n, 0, "gmueller::spectral allocated {n} times (f64)");
    let (n, acc) = count(spectral_data::<f32>);
    assert!(acc.is_finite());
    assert_eq!(n, 0, "gmueller::spectral allocated {n} times (f32)");
}
