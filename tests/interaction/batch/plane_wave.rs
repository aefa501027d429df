//! Verifies the SIMD batch path `interaction::batch::plane_wave_rayleigh_rice` against the
//! per-direction kernel it replaces, `Kernel::<Full, PlaneWave>::evaluate(..).scattered` per exit
//! direction (and the `OneShape` level): proptest over incidence 0–85°, exits over the
//! hemisphere (not unit length), dielectric and absorbing η (Im η up to 8), anisotropic PSDs,
//! tilted surfaces, turned packet frames and polarized input, f32 and f64, batch lengths 0, 1,
//! 3, 7, 17 and 1000; exactly normal incidence and exit (the s/p tangent fallback) and the band
//! near the normal; grazing; exits far off specular where the PSD underflows (exact zeros);
//! η = 1 and a smooth surface (exact zeros); indices that take the scalar fallback (bit for bit); the strided layouts; and the errors (mismatched lengths, exits
//! below the surface, NaN/∞/zero exits, a packet travelling away), after which nothing was
//! written.
//!
//! Tolerance, per Stokes parameter of each exit: `|batch − scalar| ≤ abs + rel · S0_scalar` with
//! `rel = 4 ε (4 + |E|)`, `E` the sum of the magnitudes of the exponents (PSD amplitude and
//! value, Debye–Waller, prefactor) that the batch path adds before one exponential while the
//! per-direction path exponentiates them separately (the condition number of `exp` is `|E|`): at most
//! 3.6e-15 + 8.9e-16 |E| ≤ 7e-13 in f64 (|E| ≤ 745 before underflow) and 1.9e-6 + 4.8e-7 |E| in
//! f32 (≤ 1e-5 for |E| ≤ 17, the lobe; up to 5e-5 at the f32 underflow threshold |E| ≈ 104).
//! Measured: at most 0.7 ε (1 + |E|) in both precisions. `abs` = the type's smallest normal
//! number times the output scale `2π cos θ_o/λ² · M₀₀ · S0_in · max(1, σ²|Λ|^{1/2})`, for results
//! the per-direction path rounds through subnormal numbers.

use crate::common;
use crate::common::Lcg;

use gmueller::Real;
use gmueller::error::Error;
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::batch::{DirectionsSoa, StokesSoa, plane_wave_rayleigh_rice};
use gmueller::interaction::pbsdf::{FresnelReflection, Pbsdf, RayleighRice};
use gmueller::interaction::{Full, Geometry, Kernel, OneShape, PlaneWave, RoughSurface};
use gmueller::mueller::batch::padded_stride;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{GaussianPsd, Psd};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector2, Vector3, Vector4};
use num_complex::Complex;
use proptest::prelude::*;

/// Everything a batch evaluation needs, in f64 (converted to `T` by [`Built::new`]).
#[derive(Debug, Clone)]
struct Scene {
    theta_i: f64,
    phi_i: f64,
    /// Surface normal (unit) and a hint for its first tangent.
    normal: Vector3<f64>,
    tangent_hint: Vector3<f64>,
    /// Packet frame turned from s/p by this angle.
    psi: f64,
    stokes: Vector4<f64>,
    eta: Complex<f64>,
    sigma: f64,
    /// Correlation covariance Λ (µm²).
    lambda_cov: Matrix2<f64>,
    wavelength: f64,
    exits: Vec<Vector3<f64>>,
}

struct Built<T: Real> {
    surface: Frame<T>,
    packet: WavePacket<T>,
    psd: GaussianPsd<T, 2>,
    eta: Complex<T>,
    exits: Vec<Vector3<T>>,
}

