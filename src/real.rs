//! The scalar type the crate is generic over.
//!
//! Every numeric type in `gmueller` is generic over `T: Real`, implemented for `f32` (what
//! renderers run) and `f64` (the reference precision of the tests).

use nalgebra::RealField;
use num_complex::Complex;

/// A real floating-point scalar: `f32` or `f64`.
///
/// This is [`nalgebra::RealField`] (which brings `sqrt`, `sin_cos`, `exp_m1`, `hypot`, …) plus
/// `Copy`, and two lossless-enough conversions to and from `f64` for literals and error reports.
///
/// # Examples
/// ```
/// use gmueller::real::Real;
/// fn half<T: Real>(x: T) -> T { x * T::lit(0.5) }
/// assert_eq!(half(3.0_f32), 1.5);
/// assert_eq!(half(3.0_f64).to_f64(), 1.5);
/// ```
pub trait Real: RealField + Copy + Default + Send + Sync + 'static {
    /// Machine epsilon of the type (`2⁻²³` for `f32`, `2⁻⁵²` for `f64`).
    const EPSILON: Self;

    /// Converts an `f64` literal to `Self` (rounding to nearest for `f32`).
    #[must_use]
    fn lit(x: f64) -> Self;

    /// Converts `self` to `f64` (exact for both implementations).
    #[must_use]
    fn to_f64(self) -> f64;

    /// The complex number `re + i·im`.
    #[inline]
    #[must_use]
    fn cplx(re: Self, im: Self) -> Complex<Self> {
        Complex::new(re, im)
    }

    /// The loop behind [`crate::mueller::batch::mueller_from_jones_soa`] (lengths already
    /// checked): a portable scalar loop by default, run-time-dispatched SIMD for `f32` and `f64`.
    /// Not public API; call `mueller_from_jones_soa`.
    #[doc(hidden)]
    fn mueller_from_jones_soa_kernel(
        j: &crate::mueller::batch::JonesSoa<'_, Self>,
        out: &mut crate::mueller::batch::MuellerSoa<'_, Self>,
    ) {
        crate::mueller::batch::kernel_portable(j, out);
    }

    /// The loop behind [`crate::interaction::batch::plane_wave_rayleigh_rice`] (lengths already
    /// checked): `None` by default (the caller then runs the scalar kernel per direction),
    /// run-time-dispatched SIMD for `f32` and `f64`. Not public API.
    #[doc(hidden)]
    fn plane_wave_rayleigh_rice_kernel(
        _prep: &crate::interaction::batch::PlaneWavePrep<Self>,
        _exits: &crate::interaction::batch::DirectionsSoa<'_, Self>,
        _out: &mut crate::interaction::batch::StokesSoa<'_, Self>,
    ) -> Option<Result<(), crate::error::Error>> {
        None
    }
}

impl Real for f32 {
    const EPSILON: Self = f32::EPSILON;
    #[inline]
    fn plane_wave_rayleigh_rice_kernel(
        prep: &crate::interaction::batch::PlaneWavePrep<Self>,
        exits: &crate::interaction::batch::DirectionsSoa<'_, Self>,
        out: &mut crate::interaction::batch::StokesSoa<'_, Self>,
    ) -> Option<Result<(), crate::error::Error>> {
        Some(crate::interaction::batch::kernel_simd(prep, exits, out))
    }
    #[inline]
    fn mueller_from_jones_soa_kernel(
        j: &crate::mueller::batch::JonesSoa<'_, Self>,
        out: &mut crate::mueller::batch::MuellerSoa<'_, Self>,
    ) {
        crate::mueller::batch::kernel_simd(j, out);
    }
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
    #[inline]
    fn plane_wave_rayleigh_rice_kernel(
        prep: &crate::interaction::batch::PlaneWavePrep<Self>,
        exits: &crate::interaction::batch::DirectionsSoa<'_, Self>,
        out: &mut crate::interaction::batch::StokesSoa<'_, Self>,
    ) -> Option<Result<(), crate::error::Error>> {
        Some(crate::interaction::batch::kernel_simd(prep, exits, out))
    }
    #[inline]
    fn mueller_from_jones_soa_kernel(
        j: &crate::mueller::batch::JonesSoa<'_, Self>,
        out: &mut crate::mueller::batch::MuellerSoa<'_, Self>,
    ) {
        crate::mueller::batch::kernel_simd(j, out);
    }
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
