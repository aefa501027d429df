//! Stokes parameters, the cross-spectral density (CSD) matrix, and `A_mül` between them (S1.1–S1.3).
//!
//! A CSD matrix `C = ⟨E(r₁) E(r₂)†⟩` (S1.1) and the generalized Stokes parameters
//! `S = A_mül vec(C)` (S1.2) carry the same information; `vec` is column stacking
//! ([`crate::stack::stack`], erratum 1). Equivalently `S_k = tr(σ_k C)` and `C = ½ Σ_k S_k σ_k`
//! with σ₀ = I, σ₁ = diag(1, −1), σ₂ = [[0, 1], [1, 0]], σ₃ = [[0, −i], [i, 0]].

use core::ops::{Add, Mul, Neg, Sub};

use nalgebra::{Matrix2, Matrix4, Vector4};
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::jones::JonesVector;
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

/// `√(a² + b² + c²)` without overflow or underflow of the squares (`hypot` twice): the plain
/// sum of squares overflows f32 above ~1.8e19 and underflows f64 below ~1.5e-154, which made
/// [`Stokes::new`] reject valid vectors of large intensity and accept invalid tiny ones.
#[inline]
fn norm3<T: Real>(a: T, b: T, c: T) -> T {
    a.hypot(b).hypot(c)
}

/// `max(|S0|, |S1|, |S2|, |S3|)`, the normalisation of the scale-invariant checks.
#[inline]
fn max_abs4<T: Real>(v: &Vector4<T>) -> T {
    v.iter().fold(T::zero(), |m, x| m.max(x.abs()))
}

/// `|(S1, S2, S3)|` and `S0`, both divided by `m = max |Sₖ|` (so each is at most `√3` and `1`):
/// the comparison `S0 ≥ |S|` made on these cannot overflow, and is exactly invariant under
/// scaling by powers of two. `(0, 0)` for the zero vector.
#[inline]
fn normalized_parts<T: Real>(v: &Vector4<T>) -> (T, T, T) {
    let m = max_abs4(v);
    if m == T::zero() {
        return (T::zero(), T::zero(), T::zero());
    }
    let u = v / m;
    (u[0], norm3(u[1], u[2], u[3]), m)
}

/// `(a + b)/2` without overflowing when `a + b` does (each halved first only then, so that
/// subnormal sums keep their last bit).
#[inline]
fn half_sum<T: Real>(a: T, b: T) -> T {
    let s = a + b;
    if s.is_finite() {
        s * T::lit(0.5)
    } else {
        a * T::lit(0.5) + b * T::lit(0.5)
    }
}

/// [`half_sum`] of complex numbers, part by part.
#[inline]
fn half_sum_c<T: Real>(a: Complex<T>, b: Complex<T>) -> Complex<T> {
    Complex::new(half_sum(a.re, b.re), half_sum(a.im, b.im))
}

impl<T: Real> Stokes<T> {
    /// Relative slack allowed in `S0 ≥ |S|` for rounding: `|S| ≤ S0 (1 + STOKES_SLACK_ULPS · ε)`.
    pub const SLACK_ULPS: f64 = 64.0;

