//! First-order perturbation (Rayleigh–Rice) scattering by a rough interface.

use nalgebra::Matrix2;
use num_complex::Complex;

use super::{Geometry, Pbsdf, PbsdfForm, Side, validate_eta};
use crate::error::Error;
use crate::jones::JonesMatrix;
use crate::mueller::Mueller;
use crate::numerics::principal_sqrt;
use crate::real::Real;

/// First-order perturbation (Rayleigh–Rice) scattering by a rough interface of relative
/// permittivity `ε = η²` (`η = n_below/n_above`, the convention of [`Geometry::at_interface`]),
/// in reflection (Germer, Appl. Opt. 36, 8798, 1997) and in transmission (Elson, J. Opt. Soc.
/// Am. A 12, 729, 1995, one interface), as SCATMECH's `Microroughness_BRDF_Model` defines its
/// polarization factors for its four types.
///
/// # Formula
/// With `ε` the relative permittivity seen from the source (`ε` from above, `1/ε` from below,
/// [`Geometry::incident_from_below`]), `φ` the exit azimuth from the forward plane of incidence
/// ([`Geometry::exit_azimuth`]), square roots on the principal branch:
/// ```text
/// reflection (DOWNUP, UPDOWN):
///   q_i = √(ε − sin²θ_i),   q_o = √(ε − sin²θ_o)
///   ss =  (ε−1) cos φ / [(cos θ_i + q_i)(cos θ_o + q_o)]
///   pp =  (ε−1)(ε sin θ_i sin θ_o − q_o q_i cos φ) / [(ε cos θ_i + q_i)(ε cos θ_o + q_o)]
///   ps = −(ε−1) q_i sin φ / [(ε cos θ_i + q_i)(cos θ_o + q_o)]      (p in → s out)
///   sp = −(ε−1) q_o sin φ / [(cos θ_i + q_i)(ε cos θ_o + q_o)]      (s in → p out)
///   J  = 2k cos θ_i [[ss, ps], [sp, pp]]
/// transmission (DOWNDOWN, UPUP), η = √ε = n_t/n_i, κ = η sin θ_o (the exit direction's
/// tangential wavenumber over k), θ_o measured in the exit medium:
///   q_i = √(ε − sin²θ_i),   q_o = √(ε − κ²) = η cos θ_o,   a_o = √(1 − κ²)   (imaginary when
///                                                         the exit is evanescent in the medium
///                                                         of incidence)
///   ss = (ε−1) cos φ / [(q_i + cos θ_i)(q_o + a_o)]
///   pp = (ε−1) η (κ sin θ_i + q_i a_o cos φ) / [(q_i + ε cos θ_i)(q_o + ε a_o)]
///   ps = −(ε−1) q_i sin φ / [(q_i + ε cos θ_i)(q_o + a_o)]           (p in → s out)
///   sp = (ε−1) η a_o sin φ / [(q_i + cos θ_i)(q_o + ε a_o)]           (s in → p out)
///   J  = 2k cos θ_i √η [[ss, ps], [sp, pp]]
/// M = A_mül (J* ⊗ J) A_mül⁻¹   (S1.7)
/// ```
/// `k` is the wavenumber in the medium of incidence. The factor `2k cos θ_i` makes the kernel's
/// plane-wave limit `cos θ_o/λ² · M · 2π p(h_t)` equal the Rayleigh–Rice BRDF
/// `16π²/λ⁴ cos θ_i cos θ_o Q S(f)` times `cos θ_i` (`p = S/(2π)` converts SCATMECH's PSD to
/// ours): the kernel returns radiance per unit incident irradiance *across the beam*, the BRDF
/// is per unit irradiance *on the surface*. In transmission the kernel's factor is
/// `cos θ_o/λ_t² = η² cos θ_o/λ²` (radiance in the exit medium) and `√η` in `J` completes
/// SCATMECH's BTDF `16π²|1−ε|² η² q_o cos θ_i S |E|²/λ⁴` (Elson's factors `E`, which the
/// `(ε−1)` above absorbs). Near the specular (Snell) direction of a long-correlated surface the
/// factors become those of the phase screen with the Fresnel coefficients: `|J|² → |r|² v²`
/// in reflection and `η |t|² v²` in transmission (`v` = [`Geometry::phase_factor`]), which
/// `tests/interaction/transmission.rs` checks.
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

    /// The relative permittivity the factors see: `ε` for light from above, `1/ε` (as
    /// [`RayleighRice::factors`] computes it) for light from below.
    #[inline]
    pub(crate) fn permittivity_seen(&self, from_below: bool) -> Complex<T> {
        if from_below {
            recip(self.epsilon)
        } else {
            self.epsilon
        }
    }

    /// The polarization factors `[[ss, ps], [sp, pp]]` of the geometry's side (without
    /// `2k cos θ_i`, and without `√η` in transmission).
    #[must_use]
    pub fn factors(&self, g: &Geometry<T>) -> Matrix2<Complex<T>> {
        if g.incident_from_below() {
            self.factors_from_below(g)
        } else if g.side() == Side::Reflection {
            reflection_factors(self.epsilon, g)
        } else {
            transmission_factors(self.epsilon, g)
        }
    }

    /// [`RayleighRice::factors`] for light from below the interface (relative permittivity
    /// `1/ε`), out of line.
    #[inline(never)]
    fn factors_from_below(&self, g: &Geometry<T>) -> Matrix2<Complex<T>> {
        let e = self.permittivity_seen(true);
        match g.side() {
            Side::Reflection => reflection_factors(e, g),
            Side::Transmission => transmission_factors(e, g),
        }
    }

    /// The Jones matrix `2k cos θ_i [[ss, ps], [sp, pp]]` (times `√η` in transmission).
    #[must_use]
    pub fn jones(&self, g: &Geometry<T>) -> JonesMatrix<T> {
        JonesMatrix(self.factors(g) * Complex::new(jones_scale(g), T::zero()))
    }
}

