//! Jones calculus: standard elements and states checked against physical laws (Malus, wave plates,
//! idempotence, unitarity, rotation), Jones → Stokes against the Mueller route, and Jones → Mueller
//! against pySCATMECH / py-pol and Mitsuba 3 reference values. Every law runs in f64 and f32.

use crate::common;

use common::{flip_s3, json_rows as rows, peer_cases as cases};

use common::{
    F32, F64, Tol, angle, assert_all_close, assert_close, complex, complex_matrix2, entries4,
    matrix4_from_rows, stokes_vector,
};
use gmueller::error::Error;
use gmueller::jones::{Handedness, JonesMatrix, JonesVector};
use gmueller::mueller::Mueller;
use gmueller::real::Real;
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Matrix4, Vector4};
use num_complex::Complex;
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

// ------------------------------------------------------------------ helpers (this file only)

fn c<T: Real>(z: Complex<f64>) -> Complex<T> {
    Complex::new(T::lit(z.re), T::lit(z.im))
}

fn c64<T: Real>(z: Complex<T>) -> Complex<f64> {
    Complex::new(z.re.to_f64(), z.im.to_f64())
}

/// `x` rounded to `T` and back: the value the `T` computation actually sees.
fn seen<T: Real>(x: f64) -> f64 {
    T::lit(x).to_f64()
}

fn jm<T: Real>(m: Matrix2<Complex<f64>>) -> JonesMatrix<T> {
    JonesMatrix::from_matrix(m.map(c::<T>)).unwrap()
}

fn jv<T: Real>(ex: Complex<f64>, ey: Complex<f64>) -> JonesVector<T> {
    JonesVector::new(c(ex), c(ey)).unwrap()
}

fn m64<T: Real>(m: &Mueller<T>) -> Matrix4<f64> {
    m.matrix().map(Real::to_f64)
}

fn s64<T: Real>(s: &Stokes<T>) -> Vector4<f64> {
    s.vector().map(Real::to_f64)
}

fn j64<T: Real>(j: &JonesMatrix<T>) -> Matrix2<Complex<f64>> {
    j.matrix().map(c64)
}

fn assert_jones_close(what: &str, a: Matrix2<Complex<f64>>, b: Matrix2<Complex<f64>>, tol: Tol) {
    common::assert_complex_close(what, a.iter().copied(), b.iter().copied(), tol);
}

/// The f32 tolerance, or the f64 one, by the size of `T::EPSILON`.
fn tol<T: Real>() -> Tol {
    if T::EPSILON.to_f64() > 1e-10 {
        F32
    } else {
        F64
    }
}

// ------------------------------------------------------------------ laws, generic over T

fn malus<T: Real>(theta: f64, theta0: f64) {
    let (th, th0) = (seen::<T>(theta), seen::<T>(theta0));
    let p = Mueller::from_jones(&JonesMatrix::<T>::linear_polarizer(T::lit(theta)));
    let m = m64(&p);
    // The polarizer's Mueller matrix uses 2θ (guards "θ instead of 2θ").
    assert_close("M00", m[(0, 0)], 0.5, tol::<T>());
    assert_close(
        "M01 = ½cos2θ",
        m[(0, 1)],
        0.5 * (2.0 * th).cos(),
        tol::<T>(),
    );
    assert_close(
        "M02 = ½sin2θ",
        m[(0, 2)],
        0.5 * (2.0 * th).sin(),
        tol::<T>(),
    );
    assert_close("M03", m[(0, 3)], 0.0, tol::<T>());
    let s_in = JonesVector::<T>::linear(T::lit(theta0)).to_stokes();
    let out = s64(&(p * s_in));
    assert_close(
        "Malus I = cos²(θ−θ₀)",
        out[0],
        (th - th0).cos().powi(2),
        tol::<T>(),
    );
}

fn quarter_wave_on_45<T: Real>() {
    let q = JonesMatrix::<T>::linear_retarder(T::zero(), T::lit(FRAC_PI_2));
    let s = s64(&(q * JonesVector::linear(T::lit(FRAC_PI_4))).to_stokes());
    assert_all_close(
        "QWP(x̂)·(+45°)",
        s.iter().copied(),
        [1.0, 0.0, 0.0, 1.0],
        tol::<T>(),
    );
    // Same through Mueller.
    let m = Mueller::from_jones(&q);
    let s2 = s64(&(m * JonesVector::<T>::linear(T::lit(FRAC_PI_4)).to_stokes()));
    assert_all_close(
        "QWP Mueller",
        s2.iter().copied(),
        [1.0, 0.0, 0.0, 1.0],
        tol::<T>(),
    );
}

