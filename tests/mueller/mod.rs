//! Mirrors `src/mueller/` and `src/mueller.rs`: `batch` tests `src/mueller/batch.rs`, `matrix`
//! the single-matrix module `src/mueller.rs`.

mod batch;
mod matrix;
