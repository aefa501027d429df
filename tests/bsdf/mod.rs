//! Mirrors `src/bsdf/`: the tests of `bsdf`.

mod bundle;
mod eval;
mod extremes;
mod f32;
mod furnace;
mod horizon;
mod material;
mod pairs;
mod path;
mod reciprocity;
mod rough;
mod sample_batch;
mod sampling;
mod vertices;