impl<T: Real> Built<T> {
    fn new(sc: &Scene) -> Self {
        let lit = |v: Vector3<f64>| v.map(T::lit);
        let surface = Frame::from_direction_and_x(lit(sc.normal), lit(sc.tangent_hint)).unwrap();
        let (t1, t2, n) = (surface.x(), surface.y(), surface.k());
        let (st, ct) = (T::lit(sc.theta_i.sin()), T::lit(sc.theta_i.cos()));
        let (sp, cp) = (T::lit(sc.phi_i.sin()), T::lit(sc.phi_i.cos()));
        let travel = -(t1 * (st * cp) + t2 * (st * sp) + n * ct);
        let frame = Frame::sp(travel, n).unwrap().rotated(T::lit(sc.psi));
        let s = sc.stokes.map(T::lit);
        let stokes = Stokes::new(s[0], s[1], s[2], s[3]).unwrap();
        let packet = WavePacket::from_stokes(
            stokes,
            CoherenceShape::isotropic(T::lit(10.0)).unwrap(),
            frame,
            T::lit(sc.wavelength),
        )
        .unwrap();
        let corr = Gaussian::new(sc.lambda_cov.map(T::lit)).unwrap();
        let psd = GaussianPsd::from_autocorrelation(T::lit(sc.sigma * sc.sigma), &corr).unwrap();
        Self {
            surface,
            packet,
            psd,
            eta: Complex::new(T::lit(sc.eta.re), T::lit(sc.eta.im)),
            exits: sc.exits.iter().map(|&e| lit(e)).collect(),
        }
    }

    /// The material of the scalar reference (the specular part does not enter the plane-wave
    /// scattered output).
    fn material(&self) -> RoughSurface<GaussianPsd<T, 2>, FresnelReflection<T>, RayleighRice<T>> {
        RoughSurface {
            psd: self.psd,
            specular: FresnelReflection::new(self.eta).unwrap(),
            scatter: RayleighRice::new(self.eta).unwrap(),
        }
    }

    /// The batch output as four vectors (through a padded buffer).
    fn batch(&self) -> Result<[Vec<T>; 4], Error> {
        let n = self.exits.len();
        let stride = padded_stride::<T>(n);
        let mut dirs = vec![T::zero(); 3 * stride];
        for (i, e) in self.exits.iter().enumerate() {
            for k in 0..3 {
                dirs[k * stride + i] = e[k];
            }
        }
        let mut buf = vec![T::lit(f64::NAN); 4 * stride];
        let exits = DirectionsSoa::from_strided(&dirs, n, stride).unwrap();
        let mut out = StokesSoa::from_strided(&mut buf, n, stride).unwrap();
        plane_wave_rayleigh_rice(
            &self.material(),
            &self.packet,
            &self.surface,
            &exits,
            &mut out,
        )?;
        Ok(core::array::from_fn(|k| out.s[k].to_vec()))
    }

    /// Compares the batch with the per-direction kernel exit by exit; returns the number of exits where
    /// the scalar result is exactly 0.
    fn compare(&self, what: &str) -> usize {
        let got = self.batch().unwrap();
        let material = self.material();
        let full = Kernel::<Full, PlaneWave>::default();
        let one = Kernel::<OneShape, PlaneWave>::default();
        let eps = T::EPSILON.to_f64();
        let tiny = min_positive::<T>();
        let s0_in = self.packet.stokes().s0().to_f64();
        let mut zeros = 0;
        for (i, &e) in self.exits.iter().enumerate() {
            let g = Geometry::for_packet(&self.packet, &self.surface, e).unwrap();
            let want = full.evaluate(&material, &self.packet, &g);
            let want1 = one.evaluate(&material, &self.packet, &g).scattered.vector();
            assert_eq!(
                want.specular.s0(),
                T::zero(),
                "plane wave: no specular part"
            );
            let want = want.scattered.vector().map(|v| v.to_f64());
            if want[0] == 0.0 {
                zeros += 1;
            }
            let (k, ci, co) = (g.k().to_f64(), g.cos_i().to_f64(), g.cos_o().to_f64());
            let lam = std::f64::consts::TAU / k;
            let var = self.psd.variance().to_f64();
            let log_p = self.psd.log_value(&g.h_t()).to_f64();
            let log_amp = self.psd.log_value(&Vector2::zeros()).to_f64();
            let log_alpha = -(k * (ci + co)).powi(2) * var;
            let log_pre = (std::f64::consts::TAU * (2.0 * k * ci).powi(2) / (lam * lam)).ln();
            let big_e = log_p.abs() + log_amp.abs() + log_alpha.abs() + log_pre.abs();
            let rel = 4.0 * eps * (4.0 + big_e);
            let m00 = material.scatter.m00(&g).to_f64();
            let scale = std::f64::consts::TAU * co / (lam * lam) * m00 * s0_in;
            let abs = tiny * scale * log_amp.exp().max(1.0);
            for c in 0..4 {
                let b = got[c][i].to_f64();
                let d = (b - want[c]).abs();
                let bound = abs + rel * want[0].abs();
                assert!(
                    d <= bound,
                    "{what}: exit {i} {e:?}, S{c}: batch {b:e} vs scalar {:e} (diff {d:e} > {bound:e}; \
                     S0 {:e}, |E| {big_e:.1})",
                    want[c],
                    want[0]
                );
                let d1 = (b - want1[c].to_f64()).abs();
                let bound1 = abs + (rel + 64.0 * eps) * want[0].abs();
                assert!(
                    d1 <= bound1,
                    "{what}: exit {i}, S{c} vs OneShape: {d1:e} > {bound1:e}"
                );
            }
        }
        zeros
    }
}

