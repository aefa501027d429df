//! What the sampler needs to know of a material's mean interface: whether it transmits, and
//! its Fresnel reflectance (the weight that chooses between reflection and transmission).

use crate::fresnel;
use crate::interaction::pbsdf::{FresnelInterface, FresnelReflection, Pbsdf};
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
    /// Real arithmetic for the real index (the form of [`fresnel::coefficients`], without its
    /// complex square root):
    /// ```text
    /// q = η cos θ_t = √((η² − 1) + c²)  (R = 1 where it is imaginary; 0 at η = 1),
    /// r_s = (c − q)/(c + q),   r_p = (η² c − q)/(η² c + q)
    /// ```
    #[inline]
    fn reflectance(&self, cos_theta: T, from_below: bool) -> T {
        let eta = if from_below {
            self.relative_index().recip()
        } else {
            self.relative_index()
        };
        let c = cos_theta.max(T::zero()).min(T::one());
        let e2 = eta * eta;
        let q2 = (e2 - T::one()) + c * c;
        if q2 <= T::zero() {
            return T::one();
        }
        let q = q2.sqrt();
        let rs = (c - q) / (c + q);
        let rp = (e2 * c - q) / (e2 * c + q);
        (rs * rs + rp * rp) * T::lit(0.5)
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

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex;

    /// The real-arithmetic dielectric reflectance equals the complex Fresnel coefficients' on
    /// both sides of the interface, total internal reflection included.
    #[test]
    fn dielectric_reflectance_matches_the_fresnel_coefficients() {
        for eta in [1.0001_f64, 1.33, 1.5, 2.4] {
            let f = FresnelInterface::new(eta).unwrap();
            for i in 0..=400 {
                let c = i as f64 / 400.0;
                for below in [false, true] {
                    let e = if below { 1.0 / eta } else { eta };
                    let k = fresnel::coefficients(c, Complex::new(e, 0.0));
                    let want = 0.5 * (k.reflectance_s() + k.reflectance_p());
                    let got = f.reflectance(c, below);
                    // Both round (η² − 1) + cos²θ, whose cancellation near the critical angle
                    // amplifies rounding by 1/|η² − sin²θ|.
                    let q2 = ((e * e - 1.0) + c * c).abs();
                    let tol = 1e-15 + 8.0 * f64::EPSILON / q2;
                    assert!(
                        (got - want).abs() <= tol,
                        "η {eta} cos {c} below {below}: {got} vs {want}"
                    );
                }
            }
        }
    }
}
