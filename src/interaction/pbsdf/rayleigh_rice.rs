//! First-order perturbation (Rayleigh–Rice) scattering by a rough interface.

use nalgebra::Matrix2;
use num_complex::Complex;

use super::{Geometry, Pbsdf, validate_eta};
use crate::error::Error;
use crate::jones::JonesMatrix;
use crate::mueller::Mueller;
use crate::numerics::principal_sqrt;
use crate::real::Real;

/// First-order perturbation (Rayleigh–Rice) scattering by a rough interface of relative
/// permittivity `ε = η²`, as SCATMECH's `Microroughness_BRDF_Model` (Germer, Appl. Opt. 36,
/// 8798, 1997) defines its polarization factors.
///
/// # Formula
/// ```text
/// q_i = √(ε − sin²θ_i),   q_o = √(ε − sin²θ_o)           (principal branch)
/// ss =  (ε−1) cos φ / [(cos θ_i + q_i)(cos θ_o + q_o)]
/// pp =  (ε−1)(ε sin θ_i sin θ_o − q_o q_i cos φ) / [(ε cos θ_i + q_i)(ε cos θ_o + q_o)]
/// ps = −(ε−1) q_i sin φ / [(ε cos θ_i + q_i)(cos θ_o + q_o)]      (p in → s out)
/// sp = −(ε−1) q_o sin φ / [(cos θ_i + q_i)(ε cos θ_o + q_o)]      (s in → p out)
/// J  = 2k cos θ_i [[ss, ps], [sp, pp]],      M = A_mül (J* ⊗ J) A_mül⁻¹   (S1.7)
/// ```
/// φ is the exit azimuth from the forward plane of incidence ([`Geometry::exit_azimuth`]).
/// The factor `2k cos θ_i` makes the kernel's plane-wave limit `cos θ_o/λ² · M · 2π p(h_t)`
/// equal the Rayleigh–Rice BRDF `16π²/λ⁴ cos θ_i cos θ_o Q S(f)` times `cos θ_i`
/// (`p = S/(2π)` converts SCATMECH's PSD to ours): the kernel returns radiance per unit
/// incident irradiance *across the beam*, the BRDF is per unit irradiance *on the surface*.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayleighRice<T: Real> {
    epsilon: Complex<T>,
}

impl<T: Real> RayleighRice<T> {
    /// A Rayleigh–Rice scatterer with substrate index `η = n + iκ` (relative permittivity η²).
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::OutOfRange`] unless `Re η > 0`, `Im η ≥ 0`, finite.
    pub fn new(eta: Complex<T>) -> Result<Self, Error> {
        validate_eta(eta)?;
        Ok(Self { epsilon: eta * eta })
    }

    /// The substrate's relative permittivity `ε = η²`.
    #[inline]
    #[must_use]
    pub fn permittivity(&self) -> Complex<T> {
        self.epsilon
    }

    /// The polarization factors `[[ss, ps], [sp, pp]]` (without `2k cos θ_i`).
    #[must_use]
    pub fn factors(&self, g: &Geometry<T>) -> Matrix2<Complex<T>> {
        let e = self.epsilon;
        let one = Complex::new(T::one(), T::zero());
        let (ci, co) = (g.cos_i, g.cos_o);
        let sin2 = |c: T| (T::one() - c * c).max(T::zero());
        let (si2, so2) = (sin2(ci), sin2(co));
        let (cphi, sphi) = g.exit_azimuth();
        let qi = principal_sqrt(e - one * si2);
        let qo = principal_sqrt(e - one * so2);
        let em1 = e - one;
        // Denominators: s-type D₁ = cos θ_i + q_i, D₂ = cos θ_o + q_o; p-type D₃ = ε cos θ_i + q_i,
        // D₄ = ε cos θ_o + q_o. Two complex reciprocals (one real division each) give all four
        // pairings: 1/(D₃D₂) = D₁D₄/(D₁D₂·D₃D₄), 1/(D₁D₄) = D₂D₃/(D₁D₂·D₃D₄).
        let (d1, d2, d3, d4) = (qi + ci, qo + co, e * ci + qi, e * co + qo);
        let inv_ss = recip(d1 * d2);
        let inv_pp = recip(d3 * d4);
        let both = inv_ss * inv_pp;
        let ss = em1 * inv_ss * cphi;
        let pp = em1 * (e * (si2 * so2).sqrt() - qo * qi * cphi) * inv_pp;
        let ps = -em1 * qi * (d1 * d4 * both) * sphi;
        let sp = -em1 * qo * (d2 * d3 * both) * sphi;
        Matrix2::new(ss, ps, sp, pp)
    }

    /// The Jones matrix `2k cos θ_i [[ss, ps], [sp, pp]]`.
    #[must_use]
    pub fn jones(&self, g: &Geometry<T>) -> JonesMatrix<T> {
        JonesMatrix(self.factors(g) * Complex::new(T::lit(2.0) * g.k * g.cos_i, T::zero()))
    }
}

impl<T: Real> Pbsdf<T> for RayleighRice<T> {
    #[inline]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        Mueller::from_jones(&self.jones(g))
    }
    /// `M₀₀ = ½ Σ |J_ij|²` without the rest of the Mueller matrix.
    #[inline]
    fn m00(&self, g: &Geometry<T>) -> T {
        let scale = T::lit(2.0) * g.k * g.cos_i;
        let f = self.factors(g);
        T::lit(0.5) * scale * scale * f.iter().fold(T::zero(), |acc, z| acc + z.norm_sqr())
    }
}

/// `1/z = z̄/|z|²` with one real division (for the O(1)–O(|ε|²) denominator products of
/// [`RayleighRice::factors`]: `|z|²` stays finite for `|ε|` up to ~10⁷⁵ in f64, ~10⁹ in f32).
#[inline]
fn recip<T: Real>(z: Complex<T>) -> Complex<T> {
    let inv = T::one() / z.norm_sqr();
    Complex::new(z.re * inv, -z.im * inv)
}
