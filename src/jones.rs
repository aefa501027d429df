//! Jones calculus: fully polarized, fully coherent light and the linear elements acting on it.
//!
//! A [`JonesVector`] holds the transverse field components `(E_x, E_y)` of a plane wave in a
//! given transverse basis (x̂, ŷ); a [`JonesMatrix`] maps incident to exitant components,
//! `E′ = J E` (seed §S1, "Jones calculus"). Conventions: time dependence `e^{−iωt}`, so a phase
//! lag is a factor `e^{+iδ}`, and the circular state `(1, i)/√2` has `S3 = +1`.

use core::ops::Mul;

use nalgebra::{Matrix2, Vector2};
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::real::{Real, complex_is_finite};

/// The Jones vector `(E_x, E_y)` of a fully polarized plane wave in a transverse basis (x̂, ŷ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JonesVector<T: Real>(pub(crate) Vector2<Complex<T>>);

impl<T: Real> JonesVector<T> {
    /// A Jones vector from its two complex components.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if a component is NaN or infinite.
    pub fn new(ex: Complex<T>, ey: Complex<T>) -> Result<Self, Error> {
        if complex_is_finite(ex) && complex_is_finite(ey) {
            Ok(Self(Vector2::new(ex, ey)))
        } else {
            Err(Error::NonFinite {
                what: "Jones vector component",
            })
        }
    }

    /// The components as an nalgebra vector.
    #[inline]
    #[must_use]
    pub fn vector(&self) -> Vector2<Complex<T>> {
        self.0
    }

    /// `E_x`.
    #[inline]
    #[must_use]
    pub fn ex(&self) -> Complex<T> {
        self.0[0]
    }

    /// `E_y`.
    #[inline]
    #[must_use]
    pub fn ey(&self) -> Complex<T> {
        self.0[1]
    }
}

/// A 2×2 complex Jones matrix acting on [`JonesVector`]s: `E′ = J E`.
///
/// Rows index the exitant components, columns the incident ones, each in its own transverse basis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JonesMatrix<T: Real>(pub(crate) Matrix2<Complex<T>>);

impl<T: Real> JonesMatrix<T> {
    /// A Jones matrix from its entries.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if an entry is NaN or infinite.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// use nalgebra::Matrix2;
    /// use num_complex::Complex;
    /// let one = Complex::new(1.0_f64, 0.0);
    /// let zero = Complex::new(0.0, 0.0);
    /// let j = JonesMatrix::from_matrix(Matrix2::new(one, zero, zero, one)).unwrap();
    /// assert_eq!(j, JonesMatrix::identity());
    /// ```
    pub fn from_matrix(m: Matrix2<Complex<T>>) -> Result<Self, Error> {
        ensure_finite("Jones matrix entry", m.iter().flat_map(|z| [z.re, z.im]))?;
        Ok(Self(m))
    }

    /// The identity (free propagation in an unchanged basis).
    #[must_use]
    pub fn identity() -> Self {
        Self(Matrix2::identity())
    }

    /// The entries as an nalgebra matrix.
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Matrix2<Complex<T>> {
        self.0
    }

    /// An ideal linear polarizer transmitting the field component along `theta` (radians from x̂
    /// toward ŷ).
    ///
    /// # Formula
    /// ```text
    /// J = R(−θ) diag(1, 0) R(θ) = ⎡ cos²θ       cosθ sinθ ⎤,   R(θ) = ⎡  cosθ  sinθ ⎤
    ///                             ⎣ cosθ sinθ   sin²θ     ⎦          ⎣ −sinθ  cosθ ⎦
    /// ```
    /// Its Mueller matrix depends on `2θ` (Malus: `I′ = I cos²(θ − θ_in)`).
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// let j = JonesMatrix::<f64>::linear_polarizer(core::f64::consts::FRAC_PI_2);
    /// assert!(j.matrix()[(0, 0)].norm() < 1e-15 && (j.matrix()[(1, 1)].re - 1.0).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn linear_polarizer(theta: T) -> Self {
        let (s, c) = theta.sin_cos();
        let re = |x: T| Complex::new(x, T::zero());
        Self(Matrix2::new(re(c * c), re(c * s), re(c * s), re(s * s)))
    }

    /// A linear retarder with its fast axis at `theta` and phase retardance `retardance` (radians).
    ///
    /// # Formula
    /// ```text
    /// J = R(−θ) diag(1, e^{iδ}) R(θ)      (e^{−iωt}: the slow axis lags by e^{+iδ})
    /// ```
    /// A quarter-wave plate with fast axis x̂ is `diag(1, i)`: it maps +45° linear light to
    /// `S3 = +1` in this crate's convention.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// let q = JonesMatrix::<f64>::linear_retarder(0.0, core::f64::consts::FRAC_PI_2);
    /// assert!((q.matrix()[(1, 1)].im - 1.0).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn linear_retarder(theta: T, retardance: T) -> Self {
        let (s, c) = theta.sin_cos();
        let (sd, cd) = retardance.sin_cos();
        let e = Complex::new(cd, sd);
        let one = Complex::new(T::one(), T::zero());
        // R(−θ) diag(1, e) R(θ) expanded.
        let xx = one * (c * c) + e * (s * s);
        let yy = one * (s * s) + e * (c * c);
        let xy = (one - e) * (c * s);
        Self(Matrix2::new(xx, xy, xy, yy))
    }
}

impl<T: Real> Mul for JonesMatrix<T> {
    type Output = JonesMatrix<T>;
    /// Composition: `(J₂ * J₁)` is J₁ followed by J₂.
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        Self(self.0 * rhs.0)
    }
}

impl<T: Real> Mul<JonesVector<T>> for JonesMatrix<T> {
    type Output = JonesVector<T>;
    #[inline]
    fn mul(self, rhs: JonesVector<T>) -> JonesVector<T> {
        JonesVector(self.0 * rhs.0)
    }
}
