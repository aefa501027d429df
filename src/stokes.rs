//! Stokes parameters, the cross-spectral density (CSD) matrix, and `A_mül` between them (S1.1–S1.3).

use nalgebra::{Matrix4, Vector4};
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::real::Real;

/// The matrix `A_mül` of S1.3 that maps the (column-)stacked CSD matrix to Stokes parameters.
///
/// # Formula
/// ```text
/// S1.2:  S = A_mül vec(C),   vec(C) = (C_xx, C_yx, C_xy, C_yy)   (column stacking)
///
/// S1.3:         ⎡ 1   0   0   1 ⎤
///       A_mül = ⎢ 1   0   0  −1 ⎥
///               ⎢ 0   1   1   0 ⎥
///               ⎣ 0  −i   i   0 ⎦
/// ```
/// so `S0 = C_xx + C_yy`, `S1 = C_xx − C_yy`, `S2 = 2 Re C_xy`, `S3 = 2 Im C_yx = 2 Im⟨E_x* E_y⟩`.
///
/// # Examples
/// ```
/// use gmueller::stokes::{a_mul, a_mul_inv};
/// let p = a_mul::<f64>() * a_mul_inv::<f64>();
/// assert!((p - nalgebra::Matrix4::identity()).norm() < 1e-15);
/// ```
#[must_use]
pub fn a_mul<T: Real>() -> Matrix4<Complex<T>> {
    let o = Complex::new(T::one(), T::zero());
    let z = Complex::new(T::zero(), T::zero());
    let i = Complex::new(T::zero(), T::one());
    Matrix4::new(
        o, z, z, o, //
        o, z, z, -o, //
        z, o, o, z, //
        z, -i, i, z,
    )
}

/// The inverse of [`a_mul`]: `A_mül⁻¹ = ½ A_mül†`.
///
/// # Formula
/// ```text
///                 ⎡ 1   1   0   0 ⎤
///  A_mül⁻¹ = ½ ·  ⎢ 0   0   1   i ⎥
///                 ⎢ 0   0   1  −i ⎥
///                 ⎣ 1  −1   0   0 ⎦
/// ```
#[must_use]
pub fn a_mul_inv<T: Real>() -> Matrix4<Complex<T>> {
    a_mul::<T>().adjoint() * Complex::new(T::lit(0.5), T::zero())
}

/// A classical Stokes vector `(S0, S1, S2, S3)` with `S0 ≥ |(S1, S2, S3)|`.
///
/// Conventions (crate docs, "Conventions"): `S1 > 0` is x̂-polarized, `S2 > 0` is polarized at
/// +45° (between x̂ and ŷ), `S3 > 0` is the circular state `(1, i)/√2` under `e^{−iωt}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stokes<T: Real>(pub(crate) Vector4<T>);

impl<T: Real> Stokes<T> {
    /// Relative slack allowed in `S0 ≥ |S|` for rounding: `|S| ≤ S0 (1 + STOKES_SLACK_ULPS · ε)`.
    pub const SLACK_ULPS: f64 = 64.0;

    /// A validated Stokes vector.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞; [`Error::InvalidStokes`] if `S0 < |(S1, S2, S3)|` beyond
    /// a rounding slack of [`Self::SLACK_ULPS`] machine epsilons (relative), which includes `S0 < 0`.
    pub fn new(s0: T, s1: T, s2: T, s3: T) -> Result<Self, Error> {
        ensure_finite("Stokes parameter", [s0, s1, s2, s3])?;
        let polarized = (s1 * s1 + s2 * s2 + s3 * s3).sqrt();
        let slack = T::one() + T::lit(Self::SLACK_ULPS) * T::EPSILON;
        if s0 < T::zero() || polarized > s0 * slack {
            return Err(Error::InvalidStokes {
                s0: s0.to_f64(),
                polarized: polarized.to_f64(),
            });
        }
        Ok(Self(Vector4::new(s0, s1, s2, s3)))
    }

    /// A Stokes vector from any finite 4-vector, without checking `S0 ≥ |S|`.
    ///
    /// For results of operations that preserve validity up to rounding (a realizable Mueller
    /// matrix acting on a valid Stokes vector).
    #[inline]
    #[must_use]
    pub fn from_vector_unchecked(v: Vector4<T>) -> Self {
        Self(v)
    }

    /// Unpolarized light of intensity `s0`, `(s0, 0, 0, 0)`.
    ///
    /// # Errors
    /// As [`Stokes::new`] (`s0` must be finite and ≥ 0).
    pub fn unpolarized(s0: T) -> Result<Self, Error> {
        Self::new(s0, T::zero(), T::zero(), T::zero())
    }

    /// The parameters as an nalgebra vector.
    #[inline]
    #[must_use]
    pub fn vector(&self) -> Vector4<T> {
        self.0
    }

    /// `S0`, the total intensity.
    #[inline]
    #[must_use]
    pub fn s0(&self) -> T {
        self.0[0]
    }
}

/// Generalized (two-point) Stokes parameters: a complex 4-vector `A_mül vec(C(r₁, r₂))` (S1.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeneralizedStokes<T: Real>(pub(crate) Vector4<Complex<T>>);

impl<T: Real> GeneralizedStokes<T> {
    /// From its four complex components.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if a component is NaN or infinite.
    pub fn new(v: Vector4<Complex<T>>) -> Result<Self, Error> {
        ensure_finite(
            "generalized Stokes parameter",
            v.iter().flat_map(|z| [z.re, z.im]),
        )?;
        Ok(Self(v))
    }

    /// The components as an nalgebra vector.
    #[inline]
    #[must_use]
    pub fn vector(&self) -> Vector4<Complex<T>> {
        self.0
    }
}
