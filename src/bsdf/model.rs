//! The two type parameters of a [`super::Bsdf`] beyond the scalar: the surface (the material
//! `(p, M)`: a [`RoughSurface`] of a PSD, a specular and a scattering pBSDF) and the kernel
//! (the model level: polarization, coherence, roughness). Each bundles its own parameters as
//! associated types, so that code generic over a `Bsdf` names two bounds,
//! `S: BsdfSurface<T>` and `K: BsdfKernel<T, S::Psd>`, rather than six.
//!
//! # Examples
//! A vertex function generic over every surface and level, with the static form:
//! ```
//! use gmueller::Real;
//! use gmueller::bsdf::{Bsdf, BsdfKernel, BsdfSurface, SurfaceCoherence};
//! use gmueller::frame::Frame;
//! use gmueller::interaction::{Full, Intensity, Kernel, Partial, RoughConductor, RoughDielectric};
//! use gmueller::psd::GaussianPsd;
//! use nalgebra::Vector3;
//! use num_complex::Complex;
//!
//! /// The probability of drawing a direction toward the light, from the camera's side.
//! fn mean_pdf<T: Real, S: BsdfSurface<T>, K: BsdfKernel<T, S::Psd>>(
//!     b: &Bsdf<'_, T, S, K>,
//!     to_camera: Vector3<T>,
//! ) -> Result<T, gmueller::Error> {
//!     let sky = SurfaceCoherence::new(T::lit(20.0))?;
//!     let sampler = b.incident_sampler(to_camera, &sky)?;
//!     Ok(sampler.sample(T::lit(0.3), [T::lit(0.5), T::lit(0.5)]).map_or(T::zero(), |s| s.pdf))
//! }
//!
//! let psd = GaussianPsd::<f32, 2>::isotropic(0.01, 2.0)?;
//! let glass = RoughDielectric::new(psd, 1.5)?;
//! let gold = RoughConductor::new(psd, Complex::new(0.2, 3.5))?;
//! let f = Frame::from_normal(Vector3::z())?;
//! let up = Vector3::new(0.2, 0.0, 1.0).normalize();
//! let a = mean_pdf(&Bsdf::new(&glass, Kernel::<Full, Partial>::default(), f, 0.5)?, up)?;
//! let b = mean_pdf(&Bsdf::new(&gold, Kernel::<Intensity, Partial>::default(), f, 0.5)?, up)?;
//! assert!(a > 0.0 && b > 0.0);
//! # Ok::<(), gmueller::Error>(())
//! ```

use super::Interface;
#[cfg(doc)]
use crate::interaction::RoughSurface;
use crate::interaction::coherence::CoherenceWeights;
use crate::interaction::polarization::PolarizationModel;
use crate::interaction::roughness::RoughnessWeights;
use crate::interaction::{Kernel, Surface};
use crate::psd::Psd;
use crate::real::Real;

/// A surface a [`super::Bsdf`] shades: a [`Surface`] (its PSD, specular interface and
/// scattering pBSDF as associated types, [`Surface::parts`]) whose parts the layer can sample:
/// an [`Interface`] (the PSD is read through its [`Psd::form`]). Implemented by every such surface (every
/// [`RoughSurface`] of those parts).
pub trait BsdfSurface<T: Real>: Surface<T, Specular: Interface<T>> {}

impl<T, S> BsdfSurface<T> for S
where
    T: Real,
    S: Surface<T, Specular: Interface<T>>,
{
}

/// A kernel a [`super::Bsdf`] evaluates with, for the PSD `P`: its polarization, coherence
/// and roughness levels as associated types. Implemented by every [`Kernel`] whose levels
/// serve `P`.
pub trait BsdfKernel<T: Real, P: Psd<T, 2>>: Clone {
    /// The polarization level.
    type Pol: PolarizationModel;
    /// The coherence level (with its blur method).
    type Coh: CoherenceWeights<T, P>;
    /// The roughness level.
    type Rough: RoughnessWeights<T, P, Self::Coh>;

    /// The kernel itself.
    fn kernel(&self) -> &Kernel<Self::Pol, Self::Coh, Self::Rough>;
}

impl<T, P, Pol, Coh, Rough> BsdfKernel<T, P> for Kernel<Pol, Coh, Rough>
where
    T: Real,
    P: Psd<T, 2>,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, P>,
    Rough: RoughnessWeights<T, P, Coh>,
    Self: Clone,
{
    type Pol = Pol;
    type Coh = Coh;
    type Rough = Rough;

    #[inline]
    fn kernel(&self) -> &Self {
        self
    }
}