    /// A validated Stokes vector.
    ///
    /// The check `S0 ≥ |(S1, S2, S3)|` is made on the vector divided by its largest magnitude
    /// `max |Sₖ|`, so it is scale invariant (exactly, for scalings by powers of two) and cannot
    /// overflow: `(MAX, 0.9·MAX, 0.9·MAX, 0)` is rejected like `(1, 0.9, 0.9, 0)`. Every
    /// accepted vector has a finite polarized intensity `|(S1, S2, S3)|`, so
    /// [`Self::degree_of_polarization`] and the other degrees are finite, of magnitude at most
    /// `1 + 64ε`.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞, and for a valid vector whose polarized intensity
    /// `|(S1, S2, S3)|` overflows (possible only with `S0` within 64ε of `T::MAX`);
    /// [`Error::InvalidStokes`] if `S0 < |(S1, S2, S3)|` beyond a rounding slack of
    /// [`Self::SLACK_ULPS`] machine epsilons (relative), which includes `S0 < 0`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::Stokes;
    /// let m = f64::MAX;
    /// assert!(Stokes::new(m, 0.9 * m, 0.9 * m, 0.0).is_err()); // |S| = 1.27 S0
    /// let s = Stokes::new(m, 0.6 * m, 0.8 * m, 0.0).unwrap();
    /// assert!((s.degree_of_polarization() - 1.0).abs() < 1e-15);
    /// ```
    pub fn new(s0: T, s1: T, s2: T, s3: T) -> Result<Self, Error> {
        ensure_finite("Stokes parameter", [s0, s1, s2, s3])?;
        let v = Vector4::new(s0, s1, s2, s3);
        let (a0, pol, m) = normalized_parts(&v);
        let slack = T::one() + T::lit(Self::SLACK_ULPS) * T::EPSILON;
        if a0 < T::zero() || pol > a0 * slack {
            return Err(Error::InvalidStokes {
                s0: s0.to_f64(),
                polarized: pol.to_f64() * m.to_f64(),
            });
        }
        ensure_finite("polarized intensity |(S1, S2, S3)| (overflow)", [pol * m])?;
        Ok(Self(v))
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

    /// `S1 = C_xx − C_yy`: positive for x̂-polarized light.
    #[inline]
    #[must_use]
    pub fn s1(&self) -> T {
        self.0[1]
    }

    /// `S2 = 2 Re C_xy`: positive for light polarized at +45° (between x̂ and ŷ).
    #[inline]
    #[must_use]
    pub fn s2(&self) -> T {
        self.0[2]
    }

    /// `S3 = 2 Im⟨E_x* E_y⟩`: positive for the circular state `(1, i)/√2` under `e^{−iωt}`.
    #[inline]
    #[must_use]
    pub fn s3(&self) -> T {
        self.0[3]
    }

    /// `|(S1, S2, S3)|`, the polarized intensity; finite for every vector [`Stokes::new`]
    /// accepts (computed as `m · |(S1, S2, S3)/m|`, `m = max |Sₖ|`, the form that check uses).
    #[inline]
    #[must_use]
    pub fn polarized_intensity(&self) -> T {
        let (_, pol, m) = normalized_parts(&self.0);
        pol * m
    }

    /// The degree of polarization, in `[0, 1]` (up to rounding).
    ///
    /// # Formula
    /// ```text
    /// DoP = √(S1² + S2² + S3²) / S0
    /// ```
    /// Computed on the vector divided by `max |Sₖ|`, so it neither overflows nor underflows at
    /// any scale (`S0` from the smallest subnormal to `T::MAX`). Zero intensity (`S0 = 0`, which
    /// validity forces to be the zero vector) returns 0.
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::Stokes;
    /// let s = Stokes::new(2.0_f64, 1.0, 0.0, 0.0).unwrap();
    /// assert!((s.degree_of_polarization() - 0.5).abs() < 1e-15);
    /// assert_eq!(Stokes::new(0.0_f64, 0.0, 0.0, 0.0).unwrap().degree_of_polarization(), 0.0);
    /// ```
    #[must_use]
    pub fn degree_of_polarization(&self) -> T {
        let (a0, pol, _) = normalized_parts(&self.0);
        ratio_or_zero(pol, a0)
    }

    /// The degree of linear polarization, in `[0, 1]` (up to rounding).
    ///
    /// # Formula
    /// ```text
    /// DoLP = √(S1² + S2²) / S0
    /// ```
    /// Zero intensity returns 0.
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::Stokes;
    /// let s = Stokes::new(1.0_f64, 0.6, 0.0, 0.8).unwrap();
    /// assert!((s.degree_of_linear_polarization() - 0.6).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn degree_of_linear_polarization(&self) -> T {
        let m = max_abs4(&self.0);
        if m == T::zero() {
            return T::zero();
        }
        ratio_or_zero((self.s1() / m).hypot(self.s2() / m), self.s0() / m)
    }

