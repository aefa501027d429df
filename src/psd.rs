//! Power spectral densities of random matter, and their blur by Gaussians (S2.14–S2.17).
