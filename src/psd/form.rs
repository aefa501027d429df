//! The spectral form a PSD declares ([`Psd::form`]): the one vocabulary in which the BSDF
//! sampler, the medium's quadrature and sampler, and the kernel's SIMD lanes read a PSD.
//!
//! # Formula
//! ```text
//! Zero            p = 0
//! Origin          p = (2π)^{n/2} w δ(ζ)                                  (a smooth surface)
//! Gaussian        p = (2π)^{n/2} σ² 𝒩(ζ; 0, C)                            (GaussianPsd)
//! Mixture         p = Σ_j (2π)^{n/2} σ_j² 𝒩(ζ; 0, C_j)                    (GaussianMixturePsd)
//! Orders          p = (2π)^{n/2} Σ_m η_m δ(ζ − ζ_m)                        (Grating)
//! KCorrelation    p ∝ (1 + T|ζ|²)^{−(γ+1)/2}                               (KCorrelation)
//! ```
//! A PSD whose shape is one of these declares it **exactly** ([`Form::exact`]); any other PSD
//! declares the **closest** of them ([`Form::closest`]) — a shape whose support covers its
//! own. Every reader stays unbiased for a closest form: the samplers draw from the named
//! shape and weigh by the PSD's own value; the medium evaluates the PSD itself (only its
//! quadrature nodes follow the shape); the lanes of the batch path take exact Gaussian forms
//! only. An exact form also lets the readers use the shape's closed forms (the medium's
//! closed-form Gaussian blur, its isotropic basis; the lanes).
//!
//! # Examples
//! A PSD of a downstream crate — a truncated Gaussian whose closest form is the Gaussian of the
//! same covariance — is read by every part of the crate through its form:
//! ```
//! use gmueller::psd::{Form, GaussianPsd, Psd, Shape};
//! use nalgebra::SVector;
//!
//! /// `p(ζ) = q(ζ)` for `|ζ| < 5`, 0 beyond: `q` an isotropic Gaussian PSD of spectral
//! /// width 1 (`ℓ = 1`), of which the disk holds `1 − e^{−25/2}`.
//! struct Truncated { inner: GaussianPsd<f64, 2> }
//! impl Psd<f64, 2> for Truncated {
//!     fn value(&self, zeta: &SVector<f64, 2>) -> f64 {
//!         if zeta.norm() < 5.0 { self.inner.value(zeta) } else { 0.0 }
//!     }
//!     fn variance(&self) -> f64 { self.inner.variance() * -(-12.5f64).exp_m1() }
//!     fn form(&self) -> Form<'_, f64, 2> { Form::closest(Shape::Gaussian(&self.inner)) }
//! }
//! let p = Truncated { inner: GaussianPsd::isotropic(1e-3, 1.0)? };
//! assert!(!p.form().is_exact());
//! assert!(matches!(p.form().shape(), Shape::Gaussian(_)));
//! # Ok::<(), gmueller::Error>(())
//! ```

use nalgebra::SVector;

use super::GaussianPsd;
use crate::real::Real;

#[cfg(doc)]
use super::{GaussianMixturePsd, Grating, KCorrelation, Psd, Smooth};

/// The shape of a PSD on `ℝᴺ` (module formula), as its readers need it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape<'a, T: Real, const N: usize> {
    /// `p = 0`: nothing scatters (a [`Smooth`] surface of zero weight).
    Zero,
    /// One Dirac order at `ζ = 0` (a [`Smooth`] PSD of positive weight: scattering into the
    /// specular direction only).
    Origin,
    /// A Gaussian PSD (its spectral covariance `C`, rad²/length², and its variance).
    Gaussian(&'a GaussianPsd<T, N>),
    /// A Gaussian mixture: each component with weight `σ_j²/σ²`.
    Mixture(&'a [GaussianPsd<T, N>]),
    /// Dirac orders `(ζ_m, η_m)` (a [`Grating`]): weight `η_m/Σ η`.
    Orders(&'a [(SVector<T, N>, T)]),
    /// The isotropic K-correlation PSD `∝ (1 + T|ζ|²)^{−(γ+1)/2}` ([`KCorrelation`]).
    KCorrelation {
        /// `T` (length²).
        t: T,
        /// `γ > n − 1` (`n = N`; the mass is finite).
        gamma: T,
    },
}

/// The form a PSD declares ([`Psd::form`]): a [`Shape`], and whether the PSD *is* that shape
/// or only names the closest one (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Form<'a, T: Real, const N: usize> {
    shape: Shape<'a, T, N>,
    exact: bool,
}

impl<'a, T: Real, const N: usize> Form<'a, T, N> {
    /// The PSD is exactly `shape` (readers may use the shape's closed forms).
    #[inline]
    #[must_use]
    pub const fn exact(shape: Shape<'a, T, N>) -> Self {
        Self { shape, exact: true }
    }

    /// `shape` is the closest shape to the PSD, whose support it covers (readers evaluate the
    /// PSD itself and use the shape only to place samples and quadrature nodes).
    #[inline]
    #[must_use]
    pub const fn closest(shape: Shape<'a, T, N>) -> Self {
        Self {
            shape,
            exact: false,
        }
    }

    /// The shape.
    #[inline]
    #[must_use]
    pub const fn shape(&self) -> Shape<'a, T, N> {
        self.shape
    }

    /// `true` when the PSD is exactly [`Form::shape`].
    #[inline]
    #[must_use]
    pub const fn is_exact(&self) -> bool {
        self.exact
    }

    /// The Gaussian components of an exact Gaussian or mixture form (one for a Gaussian);
    /// `None` for any other form.
    #[inline]
    #[must_use]
    pub fn exact_gaussians(&self) -> Option<&'a [GaussianPsd<T, N>]> {
        match (self.exact, self.shape) {
            (true, Shape::Gaussian(g)) => Some(core::slice::from_ref(g)),
            (true, Shape::Mixture(c)) => Some(c),
            _ => None,
        }
    }
}
