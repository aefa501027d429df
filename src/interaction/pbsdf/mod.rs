//! Polarimetric BSDFs (S2.19): the classical Mueller matrix `M` of the interaction, from the
//! incident beam's s/p frame to the exit beam's s/p frame.
//!
//! One file per pBSDF; a new one is a new file implementing [`Pbsdf`] (reading the side, the
//! angles, `h`, the phase factor and the s/p frames from [`Geometry`]) and a `pub use` here.
//!
//! Sides: [`FresnelInterface`], [`RayleighRice`] and [`PhaseScreen`] describe both reflection
//! and transmission (and, at an interface, light from either side); [`FresnelReflection`] is an
//! opaque reflector (0 in a transmission geometry); [`ConstantMueller`] and [`IdealDiffuse`] are
//! the same on both sides.
//!
//! Here: the [`Pbsdf`] trait and the built-in forms the kernel's SIMD lanes recognize
//! ([`PbsdfForm`]); the Fresnel pBSDFs of the coherent lobes ([`FresnelReflection`],
//! [`FresnelInterface`]); the scatterers ([`RayleighRice`], [`PhaseScreen`], [`TangentPlane`]);
//! and the simple ones ([`ConstantMueller`], the ideal depolarizer [`IdealDiffuse`]). The complete materials that pair
//! them with a PSD ([`super::RoughDielectric`], [`super::RoughConductor`], …) are at the top of
//! [`super`].

mod constant;
mod fresnel_interface;
mod fresnel_reflection;
mod ideal_diffuse;
mod phase_screen;
mod rayleigh_rice;
mod tangent_plane;

pub use constant::ConstantMueller;
pub use fresnel_interface::FresnelInterface;
pub use fresnel_reflection::FresnelReflection;
pub use ideal_diffuse::IdealDiffuse;
pub use phase_screen::PhaseScreen;
pub use rayleigh_rice::RayleighRice;
pub(crate) use rayleigh_rice::Scale;
pub use tangent_plane::TangentPlane;

use num_complex::Complex;

use super::geometry::{Geometry, Side};
use crate::error::Error;
use crate::mueller::Mueller;
use crate::real::Real;

/// A pBSDF: the Mueller matrix `M(ŝ → r̂)` of S2.19, from the incident s/p frame
/// ([`Geometry::incident_sp`]) to the exit s/p frame ([`Geometry::exit_sp`]), on the side the
/// geometry names ([`Geometry::side`]).
///
/// `M` is dimensionless here: the kernel supplies the `cos θ_o / λ_t²` of S2.20 (`λ_t` the
/// wavelength in the exit medium).
pub trait Pbsdf<T: Real> {
    /// The Mueller matrix for this geometry.
    #[must_use]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T>;

    /// `M₀₀` alone (what the [`super::Intensity`] level needs); override when cheaper than
    /// [`Pbsdf::mueller`].
    #[inline]
    #[must_use]
    fn m00(&self, g: &Geometry<T>) -> T {
        self.mueller(g).0[(0, 0)]
    }

    /// What the pBSDF is, where the kernel's SIMD lanes have it built in ([`PbsdfForm`]);
    /// [`PbsdfForm::Other`] by default (the kernel then evaluates it exit by exit).
    #[inline]
    #[must_use]
    fn form(&self) -> PbsdfForm<'_, T> {
        PbsdfForm::Other
    }
}

/// The pBSDFs the kernel's SIMD lanes have built in ([`Pbsdf::form`]): a rough surface whose
/// specular pBSDF is a [`FresnelReflection`] or a [`FresnelInterface`] and whose scattering
/// pBSDF is a [`RayleighRice`] (with an exact Gaussian or mixture PSD,
/// [`crate::psd::Form::exact_gaussians`]) is evaluated in lanes by
/// [`super::Kernel::evaluate_batch`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PbsdfForm<'a, T: Real> {
    /// A conductor's (or any opaque reflector's) Fresnel reflection.
    FresnelReflection(&'a FresnelReflection<T>),
    /// A dielectric interface's Fresnel reflection and transmission.
    FresnelInterface(&'a FresnelInterface<T>),
    /// The Rayleigh–Rice scattering pBSDF.
    RayleighRice(&'a RayleighRice<T>),
    /// Any other pBSDF.
    Other,
}

/// `Ok` for a refractive index `η = n + iκ` with `n > 0`, `κ ≥ 0`, both finite.
pub(super) fn validate_eta<T: Real>(eta: Complex<T>) -> Result<(), Error> {
    crate::error::ensure_finite("refractive index", [eta.re, eta.im])?;
    if !(eta.re > T::zero() && eta.im >= T::zero()) {
        return Err(Error::OutOfRange {
            what: "refractive index η = n + iκ",
            value: eta.re.to_f64(),
            expected: "Re η > 0 and Im η ≥ 0",
        });
    }
    Ok(())
}