fn half_wave_rotates<T: Real>(fast: f64, input: f64) {
    let (f, i) = (seen::<T>(fast), seen::<T>(input));
    let h = JonesMatrix::<T>::linear_retarder(T::lit(fast), T::lit(PI));
    let s = s64(&(h * JonesVector::linear(T::lit(input))).to_stokes());
    let out = i + 2.0 * (f - i); // rotated by 2(θ_fast − θ_in)
    let expect = [1.0, (2.0 * out).cos(), (2.0 * out).sin(), 0.0];
    assert_all_close("HWP output", s.iter().copied(), expect, tol::<T>());
}

fn state_stokes<T: Real>(psi: f64, chi: f64) {
    let (p, x) = (seen::<T>(psi), seen::<T>(chi));
    let t = tol::<T>();
    let lin = s64(&JonesVector::<T>::linear(T::lit(psi)).to_stokes());
    let e = [1.0, (2.0 * p).cos(), (2.0 * p).sin(), 0.0];
    assert_all_close("linear", lin.iter().copied(), e, t);
    let ell = s64(&JonesVector::<T>::elliptical(T::lit(psi), T::lit(chi)).to_stokes());
    let e = [
        1.0,
        (2.0 * x).cos() * (2.0 * p).cos(),
        (2.0 * x).cos() * (2.0 * p).sin(),
        (2.0 * x).sin(),
    ];
    assert_all_close("elliptical", ell.iter().copied(), e, t);
    for (hand, s3) in [
        (Handedness::PositiveS3, 1.0),
        (Handedness::NegativeS3, -1.0),
    ] {
        let v = JonesVector::<T>::circular(hand);
        let s = s64(&v.to_stokes());
        assert_all_close("circular", s.iter().copied(), [1.0, 0.0, 0.0, s3], t);
        assert_close("intensity", v.intensity().to_f64(), 1.0, t);
    }
    // (1, i)/√2 literally has S3 = +1 (the defining statement of the convention).
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let v = jv::<T>(Complex::new(h, 0.0), Complex::new(0.0, h));
    assert_close("(1,i)/√2 S3", s64(&v.to_stokes())[3], 1.0, t);
    // Elliptical with χ = ±π/4 is circular with the matching handedness (any azimuth).
    let e = JonesVector::<T>::elliptical(T::lit(psi), T::lit(FRAC_PI_4));
    assert_close("χ = π/4 → S3 = +1", s64(&e.to_stokes())[3], 1.0, t);
}

fn pure_state_and_mueller_route<T: Real>(
    ex: Complex<f64>,
    ey: Complex<f64>,
    j: Matrix2<Complex<f64>>,
) {
    let v = jv::<T>(ex, ey);
    let s = s64(&v.to_stokes());
    // S0² = S1² + S2² + S3² for a Jones vector; S0 = intensity = |Ex|² + |Ey|² (literal).
    let scale = s[0] * s[0];
    let t = tol::<T>();
    assert_close(
        "S0² − |S|²",
        s[0] * s[0] - (s[1] * s[1] + s[2] * s[2] + s[3] * s[3]),
        0.0,
        Tol::new(t.abs * scale.max(1.0), 0.0),
    );
    let (exs, eys) = (c64(c::<T>(ex)), c64(c::<T>(ey)));
    assert_close("S0", s[0], exs.norm_sqr() + eys.norm_sqr(), t);
    assert_close(
        "S1",
        s[1],
        exs.norm_sqr() - eys.norm_sqr(),
        Tol::new(t.abs * scale.max(1.0), t.rel),
    );
    assert_close(
        "S2",
        s[2],
        2.0 * (exs * eys.conj()).re,
        Tol::new(t.abs * scale.max(1.0), t.rel),
    );
    assert_close(
        "S3",
        s[3],
        2.0 * (exs.conj() * eys).im,
        Tol::new(t.abs * scale.max(1.0), t.rel),
    );
    // Stokes(J v) = Mueller(J) Stokes(v).
    let jj = jm::<T>(j);
    let direct = s64(&(jj * v).to_stokes());
    let via = s64(&(Mueller::from_jones(&jj) * v.to_stokes()));
    let big = direct.amax().max(1.0) * j.iter().map(|z| z.norm_sqr()).sum::<f64>().max(1.0);
    assert_all_close(
        "Stokes(Jv) vs M·Stokes(v)",
        direct.iter().copied(),
        via.iter().copied(),
        Tol::new(t.abs * big * s[0].max(1.0), t.rel),
    );
}

