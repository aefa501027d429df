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

use crate::error::Error;
use crate::psd::{Form, GaussianPsd, Shape};
use crate::real::Real;

/// The shape of a 3-D PSD's lobe, read from its [`Form`] (`crate::psd::Psd::form`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum VolumeLobes<'a, T: Real> {
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

impl<'a, T: Real> VolumeLobes<'a, T> {
    /// The lobe of a PSD of form `form`.
    ///
    /// # Errors
    /// [`Error::Unrealizable`] for a form without a continuous lobe ([`Shape::Zero`],
    /// [`Shape::Origin`], [`Shape::Orders`]): a medium's permittivity has a continuous PSD.
    pub(crate) fn of(form: Form<'a, T, 3>) -> Result<Self, Error> {
        match form.shape() {
            Shape::Gaussian(g) => Ok(Self::Gaussian(*g.spectral_shape().covariance())),
            Shape::Mixture(c) => Ok(Self::Mixture(c)),
            Shape::KCorrelation { t, gamma } => Ok(Self::KCorrelation { t, gamma }),
            Shape::Zero | Shape::Origin | Shape::Orders(_) => Err(Error::Unrealizable {
                reason: "a random medium takes a PSD of continuous form (a Gaussian, a mixture, \
                         a K-correlation, or a PSD naming one as its closest form); this one \
                         is zero or Dirac",
            }),
        }
    }
}
