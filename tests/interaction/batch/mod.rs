//! Mirrors `src/interaction/batch/`: the tests of `interaction::batch`.

mod lobes;
mod pairs;
mod plane_wave;
mod series;
