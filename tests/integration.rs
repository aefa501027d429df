//! The integration tests, built as one test binary (`[[test]] integration` in `Cargo.toml`;
//! `autotests = false`). The folders of `tests/` mirror those of `src/`: the tests of
//! `src/medium/` are in `tests/medium/` (module `medium`, its files listed in
//! `tests/medium/mod.rs`), those of `src/interaction/roughness/` in
//! `tests/interaction/roughness/`; tests of a top-level source file (`src/frame.rs`) and
//! crate-wide ones (`allocation`, `architecture`, `bad_input`, `extremes`, `side_invariance`,
//! `verification_table`) are files at the top (`tests/architecture.rs` checks that every folder
//! here names a folder of `src/`).
//!
//! One binary instead of one per file: the kernel's generic code is instantiated and optimised
//! once rather than in each of 34 binaries (as 34 binaries the test build took 16 min on the CI
//! machine). Run one file's or one folder's tests with a filter on its module path, e.g.
//! `cargo test --test integration medium::f32::` (one file) or `medium::` (the folder).
//! The counting global allocator of `allocation` serves the whole binary; it counts per thread,
//! so the other tests running concurrently do not disturb its counts.

mod common;

mod allocation;
mod architecture;
mod bad_input;
mod bsdf;
mod extremes;
mod frame;
mod fresnel;
mod gaussian;
mod interaction;
mod jones;
mod matter;
mod medium;
mod mueller;
mod packet;
mod propagation;
mod psd;
mod side_invariance;
mod spectral;
mod stack;
mod stokes;
mod verification_table;
mod verify;
