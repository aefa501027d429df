//! The Kirchhoff tangent-plane scatterer: the Fresnel matrix of the local specular facet.

use super::{Geometry, Pbsdf};
use crate::frame::frame_change_mueller;
use crate::mueller::Mueller;
use crate::real::Real;

/// The Kirchhoff (tangent-plane, physical-optics) scatterer: every point of a rough interface
/// reflects and transmits as its local tangent plane would, with the Mueller matrix of a flat
/// `facet` (e.g. [`super::FresnelReflection`], [`super::FresnelInterface`], or
/// [`super::ConstantMueller`] for an ideal mirror), evaluated at the facet that sends the light
/// from ŝ to r̂ — the one whose normal is the half vector `m ∝ h` — and weighted by the
/// Kirchhoff geometric factor.
///
/// # Formula
/// ```text
/// h = k (ŝ + η r̂),   v = h·n̂,   m = sign(v) h/|h|                      (the specular facet)
/// M = T(F'_o → F_o) · M_facet(ŝ → r̂ at m) · T(F_i → F'_i) · (r̂·h)²/cos²θ_o
/// ```
/// (`F_i`, `F_o` the incident and exit s/p frames of the geometry, `F'_i`, `F'_o` those of the
/// facet, [`Geometry::at_facet`]; 0 where no facet facing the source sends light to r̂.)
///
/// # Derivation, and what the factor is
/// In the Kirchhoff approximation the field on the surface is the incident field times the
/// Fresnel coefficients of the local tangent plane; under stationary phase (the standard
/// physical-optics result, e.g. Ogilvy, *Theory of Wave Scattering from Random Rough Surfaces*,
/// 1991, ch. 4; Tsang, Kong & Ding 2000, §6) the polarization amplitude is that of the facet
/// at the stationary point `m ∝ h`, and what remains is the scalar phase-screen integral
/// `∫ ⟨e^{iv(z₁ − z₂)}⟩ e^{−i h_t·ξ} d²ξ` — the Kirchhoff series of
/// [`super::super::roughness::KirchhoffSeries`], with the phase screen's `v²` replaced by this
/// matrix. The factor `(r̂·h)²/cos²θ_o` is fixed by the series' geometric-optics limit: there the
/// scalar integral becomes `(2π)² P(−h_t/v)/v²`, `P` the slope density, and the kernel's
/// `(cos θ_o/λ_t²)(M/v²)(2π)² P/v²` equals the microfacet BSDF (Walter et al., EGSR 2007, with
/// the shadowing term G = 1) times `cos θ_i`,
/// ```text
/// reflection:    F D/(4 cos θ_o),                              D = P/cos⁴θ_m, |h| = 2k ŝ·m
/// transmission:  η² |ŝ·m||r̂·m| (1 − F) D k²/(cos θ_o |h|²)     (the n² of radiance included)
/// ```
/// exactly when `M₀₀ = M_facet,00 (r̂·h)²/cos²θ_o` (`M_facet,00` is `F` in reflection and
/// `η |t|² = (1 − F)(ŝ·m)/|r̂·m|` in the kernel's transmission convention,
/// [`super::FresnelInterface`]; `P` per unit slope, `θ_m` the facet's tilt). At the specular (mirror or Snell) direction `m = n̂`,
/// `r̂·h = ±v cos θ_o` and the factor is `v²`: the matrix is then the phase screen's
/// `|r|² v²` (or `τ v²`) with the Fresnel polarization, which is also the Rayleigh–Rice
/// factors' limit there — so at first order the two agree near specular, to a measured
/// tolerance (`tests/interaction/roughness/series.rs`).
///
/// # Validity
/// The tangent-plane approximation needs radii of curvature much larger than the wavelength
/// (`ℓ ≫ λ` and `ℓ²/σ ≫ λ` for a Gaussian surface) and ignores shadowing, masking and
/// multiple scattering (small slopes `σ/ℓ`, incidence and exit away from grazing). The
/// stationary-phase polarization is exact in the geometric limit; at first order (`vσ ≪ 1`)
/// it differs from Rayleigh–Rice away from the specular direction by the facet's tilt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TangentPlane<F> {
    facet: F,
}

impl<F> TangentPlane<F> {
    /// The tangent-plane scatterer whose facets have the pBSDF `facet` (a specular pBSDF:
    /// Fresnel reflection, a Fresnel interface, an ideal mirror).
    #[must_use]
    pub fn new(facet: F) -> Self {
        Self { facet }
    }

    /// The facets' pBSDF.
    #[must_use]
    pub fn facet(&self) -> &F {
        &self.facet
    }
}

/// The facet geometry at `m ∝ h` and the factor `(r̂·h)²/cos²θ_o`; `None` where no facet
/// facing the source sends the light to r̂ (and where `v = 0`: a vertical facet).
#[inline]
fn specular_facet<T: Real>(g: &Geometry<T>) -> Option<(Geometry<T>, T)> {
    let h = g.scattering_vector();
    let v = g.phase_factor();
    if v == T::zero() {
        return None;
    }
    let norm = h.norm();
    let m = if v > T::zero() { h / norm } else { -h / norm };
    let facet = g.at_facet(m)?;
    let rh = g.exit().dot(&h);
    let weight = rh * rh / (g.cos_o() * g.cos_o());
    Some((facet, weight))
}

impl<T: Real, F: Pbsdf<T>> Pbsdf<T> for TangentPlane<F> {
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        let Some((facet, weight)) = specular_facet(g) else {
            return Mueller(nalgebra::Matrix4::zeros());
        };
        let into = frame_change_mueller(g.incident_sp(), facet.incident_sp());
        let out = frame_change_mueller(facet.exit_sp(), g.exit_sp());
        Mueller((out.0 * self.facet.mueller(&facet).0 * into.0) * weight)
    }
    /// `M₀₀` (the frame changes leave it unchanged).
    fn m00(&self, g: &Geometry<T>) -> T {
        match specular_facet(g) {
            Some((facet, weight)) => self.facet.m00(&facet) * weight,
            None => T::zero(),
        }
    }
}
