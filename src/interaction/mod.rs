//! The light–matter interaction kernel of S2.20: a wave packet meets rough matter.
//!
//! This page holds what a renderer names daily: the [`Kernel`], the [`Geometry`] of an
//! interaction and its [`Side`], the per-packet [`PreparedPacket`], the materials
//! ([`RoughSurface`] and the [`Surface`] trait, [`RoughDielectric`], [`RoughConductor`], their
//! smooth and Kirchhoff forms), the level markers of `Kernel::<Pol, Coh>` ([`Full`],
//! [`OneShape`], [`Intensity`]; [`PlaneWave`], [`Partial`], [`Incoherent`]) and the run-time
//! selectors [`Level`] and [`Roughness`]. The markers and the selectors are re-exports: each is
//! documented in its module. The rest is grouped by concept:
//! - [`pbsdf`]: the polarimetric BSDFs `M` (S2.19), the [`Pbsdf`] trait and [`PbsdfForm`].
//! - [`coherence`]: the coherence levels, their traits ([`CoherenceModel`],
//!   [`CoherenceWeights`]), the coherence terms of S2.17 and the section `Ξ_α`.
//! - [`polarization`]: the polarization levels, their outputs ([`Response`],
//!   [`IntensityResponse`], [`MuellerResponse`]) and the [`Throughput`] trait.
//! - [`roughness`]: the roughness levels (first order, the Kirchhoff series and quadrature, the
//!   geometric limit), their traits and the Debye–Waller attenuation.
//! - [`level`]: the run-time choice of a level and its visitors ([`LevelVisitor`]).
//! - [`exitant`]: the packet that leaves an interaction.
//! - [`sampling`]: importance sampling of the scattered lobe; [`batch`]: the SIMD batch path.
//!
//! # Formula (surface form, n = 2, constants decided by the tests; see the crate Errata)
//! ```text
//! L_o = (cos θ_o / λ_t²) · α · [ M_spec T Σ_α K^spec_α S_α  +  M_scat T Σ_α K_α S_α ]
//!
//! K_α      = |Σ_α|^{1/2} ∫ p(q) g^{Ξ_α}(h_t − q) d²q  = 2π |Σ_α|^{1/2} (p * g^{Ξ_α})(h_t)
//! K^spec_α = 2π |Σ_α|^{1/2} g^{Ξ_α}(h_t)               (the same with p = 2π δ: a smooth mean surface)
//! Ξ_α      = T_tᵀ Q Θ_α⁻¹ Qᵀ T_t,  Σ_α = Ξ_α⁻¹            (S2.18 restricted to the tangent plane)
//! α        = exp(−(v σ)²)                                  (Debye–Waller roughness attenuation)
//! S_x = S_x (1, 1, 0, 0),  S_y = S_y (1, −1, 0, 0),  S_½ = (0, 0, S2, S3)          (S2.16)
//! ```
//! with `h = k(ŝ + η r̂)` (ŝ toward the source) and `h_t` its tangential part, `v = h·n̂` its
//! normal part (the phase factor: `k (cos θ_i + cos θ_o)` in reflection,
//! `k (cos θ_i − η cos θ_o)` in transmission), `Q = [x̂ ŷ k̂]` the
//! packet frame (packet → world), `T_t = [t̂₁ t̂₂]` the surface tangents, `p` the PSD of the
//! height field (unitary transform, [`crate::psd`]) and `σ² = R(0)` its variance, `T` the
//! rotation (S2.4) from the packet frame to the incident s/p frame, `M` the pBSDFs (S2.19) from
//! the incident to the exit s/p frame. The output is a classical Stokes radiance in the exit
//! s/p frame ([`Geometry::exit_sp`]) per unit incident irradiance measured across the beam.
//!
//! **Sides.** In reflection `η = 1` and `λ_t = λ`. In transmission through an interface
//! ([`Geometry::at_interface`], [`RoughDielectric`]) `k` and `λ` are the packet's, in the
//! medium of incidence, `η = n_t/n_i` and `λ_t = λ/η` is the wavelength in the exit medium: the
//! output is radiance in the exit medium, whose `1/λ_t² = η²/λ²` carries the `n²` law of
//! radiance across the interface. The section `Ξ_α` is the same for both sides (the footprint
//! on the surface is shared); the specular lobe sits at Snell's direction, where `h_t = 0`, and
//! its width in direction space is `|Ξ|`-wide in `h_t = η k r̂_t + k ŝ_t`, i.e. `1/η` times the
//! reflected one. Radiometry: the kernel returns `f · cos θ_i` per unit beam irradiance, so the
//! BSDF is `f = L_o/(S0 cos θ_i)`; in the plane-wave limit the transmitted part obeys the
//! generalized reciprocity `f_t(i→o)/n_o² = f_t(o→i)/n_i²` (`tests/interaction/transmission.rs`).
//!
//! `Ξ_α` is the 2-D *section* of the 3-D inverse coherence (the packet's coherence function
//! evaluated at separations that lie in the surface), not the marginal: the kernel needs the
//! two-point field at pairs of points *on* the surface. For oblique incidence it stretches
//! the coherence footprint by `1/cos θ_i` in the plane of incidence.
//!
//! # Limits
//! - **Plane wave** (coherence area → ∞): `|Σ|^{1/2} g^{Ξ} → 2π δ`, so `K → 2π p(h_t)` and
//!   the specular lobe becomes a Dirac delta; with [`RayleighRice`] this is the classical
//!   Rayleigh–Rice BRDF (and BTDF) — what a renderer without coherence computes.
//! - **Incoherent** (coherence width ≪ correlation length): the Gaussian is much wider than `p`,
//!   `K → |Σ|^{1/2} g^{Ξ}(h_t) ∫p`: the lobe is set by the coherence alone.
//!
//! # Model levels (types, monomorphised)
//! - Polarization ([`PolarizationModel`]): [`Intensity`] (S0 only, `M₀₀`; returns
//!   [`IntensityResponse`]) · [`OneShape`] (Stokes, `Θ_½` for every channel) · [`Full`]
//!   (`Θ_x`, `Θ_y`, `Θ_½`; on a single-shape packet it takes the `OneShape` path). Both Stokes
//!   levels return [`Response`].
//! - Coherence ([`CoherenceModel`]): [`PlaneWave`] · [`Partial`]`<B>` · [`Incoherent`]; only
//!   `Partial` blurs the PSD, with any [`BlurMethod`] `B` (closed form by default, mixture
//!   fit, Gauss–Hermite, adaptive).
//! - Roughness ([`RoughnessModel`], the kernel's third type, [`FirstOrder`] by default): first
//!   order in the heights (valid while `vσ ≲ 0.3`) · [`KirchhoffSeries`] (the Kirchhoff
//!   phase-screen series `Σ_n e^{−g} gⁿ/n! F{ρⁿ}`, every `vσ`, to a tolerance) · [`Geometric`]
//!   (its `vσ ≫ 1` limit, the slope distribution) · [`KirchhoffQuadrature`] (the same phase
//!   screen by quadrature, for PSDs without closed-form powers). With [`TangentPlane`] as the scattering
//!   pBSDF the series carries the Kirchhoff polarization (the Fresnel matrix of the specular
//!   facet); see [`KirchhoffSeries`] for the formula and the truncation.
//! - Precision: `T = f32` or `f64`.
//! - Run-time choice: [`Level`] (one of the nine, [`Level::dispatch`], [`Level::evaluate`];
//!   first order).
//!
//! # Layout (one concept per file, each importing only those above it)
//! `geometry` (the directions and the interface's side) → `pbsdf/` (one file per pBSDF) →
//! `material` (the pair `(p, M)`) → `section` (`Ξ_α`) → `attenuation` (Debye–Waller) →
//! `coherence` (the coherence models and terms) → `roughness` (first order, the Kirchhoff
//! series, its geometric limit) → `prepared` (the per-packet part) →
//! `polarization` (the polarization models: what a level computes and returns) → `kernel` →
//! `level` (run-time choice) → `exitant`, `sampling`, `batch`.
//!
//! # Numerics (what makes every output a valid Stokes vector)
//! - **Log-space weights.** Every channel weight is computed as a logarithm
//!   ([`CoherenceWeights::log_scatter_weight`], [`BlurMethod::log_normalized_blur`],
//!   [`Psd::log_value`]) and combined with `ln S0`, `ln(cos θ_o/λ²)` and `ln α` before anything
//!   is exponentiated; the 4×4 products run on numbers of order one, and `S0 e^{…}` is applied
//!   once at the end. A far tail of a bright packet (weight ~1e-47 in `f32`, `S0 = 1e25`) is
//!   therefore not lost, and a result in the subnormal range keeps its degree of polarization
//!   (the exponent then absorbs `u₀` too, so every entry rounds once). A result beyond the
//!   largest number of the type is `±∞` (never NaN; entries that are 0 stay 0).
//! - **The [`Full`] level's channel mix.** For a realizable packet the exact weights satisfy
//!   `K_½² |μ|² ≤ K_x K_y` (Cauchy–Schwarz over the positive semidefinite spectral matrix, see
//!   [`crate::packet`]); the kernel caps `K_½` at that bound, which makes the effective Stokes
//!   vector valid by construction. Where computed weights break the inequality — nearly
//!   proportional shapes rounded separately in `f32`, per-channel quadrature errors of
//!   [`crate::psd::GaussHermite`] — the cap moves `K_½` by less than their own error.
//! - **Accurate sections.** `Ξ_α` is built from its Cholesky factor by Cauchy–Binet minors
//!   ([`surface_inverse_coherence`]), the blur's `Λ⁻¹ + Ξ_α` from the two factors, and the 2×2
//!   determinants of the shapes exactly in `f32` ([`Real::diff_of_products`], powers-of-two
//!   scaling): grazing incidence does not depend on the azimuth of the plane of incidence, and
//!   the `f32` sections of 10⁶-anisotropic shapes agree with `f64` to ~1e-8.
//!
//! Tested in `tests/extremes.rs` and `docs/numerical.md` (the crate docs, "Numerical
//! behaviour"), against independent oracles in `tests/interaction/polarization/channels.rs`,
//! `tests/interaction/s2_10.rs` and `tests/interaction/reference.rs`.
//!
//! # Cost
//! A call splits into per-packet work — the sections `Ξ_α` (one 2×2 Cholesky each: three at
//! [`Full`], one below, none for [`PlaneWave`]) and the rotation `T` to the incident s/p frame —
//! and per-exit work: per channel one blur and one specular-lobe exponential, the Debye–Waller
//! factor, and the two pBSDFs (the specular one skipped where its weight underflows to 0).
//! [`Kernel::evaluate`] does both; for one packet and many exit directions (a lobe, a grid, a
//! light sample and a BSDF sample) [`Kernel::prepare`] the packet once and call
//! [`Kernel::evaluate_prepared`] per direction: the results are bit for bit the same. Measured
//! costs per level are in the repository's `VALIDATION.md` ("Accuracy and speed") and `benches/kernel.rs`.
//!
//! [`RayleighRice`]: pbsdf::RayleighRice
//! [`Pbsdf`]: pbsdf::Pbsdf
//! [`PbsdfForm`]: pbsdf::PbsdfForm
//! [`TangentPlane`]: pbsdf::TangentPlane
//! [`CoherenceModel`]: coherence::CoherenceModel
//! [`CoherenceWeights`]: coherence::CoherenceWeights
//! [`CoherenceWeights::log_scatter_weight`]: coherence::CoherenceWeights::log_scatter_weight
//! [`surface_inverse_coherence`]: coherence::surface_inverse_coherence
//! [`PolarizationModel`]: polarization::PolarizationModel
//! [`Response`]: polarization::Response
//! [`IntensityResponse`]: polarization::IntensityResponse
//! [`MuellerResponse`]: polarization::MuellerResponse
//! [`Throughput`]: polarization::Throughput
//! [`RoughnessModel`]: roughness::RoughnessModel
//! [`FirstOrder`]: roughness::FirstOrder
//! [`KirchhoffSeries`]: roughness::KirchhoffSeries
//! [`Geometric`]: roughness::Geometric
//! [`KirchhoffQuadrature`]: roughness::KirchhoffQuadrature
//! [`LevelVisitor`]: level::LevelVisitor

