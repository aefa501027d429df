//! Mirrors `src/interaction/`: the tests of `interaction`.

pub(crate) mod batch;
mod energy;
mod exitant;
mod f32;
mod laws;
mod pbsdf;
mod polarization;
mod prepared;
mod reference;
mod roughness;
mod s2_10;
mod sampling;
mod sampling_extremes;
mod transmission;
