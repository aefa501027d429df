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

/// The handedness of a circular polarization state, named by the sign of `S3`.
///
/// Names of handedness disagree between books and libraries, so the variants are named by the
/// sign of the Stokes parameter `S3 = 2 Im(E_x* E_y)` in this crate's convention (time
/// dependence `e^{−iωt}`), which is unambiguous:
///
/// | variant | Jones vector | `S3` | field at a fixed point | Born & Wolf | Mitsuba 3 / py-pol / pypolar |
/// |---|---|---|---|---|---|
/// | [`PositiveS3`](Self::PositiveS3) | `(1, i)/√2` | `+1` | turns from x̂ toward ŷ | left-handed (seen facing the source) | printed with `S3 = −1` |
/// | [`NegativeS3`](Self::NegativeS3) | `(1, −i)/√2` | `−1` | turns from ŷ toward x̂ | right-handed (seen facing the source) | printed with `S3 = +1` |
///
/// With `e^{−iωt}` the real field of `(1, i)` is `(cos ωt, sin ωt)`, which turns from x̂ toward ŷ
/// (counter-clockwise for an observer facing the source when x̂, ŷ, k̂ is right-handed). Mitsuba 3,
/// py-pol and pypolar use `e^{+iωt}`, so they assign the same physical state the opposite `S3`
/// (convert with `D = diag(1, 1, 1, −1)`); SCATMECH agrees with this crate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Handedness {
    /// `S3 = +1`: Jones vector `(1, i)/√2`; Born & Wolf's *left-handed* circular light.
    PositiveS3,
    /// `S3 = −1`: Jones vector `(1, −i)/√2`; Born & Wolf's *right-handed* circular light.
    NegativeS3,
}

impl Handedness {
    /// The sign of `S3` of this state: `+1` or `−1`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::Handedness;
    /// assert_eq!(Handedness::PositiveS3.s3_sign::<f64>(), 1.0);
    /// assert_eq!(Handedness::NegativeS3.s3_sign::<f32>(), -1.0);
    /// ```
    #[inline]
    #[must_use]
    pub fn s3_sign<T: Real>(self) -> T {
        match self {
            Handedness::PositiveS3 => T::one(),
            Handedness::NegativeS3 => -T::one(),
        }
    }

    /// The opposite handedness.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::Handedness;
    /// assert_eq!(Handedness::PositiveS3.opposite(), Handedness::NegativeS3);
    /// ```
    #[inline]
    #[must_use]
    pub fn opposite(self) -> Self {
        match self {
            Handedness::PositiveS3 => Handedness::NegativeS3,
            Handedness::NegativeS3 => Handedness::PositiveS3,
        }
    }
}

