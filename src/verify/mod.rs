//! A verification kit for derivations in generalized Mueller calculus (cargo feature
//! `verify`; renderers leave it off and pay nothing).
//!
//! The crate's own tests are built on it. It gives:
//! - [`strategy`]: proptest strategies of objects that are valid by construction, with ranges
//!   the caller sets — Stokes vectors inside the cone and on it ([`strategy::stokes_vector_in`]);
//!   general, unitary and Hermitian Jones matrices and the standard elements at random angles;
//!   realizable Mueller matrices, depolarizers and matrices within a chosen distance of the
//!   realizability boundary; one- and two-point CSD matrices; SPD shapes of chosen condition in
//!   2 and N dimensions; the parts of realizable two-shape packets up to the Bochner bound
//!   `|μ|² = √(|Θx||Θy|)/|Θ½|` ([`strategy::PacketRanges`]); unit vectors, right-handed frames
//!   and s/p frames; polar angles and geometries with exact normal and grazing cases; Gaussian,
//!   K-correlation and mixture PSDs ([`strategy::PsdRanges`]) — and the run configuration
//!   ([`strategy::proptest_config`]: a fixed seed in a normal run, fresh seeds and more cases
//!   under `GMUELLER_PROPTEST_SEARCH`) and [`strategy::sample`] for counting coverage;
//! - [`oracle`]: the seed's formulas written literally, each naming its equation: S1.1's
//!   stacks, S1.2's `A_mül vec(C)`, S1.4–S1.7 (the CSD after a Jones pair, its stacked form, the
//!   generalized Mueller matrix), S2.3–S2.4's τ projection and `T`, Germer's Rayleigh–Rice
//!   factors, Lemma S2.1 (printed, corrected and by Fourier quadrature), Corollary S2.2 (literal
//!   and by quadrature), the PSD blur and S2.15 by quadrature, the S2.18 section and the closed
//!   S2.10 integral;
//! - [`quadrature`]: an adaptive Gauss–Legendre integrator (nodes computed, not tabulated),
//!   the exit hemisphere in exit-tangent coordinates and a surface's albedo Mueller matrix, a
//!   trapezoid rule on a cube;
//! - [`chi2`]: Pearson's chi-square test of a direction sampler against its pdf, with exact
//!   quantiles;
//! - [`tol`]: absolute-and-relative tolerances and comparisons that print both sides;
//! - [`check`]: assertions of physical validity (Stokes vectors, Cloude realizability, Mueller
//!   equality on the matrix's own scale, energy ≤ 1, reciprocity in the `D Mᵀ D` form);
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
pub mod chi2;
pub mod oracle;
pub mod quadrature;
pub mod rng;
pub mod stats;
pub mod strategy;
pub mod tol;

pub use proptest;
