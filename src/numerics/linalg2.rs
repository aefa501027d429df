//! 2×2 symmetric positive-definite matrices: determinants exact to a few ulps in `f32`, inverses
//! and inverse Cholesky factors, scaling by powers of two.

use nalgebra::Matrix2;

use crate::real::Real;

/// `|m| = m₁₁ m₂₂ − m₁₂ m₂₁` by [`Real::diff_of_products`] (accurate under cancellation in `f32`:
/// a rotated shape of anisotropy 10⁶ has `m₁₁ m₂₂ ≈ m₁₂²`, and the plain `f32` determinant — with
/// it the inverse, the Cholesky factor and the realizability bound — came out about 10 % off).
#[inline]
pub(crate) fn det2<T: Real>(m: &Matrix2<T>) -> T {
    T::diff_of_products(m[(0, 0)], m[(1, 1)], m[(0, 1)], m[(1, 0)])
}

/// The power of two nearest below `x > 0` (finite): dividing by it is exact, so a matrix scaled
/// by it keeps the determinant [`det2`] computes to a few ulps (a scale that is not a power of
/// two rounds every entry, which moved the determinant of a 10⁶-anisotropic f32 shape by
/// `κ ε₃₂ ≈ 6 %`).
#[inline]
pub(crate) fn pow2_scale<T: Real>(x: T) -> T {
    // The exponent bits of x as an f64 (exact for f32 and f64 values): 2^⌊log₂ x⌋ for normal
    // x; subnormal or zero x (exponent field 0) take the slow path.
    let bits = x.to_f64().to_bits() & 0x7ff0_0000_0000_0000;
    if bits == 0 {
        return T::lit(2f64.powi(x.to_f64().log2().floor() as i32));
    }
    T::lit(f64::from_bits(bits))
}

/// Inverse of a 2×2 matrix by its adjugate (the callers pass SPD matrices).
///
/// Normalized by the largest entry first: `|Θ|` over- or underflows f32 for entries beyond
/// ~1e19 or below ~1e-19 (length², e.g. an area source far away), while the inverse does not.
#[inline]
pub(crate) fn inverse2<T: Real>(m: &Matrix2<T>) -> Matrix2<T> {
    let s = pow2_scale(m.amax());
    let n = m / s;
    let d = det2(&n);
    Matrix2::new(n[(1, 1)], -n[(0, 1)], -n[(1, 0)], n[(0, 0)]) / (d * s)
}

/// The inverse `L⁻¹` of the lower Cholesky factor of a symmetric positive-definite 2×2 `m`
/// (`m = L Lᵀ`, so `m⁻¹ = L⁻ᵀ L⁻¹`), with `L₂₂ = √(|m|/m₁₁)` from [`det2`] (not from the
/// cancelling `m₂₂ − L₂₁²`). `None` unless the result is finite with a positive diagonal.
#[inline]
pub(crate) fn inverse_cholesky2<T: Real>(m: &Matrix2<T>) -> Option<Matrix2<T>> {
    let s = m.amax();
    if !(s > T::zero() && s.is_finite()) {
        return None;
    }
    let s = pow2_scale(s);
    let n = m / s;
    inverse_cholesky_parts(&n, det2(&n), s)
}

/// [`inverse_cholesky2`] of the mean `(a + b)/2` of two SPD matrices, with its determinant formed
/// from the two without rounding the mean first (the channel `Θ_½` of a packet: rounding
/// `(Θ_x + Θ_y)/2` to `f32` moved `|Θ_½|` of a 10⁶-anisotropic pair by `κ ε₃₂`).
#[inline]
pub(crate) fn inverse_cholesky_of_mean<T: Real>(
    a: &Matrix2<T>,
    b: &Matrix2<T>,
) -> Option<Matrix2<T>> {
    let s = a.amax().max(b.amax());
    if !(s > T::zero() && s.is_finite()) {
        return None;
    }
    let s = pow2_scale(s);
    let (na, nb) = (a / s, b / s);
    inverse_cholesky_parts(&((na + nb) * T::lit(0.5)), det2_of_mean(&na, &nb), s)
}

/// `|(a + b)/2|`, exact to a few ulps for `f32` entries (the sums and their products are exact in
/// `f64`), the plain formula in `f64`.
#[inline]
pub(crate) fn det2_of_mean<T: Real>(a: &Matrix2<T>, b: &Matrix2<T>) -> T {
    let e = |i: usize, j: usize| a[(i, j)].to_f64() + b[(i, j)].to_f64();
    T::lit(0.25 * (e(0, 0) * e(1, 1) - e(0, 1) * e(1, 0)))
}

/// `L⁻¹` of `s n` from the normalised `n` (its entries `n₁₁`, `n₁₂` and its determinant `d`).
#[inline]
fn inverse_cholesky_parts<T: Real>(n: &Matrix2<T>, d: T, s: T) -> Option<Matrix2<T>> {
    let (a, b) = (n[(0, 0)], (n[(0, 1)] + n[(1, 0)]) * T::lit(0.5));
    if !(a > T::zero() && d > T::zero()) {
        return None;
    }
    // L of n: l11 = √a, l21 = b/√a, l22 = √(d/a); L of m = √s · L of n.
    let (l11, l22) = (a.sqrt(), (d / a).sqrt());
    let l21 = b / l11;
    let rs = s.sqrt().recip();
    let inv = Matrix2::new(rs / l11, T::zero(), -l21 * rs / (l11 * l22), rs / l22);
    inv.iter().all(|x| x.is_finite()).then_some(inv)
}
