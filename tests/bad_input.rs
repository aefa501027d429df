//! Bad input: every validated constructor rejects NaN, ∞, non-SPD shape matrices,
//! zero or parallel basis vectors, non-positive wavelengths, `S0 < |S|` and `|μ| > 1` with an
//! `Error` whose message names the input and the violated condition; and a property test feeds
//! arbitrary finite values (plus ±0 and 1e±300) to every public constructor and function — the
//! PSD constructors and gratings, the Gaussian transforms, CSD/Stokes conversions, the Mueller
//! analysis functions and the importance sampler included — and asserts that nothing panics
//! (each call runs under `catch_unwind`, the failing call is named), that accepted Stokes
//! vectors have finite DoP, Gaussians are never NaN at finite points, Jones-derived coherency
//! eigenvalues are never NaN and every sample has `pdf > 0` above the horizon; interfaces
//! (either side, reflection and transmission) are exercised too.
#![allow(clippy::doc_markdown, reason = "math notation in test docs")]

use crate::common;

use std::panic::{AssertUnwindSafe, catch_unwind};

use gmueller::Error;
use gmueller::frame::{self, Frame};
use gmueller::fresnel;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::coherence::{
    surface_coherence_term, surface_inverse_coherence, volume_coherence_term,
};
use gmueller::interaction::exitant::exitant_packet;
use gmueller::interaction::pbsdf::{
    FresnelInterface, FresnelReflection, IdealDiffuse, PhaseScreen, RayleighRice,
};
use gmueller::interaction::roughness::roughness_attenuation;
use gmueller::interaction::sampling::ScatterSampler;
use gmueller::interaction::{
    Full, Geometry, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave, RoughDielectric,
    RoughSurface, SmoothDielectric,
};
use gmueller::jones::{JonesMatrix, JonesVector};
use gmueller::mueller::{GeneralizedMueller, Mueller};
use gmueller::packet::{Channel, CoherenceShape, WavePacket};
use gmueller::psd::{
    Adaptive, BlurMethod, ClosedForm, GaussHermite, GaussianMixturePsd, GaussianPsd, Grating,
    KCorrelation, OrderCutoff, Psd, Smooth,
};
use gmueller::stokes::{CsdMatrix, GeneralizedStokes, Stokes};
use nalgebra::{Matrix2, Matrix3, Matrix4, Rotation2, Vector2, Vector3, Vector4};
use num_complex::Complex;
use proptest::prelude::*;

fn ident() -> Frame<f64> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}

/// Asserts `r` is an error whose message contains every word of `words`.
#[track_caller]
fn rejects<T: std::fmt::Debug>(what: &str, r: Result<T, Error>, words: &[&str]) {
    match r {
        Ok(v) => panic!("{what}: accepted {v:?}"),
        Err(e) => {
            let msg = e.to_string();
            for w in words {
                assert!(msg.contains(w), "{what}: message {msg:?} lacks {w:?}");
            }
        }
    }
}

const NON_FINITE: [f64; 3] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];

