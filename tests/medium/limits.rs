//! The medium at its limits, in f32 and f64: continuity across the forward/backward frame switch
//! seen in a fixed frame; the limits of the coherence levels and unbounded `σ_zz`; bad exit
//! directions; extreme anisotropy and scales; a medium that does not scatter and a dark packet.

use crate::common;

use common::medium::{gaussian, simple, turned};
use common::{Tol, assert_close};
use gmueller::Real;
use gmueller::frame::{Frame, stokes_to_frame};
use gmueller::interaction::polarization::{PolarizationModel, Throughput};
use gmueller::interaction::{Full, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave};
use gmueller::medium::{Dipole, PhaseFunction, RandomMedium, Scalar, VolumeCoherence};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::verify::check::assert_valid_stokes;
use nalgebra::{Matrix2, Matrix3, Vector3, Vector4};

/// Across the forward and backward frame switch (`|d̂ × r̂| = √ε`) the scattered light, seen in
/// a frame that does not switch, is continuous: within `50 θ²` (the `O(θ²)` change of the dipole
/// matrix and of the lobe) plus 1e-12 (f64) or `2e-6 (1 + m)` (f32, `m = 2(kℓ)²` the lobe's
/// exponent at backscatter: an f32 direction moves the exponent by `ε₃₂ m`) of the exact
/// forward or backward value, for the dipole and the scalar scatterer.
#[test]
fn forward_and_backward_are_continuous() {
    fn run<T: Real, M: gmueller::medium::Scatterer<T>>(
        scatterer: M,
        angles: &[f64],
        f32_like: bool,
    ) {
        let ell = 0.4;
        let m = RandomMedium::new(
            GaussianPsd::<T, 3>::isotropic(T::lit(2e-3), T::lit(ell)).unwrap(),
            scatterer,
        );
        let p = simple::<T>(
            [1.0, 0.5, 0.3, -0.6],
            Matrix2::new(4.0, 0.0, 0.0, 4.0),
            Some(2.0),
            0.5,
        );
        let k = p.wavenumber().to_f64();
        let tol = if f32_like {
            2e-6 * (1.0 + 2.0 * (k * ell).powi(2))
        } else {
            1e-12
        };
        let phase = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
        let inc = phase.prepare(&p).unwrap();
        let d = p.frame().k().map(|x| x.to_f64());
        let x = p.frame().x().map(|x| x.to_f64());
        for sign in [1.0, -1.0] {
            let fixed = |r: &Vector3<f64>| {
                Frame::<T>::from_direction_and_x(r.map(T::lit), x.map(T::lit)).unwrap()
            };
            let at = |r: Vector3<f64>| {
                let v = phase.differential_scattering(&inc, r.map(T::lit)).unwrap();
                stokes_to_frame(
                    &Stokes::from_vector_unchecked(v.light.vector()),
                    v.geometry.exit_frame(),
                    &fixed(&r),
                )
                .vector()
                .map(|x| x.to_f64())
            };
            let exact = at(d * sign);
            for &t in angles {
                for phi in [0.0, 1.1, 2.5, 4.0] {
                    let r = turned(&(d * sign), t, phi);
                    let v = at(r);
                    let dev = (v - exact).amax() / exact[0];
                    let allowed = tol + 50.0 * t * t;
                    assert!(
                        dev <= allowed,
                        "{} θ = {t:e} φ = {phi}: {dev:e} > {allowed:e}",
                        if sign > 0.0 { "forward" } else { "backward" }
                    );
                }
            }
        }
    }
    run::<f64, _>(Dipole, &[1e-12, 1e-9, 1.4e-8, 1.6e-8, 1e-7, 1e-5], false);
    run::<f64, _>(Scalar, &[1e-12, 1.4e-8, 1.6e-8, 1e-5], false);
    run::<f32, _>(Dipole, &[1e-5, 3.4e-4, 3.6e-4, 1e-3], true);
}

