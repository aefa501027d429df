//! The guides: how to use each part of the crate, with formulas, units, conventions and
//! examples. Each is a page of `docs/` in the repository, compiled here so that every code
//! sample in it is a doctest. What was measured when (dates, machines, history) is in the
//! repository's `VALIDATION.md` and `CHANGELOG.md`, not here.
//!
//! | guide | for |
//! |---|---|
//! | [`renderer`] | path-tracer authors: eval / sample / pdf, radiometry, frames, coherence per sample, costs |
//! | [`path_tracer`] | the renderer layer at a glance and the example path tracer, with what is checked |
//! | [`kernel`] | the S2.20 kernel on rough interfaces from either side, and what it is checked against |
//! | [`roughness`] | surfaces beyond first order: the Kirchhoff series, its levels and their costs |
//! | [`matter`] | far-field propagation and locally-stationary matter (S2.1–S2.9) |
//! | [`medium`] | random media: S2.20 with n = 3 for volume path tracers |
//! | [`verifying`] | the verification kit (feature `verify`) for derivations of your own |
//! | [`results`] | every numbered result of the supplemental, its tests and its oracles |
//! | [`conventions`] | time dependence, stacking, frames, units: the crate's one set of conventions |
//! | [`errata`] | the errors of the printed derivation, each with the test that shows it |
//! | [`numerical`] | validity ranges, precision and stability |
//! | [`architecture`] | the module graph and where each concept lives |

// The guides are prose with formulas (`Y_ref`, `DoP`, image names): backticks on every such
// word would make the Markdown pages unreadable on GitHub, where they are read too.
#![allow(clippy::doc_markdown)]

/// Using gmueller in a renderer.
pub mod renderer {
    #![doc = include_str!("../docs/renderer.md")]
}

/// The renderer layer at a glance, and the example path tracer.
pub mod path_tracer {
    #![doc = include_str!("../docs/path_tracer.md")]
}

/// The interaction kernel: rough interfaces from either side.
pub mod kernel {
    #![doc = include_str!("../docs/kernel.md")]
}

/// Rough surfaces beyond first order.
pub mod roughness {
    #![doc = include_str!("../docs/roughness.md")]
}

/// Far-field propagation and locally-stationary matter.
pub mod matter {
    #![doc = include_str!("../docs/matter.md")]
}

/// Random media.
pub mod medium {
    #![doc = include_str!("../docs/medium.md")]
}

/// Verifying a derivation with `gmueller::verify`.
pub mod verifying {
    #![doc = include_str!("../docs/verifying.md")]
}

/// Every numbered result, its test and its oracle.
pub mod results {
    #![doc = include_str!("../docs/results.md")]
}

/// Conventions.
pub mod conventions {
    #![doc = include_str!("../docs/conventions.md")]
}

/// Errata of the seed derivation.
pub mod errata {
    #![doc = include_str!("../docs/errata.md")]
}

/// Numerical behaviour.
pub mod numerical {
    #![doc = include_str!("../docs/numerical.md")]
}

/// Architecture.
pub mod architecture {
    #![doc = include_str!("../docs/architecture.md")]
}