#[test]
fn non_finite_is_rejected_everywhere() {
    let f = ident();
    let one = CoherenceShape::isotropic(1.0).unwrap();
    for x in NON_FINITE {
        let c = Complex::new(x, 0.0);
        rejects(
            "Stokes::new",
            Stokes::new(x, 0.0, 0.0, 0.0),
            &["Stokes", "finite"],
        );
        rejects(
            "Stokes::new s3",
            Stokes::new(1.0, 0.0, 0.0, x),
            &["Stokes", "finite"],
        );
        rejects(
            "Frame::new",
            Frame::new(Vector3::new(x, 0.0, 0.0), Vector3::y(), Vector3::z()),
            &["frame", "finite"],
        );
        rejects(
            "Frame::sp",
            Frame::sp(Vector3::new(0.0, x, -1.0), Vector3::z()),
            &["finite"],
        );
        rejects(
            "Frame::from_direction_and_x",
            Frame::from_direction_and_x(Vector3::z(), Vector3::new(x, 0.0, 0.0)),
            &["finite"],
        );
        rejects(
            "CoherenceShape::new",
            CoherenceShape::new(Matrix2::new(1.0, 0.0, 0.0, x)),
            &["coherence shape", "finite"],
        );
        rejects(
            "CoherenceShape::isotropic",
            CoherenceShape::isotropic(x),
            &["coherence width"],
        );
        rejects(
            "WavePacket::new wavelength",
            WavePacket::new(Stokes::unpolarized(1.0).unwrap(), one, one, f, x),
            &["wavelength"],
        );
        rejects(
            "with_longitudinal_coherence",
            WavePacket::from_stokes(Stokes::unpolarized(1.0).unwrap(), one, f, 0.5)
                .unwrap()
                .with_longitudinal_coherence(x),
            &[],
        );
        rejects(
            "from_distant_disk_source",
            WavePacket::from_distant_disk_source(Stokes::unpolarized(1.0).unwrap(), x, f, 0.5),
            &["solid angle"],
        );
        rejects(
            "from_area_source",
            WavePacket::from_area_source(Stokes::unpolarized(1.0).unwrap(), x, 1.0, f, 0.5),
            &["area"],
        );
        rejects(
            "from_gaussian_source",
            WavePacket::from_gaussian_source(
                Stokes::unpolarized(1.0).unwrap(),
                Matrix2::new(x, 0.0, 0.0, 1.0),
                f,
                0.5,
            ),
            &["finite"],
        );
        rejects(
            "Gaussian::new",
            Gaussian::<f64, 2>::new(Matrix2::new(1.0, 0.0, 0.0, x)),
            &["Gaussian covariance", "finite"],
        );
        rejects(
            "Gaussian::isotropic",
            Gaussian::<f64, 3>::isotropic(x),
            &["standard deviation"],
        );
        rejects(
            "GaussianPsd::isotropic σ",
            GaussianPsd::<f64, 2>::isotropic(x, 1.0),
            &["rms height"],
        );
        rejects(
            "GaussianPsd::isotropic ℓ",
            GaussianPsd::<f64, 2>::isotropic(0.1, x),
            &["correlation length"],
        );
        rejects(
            "KCorrelation::new",
            KCorrelation::<f64, 2>::new(x, 1.0, 2.0),
            &[],
        );
        rejects("Smooth::new", Smooth::new(x), &["specular weight"]);
        rejects("Adaptive::new", Adaptive::new(x), &[]);
        rejects(
            "FresnelReflection::new",
            FresnelReflection::new(c),
            &["finite"],
        );
        rejects(
            "RayleighRice::new",
            RayleighRice::new(Complex::new(1.5, x)),
            &["finite"],
        );
        rejects("PhaseScreen::new", PhaseScreen::new(x), &[]);
        rejects("IdealDiffuse::new", IdealDiffuse::new(x), &[]);
        rejects(
            "fresnel::try_coefficients cos",
            fresnel::try_coefficients(x, Complex::new(1.5, 0.0)),
            &["cos θ_i"],
        );
        rejects(
            "fresnel::try_coefficients η",
            fresnel::try_coefficients(0.5, c),
            &[],
        );
        rejects(
            "JonesVector::new",
            JonesVector::new(c, Complex::new(1.0, 0.0)),
            &["finite"],
        );
        rejects(
            "JonesMatrix::from_matrix",
            JonesMatrix::from_matrix(Matrix2::from_element(c)),
            &["finite"],
        );
        rejects(
            "JonesMatrix::diattenuator",
            JonesMatrix::diattenuator(x, 1.0, 0.0),
            &[],
        );
        rejects(
            "Mueller::from_matrix",
            Mueller::from_matrix(Matrix4::from_element(x)),
            &["finite"],
        );
        rejects(
            "GeneralizedMueller::from_matrix",
            GeneralizedMueller::from_matrix(Matrix4::from_element(c)),
            &["finite"],
        );
        rejects(
            "GeneralizedStokes::new",
            GeneralizedStokes::new(Vector4::from_element(c)),
            &["finite"],
        );
        rejects(
            "CsdMatrix::one_point",
            CsdMatrix::one_point(Matrix2::from_element(c)),
            &["finite"],
        );
        rejects(
            "CsdMatrix::two_point",
            CsdMatrix::two_point(Matrix2::from_element(c)),
            &["finite"],
        );
        rejects(
            "Geometry::new exit",
            Geometry::new(1.0, &f, Vector3::z(), Vector3::new(x, 0.0, 1.0)),
            &["finite"],
        );
        // Also in f32.
        rejects(
            "Stokes::<f32>::new",
            Stokes::new(x as f32, 0.0, 0.0, 0.0),
            &["finite"],
        );
        rejects(
            "Gaussian::<f32>::new",
            Gaussian::<f32, 2>::new(Matrix2::new(1.0, 0.0, 0.0, x as f32)),
            &["finite"],
        );
    }
}

