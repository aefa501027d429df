//! Verifies S1.4–S1.7 and Mueller analysis: the closed forms of `Mueller::from_jones` and
//! `GeneralizedMueller::from_jones_pair` against the literal `A_mül [J₂* ⊗ J₁] A_mül⁻¹` (and the
//! Pauli-trace identity), realness for p₁ = p₂, the generalized Mueller matrix acting on gSP versus
//! the Jones pair acting on a two-point CSD, a Monte Carlo check of S1.7 over field realizations,
//! Cloude realizability, diattenuation / polarizance / depolarization index of known elements and
//! the Lu–Chipman decomposition (recomposition and recovery of known factors); scale invariance of
//! every analysis function at `10^±30` (f32) and `10^±300` (f64), with D, P, `P_Δ` of
//! `10¹⁰·diag(2, 1)` checked against the hand values; and finite coherency eigenvalues for 10⁵
//! random f32 and f64 Jones-derived matrices (three within 64ε·tr H of 0).

use crate::common;

use common::{
    F32, F64, Tol, assert_all_close, assert_close, assert_complex_close, complex_matrix2, entries4,
    stokes_vector,
};
use gmueller::Error;
use gmueller::jones::JonesMatrix;
use gmueller::mueller::{GeneralizedMueller, Mueller};
use gmueller::real::Real;
use gmueller::stack::{kron, stack, stack_rows};
use gmueller::stokes::{CsdMatrix, Stokes, a_mul, a_mul_inv};
use nalgebra::{Matrix2, Matrix4, Vector4};
use num_complex::Complex;
use proptest::prelude::*;

fn z(re: f64, im: f64) -> Complex<f64> {
    Complex::new(re, im)
}

fn to_t<T: Real>(m: &Matrix2<Complex<f64>>) -> Matrix2<Complex<T>> {
    m.map(|c| Complex::new(T::lit(c.re), T::lit(c.im)))
}

fn back44<T: Real>(m: &Matrix4<Complex<T>>) -> Vec<Complex<f64>> {
    m.iter()
        .map(|c| Complex::new(c.re.to_f64(), c.im.to_f64()))
        .collect()
}

/// The literal S1.7: `A_mül [J₂* ⊗ J₁] A_mül⁻¹` (the oracle).
fn literal<T: Real>(j1: &Matrix2<Complex<T>>, j2: &Matrix2<Complex<T>>) -> Matrix4<Complex<T>> {
    a_mul::<T>() * kron(&j2.conjugate(), j1) * a_mul_inv::<T>()
}

fn pauli(k: usize) -> Matrix2<Complex<f64>> {
    let (o, n, i) = (z(1.0, 0.0), z(0.0, 0.0), z(0.0, 1.0));
    [
        Matrix2::new(o, n, n, o),
        Matrix2::new(o, n, n, -o),
        Matrix2::new(n, o, o, n),
        Matrix2::new(n, -i, i, n),
    ][k]
}

fn from_jones_vs_literal<T: Real>(j: &Matrix2<Complex<f64>>, tol: Tol) {
    let jt = to_t::<T>(j);
    let m = Mueller::from_jones(&JonesMatrix::from_matrix(jt).unwrap()).matrix();
    let lit = literal(&jt, &jt);
    let m_c: Vec<Complex<f64>> = m.iter().map(|x| z(x.to_f64(), 0.0)).collect();
    // Equality with the complex literal also asserts that its imaginary part vanishes (S1.7 realness).
    assert_complex_close("from_jones vs A(J*⊗J)A⁻¹", m_c, back44(&lit), tol);
}

fn pair_vs_literal<T: Real>(j1: &Matrix2<Complex<f64>>, j2: &Matrix2<Complex<f64>>, tol: Tol) {
    let (a, b) = (to_t::<T>(j1), to_t::<T>(j2));
    let g = GeneralizedMueller::from_jones_pair(
        &JonesMatrix::from_matrix(a).unwrap(),
        &JonesMatrix::from_matrix(b).unwrap(),
    );
    assert_complex_close(
        "from_jones_pair vs literal",
        back44(&g.matrix()),
        back44(&literal(&a, &b)),
        tol,
    );
}

