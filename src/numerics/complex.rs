//! `hypot` and the principal complex square root.

use num_complex::Complex;

use crate::real::Real;

/// The range of `max(|a|, |b|)` in which [`hypot`] uses the plain formula.
pub(crate) const HYPOT_PLAIN: (f64, f64) = (1e-18, 1e18);

/// `√(a² + b²)` without spurious over- or underflow: the plain formula when `max(|a|, |b|)`
/// lies in `[10⁻¹⁸, 10¹⁸]` (where `a² + b²` is a normal number in f32 and f64, so the result is
/// accurate to an ulp or two), the library `hypot` — several times slower — otherwise.
#[inline]
pub(crate) fn hypot<T: Real>(a: T, b: T) -> T {
    let m = a.abs().max(b.abs());
    if m >= T::lit(HYPOT_PLAIN.0) && m <= T::lit(HYPOT_PLAIN.1) {
        (a * a + b * b).sqrt()
    } else {
        a.hypot(b)
    }
}

/// The principal square root (`Re ≥ 0`), with a zero imaginary part of either sign treated as
/// `+0`, so that a negative real `z` (total internal reflection) gives `+i√|z|`.
///
/// Computed without cancellation: the larger of `√((|z| ± Re z)/2)` first, the other as
/// `Im z / (2 ·)`.
pub(crate) fn principal_sqrt<T: Real>(z: Complex<T>) -> Complex<T> {
    let (a, b) = (z.re, z.im);
    let r = hypot(a, b);
    let half = T::lit(0.5);
    if a >= T::zero() {
        let x = ((r + a) * half).sqrt();
        let y = if x > T::zero() {
            b * half / x
        } else {
            T::zero()
        };
        Complex::new(x, y)
    } else {
        // b < 0 strictly gives the lower half-plane root; b = ±0 gives +i√|a|.
        let y = ((r - a) * half).sqrt();
        let y = if b < T::zero() { -y } else { y };
        Complex::new(b * half / y, y)
    }
}

#[cfg(test)]
mod tests {
    use super::hypot;

    /// The fast `hypot` against the library one across the whole exponent range, both types.
    #[test]
    fn hypot_matches_library_hypot_at_every_scale() {
        for e in -300..=300 {
            let m = 10f64.powi(e);
            for (a, b) in [(3.0 * m, 4.0 * m), (m, 1e-3 * m), (-m, 0.0), (0.0, -m)] {
                let (fast, lib) = (hypot(a, b), a.hypot(b));
                assert!(
                    (fast - lib).abs() <= 4.0 * f64::EPSILON * lib,
                    "f64 {a:e} {b:e}"
                );
            }
        }
        for e in -36..=36 {
            let m = 10f32.powi(e);
            for (a, b) in [(3.0 * m, 4.0 * m), (m, 1e-3 * m)] {
                let (fast, lib) = (hypot(a, b), a.hypot(b));
                assert!(
                    (fast - lib).abs() <= 4.0 * f32::EPSILON * lib,
                    "f32 {a:e} {b:e}"
                );
            }
        }
        assert_eq!(hypot(0.0_f64, 0.0), 0.0);
    }
}