/// `2k cos θ_i`, times `√η` in transmission.
#[inline]
fn jones_scale<T: Real>(g: &Geometry<T>) -> T {
    let s = T::lit(2.0) * g.k * g.cos_i;
    match g.side() {
        Side::Reflection => s,
        Side::Transmission => s * g.eta.sqrt(),
    }
}

/// Germer's reflection factors for the relative permittivity `e` seen from the source.
#[inline(always)]
fn reflection_factors<T: Real>(e: Complex<T>, g: &Geometry<T>) -> Matrix2<Complex<T>> {
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
    // Every quantity of size |η|ⁿ is divided by tⁿ, t a power of two near |η| ([`Scale`]):
    // exact, so the factors are those of the unscaled formulas bit for bit wherever those
    // neither overflow nor underflow — and they did: |D₃D₄|² ~ |ε|⁴ overflows f32 from
    // |η| ≈ 10⁴·⁵ (1/(D₃D₄) became 0, and with it pp, ps, sp: a conductor of κ = 10⁵ lost 75 %
    // of its scattered light), and 1/(D₁D₂D₃D₄) ~ |ε|⁻³ underflows it from |η| ≈ 10⁶.
    let k = Scale::of(e);
    let em1s = em1 * k.inv2;
    let inv_ss = recip((d1 * k.inv) * (d2 * k.inv));
    let inv_pp = recip((d3 * k.inv2) * (d4 * k.inv2));
    let both = inv_ss * inv_pp;
    let ss = em1s * inv_ss * cphi;
    let pp = em1s * ((e * (si2 * so2).sqrt() - qo * qi * cphi) * k.inv2) * inv_pp;
    let ps = -em1s * (qi * k.inv) * ((d1 * k.inv) * (d4 * k.inv2) * both) * sphi;
    let sp = -em1s * (qo * k.inv) * ((d2 * k.inv) * (d3 * k.inv2) * both) * sphi;
    Matrix2::new(ss, ps, sp, pp)
}

/// `1/t`, `1/t²`, `1/t³` for `t` the power of two nearest below `√|ε|` (at least 1; taken
/// from `max(|Re ε|, |Im ε|)`), the scale of the Rayleigh–Rice factors' terms: `q`, `D₁`,
/// `D₂` are of size `t`, `ε − 1`, `D₃`, `D₄` of `t²` (`D₄` up to `t³` in transmission).
/// Powers of two, so scaling by them is exact.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Scale<T> {
    pub(crate) inv: T,
    pub(crate) inv2: T,
    pub(crate) inv3: T,
}