/// Partial diattenuator with transmission axis at θ: R(−θ) diag(1, q) R(θ).
fn diattenuator(theta: f64, q: f64) -> JonesMatrix<f64> {
    let (s, c) = theta.sin_cos();
    let r = Matrix2::new(z(c, 0.0), z(s, 0.0), z(-s, 0.0), z(c, 0.0));
    let d = Matrix2::new(z(1.0, 0.0), z(0.0, 0.0), z(0.0, 0.0), z(q, 0.0));
    JonesMatrix::from_matrix(r.transpose() * d * r).unwrap()
}

fn diag(a: f64, b: f64, c: f64, d: f64) -> Mueller<f64> {
    Mueller::from_matrix(Matrix4::from_diagonal(&Vector4::new(a, b, c, d))).unwrap()
}

/// `S0 ≥ |S|` up to a relative rounding slack.
fn is_valid_stokes(v: &Vector4<f64>, rel: f64) -> bool {
    let p = (v[1] * v[1] + v[2] * v[2] + v[3] * v[3]).sqrt();
    v[0] >= 0.0 && p <= v[0] * (1.0 + rel) + rel
}

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn from_jones_equals_literal_s1_7(j in complex_matrix2(1.0)) {
        from_jones_vs_literal::<f64>(&j, F64);
        from_jones_vs_literal::<f32>(&j, F32);
    }

    #[test]
    fn from_jones_pair_equals_literal_s1_7(j1 in complex_matrix2(1.0), j2 in complex_matrix2(1.0)) {
        pair_vs_literal::<f64>(&j1, &j2, F64);
        pair_vs_literal::<f32>(&j1, &j2, F32);
    }

    #[test]
    fn pauli_trace_identity_equals_literal(j1 in complex_matrix2(1.0), j2 in complex_matrix2(1.0)) {
        // 𝓜_kl = ½ tr(σ_k J₁ σ_l J₂†), written independently of the crate.
        let lit = literal(&j1, &j2);
        let tr = Matrix4::from_fn(|k, l| (pauli(k) * j1 * pauli(l) * j2.adjoint()).trace() * 0.5);
        assert_complex_close("½ tr(σ_k J₁ σ_l J₂†) vs literal", tr.iter().copied(), lit.iter().copied(), F64);
    }

    #[test]
    fn s1_4_to_s1_6_generalized_mueller_acts_like_jones_pair(j1 in complex_matrix2(1.0), j2 in complex_matrix2(1.0), c in complex_matrix2(1.0)) {
        let g = GeneralizedMueller::from_jones_pair(&JonesMatrix::from_matrix(j1).unwrap(), &JonesMatrix::from_matrix(j2).unwrap());
        let csd = CsdMatrix::two_point(c).unwrap();
        let out = (g * csd.to_generalized_stokes()).vector();
        // S1.4 then S1.2, literally: A_mül vec(J₁ C J₂†).
        let expect = a_mul::<f64>() * stack(&(j1 * c * j2.adjoint()));
        assert_complex_close("𝓜 S vs A vec(J₁CJ₂†)", out.iter().copied(), expect.iter().copied(), F64);
    }

    #[test]
    fn same_point_pair_is_real_classical_mueller(j in complex_matrix2(1.0)) {
        let jm = JonesMatrix::from_matrix(j).unwrap();
        let g = GeneralizedMueller::from_jones_pair(&jm, &jm).matrix();
        let m = Mueller::from_jones(&jm).matrix();
        assert_complex_close("from_jones_pair(J, J) vs from_jones(J)", g.iter().copied(), m.iter().map(|&x| z(x, 0.0)), F64);
        let gm = GeneralizedMueller::from_mueller(&Mueller::from_jones(&jm)).matrix();
        assert_complex_close("from_mueller", gm.iter().copied(), g.iter().copied(), F64);
    }

    #[test]
    fn generalized_composition(a1 in complex_matrix2(1.0), a2 in complex_matrix2(1.0), b1 in complex_matrix2(1.0), b2 in complex_matrix2(1.0)) {
        let jm = |m| JonesMatrix::from_matrix(m).unwrap();
        let first = GeneralizedMueller::from_jones_pair(&jm(a1), &jm(a2));
        let second = GeneralizedMueller::from_jones_pair(&jm(b1), &jm(b2));
        let both = GeneralizedMueller::from_jones_pair(&(jm(b1) * jm(a1)), &(jm(b2) * jm(a2)));
        assert_complex_close("𝓜(B)𝓜(A) vs 𝓜(BA)", (second * first).matrix().iter().copied(), both.matrix().iter().copied(), F64);
    }

    #[test]
    fn s1_7_monte_carlo_over_field_realizations(j in complex_matrix2(1.0), seed in any::<u64>()) {
        // Random partially polarized fields E_n; average per-sample Stokes of J E_n
        // equals M · (average per-sample Stokes of E_n).
        let mut state = seed;
        let mut u = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let stokes_of = |ex: Complex<f64>, ey: Complex<f64>| {
            Vector4::new(ex.norm_sqr() + ey.norm_sqr(), ex.norm_sqr() - ey.norm_sqr(), 2.0 * (ex.conj() * ey).re, 2.0 * (ex.conj() * ey).im)
        };
        let (px, py) = (z(u(), u()), z(u(), u()));
        let n = 200;
        let (mut s_in, mut s_out) = (Vector4::zeros(), Vector4::zeros());
        for _ in 0..n {
            let ph = z(u(), u());
            let (ex, ey) = (px * ph + z(u(), u()) * 0.5, py * ph + z(u(), u()) * 0.5);
            s_in += stokes_of(ex, ey) / n as f64;
            let (ox, oy) = (j[(0, 0)] * ex + j[(0, 1)] * ey, j[(1, 0)] * ex + j[(1, 1)] * ey);
            s_out += stokes_of(ox, oy) / n as f64;
        }
        let m = Mueller::from_jones(&JonesMatrix::from_matrix(j).unwrap());
        let pred = (m * Stokes::new(s_in[0], s_in[1], s_in[2], s_in[3]).unwrap()).vector();
        assert_all_close("⟨S(JE)⟩ vs M⟨S(E)⟩", pred.iter().copied(), s_out.iter().copied(), F64);
    }

    #[test]
    fn jones_derived_mueller_is_cloude_rank_one(j in complex_matrix2(1.0), v in stokes_vector()) {
        let jm = JonesMatrix::from_matrix(j).unwrap();
        let m = Mueller::from_jones(&jm);
        let m00 = m.matrix()[(0, 0)];
        prop_assume!(m00 > 1e-3);
        // H = ½ vec_r(J) vec_r(J)† (derived in the docs from Pauli completeness).
        let vr = stack_rows(&j);
        let h_expect = vr * vr.adjoint() * z(0.5, 0.0);
        assert_complex_close("H vs ½ vec_r(J) vec_r(J)†", m.coherency_matrix().iter().copied(), h_expect.iter().copied(), F64);
        let l = m.coherency_eigenvalues();
        assert_close("λ₀ = tr H = M00", l[0], m00, F64);
        for k in 1..4 {
            assert_close("λ_k = 0", l[k], 0.0, Tol::new(1e-12 * m00, 0.0));
        }
        prop_assert!(l[0] >= l[1] && l[1] >= l[2] && l[2] >= l[3]);
        prop_assert!(m.is_physically_realizable(1e-12));
        assert_close("depolarization index", m.depolarization_index(), 1.0, Tol::new(1e-12, 1e-12));
        // Maps valid Stokes to valid Stokes.
        let out = (m * Stokes::new(v[0], v[1], v[2], v[3]).unwrap()).vector();
        prop_assert!(is_valid_stokes(&out, 1e-12), "{out:?}");
    }

    #[test]
    fn lu_chipman_recomposes(j in complex_matrix2(1.0), a in -1.0..1.0f64, b in -1.0..1.0f64, c in -1.0..1.0f64) {
        let m = diag(1.0, a, b, c) * Mueller::from_jones(&JonesMatrix::from_matrix(j).unwrap());
        prop_assume!(m.matrix()[(0, 0)] > 1e-3 && m.diattenuation() < 0.99);
        let lc = m.lu_chipman().unwrap();
        let scale = m.matrix()[(0, 0)];
        assert_all_close("M_Δ M_R M_D vs M", entries4(&lc.recompose().matrix()), entries4(&m.matrix()), Tol::new(1e-11 * scale, 1e-11));
        // M_R is a proper rotation, M_Δ's 3×3 block is symmetric.
        let r = lc.retarder.matrix().fixed_view::<3, 3>(1, 1).into_owned();
        assert_all_close("m_R m_Rᵀ = I", (r * r.transpose()).iter().copied(), nalgebra::Matrix3::<f64>::identity().iter().copied(), F64);
        assert_close("det m_R = 1", r.determinant(), 1.0, F64);
        let md = lc.depolarizer.matrix().fixed_view::<3, 3>(1, 1).into_owned();
        assert_all_close("m_Δ symmetric", md.iter().copied(), md.transpose().iter().copied(), Tol::new(1e-12, 1e-12));
        assert_close("D of M_D = D of M", lc.diattenuation(), m.diattenuation(), F64);
    }

    #[test]
    fn lu_chipman_recovers_known_factors(th_r in common::angle(), delta in 0.05..3.09f64, th_d in common::angle(), q in 0.05..1.0f64, a in 0.1..1.0f64, b in 0.1..1.0f64, c in 0.1..1.0f64) {
        let mr = Mueller::from_jones(&JonesMatrix::linear_retarder(th_r, delta));
        let md = Mueller::from_jones(&diattenuator(th_d, q));
        let mdep = diag(1.0, a, b, c);
        let m = mdep * mr * md;
        let lc = m.lu_chipman().unwrap();
        let tol = Tol::new(1e-11, 1e-11);
        assert_close("retardance", lc.retardance(), delta, tol);
        // Diattenuation of diag(1, q) in intensity: (1 − q²)/(1 + q²).
        assert_close("diattenuation", lc.diattenuation(), (1.0 - q * q) / (1.0 + q * q), F64);
        assert_all_close("M_R", entries4(&lc.retarder.matrix()), entries4(&mr.matrix()), tol);
        assert_all_close("M_D", entries4(&lc.diattenuator.matrix()), entries4(&md.matrix()), tol);
        assert_all_close("M_Δ", entries4(&lc.depolarizer.matrix()), entries4(&mdep.matrix()), tol);
    }

    #[test]
    fn depolarizer_family_realizability(a in -1.0..=1.0f64) {
        // H of diag(1, a, a, a) = ¼(I⊗I + a(σ₁⊗σ₁ + σ₂⊗σ₂ − σ₃⊗σ₃)); on the Bell basis the bracket
        // has eigenvalues (3, −1, −1, −1), so λ(H) = ((1 + 3a)/4, (1 − a)/4 ×3): realizable iff a ≥ −1/3.
        let m = diag(1.0, a, a, a);
        let l = m.coherency_eigenvalues();
        let mut expect = [(1.0 + 3.0 * a) / 4.0, (1.0 - a) / 4.0, (1.0 - a) / 4.0, (1.0 - a) / 4.0];
        expect.sort_by(|x, y| y.partial_cmp(x).unwrap());
        assert_all_close("λ(H) of diag(1,a,a,a)", l.iter().copied(), expect, F64);
        if a >= -1.0 / 3.0 + 1e-9 {
            prop_assert!(m.is_physically_realizable(1e-12));
        } else if a < -1.0 / 3.0 - 1e-9 {
            prop_assert!(!m.is_physically_realizable(1e-12));
        }
        assert_close("depolarization index", m.depolarization_index(), a.abs(), F64);
    }
}