fn min_positive<T: Real>() -> f64 {
    if T::EPSILON.to_f64() < 1e-10 {
        f64::MIN_POSITIVE
    } else {
        f64::from(f32::MIN_POSITIVE)
    }
}

/// `n` exit directions: half within ~12° of the specular direction, half uniform over the
/// hemisphere (`cos θ_o ≥ 0.002`), each scaled by a factor in [0.1, 10], in world coordinates.
fn exit_set(sc: &Scene, n: usize, seed: u64) -> Vec<Vector3<f64>> {
    let (t1, t2, nn) = surface_axes(sc);
    let mut rng = Lcg(seed);
    (0..n)
        .map(|i| {
            let (cos_o, phi) = if i % 2 == 0 {
                let to = (sc.theta_i + (rng.uniform() - 0.5) * 0.4).abs().min(1.55);
                (to.cos(), sc.phi_i + (rng.uniform() - 0.5) * 0.4)
            } else {
                (
                    0.002 + 0.998 * rng.uniform(),
                    rng.uniform() * std::f64::consts::TAU,
                )
            };
            let sin_o = (1.0 - cos_o * cos_o).sqrt();
            let scale = 0.1 * 100f64.powf(rng.uniform());
            (t1 * (sin_o * phi.cos()) + t2 * (sin_o * phi.sin()) + nn * cos_o) * scale
        })
        .collect()
}

/// The f64 surface axes (t̂₁, t̂₂, n̂) of a scene.
fn surface_axes(sc: &Scene) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let f = Frame::from_direction_and_x(sc.normal, sc.tangent_hint).unwrap();
    (f.x(), f.y(), f.k())
}

fn base_scene() -> Scene {
    Scene {
        theta_i: 0.5,
        phi_i: 0.3,
        normal: Vector3::new(0.1, -0.2, 1.0).normalize(),
        tangent_hint: Vector3::x(),
        psi: 0.4,
        stokes: Vector4::new(1.0, 0.3, -0.4, 0.5),
        eta: Complex::new(1.5, 0.0),
        sigma: 0.01,
        lambda_cov: Matrix2::new(4.0, 0.5, 0.5, 2.0),
        wavelength: 0.5,
        exits: Vec::new(),
    }
}

fn eta_strategy() -> impl Strategy<Value = Complex<f64>> {
    prop_oneof![
        (1.0..3.0f64).prop_map(|n| Complex::new(n, 0.0)),
        (0.05..3.0f64, 0.0..8.0f64).prop_map(|(n, k)| Complex::new(n, k)),
    ]
}

