//! The seeded generators of the tests: the verification kit's (`gmueller::verify::rng`).
pub use gmueller::verify::rng::{Lcg, SplitMix64};