/// The limits of the coherence levels: `Partial` → `PlaneWave` as the coherence grows (w and
/// `σ_zz` 1e4 ℓ: within 1e-6), → `Incoherent` as it shrinks (1e-3 ℓ: within 1e-5); `Full` on a
/// single-shape packet is `OneShape` exactly; `Partial` with unbounded `σ_zz` is its limit
/// (`σ_zz = 1e8 ℓ` within 1e-9), `Incoherent` with unbounded `σ_zz` is refused.
#[test]
fn coherence_level_limits() {
    let ell = 0.5;
    let m = gaussian::<f64>(ell);
    let st = [1.0, 0.3, 0.1, -0.2];
    let r0 = Vector3::new(0.2, -0.3, 0.93).normalize();
    let exits: Vec<Vector3<f64>> = [0.0, 0.05, 0.4, 1.3, 2.9]
        .iter()
        .map(|&t| turned(&r0, t, 0.6))
        .collect();
    let s0 = |pk: &WavePacket<f64>, r: &Vector3<f64>, partial: bool| -> Vector4<f64> {
        if partial {
            m.differential_scattering(&Kernel::<Full, Partial>::default(), pk, *r)
                .unwrap()
                .light
                .vector()
        } else {
            m.differential_scattering(&Kernel::<Full, PlaneWave>::default(), pk, *r)
                .unwrap()
                .light
                .vector()
        }
    };
    let wide = simple::<f64>(
        st,
        Matrix2::identity() * (1e4 * ell).powi(2),
        Some(1e4 * ell),
        0.5,
    );
    for r in &exits {
        let (a, b) = (s0(&wide, r, true), s0(&wide, r, false));
        assert!(
            (a - b).amax() <= 1e-6 * b[0],
            "Partial → PlaneWave at {r:?}: {a:?} vs {b:?}"
        );
    }
    let narrow = simple::<f64>(
        st,
        Matrix2::identity() * (1e-3 * ell).powi(2),
        Some(1e-3 * ell),
        0.5,
    );
    for r in &exits {
        let a = s0(&narrow, r, true);
        let b = m
            .differential_scattering(&Kernel::<Full, Incoherent>::default(), &narrow, *r)
            .unwrap()
            .light
            .vector();
        assert!(
            (a - b).amax() <= 1e-5 * b[0],
            "Partial → Incoherent at {r:?}: {a:?} vs {b:?}"
        );
    }
    let p = simple::<f64>(st, Matrix2::new(3.0, 1.0, 1.0, 2.0), Some(1.5), 0.5);
    for r in &exits {
        let full = m
            .differential_scattering(&Kernel::<Full, Partial>::default(), &p, *r)
            .unwrap()
            .light;
        let one = m
            .differential_scattering(&Kernel::<OneShape, Partial>::default(), &p, *r)
            .unwrap()
            .light;
        assert_eq!(full, one);
    }
    let unbounded = simple::<f64>(st, Matrix2::new(3.0, 1.0, 1.0, 2.0), None, 0.5);
    let long = simple::<f64>(st, Matrix2::new(3.0, 1.0, 1.0, 2.0), Some(1e8 * ell), 0.5);
    for r in &exits {
        let (a, b) = (s0(&unbounded, r, true), s0(&long, r, true));
        assert!(
            (a - b).amax() <= 1e-9 * b[0],
            "σ_zz = ∞ vs 1e8 ℓ at {r:?}: {a:?} vs {b:?}"
        );
    }
    let refused = m.differential_scattering(&Kernel::<Full, Incoherent>::default(), &unbounded, r0);
    assert!(
        matches!(refused, Err(gmueller::Error::Singular { .. })),
        "{refused:?}"
    );
    let phase = PhaseFunction::new(&m, Kernel::<Full, Incoherent>::default());
    assert!(phase.prepare(&unbounded).is_err());
}

/// Bad exit directions are errors, never NaN or a panic; huge and tiny finite ones are fine.
#[test]
fn bad_exit_directions() {
    let m = gaussian::<f64>(0.5);
    let p = simple::<f64>(
        [1.0, 0.0, 0.0, 0.0],
        Matrix2::identity() * 4.0,
        Some(2.0),
        0.5,
    );
    let phase = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
    let inc = phase.prepare(&p).unwrap();
    for bad in [
        Vector3::zeros(),
        Vector3::new(f64::NAN, 0.0, 1.0),
        Vector3::new(0.0, f64::INFINITY, 0.0),
    ] {
        assert!(phase.eval(&inc, bad).is_err());
        assert!(phase.differential_scattering(&inc, bad).is_err());
        assert!(
            m.differential_scattering(&Kernel::<Full, Partial>::default(), &p, bad)
                .is_err()
        );
    }
    for s in [1e-300, 1e300, f64::MAX, f64::MIN_POSITIVE * f64::EPSILON] {
        let v = phase.eval(&inc, Vector3::new(s, -s, s)).unwrap();
        assert!(v.phase.is_finite());
        assert!(phase.pdf(&inc, &v.geometry.exit_direction()).is_finite());
    }
}

