//! The scalar phase-screen (Kirchhoff) scatterer.

use super::{Geometry, Pbsdf, Side};
use crate::error::Error;
use crate::mueller::Mueller;
use crate::real::Real;

/// A scalar phase-screen (Kirchhoff) scatterer: a height field `z(x)` on a reflector of
/// amplitude reflectance `r` imprints the phase `v z(x)` (`v` the geometry's
/// [`Geometry::phase_factor`], `k (cos θ_i + cos θ_o)` in reflection), so the
/// first-order scattered field is `i v z(x) r` times the incident field and
/// ```text
/// reflection:    M = |r|² v² I₄          (polarization-preserving)
/// transmission:  M = τ v² I₄,   v = k (cos θ_i − η cos θ_o),   τ = η |t|²
/// ```
/// In transmission the screen sits on an interface that passes the field amplitude `t` into a
/// medium of relative index `η`: `τ = η |t|²` is the `M₀₀` of the transmitted specular beam in the
/// kernel's convention (see [`super::FresnelInterface`]), so that the smooth screen transmits the
/// power fraction `τ cos θ_t/cos θ_i`. The brute-force model of `wave_tracer` (the field on the
/// mean plane equals the incident field times `e^{−i v z}`, `t = 1`) has `τ = η`.
/// This is the model of the reference wave-optics tracer (`wave_tracer`); with the kernel's roughness attenuation it
/// is the first term of the Beckmann–Kirchhoff series, and with the roughness level
/// [`crate::interaction::roughness::KirchhoffSeries`] the whole series.
///
/// # Energy: not conserved near grazing incidence (a limit of the model)
/// On a lossless screen (`|r|² = 1`, mirror specular part) the plane-wave reflected fraction is
/// ```text
/// T = α_s + S,   α_s = exp(−(2kσ cos θ_i)²)                       (Debye–Waller, specular)
/// S = 1/cos θ_i ∫ cos²θ_o/λ² · α(v) v² · 2π p(h_t) dω               (first-order scattered)
///   = (1 − α_s) ρ,      T − 1 = (ρ − 1)(1 − α_s) ≈ (ρ − 1)(2kσ cos θ_i)²
/// ```
/// with ρ (Gaussian PSD, kσ = 0.1; `tests/interaction/energy.rs`, `energy_at_grazing_incidence`,
/// where the kernel's total equals this integral, computed independently, to 2e-12):
/// ```text
/// θ_i        0°     45°    60°    70°    75°    80°    85°
/// ℓ = 2λ   0.968  0.968  0.970  1.126  1.508  2.917  13.96
/// ℓ = 10λ  0.980  0.989  0.994  0.997  1.005  1.116  2.592
/// ```
/// (ρ falls slowly with kσ: 1.46 at 75°, 13.7 at 85° for ℓ = 2λ, kσ = 0.3). So at ℓ = 2λ the
/// screen reflects `T = 1.0052` at `θ_i = 75°`, kσ = 0.2 and `T = 1.0156` at 85°, inside the
/// first-order range `kσ (cos θ_i + 1) < 0.5`; at `θ_i ≤ 45°` it stays ≤ 1.
///
/// Why: the Debye–Waller factor takes `1 − α_s ≈ (v_s σ)²`, `v_s = 2k cos θ_i`, out of the
/// specular beam, while the first-order power scattered into the PSD component `p(h_t)` carries
/// `(cos θ_o/cos θ_i)(v/v_s)² = c (1 + c)²/4`, `c = cos θ_o/cos θ_i` — the far-field obliquity
/// (`cos²θ_o/λ²` over `dω = d²h_t/(k² cos θ_o)`, per `cos θ_i` of irradiance on the surface)
/// times the phase factor `v² = k² (cos θ_i + cos θ_o)²` — and nothing for evanescent `h_t`. The
/// two balance only where `c ≈ 1` across the PSD lobe, i.e. `kℓ cos²θ_i ≫ 1` (the lobe's width
/// `~1/(kℓ)` in `r̂_t` changes `c` by `~sin θ_i/(kℓ cos²θ_i)`). Near grazing the lobe reaches
/// from the horizon (`c = 0`, beyond it evanescent and lost) to `c` of several toward the
/// normal, and the cubic weight wins (`ρ > 1`); away from grazing most of the lobe has `c < 1`
/// (at normal incidence all of it) and `ρ < 1`.
///
/// The brute-force reference (the `wave_tracer` program of `validation/`, `--energy`), which
/// builds the same model from its definition with all orders of `e^{v²R}`, measures the same
/// excess: a coherent Gaussian beam on a lossless Gaussian surface (ℓ = 2λ, 128 realizations),
/// normalised by what a mirror reflects of the same beam, reflects 1.005480 ± 0.000017 at 75°, kσ = 0.2 (the model's
/// analytic total for that beam: 1.005474) and 1.015817 ± 0.000013 at 85° (1.015827).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseScreen<T: Real> {
    reflectance: T,
    transmission: T,
}

impl<T: Real> PhaseScreen<T> {
    /// A phase screen on an opaque reflector of power reflectance `|r|²` in `[0, 1]` (nothing
    /// is transmitted).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `0 ≤ |r|² ≤ 1`.
    pub fn new(reflectance: T) -> Result<Self, Error> {
        Self::interface(reflectance, T::zero())
    }

    /// A phase screen on an interface that reflects `|r|²` (in `[0, 1]`) and transmits with the
    /// factor `τ = η |t|²` (finite, ≥ 0; see the type docs).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `0 ≤ |r|² ≤ 1` and `τ ≥ 0` is finite.
    pub fn interface(reflectance: T, transmission: T) -> Result<Self, Error> {
        if !(reflectance >= T::zero() && reflectance <= T::one()) {
            return Err(Error::OutOfRange {
                what: "power reflectance",
                value: reflectance.to_f64(),
                expected: "[0, 1]",
            });
        }
        if !(transmission >= T::zero() && transmission.is_finite()) {
            return Err(Error::OutOfRange {
                what: "transmission factor τ = η|t|²",
                value: transmission.to_f64(),
                expected: "finite and ≥ 0",
            });
        }
        Ok(Self {
            reflectance,
            transmission,
        })
    }
}

impl<T: Real> Pbsdf<T> for PhaseScreen<T> {
    #[inline]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        Mueller(nalgebra::Matrix4::identity() * self.m00(g))
    }
    #[inline]
    fn m00(&self, g: &Geometry<T>) -> T {
        let v = g.phase_factor();
        let f = match g.side() {
            Side::Reflection => self.reflectance,
            Side::Transmission => self.transmission,
        };
        f * v * v
    }
}