fn elements<T: Real>(theta: f64, delta: f64, a: f64, b: f64) {
    let t = tol::<T>();
    // Polarizer idempotent.
    let p = JonesMatrix::<T>::linear_polarizer(T::lit(theta));
    assert_jones_close("P² = P", j64(&(p * p)), j64(&p), t);
    // Retarder unitary: J†J = I (adjoint checked against the literal conjugate transpose).
    let r = JonesMatrix::<T>::linear_retarder(T::lit(theta), T::lit(delta));
    let lit_adj = j64(&r).transpose().map(|z| z.conj());
    assert_jones_close("adjoint", j64(&r.adjoint()), lit_adj, t);
    assert_jones_close("J†J = I", lit_adj * j64(&r), Matrix2::identity(), t);
    assert_close("|det| = 1", r.determinant().norm_sqr().to_f64(), 1.0, t);
    // Retarder eigenstates: fast axis passes unchanged, slow axis gets e^{iδ}.
    let fast = r * JonesVector::linear(T::lit(theta));
    let slow = r * JonesVector::linear(T::lit(theta + FRAC_PI_2));
    let (th, d) = (seen::<T>(theta), seen::<T>(delta));
    let e = Complex::from_polar(1.0, d);
    common::assert_complex_close(
        "fast axis",
        [c64(fast.ex()), c64(fast.ey())],
        [Complex::new(th.cos(), 0.0), Complex::new(th.sin(), 0.0)],
        t,
    );
    common::assert_complex_close(
        "slow axis lags e^{iδ}",
        [c64(slow.ex()), c64(slow.ey())],
        [e * -th.sin(), e * th.cos()],
        t,
    );
    // Rotator: composition, action on linear light, Mueller rotates (S1, S2) by 2ρ.
    let (ra, rb) = (
        JonesMatrix::<T>::rotator(T::lit(a)),
        JonesMatrix::<T>::rotator(T::lit(b)),
    );
    let ab = JonesMatrix::<T>::rotator(T::lit(seen::<T>(a) + seen::<T>(b)));
    assert_jones_close("R(a)R(b) = R(a+b)", j64(&(ra * rb)), j64(&ab), t);
    let out = s64(&(ra * JonesVector::linear(T::lit(theta))).to_stokes());
    let ang = 2.0 * (th + seen::<T>(a));
    assert_all_close(
        "rotator turns linear light by +ρ",
        out.iter().copied(),
        [1.0, ang.cos(), ang.sin(), 0.0],
        t,
    );
    // Circular retarder: (1, ±i)/√2 are eigenstates with relative phase e^{iδ} (NegativeS3 lags).
    let cr = JonesMatrix::<T>::circular_retarder(T::lit(delta));
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let plus = cr * JonesVector::circular(Handedness::PositiveS3);
    let minus = cr * JonesVector::circular(Handedness::NegativeS3);
    let em = Complex::from_polar(1.0, -d / 2.0);
    let ep = Complex::from_polar(1.0, d / 2.0);
    common::assert_complex_close(
        "circular retarder, PositiveS3",
        [c64(plus.ex()), c64(plus.ey())],
        [em * h, em * Complex::new(0.0, h)],
        t,
    );
    common::assert_complex_close(
        "circular retarder, NegativeS3",
        [c64(minus.ex()), c64(minus.ey())],
        [ep * h, ep * Complex::new(0.0, -h)],
        t,
    );
    // Circular polarizers: transmit their hand unchanged, extinguish the other, idempotent,
    // and map linear light to their state at half intensity.
    for hand in [Handedness::PositiveS3, Handedness::NegativeS3] {
        let cp = JonesMatrix::<T>::circular_polarizer(hand);
        let own = JonesVector::<T>::circular(hand);
        let pass = cp * own;
        common::assert_complex_close(
            "circular polarizer passes its hand",
            [c64(pass.ex()), c64(pass.ey())],
            [c64(own.ex()), c64(own.ey())],
            t,
        );
        let block = cp * JonesVector::circular(hand.opposite());
        assert_close("extinguishes the other", block.intensity().to_f64(), 0.0, t);
        assert_jones_close("circular P² = P", j64(&(cp * cp)), j64(&cp), t);
        let s = s64(&(cp * JonesVector::linear(T::lit(theta))).to_stokes());
        let s3 = hand.s3_sign::<f64>() * 0.5;
        assert_all_close(
            "linear → circular",
            s.iter().copied(),
            [0.5, 0.0, 0.0, s3],
            t,
        );
    }
}

