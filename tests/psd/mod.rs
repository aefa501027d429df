//! Mirrors `src/psd/`: the tests of `psd`.

mod kcorrelation;
mod models;
mod power_law;
mod validation;
