//! The scalar type the crate is generic over.
//!
//! Every numeric type in `gmueller` is generic over `T: Real`, implemented for `f32` (what
//! renderers run) and `f64` (the reference precision of the tests).

use nalgebra::RealField;
use num_complex::Complex;

use crate::simd::Lanes;

/// A real floating-point scalar: `f32` or `f64`.
///
/// This is [`nalgebra::RealField`] (which brings `sqrt`, `sin_cos`, `exp_m1`, `hypot`, …) plus
/// `Copy`, and two lossless-enough conversions to and from `f64` for literals and error reports,
/// and the sealed lane vocabulary `Lanes` of the batch paths (crate-private) (so `Real` is implemented for
/// `f32` and `f64` only).
///
/// # Examples
/// ```
/// use gmueller::real::Real;
/// fn half<T: Real>(x: T) -> T { x * T::lit(0.5) }
/// assert_eq!(half(3.0_f32), 1.5);
/// assert_eq!(half(3.0_f64).to_f64(), 1.5);
/// ```
pub trait Real: RealField + Lanes + Copy + Default + Send + Sync + 'static {
    /// Machine epsilon of the type (`2⁻²³` for `f32`, `2⁻⁵²` for `f64`).
    const EPSILON: Self;

    /// The smallest positive normal number (`f32::MIN_POSITIVE`, `f64::MIN_POSITIVE`).
    const MIN_POSITIVE: Self;

    /// The largest finite number (`f32::MAX`, `f64::MAX`).
    const MAX: Self;

    /// Converts an `f64` literal to `Self` (rounding to nearest for `f32`).
    #[must_use]
    fn lit(x: f64) -> Self;

    /// Converts `self` to `f64` (exact for both implementations).
    #[must_use]
    fn to_f64(self) -> f64;

    /// `a·b − c·d`, accurate under cancellation in `f32`: the two products of 24-bit significands
    /// are exact in `f64`, so the result is within a few ulps of the true value however much
    /// the products cancel. In `f64` this is the plain formula (error `ε (|ab| + |cd|)`).
    ///
    /// The 2×2 determinants of the crate (shape matrices, sections, blurs) go through it: a
    /// rotated shape of anisotropy 10⁶ has `ad ≈ bc`, and the plain `f32` determinant lost
    /// about a tenth of its value.
    ///
    /// # Examples
    /// ```
    /// use gmueller::real::Real;
    /// let (a, b) = (1.0f32 + f32::EPSILON, 1.0f32 - f32::EPSILON);
    /// // (1 + ε)(1 − ε) − 1 = −ε², which plain f32 arithmetic rounds to 0.
    /// assert_eq!(a * b - 1.0, 0.0);
    /// assert_eq!(f32::diff_of_products(a, b, 1.0, 1.0), -f32::EPSILON * f32::EPSILON);
    /// ```
    #[inline]
    #[must_use]
    fn diff_of_products(a: Self, b: Self, c: Self, d: Self) -> Self {
        Self::lit(a.to_f64() * b.to_f64() - c.to_f64() * d.to_f64())
    }

    /// The complex number `re + i·im`.
    #[inline]
    #[must_use]
    fn cplx(re: Self, im: Self) -> Complex<Self> {
        Complex::new(re, im)
    }
}

impl Real for f32 {
    const EPSILON: Self = f32::EPSILON;
    const MIN_POSITIVE: Self = f32::MIN_POSITIVE;
    const MAX: Self = f32::MAX;
    #[inline]
    fn lit(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

impl Real for f64 {
    const EPSILON: Self = f64::EPSILON;
    const MIN_POSITIVE: Self = f64::MIN_POSITIVE;
    const MAX: Self = f64::MAX;
    #[inline]
    fn lit(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
}

/// `true` when the real and imaginary parts of `z` are both finite.
#[inline]
#[must_use]
pub fn complex_is_finite<T: Real>(z: Complex<T>) -> bool {
    z.re.is_finite() && z.im.is_finite()
}