prop_compose! {
    fn scene_strategy()(
        theta_i in 0.0..85f64.to_radians(),
        phi_i in common::angle(),
        normal in common::unit_vector3(),
        psi in common::angle(),
        stokes in common::stokes_vector(),
        eta in eta_strategy(),
        sigma in 0.001..0.05f64,
        lambda_cov in common::spd2(),
        wavelength in 0.3..1.0f64,
        len in 0..5usize,
        seed in any::<u64>(),
    ) -> Scene {
        let hint = if normal.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        let mut sc = Scene {
            theta_i, phi_i, normal, tangent_hint: hint, psi, stokes, eta, sigma,
            lambda_cov, wavelength, exits: Vec::new(),
        };
        let n = [0, 1, 3, 7, 17][len];
        sc.exits = exit_set(&sc, n, seed);
        sc
    }
}

proptest! {
    #![proptest_config(common::proptest_config(96))]

    #[test]
    fn batch_matches_the_per_direction_kernel_f64(sc in scene_strategy()) {
        Built::<f64>::new(&sc).compare("f64");
    }

    #[test]
    fn batch_matches_the_per_direction_kernel_f32(sc in scene_strategy()) {
        Built::<f32>::new(&sc).compare("f32");
    }
}

#[test]
fn a_thousand_exits_match_f64_and_f32() {
    let mut sc = base_scene();
    sc.exits = exit_set(&sc, 1000, 17);
    Built::<f64>::new(&sc).compare("f64, n = 1000");
    Built::<f32>::new(&sc).compare("f32, n = 1000");
    sc.eta = Complex::new(0.2, 3.5); // a metal
    Built::<f64>::new(&sc).compare("f64 metal, n = 1000");
    Built::<f32>::new(&sc).compare("f32 metal, n = 1000");
}

/// Exits exactly along the normal (any length), within √ε of it (the tangent fallback of
/// `Frame::sp`), in the re-orthogonalised band (|r̂ × n̂| < 1/8) and just outside it, at normal
/// and oblique incidence, on a flat and a tilted surface.
#[test]
fn normal_incidence_and_normal_exit() {
    for normal in [Vector3::z(), Vector3::new(0.3, -0.2, 1.0).normalize()] {
        for theta_i in [0.0, 1e-9, 1e-3, 0.5] {
            let mut sc = base_scene();
            sc.normal = normal;
            sc.theta_i = theta_i;
            let (t1, t2, n) = surface_axes(&sc);
            let mut exits = vec![n, n * 3.0, n * 1e-3];
            for off in [1e-12, 1e-9, 1e-7, 1e-4, 1e-2, 0.1, 0.124, 0.126, 0.3] {
                for phi in [0.0_f64, 1.0, 2.5, -2.0] {
                    let d = (t1 * phi.cos() + t2 * phi.sin()) * off;
                    exits.push(n + d);
                }
            }
            // Pad to a length that is not a multiple of the SIMD width.
            exits.push(n);
            sc.exits = exits;
            Built::<f64>::new(&sc).compare("f64 normal");
            Built::<f32>::new(&sc).compare("f32 normal");
        }
    }
}

#[test]
fn grazing_incidence_and_exit() {
    for theta_i in [80f64.to_radians(), 85f64.to_radians(), 89.5f64.to_radians()] {
        let mut sc = base_scene();
        sc.theta_i = theta_i;
        let (t1, t2, n) = surface_axes(&sc);
        sc.exits = (0..23)
            .map(|i| {
                let to = std::f64::consts::FRAC_PI_2 - 1e-4 * (1.0 + f64::from(i * i));
                let phi = 0.3 * f64::from(i);
                t1 * (to.sin() * phi.cos()) + t2 * (to.sin() * phi.sin()) + n * to.cos()
            })
            .collect();
        for eta in [
            Complex::new(1.5, 0.0),
            Complex::new(0.3, 8.0),
            Complex::new(0.5, 0.0),
        ] {
            sc.eta = eta;
            Built::<f64>::new(&sc).compare("f64 grazing");
            Built::<f32>::new(&sc).compare("f32 grazing");
        }
    }
}

