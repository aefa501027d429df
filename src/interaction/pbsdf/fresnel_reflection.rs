//! Specular reflection by a planar interface (Fresnel).

use num_complex::Complex;

use super::{Geometry, Pbsdf, PbsdfForm, Side, validate_eta};
use crate::error::Error;
use crate::frame::frame_change_times;
use crate::fresnel;
use crate::mueller::Mueller;
use crate::real::Real;

/// Specular reflection by a planar interface of relative index `η = n + iκ` (dielectric or
/// conductor): the Mueller matrix of [`fresnel::reflection`] at `cos θ_i`, in s/p frames.
/// An opaque reflector: 0 in a transmission geometry (for a dielectric interface in both
/// directions, see [`super::FresnelInterface`]).
///
/// # Formula
/// ```text
/// M = T(F_spec → F_exit) · A_mül (J* ⊗ J) A_mül⁻¹,   J = fresnel::reflection(cos θ_i, η)
/// F_spec = Frame::sp(r_spec, n̂),  r_spec = −ŝ + 2 cos θ_i n̂     (shares ŝ with the incident frame)
/// ```
/// `J` maps the incident s/p frame to the s/p frame of the *specular* direction; the coherent
/// lobe's exit directions `r̂ ≠ r_spec` (finite coherence) receive it by the minimal rotation
/// `r_spec → r̂` ([`crate::frame::frame_change_mueller`], the identity at `r̂ = r_spec`). Beyond
/// 90° from `r_spec` (`r_spec·r̂ < 0`, where the lobe is far below any visible level) that frame
/// change is S2.3's reflection instead: the minimal rotation to `−r̂`, onto the exit frame with
/// `p̂` reversed, then `diag(1, −1)` (`tests/interaction/batch/pairs.rs` checks both cases
/// against a literal construction). Without
/// that transport the output depended on the arbitrary choice of ŝ at normal incidence (a jump
/// of the Stokes vector across the `Frame::sp` normal-incidence switch; `tests/extremes.rs`,
/// `normal_incidence_switch_is_invisible_in_a_fixed_frame`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FresnelReflection<T: Real> {
    eta: Complex<T>,
}

impl<T: Real> FresnelReflection<T> {
    /// A Fresnel reflector.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::OutOfRange`] unless `Re η > 0`, `Im η ≥ 0`, finite.
    pub fn new(eta: Complex<T>) -> Result<Self, Error> {
        validate_eta(eta)?;
        Ok(Self { eta })
    }

    /// The complex relative index `η = n + iκ`.
    #[inline]
    #[must_use]
    pub fn index(&self) -> Complex<T> {
        self.eta
    }
}

impl<T: Real> Pbsdf<T> for FresnelReflection<T> {
    #[inline]
    fn form(&self) -> PbsdfForm<'_, T> {
        PbsdfForm::FresnelReflection(self)
    }
    #[inline]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        if g.side() == Side::Transmission {
            return Mueller(nalgebra::Matrix4::zeros());
        }
        let m = Mueller::from_jones(&fresnel::reflection(g.cos_i, self.eta));
        frame_change_times(&g.specular_sp(), &g.exit_sp, &m)
    }
    /// `M₀₀` (the frame transport leaves it unchanged).
    #[inline]
    fn m00(&self, g: &Geometry<T>) -> T {
        if g.side() == Side::Transmission {
            return T::zero();
        }
        let c = fresnel::coefficients(g.cos_i, self.eta);
        (c.reflectance_s() + c.reflectance_p()) * T::lit(0.5)
    }
}
