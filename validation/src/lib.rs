//! Validation programs for gmueller, kept out of the library's examples so that their heavy
//! dependencies (`rustfft`, `plotters`, `indicatif`, `dejavu`) are not the library's.
//!
//! - `cargo run --release -p gmueller-validation --bin wave_tracer`: the reference scalar
//!   tracer (brute-force Kirchhoff phase-screen scattering against the kernel; `--energy`;
//!   see `src/bin/wave_tracer/main.rs`). The polarized path tracer is the library's example
//!   `examples/path_tracer/`.
//! - `cargo run --release -p gmueller-validation --bin accuracy`: the speed-versus-accuracy
//!   harness (see `src/bin/accuracy/main.rs`).
//! - `src/tests/tracer.rs`: a reduced, fixed-seed version of the tracer's comparison (unit
//!   tests of this library, part of `cargo test --workspace --tests`).
//! - `src/tests/volume_tracer.rs`: the same for the tracer's volumetric configurations.
//! - `peers/`: the scripts that measure the peer libraries and regenerate the library's
//!   `tests/data/peer_values.json` (not part of CI).
//!
//! This library holds what the tracer program and the tracer test share: the brute force
//! ([`brute`], no gmueller code) and the kernel's prediction for the same scene
//! ([`kernel_side`]). Volumes likewise: the 3-D first-Born vector brute force
//! ([`brute_volume`]), the n = 3 kernel's prediction ([`kernel_side_volume`]) and the
//! configurations with their comparison ([`volume_cases`]).

pub mod brute;
pub mod brute_volume;
pub mod kernel_side;
pub mod kernel_side_volume;
pub mod volume_cases;

#[cfg(test)]
mod tests;

use std::path::PathBuf;

/// The workspace's `target/` directory (cargo's default build directory), where the programs
/// write their tables and plots (`target/wave_tracer/`, `target/accuracy/`) wherever they
/// are started from.
#[must_use]
pub fn target_dir() -> PathBuf {
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest
        .parent()
        .expect("validation/ sits inside the workspace")
        .join("target")
}