    /// The **signed** degree of circular polarization, in `[−1, 1]` (up to rounding).
    ///
    /// # Formula
    /// ```text
    /// DoCP = S3 / S0
    /// ```
    /// Positive for the state `(1, i)/√2` (the field turns from x̂ toward ŷ under `e^{−iωt}`; Born &
    /// Wolf's left-handed, seen facing the source). Take `abs()` for the unsigned degree. Zero
    /// intensity returns 0.
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::Stokes;
    /// let s = Stokes::new(1.0_f64, 0.6, 0.0, -0.8).unwrap();
    /// assert!((s.degree_of_circular_polarization() + 0.8).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn degree_of_circular_polarization(&self) -> T {
        ratio_or_zero(self.s3(), self.s0())
    }

    /// The azimuth ψ of the polarization ellipse's major axis, in `(−π/2, π/2]`, radians from x̂
    /// toward ŷ.
    ///
    /// # Formula
    /// ```text
    /// ψ = ½ atan2(S2, S1)
    /// ```
    /// Undefined for circular or unpolarized light (`S1 = S2 = 0`); then 0 is returned
    /// (`atan2(±0, ±0)` is finite, never NaN).
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::Stokes;
    /// let s = Stokes::new(1.0_f64, 0.0, 1.0, 0.0).unwrap(); // +45° linear
    /// assert!((s.azimuth() - core::f64::consts::FRAC_PI_4).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn azimuth(&self) -> T {
        if self.s1() == T::zero() && self.s2() == T::zero() {
            return T::zero();
        }
        T::lit(0.5) * self.s2().atan2(self.s1())
    }

    /// The ellipticity angle χ of the polarization ellipse, in `[−π/4, π/4]`.
    ///
    /// # Formula
    /// ```text
    /// χ = ½ asin(S3 / √(S1² + S2² + S3²))
    /// ```
    /// `tan χ` is the signed ratio of minor to major axis; `χ > 0` has the handedness of
    /// `(1, i)/√2` (`S3 > 0`). Unpolarized or zero light (`|S| = 0`) returns 0. The ratio is clamped
    /// to `[−1, 1]` against rounding.
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::Stokes;
    /// let s = Stokes::new(2.0_f64, 0.0, 0.0, 1.0).unwrap(); // partially polarized, circular part
    /// assert!((s.ellipticity_angle() - core::f64::consts::FRAC_PI_4).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn ellipticity_angle(&self) -> T {
        let (_, pol, m) = normalized_parts(&self.0);
        let r = if m == T::zero() {
            T::zero()
        } else {
            ratio_or_zero(self.s3() / m, pol)
        };
        T::lit(0.5) * r.clamp(-T::one(), T::one()).asin()
    }

    /// The fully polarized part `(|S|, S1, S2, S3)` of the decomposition `S = S_pol + S_unpol`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::Stokes;
    /// let s = Stokes::new(2.0_f64, 0.0, 0.6, 0.8).unwrap();
    /// assert!((s.polarized_part().s0() - 1.0).abs() < 1e-15);
    /// assert!((s.unpolarized_part().s0() - 1.0).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn polarized_part(&self) -> Self {
        Self(Vector4::new(
            self.polarized_intensity(),
            self.s1(),
            self.s2(),
            self.s3(),
        ))
    }

    /// The unpolarized part `(S0 − |S|, 0, 0, 0)`, with `S0 − |S|` clamped at 0 against the
    /// rounding slack allowed by [`Stokes::new`].
    #[must_use]
    pub fn unpolarized_part(&self) -> Self {
        let u = (self.s0() - self.polarized_intensity()).max(T::zero());
        Self(Vector4::new(u, T::zero(), T::zero(), T::zero()))
    }

    /// The same light as [`GeneralizedStokes`] (real components; the one-point case r₁ = r₂).
    #[must_use]
    pub fn to_generalized(&self) -> GeneralizedStokes<T> {
        GeneralizedStokes(self.0.map(|x| Complex::new(x, T::zero())))
    }

    /// The one-point CSD matrix `C = ½ Σ_k S_k σ_k` of this light (the inverse of S1.2).
    ///
    /// Exactly Hermitian; positive semidefinite up to the rounding slack [`Stokes::new`] allows
    /// (`det C = ¼ (S0² − |S|²)`).
    #[must_use]
    pub fn to_csd(&self) -> CsdMatrix<T> {
        CsdMatrix {
            m: self.to_generalized().csd_matrix(),
            one_point: true,
        }
    }
}

