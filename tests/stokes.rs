//! Verifies S1.2–S1.3 and the Stokes/CSD types: `A_mül vec(C)` of a sample CSD equals the
//! sample average of the per-field Stokes formulas; `A_mül⁻¹ = ½ A_mül†`; CSD and Stokes
//! validation errors; degree of polarization and ellipse parameters of known states; and the
//! round trips CSD ↔ generalized Stokes; scale invariance of every validity check (vectors and
//! matrices scaled by powers of two from the subnormal range to `T::MAX`: same verdict, finite
//! ratios) and errors where a derived quantity would overflow. Generic checks run in f64 and f32.

use crate::common;

use common::{
    F32, F64, Tol, assert_all_close, assert_close, assert_complex_close, complex_matrix2,
    stokes_vector,
};
use gmueller::Error;
use gmueller::jones::JonesVector;
use gmueller::real::Real;
use gmueller::stack::stack;
use gmueller::stokes::{CsdMatrix, GeneralizedStokes, Stokes, a_mul, a_mul_inv};
use nalgebra::{Matrix2, Matrix4, Vector4};
use num_complex::Complex;
use proptest::prelude::*;
use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_4, FRAC_PI_8};

fn z(re: f64, im: f64) -> Complex<f64> {
    Complex::new(re, im)
}

fn cz<T: Real>(c: Complex<f64>) -> Complex<T> {
    Complex::new(T::lit(c.re), T::lit(c.im))
}

fn back<T: Real>(c: Complex<T>) -> Complex<f64> {
    Complex::new(c.re.to_f64(), c.im.to_f64())
}

/// Partially polarized field samples: a random fixed polarization mixed with random noise.
fn samples(seed: u64, n: usize, mix: f64) -> Vec<(Complex<f64>, Complex<f64>)> {
    // SplitMix64 seeded by proptest; field samples uniform in [−1, 1).
    let mut g = common::SplitMix64(seed);
    let (px, py) = (z(g.signed(), g.signed()), z(g.signed(), g.signed()));
    (0..n)
        .map(|_| {
            let phase = z(g.signed(), g.signed());
            let nx = z(g.signed(), g.signed());
            let ny = z(g.signed(), g.signed());
            (px * phase + nx * mix, py * phase + ny * mix)
        })
        .collect()
}

