//! Fresnel coefficients: Mitsuba 3 reference Mueller matrices (after the `D M D` conversion),
//! Brewster extinction, normal incidence, energy conservation `R + T = 1` (dielectrics incl. total
//! internal reflection, and absorbing media), the TIR phase against the textbook half-angle
//! formulas, s-light reflecting with `R_s` through the Mueller route, conductors, validation.
//! Laws run in f64 and f32.

use crate::common;

use common::{flip_s3, json_rows as rows, peer_cases as cases};

use common::{F32, F64, Tol, assert_all_close, assert_close, entries4, matrix4_from_rows};
use gmueller::error::Error;
use gmueller::fresnel::{coefficients, reflection, transmission, try_coefficients};
use gmueller::mueller::Mueller;
use gmueller::real::Real;
use gmueller::stokes::Stokes;
use nalgebra::{Matrix4, Vector4};
use num_complex::Complex;
use proptest::prelude::*;

// ------------------------------------------------------------------ helpers (this file only)

fn tol<T: Real>() -> Tol {
    if T::EPSILON.to_f64() > 1e-10 {
        F32
    } else {
        F64
    }
}

fn cz<T: Real>(re: f64, im: f64) -> Complex<T> {
    Complex::new(T::lit(re), T::lit(im))
}

fn c64<T: Real>(z: Complex<T>) -> Complex<f64> {
    Complex::new(z.re.to_f64(), z.im.to_f64())
}

fn m64<T: Real>(m: &Mueller<T>) -> Matrix4<f64> {
    m.matrix().map(Real::to_f64)
}

/// Textbook Fresnel amplitudes written independently with real angles (Hecht, *Optics*, §4.6.2,
/// eqs. 4.34, 4.40, with our `r_p` sign = Born & Wolf's `r_∥`): for a real index and no TIR.
fn textbook_real(theta_i: f64, n: f64) -> (f64, f64, f64, f64) {
    let theta_t = (theta_i.sin() / n).asin();
    let ci = theta_i.cos();
    let rs = -(theta_i - theta_t).sin() / (theta_i + theta_t).sin();
    let rp = (theta_i - theta_t).tan() / (theta_i + theta_t).tan();
    let ts = 2.0 * theta_t.sin() * ci / (theta_i + theta_t).sin();
    let tp = 2.0 * theta_t.sin() * ci / ((theta_i + theta_t).sin() * (theta_i - theta_t).cos());
    (rs, rp, ts, tp)
}

// ------------------------------------------------------------------ external anchor

/// Mitsuba 3.9.1 `specular_reflection(cos θ_i, η)` with Stokes x axis = s; Mitsuba uses
/// `e^{+iωt}` (η = n − iκ internally), so ours is `D M D`, `D = diag(1, 1, 1, −1)`.
#[test]
fn fresnel_reflection_matches_mitsuba_after_s3_flip() {
    for case in cases("fresnel_reflection") {
        let theta_i = case["theta_i"].as_f64().unwrap();
        let eta = Complex::new(
            case["eta_re"].as_f64().unwrap(),
            case["eta_im"].as_f64().unwrap(),
        );
        let want = flip_s3(matrix4_from_rows(&rows(&case["mueller"])));
        let t = case["tol"].as_f64().unwrap();
        let got = m64(&Mueller::from_jones(&reflection(theta_i.cos(), eta)));
        assert_all_close(
            "Mitsuba specular_reflection (f64)",
            entries4(&got),
            entries4(&want),
            Tol::new(t, t),
        );
        let eta32 = Complex::new(eta.re as f32, eta.im as f32);
        let got = m64(&Mueller::from_jones(&reflection(
            theta_i.cos() as f32,
            eta32,
        )));
        assert_all_close(
            "Mitsuba specular_reflection (f32)",
            entries4(&got),
            entries4(&want),
            Tol::new(t.max(F32.abs), t.max(F32.rel)),
        );
    }
}

// ------------------------------------------------------------------ laws, generic over T

