//! The BSDF form of each polarization level: the same S2.20 as the Stokes form of the parent
//! module, with the incident Stokes vector left out, so that the result is a throughput
//! ([`super::MuellerResponse`]) per unit incident irradiance.
//!
//! ```text
//! Intensity:  m₀₀ = (cos θ_o/λ_t²) α M₀₀ K                       (K from Θ_½)
//! OneShape:   M   = (cos θ_o/λ_t²) α M_pbsdf T K                  (Θ_½ for every channel)
//! Full:       M   = (cos θ_o/λ_t²) α M_pbsdf T Σ_α K_α P_α        (Θ_x, Θ_y, Θ_½)
//! ```
//! The weights are the Stokes form's own (same logarithms, same linear fast path), so
//! `M S` equals the Stokes form for every `S` up to rounding, wherever the scale is a normal
//! number.

use nalgebra::{Matrix1, Matrix4};

use super::super::coherence::CoherenceWeights;
use super::super::geometry::Geometry;
use super::super::material::Surface;
use super::super::pbsdf::Pbsdf;
use super::super::prepared::{PreparedPacket, flush_to_normal, throughput_scaled};
use super::super::roughness::RoughnessWeights;
use super::response::MuellerResponse;
use super::{Front, front};
use crate::mueller::Mueller;
use crate::psd::Psd;
use crate::real::Real;

/// `ln` of the smallest positive normal number: a BSDF-form part whose scale lies below is 0.
#[inline]
fn ln_min_normal<T: Real>() -> T {
    T::lit(T::MIN_POSITIVE.to_f64().ln())
}

/// `true` when `e^{ln_e}` is below the smallest normal number (NaN counts as dark).
#[inline]
#[expect(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "a NaN exponent must count as dark too"
)]
fn is_dark<T: Real>(ln_e: T) -> bool {
    !(ln_e >= ln_min_normal::<T>())
}

/// The scattered part at the one-weight levels per unit `S0`, `u α K η²/λ²`: the linear weight
/// where it and the scale are normal numbers, the log form otherwise (as the Stokes form).
#[inline]
fn one_weight_scatter<T, P, Pol, Coh, Rough, const R: usize, const C: usize>(
    coherence: &Coh,
    roughness: &Rough,
    psd: &P,
    prepared: &PreparedPacket<T, Pol, Coh>,
    g: &Geometry<T>,
    front: &Front<T>,
    u: impl FnOnce() -> nalgebra::SMatrix<T, R, C>,
) -> nalgebra::SMatrix<T, R, C>
where
    T: Real,
    P: Psd<T, 2>,
    Coh: CoherenceWeights<T, P>,
    Rough: RoughnessWeights<T, P, Coh>,
{
    let xi = super::psd_xi(g, prepared.sections[2].as_ref());
    let (attenuation, ln_front) = front.scatter::<Rough>();
    let (kd, ln_kd) = super::scatter_weight_forms(coherence, roughness, psd, xi.as_ref(), g);
    match prepared.unit_linear_scale(kd, attenuation, g.eta) {
        Some(e) => flush_to_normal(u() * e),
        None => {
            let ld = ln_front
                + ln_kd.unwrap_or_else(|| {
                    roughness.log_scatter_weight(coherence, psd, xi.as_ref(), g)
                });
            if is_dark(ld) {
                nalgebra::SMatrix::zeros()
            } else {
                throughput_scaled(u(), ld)
            }
        }
    }
}

/// The [`super::Intensity`] level's BSDF form: scalars `(cos θ_o/λ_t²) α M₀₀ K`.
#[inline]
pub(super) fn intensity<T, S, Pol, Coh, Rough>(
    coherence: &Coh,
    roughness: &Rough,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    g: &Geometry<T>,
) -> MuellerResponse<T, T>
where
    T: Real,
    S: Surface<T>,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessWeights<T, S::Psd, Coh>,
{
    let material = material.parts();
    let psd = &material.psd;
    let f = front(psd, prepared, g);
    let (attenuation, ln_front) = (f.attenuation, f.ln_front);
    let ls = ln_front + coherence.log_specular_weight(prepared.sections[2].as_ref(), &g.h_t);
    let specular = if is_dark(ls) {
        T::zero()
    } else {
        throughput_scaled(Matrix1::new(material.specular.m00(g) * g.cos_o), ls)[0]
    };
    let scattered = one_weight_scatter(coherence, roughness, psd, prepared, g, &f, || {
        Matrix1::new(material.scatter.m00(g) * g.cos_o)
    })[0];
    MuellerResponse {
        specular,
        scattered,
        attenuation,
        side: g.side,
    }
}