fn sample_average_matches<T: Real>(seed: u64, mix: f64, tol: Tol) {
    let fields = samples(seed, 64, mix);
    let n = fields.len() as f64;
    // Independent: per-sample Stokes formulas, then averaged (f64).
    let mut s_direct = [0.0; 4];
    for (ex, ey) in &fields {
        s_direct[0] += (ex.norm_sqr() + ey.norm_sqr()) / n;
        s_direct[1] += (ex.norm_sqr() - ey.norm_sqr()) / n;
        s_direct[2] += 2.0 * (ex.conj() * ey).re / n;
        s_direct[3] += 2.0 * (ex.conj() * ey).im / n;
    }
    // Sample CSD ⟨E E†⟩ in T, through the crate's types.
    let mut c = Matrix2::<Complex<T>>::zeros();
    let inv_n = Complex::new(T::lit(1.0 / n), T::zero());
    for (ex, ey) in &fields {
        let e = JonesVector::new(cz::<T>(*ex), cz::<T>(*ey)).unwrap();
        c += CsdMatrix::from_jones_vector(&e).unwrap().matrix() * inv_n;
    }
    let csd = CsdMatrix::one_point(c).unwrap();
    // Literal S1.2: A_mül vec(C).
    let literal = a_mul::<T>() * stack(&c);
    let closed = csd.to_generalized_stokes().vector();
    let stokes = csd.to_stokes().unwrap();
    let direct: Vec<Complex<f64>> = s_direct.iter().map(|&s| z(s, 0.0)).collect();
    assert_complex_close(
        "A_mül vec(C) vs sample Stokes",
        literal.iter().map(|&x| back(x)),
        direct.clone(),
        tol,
    );
    assert_complex_close(
        "closed form vs sample Stokes",
        closed.iter().map(|&x| back(x)),
        direct,
        tol,
    );
    assert_all_close(
        "Stokes vs sample Stokes",
        stokes.vector().iter().map(|x| x.to_f64()),
        s_direct,
        tol,
    );
    // A sample average of valid states is valid.
    assert!(stokes.polarized_intensity() <= stokes.s0() * T::lit(1.0 + 1e-5));
}

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn s1_2_a_mul_of_sample_csd_equals_sample_stokes(seed in any::<u64>(), mix in 0.0..2.0f64) {
        sample_average_matches::<f64>(seed, mix, F64);
        sample_average_matches::<f32>(seed, mix, F32);
    }

    #[test]
    fn csd_generalized_stokes_round_trip(m in complex_matrix2(3.0)) {
        let c = CsdMatrix::two_point(m).unwrap();
        let s = c.to_generalized_stokes();
        // The literal S1.2 for a two-point (non-Hermitian) CSD.
        let literal = a_mul::<f64>() * stack(&m);
        assert_complex_close("closed vs literal S1.2", s.vector().iter().copied(), literal.iter().copied(), F64);
        let back = s.to_csd().matrix();
        assert_complex_close("round trip", back.iter().copied(), m.iter().copied(), F64);
        // vec(C) = A_mül⁻¹ S (the literal inverse).
        let vec_c = a_mul_inv::<f64>() * s.vector();
        assert_complex_close("A⁻¹ S", vec_c.iter().copied(), stack(&m).iter().copied(), F64);
    }

    #[test]
    fn stokes_to_csd_is_valid_one_point(v in stokes_vector()) {
        let s = Stokes::new(v[0], v[1], v[2], v[3]).unwrap();
        let c = s.to_csd();
        prop_assert!(c.is_one_point());
        // Revalidate from raw entries: a valid Stokes vector is a Hermitian PSD CSD.
        let again = CsdMatrix::one_point(c.matrix()).unwrap().to_stokes().unwrap();
        assert_all_close("Stokes → CSD → Stokes", again.vector().iter().copied(), v.iter().copied(), F64);
        let g = s.to_generalized().vector();
        assert_complex_close("to_generalized", g.iter().copied(), v.iter().map(|&x| z(x, 0.0)), F64);
    }

    #[test]
    fn polarized_plus_unpolarized_parts(v in stokes_vector()) {
        let s = Stokes::new(v[0], v[1], v[2], v[3]).unwrap();
        let sum = s.polarized_part().vector() + s.unpolarized_part().vector();
        assert_all_close("S_pol + S_unpol", sum.iter().copied(), v.iter().copied(), F64);
        let p = s.polarized_part();
        assert_close("polarized part is fully polarized", p.degree_of_polarization(), 1.0, F64);
        prop_assert!(s.degree_of_polarization() <= 1.0 + 1e-12);
        let dolp = s.degree_of_linear_polarization();
        let docp = s.degree_of_circular_polarization();
        assert_close("DoLP² + DoCP² = DoP²", dolp * dolp + docp * docp, s.degree_of_polarization().powi(2), F64);
    }

    #[test]
    fn ellipse_parameters_reproduce_stokes(v in stokes_vector()) {
        // S = |S| (cos 2χ cos 2ψ, cos 2χ sin 2ψ, sin 2χ): the standard parametrisation.
        let s = Stokes::new(v[0], v[1], v[2], v[3]).unwrap();
        let (psi, chi, p) = (s.azimuth(), s.ellipticity_angle(), s.polarized_intensity());
        prop_assume!(p > 1e-6);
        prop_assert!(chi.abs() <= FRAC_PI_4 + 1e-15);
        let rebuilt = [p * (2.0 * chi).cos() * (2.0 * psi).cos(), p * (2.0 * chi).cos() * (2.0 * psi).sin(), p * (2.0 * chi).sin()];
        // asin is ill-conditioned near ±1 (χ → ±π/4): cos 2χ carries ~√ε·|S| error there, hence 1e-9.
        assert_all_close("ellipse → Stokes", rebuilt, [v[1], v[2], v[3]], Tol::new(1e-9, 1e-9));
    }
}

#[test]
fn a_mul_inverse_is_half_adjoint() {
    let lit = a_mul::<f64>().try_inverse().unwrap();
    let half_adj = a_mul::<f64>().adjoint() * z(0.5, 0.0);
    assert_complex_close(
        "A⁻¹ = ½A†",
        lit.iter().copied(),
        half_adj.iter().copied(),
        F64,
    );
    assert_complex_close(
        "a_mul_inv",
        a_mul_inv::<f64>().iter().copied(),
        lit.iter().copied(),
        F64,
    );
    let p = a_mul::<f32>() * a_mul_inv::<f32>();
    let id = Matrix4::<Complex<f64>>::identity();
    assert_complex_close(
        "f32 A A⁻¹",
        p.iter().map(|&x| back(x)),
        id.iter().copied(),
        F32,
    );
}

