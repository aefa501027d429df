//! Mirrors `src/interaction/polarization/`: the tests of `interaction::polarization`.

mod channels;
