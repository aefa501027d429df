//! Mirrors `src/matter/`: the tests of `matter`.

mod locally_stationary;
