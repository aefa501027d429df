//! # gmueller — generalized Mueller calculus
//!
//! Coherence-aware, polarimetric light–matter interaction after Steinberg, Sen & Yan, *Towards
//! Practical Physical-Optics Rendering*, ACM TOG 41(4) (SIGGRAPH 2022), supplemental §S1–S2.
//! Equation numbers `S1.x`, `S2.x` refer to that supplemental.
//!
//! ## Module map (one module per concept)
//! - [`real`]: the scalar trait [`Real`] (`f32`, `f64`).
//! - [`error`]: the [`Error`] returned by validated constructors.
//! - [`interaction`]: the S2.20 kernel, pBSDFs, model levels.
//! - [`jones`]: Jones vectors and matrices, standard polarization elements.
//! - [`fresnel`]: Fresnel coefficients of dielectric and conducting interfaces as Jones matrices.
//! - [`stack`]: the stack operator and Kronecker product, Lemma S1.1.
//! - [`stokes`]: `A_mül` (S1.3), CSD matrices, Stokes and generalized Stokes vectors (S1.2).
//! - [`mueller`]: classical and generalized Mueller matrices (S1.7) and their analysis.
//! - [`frame`]: transverse frames, τ (S2.3) and the rotation Mueller matrix T(φ) (S2.4).
//! - [`gaussian`]: anisotropic Gaussians and their Fourier transforms (Lemma S2.1, Corollary S2.2).
//! - [`packet`]: the canonical wave packet (Definition 3.1): Stokes vector, coherence shapes, sources.
//! - [`psd`]: power spectral densities of random matter and their Gaussian blur (S2.14–S2.17).
//!
//! ## Conventions
#![doc = include_str!("../docs/conventions.md")]
//!
//! ## Errata of the seed derivation
#![doc = include_str!("../docs/errata.md")]
#![forbid(unsafe_code)]

pub mod error;
pub mod frame;
pub mod fresnel;
pub mod gaussian;
pub mod interaction;
pub mod jones;
pub mod mueller;
pub mod packet;
pub mod psd;
pub mod real;
pub mod stack;
pub mod stokes;

pub use error::Error;
pub use real::Real;

/// The README's Rust examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
