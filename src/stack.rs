//! The stack (vectorization) operator and the Kronecker product (Lemma S1.1).
//!
//! # Column stacking is the crate's `X^S` (erratum 1)
//!
//! The seed defines the stack operator `X^S` as "the column vector that arises by stacking the
//! rows" of `X`, and then states Lemma S1.1 as `A D Bᵀ = C ⇔ (B ⊗ A) D^S = C^S`. That lemma is the
//! classical identity for **column** stacking (Van Loan 2000); for row stacking the Kronecker
//! factors swap, `vec_r(A D Bᵀ) = (A ⊗ B) vec_r(D)`. Everything downstream in the seed — S1.5's
//! `J(p₂)* ⊗ J(p₁)`, `A_mül` (S1.3) and S1.7 — is consistent only with column stacking: with row
//! stacking `A_mül` gives `S3` the opposite sign and S1.7 no longer maps generalized Stokes
//! parameters to generalized Stokes parameters. The crate therefore uses column stacking,
//! [`stack`], as `X^S` throughout, and provides [`stack_rows`] with its own (correct) lemma.
//! `tests/stack.rs` shows both facts numerically (`printed_lemma_fails_for_row_stacking`,
//! `row_stacking_flips_s3`).
//!
//! # Identities (tested in `tests/stack.rs`)
//! ```text
//! Lemma S1.1, column form:  vec(A D Bᵀ)   = (B ⊗ A) vec(D)
//! Lemma S1.1, row form:     vec_r(A D Bᵀ) = (A ⊗ B) vec_r(D)
//! mixed product:            (A ⊗ B)(C ⊗ D) = (AC) ⊗ (BD)
//! ```
//! All functions are generic over `T: Real`, work on fixed-size nalgebra types and never allocate.

use nalgebra::{Matrix2, Matrix4, Vector4};
use num_complex::Complex;

use crate::real::Real;

/// Column stacking `vec(X)`: the columns of `X` one below the other (the crate's `X^S`).
///
/// # Formula
/// ```text
/// vec(X) = (X₁₁, X₂₁, X₁₂, X₂₂)ᵀ,   vec(X)_{2j+i} = X_ij   (0-based i, j)
/// ```
/// This is the stacking for which Lemma S1.1 holds as printed (see the module docs, erratum 1).
///
/// # Examples
/// ```
/// use gmueller::stack::stack;
/// use nalgebra::Matrix2;
/// use num_complex::Complex;
/// let c = |x: f64| Complex::new(x, 0.0);
/// let v = stack(&Matrix2::new(c(1.0), c(2.0), c(3.0), c(4.0))); // rows (1, 2), (3, 4)
/// assert!((v[1] - c(3.0)).norm() < 1e-15 && (v[2] - c(2.0)).norm() < 1e-15);
/// ```
#[inline]
#[must_use]
pub fn stack<T: Real>(x: &Matrix2<Complex<T>>) -> Vector4<Complex<T>> {
    Vector4::new(x[(0, 0)], x[(1, 0)], x[(0, 1)], x[(1, 1)])
}

/// Row stacking `vec_r(X)`: the rows of `X`, transposed, one below the other.
///
/// # Formula
/// ```text
/// vec_r(X) = (X₁₁, X₁₂, X₂₁, X₂₂)ᵀ = vec(Xᵀ),   vec_r(X)_{2i+j} = X_ij   (0-based i, j)
/// ```
/// This is what the seed's text describes; its lemma is `vec_r(A D Bᵀ) = (A ⊗ B) vec_r(D)`, not
/// the printed S1.1 (module docs, erratum 1).
///
/// # Examples
/// ```
/// use gmueller::stack::stack_rows;
/// use nalgebra::Matrix2;
/// use num_complex::Complex;
/// let c = |x: f64| Complex::new(x, 0.0);
/// let v = stack_rows(&Matrix2::new(c(1.0), c(2.0), c(3.0), c(4.0)));
/// assert!((v[1] - c(2.0)).norm() < 1e-15 && (v[2] - c(3.0)).norm() < 1e-15);
/// ```
#[inline]
#[must_use]
pub fn stack_rows<T: Real>(x: &Matrix2<Complex<T>>) -> Vector4<Complex<T>> {
    Vector4::new(x[(0, 0)], x[(0, 1)], x[(1, 0)], x[(1, 1)])
}

/// The inverse of [`stack`]: rebuilds `X` from `vec(X)`.
///
/// # Formula
/// ```text
/// X_ij = v_{2j+i}   (0-based)
/// ```
///
/// # Examples
/// ```
/// use gmueller::stack::{stack, unstack};
/// use nalgebra::Matrix2;
/// use num_complex::Complex;
/// let x = Matrix2::new(Complex::new(1.0_f64, 2.0), Complex::new(3.0, 0.0),
///                      Complex::new(0.0, -1.0), Complex::new(5.0, 5.0));
/// assert_eq!(unstack(&stack(&x)), x);
/// ```
#[inline]
#[must_use]
pub fn unstack<T: Real>(v: &Vector4<Complex<T>>) -> Matrix2<Complex<T>> {
    Matrix2::new(v[0], v[2], v[1], v[3])
}

