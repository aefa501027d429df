//! Mirrors `src/medium/`: the tests of `medium`.

pub(crate) mod born;
mod conventions;
mod extremes;
mod f32;
mod limits;
mod paraxial;
pub(crate) mod sampling;
mod spectrum;
