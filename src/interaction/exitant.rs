//! The exitant packet: the light leaving an interaction as a new canonical wave packet.
//!
//! # The shape-matrix update (the rule implemented, and where it is an approximation)
//! The incident coherence of channel α, restricted to the surface, has the covariance
//! `Σ_α = Ξ_α⁻¹` in tangent coordinates ([`super::coherence::surface_inverse_coherence`]). Seen
//! from the exit direction r̂, a surface separation ξ appears as its projection on the exit
//! transverse plane, `ξ⊥ = P ξ` with `P_ij = e_i · t̂_j` (e = the exit s/p frame's x̂, ŷ), so the
//! geometric image of the footprint is
//! ```text
//! Θ_geo = P Σ_α Pᵀ,        |Θ_geo| = cos²θ_o |Σ_α|
//! Θ′_α  = U Θ_α Uᵀ  with det U = 1:   Θ′_α = Θ_geo · (|Θ_α| / |Θ_geo|)^{1/2}
//! ```
//! i.e. the coherence **area is conserved** (the paper's rule) and only the eccentricity and
//! orientation are taken from the projection. In the specular direction of a packet with
//! unbounded longitudinal coherence the projection itself conserves the area and the rule is
//! exact (a mirror image of the incident shape); off-specular the pure projection would scale
//! the area by `cos θ_o / cos θ_i`, and the rule is an approximation — the kernel does not
//! predict the scattered light's coherence (S2.20 discards it, see the seed's last paragraph).
//!
//! **Transmission.** The footprint on the surface is shared by the incident and the refracted
//! light (the field is continuous across the interface), so the transmitted shape is the pure
//! projection, `Θ′_α = Θ_geo`: at Snell's direction it is exact (the widths in the plane of
//! incidence scale by `cos θ_t/cos θ_i`, the others are unchanged, and the far-field width of
//! the kernel's coherent transmitted lobe is `1/(η k w′)` for the projected width `w′`), and
//! off Snell's direction it is the same approximation as in reflection. The packet's wavenumber
//! becomes `η k` (wavelength `λ/η`) in the new medium.
//!
//! The exitant packet carries **one** shape matrix, the image of `Θ_½`: a pBSDF mixes the x
//! and y channels, and the per-channel shapes of the result are sums of Gaussians that the
//! canonical packet cannot hold. One shape keeps the result realizable for every Stokes vector.

use nalgebra::Matrix2;

use super::section::surface_inverse_coherence;
use super::{Geometry, Side};
use crate::error::Error;
use crate::numerics::{det2, pow2_scale};
use crate::packet::{Channel, CoherenceShape, WavePacket};
use crate::real::Real;
use crate::stokes::Stokes;

/// The updated shape of the light leaving along `g.exit`, in the exit s/p frame (module docs):
/// `Θ′ = U Θ_½ Uᵀ` (det U = 1) in reflection, the projection `Θ_geo` in transmission.
///
/// # Errors
/// [`Error::NotPositiveDefinite`] (or another shape error) when the section of the incident
/// coherence by the surface is numerically singular (extreme anisotropy or grazing angles).
pub fn exitant_shape<T: Real>(
    packet: &WavePacket<T>,
    g: &Geometry<T>,
) -> Result<CoherenceShape<T>, Error> {
    let xi = surface_inverse_coherence(packet, Channel::Half, &g.surface).ok_or(
        Error::NotPositiveDefinite {
            what: "section of the incident coherence by the surface",
            min_eigenvalue: 0.0,
        },
    )?;
    // Σ = Ξ⁻¹ = L⁻ᵀ L⁻¹ from Ξ's Cholesky factor L, so Θ_geo = P Σ Pᵀ = G Gᵀ with G = P L⁻ᵀ.
    let l = xi.cholesky_factor();
    let li = Matrix2::new(
        l[(0, 0)].recip(),
        T::zero(),
        -l[(1, 0)] / (l[(0, 0)] * l[(1, 1)]),
        l[(1, 1)].recip(),
    );
    let (ex, ey) = (g.exit_sp.x(), g.exit_sp.y());
    let (t1, t2) = (g.surface.x(), g.surface.y());
    let p = Matrix2::new(ex.dot(&t1), ex.dot(&t2), ey.dot(&t1), ey.dot(&t2));
    let gm = p * li.transpose();
    let geo = gm * gm.transpose();
    // |Θ_geo| = (det P)² |Σ| = cos²θ_o / |Ξ| (det P = (x̂_e × ŷ_e)·n̂ = r̂·n̂), so the
    // area-conserving scale (|Θ_½|/|Θ_geo|)^{1/2} is (|Θ_½| |Ξ|)^{1/2}/cos θ_o, formed from
    // logarithms rather than from the cancelling 2×2 determinants of `geo` and `Θ_½`.
    if g.side() == Side::Transmission {
        // The shared footprint, projected (module docs).
        return CoherenceShape::new(geo);
    }
    let theta = packet.shape(Channel::Half);
    let s = pow2_scale(theta.amax());
    let ln_det_theta = det2(&(theta / s)).ln() + T::lit(2.0) * s.ln();
    let scale = (T::lit(0.5) * (ln_det_theta + xi.log_det())).exp() / g.cos_o;
    CoherenceShape::new(geo * scale)
}

/// The exitant packet carrying `stokes` (e.g. a kernel [`super::polarization::Response`]'s total, a
/// Stokes radiance in the exit s/p frame) along `g.exit`, with the shape of [`exitant_shape`], the
/// exit s/p frame, the wavelength in the exit medium (`λ` in reflection, `λ/η` in transmission) and
/// longitudinal coherence unbounded.
///
/// # Errors
/// As [`exitant_shape`].
pub fn exitant_packet<T: Real>(
    packet: &WavePacket<T>,
    g: &Geometry<T>,
    stokes: Stokes<T>,
) -> Result<WavePacket<T>, Error> {
    let shape = exitant_shape(packet, g)?;
    WavePacket::from_stokes(stokes, shape, g.exit_sp, packet.wavelength() / g.eta)
}