#[test]
fn non_spd_shape_matrices_are_rejected() {
    let f = ident();
    for (m, words) in [
        (
            Matrix2::new(1.0, 0.0, 0.0, -1.0),
            &["positive", "eigenvalue"][..],
        ),
        (
            Matrix2::new(1.0, 2.0, 2.0, 1.0),
            &["positive", "eigenvalue"],
        ),
        (Matrix2::new(0.0, 0.0, 0.0, 0.0), &["positive"]),
        (Matrix2::new(1.0, 1.0, 1.0, 1.0), &["positive"]),
        (Matrix2::new(1.0, 0.5, -0.5, 1.0), &["Hermitian", "A − A†"]),
    ] {
        rejects("CoherenceShape::new", CoherenceShape::new(m), words);
        rejects("Gaussian::new", Gaussian::<f64, 2>::new(m), &[]);
        rejects(
            "from_gaussian_source",
            WavePacket::from_gaussian_source(Stokes::unpolarized(1.0).unwrap(), m, f, 0.5),
            &[],
        );
    }
    rejects(
        "Gaussian 3-D",
        Gaussian::<f64, 3>::new(Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1e-9))),
        &["positive"],
    );
    rejects(
        "CoherenceShape::isotropic 0",
        CoherenceShape::isotropic(0.0),
        &["coherence width", "> 0"],
    );
    rejects(
        "CoherenceShape::isotropic <0",
        CoherenceShape::isotropic(-1.0),
        &["coherence width"],
    );
}

#[test]
fn zero_and_parallel_basis_vectors_are_rejected() {
    let z = Vector3::zeros();
    rejects(
        "Frame::new zero",
        Frame::new(z, Vector3::y(), Vector3::z()),
        &["basis", "zero"],
    );
    rejects(
        "Frame::new parallel",
        Frame::<f64>::new(Vector3::x(), Vector3::x(), Vector3::z()),
        &["basis"],
    );
    rejects(
        "Frame::new left-handed",
        Frame::<f64>::new(Vector3::y(), Vector3::x(), Vector3::z()),
        &["left-handed"],
    );
    rejects(
        "Frame::new not unit",
        Frame::new(Vector3::x() * 2.0, Vector3::y(), Vector3::z()),
        &["unit length"],
    );
    rejects(
        "from_direction_and_x parallel",
        Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::z() * 3.0),
        &["parallel"],
    );
    rejects(
        "from_direction_and_x zero",
        Frame::from_direction_and_x(z, Vector3::x()),
        &["zero"],
    );
    rejects(
        "Frame::sp zero direction",
        Frame::sp(z, Vector3::z()),
        &["zero"],
    );
    rejects(
        "Frame::sp zero normal",
        Frame::sp(Vector3::z(), z),
        &["zero"],
    );
    let f = ident();
    rejects(
        "Geometry zero exit",
        Geometry::new(1.0, &f, Vector3::z(), z),
        &["zero"],
    );
    rejects(
        "Geometry below surface",
        Geometry::new(1.0, &f, Vector3::z(), -Vector3::z()),
        &["cos θ_o"],
    );
    rejects(
        "Geometry source below",
        Geometry::new(1.0, &f, -Vector3::z(), Vector3::z()),
        &["cos θ_i"],
    );
    // Interfaces: either side is fine, the plane of the surface is not.
    let up = Vector3::new(0.2, 0.0, 1.0);
    let along = Vector3::new(1.0, 0.3, 0.0);
    assert!(Geometry::at_interface(1.0, &f, 1.5, -up, up).is_ok());
    rejects(
        "interface source in the plane",
        Geometry::at_interface(1.0, &f, 1.5, along, up),
        &["cos θ_i", "plane"],
    );
    rejects(
        "interface exit in the plane",
        Geometry::at_interface(1.0, &f, 1.5, up, along),
        &["cos θ_o", "plane"],
    );
    rejects(
        "interface zero exit",
        Geometry::at_interface(1.0, &f, 1.5, up, z),
        &["zero"],
    );
}

