//! The flat interface between two dielectrics (Fresnel), in reflection and transmission, from
//! either side.

use num_complex::Complex;

use super::{Geometry, Pbsdf, PbsdfForm, Side};
use crate::error::Error;
use crate::frame::frame_change_times;
use crate::fresnel;
use crate::jones::JonesMatrix;
use crate::mueller::Mueller;
use crate::real::Real;

/// The specular pBSDF of a flat interface between two lossless media of relative index
/// `η = n_below/n_above` (the convention of [`Geometry::at_interface`]): Fresnel reflection on
/// the side of the source, Fresnel transmission across, from either side.
///
/// # Formula
/// ```text
/// η_t = η from above, 1/η from below ([`Geometry::incident_from_below`])
/// reflection:    J = diag(r_s, r_p)(cos θ_i, η_t)             (fresnel::reflection)
/// transmission:  J = √η_t · diag(t_s, t_p)(cos θ_i, η_t)      (0 when sin θ_i ≥ η_t: total
///                                                              internal reflection)
/// M = T(F_spec → F_exit) · A_mül (J* ⊗ J) A_mül⁻¹
/// ```
/// `F_spec` is the s/p frame of the specular (mirror or Snell) direction
/// ([`Geometry::specular_sp`]); exit directions of the coherent lobe that differ from it (finite
/// coherence) receive the light by the minimal rotation (S2.3's reflection beyond 90°), as in
/// [`super::FresnelReflection`].
///
/// Why `√η_t`: the kernel returns radiance in the exit medium with the factor `1/λ_t² = η_t²/λ²`
/// ([`crate::interaction`], module formula), and the specular lobe integrates to
/// `α M₀₀ cos θ_t/cos θ_i` of the incident power (the lobe's solid angle shrinks by `η_t²` and
/// its cosine is `cos θ_t`). With `M₀₀ = η_t |t|²` this is `α T`, the Fresnel power
/// transmittance `T = η_t cos θ_t |t|²/cos θ_i` attenuated by roughness; in the plane-wave limit
/// the radiance is `η_t² T` times the incident one (the `n²` law of radiance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FresnelInterface<T: Real> {
    eta: T,
}

impl<T: Real> FresnelInterface<T> {
    /// A flat interface of relative index `η = n_below/n_above`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `η` is finite and positive with `1/η` finite.
    pub fn new(eta: T) -> Result<Self, Error> {
        check_relative_index(eta)?;
        Ok(Self { eta })
    }

    /// `η = n_below/n_above`.
    #[inline]
    #[must_use]
    pub fn relative_index(&self) -> T {
        self.eta
    }

    /// The Jones matrix from the incident s/p frame to the specular direction's s/p frame
    /// (`None` in transmission under total internal reflection).
    #[must_use]
    pub fn jones(&self, g: &Geometry<T>) -> Option<JonesMatrix<T>> {
        let eta = relative_to_source(self.eta, g);
        match g.side() {
            Side::Reflection => Some(fresnel::reflection(g.cos_i, Complex::new(eta, T::zero()))),
            Side::Transmission => transmission_jones(g.cos_i, eta),
        }
    }
}

impl<T: Real> Pbsdf<T> for FresnelInterface<T> {
    #[inline]
    fn form(&self) -> PbsdfForm<'_, T> {
        PbsdfForm::FresnelInterface(self)
    }
    #[inline]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        match self.jones(g) {
            Some(j) => frame_change_times(&g.specular_sp(), &g.exit_sp, &Mueller::from_jones(&j)),
            None => Mueller(nalgebra::Matrix4::zeros()),
        }
    }
    /// `M₀₀` (the frame transport leaves it unchanged).
    #[inline]
    fn m00(&self, g: &Geometry<T>) -> T {
        let eta = relative_to_source(self.eta, g);
        let half = T::lit(0.5);
        match g.side() {
            Side::Reflection => {
                let c = fresnel::coefficients(g.cos_i, Complex::new(eta, T::zero()));
                (c.reflectance_s() + c.reflectance_p()) * half
            }
            Side::Transmission => {
                if total_internal_reflection(g.cos_i, eta) {
                    return T::zero();
                }
                let c = fresnel::coefficients(g.cos_i, Complex::new(eta, T::zero()));
                eta * (c.ts.norm_sqr() + c.tp.norm_sqr()) * half
            }
        }
    }
}

/// `η` as seen from the source: `η` from above, `1/η` from below.
#[inline]
pub(super) fn relative_to_source<T: Real>(eta: T, g: &Geometry<T>) -> T {
    if g.incident_from_below() {
        eta.recip()
    } else {
        eta
    }
}

/// `sin²θ_i ≥ η²`: no transmitted beam. As `(η² − 1) + cos²θ_i ≤ 0`, the form
/// [`fresnel::coefficients`] takes the square root of, so both agree on the branch.
#[inline]
fn total_internal_reflection<T: Real>(cos_i: T, eta: T) -> bool {
    (eta * eta - T::one()) + cos_i * cos_i <= T::zero()
}

/// `√η diag(t_s, t_p)` in the s/p frames of the incident and the Snell direction; `None` under
/// total internal reflection.
fn transmission_jones<T: Real>(cos_i: T, eta: T) -> Option<JonesMatrix<T>> {
    if total_internal_reflection(cos_i, eta) {
        return None;
    }
    let c = fresnel::coefficients(cos_i, Complex::new(eta, T::zero()));
    let root = Complex::new(eta.sqrt(), T::zero());
    let z = Complex::new(T::zero(), T::zero());
    Some(JonesMatrix(nalgebra::Matrix2::new(
        c.ts * root,
        z,
        z,
        c.tp * root,
    )))
}

/// `Ok` for a relative index that is finite and positive with a finite reciprocal.
pub(super) fn check_relative_index<T: Real>(eta: T) -> Result<(), Error> {
    crate::error::ensure_finite("relative index", [eta])?;
    if !(eta > T::zero() && eta.recip().is_finite()) {
        return Err(Error::OutOfRange {
            what: "relative index η = n_below/n_above",
            value: eta.to_f64(),
            expected: "finite and > 0, with 1/η finite",
        });
    }
    Ok(())
}
