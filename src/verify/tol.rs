//! Tolerances with an absolute and a relative part, and the assertions that use them.
//!
//! Every comparison is `|a − b| ≤ abs + rel · max(|a|, |b|)` for finite values; a non-finite
//! value is accepted only against the very same value (`rel · ∞` would accept ∞ against
//! anything). The assertions panic with both values, the difference and the tolerance.

use num_complex::Complex;

/// An absolute and a relative tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tol {
    /// The absolute part.
    pub abs: f64,
    /// The relative part, times `max(|a|, |b|)`.
    pub rel: f64,
}

/// For `f64` results of short closed-form computations: `1e-12` absolute and relative.
pub const F64: Tol = Tol {
    abs: 1e-12,
    rel: 1e-12,
};

/// For `f32` results of short closed-form computations: `2e-5` absolute and relative.
pub const F32: Tol = Tol {
    abs: 2e-5,
    rel: 2e-5,
};

impl Tol {
    /// The tolerance `abs + rel · max(|a|, |b|)`.
    #[must_use]
    pub const fn new(abs: f64, rel: f64) -> Self {
        Self { abs, rel }
    }

    /// `|a − b| ≤ abs + rel · max(|a|, |b|)` for finite values; a non-finite value only
    /// against the very same value.
    ///
    /// ```
    /// use gmueller::verify::tol::Tol;
    /// let t = Tol::new(0.0, 1e-6);
    /// assert!(t.accepts(1.0, 1.0 + 5e-7));
    /// assert!(!t.accepts(1.0, 1.0 + 2e-6));
    /// assert!(!t.accepts(f64::INFINITY, 1.0) && t.accepts(f64::INFINITY, f64::INFINITY));
    /// ```
    #[must_use]
    pub fn accepts(self, a: f64, b: f64) -> bool {
        if !(a.is_finite() && b.is_finite()) {
            return a == b;
        }
        (a - b).abs() <= self.abs + self.rel * a.abs().max(b.abs())
    }
}

/// Panics with both values unless `a` and `b` agree within `tol`.
///
/// # Panics
/// When they do not agree.
#[track_caller]
pub fn assert_close(what: &str, a: f64, b: f64, tol: Tol) {
    assert!(
        tol.accepts(a, b),
        "{what}: {a:e} vs {b:e} (diff {:e}, tol abs {:e} rel {:e})",
        (a - b).abs(),
        tol.abs,
        tol.rel
    );
}

/// Element-wise [`assert_close`] over two sequences of equal length; the message prints both
/// sequences whole.
///
/// # Panics
/// When the lengths differ or an element does not agree.
#[track_caller]
pub fn assert_all_close(
    what: &str,
    a: impl IntoIterator<Item = f64>,
    b: impl IntoIterator<Item = f64>,
    tol: Tol,
) {
    let a: Vec<f64> = a.into_iter().collect();
    let b: Vec<f64> = b.into_iter().collect();
    assert_eq!(a.len(), b.len(), "{what}: length mismatch");
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!(
            tol.accepts(*x, *y),
            "{what}[{i}]: {x:e} vs {y:e} (diff {:e}); whole:\n{a:?}\nvs\n{b:?}",
            (x - y).abs()
        );
    }
}

/// Element-wise comparison of complex values, real and imaginary parts separately.
///
/// # Panics
/// As [`assert_all_close`].
#[track_caller]
pub fn assert_complex_close(
    what: &str,
    a: impl IntoIterator<Item = Complex<f64>>,
    b: impl IntoIterator<Item = Complex<f64>>,
    tol: Tol,
) {
    let flat = |v: Vec<Complex<f64>>| v.into_iter().flat_map(|z| [z.re, z.im]).collect::<Vec<_>>();
    assert_all_close(
        what,
        flat(a.into_iter().collect()),
        flat(b.into_iter().collect()),
        tol,
    );
}
