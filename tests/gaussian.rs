//! Verifies `gmueller::gaussian`: evaluation against the literal formula, Lemma S2.1 (corrected, and
//! the printed form failing) and Corollary S2.2 against direct numerical Fourier quadrature in 2-D
//! and 3-D, product/convolution closed forms and Parseval against quadrature, marginal vs section,
//! and stability at extreme scales.

use crate::common;

use common::{F64, Tol, assert_close};
use gmueller::Error;
use gmueller::gaussian::Gaussian;
use gmueller::verify::oracle;
use nalgebra::{Matrix2, Matrix3, Rotation2, Rotation3, SVector, Vector2, Vector3};
use num_complex::Complex;
use proptest::prelude::*;

const TAU: f64 = std::f64::consts::TAU;

/// The literal `exp(−½ xᵀΣ⁻¹x)` with nalgebra's general inverse (the kit's oracle).
use oracle::gaussian as literal;

/// The unitary Fourier transform by the trapezoid rule over the cube `[−half, half]ᴺ` with `n`
/// points per axis (spectrally accurate for Gaussians decayed at the boundary): an independent
/// numerical Fourier transform (the kit's oracle).
use oracle::fourier_transform as fourier_quad;

/// `∫ f dᴺx` by the same trapezoid rule (no prefactor).
fn integral_quad<const N: usize>(f: impl Fn(&SVector<f64, N>) -> f64, half: f64, n: usize) -> f64 {
    let z = SVector::<f64, N>::zeros();
    fourier_quad(|x| Complex::new(f(x), 0.0), &z, half, n).re * TAU.powf(N as f64 / 2.0)
}

fn sym2(a: f64, b: f64, c: f64) -> Matrix2<f64> {
    Matrix2::new(a, b, b, c)
}

fn sym3() -> Matrix3<f64> {
    Matrix3::new(1.0, 0.3, -0.2, 0.3, 0.7, 0.15, -0.2, 0.15, 0.5)
}

/// Quadrature tolerance: the trapezoid sums below are converged to ~1e-12.
const QUAD: Tol = Tol::new(1e-10, 1e-9);

#[test]
fn rejects_invalid_covariances() {
    assert!(matches!(
        Gaussian::new(sym2(1.0, f64::NAN, 1.0)),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        Gaussian::new(sym2(1.0, 2.0, 1.0)),
        Err(Error::NotPositiveDefinite { .. })
    ));
    assert!(matches!(
        Gaussian::new(Matrix2::new(1.0, 0.5, 0.0, 1.0)),
        Err(Error::NotHermitian { .. })
    ));
    assert!(matches!(
        Gaussian::<f64, 2>::isotropic(0.0),
        Err(Error::OutOfRange { .. })
    ));
}

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn value_logdet_precision_match_literal(cov in common::spd2(), x in common::real(3.0), y in common::real(3.0)) {
        let g = Gaussian::new(cov).unwrap();
        let v = Vector2::new(x, y);
        let lit = literal(&cov, &v);
        prop_assert!(F64.accepts(g.value(&v), lit), "{} vs {}", g.value(&v), lit);
        prop_assert!(F64.accepts(g.log_det(), cov.determinant().ln()));
        let inv = cov.try_inverse().unwrap();
        for (a, b) in g.precision().iter().zip(inv.iter()) {
            prop_assert!(Tol::new(1e-10, 1e-10).accepts(*a, *b));
        }
        let dens = lit / (TAU * cov.determinant().sqrt());
        prop_assert!(F64.accepts(g.density(&v), dens));
    }

    /// Closed-form product: g^A g^B = g^{(A⁻¹+B⁻¹)⁻¹} pointwise.
    #[test]
    fn product_is_pointwise(a in common::spd2(), b in common::spd2(), x in common::real(2.0), y in common::real(2.0)) {
        let (ga, gb) = (Gaussian::new(a).unwrap(), Gaussian::new(b).unwrap());
        let v = Vector2::new(x, y);
        let p = ga.product(&gb).unwrap();
        prop_assert!(F64.accepts(p.value(&v), literal(&a, &v) * literal(&b, &v)));
        // Shifted product.
        let (sa, sb) = (Vector2::new(0.3, -0.2), Vector2::new(-0.5, 0.4));
        let (sg, c) = ga.product_shifted(&sa, &gb, &sb).unwrap();
        let lhs = literal(&a, &(v - sa)) * literal(&b, &(v - sb));
        prop_assert!(Tol::new(1e-12, 1e-10).accepts(sg.value(&(v - c)), lhs));
    }
}

