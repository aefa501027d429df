//! The literal seed formulas the tests compare with: the verification kit's
//! (`gmueller::verify::oracle`).
pub use gmueller::verify::oracle::*;