#[test]
fn csd_validation_errors() {
    let non_herm = Matrix2::new(z(1.0, 0.0), z(0.5, 0.0), z(-0.5, 0.0), z(1.0, 0.0));
    assert!(matches!(
        CsdMatrix::one_point(non_herm),
        Err(Error::NotHermitian { .. })
    ));
    // Imaginary diagonal is non-Hermitian too.
    let im_diag = Matrix2::new(z(1.0, 0.1), z(0.0, 0.0), z(0.0, 0.0), z(1.0, 0.0));
    assert!(matches!(
        CsdMatrix::one_point(im_diag),
        Err(Error::NotHermitian { .. })
    ));
    let neg_diag = Matrix2::new(z(-0.1, 0.0), z(0.0, 0.0), z(0.0, 0.0), z(1.0, 0.0));
    match CsdMatrix::one_point(neg_diag) {
        Err(Error::NotPositiveDefinite { min_eigenvalue, .. }) => {
            assert_close("λ_min", min_eigenvalue, -0.1, F64)
        }
        other => panic!("expected NotPositiveDefinite, got {other:?}"),
    }
    // Positive diagonal, negative determinant: eigenvalues 1 ± 2.
    let neg_det = Matrix2::new(z(1.0, 0.0), z(0.0, 2.0), z(0.0, -2.0), z(1.0, 0.0));
    match CsdMatrix::one_point(neg_det) {
        Err(Error::NotPositiveDefinite { min_eigenvalue, .. }) => {
            assert_close("λ_min", min_eigenvalue, -1.0, F64)
        }
        other => panic!("expected NotPositiveDefinite, got {other:?}"),
    }
    let nan = Matrix2::new(z(f64::NAN, 0.0), z(0.0, 0.0), z(0.0, 0.0), z(1.0, 0.0));
    assert!(matches!(
        CsdMatrix::one_point(nan),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        CsdMatrix::two_point(nan),
        Err(Error::NonFinite { .. })
    ));
    let inf = Matrix2::new(z(1.0, 0.0), z(0.0, f64::INFINITY), z(0.0, 0.0), z(1.0, 0.0));
    assert!(matches!(
        CsdMatrix::two_point(inf),
        Err(Error::NonFinite { .. })
    ));
    // A two-point CSD accepts the non-Hermitian matrix, and to_stokes then validates it.
    let tp = CsdMatrix::two_point(non_herm).unwrap();
    assert!(!tp.is_one_point());
    assert!(matches!(tp.to_stokes(), Err(Error::NotHermitian { .. })));
    // Rank-1 PSD (det = 0 exactly in exact arithmetic) within rounding is accepted.
    let e = (z(0.3, 0.7), z(-1.1, 0.2));
    let r1 = Matrix2::new(
        e.0 * e.0.conj(),
        e.0 * e.1.conj(),
        e.1 * e.0.conj(),
        e.1 * e.1.conj(),
    );
    assert!(CsdMatrix::one_point(r1).is_ok());
}

#[test]
fn stokes_new_rejects_invalid() {
    assert!(matches!(
        Stokes::new(1.0, 0.8, 0.8, 0.0),
        Err(Error::InvalidStokes { .. })
    ));
    assert!(matches!(
        Stokes::new(-1.0_f64, 0.0, 0.0, 0.0),
        Err(Error::InvalidStokes { .. })
    ));
    assert!(matches!(
        Stokes::new(f64::NAN, 0.0, 0.0, 0.0),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        Stokes::new(1.0_f32, 0.0, f32::NAN, 0.0),
        Err(Error::NonFinite { .. })
    ));
    assert!(Stokes::new(1.0, 0.6, 0.0, 0.8).is_ok());
}

