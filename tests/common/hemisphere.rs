//! Quadrature over the exit hemisphere: the verification kit's (`gmueller::verify::quadrature`).
pub use gmueller::verify::quadrature::{Hemisphere, hemisphere_integral};