fn diattenuator_law<T: Real>(tx: f64, ty: f64, theta: f64) {
    let t = tol::<T>();
    let d = JonesMatrix::<T>::diattenuator(T::lit(tx), T::lit(ty), T::lit(theta)).unwrap();
    let along = (d * JonesVector::linear(T::lit(theta)))
        .intensity()
        .to_f64();
    let across = (d * JonesVector::linear(T::lit(theta + FRAC_PI_2)))
        .intensity()
        .to_f64();
    assert_close("along-axis intensity t_x²", along, seen::<T>(tx).powi(2), t);
    assert_close(
        "cross-axis intensity t_y²",
        across,
        seen::<T>(ty).powi(2),
        t,
    );
    let pol = JonesMatrix::<T>::diattenuator(T::one(), T::zero(), T::lit(theta)).unwrap();
    let lp = JonesMatrix::<T>::linear_polarizer(T::lit(theta));
    assert_jones_close("(1, 0, θ) = polarizer", j64(&pol), j64(&lp), t);
}

fn diattenuator_rejects<T: Real>() {
    let bad = |tx: f64, ty: f64, th: f64| {
        JonesMatrix::<T>::diattenuator(T::lit(tx), T::lit(ty), T::lit(th))
    };
    assert!(matches!(bad(-0.1, 0.5, 0.0), Err(Error::OutOfRange { .. })));
    assert!(matches!(
        bad(0.5, -1e-3, 0.0),
        Err(Error::OutOfRange { .. })
    ));
    assert!(matches!(bad(1.01, 0.5, 0.0), Err(Error::OutOfRange { .. })));
    assert!(matches!(bad(0.5, 2.0, 0.0), Err(Error::OutOfRange { .. })));
    assert!(matches!(
        bad(f64::NAN, 0.5, 0.0),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        bad(0.5, f64::NAN, 0.0),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        bad(0.5, 0.5, f64::NAN),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        bad(0.5, 0.5, f64::INFINITY),
        Err(Error::NonFinite { .. })
    ));
    assert!(bad(0.0, 1.0, 0.3).is_ok() && bad(1.0, 1.0, -7.0).is_ok());
}

fn from_matrix_rejects<T: Real>() {
    for k in 0..4 {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for imag in [false, true] {
                let mut m = Matrix2::from_element(Complex::new(T::one(), T::zero()));
                let z = if imag {
                    Complex::new(T::one(), T::lit(bad))
                } else {
                    Complex::new(T::lit(bad), T::one())
                };
                m[k] = z;
                assert!(
                    matches!(JonesMatrix::from_matrix(m), Err(Error::NonFinite { .. })),
                    "entry {k} = {bad} (imag {imag}) accepted"
                );
            }
        }
    }
    let nan = Complex::new(T::lit(f64::NAN), T::zero());
    let one = Complex::new(T::one(), T::zero());
    assert!(JonesVector::new(nan, one).is_err() && JonesVector::new(one, nan).is_err());
}

fn inverse_round_trip<T: Real>(j: Matrix2<Complex<f64>>) {
    let jj = jm::<T>(j);
    let det = c64(jj.determinant());
    let lit = j[(0, 0)] * j[(1, 1)] - j[(0, 1)] * j[(1, 0)];
    let norm2: f64 = j.iter().map(|z| z.norm_sqr()).sum();
    let t = tol::<T>();
    common::assert_complex_close("det", [det], [lit], Tol::new(t.abs * norm2.max(1.0), t.rel));
    // Well-conditioned draws only: |det| ≥ 0.05 ‖J‖²_F bounds the condition number.
    if lit.norm() < 0.05 * norm2 {
        return;
    }
    let inv = jj.inverse().expect("invertible");
    let cond = norm2 / lit.norm();
    let tl = Tol::new(t.abs * cond * 4.0, 0.0);
    assert_jones_close("J⁻¹J = I", j64(&(inv * jj)), Matrix2::identity(), tl);
    assert_jones_close("JJ⁻¹ = I", j64(&(jj * inv)), Matrix2::identity(), tl);
}