#[test]
fn known_states() {
    let h = FRAC_1_SQRT_2;
    // (1, i)/√2: S3 = +1 (crate convention), fully circular.
    let e = JonesVector::new(z(h, 0.0), z(0.0, h)).unwrap();
    let s = CsdMatrix::from_jones_vector(&e)
        .unwrap()
        .to_stokes()
        .unwrap();
    assert_all_close(
        "circular",
        s.vector().iter().copied(),
        [1.0, 0.0, 0.0, 1.0],
        F64,
    );
    assert_close("DoP", s.degree_of_polarization(), 1.0, F64);
    assert_close("DoCP", s.degree_of_circular_polarization(), 1.0, F64);
    assert_close("DoLP", s.degree_of_linear_polarization(), 0.0, F64);
    assert_close("χ", s.ellipticity_angle(), FRAC_PI_4, F64);
    assert_eq!(s.azimuth(), 0.0, "undefined azimuth returns 0");
    // Linear at 22.5°: E = (cos, sin), ψ = π/8, χ = 0.
    let e = JonesVector::new(z(FRAC_PI_8.cos(), 0.0), z(FRAC_PI_8.sin(), 0.0)).unwrap();
    let s = CsdMatrix::from_jones_vector(&e)
        .unwrap()
        .to_stokes()
        .unwrap();
    assert_close("ψ", s.azimuth(), FRAC_PI_8, F64);
    assert_close("χ", s.ellipticity_angle(), 0.0, F64);
    assert_close("DoLP", s.degree_of_linear_polarization(), 1.0, F64);
    // Linear at −60°: ψ = −π/3.
    let t = -std::f64::consts::FRAC_PI_3;
    let e = JonesVector::new(z(t.cos(), 0.0), z(t.sin(), 0.0)).unwrap();
    let s = CsdMatrix::from_jones_vector(&e)
        .unwrap()
        .to_stokes()
        .unwrap();
    assert_close("ψ", s.azimuth(), t, F64);
    // Unpolarized and zero light: no NaN.
    let u = Stokes::unpolarized(2.0_f64).unwrap();
    assert_eq!(
        [
            u.degree_of_polarization(),
            u.degree_of_linear_polarization(),
            u.degree_of_circular_polarization(),
            u.azimuth(),
            u.ellipticity_angle()
        ],
        [0.0; 5]
    );
    let zero = Stokes::new(0.0_f32, 0.0, 0.0, 0.0).unwrap();
    assert_eq!(
        [
            zero.degree_of_polarization(),
            zero.degree_of_linear_polarization(),
            zero.degree_of_circular_polarization(),
            zero.azimuth(),
            zero.ellipticity_angle()
        ],
        [0.0; 5]
    );
    assert_eq!(zero.unpolarized_part().s0(), 0.0);
    // Partially polarized: (2, 0, 0, −1) has DoP ½, DoCP −½.
    let p = Stokes::new(2.0_f64, 0.0, 0.0, -1.0).unwrap();
    assert_close("DoP", p.degree_of_polarization(), 0.5, F64);
    assert_close(
        "DoCP signed",
        p.degree_of_circular_polarization(),
        -0.5,
        F64,
    );
    assert_close("χ", p.ellipticity_angle(), -FRAC_PI_4, F64);
    assert_eq!((p.s1(), p.s2(), p.s3()), (0.0, 0.0, -1.0));
}

#[test]
fn generalized_stokes_arithmetic() {
    let a = GeneralizedStokes::new(Vector4::new(
        z(1.0, 0.5),
        z(0.0, 1.0),
        z(2.0, 0.0),
        z(-1.0, 0.0),
    ))
    .unwrap();
    let b = GeneralizedStokes::new(Vector4::new(
        z(0.5, 0.0),
        z(1.0, 1.0),
        z(0.0, -2.0),
        z(3.0, 0.0),
    ))
    .unwrap();
    let s = (a + b).vector();
    assert_eq!(s[1], z(1.0, 2.0));
    assert_eq!((a - b).vector()[2], z(2.0, 2.0));
    assert_eq!((-a).vector()[0], z(-1.0, -0.5));
    assert_eq!((a * 2.0).vector()[0], z(2.0, 1.0));
    assert_eq!((a * z(0.0, 1.0)).vector()[0], z(-0.5, 1.0));
    assert!(
        GeneralizedStokes::new(Vector4::new(
            z(f64::NAN, 0.0),
            z(0.0, 0.0),
            z(0.0, 0.0),
            z(0.0, 0.0)
        ))
        .is_err()
    );
}

// ------------------------------------------------------------------ scale invariance, overflow

/// The powers of two from the smallest normal `T` up to `top`, and `top` itself.
fn scales<T: Real>(top: T) -> Vec<T> {
    let min_normal = T::max_value().unwrap().to_f64().recip() * 4.0; // 2⁻¹²⁶ f32, 2⁻¹⁰²² f64
    let mut out: Vec<T> = (-1100..1100)
        .map(|k| 2f64.powi(k))
        .filter(|&s| s >= min_normal && s <= top.to_f64())
        .map(T::lit)
        .collect();
    out.push(top);
    out
}