/// η = 1 and a smooth surface (σ = 0, `ln p = −∞`) scatter nothing: the per-direction kernel gives
/// exactly 0 and so must the batch.
#[test]
fn index_one_and_smooth_surface_give_zero() {
    let mut sc = base_scene();
    sc.eta = Complex::new(1.0, 0.0);
    sc.exits = exit_set(&sc, 9, 3);
    let mut smooth = sc.clone();
    smooth.eta = Complex::new(1.5, 0.2);
    smooth.sigma = 0.0;
    for sc in [sc, smooth] {
        let got = Built::<f64>::new(&sc).batch().unwrap();
        for s in &got {
            assert!(s.iter().all(|&v| v == 0.0), "{s:?}");
        }
        let got = Built::<f32>::new(&sc).batch().unwrap();
        for s in &got {
            assert!(s.iter().all(|&v| v == 0.0), "{s:?}");
        }
        let b = Built::<f64>::new(&sc);
        let kernel = Kernel::<Full, PlaneWave>::default();
        for &e in &b.exits {
            let g = Geometry::for_packet(&b.packet, &b.surface, e).unwrap();
            let want = kernel.evaluate(&b.material(), &b.packet, &g).scattered;
            assert_eq!(
                want.s0(),
                0.0,
                "the per-direction kernel scatters nothing too"
            );
        }
    }
}

/// A long correlation length (ℓ = 40 µm) makes the PSD underflow to exactly 0 a few degrees off
/// specular: the batch agrees with the per-direction kernel to the smallest normal number there, and
/// both give 0 for most of the hemisphere.
#[test]
fn far_off_specular_underflow() {
    for wavelength in [0.5, 0.2] {
        let mut sc = base_scene();
        sc.lambda_cov = Matrix2::new(1600.0, 0.0, 0.0, 900.0);
        sc.sigma = 0.002;
        sc.wavelength = wavelength;
        sc.exits = exit_set(&sc, 301, 11);
        let z64 = Built::<f64>::new(&sc).compare("f64 underflow");
        let z32 = Built::<f32>::new(&sc).compare("f32 underflow");
        assert!(z64 > 60 && z32 > 60, "zeros: f64 {z64}, f32 {z32} of 301");
        // Exactly zero in the batch where the exponent is far below the underflow threshold.
        let b = Built::<f64>::new(&sc);
        let got = b.batch().unwrap();
        let far = b
            .exits
            .iter()
            .enumerate()
            .filter(|(_, e)| {
                let g = Geometry::for_packet(&b.packet, &b.surface, **e).unwrap();
                b.psd.log_value(&g.h_t()) < -800.0
            })
            .map(|(i, _)| i)
            .collect::<Vec<_>>();
        assert!(far.len() > 50, "{}", far.len());
        for i in far {
            for s in &got {
                assert_eq!(s[i], 0.0, "exit {i}");
            }
        }
    }
}

/// An index so extreme that the scalar `hypot` leaves its fast branch goes through the
/// per-direction kernel: bit for bit its result.
#[test]
fn extreme_index_takes_the_scalar_fallback() {
    let mut sc = base_scene();
    sc.eta = Complex::new(1.5, 1e-20);
    sc.exits = exit_set(&sc, 9, 5);
    let b = Built::<f64>::new(&sc);
    let got = b.batch().unwrap();
    let material = b.material();
    let kernel = Kernel::<Full, PlaneWave>::default();
    for (i, &e) in b.exits.iter().enumerate() {
        let g = Geometry::for_packet(&b.packet, &b.surface, e).unwrap();
        let want = kernel.evaluate(&material, &b.packet, &g).scattered.vector();
        for k in 0..4 {
            assert_eq!(got[k][i], want[k], "exit {i}, S{k}");
        }
    }
    b.compare("f64 extreme index");
}