mod attenuation;
pub mod batch;
pub mod coherence;
pub mod exitant;
mod geometry;
mod kernel;
pub mod level;
mod material;
pub mod pbsdf;
pub mod polarization;
mod prepared;
pub mod roughness;
pub mod sampling;
mod section;

// The core a user names daily. The level markers and the run-time selectors live in their
// sub-modules (`polarization`, `coherence`, `level`) and are re-exported here as well, so that
// `Kernel::<Full, Partial>` needs one import; rustdoc lists them under "Re-exports".
pub use coherence::{Incoherent, Partial, PlaneWave};
pub(crate) use geometry::Incidence;
pub use geometry::{Geometry, Side};
pub use kernel::Kernel;
pub use level::{Level, Roughness};
pub use material::{
    KirchhoffConductor, KirchhoffDielectric, RoughConductor, RoughDielectric, RoughSurface,
    SmoothConductor, SmoothDielectric, Surface,
};
pub use polarization::{Full, Intensity, OneShape};
pub use prepared::PreparedPacket;

// The per-packet machinery the random medium (`crate::medium`) shares with the surface kernel.
pub(crate) use polarization::onto_cone;
pub(crate) use prepared::{Plan, flush_to_normal, throughput_scaled, unit_scaled};

#[cfg(doc)]
use crate::psd::{BlurMethod, Psd};
#[cfg(doc)]
use crate::real::Real;