fn normal_incidence<T: Real>(n: f64, k: f64) {
    let f = coefficients(T::one(), cz::<T>(n, k));
    let eta = Complex::new(n, k);
    let rs = (1.0 - eta) / (1.0 + eta);
    let t = tol::<T>();
    common::assert_complex_close("r_s = (1−η)/(1+η)", [c64(f.rs)], [rs], t);
    // Our r_p sign (Born & Wolf's r_∥): r_p = −r_s at normal incidence, i.e. a mirror.
    common::assert_complex_close("r_p = (η−1)/(η+1)", [c64(f.rp)], [-rs], t);
    let m = m64(&Mueller::from_jones(&reflection(T::one(), cz::<T>(n, k))));
    let r = rs.norm_sqr();
    let mirror = Matrix4::from_diagonal(&Vector4::new(r, r, -r, -r));
    assert_all_close("mirror Mueller", entries4(&m), entries4(&mirror), t);
}

fn brewster<T: Real>(n: f64) -> f64 {
    // tan θ_B = n.
    let cos_b = 1.0 / (1.0 + n * n).sqrt();
    let f = coefficients(T::lit(cos_b), cz::<T>(n, 0.0));
    f.rp.norm_sqr().sqrt().to_f64()
}

fn lossless_dielectric<T: Real>(theta_i: f64, n: f64) {
    let t = tol::<T>();
    let c = T::lit(theta_i.cos());
    let f = coefficients(c, cz::<T>(n, 0.0));
    let (rs, rp) = (f.reflectance_s().to_f64(), f.reflectance_p().to_f64());
    let (ts, tp) = (f.transmittance_s().to_f64(), f.transmittance_p().to_f64());
    assert_close("R_s + T_s", rs + ts, 1.0, t);
    assert_close("R_p + T_p", rp + tp, 1.0, t);
    // Through the Jones matrices and Mueller M00 (unpolarized light).
    let mr = m64(&Mueller::from_jones(&reflection(c, cz::<T>(n, 0.0))));
    let mt = m64(&Mueller::from_jones(&transmission(c, cz::<T>(n, 0.0))));
    assert_close("M00(r) + M00(t)", mr[(0, 0)] + mt[(0, 0)], 1.0, t);
    // The inputs the T computation actually sees.
    let ci = T::lit(theta_i.cos()).to_f64();
    let n = T::lit(n).to_f64();
    let sin_i = (1.0 - ci * ci).sqrt();
    if sin_i > n {
        // Total internal reflection: |r| = 1, nothing transmitted.
        assert_close("TIR R_s", rs, 1.0, t);
        assert_close("TIR R_p", rp, 1.0, t);
        assert_close("TIR T_s", ts, 0.0, t);
        assert_close("TIR T_p", tp, 0.0, t);
        // Decaying transmitted wave: Im(η cos θ_t) ≥ 0 (e^{+i k z}).
        let q = c64(f.cos_theta_t) * n;
        assert!(q.im >= 0.0 && q.re.abs() <= 1e-6, "η cos θ_t = {q}");
        // Phases vs the textbook half-angle formulas (Born & Wolf §1.5.4, eq. 60), with the
        // sign that e^{−iωt} gives here: tan(δ_s/2) = −√(sin²θ − n²)/cos θ,
        // tan(δ_p/2) = −√(sin²θ − n²)/(n² cos θ).
        let root = (sin_i * sin_i - n * n).sqrt();
        let ds = -2.0 * root.atan2(ci);
        let dp = -2.0 * root.atan2(n * n * ci);
        let ph = |z: Complex<T>| c64(z).arg();
        let wrap = |a: f64| {
            (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
        };
        // Conditioning: sin²θ − n² carries an absolute rounding error of a few ε, so the phases
        // (functions of its root) carry ≈ ε/(sin²θ − n²) near the critical angle.
        let eps = T::EPSILON.to_f64();
        let pt = Tol::new(t.abs * 10.0 + 8.0 * eps / (root * root), 0.0);
        assert_close("TIR phase δ_s", wrap(ph(f.rs) - ds), 0.0, pt);
        assert_close("TIR phase δ_p", wrap(ph(f.rp) - dp), 0.0, pt);
        // Relative phase, Born & Wolf eq. 61: tan(δ/2) = cos θ √(sin²θ − n²)/sin²θ, δ = δ_s − δ_p.
        let rel = 2.0 * (ci * root).atan2(sin_i * sin_i);
        assert_close(
            "TIR relative phase",
            wrap(ph(f.rs) - ph(f.rp) - rel),
            0.0,
            pt,
        );
    } else if sin_i < n * 0.95 && ci < 1.0 - 1e-6 {
        // Away from the critical angle (ill-conditioned there) and from normal incidence (the
        // real-angle forms are 0/0 there): the textbook forms.
        let (trs, trp, tts, ttp) = textbook_real(ci.acos(), n);
        let g = |z: Complex<T>| c64(z);
        let tl = Tol::new(t.abs * 10.0, t.rel * 10.0);
        common::assert_complex_close("r_s textbook", [g(f.rs)], [Complex::new(trs, 0.0)], tl);
        common::assert_complex_close("r_p textbook", [g(f.rp)], [Complex::new(trp, 0.0)], tl);
        common::assert_complex_close("t_s textbook", [g(f.ts)], [Complex::new(tts, 0.0)], tl);
        common::assert_complex_close("t_p textbook", [g(f.tp)], [Complex::new(ttp, 0.0)], tl);
    }
}

fn s_light_reflects_with_rs<T: Real>(theta_i: f64, n: f64, k: f64) {
    let t = tol::<T>();
    let c = T::lit(theta_i.cos());
    let eta = cz::<T>(n, k);
    let f = coefficients(c, eta);
    let m = Mueller::from_jones(&reflection(c, eta));
    let one = T::one();
    let z = T::zero();
    let s_light = Stokes::new(one, one, z, z).unwrap();
    let p_light = Stokes::new(one, -one, z, z).unwrap();
    let out_s = (m * s_light).vector().map(Real::to_f64);
    let out_p = (m * p_light).vector().map(Real::to_f64);
    let (rs, rp) = (f.reflectance_s().to_f64(), f.reflectance_p().to_f64());
    assert_all_close(
        "s-light → (R_s, R_s, 0, 0)",
        out_s.iter().copied(),
        [rs, rs, 0.0, 0.0],
        t,
    );
    assert_all_close(
        "p-light → (R_p, −R_p, 0, 0)",
        out_p.iter().copied(),
        [rp, -rp, 0.0, 0.0],
        t,
    );
    // R_s computed literally from the Born & Wolf s formula, not through the crate.
    let ci = T::lit(theta_i.cos()).to_f64();
    let eta64 = c64(eta);
    let ct = (1.0 - (1.0 - ci * ci) / (eta64 * eta64)).sqrt();
    let lit_rs = ((ci - eta64 * ct) / (ci + eta64 * ct)).norm_sqr();
    assert_close("R_s literal", rs, lit_rs, t);
}

fn absorbing<T: Real>(theta_i: f64, n: f64, k: f64) {
    let t = tol::<T>();
    let f = coefficients(T::lit(theta_i.cos()), cz::<T>(n, k));
    let (rs, rp) = (f.reflectance_s().to_f64(), f.reflectance_p().to_f64());
    assert!(
        rs <= 1.0 + t.abs && rp <= 1.0 + t.abs,
        "|r| > 1: R_s {rs}, R_p {rp}"
    );
    assert_close(
        "R_s + T_s (absorbing)",
        rs + f.transmittance_s().to_f64(),
        1.0,
        t,
    );
    assert_close(
        "R_p + T_p (absorbing)",
        rp + f.transmittance_p().to_f64(),
        1.0,
        t,
    );
    // The transmitted wave decays: Im(η cos θ_t) ≥ 0.
    let q = c64(f.cos_theta_t) * c64(f.eta);
    assert!(q.im >= -t.abs, "Im(η cos θ_t) = {}", q.im);
    // Stokes validity of reflected and transmitted light from any valid input.
    for m in [
        Mueller::from_jones(&reflection(T::lit(theta_i.cos()), cz::<T>(n, k))),
        Mueller::from_jones(&transmission(T::lit(theta_i.cos()), cz::<T>(n, k))),
    ] {
        for s in [
            [1.0, 1.0, 0.0, 0.0],
            [1.0, 0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0, 0.0],
        ] {
            let s_in = Stokes::new(T::lit(s[0]), T::lit(s[1]), T::lit(s[2]), T::lit(s[3])).unwrap();
            let o = (m * s_in).vector();
            assert!(
                Stokes::new(o[0], o[1], o[2], o[3]).is_ok(),
                "invalid output {o:?}"
            );
        }
    }
}

// ------------------------------------------------------------------ instantiations

#[test]
fn normal_incidence_is_a_mirror() {
    for (n, k) in [(1.5, 0.0), (0.5, 0.0), (0.18, 3.0), (2.0, 1.5)] {
        normal_incidence::<f64>(n, k);
        normal_incidence::<f32>(n, k);
    }
}

#[test]
fn brewster_extinguishes_p() {
    for n in [1.01, 1.33, 1.5, 2.4, 4.0, 1.0 / 1.5, 0.5] {
        let r = brewster::<f64>(n);
        assert!(r < 1e-15, "|r_p| at Brewster, n = {n}: {r:e}");
        let r = brewster::<f32>(n);
        assert!(r < 1e-6, "|r_p| at Brewster (f32), n = {n}: {r:e}");
        // s is not extinguished there.
        let cos_b = 1.0 / (1.0 + n * n).sqrt();
        assert!(coefficients(cos_b, Complex::new(n, 0.0)).reflectance_s() > 1e-5);
    }
}

#[test]
fn gold_at_633nm_reflects_strongly() {
    // Gold at 633 nm, η ≈ 0.18 + 3.0i (Johnson & Christy 1972): R ≈ 0.9+ at normal incidence.
    let eta = Complex::new(0.18, 3.0);
    let f = coefficients(1.0_f64, eta);
    let r = f.reflectance_s();
    let lit = ((1.0 - eta) / (1.0 + eta)).norm_sqr();
    assert_close("gold R(0°)", r, lit, F64);
    assert!(r > 0.9 && r < 1.0, "gold R = {r}");
    for deg in [0.0_f64, 30.0, 60.0, 80.0, 89.9] {
        absorbing::<f64>(deg.to_radians(), 0.18, 3.0);
        absorbing::<f32>(deg.to_radians(), 0.18, 3.0);
    }
}

#[test]
fn grazing_and_out_of_range_inputs_do_not_panic() {
    // Grazing: |r| = 1 with r_s = r_p = −1 for any η ≠ 1.
    let f = coefficients(0.0_f64, Complex::new(1.5, 0.0));
    common::assert_complex_close("grazing", [f.rs, f.rp], [Complex::new(-1.0, 0.0); 2], F64);
    assert_close("grazing T_s", f.transmittance_s(), 0.0, F64);
    // η = 1 at grazing: no interface.
    let f = coefficients(0.0_f64, Complex::new(1.0, 0.0));
    assert!(f.rs.norm() == 0.0 && f.rp.norm() == 0.0 && f.transmittance_s() == 1.0);
    // Clamping: cos θ_i outside [0, 1] behaves like the nearest end.
    assert_eq!(
        coefficients(1.5_f64, Complex::new(1.5, 0.0)),
        coefficients(1.0, Complex::new(1.5, 0.0))
    );
    assert_eq!(
        coefficients(-0.5_f64, Complex::new(1.5, 0.0)),
        coefficients(0.0, Complex::new(1.5, 0.0))
    );
    // NaN propagates, no panic.
    assert!(
        coefficients(f64::NAN, Complex::new(1.5, 0.0))
            .rs
            .re
            .is_nan()
    );
}

#[test]
fn try_coefficients_validates() {
    let ok = Complex::new(1.5_f64, 0.0);
    assert!(try_coefficients(0.5, ok).is_ok());
    assert!(matches!(
        try_coefficients(f64::NAN, ok),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        try_coefficients(0.5, Complex::new(f64::INFINITY, 0.0)),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        try_coefficients(0.5, Complex::new(1.5, f64::NAN)),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        try_coefficients(-0.1, ok),
        Err(Error::OutOfRange { .. })
    ));
    assert!(matches!(
        try_coefficients(1.1, ok),
        Err(Error::OutOfRange { .. })
    ));
    assert!(matches!(
        try_coefficients(0.5, Complex::new(0.0, 1.0)),
        Err(Error::OutOfRange { .. })
    ));
    assert!(matches!(
        try_coefficients(0.5, Complex::new(1.5, -0.1)),
        Err(Error::OutOfRange { .. })
    ));
    assert_eq!(try_coefficients(0.5, ok).unwrap(), coefficients(0.5, ok));
}

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn lossless_dielectric_conserves_energy_and_matches_textbook(
        theta_i in 0.0..std::f64::consts::FRAC_PI_2, n in 1.01..4.0f64, inverse in any::<bool>()
    ) {
        // n > 1 (external) and n < 1 (internal reflection, TIR beyond the critical angle).
        let n = if inverse { 1.0 / n } else { n };
        lossless_dielectric::<f64>(theta_i, n);
        lossless_dielectric::<f32>(theta_i, n);
    }

    #[test]
    fn s_polarized_light_reflects_with_r_s(
        theta_i in 0.0..std::f64::consts::FRAC_PI_2, n in 0.2..4.0f64, k in 0.0..5.0f64
    ) {
        s_light_reflects_with_rs::<f64>(theta_i, n, k);
        s_light_reflects_with_rs::<f32>(theta_i, n, k);
    }

    #[test]
    fn absorbing_media_conserve_energy_and_keep_stokes_valid(
        theta_i in 0.0..std::f64::consts::FRAC_PI_2, n in 0.05..5.0f64, k in 0.0..8.0f64
    ) {
        absorbing::<f64>(theta_i, n, k);
        absorbing::<f32>(theta_i, n, k);
    }
}