/// The inverse of [`stack_rows`]: rebuilds `X` from `vec_r(X)`.
///
/// # Formula
/// ```text
/// X_ij = v_{2i+j}   (0-based)
/// ```
///
/// # Examples
/// ```
/// use gmueller::stack::{stack_rows, unstack_rows};
/// use nalgebra::Matrix2;
/// use num_complex::Complex;
/// let x = Matrix2::new(Complex::new(1.0_f64, 2.0), Complex::new(3.0, 0.0),
///                      Complex::new(0.0, -1.0), Complex::new(5.0, 5.0));
/// assert_eq!(unstack_rows(&stack_rows(&x)), x);
/// ```
#[inline]
#[must_use]
pub fn unstack_rows<T: Real>(v: &Vector4<Complex<T>>) -> Matrix2<Complex<T>> {
    Matrix2::new(v[0], v[1], v[2], v[3])
}

/// The Kronecker product `A ⊗ B` of two 2×2 complex matrices.
///
/// # Formula
/// ```text
/// (A ⊗ B)_{2i+k, 2j+l} = A_ij B_kl        (0-based i, j, k, l ∈ {0, 1})
///
///          ⎡ A₁₁B  A₁₂B ⎤
/// A ⊗ B =  ⎣ A₂₁B  A₂₂B ⎦      (each block is 2×2)
/// ```
/// Order matters: `A ⊗ B ≠ B ⊗ A` in general. With column stacking, `vec(A D Bᵀ) = (B ⊗ A) vec(D)`
/// (Lemma S1.1); see [`sandwich_operator`].
///
/// # Examples
/// ```
/// use gmueller::stack::kron;
/// use nalgebra::Matrix2;
/// use num_complex::Complex;
/// let c = |x: f64| Complex::new(x, 0.0);
/// let a = Matrix2::new(c(1.0), c(2.0), c(3.0), c(4.0));
/// let b = Matrix2::new(c(0.0), c(5.0), c(6.0), c(7.0));
/// let k = kron(&a, &b);
/// // (A ⊗ B)_{2·1+0, 2·0+1} = A₁₀ B₀₁ = 3 · 5
/// assert!((k[(2, 1)] - c(15.0)).norm() < 1e-15);
/// ```
#[must_use]
pub fn kron<T: Real>(a: &Matrix2<Complex<T>>, b: &Matrix2<Complex<T>>) -> Matrix4<Complex<T>> {
    Matrix4::from_fn(|r, c| a[(r / 2, c / 2)] * b[(r % 2, c % 2)])
}

/// The 4×4 operator of the map `D ↦ A D Bᵀ` on column-stacked matrices (Lemma S1.1).
///
/// # Formula
/// ```text
/// S1.1 (column stacking):  vec(A D Bᵀ) = (B ⊗ A) vec(D)
/// ```
/// S1.5 is the case `A = J(p₁)`, `B = J(p₂)*` (so that `Bᵀ = J(p₂)†`).
///
/// # Examples
/// ```
/// use gmueller::stack::{sandwich_operator, stack};
/// use nalgebra::Matrix2;
/// use num_complex::Complex;
/// let z = |re: f64, im: f64| Complex::new(re, im);
/// let a = Matrix2::new(z(1.0, 1.0), z(0.5, 0.0), z(0.0, -2.0), z(3.0, 0.0));
/// let b = Matrix2::new(z(0.0, 1.0), z(2.0, 0.0), z(1.0, 1.0), z(-1.0, 0.0));
/// let d = Matrix2::new(z(2.0, 0.0), z(0.0, 1.0), z(1.0, -1.0), z(0.5, 0.5));
/// let lhs = stack(&(a * d * b.transpose()));
/// let rhs = sandwich_operator(&a, &b) * stack(&d);
/// assert!((lhs - rhs).norm() < 1e-12);
/// ```
#[inline]
#[must_use]
pub fn sandwich_operator<T: Real>(
    a: &Matrix2<Complex<T>>,
    b: &Matrix2<Complex<T>>,
) -> Matrix4<Complex<T>> {
    kron(b, a)
}

/// The 4×4 operator of the map `D ↦ A D Bᵀ` on row-stacked matrices.
///
/// # Formula
/// ```text
/// row stacking:  vec_r(A D Bᵀ) = (A ⊗ B) vec_r(D)      (not (B ⊗ A), as S1.1 is printed)
/// ```
///
/// # Examples
/// ```
/// use gmueller::stack::{sandwich_operator_rows, stack_rows};
/// use nalgebra::Matrix2;
/// use num_complex::Complex;
/// let z = |re: f64, im: f64| Complex::new(re, im);
/// let a = Matrix2::new(z(1.0, 1.0), z(0.5, 0.0), z(0.0, -2.0), z(3.0, 0.0));
/// let b = Matrix2::new(z(0.0, 1.0), z(2.0, 0.0), z(1.0, 1.0), z(-1.0, 0.0));
/// let d = Matrix2::new(z(2.0, 0.0), z(0.0, 1.0), z(1.0, -1.0), z(0.5, 0.5));
/// let lhs = stack_rows(&(a * d * b.transpose()));
/// let rhs = sandwich_operator_rows(&a, &b) * stack_rows(&d);
/// assert!((lhs - rhs).norm() < 1e-12);
/// ```
#[inline]
#[must_use]
pub fn sandwich_operator_rows<T: Real>(
    a: &Matrix2<Complex<T>>,
    b: &Matrix2<Complex<T>>,
) -> Matrix4<Complex<T>> {
    kron(a, b)
}
