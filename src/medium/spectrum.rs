//! The 3-D PSDs a random medium takes, and the shape of their lobes as the medium's sampler
//! and its scattering-coefficient quadrature need it.
//!
//! # Formula
//! ```text
//! Gaussian       p(q) = σ² |Λ|^{1/2} exp(−½ qᵀΛq)                 R(ξ) = σ² exp(−½ ξᵀΛ⁻¹ξ)
//! mixture        p = Σ_j p_j  (Gaussian components)
//! K-correlation  p(q) = σ² c (1 + T|q|²)^{−(γ+1)/2},  c = (2T)^{3/2} Γ(ν)/Γ(ν − 3/2),  ν = (γ+1)/2,  γ > 2
//!                γ = 3: R(ξ) = σ² exp(−|ξ|/√T)   (the Debye–Bueche medium)
//! ```
//! (`crate::psd`: unitary transform, `∫p d³q = (2π)^{3/2} σ²`.) `p` is the PSD of the relative
//! permittivity fluctuation `δε` of the medium (`σ² = ⟨δε²⟩`).

use nalgebra::Matrix3;

use crate::psd::{GaussianMixturePsd, GaussianPsd, KCorrelation, Psd};
use crate::real::Real;

/// The shape of a 3-D PSD's lobe ([`VolumePsd::lobes`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VolumeLobes<'a, T: Real> {
    /// A Gaussian PSD of spectral covariance `Λ` (rad²/length², world axes).
    Gaussian(Matrix3<T>),
    /// A Gaussian mixture: each component with weight `σ_j²/σ²`.
    Mixture(&'a [GaussianPsd<T, 3>]),
    /// The isotropic K-correlation PSD `∝ (1 + T|q|²)^{−(γ+1)/2}`.
    KCorrelation {
        /// `T` (length²).
        t: T,
        /// `γ > 2`.
        gamma: T,
    },
}

/// A 3-D PSD that a [`crate::medium::RandomMedium`] can use: it names the shape of its lobe, which
/// places the nodes of the scattering-coefficient quadrature and the lobes of the sampler.
///
/// Implemented for [`GaussianPsd`], [`GaussianMixturePsd`] and [`KCorrelation`] in 3-D; a
/// downstream PSD can implement it by naming the closest shape (the sampler stays exact and
/// unbiased for any PSD, only less efficient, and the quadrature less accurate the further the
/// named shape is from the PSD's).
pub trait VolumePsd<T: Real>: Psd<T, 3> {
    /// The lobe's shape.
    fn lobes(&self) -> VolumeLobes<'_, T>;

    /// `true` when the PSD *is* the shape [`Self::lobes`] names, not merely the closest one:
    /// the medium may then evaluate it through that shape — a Gaussian PSD's blur in closed
    /// form (where the coherence level's blur is exact for Gaussians,
    /// [`super::VolumeCoherence::closed_form_for_gaussians`]), and an isotropic shape (a
    /// Gaussian or mixture with `Λ ∝ I`, the K-correlation) in any orthonormal basis — in the
    /// packet's own axes, where a long correlation length beside a short `σ_zz` keeps its
    /// precision in `f32` ([module docs](crate::medium)). `false` by default (a downstream PSD
    /// that names its closest shape); `true` for [`GaussianPsd`], [`GaussianMixturePsd`] and
    /// [`KCorrelation`].
    fn exact_lobes(&self) -> bool {
        false
    }
}

impl<T: Real> VolumePsd<T> for GaussianPsd<T, 3> {
    #[inline]
    fn lobes(&self) -> VolumeLobes<'_, T> {
        VolumeLobes::Gaussian(*self.spectral_shape().covariance())
    }
    #[inline]
    fn exact_lobes(&self) -> bool {
        true
    }
}

impl<T: Real> VolumePsd<T> for GaussianMixturePsd<T, 3> {
    #[inline]
    fn lobes(&self) -> VolumeLobes<'_, T> {
        VolumeLobes::Mixture(self.components())
    }
    #[inline]
    fn exact_lobes(&self) -> bool {
        true
    }
}

impl<T: Real> VolumePsd<T> for KCorrelation<T, 3> {
    #[inline]
    fn lobes(&self) -> VolumeLobes<'_, T> {
        VolumeLobes::KCorrelation {
            t: self.t(),
            gamma: self.gamma(),
        }
    }
    #[inline]
    fn exact_lobes(&self) -> bool {
        true
    }
}
