//! Cholesky factorisation of small symmetric matrices, triangular solves, log-determinants.

use nalgebra::{SMatrix, SVector};

use crate::real::Real;

/// Cholesky factorisation of a symmetric matrix; `Err(pivot)` with the first non-positive pivot.
pub(crate) fn cholesky<T: Real, const N: usize>(
    a: &SMatrix<T, N, N>,
) -> Result<SMatrix<T, N, N>, T> {
    let mut l = SMatrix::<T, N, N>::zeros();
    for j in 0..N {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if !(d > T::zero() && d.is_finite()) {
            return Err(d);
        }
        let djj = d.sqrt();
        l[(j, j)] = djj;
        for i in (j + 1)..N {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / djj;
        }
    }
    Ok(l)
}

/// Solves `L y = x` for lower-triangular `L` (forward substitution).
#[inline]
pub(crate) fn solve_lower<T: Real, const N: usize>(
    l: &SMatrix<T, N, N>,
    x: &SVector<T, N>,
) -> SVector<T, N> {
    let mut y = *x;
    for i in 0..N {
        let mut s = y[i];
        for k in 0..i {
            s -= l[(i, k)] * y[k];
        }
        y[i] = s / l[(i, i)];
    }
    y
}

/// `true` for NaN (`RealField` has no `is_nan`).
#[inline]
pub(crate) fn is_nan<T: Real>(x: T) -> bool {
    x.partial_cmp(&x).is_none()
}

/// `x ∈ [10⁻³⁰, 10³⁰]`: safely inside the normal numbers of f32 and f64, so products and
/// quotients of two such values neither over- nor underflow.
#[inline]
pub(crate) fn in_normal_range<T: Real>(x: T) -> bool {
    x >= T::lit(1e-30) && x <= T::lit(1e30)
}

/// `ln|Σ| = 2 ln ∏ Lᵢᵢ` for a Cholesky factor with positive diagonal: one logarithm of the
/// product when it lies in `[10⁻³⁰, 10³⁰]` (normal in f32 and f64, so exact to rounding), the
/// sum of logarithms otherwise (where the product could over- or underflow).
#[inline]
pub(crate) fn log_det_from_cholesky<T: Real, const N: usize>(l: &SMatrix<T, N, N>) -> T {
    let mut prod = T::one();
    for i in 0..N {
        prod *= l[(i, i)];
    }
    let two = T::lit(2.0);
    if in_normal_range(prod) {
        two * prod.ln()
    } else {
        (0..N).fold(T::zero(), |acc, i| acc + l[(i, i)].ln()) * two
    }
}