/// Extreme anisotropy and scales: transverse coherence widths with a ratio up to 1e3 (1e6 in
/// `Θ⊥`), turned; `σ_zz` from 1e-3 to 1e6 λ; Gaussian media with ℓ from 1e-3 to 1e3 λ and a
/// correlation anisotropy of 100. Every level and precision either prepares and returns
/// finite, valid outputs with a finite `σ_s ≥ 0` and a finite positive pdf, or refuses the packet
/// with an error — never a panic or a NaN.
#[test]
fn extreme_anisotropy_and_scales() {
    fn run<T: Real>(tol: f64) -> (usize, usize) {
        let (mut ok, mut refused) = (0, 0);
        let lambda = 0.5;
        for &ratio in &[1e-3, 1.0, 1e3] {
            for &zz in &[1e-3, 1.0, 1e6] {
                for &ell in &[1e-3, 1.0, 1e3] {
                    let w = 3.0_f64;
                    let rot = |a: f64| Matrix2::new(a.cos(), -a.sin(), a.sin(), a.cos());
                    let r = rot(0.4);
                    let shape = r
                        * Matrix2::new(w * w, 0.0, 0.0, (w * ratio).powi(2))
                        * r.transpose()
                        * (lambda * lambda);
                    let shape = (shape + shape.transpose()) * 0.5;
                    let Ok(cs) = CoherenceShape::new(shape.map(T::lit)) else {
                        refused += 1;
                        continue;
                    };
                    let f = Frame::from_direction_and_x(
                        Vector3::new(0.2, -0.3, 0.93).map(T::lit),
                        Vector3::new(1.0, 0.1, 0.0).map(T::lit),
                    )
                    .unwrap();
                    let Ok(p) = WavePacket::from_stokes(
                        Stokes::new(T::one(), T::lit(0.3), T::lit(-0.4), T::lit(0.5)).unwrap(),
                        cs,
                        f,
                        T::lit(lambda),
                    )
                    .and_then(|p| p.with_longitudinal_coherence(T::lit(zz * lambda))) else {
                        refused += 1;
                        continue;
                    };
                    let l = ell * lambda;
                    let cov = Matrix3::new(
                        l * l,
                        0.0,
                        0.0,
                        0.0,
                        1e-4 * l * l,
                        0.0,
                        0.0,
                        0.0,
                        0.3 * l * l,
                    );
                    let Ok(corr) = gmueller::gaussian::Gaussian::new(cov.map(T::lit)) else {
                        refused += 1;
                        continue;
                    };
                    let Ok(psd) = GaussianPsd::from_autocorrelation(T::lit(1e-6), &corr) else {
                        refused += 1;
                        continue;
                    };
                    let m = RandomMedium::new(psd, Dipole);
                    let d = p.frame().k().map(|x| x.to_f64());
                    for t in [0.0, 1e-3, 0.5, 2.0, std::f64::consts::PI] {
                        let r = turned(&d, t, 0.3).map(T::lit);
                        for outcome in [
                            probe(&m, Kernel::<Full, Partial>::default(), &p, r, tol),
                            probe(&m, Kernel::<Full, Incoherent>::default(), &p, r, tol),
                            probe(&m, Kernel::<Intensity, PlaneWave>::default(), &p, r, tol),
                        ] {
                            if outcome { ok += 1 } else { refused += 1 }
                        }
                    }
                }
            }
        }
        (ok, refused)
    }
    let (ok64, no64) = run::<f64>(1e-12);
    let (ok32, no32) = run::<f32>(2e-6);
    println!("f64: {ok64} evaluated, {no64} refused; f32: {ok32} evaluated, {no32} refused");
    assert!(ok64 > 0 && ok32 > 0);
}

/// One level at one exit: `true` if it prepared and every output is finite and valid, `false`
/// if it refused the packet with an error (a NaN or an invalid output fails the test).
fn probe<T, P, Pol, Coh>(
    m: &RandomMedium<P, Dipole>,
    kernel: Kernel<Pol, Coh>,
    p: &WavePacket<T>,
    r: Vector3<T>,
    tol: f64,
) -> bool
where
    T: Real,
    P: gmueller::psd::Psd<T, 3>,
    Pol: PolarizationModel,
    Coh: VolumeCoherence<T, P>,
{
    let phase = PhaseFunction::new(m, kernel);
    let inc = match phase.prepare(p) {
        Ok(i) => i,
        Err(e) => {
            println!(
                "refused: {e} (Θ⊥ {:?}, 1/σ_zz² {:?})",
                p.shape(gmueller::packet::Channel::X),
                p.inverse_longitudinal_variance()
            );
            return false;
        }
    };
    let sigma = inc.scattering_coefficient();
    assert!(sigma.is_finite() && sigma >= T::zero(), "σ_s = {sigma:?}");
    let f = phase.eval(&inc, r).unwrap().phase;
    assert!(f.is_finite());
    let d = phase.differential_scattering(&inc, r).unwrap().light;
    let light = <Pol::Throughput<T> as Throughput<T>>::light_stokes(&d).map_or_else(
        || {
            Vector4::new(
                <Pol::Throughput<T> as Throughput<T>>::intensity(&d),
                T::zero(),
                T::zero(),
                T::zero(),
            )
        },
        |s| s.vector(),
    );
    assert_valid_stokes("dI/dV", light.map(|x| x.to_f64()), Tol::new(0.0, tol));
    let pdf = phase.pdf(&inc, &r);
    assert!(pdf.is_finite() && pdf > T::zero(), "pdf {pdf:?}");
    let s = phase.sample(&inc, T::lit(0.6), [T::lit(0.2), T::lit(0.9)]);
    assert!(s.pdf.is_finite() && s.pdf > T::zero() && s.weight.is_finite());
    true
}