#[test]
fn density_integrates_to_one() {
    let g = Gaussian::new(sym2(0.8, 0.3, 0.4)).unwrap();
    let i = integral_quad(|x: &Vector2<f64>| g.density(x), 8.0, 201);
    assert_close("∫ density (2-D)", i, 1.0, QUAD);
    let g3 = Gaussian::new(sym3()).unwrap();
    let i3 = integral_quad(|x: &Vector3<f64>| g3.density(x), 7.0, 81);
    assert_close("∫ density (3-D)", i3, 1.0, QUAD);
    assert_close(
        "log_integral",
        g3.log_integral(),
        i3.ln() - g3.density(&Vector3::zeros()).ln(),
        QUAD,
    );
}

/// Printed Lemma S2.1: `|Σ|^{1/2}/|B| · g^{Σ⁻¹}(B⁻¹ q)` with `|B| = det B` (the kit's oracle).
use oracle::lemma_s2_1_printed as lemma_printed;

#[test]
fn lemma_s2_1_matches_quadrature_2d() {
    let cov = sym2(1.0, 0.3, 0.5);
    let b = Matrix2::new(1.0, 0.8, 1.3, -0.2); // non-symmetric, det < 0
    let g = Gaussian::new(cov).unwrap();
    for q in [
        Vector2::new(0.9, -0.6),
        Vector2::new(-1.5, 2.0),
        Vector2::new(0.0, 1.1),
    ] {
        let quad = oracle::lemma_s2_1_by_quadrature(&cov, &b, &q, 301);
        let lemma = g.fourier_of_linear_map(&b, &q).unwrap();
        assert_close("Lemma S2.1 (corrected) re", lemma, quad.re, QUAD);
        assert_close("Lemma S2.1 im", quad.im, 0.0, QUAD);
    }
}

#[test]
fn lemma_s2_1_matches_quadrature_3d() {
    let cov = sym3();
    let b = Matrix3::new(1.0, 0.4, 0.0, -0.3, 0.9, 0.5, 0.2, 0.0, 1.2);
    let g = Gaussian::new(cov).unwrap();
    let q = Vector3::new(0.8, -0.5, 1.1);
    let quad = oracle::lemma_s2_1_by_quadrature(&cov, &b, &q, 91);
    assert_close(
        "Lemma S2.1 (corrected, 3-D)",
        g.fourier_of_linear_map(&b, &q).unwrap(),
        quad.re,
        QUAD,
    );
}

/// Errata: the printed `B⁻¹ q` and signed `|B|` disagree with quadrature for a non-symmetric B.
#[test]
fn lemma_s2_1_printed_form_fails() {
    let cov = sym2(1.0, 0.3, 0.5);
    let b = Matrix2::new(1.0, 0.8, 1.3, -0.2);
    let q = Vector2::new(0.9, -0.6);
    let quad = oracle::lemma_s2_1_by_quadrature(&cov, &b, &q, 301).re;
    let printed = lemma_printed(&cov, &b, &q);
    assert!(
        (printed - quad).abs() > 0.05 * quad.abs(),
        "printed {printed} vs quadrature {quad}"
    );
    // Even with |det B|, the argument B⁻¹q is wrong for non-symmetric B:
    assert!(
        (printed.abs() - quad).abs() > 0.05 * quad.abs(),
        "|printed| {} vs {quad}",
        printed.abs()
    );
    // 3-D, positive det: only the argument differs.
    let cov3 = sym3();
    let b3 = Matrix3::new(1.0, 0.4, 0.0, -0.3, 0.9, 0.5, 0.2, 0.0, 1.2);
    assert!(b3.determinant() > 0.0);
    let q3 = Vector3::new(0.8, -0.5, 1.1);
    let quad3 = oracle::lemma_s2_1_by_quadrature(&cov3, &b3, &q3, 71).re;
    let printed3 = lemma_printed(&cov3, &b3, &q3);
    assert!(
        (printed3 - quad3).abs() > 0.05 * quad3.abs(),
        "printed {printed3} vs {quad3}"
    );
    // For a symmetric B the two forms agree (the printed lemma is right there).
    let bs = sym2(1.2, 0.4, 0.9);
    assert_close(
        "printed = corrected for symmetric B",
        lemma_printed(&cov, &bs, &q),
        Gaussian::new(cov)
            .unwrap()
            .fourier_of_linear_map(&bs, &q)
            .unwrap(),
        F64,
    );
}

