//! Generic numerics shared by the physics modules (not public API): accurate 2×2 linear
//! algebra, small Cholesky factorisations, complex square roots, `hypot`, log-space sums,
//! piecewise Chebyshev tables of a cumulative distribution.
//!
//! Nothing here knows about light: these are the building blocks that several concepts need
//! (a shape matrix, a section of the coherence by a surface, a PSD blur, a Fresnel coefficient),
//! kept in one place so that no physics module borrows them from another.

pub(crate) mod chebyshev;
mod cholesky;
mod complex;
mod dft;
mod gauss_legendre;
mod linalg2;

pub(crate) use cholesky::{cholesky, in_normal_range, is_nan, log_det_from_cholesky, solve_lower};
pub(crate) use complex::{HYPOT_PLAIN, principal_sqrt};
pub(crate) use dft::dft_in_place;
pub(crate) use gauss_legendre::GL8;
pub(crate) use linalg2::{
    det2, det2_of_mean, inverse_cholesky_of_mean, inverse_cholesky2, inverse2, pow2_scale,
};

use crate::real::Real;

/// `true` when `a` and `b` agree within `ulps` units of the larger's last place (a NaN fails):
/// the check that a wavenumber (or wavelength) given twice is the same one.
#[inline]
pub(crate) fn within_ulps<T: Real>(a: T, b: T, ulps: f64) -> bool {
    (a - b).abs() <= T::lit(ulps) * T::EPSILON * a.abs().max(b.abs())
}

/// `v/|v|` for a finite `v`, rescaled by its largest component first (`None` for the zero
/// vector): `|v|` itself over- or underflows for components beyond ~1e±154 (f64) or ~1e±19
/// (f32), and a subnormal `|v|²` keeps too few digits to normalise by. The one normaliser of
/// user directions (frames, geometries, the sampler's slow path).
#[inline]
pub(crate) fn unit_by_largest<T: Real>(v: &nalgebra::Vector3<T>) -> Option<nalgebra::Vector3<T>> {
    let m = v.amax();
    if m == T::zero() {
        return None;
    }
    let u = v / m;
    Some(u / u.norm())
}

/// `ln Σᵢ e^{xᵢ}` without overflow or underflow (`−∞` for an empty or all-`−∞` list).
#[inline]
pub(crate) fn log_sum_exp<T: Real>(terms: impl Iterator<Item = T> + Clone) -> T {
    // Start from the most negative finite number: with every term −∞ the sum is then 0 and
    // the result −MAX + ln 0 = −∞, with no 0/0 or ∞ − ∞ on the way.
    let m = terms.clone().fold(-T::MAX, |m, x| m.max(x));
    m + terms.fold(T::zero(), |acc, x| acc + (x - m).exp()).ln()
}