/// A medium that does not scatter (`δε = 0`): `σ_s = 0`, `F = 0`, `dI/dV = 0`, sample weights
/// and `weight · S` 0, and the sampler still draws with a finite positive pdf; a dark packet
/// (`S0 = 0`) scatters nothing but has the phase matrix and `σ_s` of unpolarized light of its
/// coherence.
#[test]
fn silent_medium_and_dark_packet() {
    let silent = RandomMedium::new(GaussianPsd::<f64, 3>::isotropic(0.0, 0.5).unwrap(), Dipole);
    let p = simple::<f64>(
        [1.0, 0.2, 0.0, 0.1],
        Matrix2::identity() * 4.0,
        Some(2.0),
        0.5,
    );
    let phase = PhaseFunction::new(&silent, Kernel::<Full, Partial>::default());
    let inc = phase.prepare(&p).unwrap();
    assert_eq!(inc.scattering_coefficient(), 0.0);
    let r = Vector3::new(0.3, 0.1, 0.9);
    assert_eq!(
        phase.eval(&inc, r).unwrap().phase.matrix(),
        nalgebra::Matrix4::zeros()
    );
    assert_eq!(
        phase.differential_scattering(&inc, r).unwrap().light.s0(),
        0.0
    );
    let s = phase.sample(&inc, 0.5, [0.5, 0.5]);
    assert!(s.pdf.is_finite() && s.pdf > 0.0);
    assert_eq!(s.weight.matrix(), nalgebra::Matrix4::zeros(), "zero weight");
    assert_eq!(s.apply(&p.stokes()).vector(), Vector4::zeros());

    let m = gaussian::<f64>(0.5);
    let phase = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
    let dark = simple::<f64>(
        [0.0, 0.0, 0.0, 0.0],
        Matrix2::identity() * 4.0,
        Some(2.0),
        0.5,
    );
    let lit = simple::<f64>(
        [1.0, 0.0, 0.0, 0.0],
        Matrix2::identity() * 4.0,
        Some(2.0),
        0.5,
    );
    let (a, b) = (phase.prepare(&dark).unwrap(), phase.prepare(&lit).unwrap());
    assert_close(
        "σ_s",
        a.scattering_coefficient(),
        b.scattering_coefficient(),
        Tol::new(0.0, 1e-14),
    );
    assert_eq!(
        phase.differential_scattering(&a, r).unwrap().light.s0(),
        0.0
    );
    let (fa, fb) = (
        phase.eval(&a, r).unwrap().phase.matrix(),
        phase.eval(&b, r).unwrap().phase.matrix(),
    );
    assert!((fa - fb).amax() <= 1e-14 * fb.amax());
}

/// A medium's permittivity has a continuous PSD: one whose form is zero or Dirac (`Smooth` of
/// zero or positive weight) is refused by `prepare` with `Error::Unrealizable`, in both
/// precisions, not prepared into a phase function of NaN.
#[test]
fn zero_or_dirac_psd_is_refused() {
    fn run<T: Real>() {
        let p = simple::<T>([1.0, 0.2, 0.0, 0.1], Matrix2::identity() * 9.0, None, 0.6);
        for weight in [0.0, 1e-6] {
            let m = RandomMedium::new(
                gmueller::psd::Smooth::<T>::new(T::lit(weight)).unwrap(),
                Dipole,
            );
            let got = PhaseFunction::new(&m, Kernel::<Full, PlaneWave>::default()).prepare(&p);
            assert!(
                matches!(got, Err(gmueller::Error::Unrealizable { .. })),
                "weight {weight}: {got:?}"
            );
        }
    }
    run::<f32>();
    run::<f64>();
}