/// Relative indices of interfaces and the materials built on them: zero, negative, non-finite,
/// or so small or large that `η k` or `k/η` leaves the normal range, are refused with the name
/// of the input.
#[test]
fn interface_indices_are_validated() {
    let f = ident();
    let (up, down) = (Vector3::new(0.2, 0.0, 1.0), Vector3::new(0.1, 0.0, -1.0));
    for eta in [
        0.0,
        -0.0,
        -1.5,
        1e-320,
        f64::NAN,
        f64::INFINITY,
        -f64::INFINITY,
    ] {
        rejects(
            &format!("Geometry::at_interface η = {eta}"),
            Geometry::at_interface(1.0, &f, eta, up, down),
            &["η"],
        );
        rejects(
            &format!("FresnelInterface η = {eta}"),
            FresnelInterface::new(eta),
            &["index"],
        );
        let psd = GaussianPsd::<f64, 2>::isotropic(0.01, 1.0).unwrap();
        assert!(
            RoughDielectric::new(psd, eta).is_err(),
            "RoughDielectric η = {eta}"
        );
        assert!(SmoothDielectric::<f64>::smooth(eta).is_err());
    }
    // η k overflows, or k/η underflows below the normal range.
    rejects(
        "η k overflow",
        Geometry::at_interface(1e300, &f, 1e10, up, down),
        &["η"],
    );
    rejects(
        "k/η subnormal",
        Geometry::at_interface(1e-300, &f, 1e10, up, down),
        &["η"],
    );
    rejects(
        "phase screen negative transmission",
        PhaseScreen::interface(0.5, -1.0),
        &["transmission"],
    );
    rejects(
        "phase screen infinite transmission",
        PhaseScreen::interface(0.5, f64::INFINITY),
        &["transmission"],
    );
}

#[test]
fn non_positive_wavelengths_are_rejected() {
    let f = ident();
    let one = CoherenceShape::isotropic(1.0).unwrap();
    let s = Stokes::unpolarized(1.0).unwrap();
    for w in [0.0, -0.0, -0.5, -1e300, -f64::MIN_POSITIVE] {
        rejects(
            "WavePacket::new",
            WavePacket::new(s, one, one, f, w),
            &["wavelength", "> 0"],
        );
        rejects(
            "from_stokes",
            WavePacket::from_stokes(s, one, f, w),
            &["wavelength"],
        );
        rejects(
            "from_distant_disk_source",
            WavePacket::from_distant_disk_source(s, 1e-4, f, w),
            &["wavelength"],
        );
    }
}

/// Regression (validation gaps): `Geometry::new` accepted a wavenumber `k` that is NaN, ±∞, 0,
/// negative or subnormal (and its fields were public, so every check could be bypassed; they
/// are read through accessors now); a subnormal wavelength gave `k = ∞` and a subnormal `σ_zz`
/// gave `1/σ_zz² = ∞`. Each is now an `OutOfRange` error naming the input, in f32 and f64.
#[test]
fn wavenumbers_and_coherence_lengths_must_be_normal() {
    fn check<T: gmueller::Real>() {
        let f = Frame::<T>::new(
            Vector3::new(T::one(), T::zero(), T::zero()),
            Vector3::new(T::zero(), T::one(), T::zero()),
            Vector3::new(T::zero(), T::zero(), T::one()),
        )
        .unwrap();
        let (up, out) = (
            Vector3::new(T::zero(), T::zero(), T::one()),
            Vector3::new(T::lit(0.3), T::zero(), T::lit(0.9)),
        );
        let sub = T::MIN_POSITIVE * T::lit(0.25);
        for k in [
            T::lit(f64::NAN),
            T::lit(f64::INFINITY),
            T::lit(f64::NEG_INFINITY),
            T::zero(),
            -T::zero(),
            -T::one(),
            sub,
        ] {
            rejects(
                &format!("Geometry::new k = {:e}", k.to_f64()),
                Geometry::new(k, &f, up, out),
                &["wavenumber"],
            );
        }
        assert!(Geometry::new(T::MIN_POSITIVE, &f, up, out).is_ok());
        let s = Stokes::<T>::unpolarized(T::one()).unwrap();
        let w = CoherenceShape::isotropic(T::one()).unwrap();
        for lambda in [sub, T::MIN_POSITIVE] {
            rejects(
                &format!("wavelength {:e}", lambda.to_f64()),
                WavePacket::from_stokes(s, w, f, lambda),
                &["wavelength"],
            );
        }
        let p = WavePacket::from_stokes(s, w, f, T::lit(0.5)).unwrap();
        for sz in [sub, T::MIN_POSITIVE] {
            rejects(
                &format!("σ_zz {:e}", sz.to_f64()),
                p.with_longitudinal_coherence(sz),
                &["longitudinal coherence"],
            );
        }
        // Huge σ_zz: its square overflows, which is unbounded coherence (the limit).
        let huge = p.with_longitudinal_coherence(T::MAX).unwrap();
        assert_eq!(huge.inverse_longitudinal_variance(), T::zero());
    }
    check::<f32>();
    check::<f64>();
}

