//! The coherence weights `K³_α` of a volume (S2.17 with n = 3, corrected constant) at each
//! coherence level of the crate ([`PlaneWave`], [`Partial`], [`Incoherent`]).
//!
//! # Formula
//! ```text
//! PlaneWave:   K³ = (2π)^{3/2} p(h)
//! Partial<B>:  K³ = |Θ_α|^{1/2} ∫ p(q) g^{Ξ_α}(h − q) d³q = (2π)^{3/2} ∫ p(q) 𝒩_{Ξ_α}(h − q) d³q
//! Incoherent:  K³ = |Θ_α|^{1/2} g^{Ξ_α}(h) ∫ p d³q
//! Ξ_α = Q Θ_α⁻¹ Qᵀ  (S2.18; Q = [x̂ ŷ k̂] packet → world),   Θ_α = blockdiag(Θ⊥_α, σ_zz²),   h = k(r̂ + ŝ)
//! ```
//! `Partial` is [`crate::interaction::coherence::volume_coherence_term`] (its values are the same
//! to rounding, `tests/medium/born.rs`); as the coherence grows it tends to `PlaneWave`
//! (`|Θ|^{1/2} g^Ξ → (2π)^{3/2} δ`), as it shrinks below the correlation lengths to
//! `Incoherent`. The weights are computed as logarithms, so a far tail is not lost before it
//! meets the Stokes vector's own scale.

use nalgebra::Vector3;

use crate::gaussian::Gaussian;
use crate::interaction::coherence::CoherenceModel;
use crate::interaction::{Incoherent, Partial, PlaneWave};
use crate::psd::{BlurMethod, Psd};
use crate::real::Real;

/// `ln (2π)^{3/2}`.
#[inline]
pub(crate) fn ln_two_pi_3_2<T: Real>() -> T {
    T::lit(1.5 * core::f64::consts::TAU.ln())
}

/// The volume coherence weight `K³` of a coherence level for a 3-D PSD `P`: S2.17 with n = 3
/// and the corrected constant.
///
/// # Formula
/// ```text
/// PlaneWave:   K³ = (2π)^{3/2} p(h)
/// Partial<B>:  K³ = |Θ_α|^{1/2} ∫ p(q) g^{Ξ_α}(h − q) d³q = (2π)^{3/2} ∫ p(q) 𝒩_{Ξ_α}(h − q) d³q
/// Incoherent:  K³ = |Θ_α|^{1/2} g^{Ξ_α}(h) ∫ p d³q
/// Ξ_α = Q Θ_α⁻¹ Qᵀ  (S2.18; Q = [x̂ ŷ k̂] packet → world),   Θ_α = blockdiag(Θ⊥_α, σ_zz²),   h = k(r̂ + ŝ)
/// ```
/// `Partial` is [`crate::interaction::coherence::volume_coherence_term`] (the same values to
/// rounding, `tests/medium/born.rs`); as the coherence grows it tends to `PlaneWave`
/// (`|Θ|^{1/2} g^Ξ → (2π)^{3/2} δ`), as it shrinks below the correlation lengths to
/// `Incoherent`. Implemented for the crate's three coherence levels (the trait is sealed
/// through [`CoherenceModel`]).
pub trait VolumeCoherence<T: Real, P: Psd<T, 3>>: CoherenceModel {
    /// `ln K³` for a channel whose inverse coherence in world coordinates is `xi` (`Ξ_α`, a
    /// covariance in `h`, rad²/length²; `None` at the plane-wave level, which needs none), at
    /// the scattering vector `h` (rad/length); `−∞` where `K³ = 0`.
    #[must_use]
    fn log_volume_weight(&self, psd: &P, xi: Option<&Gaussian<T, 3>>, h: &Vector3<T>) -> T;

    /// `true` when this level's `K³` of a Gaussian PSD is its closed form
    /// (`(2π)^{3/2} σ² |Λ + Ξ|^{−1/2} exp(−½ hᵀ(Λ + Ξ)⁻¹h)`): `Partial` with a blur exact for
    /// Gaussians ([`BlurMethod::exact_for_gaussians`], e.g. [`crate::psd::ClosedForm`]). The
    /// medium then evaluates that closed form itself, in the packet's own axes, where it keeps
    /// every variance in both precisions ([module docs](crate::medium)); `false` by default.
    #[must_use]
    fn closed_form_for_gaussians(&self) -> bool {
        false
    }
}

impl<T: Real, P: Psd<T, 3>> VolumeCoherence<T, P> for PlaneWave {
    #[inline]
    fn log_volume_weight(&self, psd: &P, _xi: Option<&Gaussian<T, 3>>, h: &Vector3<T>) -> T {
        ln_two_pi_3_2::<T>() + psd.log_value(h)
    }
}

impl<T, P, B> VolumeCoherence<T, P> for Partial<B>
where
    T: Real,
    P: Psd<T, 3>,
    B: BlurMethod<T, 3, P> + Clone + core::fmt::Debug,
{
    #[inline]
    fn log_volume_weight(&self, psd: &P, xi: Option<&Gaussian<T, 3>>, h: &Vector3<T>) -> T {
        // (2π)^{3/2} |Θ|^{1/2} (p * g^Ξ) with |Θ| = 1/|Ξ|: (2π)^{3/2} times the normalised blur,
        // which never forms the tiny (p * g^Ξ) of a wide coherence volume.
        match xi {
            Some(xi) => ln_two_pi_3_2::<T>() + self.0.log_normalized_blur(psd, xi, h),
            None => ln_two_pi_3_2::<T>() + psd.log_value(h),
        }
    }

    #[inline]
    fn closed_form_for_gaussians(&self) -> bool {
        self.0.exact_for_gaussians()
    }
}

impl<T: Real, P: Psd<T, 3>> VolumeCoherence<T, P> for Incoherent {
    #[inline]
    fn log_volume_weight(&self, psd: &P, xi: Option<&Gaussian<T, 3>>, h: &Vector3<T>) -> T {
        match xi {
            // |Θ|^{1/2} = |Ξ|^{−1/2} (|Q| = 1).
            Some(xi) => xi.log_value(h) - T::lit(0.5) * xi.log_det() + psd.integral().ln(),
            None => ln_two_pi_3_2::<T>() + psd.log_value(h),
        }
    }
}
