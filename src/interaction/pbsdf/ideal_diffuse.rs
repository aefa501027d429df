//! An ideal depolarizer.

use super::{Geometry, Pbsdf};
use crate::error::Error;
use crate::mueller::Mueller;
use crate::real::Real;

/// An ideal depolarizer of albedo `a`: `M = a · diag(1, 0, 0, 0)` — every output unpolarized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdealDiffuse<T: Real> {
    albedo: T,
}

impl<T: Real> IdealDiffuse<T> {
    /// An ideal depolarizer.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `albedo ≥ 0` and finite.
    pub fn new(albedo: T) -> Result<Self, Error> {
        if !(albedo >= T::zero() && albedo.is_finite()) {
            return Err(Error::OutOfRange {
                what: "albedo",
                value: albedo.to_f64(),
                expected: "finite and ≥ 0",
            });
        }
        Ok(Self { albedo })
    }
}

impl<T: Real> Pbsdf<T> for IdealDiffuse<T> {
    #[inline]
    fn mueller(&self, _g: &Geometry<T>) -> Mueller<T> {
        let mut m = nalgebra::Matrix4::zeros();
        m[(0, 0)] = self.albedo;
        Mueller(m)
    }
    #[inline]
    fn m00(&self, _g: &Geometry<T>) -> T {
        self.albedo
    }
}
