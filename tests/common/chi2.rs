//! The chi-square test of a direction sampler: the verification kit's (`gmueller::verify::chi2`).
pub use gmueller::verify::chi2::*;