#[test]
fn overpolarized_stokes_and_mu_above_one_are_rejected() {
    rejects(
        "S0 < |S|",
        Stokes::new(1.0, 0.8, 0.8, 0.0),
        &["S0 = 1", "less than"],
    );
    rejects("S0 < 0", Stokes::new(-1.0, 0.0, 0.0, 0.0), &["S0 = -1"]);
    rejects(
        "f32 S0 < |S|",
        Stokes::new(1.0f32, 0.0, 0.0, 1.001),
        &["less than"],
    );
    // |μ| = |S2 + iS3| / (2√(SxSy)) > 1 can only be built by bypassing Stokes::new; the packet
    // still refuses it (realizability |μ|² ≤ 1 even with equal shapes).
    let f = ident();
    let one = CoherenceShape::isotropic(1.0).unwrap();
    let bad = Stokes::from_vector_unchecked(Vector4::new(1.0, 0.0, 1.5, 0.0)); // |μ| = 1.5
    rejects(
        "WavePacket |μ| > 1",
        WavePacket::new(bad, one, one, f, 0.5),
        &["realizable", "|μ|²"],
    );
    // |μ| ≤ 1 but above the bound for different shapes: 4r/(1+r)² = 0.64 for r = 4.
    let four = CoherenceShape::isotropic(2.0).unwrap();
    let s = Stokes::new(1.0, 0.0, 0.9, 0.0).unwrap(); // |μ|² = 0.81
    rejects(
        "WavePacket |μ|² > bound",
        WavePacket::new(s, one, four, f, 0.5),
        &["realizable"],
    );
    // One-point CSD with |μ| > 1 (not positive semidefinite).
    let z = |r: f64| Complex::new(r, 0.0);
    rejects(
        "CsdMatrix |μ| > 1",
        CsdMatrix::one_point(Matrix2::new(z(1.0), z(2.0), z(2.0), z(1.0))),
        &[],
    );
}

// ------------------------------------------------------------------ no panic, anywhere

/// Arbitrary finite f64 plus the special magnitudes ±0, ±1e±300, ±MIN_POSITIVE, ±MAX.
fn any_finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => any::<f64>().prop_filter("finite", |x| x.is_finite()),
        2 => -10.0..10.0f64,
        1 => prop::sample::select(vec![0.0, -0.0, 1e300, -1e300, 1e-300, -1e-300, f64::MIN_POSITIVE, f64::MAX, -f64::MAX, 1.0, -1.0]),
    ]
}

/// Runs `f`, reporting the name of the call that panicked.
fn no_panic(name: &str, f: impl FnOnce()) -> Result<(), TestCaseError> {
    let r = catch_unwind(AssertUnwindSafe(f));
    prop_assert!(r.is_ok(), "{name} panicked");
    Ok(())
}

/// How many proptest cases reached the kernel (the strategy must get there, or the property
/// says nothing about it).
static KERNEL_CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
/// How many proptest cases built an importance sampler, and a grating.
static SAMPLER_CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
static GRATING_CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
/// How many proptest cases evaluated the kernel at an interface (either side, either exit).
static INTERFACE_CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

