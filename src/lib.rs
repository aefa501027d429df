//! # gmueller — generalized Mueller calculus
//!
//! Coherence-aware, polarimetric light–matter interaction after Steinberg, Sen & Yan, *Towards
//! Practical Physical-Optics Rendering*, ACM TOG 41(4) (SIGGRAPH 2022), supplemental §S1–S2.
//! Equation numbers `S1.x`, `S2.x` refer to that supplemental.
//!
//! ## Module map
//! One module per concept, bottom first: a module imports only from those listed before it
//! ([`guide::architecture`] draws the graph; `tests/architecture.rs` checks it).
//! - `simd` (crate-private): the lane vocabulary, vector exponential, structure-of-arrays
//!   view and chunk loop under the batch paths (imports no physics module).
//! - [`real`]: the scalar trait [`Real`] (`f32`, `f64`).
//! - [`error`]: the [`Error`] returned by validated constructors.
//! - [`stack`]: the stack operator and Kronecker product, Lemma S1.1.
//! - [`jones`]: Jones vectors and matrices, standard polarization elements.
//! - [`stokes`]: `A_mül` (S1.3), CSD matrices, Stokes and generalized Stokes vectors (S1.2).
//! - [`mueller`]: classical and generalized Mueller matrices (S1.7) and their analysis;
//!   [`mueller::batch`], Jones → Mueller over structure-of-arrays batches with run-time SIMD.
//! - [`frame`]: transverse frames, τ (S2.3) and the rotation Mueller matrix T(φ) (S2.4).
//! - [`fresnel`]: Fresnel coefficients of dielectric and conducting interfaces as Jones matrices.
//! - [`spectral`]: spectral data for renderers — the CIE 1931 colour-matching functions,
//!   XYZ ↔ sRGB, measured complex indices of metals, glass dispersion (Sellmeier, Cauchy).
//! - [`gaussian`]: anisotropic Gaussians and their Fourier transforms (Lemma S2.1, Corollary S2.2).
//! - [`packet`]: the canonical wave packet (Definition 3.1): Stokes vector, coherence shapes, sources.
//! - [`propagation`]: far-field propagation (S2.1–S2.6): the vector Smythe formula and the
//!   propagation of CSD matrices, generalized Stokes parameters and radiance from a region.
//! - [`psd`]: power spectral densities of random matter and their Gaussian blur (S2.14–S2.17).
//! - [`matter`]: locally-stationary matter (S2.7–S2.9), its angular spectrum (S2.14) and pBSDF
//!   (S2.19), and a generator of its random realizations.
//! - [`interaction`]: the S2.20 kernel, pBSDFs (S2.19), model levels, the exitant packet, in
//!   reflection and in transmission through rough interfaces from either side; complete
//!   materials ([`interaction::RoughDielectric`], [`interaction::RoughConductor`] and their smooth
//!   limits); [`interaction::batch`], the kernel over batches of directions and wavelengths, in SIMD
//!   lanes for Gaussian and mixture PSDs on conductors and dielectrics (both sides).
//! - [`bsdf`]: the layer a renderer calls — the kernel as a BSDF (Mueller matrices per lobe in
//!   documented frames, lobe flags), sampling and pdf in both tracing directions, and the
//!   coherence one Monte Carlo sample of light carries ([`guide::renderer`]); [`bsdf::Material`],
//!   one type for every surface with its model level chosen at run time, and
//!   [`bsdf::PathThroughput`], a backward path's state.
//! - [`medium`]: random media — S2.20 with n = 3 in first-Born form, as a volume path tracer
//!   needs it: a scattering coefficient and a Mueller phase matrix for the incident packet's
//!   coherence, with sampling and its exact pdf.
//! - [`prelude`]: the names a renderer uses, in one import.
//! - [`guide`]: the guides (no code: pages of `docs/`, their examples doctests).
//!
//! ## Quick start
//! ```
//! use gmueller::frame::Frame;
//! use gmueller::interaction::{Full, Geometry, Kernel, Partial, PlaneWave, RoughSurface};
//! use gmueller::interaction::pbsdf::{FresnelReflection, RayleighRice};
//! use gmueller::packet::WavePacket;
//! use gmueller::psd::{ClosedForm, GaussianPsd};
//! use gmueller::stokes::Stokes;
//! use nalgebra::Vector3;
//! use num_complex::Complex;
//!
//! // Sunlight (a disk source of 6.8e-5 sr) at 550 nm, 40° incidence, on glass with 5 nm rms
//! // roughness and a 1 µm correlation length.
//! let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
//! let travel = Vector3::new(40f64.to_radians().sin(), 0.0, -40f64.to_radians().cos());
//! let sun = WavePacket::from_distant_disk_source(
//!     Stokes::unpolarized(1.0)?, 6.8e-5, Frame::sp(travel, Vector3::z())?, 0.55)?;
//! let glass = Complex::new(1.5, 0.0);
//! let material = RoughSurface {
//!     psd: GaussianPsd::isotropic(0.005, 1.0)?,
//!     specular: FresnelReflection::new(glass)?,
//!     scatter: RayleighRice::new(glass)?,
//! };
//! let exit = Vector3::new(0.5, 0.1, 0.86);
//! let g = Geometry::for_packet(&sun, &surface, exit)?;
//! let partial = Kernel::<Full, Partial>::default().evaluate(&material, &sun, &g);
//! let classical = Kernel::<Full, PlaneWave>::default().evaluate(&material, &sun, &g);
//! // Sunlight's coherence (≈ 34 µm) is far wider than the 1 µm correlation length: the partially
//! // coherent kernel is within 1 % of the classical (plane-wave) BRDF here.
//! let rel = (partial.scattered.s0() / classical.scattered.s0() - 1.0).abs();
//! assert!(rel < 1e-2, "{rel}");
//! # Ok::<(), gmueller::Error>(())
//! ```
//!
//! ## Guides
//! [`guide`] holds the guides (each a page of the repository's `docs/`, its examples
//! doctests): [`guide::renderer`] for path-tracer authors, [`guide::kernel`],
//! [`guide::roughness`], [`guide::matter`], [`guide::medium`], [`guide::verifying`], and the
//! reference pages [`guide::conventions`], [`guide::errata`], [`guide::numerical`],
//! [`guide::results`] (every numbered result of the supplemental with its tests and oracles)
//! and [`guide::architecture`].
#![forbid(unsafe_code)]

pub mod bsdf;
pub mod error;
pub mod frame;
pub mod fresnel;
pub mod gaussian;
pub mod guide;
pub mod interaction;
pub mod jones;
pub mod matter;
pub mod medium;
pub mod mueller;
mod numerics;
pub mod packet;
pub mod prelude;
pub mod propagation;
pub mod psd;
pub mod real;
mod simd;
pub mod spectral;
pub mod stack;
pub mod stokes;
#[cfg(feature = "verify")]
pub mod verify;

pub use error::Error;
pub use real::Real;

/// The README's Rust examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
