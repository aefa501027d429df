//! What the sampler needs to know of a material's mean interface: whether it transmits, and
//! its Fresnel reflectance (the weight that chooses between reflection and transmission).

use num_complex::Complex;

use crate::fresnel;
use crate::interaction::{FresnelInterface, FresnelReflection, Pbsdf};
use crate::real::Real;

/// The mean interface of a material, as the renderer layer sees it: the specular pBSDF of a
/// [`crate::interaction::RoughSurface`] that knows its media.
///
/// Implemented for [`FresnelInterface`] (a dielectric interface: reflection and transmission
/// from either side) and [`FresnelReflection`] (an opaque conductor: reflection from the side
/// the surface normal points to).
pub trait Interface<T: Real>: Pbsdf<T> {
    /// `Some(η)`, `η = n_below/n_above`, for an interface that transmits; `None` for an opaque
    /// surface (light arrives and leaves on the side the surface normal points to).
    #[must_use]
    fn transmission_index(&self) -> Option<T>;

    /// The Fresnel reflectance of unpolarized light, `(R_s + R_p)/2`, arriving at `cos θ` (in
    /// `(0, 1]`) from above (`from_below = false`) or from below. 1 under total internal
    /// reflection.
    #[must_use]
    fn reflectance(&self, cos_theta: T, from_below: bool) -> T;
}

impl<T: Real> Interface<T> for FresnelInterface<T> {
    #[inline]
    fn transmission_index(&self) -> Option<T> {
        Some(self.relative_index())
    }
    #[inline]
    fn reflectance(&self, cos_theta: T, from_below: bool) -> T {
        let eta = if from_below {
            self.relative_index().recip()
        } else {
            self.relative_index()
        };
        let c = fresnel::coefficients(cos_theta, Complex::new(eta, T::zero()));
        (c.reflectance_s() + c.reflectance_p()) * T::lit(0.5)
    }
}

impl<T: Real> Interface<T> for FresnelReflection<T> {
    #[inline]
    fn transmission_index(&self) -> Option<T> {
        None
    }
    #[inline]
    fn reflectance(&self, cos_theta: T, _from_below: bool) -> T {
        let c = fresnel::coefficients(cos_theta, self.index());
        (c.reflectance_s() + c.reflectance_p()) * T::lit(0.5)
    }
}