#[test]
fn non_physical_matrices_are_rejected() {
    // diag(1, 1, 1, −1) flips handedness: maps valid Stokes to valid Stokes, but its H has the
    // eigenvalues of ½ SWAP, (½, ½, ½, −½): not a convex sum of Jones matrices.
    let flip = diag(1.0, 1.0, 1.0, -1.0);
    assert_all_close(
        "λ(H) flip",
        flip.coherency_eigenvalues().iter().copied(),
        [0.5, 0.5, 0.5, -0.5],
        F64,
    );
    assert!(!flip.is_physically_realizable(1e-12));
    // diag(1, 2, 0, 0) maps (1, 1, 0, 0) to the invalid (1, 2, 0, 0).
    let over = diag(1.0, 2.0, 0.0, 0.0);
    let out = (over * Stokes::new(1.0, 1.0, 0.0, 0.0).unwrap()).vector();
    assert!(!is_valid_stokes(&out, 1e-12));
    assert!(!over.is_physically_realizable(1e-12));
    // Identity plus M01 = ½ maps (1, −1, 0, 0) to (½, −1, 0, 0): invalid.
    let mut m = Matrix4::identity();
    m[(0, 1)] = 0.5;
    let off = Mueller::from_matrix(m).unwrap();
    let out = (off * Stokes::new(1.0, -1.0, 0.0, 0.0).unwrap()).vector();
    assert!(!is_valid_stokes(&out, 1e-12));
    assert!(!off.is_physically_realizable(1e-12));
    // Negative transmittance.
    assert!(!diag(-1.0, 0.0, 0.0, 0.0).is_physically_realizable(1e-12));
}