/// Corollary S2.2: F{e^{−ikŝ·ξ} g^Θ(Qᵀξ)}(q) = |Θ|^{1/2} g^{Θ⁻¹}(Qᵀ(q + kŝ)), Q local → world.
#[test]
fn corollary_s2_2_matches_quadrature_2d() {
    let theta = sym2(1.5, 0.4, 0.3); // anisotropic, local coordinates
    let rot = Rotation2::new(0.7);
    let ks = Vector2::new(1.2, -0.7);
    let g = Gaussian::new(theta).unwrap();
    let qm = *rot.matrix();
    let f = |x: &Vector2<f64>| {
        literal(&theta, &(qm.transpose() * x)) * Complex::from_polar(1.0, -ks.dot(x))
    };
    for q in [
        Vector2::new(-1.0, 0.5),
        Vector2::new(-0.6, 1.0),
        Vector2::new(0.3, 0.2),
    ] {
        let quad = fourier_quad(f, &q, 12.0, 301);
        let cor = g.fourier_of_packet_term(&rot, &ks, &q).unwrap();
        assert_close("Corollary S2.2 re", cor, quad.re, QUAD);
        assert_close("Corollary S2.2 im", quad.im, 0.0, QUAD);
        // Ξ = Q Θ⁻¹ Qᵀ (S2.18): the same value from the world-frame Gaussian g^Ξ.
        let xi = g.inverse().unwrap().rotated(&rot).unwrap();
        assert_close(
            "Ξ = QΘ⁻¹Qᵀ",
            g.det().sqrt() * xi.value(&(q + ks)),
            quad.re,
            QUAD,
        );
    }
    // The opposite shift (q − kŝ) and the opposite direction of Q both fail.
    let q = Vector2::new(-0.6, 1.0);
    let quad = fourier_quad(f, &q, 12.0, 301).re;
    let wrong_shift = g.fourier_of_packet_term(&rot, &(-ks), &q).unwrap();
    let wrong_q = g.fourier_of_packet_term(&rot.inverse(), &ks, &q).unwrap();
    assert!(
        (wrong_shift - quad).abs() > 0.05 * quad,
        "{wrong_shift} vs {quad}"
    );
    assert!((wrong_q - quad).abs() > 0.05 * quad, "{wrong_q} vs {quad}");
}

#[test]
fn corollary_s2_2_matches_quadrature_3d() {
    let theta = Matrix3::new(1.2, 0.2, 0.0, 0.2, 0.4, 0.0, 0.0, 0.0, 0.8);
    let rot = Rotation3::from_euler_angles(0.3, -0.5, 0.9);
    let ks = Vector3::new(0.4, -0.3, 0.9);
    let g = Gaussian::new(theta).unwrap();
    let qm = *rot.matrix();
    let f = |x: &Vector3<f64>| {
        literal(&theta, &(qm.transpose() * x)) * Complex::from_polar(1.0, -ks.dot(x))
    };
    let q = Vector3::new(-0.2, 0.5, -0.4);
    let quad = fourier_quad(f, &q, 10.0, 81);
    assert_close(
        "Corollary S2.2 (3-D) re",
        g.fourier_of_packet_term(&rot, &ks, &q).unwrap(),
        quad.re,
        QUAD,
    );
    assert_close("Corollary S2.2 (3-D) im", quad.im, 0.0, QUAD);
}

