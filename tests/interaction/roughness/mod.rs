//! Mirrors `src/interaction/roughness/`: the tests of `interaction::roughness`.

mod limits;
mod quadrature;
mod series;