/// `num / den`, or 0 when `den` is 0 (the degenerate zero-intensity / unpolarized cases).
fn ratio_or_zero<T: Real>(num: T, den: T) -> T {
    if den == T::zero() {
        T::zero()
    } else {
        num / den
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

impl<T: Real> GeneralizedStokes<T> {
    /// The generalized Stokes parameters of a CSD matrix (S1.2), in closed form.
    ///
    /// # Formula
    /// ```text
    /// S1.2:  S = A_mül vec(C):   S0 = C_xx + C_yy,   S1 = C_xx − C_yy,
    ///                            S2 = C_xy + C_yx,   S3 = i (C_xy − C_yx)
    /// ```
    /// For a one-point (Hermitian) CSD all four are real.
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::{CsdMatrix, GeneralizedStokes};
    /// use nalgebra::Matrix2;
    /// use num_complex::Complex;
    /// let z = |re: f64, im: f64| Complex::new(re, im);
    /// let c = CsdMatrix::two_point(Matrix2::new(z(1.0, 0.5), z(0.0, 1.0), z(2.0, 0.0), z(0.5, 0.0))).unwrap();
    /// let s = GeneralizedStokes::from_csd(&c);
    /// assert!((s.vector()[3] - z(-1.0, -2.0)).norm() < 1e-15); // i (i − 2)
    /// ```
    #[must_use]
    pub fn from_csd(c: &CsdMatrix<T>) -> Self {
        let m = &c.m;
        let (xx, xy, yx, yy) = (m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]);
        let d = xy - yx;
        Self(Vector4::new(
            xx + yy,
            xx - yy,
            xy + yx,
            // i · d
            Complex::new(-d.im, d.re),
        ))
    }

    /// The CSD matrix described by these parameters (the inverse of S1.2), as a two-point CSD.
    ///
    /// # Formula
    /// ```text
    /// vec(C) = A_mül⁻¹ S  ⇔  C = ½ Σ_k S_k σ_k = ½ ⎡ S0 + S1      S2 − i S3 ⎤
    ///                                              ⎣ S2 + i S3    S0 − S1   ⎦
    /// ```
    /// The result is flagged two-point (not validated as Hermitian); use
    /// [`CsdMatrix::to_stokes`] to validate it as a one-point CSD.
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::{CsdMatrix, GeneralizedStokes};
    /// use nalgebra::{Matrix2, Vector4};
    /// use num_complex::Complex;
    /// let z = |re: f64, im: f64| Complex::new(re, im);
    /// let m = Matrix2::new(z(1.0, 0.5), z(0.0, 1.0), z(2.0, 0.0), z(0.5, 0.0));
    /// let back = GeneralizedStokes::from_csd(&CsdMatrix::two_point(m).unwrap()).to_csd();
    /// assert!((back.matrix() - m).norm() < 1e-15);
    /// ```
    #[must_use]
    pub fn to_csd(&self) -> CsdMatrix<T> {
        CsdMatrix {
            m: self.csd_matrix(),
            one_point: false,
        }
    }

    /// `½ Σ_k S_k σ_k`, halving before adding where the sum would overflow (so the CSD of
    /// any finite parameters is finite).
    fn csd_matrix(&self) -> Matrix2<Complex<T>> {
        let s = &self.0;
        // i · S3
        let is3 = Complex::new(-s[3].im, s[3].re);
        Matrix2::new(
            half_sum_c(s[0], s[1]),
            half_sum_c(s[2], -is3),
            half_sum_c(s[2], is3),
            half_sum_c(s[0], -s[1]),
        )
    }
}

impl<T: Real> Add for GeneralizedStokes<T> {
    type Output = Self;
    /// Component-wise sum (incoherent superposition of the underlying fields' CSDs).
    #[inline]
    fn add(self, rhs: Self) -> Self {
        Self(self.0 + rhs.0)
    }
}

impl<T: Real> Sub for GeneralizedStokes<T> {
    type Output = Self;
    #[inline]
    fn sub(self, rhs: Self) -> Self {
        Self(self.0 - rhs.0)
    }
}

impl<T: Real> Neg for GeneralizedStokes<T> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self(-self.0)
    }
}

impl<T: Real> Mul<T> for GeneralizedStokes<T> {
    type Output = Self;
    /// Scaling by a real factor.
    #[inline]
    fn mul(self, rhs: T) -> Self {
        Self(self.0.map(|z| z * rhs))
    }
}

