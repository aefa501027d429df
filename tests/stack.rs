//! Verifies the stack operators and the Kronecker product (Lemma S1.1, erratum 1): the printed
//! lemma holds for column stacking on random complex matrices, fails for row stacking (which needs
//! `A ⊗ B`), the mixed-product law, the index formula, and that row stacking flips `S3` under the
//! printed `A_mül`. Each law is checked in f64 and f32.

use crate::common;

use common::{F32, F64, Tol, assert_complex_close, complex_matrix2};
use gmueller::real::Real;
use gmueller::stack::{
    kron, sandwich_operator, sandwich_operator_rows, stack, stack_rows, unstack, unstack_rows,
};
use gmueller::stokes::a_mul;
use nalgebra::{Matrix2, Matrix4, Vector4};
use num_complex::Complex;
use proptest::prelude::*;

fn to_t<T: Real>(m: &Matrix2<Complex<f64>>) -> Matrix2<Complex<T>> {
    m.map(|z| Complex::new(T::lit(z.re), T::lit(z.im)))
}

fn back4<T: Real>(v: &Vector4<Complex<T>>) -> Vec<Complex<f64>> {
    v.iter()
        .map(|z| Complex::new(z.re.to_f64(), z.im.to_f64()))
        .collect()
}

fn back44<T: Real>(m: &Matrix4<Complex<T>>) -> Vec<Complex<f64>> {
    m.iter()
        .map(|z| Complex::new(z.re.to_f64(), z.im.to_f64()))
        .collect()
}

fn lemma_column<T: Real>(
    a: &Matrix2<Complex<f64>>,
    d: &Matrix2<Complex<f64>>,
    b: &Matrix2<Complex<f64>>,
    tol: Tol,
) {
    let (a, d, b) = (to_t::<T>(a), to_t::<T>(d), to_t::<T>(b));
    let lhs = stack(&(a * d * b.transpose()));
    // S1.1 as printed: (B ⊗ A) D^S.
    let rhs = kron(&b, &a) * stack(&d);
    assert_complex_close("vec(A D Bᵀ) vs (B⊗A) vec(D)", back4(&lhs), back4(&rhs), tol);
    let op = sandwich_operator(&a, &b) * stack(&d);
    assert_complex_close("sandwich_operator", back4(&lhs), back4(&op), tol);
}

fn lemma_rows<T: Real>(
    a: &Matrix2<Complex<f64>>,
    d: &Matrix2<Complex<f64>>,
    b: &Matrix2<Complex<f64>>,
    tol: Tol,
) {
    let (a, d, b) = (to_t::<T>(a), to_t::<T>(d), to_t::<T>(b));
    let lhs = stack_rows(&(a * d * b.transpose()));
    let rhs = kron(&a, &b) * stack_rows(&d);
    assert_complex_close(
        "vec_r(A D Bᵀ) vs (A⊗B) vec_r(D)",
        back4(&lhs),
        back4(&rhs),
        tol,
    );
    let op = sandwich_operator_rows(&a, &b) * stack_rows(&d);
    assert_complex_close("sandwich_operator_rows", back4(&lhs), back4(&op), tol);
}

fn mixed_product<T: Real>(
    a: &Matrix2<Complex<f64>>,
    b: &Matrix2<Complex<f64>>,
    c: &Matrix2<Complex<f64>>,
    d: &Matrix2<Complex<f64>>,
    tol: Tol,
) {
    let (a, b, c, d) = (to_t::<T>(a), to_t::<T>(b), to_t::<T>(c), to_t::<T>(d));
    let lhs = kron(&a, &b) * kron(&c, &d);
    let rhs = kron(&(a * c), &(b * d));
    assert_complex_close("(A⊗B)(C⊗D) vs (AC)⊗(BD)", back44(&lhs), back44(&rhs), tol);
}

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn lemma_s1_1_column_stacking(a in complex_matrix2(1.0), d in complex_matrix2(1.0), b in complex_matrix2(1.0)) {
        lemma_column::<f64>(&a, &d, &b, F64);
        lemma_column::<f32>(&a, &d, &b, F32);
    }

    #[test]
    fn lemma_row_stacking_swaps_factors(a in complex_matrix2(1.0), d in complex_matrix2(1.0), b in complex_matrix2(1.0)) {
        lemma_rows::<f64>(&a, &d, &b, F64);
        lemma_rows::<f32>(&a, &d, &b, F32);
    }

    #[test]
    fn mixed_product_property(a in complex_matrix2(1.0), b in complex_matrix2(1.0), c in complex_matrix2(1.0), d in complex_matrix2(1.0)) {
        mixed_product::<f64>(&a, &b, &c, &d, F64);
        mixed_product::<f32>(&a, &b, &c, &d, F32);
    }

    #[test]
    fn kron_index_formula(a in complex_matrix2(2.0), b in complex_matrix2(2.0)) {
        let k = kron(&a, &b);
        for i in 0..2 { for j in 0..2 { for p in 0..2 { for q in 0..2 {
            // (A ⊗ B)_{2i+p, 2j+q} = A_ij B_pq, bit-exact (one product each).
            prop_assert_eq!(k[(2 * i + p, 2 * j + q)], a[(i, j)] * b[(p, q)]);
        }}}}
    }

    #[test]
    fn stack_unstack_round_trip(x in complex_matrix2(5.0)) {
        prop_assert_eq!(unstack(&stack(&x)), x);
        prop_assert_eq!(unstack_rows(&stack_rows(&x)), x);
        // vec_r(X) = vec(Xᵀ), and the explicit orders.
        prop_assert_eq!(stack_rows(&x), stack(&x.transpose()));
        prop_assert_eq!(stack(&x), Vector4::new(x[(0, 0)], x[(1, 0)], x[(0, 1)], x[(1, 1)]));
    }
}