/// `Stokes::new` gives the same verdict at every scale, and every accepted vector has finite
/// degrees of polarization equal to the unscaled ones (`DoP = ∞` at MAX before: the polarized
/// norm overflowed and `∞ > S0·(1 + 64ε)` was false).
fn stokes_scale_invariance<T: Real>(tol: Tol) {
    let bases = [
        [1.0, 0.9, 0.9, 0.0],  // |S| = 1.27: invalid
        [1.0, 0.6, 0.8, 0.0],  // |S| = 1: valid, fully polarized
        [1.0, 0.6, 0.0, -0.8], // circular part
        [1.0, 0.3, -0.2, 0.1], // partially polarized
        [1.0, 0.6, 0.8, 0.01], // |S| = 1.00005: invalid
        [-1.0, 0.0, 0.0, 0.0], // S0 < 0
        [0.5, 0.0, 0.0, 0.0],  // unpolarized
    ];
    for b in bases {
        // Bases with max|Sₖ| = 1, so that the top scale is T::MAX itself.
        let max_entry = b.iter().fold(0.0f64, |m: f64, x: &f64| m.max(x.abs()));
        let b = b.map(|x| x / max_entry);
        let base = Stokes::new(T::lit(b[0]), T::lit(b[1]), T::lit(b[2]), T::lit(b[3]));
        for sc in scales(T::max_value().unwrap()) {
            let v = b.map(|x| T::lit(x) * sc);
            let r = Stokes::new(v[0], v[1], v[2], v[3]);
            let what = format!("{b:?} × {:e} ({})", sc.to_f64(), std::any::type_name::<T>());
            assert_eq!(r.is_ok(), base.is_ok(), "verdict changed: {what}: {r:?}");
            if let (Ok(s), Ok(b0)) = (r, &base) {
                for (name, got, want) in [
                    (
                        "DoP",
                        s.degree_of_polarization(),
                        b0.degree_of_polarization(),
                    ),
                    (
                        "DoLP",
                        s.degree_of_linear_polarization(),
                        b0.degree_of_linear_polarization(),
                    ),
                    (
                        "DoCP",
                        s.degree_of_circular_polarization(),
                        b0.degree_of_circular_polarization(),
                    ),
                    ("χ", s.ellipticity_angle(), b0.ellipticity_angle()),
                    ("ψ", s.azimuth(), b0.azimuth()),
                    (
                        "|S|/scale",
                        s.polarized_intensity() / sc,
                        b0.polarized_intensity(),
                    ),
                ] {
                    assert!(got.is_finite(), "{name} not finite: {what}");
                    assert_close(&format!("{name} {what}"), got.to_f64(), want.to_f64(), tol);
                }
                let c = s.to_csd();
                assert!(
                    c.matrix()
                        .iter()
                        .all(|z| z.re.is_finite() && z.im.is_finite()),
                    "CSD {what}"
                );
                let back = c.to_stokes().unwrap();
                assert!(back.vector().iter().all(|x| x.is_finite()), "back {what}");
                for (k, &bk) in b.iter().enumerate() {
                    assert_close(
                        &format!("S{k} back {what}"),
                        (back.vector()[k] / sc).to_f64(),
                        bk,
                        tol,
                    );
                }
            }
        }
    }
    let m = T::max_value().unwrap();
    let nine = T::lit(0.9);
    assert!(matches!(
        Stokes::new(m, nine * m, nine * m, T::zero()),
        Err(Error::InvalidStokes { .. })
    ));
}

#[test]
fn stokes_validity_is_scale_invariant() {
    stokes_scale_invariance::<f32>(Tol::new(0.0, 1e-6));
    stokes_scale_invariance::<f64>(Tol::new(0.0, 1e-15));
}

