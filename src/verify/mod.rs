//! A verification kit for derivations in generalized Mueller calculus (cargo feature
//! `verify`; renderers leave it off and pay nothing).
//!
//! The crate's own tests are built on it. It gives:
//! - [`strategy`]: proptest strategies of objects that are valid by construction (Stokes
//!   vectors inside the cone and on it, general, unitary and Hermitian Jones matrices,
//!   realizable Mueller matrices, SPD 2×2 shapes of chosen condition, unit vectors, the parts
//!   of realizable two-shape packets up to the Bochner bound `|μ|² = √(|Θx||Θy|)/|Θ½|`,
//!   right-handed frames, polar angles and geometries with exact normal and grazing cases) and the
//!   run configuration ([`strategy::proptest_config`]: a fixed seed in a normal run, fresh
//!   seeds and more cases under `GMUELLER_PROPTEST_SEARCH`);
//! - [`oracle`]: the seed's formulas written literally (S1.3's `A_mül`, S1.7's Kronecker form,
//!   S2.3–S2.4's τ projection, Germer's Rayleigh–Rice factors, the S2.18 section and the
//!   closed S2.10 integral), each naming its equation;
//! - [`quadrature`]: an adaptive Gauss–Legendre integrator (nodes computed, not tabulated),
//!   the exit hemisphere in exit-tangent coordinates, a trapezoid rule on a cube;
//! - [`tol`]: absolute-and-relative tolerances and comparisons that print both sides;
//! - [`check`]: assertions of physical validity (Stokes vectors, Cloude realizability, Mueller
//!   equality on the matrix's own scale);
//! - [`rng`]: small seeded generators for inputs outside proptest;
//! - [`stats`]: Monte Carlo estimates with standard errors, and agreement within a number of them.
//!
//! [`proptest`] is re-exported, so a test needs no dependency of its own beyond this crate with
//! the feature on.
//!
//! # Example: a closed form against the Jones path
//! A claim — "a rotated unitary element's Mueller matrix is realizable and maps a fully
//! polarized Stokes vector onto the cone" — checked over 64 cases:
//! ```
//! use gmueller::jones::JonesMatrix;
//! use gmueller::mueller::Mueller;
//! use gmueller::verify::proptest::prelude::*;
//! use gmueller::verify::{check, strategy, tol};
//!
//! proptest!(strategy::proptest_config(64), |(j in strategy::unitary_jones(),
//!                                              s in strategy::stokes_on_cone())| {
//!     let m = Mueller::from_jones(&JonesMatrix::from_matrix(j).unwrap());
//!     check::assert_realizable("unitary", &m.matrix(), 1e-12);
//!     let out = m.matrix() * s;
//!     check::assert_valid_stokes("output", out, tol::F64);
//!     let dop = out.fixed_rows::<3>(1).norm() / out[0];
//!     tol::assert_close("DoP", dop, 1.0, tol::F64);
//! });
//! ```

pub mod check;
pub mod oracle;
pub mod quadrature;
pub mod rng;
pub mod stats;
pub mod strategy;
pub mod tol;

pub use proptest;
