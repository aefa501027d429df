//! The names a renderer uses, in one import: `use gmueller::prelude::*;`.
//!
//! The material handle and its inputs ([`Material`], [`ShadingPoint`], [`SurfaceCoherence`],
//! [`Level`], [`Roughness`]), the materials' constructors, the path state
//! ([`PathThroughput`]), frames, Stokes vectors and Mueller matrices, and the [`Throughput`]
//! trait (whose methods `m00`, `scaled`, `then` … a renderer generic over the polarization
//! level calls on the static [`crate::bsdf::Bsdf`]'s throughputs).
//!
//! # Examples
//! ```
//! use gmueller::prelude::*;
//! let glass = Material::new(
//!     RoughDielectric::new(GaussianPsd::<f32, 2>::isotropic(0.01, 2.0)?, 1.5)?,
//!     Level::ALL[7],
//! );
//! assert!(!glass.is_opaque());
//! # Ok::<(), gmueller::Error>(())
//! ```

pub use crate::bsdf::{
    Bsdf, BsdfKernel, BsdfSample, BsdfSurface, BsdfValue, Bundle, BundleSample, IncidentVertex,
    LobeFlags, Material, PathThroughput, ShadingPoint, SurfaceCoherence, VertexQuery,
};
pub use crate::error::Error;
pub use crate::frame::Frame;
pub use crate::interaction::polarization::Throughput;
pub use crate::interaction::roughness::KirchhoffSeries;
pub use crate::interaction::{
    Geometry, KirchhoffConductor, KirchhoffDielectric, Level, RoughConductor, RoughDielectric,
    Roughness, SmoothConductor, SmoothDielectric,
};
pub use crate::mueller::Mueller;
pub use crate::psd::{GaussianMixturePsd, GaussianPsd, Grating, KCorrelation, Smooth};
pub use crate::spectral::{Glass, Metal};
pub use crate::stokes::Stokes;