#[test]
fn shift_and_modulation_match_quadrature() {
    let cov = sym2(0.6, -0.2, 0.9);
    let g = Gaussian::new(cov).unwrap();
    let (a, k) = (Vector2::new(0.7, -0.3), Vector2::new(0.5, 1.0));
    let f = |x: &Vector2<f64>| literal(&cov, &(x - a)) * Complex::from_polar(1.0, k.dot(x));
    let q = Vector2::new(0.2, -0.4);
    let quad = fourier_quad(f, &q, 12.0, 301);
    let cf = g.fourier_shifted_modulated(&a, &k, &q).unwrap();
    assert_close("shift/modulation re", cf.re, quad.re, QUAD);
    assert_close("shift/modulation im", cf.im, quad.im, QUAD);
}

/// g^A * g^B = (|A||B|/|A+B|)^{1/2} g^{A+B} with (2π)^{−n/2}∫.
#[test]
fn convolution_matches_quadrature() {
    let (a, b) = (sym2(0.8, 0.3, 0.5), sym2(0.4, -0.1, 1.1));
    let (ga, gb) = (Gaussian::new(a).unwrap(), Gaussian::new(b).unwrap());
    let conv = ga.convolve(&gb).unwrap();
    for x in [
        Vector2::new(0.0, 0.0),
        Vector2::new(0.8, -1.2),
        Vector2::new(2.0, 1.0),
    ] {
        let quad = integral_quad(|y| literal(&a, y) * literal(&b, &(x - y)), 10.0, 241) / TAU;
        assert_close("convolution", conv.value(&x), quad, QUAD);
    }
    let expected_scale = (a.determinant() * b.determinant() / (a + b).determinant()).sqrt();
    assert_close("convolution constant", conv.scale(), expected_scale, F64);
}

/// Parseval: ∫|g|² dx = ∫|F{g}|² dq, both sides by quadrature (F{g} from `fourier`).
#[test]
fn parseval() {
    let cov = sym2(0.7, 0.25, 0.4);
    let g = Gaussian::new(cov).unwrap();
    let fg = g.fourier().unwrap();
    let lhs = integral_quad(|x| g.value(x).powi(2), 8.0, 201);
    let rhs = integral_quad(|q| fg.value(q).powi(2), 14.0, 301);
    assert_close("Parseval", lhs, rhs, QUAD);
    // And F{g} itself against quadrature.
    let q = Vector2::new(0.5, -1.0);
    assert_close(
        "F{g}",
        fg.value(&q),
        fourier_quad(|x| Complex::new(g.value(x), 0.0), &q, 8.0, 201).re,
        QUAD,
    );
}

/// Marginal (∫ dz) and section (z = 0) of a 3-D Gaussian, and that they differ when oblique.
#[test]
fn marginal_and_section() {
    let cov = sym3();
    let g = Gaussian::new(cov).unwrap();
    let marg = g.marginal_xy().unwrap();
    let sect = g.section_xy().unwrap();
    for v in [
        Vector2::new(0.0, 0.0),
        Vector2::new(0.5, -0.4),
        Vector2::new(-1.0, 0.7),
    ] {
        // Marginal: ∫ g(x, y, z) dz by the trapezoid rule.
        let n = 2001;
        let step = 16.0 / (n - 1) as f64;
        let m: f64 = (0..n)
            .map(|i| literal(&cov, &Vector3::new(v.x, v.y, -8.0 + step * i as f64)))
            .sum::<f64>()
            * step;
        assert_close("marginal", marg.value(&v), m, QUAD);
        assert_close(
            "section",
            sect.value(&v),
            literal(&cov, &Vector3::new(v.x, v.y, 0.0)),
            F64,
        );
    }
    // Schur complement vs the inverse of the precision block.
    let inv = cov.try_inverse().unwrap();
    let block = inv
        .fixed_view::<2, 2>(0, 0)
        .into_owned()
        .try_inverse()
        .unwrap();
    for (a, b) in sect.covariance().iter().zip(block.iter()) {
        assert_close("section covariance", *a, *b, F64);
    }
    // Oblique (non-zero Σ_xz, Σ_yz): the marginal block and the Schur complement differ.
    let diff = (marg.gaussian.covariance() - sect.covariance()).amax();
    assert!(
        diff > 0.05,
        "marginal vs section covariance differ by only {diff}"
    );
}

