//! Mirrors `src/verify/`: the tests of `verify`.

mod kit;
mod oracles;
mod strategies;