fn z(re: f64, im: f64) -> Complex<f64> {
    Complex::new(re, im)
}

/// A fixed generic case: the printed S1.1, `(B ⊗ A) vec_r(D)`, misses `vec_r(A D Bᵀ)` by O(1)
/// with row stacking, while `(A ⊗ B) vec_r(D)` matches.
#[test]
fn printed_lemma_fails_for_row_stacking() {
    let a = Matrix2::new(z(1.0, 0.5), z(-0.3, 0.2), z(0.7, -1.0), z(0.4, 0.0));
    let b = Matrix2::new(z(0.2, -0.6), z(1.1, 0.3), z(-0.5, 0.0), z(0.9, 0.8));
    let d = Matrix2::new(z(0.6, 0.1), z(-1.2, 0.4), z(0.3, 0.9), z(-0.2, -0.7));
    let target = stack_rows(&(a * d * b.transpose()));
    let printed = kron(&b, &a) * stack_rows(&d);
    let corrected = kron(&a, &b) * stack_rows(&d);
    let err_printed = (printed - target).norm() / target.norm();
    let err_corrected = (corrected - target).norm() / target.norm();
    assert!(
        err_printed > 0.1,
        "printed form unexpectedly close: {err_printed}"
    );
    assert!(err_corrected < 1e-14, "corrected form off: {err_corrected}");
}

/// With row stacking, the printed `A_mül` yields `S3 = −2 Im⟨E_x* E_y⟩`: the circular state
/// `(1, i)/√2` (S3 = +1 by the per-field formula) comes out as −1. Column stacking gives +1.
#[test]
fn row_stacking_flips_s3() {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let (ex, ey) = (z(h, 0.0), z(0.0, h));
    let s3_field = 2.0 * (ex.conj() * ey).im;
    assert!((s3_field - 1.0).abs() < 1e-15);
    // C = E E†.
    let c = Matrix2::new(
        ex * ex.conj(),
        ex * ey.conj(),
        ey * ex.conj(),
        ey * ey.conj(),
    );
    let s_col = a_mul::<f64>() * stack(&c);
    let s_row = a_mul::<f64>() * stack_rows(&c);
    assert!((s_col[3] - z(s3_field, 0.0)).norm() < 1e-15);
    assert!((s_row[3] - z(-s3_field, 0.0)).norm() < 1e-15);
    // S0, S1, S2 agree (C is Hermitian, so only the antisymmetric part flips).
    for k in 0..3 {
        assert!((s_col[k] - s_row[k]).norm() < 1e-15);
    }
}

/// With row stacking, S1.7's `J* ⊗ J` no longer maps Stokes parameters to Stokes parameters:
/// `A_mül (J*⊗J) vec_r(C)` differs from `A_mül vec_r(J C J†)` for a generic J and C.
#[test]
fn s1_7_fails_with_row_stacking() {
    let j = Matrix2::new(z(1.0, 0.5), z(-0.3, 0.2), z(0.7, -1.0), z(0.4, 0.0));
    let e = Matrix2::new(z(0.6, 0.1), z(-1.2, 0.4), z(0.3, 0.9), z(-0.2, -0.7));
    let c = e * e.adjoint(); // Hermitian PSD
    let target_col = a_mul::<f64>() * stack(&(j * c * j.adjoint()));
    let via_col = a_mul::<f64>() * kron(&j.conjugate(), &j) * stack(&c);
    assert!((target_col - via_col).norm() < 1e-12 * target_col.norm());
    let target_row = a_mul::<f64>() * stack_rows(&(j * c * j.adjoint()));
    let via_row = a_mul::<f64>() * kron(&j.conjugate(), &j) * stack_rows(&c);
    assert!((target_row - via_row).norm() > 0.1 * target_row.norm());
}