impl<T: Real> Mul<Complex<T>> for GeneralizedStokes<T> {
    type Output = Self;
    /// Scaling by a complex factor (e.g. a propagation phase `e^{ik r̂·(r₁−r₂)}`).
    #[inline]
    fn mul(self, rhs: Complex<T>) -> Self {
        Self(self.0 * rhs)
    }
}

/// A 2×2 cross-spectral density (CSD) matrix `C = ⟨E(r₁) E(r₂)†⟩` (S1.1).
///
/// Built either as a validated **one-point** CSD ([`CsdMatrix::one_point`], r₁ = r₂: Hermitian
/// positive semidefinite, the coherency matrix of classical optics) or as a **two-point** CSD
/// ([`CsdMatrix::two_point`]: any finite complex matrix, since `C(r₁, r₂)† = C(r₂, r₁)` need not
/// equal `C(r₁, r₂)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CsdMatrix<T: Real> {
    m: Matrix2<Complex<T>>,
    /// Validated Hermitian positive semidefinite.
    one_point: bool,
}

impl<T: Real> CsdMatrix<T> {
    /// Relative tolerance, in machine epsilons, of the one-point checks: `|C − C†|` entries and the
    /// negative slack of `C_xx`, `C_yy` (scaled by `max |C_ij|`) and `det C` (scaled by its square).
    pub const TOLERANCE_ULPS: f64 = 256.0;

    /// A validated one-point CSD matrix (Hermitian, positive semidefinite).
    ///
    /// The stored matrix is the Hermitian part `½(C + C†)` of the input, so that downstream
    /// results (Stokes parameters) are exactly real.
    ///
    /// # Formula
    /// ```text
    /// S1.1 (r₁ = r₂):  C = ⟨E E†⟩ = C†,   C_xx ≥ 0,   C_yy ≥ 0,   det C = C_xx C_yy − |C_xy|² ≥ 0
    /// ```
    /// Each check allows `tol = TOLERANCE_ULPS · ε` relative to `s = max |C_ij|`: asymmetry
    /// `≤ tol·s`, diagonal `≥ −tol·s`, `det ≥ −tol·s²`. The checks run on `C / r`,
    /// `r = max(|Re C_ij|, |Im C_ij|)`, so they are scale invariant (exactly, for powers of two)
    /// and cannot overflow: an entry `MAX + MAX·i` facing a zero is not Hermitian at any scale.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞ entries, and when the Stokes parameters of the matrix
    /// (`C_xx + C_yy`, …, and their polarized intensity) overflow (entries near `T::MAX`);
    /// [`Error::NotHermitian`] if `|C − C†|` exceeds the tolerance; [`Error::NotPositiveDefinite`]
    /// if a diagonal entry or the determinant is negative beyond it (reporting the smallest
    /// eigenvalue of the Hermitian part).
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::CsdMatrix;
    /// use nalgebra::Matrix2;
    /// use num_complex::Complex;
    /// let z = |re: f64, im: f64| Complex::new(re, im);
    /// let c = CsdMatrix::one_point(Matrix2::new(z(1.0, 0.0), z(0.0, -0.5), z(0.0, 0.5), z(1.0, 0.0))).unwrap();
    /// let s = c.to_stokes().unwrap();
    /// assert!((s.s3() - 1.0).abs() < 1e-15); // 2 Im C_yx
    /// assert!(CsdMatrix::one_point(Matrix2::new(z(1.0, 0.0), z(2.0, 0.0), z(2.0, 0.0), z(1.0, 0.0))).is_err());
    /// ```
    pub fn one_point(m: Matrix2<Complex<T>>) -> Result<Self, Error> {
        ensure_finite("CSD matrix entry", m.iter().flat_map(|z| [z.re, z.im]))?;
        let r = m
            .iter()
            .fold(T::zero(), |acc, z| acc.max(z.re.abs()).max(z.im.abs()));
        if r == T::zero() {
            return Ok(Self { m, one_point: true });
        }
        // Every part of C/r is in [−1, 1]: no product or sum below can overflow.
        let mn = m.map(|z| z / r);
        let modulus_max =
            |a: &Matrix2<Complex<T>>| a.iter().fold(T::zero(), |acc, z| acc.max(z.re.hypot(z.im)));
        let scale = modulus_max(&mn);
        let tol = T::lit(Self::TOLERANCE_ULPS) * T::EPSILON;
        let adj = mn.adjoint();
        let asym = modulus_max(&(mn - adj));
        if asym > tol * scale {
            return Err(Error::NotHermitian {
                what: "one-point CSD matrix",
                asymmetry: asym.to_f64() * r.to_f64(),
            });
        }
        let hn = (mn + adj) * Complex::new(T::lit(0.5), T::zero());
        let (a, d, b) = (hn[(0, 0)].re, hn[(1, 1)].re, hn[(0, 1)]);
        let det = a * d - b.norm_sqr();
        if a < -tol * scale || d < -tol * scale || det < -tol * scale * scale {
            // Smallest eigenvalue of the Hermitian 2×2: (a + d)/2 − √(((a − d)/2)² + |b|²).
            let half = T::lit(0.5);
            let min_eig = half * (a + d) - (half * (a - d)).hypot(b.re.hypot(b.im));
            return Err(Error::NotPositiveDefinite {
                what: "one-point CSD matrix",
                min_eigenvalue: min_eig.to_f64() * r.to_f64(),
            });
        }
        // The Hermitian part at the input's scale; where (C + C†)/2 overflows, r·(C/r + …)/2
        // instead (each part of hn is at most 1 in magnitude, so that is finite).
        let h = (m + m.adjoint()) * Complex::new(T::lit(0.5), T::zero());
        let h = if h.iter().all(|z| z.re.is_finite() && z.im.is_finite()) {
            h
        } else {
            hn.map(|z| z * r)
        };
        let c = Self {
            m: h,
            one_point: true,
        };
        let stokes = GeneralizedStokes::from_csd(&c).0.map(|z| z.re);
        let (_, pol, sm) = normalized_parts(&stokes);
        ensure_finite(
            "Stokes parameters of the one-point CSD matrix (overflow)",
            stokes.iter().copied().chain([pol * sm]),
        )?;
        Ok(c)
    }

