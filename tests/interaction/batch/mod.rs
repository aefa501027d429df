//! Mirrors `src/interaction/batch/`: the tests of `interaction::batch`.

mod lobes;
mod plane_wave;
mod series;
