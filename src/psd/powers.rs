//! The spectra of the powers of a normalised autocorrelation, `F{σ² ρˣ}` with `ρ = R/σ²`: the
//! terms of the Kirchhoff series of a rough surface beyond first order
//! ([`crate::interaction::roughness::KirchhoffSeries`]).

use nalgebra::Matrix2;

use super::Psd;
use crate::real::Real;

/// A height PSD whose autocorrelation's powers have spectra of their own: `p_x = F{σ² ρˣ}`,
/// `ρ = R/σ²` the normalised autocorrelation, for a real exponent `x ≥ 1` (`p_1 = p`).
///
/// # Formula
/// ```text
/// p_x(ζ) = F{σ² ρˣ}(ζ) = (2π)⁻¹ ∫ σ² ρ(ξ)ˣ e^{−iζ·ξ} d²ξ,      ∫ p_x d²ζ = 2π σ²   (every x)
/// Gaussian  R = σ² g^Λ:   ρˣ = g^{Λ/x},   p_x(ζ) = σ² |Λ/x|^{1/2} exp(−½ x ζᵀΛ⁻¹ζ)
/// ```
/// The Kirchhoff (phase-screen) series of a surface with Gaussian heights is, with `g = (vσ)²`
/// and the Poisson weights `w_n = e^{−g} gⁿ/n!`,
/// ```text
/// F{⟨e^{iv(z₁−z₂)}⟩}(ζ) = e^{−g} 2π δ(ζ) + Σ_{n≥1} w_n F{ρⁿ}(ζ) = α 2π δ(ζ) + (v²/g) Σ_{n≥1} w_n p_n(ζ)
/// ```
/// (`α = e^{−g}` the Debye–Waller factor; the `n = 1` term `α v² p` is the first-order kernel),
/// and its large-`g` (geometric-optics) limit is the single power `x = g`: for the Gaussian a
/// Gaussian of slope covariance `σ² Λ⁻¹` (`σ²/ℓ²` per axis for `R = σ² e^{−r²/2ℓ²}`).
///
/// Every `p_x` has the variance `σ²` of `p`.
pub trait CorrelationPowers<T: Real>: Psd<T, 2> {
    /// The PSD type of a power.
    type Power: Psd<T, 2>;

    /// `p_x = F{σ² ρˣ}` (`x ≥ 1` real; `x < 1` is allowed where the closed form allows it),
    /// `None` where it is not representable in `T` (e.g. `x Λ⁻¹` overflows) or `x ≤ 0`.
    #[must_use]
    fn correlation_power(&self, x: T) -> Option<Self::Power>;

    /// For a Gaussian PSD, its variance `σ²` and the Cholesky factor `L` of its spectral
    /// covariance `Λ⁻¹` (`p_x` has `x Λ⁻¹`): the series then has one closed form for all its
    /// orders (`KirchhoffSeries`). `None` (the default) for other PSDs.
    #[inline]
    #[must_use]
    fn gaussian_spectrum(&self) -> Option<(T, Matrix2<T>)> {
        None
    }
}