    /// A two-point CSD matrix `C(r₁, r₂)`: any finite complex 2×2 matrix whose generalized Stokes
    /// parameters `A_mül vec(C)` (sums of two entries) are finite too.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞ entries, and when a generalized Stokes parameter
    /// overflows (entries near `T::MAX`).
    ///
    /// # Examples
    /// ```
    /// use gmueller::stokes::CsdMatrix;
    /// use nalgebra::Matrix2;
    /// use num_complex::Complex;
    /// let z = |re: f64, im: f64| Complex::new(re, im);
    /// assert!(CsdMatrix::two_point(Matrix2::new(z(1.0, 1.0), z(2.0, 0.0), z(0.0, 0.0), z(-1.0, 0.0))).is_ok());
    /// assert!(CsdMatrix::two_point(Matrix2::new(z(f64::NAN, 0.0), z(0.0, 0.0), z(0.0, 0.0), z(0.0, 0.0))).is_err());
    /// ```
    pub fn two_point(m: Matrix2<Complex<T>>) -> Result<Self, Error> {
        ensure_finite("CSD matrix entry", m.iter().flat_map(|z| [z.re, z.im]))?;
        let c = Self {
            m,
            one_point: false,
        };
        ensure_finite(
            "generalized Stokes parameters of the CSD matrix (overflow)",
            GeneralizedStokes::from_csd(&c)
                .0
                .iter()
                .flat_map(|z| [z.re, z.im]),
        )?;
        Ok(c)
    }

