//! A constant Mueller matrix.

use super::{Geometry, Pbsdf};
use crate::mueller::Mueller;
use crate::real::Real;

/// A constant Mueller matrix, the same for every geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantMueller<T: Real>(pub Mueller<T>);

impl<T: Real> Pbsdf<T> for ConstantMueller<T> {
    #[inline]
    fn mueller(&self, _g: &Geometry<T>) -> Mueller<T> {
        self.0
    }
}