#[test]
fn diattenuation_polarizance_depolarization_of_known_elements() {
    for &theta in &[0.0, 0.3, -1.2, 2.0] {
        let p = Mueller::from_jones(&JonesMatrix::<f64>::linear_polarizer(theta));
        assert_close("D polarizer", p.diattenuation(), 1.0, F64);
        assert_close("P polarizer", p.polarizance(), 1.0, F64);
        let r = Mueller::from_jones(&JonesMatrix::<f64>::linear_retarder(theta, 0.8));
        assert_close("D retarder", r.diattenuation(), 0.0, F64);
        assert_close("P retarder", r.polarizance(), 0.0, F64);
        assert_close("P_Δ retarder", r.depolarization_index(), 1.0, F64);
        let pf = Mueller::from_jones(&JonesMatrix::<f32>::linear_polarizer(theta as f32));
        assert_close("D polarizer f32", f64::from(pf.diattenuation()), 1.0, F32);
    }
    let ideal = diag(1.0, 0.0, 0.0, 0.0);
    assert_eq!(ideal.depolarization_index(), 0.0);
    assert!(ideal.is_physically_realizable(0.0));
    // Opaque element: no NaN.
    let zero = diag(0.0, 0.0, 0.0, 0.0);
    assert_eq!(
        [
            zero.diattenuation(),
            zero.polarizance(),
            zero.depolarization_index()
        ],
        [0.0; 3]
    );
}