fn mueller_keeps_stokes_valid<T: Real>(j: Matrix2<Complex<f64>>, s: Vector4<f64>) -> bool {
    let jj = jm::<T>(j);
    let m = Mueller::from_jones(&jj);
    let s_in = Stokes::new(T::lit(s[0]), T::lit(s[1]), T::lit(s[2]), T::lit(s[3]));
    let Ok(s_in) = s_in else {
        return false; // rounding of an (almost) pure input into T; not this test's subject
    };
    let out = (m * s_in).vector();
    // Conditioning: the output intensity must not be a cancellation residue far below the size
    // of the terms summed (rounding in |S| would then exceed the relative slack of Stokes::new).
    let terms: f64 = (0..4)
        .map(|k| (m.matrix()[(0, k)] * s_in.vector()[k]).abs().to_f64())
        .sum();
    if out[0].to_f64() < 1e-2 * terms {
        return false;
    }
    let ok = Stokes::new(out[0], out[1], out[2], out[3]);
    assert!(ok.is_ok(), "output not valid Stokes: {out:?} ({ok:?})");
    true
}

// ------------------------------------------------------------------ instantiations

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn malus_law_and_polarizer_uses_two_theta(theta in angle(), theta0 in angle()) {
        malus::<f64>(theta, theta0);
        malus::<f32>(theta, theta0);
    }

    #[test]
    fn half_wave_plate_rotates_by_twice_the_offset(fast in angle(), input in angle()) {
        half_wave_rotates::<f64>(fast, input);
        half_wave_rotates::<f32>(fast, input);
    }

    #[test]
    fn stokes_of_linear_circular_elliptical(psi in angle(), chi in -FRAC_PI_4..=FRAC_PI_4) {
        state_stokes::<f64>(psi, chi);
        state_stokes::<f32>(psi, chi);
    }

    #[test]
    fn jones_vector_is_pure_and_stokes_of_jv_is_mueller_times_stokes(
        ex in complex(2.0), ey in complex(2.0), j in complex_matrix2(2.0)
    ) {
        pure_state_and_mueller_route::<f64>(ex, ey, j);
        pure_state_and_mueller_route::<f32>(ex, ey, j);
    }

    #[test]
    fn element_laws(theta in angle(), delta in angle(), a in angle(), b in angle()) {
        elements::<f64>(theta, delta, a, b);
        elements::<f32>(theta, delta, a, b);
    }

    #[test]
    fn diattenuator_transmits_amplitudes(tx in 0.0..=1.0f64, ty in 0.0..=1.0f64, theta in angle()) {
        diattenuator_law::<f64>(tx, ty, theta);
        diattenuator_law::<f32>(tx, ty, theta);
    }

    #[test]
    fn inverse_round_trip_and_determinant(j in complex_matrix2(2.0)) {
        inverse_round_trip::<f64>(j);
        inverse_round_trip::<f32>(j);
    }

    #[test]
    fn mueller_from_jones_maps_valid_stokes_to_valid_stokes(
        j in complex_matrix2(2.0), s in stokes_vector()
    ) {
        let a = mueller_keeps_stokes_valid::<f64>(j, s);
        let b = mueller_keeps_stokes_valid::<f32>(j, s);
        prop_assume!(a || b);
    }
}

#[test]
fn quarter_wave_plate_fast_x_on_plus_45_gives_s3_plus_one() {
    quarter_wave_on_45::<f64>();
    quarter_wave_on_45::<f32>();
}

#[test]
fn diattenuator_validation() {
    diattenuator_rejects::<f64>();
    diattenuator_rejects::<f32>();
}

#[test]
fn from_matrix_and_new_reject_non_finite() {
    from_matrix_rejects::<f64>();
    from_matrix_rejects::<f32>();
}