fn exercise<T: gmueller::Real>(v: &[f64]) -> Result<(), TestCaseError> {
    let t = |i: usize| T::lit(v[i % v.len()]);
    let v3 = |i: usize| Vector3::new(t(i), t(i + 1), t(i + 2));
    let m2 = |i: usize| Matrix2::new(t(i), t(i + 1), t(i + 2), t(i + 3));
    let c = |i: usize| Complex::new(t(i), t(i + 1));
    let cm2 = |i: usize| Matrix2::new(c(i), c(i + 2), c(i + 4), c(i + 6));

    no_panic("Stokes", || {
        if let Ok(s) = Stokes::new(t(0), t(1), t(2), t(3)) {
            let _ = (
                s.degree_of_polarization(),
                s.degree_of_linear_polarization(),
                s.degree_of_circular_polarization(),
                s.polarized_intensity(),
                s.azimuth(),
                s.ellipticity_angle(),
                s.polarized_part(),
                s.unpolarized_part(),
                s.to_csd().to_stokes(),
                s.to_generalized(),
            );
            // Accepted vectors have finite ratios at every scale.
            assert!(s.degree_of_polarization().is_finite(), "DoP of {s:?}");
            assert!(s.polarized_intensity().is_finite(), "|S| of {s:?}");
        }
        let _ = Stokes::from_vector_unchecked(Vector4::new(t(0), t(1), t(2), t(3)))
            .degree_of_polarization();
    })?;
    no_panic("Frame", || {
        if let Ok(f) = Frame::new(v3(0), v3(3), v3(6)) {
            let _ = f.rotated(t(9));
        }
        if let Ok(f) = Frame::from_direction_and_x(v3(0), v3(3)) {
            let g = f.rotated(t(7));
            let _ = (
                frame::tau(&f, &g),
                frame::frame_change_mueller(&f, &g),
                frame::rotation_angle(&f, &g),
                f.reversed(),
            );
        }
        let _ = Frame::sp(v3(1), v3(4));
        let _ = frame::rotation_mueller(t(2));
    })?;
    no_panic("Jones/Mueller", || {
        let _ = JonesVector::new(c(0), c(2)).map(|j| (j.to_stokes(), j.intensity()));
        let _ = (
            JonesVector::linear(t(0)),
            JonesVector::elliptical(t(1), t(2)),
        );
        if let Ok(j) = JonesMatrix::from_matrix(cm2(0)) {
            let m = Mueller::from_jones(&j);
            if m.matrix().iter().all(|x| x.is_finite()) {
                // Scale-invariant analysis: finite for every finite Jones-derived matrix.
                let l = m.coherency_eigenvalues();
                assert!(
                    l.iter().all(|x| !x.to_f64().is_nan()),
                    "λ(H) = {l:?} of {j:?}"
                );
                assert!(
                    !m.diattenuation().to_f64().is_nan()
                        && !m.depolarization_index().to_f64().is_nan()
                );
            }
            let _ = (
                m.is_physically_realizable(t(3)),
                m.diattenuation(),
                m.polarizance(),
                m.depolarization_index(),
                m.coherency_eigenvalues(),
                m.lu_chipman(),
            );
            let _ = (
                j.inverse(),
                j.determinant(),
                GeneralizedMueller::from_jones_pair(&j, &j),
            );
        }
        let _ = (
            JonesMatrix::linear_retarder(t(0), t(1)),
            JonesMatrix::rotator(t(2)),
            JonesMatrix::diattenuator(t(0), t(1), t(2)),
        );
        if let Ok(m) = Mueller::from_matrix(Matrix4::from_fn(|r, q| t(r * 4 + q))) {
            let _ = (
                m.lu_chipman(),
                m.coherency_eigenvalues(),
                m.is_physically_realizable(t(0)),
                m.depolarization_index(),
                m.diattenuation(),
                m.polarizance(),
            );
        }
    })?;
    no_panic("fresnel", || {
        let _ = fresnel::coefficients(t(0), c(1));
        let _ = fresnel::try_coefficients(t(0), c(1)).map(|f| {
            (
                f.reflectance_s(),
                f.reflectance_p(),
                f.transmittance_s(),
                f.transmittance_p(),
            )
        });
        let _ = (
            fresnel::reflection(t(2), c(3)),
            fresnel::transmission(t(2), c(3)),
        );
    })?;
    no_panic("CSD", || {
        let _ = CsdMatrix::one_point(cm2(0)).map(|m| (m.to_stokes(), m.to_generalized_stokes()));
        let _ = CsdMatrix::two_point(cm2(1)).map(|m| (m.to_generalized_stokes(), m.to_stokes()));
        let _ = JonesVector::new(c(0), c(2)).map(|e| CsdMatrix::from_jones_vector(&e));
        let _ = GeneralizedStokes::new(Vector4::new(c(0), c(2), c(4), c(6)))
            .map(|g| (g.to_csd(), g.to_csd().to_stokes()));
    })?;
    no_panic("Gaussian", || {
        if let Ok(g) = Gaussian::<T, 2>::new(m2(0)) {
            let x = Vector2::new(t(4), t(5));
            let _ = (
                g.value(&x),
                g.log_value(&x),
                g.density(&x),
                g.inverse(),
                g.product(&g),
                g.convolve(&g),
                g.fourier(),
                g.fourier_of_linear_map(&m2(6), &x),
                g.compose_linear(&m2(1)),
            );
            let y = Vector2::new(t(10), t(11));
            let rot = Rotation2::new(t(12));
            let _ = (
                g.mahalanobis_sq(&x),
                g.log_value_of_inverse(&x),
                g.log_fourier_at(&x),
                g.log_density(&x),
                g.product_shifted(&x, &g, &y),
                g.fourier_shifted_modulated(&x, &y, &Vector2::new(t(13), t(14))),
                g.fourier_of_packet_term(&rot, &x, &y),
                g.convolve(&g).map(|s| (s.value(&x), s.log_value(&y))),
            );
            // Never NaN at finite points (0 and −∞ where out of range).
            assert!(
                !g.value(&x).to_f64().is_nan() && !g.log_value(&x).to_f64().is_nan(),
                "g at {x:?}"
            );
        }
        let _ = Gaussian::<T, 3>::isotropic(t(0)).map(|g| (g.section_xy(), g.marginal_xy()));
    })?;
    no_panic("PSD", || {
        let h = Vector2::new(t(3), t(4));
        if let (Ok(p), Ok(cov)) = (
            GaussianPsd::<T, 2>::isotropic(t(0), t(1)),
            Gaussian::<T, 2>::isotropic(t(2)),
        ) {
            let _ = (
                p.value(&h),
                p.log_blur(&cov, &h),
                ClosedForm.blur(&p, &cov, &h),
                ClosedForm.normalized_blur(&p, &cov, &h),
            );
            let _ = GaussHermite::<T>::new(6).map(|gh| gh.normalized_blur(&p, &cov, &h));
        }
        if let Ok(k) = KCorrelation::<T, 2>::new(t(0), t(1), t(2)) {
            let _ = (k.value(&h), k.peak_value(), k.mixture_fit(4));
        }
        let _ = KCorrelation::<T, 2>::from_abc(t(5), t(6), t(7)).map(|k| k.abc());
        let unit = Gaussian::<T, 2>::isotropic(T::one()).unwrap();
        let _ = Smooth::new(t(0)).map(|s| ClosedForm.blur(&s, &unit, &h));
        let _ = GaussianPsd::<T, 2>::from_scatmech(t(8), t(9));
        if let Ok(g) = Gaussian::<T, 2>::new(m2(10)) {
            let a = GaussianPsd::from_autocorrelation(t(14), &g);
            let b = GaussianPsd::from_spectral_shape(t(15), g);
            if let (Ok(a), Ok(b)) = (a, b) {
                let _ = GaussianMixturePsd::new(vec![a, b]).map(|m| m.value(&h));
            }
        }
        let cut = OrderCutoff {
            max_frequency: t(16),
            tail: t(17),
        };
        let dir = Vector2::new(t(18), t(19));
        let gratings = [
            Grating::<T, 2>::sinusoidal(t(20), &dir, t(21), cut),
            Grating::<T, 2>::rectangular(t(20), &dir, t(21), t(22), cut),
        ];
        for g in gratings.iter().flatten() {
            GRATING_CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let _ = (Grating::crossed(g, g, t(23)), Grating::crossed(g, g, t(24)));
            if let Ok(cov) = Gaussian::<T, 2>::isotropic(t(25)) {
                let _ = (
                    ClosedForm.blur(g, &cov, &h),
                    ClosedForm.normalized_blur(g, &cov, &h),
                );
            }
        }
    })?;
    no_panic("sampling", || {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let src = Vector3::new(t(0), t(1), t(2).abs());
        let u = [t(3), t(4)];
        let (k, w) = (t(7).abs(), t(8).abs());
        if let Ok(p) = GaussianPsd::<T, 2>::isotropic(t(5).abs(), t(6).abs())
            && let Ok(s) = ScatterSampler::gaussian(&p, &surface, &src, k, w)
        {
            SAMPLER_CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let d = s.sample(u);
            assert!(
                d.pdf > T::zero() && d.direction.z > T::zero(),
                "sample {d:?}"
            );
            let _ = s.pdf(&v3(9));
        }
        if let Ok(kc) = KCorrelation::<T, 2>::new(t(5).abs(), t(6).abs(), t(10).abs())
            && let Ok(s) = ScatterSampler::k_correlation(&kc, &surface, &src, k, w)
        {
            let d = s.sample(u);
            assert!(
                d.pdf > T::zero() && d.direction.z > T::zero(),
                "sample {d:?}"
            );
        }
    })?;
    no_panic("packet & kernel", || {
        let Ok(frame) = Frame::from_direction_and_x(Vector3::new(t(0), t(1), -t(2).abs()), v3(3))
        else {
            return;
        };
        let Ok(shape) = CoherenceShape::new(Matrix2::new(
            t(6).abs() + t(7).abs(),
            t(7),
            t(7),
            t(8).abs() + t(7).abs(),
        )) else {
            return;
        };
        let s0 = t(10).abs() + t(11).abs() + t(12).abs() + t(13).abs();
        let Ok(stokes) = Stokes::new(s0, t(11), t(12), t(13)) else {
            return;
        };
        let Ok(packet) = WavePacket::from_stokes(stokes, shape, frame, t(14).abs()) else {
            return;
        };
        let _ = (
            packet.rotated(t(15)),
            packet.propagate(t(16)),
            packet.with_longitudinal_coherence(t(17)),
        );
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let Ok(g) =
            Geometry::for_packet(&packet, &surface, Vector3::new(t(18), t(19), t(20).abs()))
        else {
            return;
        };
        let Ok(psd) = GaussianPsd::<T, 2>::isotropic(t(21).abs(), t(22).abs()) else {
            return;
        };
        let eta = Complex::new(t(23).abs(), t(24).abs());
        let (Ok(sp), Ok(sc)) = (FresnelReflection::new(eta), RayleighRice::new(eta)) else {
            return;
        };
        let mat = RoughSurface {
            psd,
            specular: sp,
            scatter: sc,
        };
        KERNEL_CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let _ = Kernel::<Full, Partial>::default().evaluate(&mat, &packet, &g);
        let _ = Kernel::<OneShape, Incoherent>::default().evaluate(&mat, &packet, &g);
        let _ = Kernel::<Intensity, PlaneWave>::default().evaluate(&mat, &packet, &g);
        let _ = (
            roughness_attenuation(&mat.psd, &g),
            surface_inverse_coherence(&packet, Channel::X, &surface),
            g.exit_azimuth(),
        );
        let _ = surface_coherence_term(
            &mat.psd,
            &ClosedForm,
            &packet,
            Channel::Half,
            &surface,
            &g.h_t(),
        );
        let _ = exitant_packet(&packet, &g, stokes);
        // The same packet at an interface, the exit on either side.
        if let (Ok(glass), Ok(gi)) = (
            RoughDielectric::new(mat.psd, t(26).abs()),
            Geometry::for_packet_at_interface(
                &packet,
                &surface.facing(&-packet.direction()),
                t(26).abs(),
                v3(27),
            ),
        ) {
            INTERFACE_CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let _ = Kernel::<Full, Partial>::default().evaluate(&glass, &packet, &gi);
            let _ = Kernel::<OneShape, Incoherent>::default().evaluate(&glass, &packet, &gi);
            let _ = Kernel::<Intensity, PlaneWave>::default().evaluate(&glass, &packet, &gi);
            let _ = (
                gi.specular_direction(),
                gi.specular_sp(),
                gi.phase_factor(),
                exitant_packet(&packet, &gi, stokes),
            );
        }
        if let (Ok(p3), Ok(pk)) = (
            GaussianPsd::<T, 3>::isotropic(t(21), t(22)),
            packet.with_longitudinal_coherence(t(25)),
        ) {
            let _ = volume_coherence_term(&p3, &ClosedForm, &pk, Channel::Y, &v3(26));
        }
    })?;
    Ok(())
}

