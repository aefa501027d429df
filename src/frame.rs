//! Transverse frames and their changes: τ (S2.3) and the Mueller rotation T(φ) (S2.4).

use nalgebra::Vector3;

use crate::real::Real;

/// A right-handed orthonormal frame (x̂, ŷ, k̂): the transverse basis of a beam travelling along k̂.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame<T: Real> {
    pub(crate) x: Vector3<T>,
    pub(crate) y: Vector3<T>,
    pub(crate) k: Vector3<T>,
}