/// Eigenvalues 1e-12…1e12, anisotropy up to 1e6: finite, log-values accurate, underflow → 0.
#[test]
fn stability_extreme_scales() {
    for &scale in &[1e-12, 1e-6, 1.0, 1e6, 1e12] {
        for &aniso in &[1.0, 1e3, 1e6] {
            for &angle in &[0.0, 0.4, 1.3] {
                let (l1, l2) = (scale, scale / aniso);
                let r = Rotation2::new(angle);
                let v1 = r * Vector2::new(1.0, 0.0);
                let v2 = r * Vector2::new(0.0, 1.0);
                let cov = v1 * v1.transpose() * l1 + v2 * v2.transpose() * l2;
                let cov = (cov + cov.transpose()) * 0.5;
                let g = Gaussian::new(cov).unwrap();
                assert_close(
                    "log det",
                    g.log_det(),
                    l1.ln() + l2.ln(),
                    Tol::new(1e-9, 1e-9),
                );
                for &xs in &[0.0, 1e-7, 1.0, 1e7] {
                    let x = Vector2::new(0.6, -0.8) * xs * scale.sqrt();
                    let exact = -0.5 * (v1.dot(&x).powi(2) / l1 + v2.dot(&x).powi(2) / l2);
                    let lv = g.log_value(&x);
                    assert!(lv.is_finite());
                    assert_close("log value", lv, exact, Tol::new(1e-9, 1e-7));
                    let v = g.value(&x);
                    assert!(v.is_finite() && v >= 0.0);
                    if exact < -800.0 {
                        assert_eq!(v, 0.0, "underflow must give 0");
                    }
                    // f32: finite, never NaN.
                    let g32 = Gaussian::new(cov.cast::<f32>()).unwrap();
                    let v32 = g32.value(&x.cast::<f32>());
                    assert!(v32.is_finite() && v32 >= 0.0);
                    assert!(g32.log_value(&x.cast::<f32>()).is_finite() || exact < -1e37);
                    if exact.abs() < 50.0 {
                        assert_close(
                            "f32 log value",
                            f64::from(g32.log_value(&x.cast::<f32>())),
                            exact,
                            Tol::new(1e-3, 1e-2),
                        );
                    }
                }
            }
        }
    }
}

// ------------------------------------------------------------------ bad input (f32 and f64)

/// The transforms return `Err(NonFinite)` naming the argument for NaN and ±∞ (they returned
/// `Ok(NaN)` before).
fn transforms_reject_non_finite<T: gmueller::Real>() {
    let g = Gaussian::<T, 2>::new(Matrix2::new(2.0, 0.5, 0.5, 1.0).map(T::lit)).unwrap();
    let one = Vector2::new(T::lit(0.3), T::lit(-0.2));
    let rot = Rotation2::new(T::lit(0.4));
    let names = |r: Result<(), Error>, name: &str, case: &str| match r {
        Err(Error::NonFinite { what }) => assert!(what.contains(name), "{case}: {what}"),
        other => panic!("{case}: expected NonFinite naming {name}, got {other:?}"),
    };
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY].map(T::lit) {
        let v = Vector2::new(bad, T::one());
        let m = Matrix2::new(T::one(), T::zero(), bad, T::one());
        names(
            g.fourier_of_linear_map(&m, &one).map(drop),
            "linear map B",
            "lemma B",
        );
        names(
            g.fourier_of_linear_map(&Matrix2::identity(), &v).map(drop),
            "frequency q",
            "lemma q",
        );
        names(
            g.product_shifted(&v, &g, &one).map(drop),
            "shift a",
            "product a",
        );
        names(
            g.product_shifted(&one, &g, &v).map(drop),
            "shift b",
            "product b",
        );
        names(
            g.fourier_shifted_modulated(&v, &one, &one).map(drop),
            "shift a",
            "fsm a",
        );
        names(
            g.fourier_shifted_modulated(&one, &v, &one).map(drop),
            "modulation k",
            "fsm k",
        );
        names(
            g.fourier_shifted_modulated(&one, &one, &v).map(drop),
            "frequency q",
            "fsm q",
        );
        names(
            g.fourier_of_packet_term(&rot, &v, &one).map(drop),
            "k ŝ",
            "corollary k_s",
        );
        names(
            g.fourier_of_packet_term(&rot, &one, &v).map(drop),
            "frequency q",
            "corollary q",
        );
    }
}