#[test]
fn singular_matrices_have_no_inverse() {
    for th in [0.0, 0.3, 1.0, 2.5] {
        assert!(JonesMatrix::<f64>::linear_polarizer(th).inverse().is_none());
        assert!(
            JonesMatrix::<f32>::linear_polarizer(th as f32)
                .inverse()
                .is_none()
        );
    }
    for hand in [Handedness::PositiveS3, Handedness::NegativeS3] {
        assert!(
            JonesMatrix::<f64>::circular_polarizer(hand)
                .inverse()
                .is_none()
        );
    }
    let z = Complex::new(0.0_f64, 0.0);
    assert!(
        JonesMatrix::from_matrix(Matrix2::from_element(z))
            .unwrap()
            .inverse()
            .is_none()
    );
}

// ------------------------------------------------------------------ external anchors

/// pySCATMECH `JonesMueller` (= py-pol `Mueller.from_Jones`), same Stokes convention as ours.
#[test]
fn jones_to_mueller_matches_pyscatmech_and_pypol() {
    for case in cases("jones_to_mueller") {
        let (re, im) = (rows(&case["jones_re"]), rows(&case["jones_im"]));
        let j = Matrix2::from_fn(|r, k| Complex::new(re[r][k], im[r][k]));
        let want = matrix4_from_rows(&rows(&case["mueller"]));
        let got = m64(&Mueller::from_jones(&jm::<f64>(j)));
        assert_all_close(
            "pySCATMECH JonesMueller (f64)",
            entries4(&got),
            entries4(&want),
            Tol::new(1e-13, 1e-13),
        );
        let got32 = m64(&Mueller::from_jones(&jm::<f32>(j)));
        let scale = want.amax().max(1.0);
        assert_all_close(
            "pySCATMECH JonesMueller (f32)",
            entries4(&got32),
            entries4(&want),
            Tol::new(F32.abs * scale, F32.rel),
        );
    }
}

fn case_tol(case: &serde_json::Value) -> f64 {
    case["tol"].as_f64().expect("case tolerance")
}

/// Mitsuba 3.9.1 `rotated_element(θ, linear_polarizer(1))`; no conversion needed.
#[test]
fn linear_polarizer_matches_mitsuba() {
    for case in cases("linear_polarizer") {
        let theta = case["theta"].as_f64().unwrap();
        let want = matrix4_from_rows(&rows(&case["mueller"]));
        let tl = Tol::new(case_tol(&case), case_tol(&case));
        let got = m64(&Mueller::from_jones(&JonesMatrix::<f64>::linear_polarizer(
            theta,
        )));
        assert_all_close(
            "Mitsuba linear_polarizer (f64)",
            entries4(&got),
            entries4(&want),
            tl,
        );
        let got = m64(&Mueller::from_jones(&JonesMatrix::<f32>::linear_polarizer(
            theta as f32,
        )));
        let tl = Tol::new(tl.abs.max(F32.abs), tl.rel.max(F32.rel));
        assert_all_close(
            "Mitsuba linear_polarizer (f32)",
            entries4(&got),
            entries4(&want),
            tl,
        );
    }
}

/// Mitsuba 3.9.1 `rotated_element(θ, linear_retarder(δ))`, fast axis at θ; Mitsuba uses
/// `e^{+iωt}`, so our matrix is `D M D` with `D = diag(1, 1, 1, −1)`.
#[test]
fn linear_retarder_matches_mitsuba_after_s3_flip() {
    for case in cases("linear_retarder") {
        let theta = case["theta"].as_f64().unwrap();
        let delta = case["delta"].as_f64().unwrap();
        let want = flip_s3(matrix4_from_rows(&rows(&case["mueller"])));
        let tl = Tol::new(case_tol(&case), case_tol(&case));
        let j = JonesMatrix::<f64>::linear_retarder(theta, delta);
        let got = m64(&Mueller::from_jones(&j));
        assert_all_close(
            "Mitsuba linear_retarder (f64)",
            entries4(&got),
            entries4(&want),
            tl,
        );
        let j = JonesMatrix::<f32>::linear_retarder(theta as f32, delta as f32);
        let got = m64(&Mueller::from_jones(&j));
        let tl = Tol::new(tl.abs.max(F32.abs), tl.rel.max(F32.rel));
        assert_all_close(
            "Mitsuba linear_retarder (f32)",
            entries4(&got),
            entries4(&want),
            tl,
        );
    }
}