#[test]
fn strided_and_separate_slices_agree() {
    let mut sc = base_scene();
    sc.exits = exit_set(&sc, 13, 23);
    let b = Built::<f64>::new(&sc);
    let strided = b.batch().unwrap();
    let x: Vec<f64> = b.exits.iter().map(|e| e.x).collect();
    let y: Vec<f64> = b.exits.iter().map(|e| e.y).collect();
    let z: Vec<f64> = b.exits.iter().map(|e| e.z).collect();
    let mut s = [vec![0.0; 13], vec![0.0; 13], vec![0.0; 13], vec![0.0; 13]];
    let [s0, s1, s2, s3] = &mut s;
    let mut out = StokesSoa {
        s: [s0, s1, s2, s3],
    };
    let exits = DirectionsSoa {
        x: &x,
        y: &y,
        z: &z,
    };
    plane_wave_rayleigh_rice(&b.material(), &b.packet, &b.surface, &exits, &mut out).unwrap();
    assert_eq!(s.to_vec(), strided.to_vec());
    // Buffers too short or strides too small are refused.
    let buf = vec![0.0; 30];
    assert!(DirectionsSoa::from_strided(&buf, 11, 10).is_err());
    assert!(DirectionsSoa::from_strided(&buf, 10, 10).is_ok());
    assert!(DirectionsSoa::from_strided(&buf, 10, 11).is_err());
    let mut buf = vec![0.0; 40];
    assert!(StokesSoa::from_strided(&mut buf, 11, 10).is_err());
    assert!(StokesSoa::from_strided(&mut buf, 10, 10).is_ok());
    assert!(StokesSoa::from_strided(&mut buf, 10, 11).is_err());
}

/// Runs the batch on `exits` (separate slices) with the output prefilled with 7.0; returns the
/// result and whether the output is untouched.
fn run_raw(
    b: &Built<f64>,
    x: &[f64],
    y: &[f64],
    z: &[f64],
    out_len: [usize; 4],
) -> (Result<(), Error>, bool) {
    let mut s = out_len.map(|n| vec![7.0; n]);
    let [s0, s1, s2, s3] = &mut s;
    let mut out = StokesSoa {
        s: [s0, s1, s2, s3],
    };
    let exits = DirectionsSoa { x, y, z };
    let r = plane_wave_rayleigh_rice(&b.material(), &b.packet, &b.surface, &exits, &mut out);
    let untouched = s.iter().all(|v| v.iter().all(|&w| w == 7.0));
    (r, untouched)
}

