//! The brute force against the kernel, reduced to fixed seeds and seconds (part of the
//! README's test command). They are unit tests of this library, not integration tests under
//! `tests/`, so that `cargo test` does not build the validation binaries (the `accuracy`
//! harness alone took 149 s of a clean test build on a 2-core machine, 2026-12-07): they use only the
//! library.

mod tracer;
mod volume_tracer;