/// The [`super::OneShape`] level's BSDF form (also [`super::Full`] on single-shape packets):
/// `(cos θ_o/λ_t²) α M_pbsdf T K`.
#[inline]
pub(super) fn one_shape<T, S, Pol, Coh, Rough>(
    coherence: &Coh,
    roughness: &Rough,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    g: &Geometry<T>,
) -> MuellerResponse<T, Mueller<T>>
where
    T: Real,
    S: Surface<T>,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessWeights<T, S::Psd, Coh>,
{
    let material = material.parts();
    let psd = &material.psd;
    let f = front(psd, prepared, g);
    let (attenuation, ln_front) = (f.attenuation, f.ln_front);
    let ls = ln_front + coherence.log_specular_weight(prepared.sections[2].as_ref(), &g.h_t);
    let t = prepared.t * g.cos_o;
    let specular = if Coh::USES_SHAPE && !is_dark(ls) {
        throughput_scaled(material.specular.mueller(g).0 * t, ls)
    } else {
        Matrix4::zeros()
    };
    let scattered = one_weight_scatter(coherence, roughness, psd, prepared, g, &f, || {
        material.scatter.mueller(g).0 * t
    });
    MuellerResponse {
        specular: Mueller(specular),
        scattered: Mueller(scattered),
        attenuation,
        side: g.side,
    }
}

/// The [`super::Full`] level's BSDF form on a packet with two shapes:
/// `(cos θ_o/λ_t²) α M_pbsdf T Σ_α K_α P_α` ([`PreparedPacket::channel_matrix`]).
#[inline]
pub(super) fn full<T, S, Pol, Coh, Rough>(
    coherence: &Coh,
    roughness: &Rough,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    g: &Geometry<T>,
) -> MuellerResponse<T, Mueller<T>>
where
    T: Real,
    S: Surface<T>,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessWeights<T, S::Psd, Coh>,
{
    let material = material.parts();
    let psd = &material.psd;
    let f = front(psd, prepared, g);
    let (attenuation, ln_front) = (f.attenuation, f.ln_front);
    let log_weights = |i: usize| {
        let xi = prepared.sections[i].as_ref();
        (
            coherence.log_specular_weight(xi, &g.h_t),
            roughness.log_scatter_weight(coherence, psd, super::psd_xi(g, xi).as_ref(), g),
        )
    };
    let ((xs, xd), (ys, yd), (hs, hd)) = (log_weights(0), log_weights(1), log_weights(2));
    let (spec_d, spec_m) = prepared.channel_matrix(xs, ys, hs);
    let (scat_d, scat_m) = prepared.channel_matrix(xd, yd, hd);
    let (spec_ln, scat_ln) = (ln_front + spec_m, f.scatter::<Rough>().1 + scat_m);
    let specular = part(spec_ln, || material.specular.mueller(g).0, &spec_d, g.cos_o);
    let scattered = part(scat_ln, || material.scatter.mueller(g).0, &scat_d, g.cos_o);
    MuellerResponse {
        specular: Mueller(specular),
        scattered: Mueller(scattered),
        attenuation,
        side: g.side,
    }
}

/// `M_pbsdf · D cos θ_o · e^{ln}` of one Full-level part, 0 where the scale is dark (the pBSDF
/// is then not evaluated).
#[inline]
fn part<T: Real>(
    ln: T,
    pbsdf: impl FnOnce() -> Matrix4<T>,
    d: &Matrix4<T>,
    cos_o: T,
) -> Matrix4<T> {
    if is_dark(ln) {
        Matrix4::zeros()
    } else {
        throughput_scaled(pbsdf() * (d * cos_o), ln)
    }
}