proptest! {
    #![proptest_config(common::proptest_config(512))]

    /// Arbitrary finite values into every public constructor and function: no panic
    /// (Result-returning constructors return `Err` or `Ok`; infallible functions return).
    #[test]
    fn nothing_panics_on_finite_input(v in prop::collection::vec(any_finite(), 32)) {
        exercise::<f64>(&v)?;
        exercise::<f32>(&v)?;
    }
}

/// Same, on moderate values (|x| ≤ 10 and the special magnitudes), where the kernel is
/// actually reached; asserts that it was, in at least 5 % of 512 cases (and that samplers and
/// gratings were built as often).
#[test]
fn nothing_panics_and_kernel_is_reached() {
    let mut runner = proptest::test_runner::TestRunner::new(common::proptest_config(512));
    let strat = prop::collection::vec(
        prop_oneof![8 => -10.0..10.0f64, 1 => prop::sample::select(vec![0.0, -0.0, 1e-300, 1e300, -1e300])],
        32,
    );
    let before = KERNEL_CALLS.load(std::sync::atomic::Ordering::Relaxed);
    let (s0, g0, i0) = (
        SAMPLER_CALLS.load(std::sync::atomic::Ordering::Relaxed),
        GRATING_CALLS.load(std::sync::atomic::Ordering::Relaxed),
        INTERFACE_CALLS.load(std::sync::atomic::Ordering::Relaxed),
    );
    runner
        .run(&strat, |v| {
            exercise::<f64>(&v)?;
            exercise::<f32>(&v)
        })
        .unwrap();
    let reached = KERNEL_CALLS.load(std::sync::atomic::Ordering::Relaxed) - before;
    assert!(reached >= 50, "kernel reached only {reached} times");
    let samplers = SAMPLER_CALLS.load(std::sync::atomic::Ordering::Relaxed) - s0;
    let gratings = GRATING_CALLS.load(std::sync::atomic::Ordering::Relaxed) - g0;
    assert!(samplers >= 50, "a sampler was built only {samplers} times");
    assert!(gratings >= 50, "a grating was built only {gratings} times");
    let interfaces = INTERFACE_CALLS.load(std::sync::atomic::Ordering::Relaxed) - i0;
    assert!(
        interfaces >= 50,
        "an interface was evaluated only {interfaces} times"
    );
}
