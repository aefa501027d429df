//! Mirrors `src/spectral/`: the tests of `spectral`.

mod data;
