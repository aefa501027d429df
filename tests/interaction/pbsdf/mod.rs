//! Mirrors `src/interaction/pbsdf/`: the tests of `interaction::pbsdf`.

mod tangent_plane;
