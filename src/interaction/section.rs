//! The section of a packet's coherence by the surface: the 2-D inverse coherence `Ξ_α` of
//! S2.18 restricted to the tangent plane, built from its Cholesky factor.

use nalgebra::{Matrix2, Vector2, Vector3};

use crate::frame::Frame;
use crate::gaussian::Gaussian;
use crate::packet::{Channel, WavePacket};
use crate::real::Real;

/// The 2-D inverse coherence `Ξ_α` of a packet channel on a surface (a covariance in `h_t`
/// space, rad²/length²): the section of `Q Θ_α⁻¹ Qᵀ` by the tangent plane (S2.18).
///
/// # Formula
/// ```text
/// Ξ_α = Aᵀ Θ⊥_α⁻¹ A + σ_zz⁻² b bᵀ = Fᵀ F,   F = [ L⁻¹ A ; σ_zz⁻¹ bᵀ ]  (3×2),   Θ⊥_α = L Lᵀ
/// A_ij = e_i · t̂_j (e = x̂, ŷ),   b_j = k̂ · t̂_j
/// ```
/// The Cholesky factor of `Ξ_α` is built from `F` without ever forming `Ξ_α`:
/// ```text
/// ℓ₁₁ = |F₁|,   ℓ₂₁ = F₁·F₂ / ℓ₁₁,   ℓ₂₂ = √|Ξ_α| / ℓ₁₁          (F_j the columns of F)
/// |Ξ_α| = Σ_{i<j} m_ij²   (Cauchy–Binet over the 2×2 minors of F's rows)
/// minors of (A₁, A₂, b): (x̂×ŷ)·n̂ = k̂·n̂ = −cos θ_i,  (x̂×k̂)·n̂ = −ŷ·n̂,  (ŷ×k̂)·n̂ = x̂·n̂
/// ```
/// (`(u·t̂₁)(v·t̂₂) − (u·t̂₂)(v·t̂₁) = (u×v)·n̂`). Why: at grazing incidence the section's small
/// eigenvalue is `∝ cos²θ_i` (the footprint stretched by `1/cos θ_i`), and forming the matrix
/// `AᵀΘ⁻¹A` first recovers it only as a difference of O(1) entries: in `f32` at 89.99° it lost
/// every digit once the plane of incidence was turned away from t̂₁ (φ ≠ 0), and the section
/// was "not positive definite". From the minors, `|Ξ_α|` is a sum of squares of products that
/// are each accurate to a few ulps, so the result no longer depends on the azimuth.
///
/// `None` only when the section over- or underflows the type (inputs far outside the tested
/// ranges, or `cos θ_i = 0`); the kernel then falls back to the plane-wave limit.
#[must_use]
pub fn surface_inverse_coherence<T: Real>(
    packet: &WavePacket<T>,
    channel: Channel,
    surface: &Frame<T>,
) -> Option<Gaussian<T, 2>> {
    let f = packet.frame();
    let (x, y, k) = (f.x(), f.y(), f.k());
    let (t1, t2, n) = (surface.x(), surface.y(), surface.k());
    let li = packet.shape_inverse_cholesky(channel)?;
    let (a, c, d) = (li[(0, 0)], li[(1, 0)], li[(1, 1)]);
    let rz = packet.inverse_longitudinal_variance().sqrt();
    // Rows of F: f1 = a A₁, f2 = c A₁ + d A₂, f3 = σ_zz⁻¹ b.
    let a1 = Vector2::new(x.dot(&t1), x.dot(&t2));
    let a2 = Vector2::new(y.dot(&t1), y.dot(&t2));
    let bb = Vector2::new(k.dot(&t1), k.dot(&t2));
    let f1 = a1 * a;
    let f2 = a1 * c + a2 * d;
    let f3 = bb * rz;
    let col1 = Vector3::new(f1[0], f2[0], f3[0]);
    let col2 = Vector3::new(f1[1], f2[1], f3[1]);
    // Minors of F's rows from the frames (exact identities, no cancellation).
    let (xn, yn) = (x.dot(&n), y.dot(&n));
    let m12 = a * d * k.dot(&n);
    let m13 = -a * rz * yn;
    let m23 = rz * (d * xn - c * yn);
    let l11 = col1.norm();
    let det = m12 * m12 + m13 * m13 + m23 * m23;
    let l21 = col1.dot(&col2) / l11;
    let l22 = det.sqrt() / l11;
    Gaussian::from_cholesky(Matrix2::new(l11, T::zero(), l21, l22))
}