#[test]
fn errors_write_nothing() {
    let mut sc = base_scene();
    sc.normal = Vector3::z();
    let b = Built::<f64>::new(&sc);
    // Valid exits around the specular direction, long enough for whole SIMD vectors.
    let n = 11;
    let x: Vec<f64> = (0..n).map(|i| 0.3 + 0.01 * f64::from(i)).collect();
    let y: Vec<f64> = (0..n).map(|i| 0.1 - 0.02 * f64::from(i)).collect();
    let z: Vec<f64> = vec![0.9; n as usize];
    let n = n as usize;
    let (ok, _) = run_raw(&b, &x, &y, &z, [n; 4]);
    ok.unwrap();
    // Mismatched lengths, in every slice.
    for k in 0..4 {
        let mut lens = [n; 4];
        lens[k] = n - 1;
        let (r, untouched) = run_raw(&b, &x, &y, &z, lens);
        assert!(matches!(r, Err(Error::OutOfRange { .. })), "{r:?}");
        assert!(untouched);
    }
    let (r, untouched) = run_raw(&b, &x, &y[..n - 1], &z, [n; 4]);
    assert!(
        matches!(r, Err(Error::OutOfRange { .. })) && untouched,
        "{r:?}"
    );
    let (r, untouched) = run_raw(&b, &x, &y, &z[..n - 1], [n; 4]);
    assert!(
        matches!(r, Err(Error::OutOfRange { .. })) && untouched,
        "{r:?}"
    );
    // One bad exit, in a whole vector (index 2) and in the remainder (index n − 1).
    for at in [2, n - 1] {
        for (bad, want) in [
            ([0.3, 0.1, -0.9], "out of range"),
            ([0.3, 0.1, 0.0], "out of range"),
            ([1.0, 0.0, -1e-300], "out of range"),
            ([f64::NAN, 0.1, 0.9], "non-finite"),
            ([0.3, f64::INFINITY, 0.9], "non-finite"),
            ([0.0, 0.0, 0.0], "invalid basis"),
        ] {
            let (mut x, mut y, mut z) = (x.clone(), y.clone(), z.clone());
            x[at] = bad[0];
            y[at] = bad[1];
            z[at] = bad[2];
            let (r, untouched) = run_raw(&b, &x, &y, &z, [n; 4]);
            let kind = match r {
                Err(Error::OutOfRange { .. }) => "out of range",
                Err(Error::NonFinite { .. }) => "non-finite",
                Err(Error::InvalidBasis { .. }) => "invalid basis",
                _ => "other",
            };
            assert_eq!(kind, want, "exit {bad:?} at {at}: {r:?}");
            assert!(untouched, "exit {bad:?} at {at}: output was written");
            // The same error as the scalar geometry.
            let scalar = Geometry::for_packet(&b.packet, &b.surface, Vector3::from(bad));
            assert_eq!(r.unwrap_err(), scalar.unwrap_err());
        }
    }
    // Tiny, huge and barely-above-the-surface exits are valid (the exact check decides).
    for good in [
        [1e-300, 0.0, 1e-300],
        [1e300, 1e300, 1e300],
        [1.0, 0.0, 1e-12],
    ] {
        let (mut x, mut y, mut z) = (x.clone(), y.clone(), z.clone());
        x[4] = good[0];
        y[4] = good[1];
        z[4] = good[2];
        let (r, _) = run_raw(&b, &x, &y, &z, [n; 4]);
        r.unwrap();
    }
    // A packet travelling away from the surface.
    let mut away = base_scene();
    away.normal = Vector3::z();
    let b_away = Built::<f64>::new(&away);
    let reversed = WavePacket::from_stokes(
        b_away.packet.stokes(),
        CoherenceShape::isotropic(10.0).unwrap(),
        b_away.packet.frame().reversed(),
        0.5,
    )
    .unwrap();
    let b_rev = Built {
        packet: reversed,
        ..b_away
    };
    let (r, untouched) = run_raw(&b_rev, &x, &y, &z, [n; 4]);
    assert!(
        matches!(r, Err(Error::OutOfRange { .. })) && untouched,
        "{r:?}"
    );
    // Empty batches succeed.
    let (r, _) = run_raw(&b, &[], &[], &[], [0; 4]);
    r.unwrap();
}

