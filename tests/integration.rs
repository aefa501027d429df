//! The integration tests, one module per file of `tests/`, built as one test binary
//! (`[[test]] integration` in `Cargo.toml`; `autotests = false`).
//!
//! One binary instead of one per file: the kernel's generic code is instantiated and optimised
//! once rather than in each of 34 binaries (as 34 binaries the test build took 16 min on the CI
//! machine). Run one file's tests with a filter on its module path, e.g.
//! `cargo test --test integration extremes::`. The counting global allocator of
//! `allocation` serves the whole binary; it counts per thread, so the other tests running
//! concurrently do not disturb its counts.

mod common;

mod allocation;
mod architecture;
mod bad_input;
mod bsdf_bundle;
mod bsdf_eval;
mod bsdf_extremes;
mod bsdf_f32;
mod bsdf_furnace;
mod bsdf_horizon;
mod bsdf_material;
mod bsdf_path;
mod bsdf_reciprocity;
mod bsdf_rough;
mod bsdf_sampling;
mod extremes;
mod extremes_f32;
mod extremes_sampling;
mod frame;
mod fresnel;
mod gaussian;
mod interaction_batch;
mod interaction_channels;
mod interaction_energy;
mod interaction_exitant;
mod interaction_laws;
mod interaction_prepared;
mod interaction_reference;
mod interaction_s2_10;
mod interaction_transmission;
mod jones;
mod lobe_batch;
mod matter;
mod medium;
mod medium_conventions;
mod medium_extremes;
mod medium_f32;
mod medium_limits;
mod medium_paraxial;
mod medium_sampling;
mod medium_spectrum;
mod mueller;
mod mueller_batch;
mod packet;
mod propagation;
mod psd;
mod psd_kcorrelation;
mod psd_power_law;
mod psd_validation;
mod roughness_limits;
mod roughness_quadrature;
mod roughness_series;
mod roughness_tangent_plane;
mod sampling;
mod side_invariance;
mod spectral;
mod stack;
mod stokes;
mod verification_table;
mod verify_kit;
mod verify_oracles;
mod verify_strategies;
