//! The stages of the partially coherent lobe batch (`channels`, `specular`) against their
//! scalar twins at every back-end.
