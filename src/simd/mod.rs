//! The SIMD layer under the batch paths: the lane vocabulary of `f32` and `f64` ([`Lanes`],
//! a supertrait of [`crate::real::Real`]), the vector exponential, logarithm and sine–cosine,
//! complex numbers in lanes, the structure-of-arrays view [`Soa`] / [`SoaMut`] with
//! [`padded_stride`], and the chunk loop shared by the batch kernels.
//!
//! This module imports nothing from the physics modules (nor from [`crate::real`]): a batch
//! kernel of a physics module writes its per-lane computation once, generic over
//! [`pulp::Simd`], and runs it through [`dispatch`] and the driver here. No `unsafe`, no heap
//! allocation.

#[cfg(test)]
mod check;
pub(crate) mod complex;
pub(crate) mod driver;
pub(crate) mod exp;
mod lanes;
pub(crate) mod ln;
pub(crate) mod sin_cos;
mod soa;

pub use lanes::{Lanes, dispatch};
pub use soa::{LayoutError, Soa, SoaMut, padded_stride};