/// FNV-1a over the output bits of both batch entry points (`plane_wave_rayleigh_rice` here,
/// `mueller_from_jones_soa` too) in f32 and f64 on a large deterministic set with the edge cases
/// of this file: a refactoring of the batch layer must leave the printed digests unchanged on
/// one machine (run with `cargo test --release --test integration -- --ignored
/// --nocapture batch_output_digest`).
#[test]
#[ignore = "prints a digest to compare before and after a refactoring"]
fn batch_output_digest() {
    use gmueller::mueller::batch::{JonesSoa, MuellerSoa, mueller_from_jones_soa};
    struct Fnv(u64);
    impl Fnv {
        fn eat(&mut self, bits: u64) {
            for b in bits.to_le_bytes() {
                self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x100000001b3);
            }
        }
        fn text(&mut self, s: &str) {
            for b in s.bytes() {
                self.eat(u64::from(b));
            }
        }
    }
    fn pw<T: Real>(h: &mut Fnv) {
        let mut scenes = Vec::new();
        for (theta_i, eta, sigma) in [
            (0.5, Complex::new(1.5, 0.0), 0.01),
            (0.0, Complex::new(1.5, 0.0), 0.01),
            (1e-9, Complex::new(0.2, 3.5), 0.02),
            (1.2, Complex::new(2.0, 0.5), 0.005),
            (89.5f64.to_radians(), Complex::new(0.05, 8.0), 0.01),
            (0.3, Complex::new(1.0, 0.0), 0.01),
            (0.3, Complex::new(1.5, 0.2), 0.0),
            (0.3, Complex::new(1.5, 1e-20), 0.01),
            (0.7, Complex::new(1.3, 0.0), 0.002),
        ] {
            for normal in [Vector3::z(), Vector3::new(0.1, -0.2, 1.0).normalize()] {
                let mut sc = base_scene();
                sc.theta_i = theta_i;
                sc.eta = eta;
                sc.sigma = sigma;
                sc.normal = normal;
                scenes.push(sc);
            }
        }
        for (k, sc) in scenes.iter_mut().enumerate() {
            let n = [0, 1, 3, 7, 8, 9, 15, 16, 17, 33, 1000][k % 11];
            let mut exits = exit_set(sc, n, 100 + k as u64);
            let (t1, _, nn) = surface_axes(sc);
            exits.extend([nn, nn * 3.0, nn * 1e-3, nn + t1 * 1e-9, nn + t1 * 1e-5]);
            exits.extend((0..9).map(|j| nn * 0.01 + t1 * (1.0 + j as f64)));
            exits.extend((0..5).map(|j| nn + t1 * (3.0 + 2.0 * j as f64)));
            sc.exits = exits;
        }
        // Error cases: a non-finite, a zero and a below-the-surface exit.
        let mut bad = Vec::new();
        for e in [
            Vector3::new(f64::NAN, 0.0, 1.0),
            Vector3::zeros(),
            Vector3::new(0.0, 0.3, -1.0),
        ] {
            let mut sc = base_scene();
            sc.exits = exit_set(&sc, 20, 9);
            sc.exits[13] = e;
            bad.push(sc);
        }
        for sc in scenes.iter().chain(&bad) {
            match Built::<T>::new(sc).batch() {
                Ok(out) => {
                    for s in &out {
                        for &v in s {
                            h.eat(v.to_f64().to_bits());
                        }
                    }
                }
                Err(e) => h.text(&format!("{e}")),
            }
        }
    }
    fn mj<T: Real>(h: &mut Fnv) {
        let mut rng = Lcg(0xd1e5);
        for n in (0..42).chain([255, 1000, 1024]) {
            let stride = if n % 2 == 0 { padded_stride::<T>(n) } else { n };
            let mut input = vec![T::zero(); 8 * stride.max(1)];
            for k in 0..8 {
                for i in 0..n {
                    let scale = [1.0, 1e-20, 1e20, 0.0, 3.0][(i + k) % 5];
                    let scale = if n == 1000 { 1.0 } else { scale };
                    input[k * stride + i] = T::lit((rng.uniform() * 4.0 - 2.0) * scale);
                }
            }
            let mut out = vec![T::lit(f64::NAN); 16 * stride.max(1)];
            let j = JonesSoa::from_strided(&input, n, stride).unwrap();
            let mut m = MuellerSoa::from_strided(&mut out, n, stride).unwrap();
            mueller_from_jones_soa(&j, &mut m).unwrap();
            for s in &m.m {
                for &v in s.iter() {
                    h.eat(v.to_f64().to_bits());
                }
            }
        }
    }
    let mut d = [0u64; 4];
    for (slot, f) in d
        .iter_mut()
        .zip([pw::<f64>, pw::<f32>, mj::<f64>, mj::<f32>])
    {
        let mut h = Fnv(0xcbf29ce484222325);
        f(&mut h);
        *slot = h.0;
    }
    println!(
        "digest plane_wave f64 {:016x} f32 {:016x}; mueller f64 {:016x} f32 {:016x}",
        d[0], d[1], d[2], d[3]
    );
}
