//! Mirrors `src/medium/`: the tests of `medium`.

mod born;
mod conventions;
mod extremes;
mod f32;
mod limits;
mod paraxial;
mod sampling;
mod spectrum;
