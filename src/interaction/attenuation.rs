//! The Debye–Waller roughness attenuation of the coherent (specular) part.

use super::geometry::Geometry;
use crate::psd::Psd;
use crate::real::Real;

/// The Debye–Waller roughness attenuation `α = exp(−(v σ)²)`, `σ² = R(0)`, with the phase
/// factor `v` of the interface's geometry ([`Geometry::phase_factor`]: `k (cos θ_i + cos θ_o)`
/// in reflection).
///
/// For a height field `z` the phase imprinted on the light is `v z`, and for Gaussian heights
/// `⟨e^{iv(z₁ − z₂)}⟩ = α e^{v² R(ξ)}`:
/// `α` is the coherent (specular) fraction; its first-order companion `α v² R(ξ)` is the
/// scattered part, so both carry `α` and their sum `α (1 + v²σ²) ≤ 1` conserves energy.
#[must_use]
pub fn roughness_attenuation<T: Real, P: Psd<T, 2>>(psd: &P, g: &Geometry<T>) -> T {
    let v = g.phase_factor();
    (-(v * v) * psd.variance()).exp()
}
