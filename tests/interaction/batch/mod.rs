//! Mirrors `src/interaction/batch/`: the tests of `interaction::batch`.

mod lobes;
pub(crate) mod pairs;
mod plane_wave;
mod series;
