//! Mueller matrices: classical (real 4×4, acting on Stokes vectors) and generalized (complex 4×4,
//! acting on generalized Stokes parameters), S1.6–S1.7.

use core::ops::Mul;

use nalgebra::Matrix4;
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::jones::JonesMatrix;
use crate::real::Real;
use crate::stokes::Stokes;

/// A classical (real 4×4) Mueller matrix acting on [`Stokes`] vectors: `S′ = M S`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mueller<T: Real>(pub(crate) Matrix4<T>);

impl<T: Real> Mueller<T> {
    /// A Mueller matrix from its entries.
    ///
    /// Only finiteness is checked: use [`Mueller::is_physically_realizable`] to test that it maps
    /// every valid Stokes vector to a valid one.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if an entry is NaN or infinite.
    pub fn from_matrix(m: Matrix4<T>) -> Result<Self, Error> {
        ensure_finite("Mueller matrix entry", m.iter().copied())?;
        Ok(Self(m))
    }

    /// The identity.
    #[must_use]
    pub fn identity() -> Self {
        Self(Matrix4::identity())
    }

    /// The entries as an nalgebra matrix.
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Matrix4<T> {
        self.0
    }

    /// The Mueller matrix of a Jones matrix, in closed form (S1.7 with p₁ = p₂).
    ///
    /// # Formula
    /// ```text
    /// S1.7 (p₁ = p₂):  M = A_mül (J* ⊗ J) A_mül⁻¹,   equivalently   M_kl = ½ tr(σ_k J σ_l J†)
    /// with σ₀ = I, σ₁ = diag(1, −1), σ₂ = [[0, 1], [1, 0]], σ₃ = [[0, −i], [i, 0]].
    /// For H_l = J σ_l J† (Hermitian):  M_0l = ½(H₁₁ + H₂₂),  M_1l = ½(H₁₁ − H₂₂),
    ///                                  M_2l = Re H₁₂,        M_3l = −Im H₁₂.
    /// ```
    /// No 4×4 complex product is formed; the literal formula is the test oracle.
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesMatrix, mueller::Mueller};
    /// let m = Mueller::from_jones(&JonesMatrix::<f64>::linear_polarizer(0.0));
    /// assert!((m.matrix()[(0, 1)] - 0.5).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn from_jones(j: &JonesMatrix<T>) -> Self {
        let m = &j.0;
        let (a, b, c, d) = (m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]);
        let half = T::lit(0.5);
        let (aa, bb, cc, dd) = (a.norm_sqr(), b.norm_sqr(), c.norm_sqr(), d.norm_sqr());
        let ac = a * c.conj();
        let bd = b * d.conj();
        let ab = a * b.conj();
        let cd = c * d.conj();
        let bc = b * c.conj();
        let ad = a * d.conj();
        // H_l = J σ_l J†: (H11, H22, H12) for l = 0..3.
        let h11 = [aa + bb, aa - bb, ab.re + ab.re, ab.im + ab.im];
        let h22 = [cc + dd, cc - dd, cd.re + cd.re, cd.im + cd.im];
        // l = 3: H12 = i (b c̄ − a d̄).
        let h12_3 = Complex::new(-(bc.im - ad.im), bc.re - ad.re);
        let h12 = [ac + bd, ac - bd, bc + ad, h12_3];
        let mut out = Matrix4::zeros();
        for l in 0..4 {
            out[(0, l)] = half * (h11[l] + h22[l]);
            out[(1, l)] = half * (h11[l] - h22[l]);
            out[(2, l)] = h12[l].re;
            out[(3, l)] = -h12[l].im;
        }
        Self(out)
    }
}

impl<T: Real> Mul for Mueller<T> {
    type Output = Mueller<T>;
    /// Composition: `(M₂ * M₁)` is M₁ followed by M₂.
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        Self(self.0 * rhs.0)
    }
}

impl<T: Real> Mul<Stokes<T>> for Mueller<T> {
    type Output = Stokes<T>;
    /// `S′ = M S`. Valid whenever `M` is physically realizable (e.g. built from Jones matrices).
    #[inline]
    fn mul(self, rhs: Stokes<T>) -> Stokes<T> {
        Stokes(self.0 * rhs.0)
    }
}

/// A generalized (two-point, complex 4×4) Mueller matrix (S1.7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeneralizedMueller<T: Real>(pub(crate) Matrix4<Complex<T>>);

impl<T: Real> GeneralizedMueller<T> {
    /// The entries as an nalgebra matrix.
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Matrix4<Complex<T>> {
        self.0
    }
}