impl<T: Real> Scale<T> {
    #[inline]
    pub(crate) fn of(e: Complex<T>) -> Self {
        let m = e.re.abs().max(e.im.abs()).to_f64();
        let inv = if m >= 4.0 && m.is_finite() {
            // 2^−⌊½ log₂ m⌋ from the exponent field (m ≥ 4 is normal).
            let exp = ((m.to_bits() >> 52) & 0x7ff) as i64 - 1023;
            T::lit(f64::from_bits(((1023 - exp / 2) as u64) << 52))
        } else {
            T::one()
        };
        Self {
            inv,
            inv2: inv * inv,
            inv3: inv * inv * inv,
        }
    }
}

/// Elson's transmission factors (one interface) for the relative permittivity `e` seen from
/// the source, with `(ε − 1)` taken in (see the type docs).
#[inline(never)]
fn transmission_factors<T: Real>(e: Complex<T>, g: &Geometry<T>) -> Matrix2<Complex<T>> {
    let one = Complex::new(T::one(), T::zero());
    let ci = g.cos_i;
    let sin2 = |c: T| (T::one() - c * c).max(T::zero());
    let si2 = sin2(ci);
    let (cphi, sphi) = g.exit_azimuth();
    // κ = η sin θ_o, the exit direction's tangential wavenumber in units of k, with η = √ε the
    // pBSDF's own index (the geometry's `relative_index` to rounding): then
    // q_o = √(ε − κ²) = η cos θ_o exactly. Formed as the difference ε − κ² (with η from the
    // geometry) it cancelled at grazing exits, and in f32 the rounding of ε against η² made q_o
    // imaginary at θ_o = 89.99° from the dense side.
    let index = principal_sqrt(e);
    let (so, co) = (sin2(g.cos_o).sqrt(), g.cos_o);
    let kappa = index * so;
    let qi = principal_sqrt(e - one * si2);
    let qo = index * co;
    // a_o = √(1 − κ²) = √(1 − ε sin²θ_o): imaginary (+i√(κ² − 1)) when the exit is evanescent in
    // the medium of incidence.
    let ao = principal_sqrt(one - e * (so * so));
    let em1 = e - one;
    // s-type denominators D₁ = q_i + cos θ_i, D₂ = q_o + a_o; p-type D₃ = q_i + ε cos θ_i,
    // D₄ = q_o + ε a_o.
    let (d1, d2, d3, d4) = (qi + ci, qo + ao, qi + e * ci, qo + e * ao);
    // Scaled as in `reflection_factors` (`D₄` by t³): the unscaled numerator of pp is of size
    // |η|⁵ and overflowed f32 from |η| ≈ 10⁷·⁵, |D₃D₄|² from |η| ≈ 10³·⁵.
    let k = Scale::of(e);
    let (em1s, index_s) = (em1 * k.inv2, index * k.inv);
    let (d1s, d2s, d3s, d4s) = (d1 * k.inv, d2 * k.inv, d3 * k.inv2, d4 * k.inv3);
    let ss = em1s * cphi * recip(d1s * d2s);
    let pp = em1s * index_s * ((qi * ao * cphi + kappa * si2.sqrt()) * k.inv2) * recip(d3s * d4s);
    let ps = -em1s * (qi * k.inv) * sphi * recip(d3s * d2s);
    let sp = em1s * index_s * (ao * k.inv) * sphi * recip(d1s * d4s);
    Matrix2::new(ss, ps, sp, pp)
}

impl<T: Real> Pbsdf<T> for RayleighRice<T> {
    #[inline]
    fn form(&self) -> PbsdfForm<'_, T> {
        PbsdfForm::RayleighRice(self)
    }
    #[inline]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        Mueller::from_jones(&self.jones(g))
    }
    /// `M₀₀ = ½ Σ |J_ij|²` without the rest of the Mueller matrix.
    #[inline]
    fn m00(&self, g: &Geometry<T>) -> T {
        let scale = jones_scale(g);
        let f = self.factors(g);
        T::lit(0.5) * scale * scale * f.iter().fold(T::zero(), |acc, z| acc + z.norm_sqr())
    }
}

/// `1/z = z̄/|z|²` with one real division (for the denominator products of
/// [`RayleighRice::factors`], scaled to size O(1) by [`Scale`]).
#[inline]
fn recip<T: Real>(z: Complex<T>) -> Complex<T> {
    let inv = T::one() / z.norm_sqr();
    Complex::new(z.re * inv, -z.im * inv)
}