    /// The one-point CSD `E E†` of a fully polarized, fully coherent field (Hermitian, rank 1).
    ///
    /// # Formula
    /// ```text
    /// C = E E† = ⎡ |E_x|²     E_x E_y* ⎤
    ///            ⎣ E_y E_x*   |E_y|²   ⎦
    /// ```
    ///
    /// # Errors
    /// [`Error::NonFinite`] if an entry or a Stokes parameter (`S0 = |E_x|² + |E_y|²`)
    /// overflows: `|E|` above about `√(T::MAX/2)` (1.3e154 in f64, 1.3e19 in f32).
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesVector, stokes::CsdMatrix};
    /// use num_complex::Complex;
    /// let h = core::f64::consts::FRAC_1_SQRT_2;
    /// let e = JonesVector::new(Complex::new(h, 0.0), Complex::new(0.0, h)).unwrap();
    /// let s = CsdMatrix::from_jones_vector(&e).unwrap().to_stokes().unwrap();
    /// assert!((s.s3() - 1.0).abs() < 1e-15); // (1, i)/√2 has S3 = +1
    /// let big = JonesVector::new(Complex::new(1e200, 0.0), Complex::new(0.0, 0.0)).unwrap();
    /// assert!(CsdMatrix::from_jones_vector(&big).is_err());
    /// ```
    pub fn from_jones_vector(e: &JonesVector<T>) -> Result<Self, Error> {
        let (x, y) = (e.ex(), e.ey());
        let xy = x * y.conj();
        let c = Self {
            m: Matrix2::new(
                Complex::new(x.norm_sqr(), T::zero()),
                xy,
                xy.conj(),
                Complex::new(y.norm_sqr(), T::zero()),
            ),
            one_point: true,
        };
        let stokes = GeneralizedStokes::from_csd(&c).0.map(|z| z.re);
        let (_, pol, sm) = normalized_parts(&stokes);
        ensure_finite(
            "|E|² of the Jones vector (overflow)",
            c.m.iter()
                .flat_map(|z| [z.re, z.im])
                .chain(stokes.iter().copied())
                .chain([pol * sm]),
        )?;
        Ok(c)
    }

    /// The entries `[[C_xx, C_xy], [C_yx, C_yy]]`.
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Matrix2<Complex<T>> {
        self.m
    }

    /// `true` if this matrix was validated (or built) as a one-point CSD.
    #[inline]
    #[must_use]
    pub fn is_one_point(&self) -> bool {
        self.one_point
    }

    /// The generalized Stokes parameters `A_mül vec(C)` (S1.2); see [`GeneralizedStokes::from_csd`].
    #[inline]
    #[must_use]
    pub fn to_generalized_stokes(&self) -> GeneralizedStokes<T> {
        GeneralizedStokes::from_csd(self)
    }

    /// The classical Stokes vector of a one-point CSD, `Re(A_mül vec(C))`.
    ///
    /// For a matrix built by [`CsdMatrix::one_point`] / [`CsdMatrix::from_jones_vector`] this
    /// always succeeds; the result is a valid Stokes vector up to the validation tolerance (it
    /// is not re-checked against [`Stokes::new`]'s slack, since `S0² − |S|² = 4 det C`).
    ///
    /// # Errors
    /// For a two-point CSD, the checks of [`CsdMatrix::one_point`] are run first and their error
    /// is returned if the matrix is not Hermitian positive semidefinite.
    pub fn to_stokes(&self) -> Result<Stokes<T>, Error> {
        let c = if self.one_point {
            *self
        } else {
            Self::one_point(self.m)?
        };
        Ok(Stokes(GeneralizedStokes::from_csd(&c).0.map(|z| z.re)))
    }
}

/// The Stokes vector of a Jones vector lives here, beside the Stokes types, so that `jones`
/// (S1's Jones calculus, first in the derivation) does not depend on `stokes`.
impl<T: Real> JonesVector<T> {
    /// The Stokes vector of this fully polarized state (S1.2 with `C = E E†`).
    ///
    /// # Formula
    /// ```text
    /// S0 = |E_x|² + |E_y|²,   S1 = |E_x|² − |E_y|²,
    /// S2 = 2 Re(E_x E_y*),    S3 = 2 Im(E_x* E_y)
    /// ```
    /// It satisfies `S0² = S1² + S2² + S3²` up to rounding, so it is returned without the
    /// validation of [`Stokes::new`].
    ///
    /// # Examples
    /// ```
    /// use gmueller::jones::JonesVector;
    /// use num_complex::Complex;
    /// let v = JonesVector::new(Complex::new(1.0_f64, 0.0), Complex::new(0.0, 1.0)).unwrap();
    /// let s = v.to_stokes().vector();
    /// assert!((s[0] - 2.0).abs() < 1e-15 && (s[3] - 2.0).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn to_stokes(&self) -> Stokes<T> {
        let (ex, ey) = (self.0[0], self.0[1]);
        let (xx, yy) = (ex.norm_sqr(), ey.norm_sqr());
        let c = ex.conj() * ey; // E_x* E_y
        let two = T::lit(2.0);
        Stokes::from_vector_unchecked(nalgebra::Vector4::new(
            xx + yy,
            xx - yy,
            two * c.re,
            two * c.im,
        ))
    }
}