#[test]
fn lu_chipman_degenerate_cases() {
    // Ideal polarizer: D = 1, M_D singular.
    let p = Mueller::from_jones(&JonesMatrix::<f64>::linear_polarizer(0.4));
    assert!(matches!(p.lu_chipman(), Err(Error::Singular { .. })));
    // Opaque.
    assert!(matches!(
        diag(0.0, 0.0, 0.0, 0.0).lu_chipman(),
        Err(Error::OutOfRange { .. })
    ));
    // Ideal depolarizer: m′ = 0; factors are identity retarder and the depolarizer itself.
    let ideal = diag(2.0, 0.0, 0.0, 0.0);
    let lc = ideal.lu_chipman().unwrap();
    assert_all_close(
        "recompose",
        entries4(&lc.recompose().matrix()),
        entries4(&ideal.matrix()),
        F64,
    );
    assert_close("retardance", lc.retardance(), 0.0, F64);
    assert_close("D", lc.diattenuation(), 0.0, F64);
    // Rank-deficient m′ with det(U Vᵀ) possibly −1: diag(1, 0.5, 0, −0.5) recomposes with a proper m_R.
    let sing = diag(1.0, 0.5, 0.0, -0.5);
    let lc = sing.lu_chipman().unwrap();
    assert_all_close(
        "recompose singular",
        entries4(&lc.recompose().matrix()),
        entries4(&sing.matrix()),
        F64,
    );
    let r = lc.retarder.matrix().fixed_view::<3, 3>(1, 1).into_owned();
    assert_close("det m_R", r.determinant(), 1.0, F64);
    // f32 works too.
    let r32 = Mueller::from_jones(&JonesMatrix::<f32>::linear_retarder(0.2, 1.0));
    assert_close(
        "retardance f32",
        f64::from(r32.lu_chipman().unwrap().retardance()),
        1.0,
        Tol::new(1e-3, 0.0),
    );
}