#[test]
fn transforms_reject_non_finite_input() {
    transforms_reject_non_finite::<f32>();
    transforms_reject_non_finite::<f64>();
}

/// At huge finite points the value is 0 and the log-value −∞ (the plain substitution gave NaN
/// from 0·∞ when an off-diagonal Cholesky entry is 0); the same for `density`,
/// `mahalanobis_sq` (+∞) and `ScaledGaussian::value`. Moderate points keep the literal value.
fn huge_points_give_zero<T: gmueller::Real>(huge: f64) {
    let g = Gaussian::<T, 2>::new(Matrix2::new(1e-20, 0.0, 0.0, 1.0).map(T::lit)).unwrap();
    let conv = g.convolve(&g).unwrap();
    for x in [
        Vector2::new(huge, 1.0),
        Vector2::new(huge, -huge),
        Vector2::new(-huge, 0.0),
        Vector2::new(0.0, huge),
    ] {
        let x = x.map(T::lit);
        let what = format!("{} at {x:?}", std::any::type_name::<T>());
        assert_eq!(
            g.mahalanobis_sq(&x).to_f64(),
            f64::INFINITY,
            "mahalanobis {what}"
        );
        assert_eq!(
            g.log_value(&x).to_f64(),
            f64::NEG_INFINITY,
            "log_value {what}"
        );
        assert_eq!(g.value(&x).to_f64(), 0.0, "value {what}");
        assert_eq!(g.density(&x).to_f64(), 0.0, "density {what}");
        assert_eq!(
            g.log_density(&x).to_f64(),
            f64::NEG_INFINITY,
            "log_density {what}"
        );
        assert_eq!(conv.value(&x).to_f64(), 0.0, "ScaledGaussian::value {what}");
        assert_eq!(
            g.log_value_of_inverse(&x).to_f64(),
            f64::NEG_INFINITY,
            "inverse {what}"
        );
    }
    // Oracle: the literal exp(−½ xᵀΣ⁻¹x) for Σ = diag(1e-20, 1), x = (1e-10, 2).
    let x = Vector2::new(T::lit(1e-10), T::lit(2.0));
    assert_close(
        "mahalanobis",
        g.mahalanobis_sq(&x).to_f64(),
        5.0,
        Tol::new(0.0, 1e-6),
    );
}

#[test]
fn huge_finite_points_give_zero_never_nan() {
    huge_points_give_zero::<f32>(3e38);
    huge_points_give_zero::<f64>(1e300);
}

/// `qᵀΣq` where the products `Lⱼᵢ qⱼ` overflow: Σ = L Lᵀ with L = [[2, 0], [2, 1]] and
/// `q = (T::MAX, −T::MAX)` give `Lᵀq = (2·MAX − 2·MAX, −MAX)`, by hand `qᵀΣq = MAX²` = +∞, so
/// `ln g^{Σ⁻¹}(q) = −∞` (the plain product gave ∞ − ∞ = NaN); with q scaled by 2⁻⁶⁰⁰ (f64)
/// the same vector gives exactly `−½ (2⁻⁶⁰⁰·MAX)²`.
fn inverse_at_overflowing_products<T: gmueller::Real>() {
    let max = T::max_value().unwrap();
    let g = Gaussian::<T, 2>::new(Matrix2::new(4.0, 4.0, 4.0, 5.0).map(T::lit)).unwrap();
    let q = Vector2::new(max, -max);
    assert_eq!(g.log_value_of_inverse(&q).to_f64(), f64::NEG_INFINITY);
    assert_eq!(g.log_fourier_at(&q).to_f64(), f64::NEG_INFINITY);
}