/// `CsdMatrix::one_point` gives the same verdict at every scale (a Hermitian PSD, a
/// non-Hermitian and an indefinite matrix), and the Stokes vector scales with the matrix.
fn csd_scale_invariance<T: Real>(tol: Tol) {
    let bases = [
        ([z(0.5, 0.0), z(0.1, -0.3), z(0.1, 0.3), z(0.25, 0.0)], true),
        (
            [z(0.5, 0.0), z(0.1, -0.3), z(0.1, 0.31), z(0.25, 0.0)],
            false,
        ), // not Hermitian
        ([z(0.5, 0.0), z(0.5, 0.0), z(0.5, 0.0), z(0.25, 0.0)], false), // det < 0
        ([z(0.0, 0.0), z(1.0, 1.0), z(0.0, 0.0), z(0.0, 0.0)], false),  // not Hermitian
    ];
    for (b, valid) in bases {
        let bm = Matrix2::new(b[0], b[1], b[2], b[3]);
        let base = CsdMatrix::one_point(bm.map(cz::<T>));
        assert_eq!(base.is_ok(), valid, "{bm:?}");
        // Stokes parameters reach 2·max part: keep them finite at the top scale.
        for sc in scales(T::max_value().unwrap() * T::lit(0.5)) {
            let c = CsdMatrix::one_point(bm.map(|x| cz::<T>(x) * sc));
            let what = format!(
                "{bm:?} × {:e} ({})",
                sc.to_f64(),
                std::any::type_name::<T>()
            );
            assert_eq!(c.is_ok(), valid, "verdict changed: {what}: {c:?}");
            if let (Ok(c), Ok(b0)) = (c, &base) {
                let (s, s0) = (c.to_stokes().unwrap(), b0.to_stokes().unwrap());
                for k in 0..4 {
                    let (got, want) = ((s.vector()[k] / sc).to_f64(), s0.vector()[k].to_f64());
                    assert_close(&format!("S{k} {what}"), got, want, tol);
                }
                assert!(s.degree_of_polarization().is_finite(), "DoP {what}");
            }
        }
    }
}

#[test]
fn csd_validity_is_scale_invariant() {
    csd_scale_invariance::<f32>(Tol::new(0.0, 1e-6));
    csd_scale_invariance::<f64>(Tol::new(0.0, 1e-15));
}

/// Entries near `T::MAX`: the asymmetry of `[[0, MAX + MAX·i], [0, 0]]` overflowed (∞ > tol·∞
/// is false) and it was accepted as Hermitian; `diag(MAX, MAX)` is Hermitian PSD but its
/// `S0 = 2·MAX` overflows (it was accepted, `to_stokes` gave S0 = ∞); the same for the
/// two-point CSD and for `E E†` with `|E| = 1e200`. The Stokes → CSD maps halve before adding.
fn csd_overflow<T: Real>() {
    let m = T::max_value().unwrap();
    let zc = |re: T, im: T| Complex::new(re, im);
    let (o, big) = (zc(T::zero(), T::zero()), zc(m, m));
    assert!(matches!(
        CsdMatrix::one_point(Matrix2::new(o, big, o, o)),
        Err(Error::NotHermitian { .. })
    ));
    let diag = Matrix2::new(zc(m, T::zero()), o, o, zc(m, T::zero()));
    for r in [CsdMatrix::one_point(diag), CsdMatrix::two_point(diag)] {
        assert!(
            matches!(r, Err(Error::NonFinite { what }) if what.contains("Stokes")),
            "{r:?}"
        );
    }
    let half = T::lit(0.5);
    let ok = Matrix2::new(zc(m * half, T::zero()), o, o, zc(m * half, T::zero()));
    let s = CsdMatrix::one_point(ok).unwrap().to_stokes().unwrap();
    assert_eq!(s.s0(), m);
    let e = JonesVector::new(zc(T::lit(1e200f64.min(m.to_f64())), T::zero()), o).unwrap();
    assert!(matches!(
        CsdMatrix::from_jones_vector(&e),
        Err(Error::NonFinite { .. })
    ));
    // Stokes → CSD at the top of the range: C_xx = (S0 + S1)/2 = MAX, finite.
    let c = Stokes::new(m, m, T::zero(), T::zero()).unwrap().to_csd();
    assert_eq!(c.matrix()[(0, 0)].re, m);
    assert!(
        c.matrix()
            .iter()
            .all(|z| z.re.is_finite() && z.im.is_finite())
    );
    let g = GeneralizedStokes::new(Vector4::new(big, big, big, big))
        .unwrap()
        .to_csd();
    assert!(
        g.matrix()
            .iter()
            .all(|z| z.re.is_finite() && z.im.is_finite())
    );
}

#[test]
fn csd_overflow_is_rejected_or_avoided() {
    csd_overflow::<f32>();
    csd_overflow::<f64>();
}