#[test]
fn distinct_points_give_complex_generalized_mueller() {
    // For J₁ ≠ J₂ the generalized Mueller matrix is genuinely complex.
    let j1 = JonesMatrix::<f64>::linear_retarder(0.3, 1.1);
    let j2 = JonesMatrix::<f64>::linear_polarizer(0.9);
    let g = GeneralizedMueller::from_jones_pair(&j1, &j2).matrix();
    assert!(g.iter().any(|c| c.im.abs() > 0.1));
}

// ------------------------------------------------------------------ scale invariance, robustness

/// A Jones matrix with entries uniform in [−1, 1) + i[−1, 1) from the shared `SplitMix64`.
fn random_jones<T: Real>(rng: &mut common::SplitMix64) -> JonesMatrix<T> {
    let mut c = || Complex::new(T::lit(rng.signed()), T::lit(rng.signed()));
    JonesMatrix::from_matrix(Matrix2::new(c(), c(), c(), c())).unwrap()
}

/// J = 10¹⁰·diag(2, 1) in f32 (|J₀₀|² = 4e20, and the squares of the Mueller entries overflow):
/// by hand, the intensity transmittances are 4·10²⁰ and 10²⁰, so D = P = (4 − 1)/(4 + 1) = 0.6,
/// and `M = ½·10²⁰ [[5, 3, 0, 0], [3, 5, 0, 0], [0, 0, 4, 0], [0, 0, 0, 4]]` gives
/// `Σ M_ij² − M₀₀² = (25 − 6.25)·10⁴⁰`, so `P_Δ = √18.75 / (√3 · 2.5) = 1` (`D = ∞`, `P_Δ = 0` before).
#[test]
fn analysis_of_a_huge_f32_diattenuator_matches_the_hand_values() {
    let j = JonesMatrix::from_matrix(Matrix2::new(
        Complex::new(2e10f32, 0.0),
        Complex::new(0.0, 0.0),
        Complex::new(0.0, 0.0),
        Complex::new(1e10, 0.0),
    ))
    .unwrap();
    let m = Mueller::from_jones(&j);
    // (assert_close accepts ∞ against a finite value through its relative term: check finiteness.)
    assert!(
        [m.diattenuation(), m.polarizance(), m.depolarization_index()]
            .iter()
            .all(|x| x.is_finite())
    );
    assert_close("M00", f64::from(m.matrix()[(0, 0)]), 2.5e20, F32);
    assert_close("D", f64::from(m.diattenuation()), 0.6, F32);
    assert_close("P", f64::from(m.polarizance()), 0.6, F32);
    assert_close("P_Δ", f64::from(m.depolarization_index()), 1.0, F32);
    assert!(m.is_physically_realizable(64.0 * f32::EPSILON));
    let l = m.coherency_eigenvalues();
    assert_close("λ₀ = M00", f64::from(l[0]), 2.5e20, F32);
    for k in 1..4 {
        assert!(
            f64::from(l[k]).abs() <= 64.0 * f64::from(f32::EPSILON) * 2.5e20,
            "λ{k} = {}",
            l[k]
        );
    }
}

