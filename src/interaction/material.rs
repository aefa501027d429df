//! The material of the paper, `(p, M)`: a rough surface's PSD and its two pBSDFs.

/// A rough surface: the PSD of its height field, the pBSDF of its mean (specular) interface
/// and the pBSDF of its first-order scattering — the material `(p, M)` of the paper.
#[derive(Debug, Clone, PartialEq)]
pub struct RoughSurface<P, Sp, Sc> {
    /// The height PSD `p` (unitary transform; `R(0) = σ²` the squared rms height).
    pub psd: P,
    /// The specular pBSDF (e.g. [`super::FresnelReflection`]).
    pub specular: Sp,
    /// The scattering pBSDF (e.g. [`super::RayleighRice`], [`super::PhaseScreen`]).
    pub scatter: Sc,
}
