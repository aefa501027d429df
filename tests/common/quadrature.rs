//! The adaptive Gauss–Legendre integrator: the verification kit's
//! (`gmueller::verify::quadrature`).
pub use gmueller::verify::quadrature::{gauss_legendre, integrate};