/// Every analysis function of `Mueller` gives the same answer for `s·M` as for `M` at
/// `s = 10^±30` (f32) and `10^±300` (f64): D, P, `P_Δ`, `λ(H)/s`, realizability, and the Lu–Chipman
/// retardance and diattenuation.
fn analysis_scale_invariance<T: Real>(scales: [f64; 2], tol: Tol) {
    let cast = |m: &Mueller<f64>| Mueller::from_matrix(m.matrix().map(T::lit)).unwrap();
    let mj = |j: &JonesMatrix<f64>| Mueller::from_jones(j);
    let bases = [
        mj(&diattenuator(0.3, 0.5)),
        mj(&JonesMatrix::linear_retarder(0.7, 1.1)) * mj(&diattenuator(-0.4, 0.2)),
        diag(1.0, 0.5, 0.3, 0.2) * mj(&diattenuator(1.0, 0.7)),
        diag(1.0, 0.0, 0.0, 0.0),
        diag(1.0, 1.0, 1.0, -1.0), // not realizable
    ];
    for base in &bases {
        let b = cast(base);
        let blc = b.lu_chipman();
        let bl = b.coherency_eigenvalues();
        let eps = T::EPSILON.to_f64();
        for &sc in &scales {
            let m = Mueller::from_matrix(b.matrix() * T::lit(sc)).unwrap();
            let what = format!(
                "{} × {sc:e}: {:?}",
                std::any::type_name::<T>(),
                base.matrix()
            );
            for (name, got, want) in [
                ("D", m.diattenuation(), b.diattenuation()),
                ("P", m.polarizance(), b.polarizance()),
                ("P_Δ", m.depolarization_index(), b.depolarization_index()),
            ] {
                assert!(got.is_finite(), "{name} = {got:?}: {what}");
                assert_close(&format!("{name} {what}"), got.to_f64(), want.to_f64(), tol);
            }
            let l = m.coherency_eigenvalues();
            assert!(l.iter().all(|x| x.is_finite()), "λ = {l:?}: {what}");
            for k in 0..4 {
                let t = Tol::new(64.0 * eps, 0.0);
                assert_close(
                    &format!("λ{k}/s {what}"),
                    l[k].to_f64() / sc,
                    bl[k].to_f64(),
                    t,
                );
            }
            let tol_real = T::lit(64.0) * T::EPSILON;
            assert_eq!(
                m.is_physically_realizable(tol_real),
                b.is_physically_realizable(tol_real),
                "{what}"
            );
            match (m.lu_chipman(), &blc) {
                (Ok(lc), Ok(b0)) => {
                    let t = Tol::new(1e3 * eps, 1e3 * eps);
                    assert_close(
                        &format!("retardance {what}"),
                        lc.retardance().to_f64(),
                        b0.retardance().to_f64(),
                        t,
                    );
                    assert_close(
                        &format!("LC D {what}"),
                        lc.diattenuation().to_f64(),
                        b0.diattenuation().to_f64(),
                        t,
                    );
                }
                (r, b0) => assert_eq!(r.is_ok(), b0.is_ok(), "Lu–Chipman {what}"),
            }
        }
    }
}