#[test]
fn log_value_of_inverse_at_overflowing_products_is_minus_infinity() {
    inverse_at_overflowing_products::<f32>();
    inverse_at_overflowing_products::<f64>();
    let g = Gaussian::<f64, 2>::new(Matrix2::new(4.0, 4.0, 4.0, 5.0)).unwrap();
    let m = f64::MAX * 2f64.powi(-600);
    assert_close(
        "−½ qᵀΣq",
        g.log_value_of_inverse(&Vector2::new(m, -m)),
        -0.5 * m * m,
        Tol::new(0.0, 1e-15),
    );
}

/// Lemma S2.1 for `B = 10⁻¹¹⁰ diag(1, 2, 3)` (|det B| = 6·10⁻³³⁰ underflows f64, so the
/// unscaled inverse reported `Singular`): by hand, with Σ = I and `B⁻ᵀq = (40, 0, 0)`,
/// `ln F = −½·40² − ln 6 + 330 ln 10`.
#[test]
fn lemma_s2_1_tiny_b_is_not_singular() {
    let g = Gaussian::<f64, 3>::isotropic(1.0).unwrap();
    let b = Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 3.0)) * 1e-110;
    let q = Vector3::new(40e-110, 0.0, 0.0);
    let expected = (-800.0 - 6f64.ln() + 330.0 * 10f64.ln()).exp();
    let got = g.fourier_of_linear_map(&b, &q).unwrap();
    assert!(got.is_finite(), "{got}");
    assert_close("lemma, tiny B", got, expected, Tol::new(0.0, 1e-12));
    // A truly singular B is still rejected.
    let sing = Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 0.0, 1.0);
    assert!(matches!(
        g.fourier_of_linear_map(&sing, &q),
        Err(Error::Singular { .. })
    ));
}

/// Overflowing intermediates of the shifted forms: an error naming the quantity, or 0 —
/// never NaN. `c = ½(a + b)` for equal shapes overflows at `a = b = 0.9·T::MAX`; `q − k`
/// overflowing gives 0 (far in the tail); a phase `(q − k)·a = 2·T::MAX` with a non-zero
/// magnitude (`q − k = (1, 1)`) is an error.
fn shifted_forms_overflow<T: gmueller::Real>() {
    let max = T::max_value().unwrap();
    let g = Gaussian::<T, 2>::new(Matrix2::new(2.0, 0.5, 0.5, 1.0).map(T::lit)).unwrap();
    let big = Vector2::new(max * T::lit(0.9), T::zero());
    match g.product_shifted(&big, &g, &big) {
        Err(Error::NonFinite { what }) => assert!(what.contains("centre"), "{what}"),
        other => panic!("product centre: {:?}", other.map(|(s, c)| (s.log_scale, c))),
    }
    let (sg, c) = g.product_shifted(&big, &g, &(-big)).unwrap();
    assert_eq!(sg.log_scale.to_f64(), f64::NEG_INFINITY);
    assert!(c.iter().all(|v| v.is_finite()));
    let z = Vector2::zeros();
    let far = g.fourier_shifted_modulated(&z, &(-big), &big).unwrap();
    assert_eq!((far.re.to_f64(), far.im.to_f64()), (0.0, 0.0));
    let rot = Rotation2::new(T::lit(0.4));
    assert_eq!(
        g.fourier_of_packet_term(&rot, &big, &big).unwrap().to_f64(),
        0.0
    );
    let near = Vector2::new(T::one(), T::one());
    let r = g.fourier_shifted_modulated(&Vector2::new(max, max), &z, &near);
    assert!(
        matches!(r, Err(Error::NonFinite { what }) if what.contains("phase")),
        "{r:?}"
    );
}

#[test]
fn shifted_forms_overflow_to_an_error_or_zero() {
    shifted_forms_overflow::<f32>();
    shifted_forms_overflow::<f64>();
}
