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

use nalgebra::Unit;

use crate::error::Error;
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
    let m = amax(v);
    if m == T::zero() {
        return None;
    }
    let u = v / m;
    Some(u / u.norm())
}

/// A user's direction as a unit vector: finite ([`Error::NonFinite`] naming `what`
/// otherwise), non-zero ([`Error::InvalidBasis`]), normalised by [`unit_by_largest`]. The one
/// check of directions given to the kernel's and the renderer layer's constructors; what it
/// returns is typed [`Unit`], so that the crate's internal paths take it as it is and a
/// direction is normalised once on its way through the crate.
#[inline]
pub(crate) fn unit_direction<T: Real>(
    v: &nalgebra::Vector3<T>,
    what: &'static str,
) -> Result<Unit<nalgebra::Vector3<T>>, Error> {
    crate::error::ensure_finite(what, v.iter().copied())?;
    unit_by_largest(v)
        .map(Unit::new_unchecked)
        .ok_or(Error::InvalidBasis {
            reason: "zero direction vector",
        })
}

/// `max |mᵢⱼ|` (NaN entries ignored; 0 for a matrix of NaNs), as nalgebra's `amax` gives it
/// for a matrix without NaN, in a plain loop: nalgebra's generic fold costs about
/// 20 instructions per entry in the kernel's hot paths (callgrind, issue 39), this one about 2.
#[inline]
pub(crate) fn amax<T: Real, const R: usize, const C: usize>(m: &nalgebra::SMatrix<T, R, C>) -> T {
    m.as_slice()
        .iter()
        .fold(T::zero(), |largest, &x| largest.max(x.abs()))
}

/// `ln Σᵢ e^{xᵢ}` without overflow or underflow (`−∞` for an empty or all-`−∞` list).
#[inline]
pub(crate) fn log_sum_exp<T: Real>(terms: impl Iterator<Item = T> + Clone) -> T {
    // Start from the most negative finite number: with every term −∞ the sum is then 0 and
    // the result −MAX + ln 0 = −∞, with no 0/0 or ∞ − ∞ on the way.
    let m = terms.clone().fold(-T::MAX, |m, x| m.max(x));
    m + terms.fold(T::zero(), |acc, x| acc + (x - m).exp()).ln()
}

/// `a` and `b` with the same bits (NaN allowed only on both sides): the tests' bit-for-bit
/// comparison.
#[cfg(test)]
pub(crate) fn same<F: Real>(a: F, b: F) -> bool {
    a.to_f64().to_bits() == b.to_f64().to_bits()
}

/// `SplitMix64`'s next 64 bits, for the library's own unit tests (`verify::rng`, which the
/// integration tests use, is behind the `verify` feature).
#[cfg(test)]
pub(crate) fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix4, Vector3};

    use super::splitmix64 as next;

    /// Entries of every magnitude: random bits as a float (any sign, exponent and mantissa:
    /// zeros, subnormals, infinities and NaNs included), or a plain number in [−1, 1).
    fn entry(state: &mut u64) -> f64 {
        let bits = next(state);
        if bits.is_multiple_of(3) {
            f64::from_bits(next(state))
        } else {
            (bits >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// The plain loop gives nalgebra's `amax` bit for bit on matrices without NaN (f64 and
    /// f32, 20 000 matrices each, with zeros, subnormals and infinities), and the largest
    /// magnitude of the numbers where there are NaNs (nalgebra's fold then depends on where
    /// the NaN sits: seen giving the first entry, 0.97, with 6.9e108 in the matrix).
    #[test]
    fn amax_is_nalgebras_without_nan() {
        let mut state = 0x5eed;
        let mut with_nan = 0;
        for _ in 0..20_000 {
            let m = Matrix4::<f64>::from_fn(|_, _| entry(&mut state));
            let m32 = m.map(|x| x as f32);
            let v = Vector3::new(m[(0, 0)], m[(1, 1)], m[(2, 2)]);
            if m.iter().any(|x| x.is_nan()) {
                with_nan += 1;
                let numbers = m.iter().filter(|x| !x.is_nan()).map(|x| x.abs());
                assert_eq!(amax(&m), numbers.fold(0.0, f64::max));
                continue;
            }
            assert_eq!(amax(&m).to_bits(), m.amax().to_bits(), "{m:?}");
            if !m32.iter().any(|x| x.is_nan()) {
                assert_eq!(amax(&m32).to_bits(), m32.amax().to_bits(), "{m32:?}");
            }
            assert_eq!(amax(&v).to_bits(), v.amax().to_bits(), "{v:?}");
        }
        assert!(with_nan > 20, "{with_nan}");
        assert_eq!(amax(&Vector3::new(f64::NAN, f64::NAN, f64::NAN)), 0.0);
    }
}