/// `x + 0i`.
#[inline]
fn re<T: Real>(x: T) -> Complex<T> {
    Complex::new(x, T::zero())
}

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

    /// Linear polarization of unit intensity at angle `theta` (radians from x̂ toward ŷ).
    ///
    /// # Formula
    /// ```text
    /// E = (cos θ, sin θ)        Stokes: (1, cos 2θ, sin 2θ, 0)
    /// ```
    /// Infallible: a NaN or infinite `theta` gives NaN components.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesVector;
    /// let s = JonesVector::<f64>::linear(core::f64::consts::FRAC_PI_4).to_stokes().vector();
    /// assert!((s[0] - 1.0).abs() < 1e-15 && s[1].abs() < 1e-15 && (s[2] - 1.0).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn linear(theta: T) -> Self {
        let (s, c) = theta.sin_cos();
        Self(Vector2::new(re(c), re(s)))
    }

    /// Circular polarization of unit intensity with the given [`Handedness`].
    ///
    /// # Formula
    /// ```text
    /// PositiveS3:  E = (1,  i)/√2,  Stokes (1, 0, 0, +1)
    /// NegativeS3:  E = (1, −i)/√2,  Stokes (1, 0, 0, −1)
    /// ```
    /// See [`Handedness`] for how these map to Born & Wolf's and other libraries' names.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::{Handedness, JonesVector};
    /// let s = JonesVector::<f64>::circular(Handedness::PositiveS3).to_stokes().vector();
    /// assert!((s[3] - 1.0).abs() < 1e-15 && s[1].abs() < 1e-15 && s[2].abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn circular(hand: Handedness) -> Self {
        let h = T::lit(core::f64::consts::FRAC_1_SQRT_2);
        Self(Vector2::new(
            re(h),
            Complex::new(T::zero(), hand.s3_sign::<T>() * h),
        ))
    }

    /// Elliptical polarization of unit intensity with major-axis azimuth `azimuth` (ψ, radians from
    /// x̂ toward ŷ) and ellipticity angle `ellipticity` (χ, `tan χ = ±b/a`, the ratio of the
    /// ellipse's semi-axes, signed by the sense of rotation).
    ///
    /// # Formula
    /// ```text
    /// E = R(ψ) (cos χ, i sin χ),   R(ψ) = ⎡ cos ψ  −sin ψ ⎤
    ///                                     ⎣ sin ψ   cos ψ ⎦
    /// Stokes: S0 = 1,  S1 = cos 2χ cos 2ψ,  S2 = cos 2χ sin 2ψ,  S3 = sin 2χ
    /// ```
    /// `χ > 0` turns from x̂ toward ŷ like [`Handedness::PositiveS3`]; `χ = ±π/4` is circular,
    /// `χ = 0` is [`linear`](Self::linear)`(ψ)`. Infallible: NaN propagates.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesVector;
    /// let (psi, chi) = (0.3_f64, 0.2_f64);
    /// let s = JonesVector::elliptical(psi, chi).to_stokes().vector();
    /// assert!((s[1] - (2.0 * chi).cos() * (2.0 * psi).cos()).abs() < 1e-15);
    /// assert!((s[3] - (2.0 * chi).sin()).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn elliptical(azimuth: T, ellipticity: T) -> Self {
        let (sp, cp) = azimuth.sin_cos();
        let (sc, cc) = ellipticity.sin_cos();
        // R(ψ) (cos χ, i sin χ)
        Self(Vector2::new(
            Complex::new(cp * cc, -sp * sc),
            Complex::new(sp * cc, cp * sc),
        ))
    }

    /// The intensity `|E_x|² + |E_y|²` (= `S0`).
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesVector;
    /// use num_complex::Complex;
    /// let v = JonesVector::new(Complex::new(3.0_f64, 0.0), Complex::new(0.0, 4.0)).unwrap();
    /// assert!((v.intensity() - 25.0).abs() < 1e-12);
    /// ```
    #[inline]
    #[must_use]
    pub fn intensity(&self) -> T {
        self.0[0].norm_sqr() + self.0[1].norm_sqr()
    }

    /// The state scaled by a complex factor `z` (amplitude `|z|`, phase `arg z`).
    ///
    /// # Formula
    /// ```text
    /// E′ = z E,   so   S′ = |z|² S
    /// ```
    /// Infallible: a non-finite `z` gives non-finite components.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesVector;
    /// use num_complex::Complex;
    /// let v = JonesVector::<f64>::linear(0.0).scaled(Complex::new(0.0, 2.0));
    /// assert!((v.intensity() - 4.0).abs() < 1e-15 && (v.ex().im - 2.0).abs() < 1e-15);
    /// ```
    #[inline]
    #[must_use]
    pub fn scaled(&self, z: Complex<T>) -> Self {
        Self(self.0 * z)
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

    /// A linear diattenuator: field amplitude transmission `tx` along the axis at `theta` (radians
    /// from x̂ toward ŷ) and `ty` along the perpendicular axis.
    ///
    /// # Formula
    /// ```text
    /// J = R(−θ) diag(t_x, t_y) R(θ) = ⎡ t_x cos²θ + t_y sin²θ    (t_x − t_y) cosθ sinθ ⎤
    ///                                 ⎣ (t_x − t_y) cosθ sinθ    t_x sin²θ + t_y cos²θ ⎦
    /// ```
    /// `t` are amplitude (not intensity) transmissions: the intensity transmissions are `t_x²`,
    /// `t_y²`. `(1, 0, θ)` is [`linear_polarizer`](Self::linear_polarizer)`(θ)`.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if an input is NaN or infinite; [`Error::OutOfRange`] unless
    /// `0 ≤ t_x ≤ 1` and `0 ≤ t_y ≤ 1`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// let d = JonesMatrix::<f64>::diattenuator(1.0, 0.5, 0.0).unwrap();
    /// assert!((d.matrix()[(1, 1)].re - 0.5).abs() < 1e-15);
    /// assert!(JonesMatrix::<f64>::diattenuator(1.5, 0.5, 0.0).is_err());
    /// ```
    pub fn diattenuator(tx: T, ty: T, theta: T) -> Result<Self, Error> {
        ensure_finite("diattenuator input", [tx, ty, theta])?;
        for (what, t) in [("diattenuator t_x", tx), ("diattenuator t_y", ty)] {
            if t < T::zero() || t > T::one() {
                return Err(Error::OutOfRange {
                    what,
                    value: t.to_f64(),
                    expected: "[0, 1]",
                });
            }
        }
        let (s, c) = theta.sin_cos();
        let xx = tx * c * c + ty * s * s;
        let yy = tx * s * s + ty * c * c;
        let xy = (tx - ty) * c * s;
        Ok(Self(Matrix2::new(re(xx), re(xy), re(xy), re(yy))))
    }

    /// A rotator (optically active medium): turns the field by `angle` (radians) counter-clockwise,
    /// from x̂ toward ŷ, in a fixed basis.
    ///
    /// # Formula
    /// ```text
    /// J = R(ρ) = ⎡ cos ρ  −sin ρ ⎤        Mueller: rotates (S1, S2) by 2ρ, leaves S0, S3
    ///            ⎣ sin ρ   cos ρ ⎦
    /// ```
    /// Linear light at `θ` leaves at `θ + ρ`. Its eigenstates are the circular states:
    /// `R(ρ)(1, ±i)/√2 = e^{∓iρ}(1, ±i)/√2`, so a rotation by `ρ` is a
    /// [`circular_retarder`](Self::circular_retarder) of retardance `2ρ`. This is a physical
    /// element acting on the field, not a change of basis: re-expressing a fixed field in a basis
    /// turned by `ψ` is `R(−ψ)` (the τ of S2.3, module `frame`).
    /// Infallible: NaN propagates.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::{JonesMatrix, JonesVector};
    /// let v = JonesMatrix::<f64>::rotator(0.5) * JonesVector::linear(0.2);
    /// assert!((v.ex().re - 0.7_f64.cos()).abs() < 1e-15 && (v.ey().re - 0.7_f64.sin()).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn rotator(angle: T) -> Self {
        let (s, c) = angle.sin_cos();
        Self(Matrix2::new(re(c), re(-s), re(s), re(c)))
    }

    /// A circular retarder of retardance `retardance` (δ, radians): the state
    /// [`Handedness::NegativeS3`] lags the state [`Handedness::PositiveS3`] by `e^{+iδ}`.
    ///
    /// # Formula
    /// ```text
    /// J = R(δ/2) = ⎡ cos δ/2  −sin δ/2 ⎤,   J (1, ±i)/√2 = e^{∓iδ/2} (1, ±i)/√2
    ///              ⎣ sin δ/2   cos δ/2 ⎦
    /// ```
    /// This is the same matrix as [`rotator`](Self::rotator)`(δ/2)`: the `PositiveS3` state is the
    /// fast one, as x̂ is for [`linear_retarder`](Self::linear_retarder)`(0, δ) = diag(1, e^{iδ})`
    /// (`e^{−iωt}`: a lag is `e^{+iδ}`). Infallible: NaN propagates.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// let a = JonesMatrix::<f64>::circular_retarder(1.0).matrix();
    /// let b = JonesMatrix::<f64>::rotator(0.5).matrix();
    /// assert!((a - b).iter().all(|z| z.norm() < 1e-15));
    /// ```
    #[must_use]
    pub fn circular_retarder(retardance: T) -> Self {
        Self::rotator(retardance * T::lit(0.5))
    }

    /// An ideal circular polarizer transmitting the circular state of handedness `hand` and
    /// extinguishing the other.
    ///
    /// # Formula
    /// ```text
    /// J = v v†,   v = (1, ±i)/√2:
    /// PositiveS3:  J = ½ ⎡ 1  −i ⎤      NegativeS3:  J = ½ ⎡ 1   i ⎤
    ///                    ⎣ i   1 ⎦                         ⎣ −i  1 ⎦
    /// ```
    /// The output is always the state `v` (a homogeneous polarizer: the exit state equals the
    /// transmitted eigenstate), with intensity `|v† E|²`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::{Handedness, JonesMatrix, JonesVector};
    /// let p = JonesMatrix::<f64>::circular_polarizer(Handedness::PositiveS3);
    /// let out = p * JonesVector::circular(Handedness::NegativeS3);
    /// assert!(out.intensity() < 1e-30);
    /// ```
    #[must_use]
    pub fn circular_polarizer(hand: Handedness) -> Self {
        let h = T::lit(0.5);
        let i = Complex::new(T::zero(), hand.s3_sign::<T>() * h);
        Self(Matrix2::new(re(h), -i, i, re(h)))
    }

    /// The determinant `J₁₁ J₂₂ − J₁₂ J₂₁`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// let d = JonesMatrix::<f64>::linear_retarder(0.3, 1.0).determinant();
    /// assert!((d.norm() - 1.0).abs() < 1e-15);
    /// ```
    #[inline]
    #[must_use]
    pub fn determinant(&self) -> Complex<T> {
        let m = &self.0;
        m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)]
    }

    /// The inverse, or `None` if the matrix is singular to working precision.
    ///
    /// # Formula
    /// ```text
    /// J⁻¹ = (1 / det J) ⎡  J₂₂  −J₁₂ ⎤
    ///                   ⎣ −J₂₁   J₁₁ ⎦
    /// ```
    /// `None` when `|det J| ≤ 8 ε ‖J‖_F²` (ε the machine epsilon of `T`), which catches ideal
    /// polarizers whose rounded determinant is a few ulps instead of 0, or when the result is not
    /// finite (non-finite input).
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// let j = JonesMatrix::<f64>::linear_retarder(0.3, 1.0);
    /// let p = (j.inverse().unwrap() * j).matrix();
    /// assert!((p[(0, 0)].re - 1.0).abs() < 1e-15 && p[(0, 1)].norm() < 1e-15);
    /// assert!(JonesMatrix::<f64>::linear_polarizer(0.3).inverse().is_none());
    /// ```
    #[must_use]
    pub fn inverse(&self) -> Option<Self> {
        let det = self.determinant();
        let norm2 = self.0.iter().fold(T::zero(), |acc, z| acc + z.norm_sqr());
        let det_abs = det.norm_sqr().sqrt();
        if !det_abs.is_finite() || det_abs <= T::lit(8.0) * T::EPSILON * norm2 {
            return None;
        }
        let m = &self.0;
        let inv = Matrix2::new(m[(1, 1)], -m[(0, 1)], -m[(1, 0)], m[(0, 0)]) / det;
        if inv.iter().all(|z| complex_is_finite(*z)) {
            Some(Self(inv))
        } else {
            None
        }
    }

    /// The Hermitian adjoint (conjugate transpose) `J†`.
    ///
    /// A unitary (lossless) element satisfies `J† J = I`; the adjoint is also the Jones matrix of
    /// the element traversed in reverse for reciprocal media expressed in a suitable basis.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// let j = JonesMatrix::<f64>::linear_retarder(0.3, 1.0);
    /// let p = (j.adjoint() * j).matrix();
    /// assert!((p[(1, 1)].re - 1.0).abs() < 1e-15 && p[(1, 0)].norm() < 1e-15);
    /// ```
    #[inline]
    #[must_use]
    pub fn adjoint(&self) -> Self {
        Self(self.0.adjoint())
    }

    /// The complex conjugate `J*` (entry-wise).
    ///
    /// Conjugation maps this crate's `e^{−iωt}` Jones matrices to those of the `e^{+iωt}`
    /// convention (Mitsuba 3, py-pol), and enters S1.7 as the left factor of `J* ⊗ J`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// let q = JonesMatrix::<f64>::linear_retarder(0.0, core::f64::consts::FRAC_PI_2).conj();
    /// assert!((q.matrix()[(1, 1)].im + 1.0).abs() < 1e-15);
    /// ```
    #[inline]
    #[must_use]
    pub fn conj(&self) -> Self {
        Self(self.0.map(|z| z.conj()))
    }

    /// The matrix multiplied by a complex factor `z` (e.g. a common amplitude or phase).
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesMatrix;
    /// use num_complex::Complex;
    /// let j = JonesMatrix::<f64>::identity().scaled(Complex::new(0.0, 2.0));
    /// assert!((j.matrix()[(0, 0)].im - 2.0).abs() < 1e-15);
    /// ```
    #[inline]
    #[must_use]
    pub fn scaled(&self, z: Complex<T>) -> Self {
        Self(self.0 * z)
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