// ------------------------------------------------------------------ issue 36: η = 1

/// An index-matched interface (η = 1) is no interface: `r_s = r_p = 0` exactly (Born & Wolf
/// §1.5.2: `cos θ_t = cos θ_i`, so both numerators vanish), at every angle whose `cos²θ_i` is a
/// normal number, in both precisions — the coefficients, the reflectances, the Mueller matrix,
/// `FresnelReflection`'s and `FresnelInterface`'s reflection (`M₀₀`, and `T = 1` across), the
/// renderer layer's `Interface::reflectance` from either side, and the kernel's specular lobe,
/// scalar and batch. Before, `q` was formed as `η² − (1 − cos²θ_i)` and the rounding of
/// `1 − cos²θ_i` left `R ≈ 8e-30` in f64 and `2e-12` in f32 (issue 36).
#[test]
fn index_matched_interface_reflects_exactly_nothing() {
    fn run<T: Real>() -> usize {
        use gmueller::bsdf::Interface;
        use gmueller::interaction::pbsdf::{FresnelInterface, FresnelReflection, Pbsdf};
        let one = Complex::new(T::one(), T::zero());
        let mut cosines: Vec<T> = (0..=2000).map(|i| T::lit(f64::from(i) / 2000.0)).collect();
        cosines.extend((1..=90).map(|d| T::lit(f64::from(d).to_radians().cos())));
        cosines.push(T::lit(89.99f64.to_radians().cos()));
        // The smallest cosines whose squares are normal numbers.
        let tiny = T::MIN_POSITIVE.sqrt();
        cosines.extend([tiny, tiny * T::lit(1.5), tiny * T::lit(1e3), T::lit(1e-9)]);
        let interface = FresnelInterface::new(T::one()).unwrap();
        let mirror = FresnelReflection::new(one).unwrap();
        for &c in &cosines {
            let k = coefficients(c, one);
            let what = format!("cos θ {:e}", c.to_f64());
            assert!(
                k.rs == Complex::new(T::zero(), T::zero()),
                "{what}: r_s {:?}",
                k.rs
            );
            assert!(
                k.rp == Complex::new(T::zero(), T::zero()),
                "{what}: r_p {:?}",
                k.rp
            );
            assert!(k.reflectance_s() == T::zero() && k.reflectance_p() == T::zero());
            if c > T::zero() {
                assert!(
                    k.ts == one && k.tp == one,
                    "{what}: t {:?} {:?}",
                    k.ts,
                    k.tp
                );
            }
            let m = Mueller::from_jones(&reflection(c, one));
            assert!(
                m.matrix().iter().all(|x| *x == T::zero()),
                "{what}: {:?}",
                m.matrix()
            );
            // `Interface::reflectance` takes cos θ in (0, 1].
            for below in [false, true] {
                assert!(
                    c == T::zero() || interface.reflectance(c, below) == T::zero(),
                    "{what}: below {below}"
                );
            }
            let _ = mirror.index();
        }
        // Through the pBSDFs at a geometry (normal, 40°, 89.99°).
        let surface = gmueller::frame::Frame::<T>::new(
            nalgebra::Vector3::x(),
            nalgebra::Vector3::y(),
            nalgebra::Vector3::z(),
        )
        .unwrap();
        for deg in [0.0f64, 40.0, 89.99] {
            let t = deg.to_radians();
            let to_source = nalgebra::Vector3::new(-t.sin(), 0.0, t.cos()).map(T::lit);
            let exit = nalgebra::Vector3::new(t.sin(), 0.0, t.cos()).map(T::lit);
            let g = gmueller::interaction::Geometry::new(T::lit(10.0), &surface, to_source, exit)
                .unwrap();
            assert!(mirror.m00(&g) == T::zero(), "{deg}°");
            assert!(
                mirror.mueller(&g).matrix().iter().all(|x| *x == T::zero()),
                "{deg}°"
            );
            let gi = gmueller::interaction::Geometry::at_interface(
                T::lit(10.0),
                &surface,
                T::one(),
                to_source,
                exit,
            )
            .unwrap();
            assert!(interface.m00(&gi) == T::zero(), "{deg}°");
            let across = gmueller::interaction::Geometry::at_interface(
                T::lit(10.0),
                &surface,
                T::one(),
                to_source,
                -to_source,
            )
            .unwrap();
            let tm = interface.m00(&across);
            assert!(
                (tm - T::one()).abs() <= T::lit(4.0) * T::EPSILON,
                "{deg}°: T = {tm:?}"
            );
        }
        cosines.len()
    }
    let n = run::<f64>();
    run::<f32>();
    println!("{n} angles per precision");
}