#[test]
fn analysis_is_scale_invariant() {
    analysis_scale_invariance::<f32>([1e30, 1e-30], Tol::new(0.0, 2e-6));
    analysis_scale_invariance::<f64>([1e300, 1e-300], Tol::new(0.0, 1e-14));
}

/// The checks on one Jones-derived matrix: every coherency eigenvalue finite, H rank 1
/// (λ₀ = M₀₀ and the other three within 64ε·tr H of 0), realizable with tolerance 64ε.
fn check_rank_one<T: Real>(j: &JonesMatrix<T>, what: &str) {
    let m = Mueller::from_jones(j);
    let l = m.coherency_eigenvalues();
    let tr = m.matrix()[(0, 0)].to_f64();
    let eps = T::EPSILON.to_f64();
    let what = format!(
        "{} {what}: J = {:?}",
        std::any::type_name::<T>(),
        j.matrix()
    );
    assert!(l.iter().all(|x| x.is_finite()), "λ = {l:?}: {what}");
    assert!(
        (l[0].to_f64() - tr).abs() <= 64.0 * eps * tr,
        "λ₀ = {:e} vs {tr:e}: {what}",
        l[0].to_f64()
    );
    for k in 1..4 {
        assert!(
            l[k].to_f64().abs() <= 64.0 * eps * tr,
            "λ{k} = {:e}: {what}",
            l[k].to_f64()
        );
    }
    assert!(
        m.is_physically_realizable(T::lit(64.0) * T::EPSILON),
        "{what}"
    );
}

/// 10⁵ random Jones matrices (entries uniform in the unit square of ℂ) and 10⁵ nearly singular
/// upper-triangular ones `[[10⁻⁴ a, b], [0, d]]`: nalgebra's Hermitian eigensolver returned
/// NaN for 32 of the latter in f32 (so `is_physically_realizable` reported false).
fn coherency_robustness<T: Real>(seed: u64) {
    let mut rng = common::SplitMix64(seed);
    for i in 0..100_000 {
        check_rank_one(&random_jones::<T>(&mut rng), &format!("random {i}"));
        let j = random_jones::<T>(&mut rng).matrix();
        let tri = Matrix2::new(
            j[(0, 0)] * T::lit(1e-4),
            j[(0, 1)],
            Complex::new(T::zero(), T::zero()),
            j[(1, 1)],
        );
        check_rank_one(
            &JonesMatrix::from_matrix(tri).unwrap(),
            &format!("triangular {i}"),
        );
    }
}

#[test]
fn coherency_eigenvalues_are_finite_for_random_jones_matrices() {
    coherency_robustness::<f32>(1);
    coherency_robustness::<f64>(2);
}

/// Every Jones matrix with entries from {0, ±1, ±i, ½, 1 + i, 0.3 − 0.7i, 10⁻⁴, 1 + 10⁻⁴i}
/// (10⁴ matrices, with exact zeros and repeated eigenvalues of H): e.g. f32
/// `[[10⁻⁴, 1 + 10⁻⁴i], [0, 1]]` gave NaN eigenvalues before.
fn coherency_structured<T: Real>() {
    let vals = [
        (0.0, 0.0),
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 1.0),
        (0.0, -1.0),
        (0.5, 0.0),
        (1.0, 1.0),
        (0.3, -0.7),
        (1e-4, 0.0),
        (1.0, 1e-4),
    ];
    let z = |k: usize| Complex::new(T::lit(vals[k].0), T::lit(vals[k].1));
    for i in 0..10_000 {
        let j = Matrix2::new(z(i / 1000), z(i / 100 % 10), z(i / 10 % 10), z(i % 10));
        check_rank_one(
            &JonesMatrix::from_matrix(j).unwrap(),
            &format!("structured {i}"),
        );
    }
}

#[test]
fn coherency_eigenvalues_are_finite_for_structured_jones_matrices() {
    coherency_structured::<f32>();
    coherency_structured::<f64>();
}
