//! Anisotropic Gaussians, their products, convolutions and Fourier transforms (Lemma S2.1, Corollary S2.2).