/// The kernel's specular lobe at η = 1 is exactly 0 at every exit, scalar and batch (the batch
/// path takes its Fresnel matrix from `fresnel::reflection` per packet), `Full · Partial`, both
/// precisions.
#[test]
fn index_matched_specular_lobe_is_exactly_zero() {
    fn run<T: Real>() {
        use gmueller::frame::Frame;
        use gmueller::interaction::batch::{DirectionsSoa, LobesSoa, StokesSoa};
        use gmueller::interaction::pbsdf::FresnelReflection;
        use gmueller::interaction::pbsdf::RayleighRice;
        use gmueller::interaction::{Full, Geometry, Kernel, Partial, RoughSurface};
        use gmueller::packet::{CoherenceShape, WavePacket};
        use gmueller::psd::GaussianPsd;
        use nalgebra::Vector3;
        let one = Complex::new(T::one(), T::zero());
        let material = RoughSurface {
            psd: GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(2.0)).unwrap(),
            specular: FresnelReflection::new(one).unwrap(),
            scatter: RayleighRice::new(one).unwrap(),
        };
        let surface = Frame::<T>::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let kernel = Kernel::<Full, Partial>::default();
        for deg in [0.0f64, 25.0, 60.0, 85.0] {
            let t = deg.to_radians();
            let travel = Vector3::new(t.sin(), 0.0, -t.cos()).map(T::lit);
            let packet = WavePacket::from_stokes(
                Stokes::new(T::one(), T::lit(0.3), T::zero(), T::zero()).unwrap(),
                CoherenceShape::isotropic(T::lit(3.0)).unwrap(),
                gmueller::frame::Frame::sp(travel, Vector3::z()).unwrap(),
                T::lit(0.5),
            )
            .unwrap();
            let exits: Vec<Vector3<T>> = (0..16)
                .map(|i| {
                    let o = t + 1e-3 * (f64::from(i) - 8.0);
                    Vector3::new(o.sin(), 1e-3 * f64::from(i % 3), o.cos().abs())
                        .map(T::lit)
                        .normalize()
                })
                .collect();
            for e in &exits {
                let g = Geometry::for_packet(&packet, &surface, *e).unwrap();
                let r = kernel.evaluate(&material, &packet, &g);
                assert!(
                    r.specular.vector() == nalgebra::Vector4::zeros(),
                    "{deg}°: {:?}",
                    r.specular
                );
            }
            let cols: [Vec<T>; 3] = core::array::from_fn(|k| exits.iter().map(|e| e[k]).collect());
            let n = exits.len();
            let mut out: Vec<Vec<T>> = vec![vec![T::one(); n]; 8];
            let (a, b) = out.split_at_mut(4);
            let [s0, s1, s2, s3] = a else { unreachable!() };
            let [c0, c1, c2, c3] = b else { unreachable!() };
            let mut lobes = LobesSoa {
                specular: StokesSoa {
                    s: [s0, s1, s2, s3],
                },
                scattered: StokesSoa {
                    s: [c0, c1, c2, c3],
                },
            };
            kernel
                .evaluate_batch(
                    &material,
                    &packet,
                    &surface,
                    None,
                    DirectionsSoa {
                        x: &cols[0],
                        y: &cols[1],
                        z: &cols[2],
                    },
                    &mut lobes,
                    None,
                )
                .unwrap();
            for column in out.iter().take(4) {
                assert!(
                    column.iter().all(|x| *x == T::zero()),
                    "{deg}°: batch {:?}",
                    column
                );
            }
        }
    }
    run::<f64>();
    run::<f32>();
}
