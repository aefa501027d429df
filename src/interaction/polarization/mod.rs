//! The polarization models of the kernel (a model level): what a level computes per packet and
//! per exit direction, and what it returns.
//!
//! ```text
//! Intensity:  L₀ = (cos θ_o/λ_t²) α M₀₀ K S0                    (K from Θ_½; no frames)
//! OneShape:   L  = (cos θ_o/λ_t²) α M T K S                     (Θ_½ for every channel)
//! Full:       L  = (cos θ_o/λ_t²) α M T Σ_α K_α S_α             (Θ_x, Θ_y, Θ_½; S2.20)
//! ```
//! (`λ_t = λ/η` the wavelength in the exit medium: `λ` in reflection.)
//! `Full` on a packet with one shape (`Θ_x = Θ_y`, e.g. every packet from
//! `WavePacket::from_stokes` and `exitant_packet`) has three equal weights and takes the
//! one-weight path of `OneShape`: same result, same cost.
//!
//! Here: the level markers [`Intensity`], [`OneShape`] and [`Full`] (also re-exported at the top
//! of [`super`], for `Kernel::<Pol, Coh>`), their trait ([`PolarizationModel`], with the
//! per-packet work it plans, [`PreparationPlan`]) and values ([`PolarizationLevel`]); the
//! kernel's outputs in Stokes form ([`Response`], [`IntensityResponse`], [`LevelResponse`], all
//! [`KernelOutput`]) and in BSDF form ([`MuellerResponse`], whose lobes are [`Throughput`]s: the
//! trait whose `m00`, `scaled`, `then` … a renderer generic over the level calls).

mod matrix;
mod response;

pub use response::{
    IntensityResponse, KernelOutput, LevelResponse, MuellerResponse, Response, Throughput,
};

use core::fmt::Debug;

use nalgebra::Vector4;

use super::coherence::{CoherenceLevel, CoherenceWeights, ln_two_pi};
use super::geometry::Geometry;
use super::material::Surface;
use super::pbsdf::Pbsdf;
use super::prepared::{Plan, PreparedPacket};
use super::roughness::{RoughnessLevel, RoughnessModel, RoughnessWeights};
use crate::gaussian::Gaussian;
use crate::mueller::Mueller;
use crate::packet::WavePacket;
use crate::psd::{Psd, Shape};
use crate::real::Real;
use crate::stokes::Stokes;

pub(crate) mod sealed {
    pub trait Sealed {}
}

/// The polarization levels, as values (for reports and run-time selection, [`super::Level`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PolarizationLevel {
    /// S0 only.
    Intensity,
    /// Full Stokes, one shape matrix (`Θ_½`) for every channel.
    OneShape,
    /// Full S2.20: `Θ_x`, `Θ_y`, `Θ_½`.
    Full,
}

/// How much of the polarization a kernel keeps (a model level), and how it evaluates S2.20.
///
/// Sealed: the three levels below are the crate's. Their `plan` and `evaluate` are what
/// [`super::Kernel::prepare`] and [`super::Kernel::evaluate_prepared`] run.
pub trait PolarizationModel: sealed::Sealed + Copy + Default + Debug {
    /// Which level.
    const LEVEL: PolarizationLevel;

    /// What the level returns per exit direction.
    type Output<T: Real>: KernelOutput<T>;

    /// The per-packet work the level needs (which sections `Ξ_α`, the rotation `T`, the channel
    /// logarithms of the Full level's channel mix).
    #[must_use]
    fn plan<T: Real>(packet: &WavePacket<T>, uses_shape: bool) -> PreparationPlan;

    /// The level's S2.20 for one exit direction `g` (see the module formula), with the
    /// scattered weights of the roughness level `roughness`.
    #[must_use]
    fn evaluate<T, S, Coh, R>(
        coherence: &Coh,
        roughness: &R,
        material: &S,
        prepared: &PreparedPacket<T, Self, Coh>,
        g: &Geometry<T>,
    ) -> Self::Output<T>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        R: RoughnessWeights<T, S::Psd, Coh>;

    /// What the level's BSDF form holds per lobe: a Mueller matrix at the Stokes levels, a
    /// scalar at the intensity level.
    type Throughput<T: Real>: Throughput<T>;

    /// The level's S2.20 for one exit direction `g` in BSDF form: per unit incident
    /// irradiance, acting on Stokes vectors in the packet's frame ([`MuellerResponse`]).
    #[must_use]
    fn evaluate_mueller<T, S, Coh, R>(
        coherence: &Coh,
        roughness: &R,
        material: &S,
        prepared: &PreparedPacket<T, Self, Coh>,
        g: &Geometry<T>,
    ) -> MuellerResponse<T, Self::Throughput<T>>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        R: RoughnessWeights<T, S::Psd, Coh>;
}

/// The per-packet work a polarization level asks for ([`PolarizationModel::plan`]); opaque.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PreparationPlan(pub(crate) Plan);

/// Intensity only: `L₀ = (cos θ_o/λ²) α M₀₀ K S0` with `K` from `Θ_½`. No frames, no 4×4 products;
/// returns [`IntensityResponse`].
#[doc(alias = "Scalar")]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Intensity;
/// Stokes vectors with one coherence shape, `Θ_½`, for all channels: `L = … M T K S`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OneShape;
/// The full S2.20 with a shape matrix per channel.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Full;

impl sealed::Sealed for Intensity {}
impl sealed::Sealed for OneShape {}
impl sealed::Sealed for Full {}

/// The factors in front of the parts for one exit: `α` (the Debye–Waller factor from the
/// geometry's phase factor), `ln(α/λ_t²)` and `ln(1/λ_t²)` (`λ_t = λ/η` the wavelength in the
/// exit medium: `λ = 2π/k` from the packet, `η` the geometry's relative index, 1 in
/// reflection). The factor `cos θ_o ∈ (0, 1]` multiplies the Stokes vector instead (one
/// logarithm less per exit; it cannot underflow it).
#[derive(Debug, Clone, Copy)]
pub(super) struct Front<T> {
    /// `α`.
    pub(super) attenuation: T,
    /// `ln(α/λ_t²)`: the specular part's, and the first-order scattered part's.
    pub(super) ln_front: T,
    /// `ln(1/λ_t²)`: the scattered part's at the roughness levels whose weights carry `α`.
    pub(super) ln_base: T,
}

impl<T: Real> Front<T> {
    /// The scattered part's attenuation and log front for the roughness level `R`: `(α,
    /// ln(α/λ_t²))`, or `(1, ln(1/λ_t²))` where its weights carry `α`
    /// ([`RoughnessModel::CARRIES_ATTENUATION`]).
    #[inline]
    pub(super) fn scatter<R: RoughnessModel>(&self) -> (T, T) {
        if R::CARRIES_ATTENUATION {
            (T::one(), self.ln_base)
        } else {
            (self.attenuation, self.ln_front)
        }
    }
}

#[inline]
fn front<T: Real, P: Psd<T, 2>, Pol, Coh>(
    psd: &P,
    prepared: &PreparedPacket<T, Pol, Coh>,
    g: &Geometry<T>,
) -> Front<T> {
    let ln_alpha = ln_attenuation(psd.variance(), g);
    let ln_base = prepared.two_ln_k_over_2pi + g.ln_eta_sq;
    Front {
        attenuation: ln_alpha.exp(),
        ln_front: ln_base + ln_alpha,
        ln_base,
    }
}

/// `ln α = −v² σ²`, the Debye–Waller exponent of the geometry's phase factor `v` for a surface of
/// height variance `σ²` (its exponential is every response's `attenuation`).
#[inline]
pub(crate) fn ln_attenuation<T: Real>(variance: T, g: &Geometry<T>) -> T {
    let v = g.phase_factor();
    -(v * v) * variance
}

/// `u` onto the cone of valid Stokes vectors: its polarized part scaled down to `u₀` where
/// rounding left it longer, and 0 where `u₀ ≤ 0`. The exact product of a pBSDF (a physical
/// Mueller matrix) and a valid Stokes vector lies in the cone; near extinction (a strongly
/// polarizing matrix at grazing exit, nearly orthogonal light) its computed `u₀` carries an
/// error of a few `ε M₀₀ S0` that is large *relative to* `u₀`: a metal grating at 89.99° exit
/// gave `|u_pol| = u₀ (1 + 4·10⁻¹⁴)` in f64. The projection moves `u` by no more than that
/// rounding (`tests/bsdf/extremes.rs`).
#[inline]
pub(crate) fn onto_cone<T: Real>(u: Vector4<T>) -> Vector4<T> {
    let u0 = u[0];
    if u0 > T::zero() {
        let inv = u0.recip();
        // 1/u₀ overflows for the smallest subnormal u₀: divide instead (|u_k/u₀| ≲ 1).
        let (a, b, c) = if inv <= T::MAX {
            (u[1] * inv, u[2] * inv, u[3] * inv)
        } else {
            (u[1] / u0, u[2] / u0, u[3] / u0)
        };
        let r2 = a * a + b * b + c * c;
        if r2 > T::one() {
            let f = r2.sqrt().recip();
            return Vector4::new(u0, u[1] * f, u[2] * f, u[3] * f);
        }
        u
    } else if u0 <= T::zero() {
        Vector4::zeros()
    } else {
        u
    }
}

/// The section `Ξ` as a height PSD given in the caller's surface frame sees it: mirrored
/// (`D Ξ D`, `D = diag(1, −1)`) when the light comes from below, where the geometry's oriented
/// frame has t̂₂ negated (with [`Geometry::psd_h`]; the specular weight, which involves no
/// PSD, stays in the oriented frame: it is invariant under mirroring both).
#[inline]
pub(crate) fn psd_xi<T: Real>(
    g: &Geometry<T>,
    xi: Option<&Gaussian<T, 2>>,
) -> Option<Gaussian<T, 2>> {
    xi.map(|x| if g.from_below { x.mirrored_y() } else { *x })
}

/// The scattered weight `K̃` of the one-weight levels in its linear form, with `ln K̃` where
/// computing the linear form already gave it (`None` otherwise: the caller that needs it then
/// asks [`RoughnessWeights::log_scatter_weight`]). `xi` is the section as the PSD sees it
/// ([`psd_xi`]).
///
/// The one case that returns the logarithm is first order, partially coherent, a closed-form
/// blur and a PSD whose form is exactly a Gaussian, with a section: there
/// [`crate::psd::GaussianPsd::normalized_blur_forms`] hands back the logarithm it
/// exponentiated, where the weight is far in the lobe's tail (off a narrow lobe, most of the
/// hemisphere), instead of factoring `Λ⁻¹ + Ξ` a second time. For [`crate::psd::GaussianPsd`]
/// (the crate's one PSD of that form) both values are bit for bit
/// `(roughness.scatter_weight(..), roughness.log_scatter_weight(..))`
/// (`src/interaction/polarization/tests.rs`); another PSD type reporting an exact Gaussian form
/// gets that Gaussian's closed form, equal to its own up to rounding. Every other case is the
/// trait call itself.
#[inline]
pub(crate) fn scatter_weight_forms<T, P, Coh, R>(
    coherence: &Coh,
    roughness: &R,
    psd: &P,
    xi: Option<&Gaussian<T, 2>>,
    g: &Geometry<T>,
) -> (T, Option<T>)
where
    T: Real,
    P: Psd<T, 2>,
    Coh: CoherenceWeights<T, P>,
    R: RoughnessWeights<T, P, Coh>,
{
    if R::LEVEL == RoughnessLevel::FirstOrder
        && Coh::LEVEL == CoherenceLevel::Partial
        && coherence.closed_form_gaussian()
    {
        let form = psd.form();
        if let (Some(xi), true, Shape::Gaussian(gaussian)) = (xi, form.is_exact(), form.shape()) {
            // K = 2π ∫ p 𝒩_Ξ(h_t − ·) and ln K = ln 2π + ln ∫ p 𝒩_Ξ(h_t − ·), as
            // `Partial::scatter_weight` and `Partial::log_scatter_weight` compute them.
            let (v, ln) = gaussian.normalized_blur_forms(xi, &g.psd_h());
            return (T::two_pi() * v, ln.map(|l| ln_two_pi::<T>() + l));
        }
    }
    (roughness.scatter_weight(coherence, psd, xi, g), None)
}

/// The scattered part at the one-weight levels, `u · S0 α K/λ²` (`u · S0 K̃/λ²` at the
/// roughness levels whose weight `K̃` carries `α`): the linear weight (one exponential) where it
/// and the whole scale are safely normal, the log form otherwise.
#[inline]
fn one_weight_scatter<T, P, Pol, Coh, R>(
    coherence: &Coh,
    roughness: &R,
    psd: &P,
    prepared: &PreparedPacket<T, Pol, Coh>,
    g: &Geometry<T>,
    front: &Front<T>,
    u: Vector4<T>,
) -> Vector4<T>
where
    T: Real,
    P: Psd<T, 2>,
    Coh: CoherenceWeights<T, P>,
    R: RoughnessWeights<T, P, Coh>,
{
    let xi = psd_xi(g, prepared.sections[2].as_ref());
    let (attenuation, ln_front) = front.scatter::<R>();
    let (kd, ln_kd) = scatter_weight_forms(coherence, roughness, psd, xi.as_ref(), g);
    match prepared.linear_scale(kd, attenuation, g.eta) {
        Some(e) => crate::interaction::prepared::subnormal_onto_cone(u * e),
        None => {
            let ld = ln_front
                + ln_kd.unwrap_or_else(|| {
                    roughness.log_scatter_weight(coherence, psd, xi.as_ref(), g)
                });
            if prepared.is_dark(ld) {
                Vector4::zeros()
            } else {
                prepared.scaled(u, ld)
            }
        }
    }
}

/// The [`OneShape`] path (also [`Full`] on single-shape packets and without shapes): `M T S K`.
#[inline]
fn one_shape<T, S, Pol, Coh, R>(
    coherence: &Coh,
    roughness: &R,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    g: &Geometry<T>,
) -> Response<T>
where
    T: Real,
    S: Surface<T>,
    Coh: CoherenceWeights<T, S::Psd>,
    R: RoughnessWeights<T, S::Psd, Coh>,
{
    let material = material.parts();
    let psd = &material.psd;
    let f = front(psd, prepared, g);
    let (attenuation, ln_front) = (f.attenuation, f.ln_front);
    let ls = ln_front + coherence.log_specular_weight(prepared.sections[2].as_ref(), &g.h_t);
    let t = prepared.t_stokes * g.cos_o;
    // Off the specular lobe (and always for a plane wave) its weight underflows: skip the
    // specular pBSDF there.
    let specular = if Coh::USES_SHAPE && !prepared.is_dark(ls) {
        prepared.scaled(onto_cone(material.specular.mueller(g).0 * t), ls)
    } else {
        Vector4::zeros()
    };
    let scattered = one_weight_scatter(
        coherence,
        roughness,
        psd,
        prepared,
        g,
        &f,
        onto_cone(material.scatter.mueller(g).0 * t),
    );
    Response {
        specular: Stokes(specular),
        scattered: Stokes(scattered),
        attenuation,
        side: g.side,
    }
}

impl PolarizationModel for Intensity {
    type Throughput<T: Real> = T;

    #[inline]
    fn evaluate_mueller<T, S, Coh, R>(
        coherence: &Coh,
        roughness: &R,
        material: &S,
        prepared: &PreparedPacket<T, Self, Coh>,
        g: &Geometry<T>,
    ) -> MuellerResponse<T, T>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        R: RoughnessWeights<T, S::Psd, Coh>,
    {
        matrix::intensity(coherence, roughness, material, prepared, g)
    }
    const LEVEL: PolarizationLevel = PolarizationLevel::Intensity;
    type Output<T: Real> = IntensityResponse<T>;

    #[inline]
    fn plan<T: Real>(packet: &WavePacket<T>, uses_shape: bool) -> PreparationPlan {
        PreparationPlan(Plan::one_weight(packet, uses_shape, false))
    }

    #[inline]
    fn evaluate<T, S, Coh, R>(
        coherence: &Coh,
        roughness: &R,
        material: &S,
        prepared: &PreparedPacket<T, Self, Coh>,
        g: &Geometry<T>,
    ) -> IntensityResponse<T>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        R: RoughnessWeights<T, S::Psd, Coh>,
    {
        let material = material.parts();
        let psd = &material.psd;
        let f = front(psd, prepared, g);
        let (attenuation, ln_front) = (f.attenuation, f.ln_front);
        let xi = prepared.sections[2].as_ref();
        // Off the specular lobe (and always for a plane wave) its weight is 0.
        let ls = ln_front + coherence.log_specular_weight(xi, &g.h_t);
        let u = |m00: T| Vector4::new(m00 * g.cos_o, T::zero(), T::zero(), T::zero());
        let specular = if prepared.is_dark(ls) {
            T::zero()
        } else {
            prepared.scaled(u(material.specular.m00(g)), ls)[0]
        };
        let scattered = one_weight_scatter(
            coherence,
            roughness,
            psd,
            prepared,
            g,
            &f,
            u(material.scatter.m00(g)),
        )[0];
        IntensityResponse {
            specular,
            scattered,
            attenuation,
            side: g.side,
        }
    }
}

impl PolarizationModel for OneShape {
    type Throughput<T: Real> = Mueller<T>;

    #[inline]
    fn evaluate_mueller<T, S, Coh, R>(
        coherence: &Coh,
        roughness: &R,
        material: &S,
        prepared: &PreparedPacket<T, Self, Coh>,
        g: &Geometry<T>,
    ) -> MuellerResponse<T, Mueller<T>>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        R: RoughnessWeights<T, S::Psd, Coh>,
    {
        matrix::one_shape(coherence, roughness, material, prepared, g)
    }
    const LEVEL: PolarizationLevel = PolarizationLevel::OneShape;
    type Output<T: Real> = Response<T>;

    #[inline]
    fn plan<T: Real>(packet: &WavePacket<T>, uses_shape: bool) -> PreparationPlan {
        PreparationPlan(Plan::one_weight(packet, uses_shape, true))
    }

    #[inline]
    fn evaluate<T, S, Coh, R>(
        coherence: &Coh,
        roughness: &R,
        material: &S,
        prepared: &PreparedPacket<T, Self, Coh>,
        g: &Geometry<T>,
    ) -> Response<T>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        R: RoughnessWeights<T, S::Psd, Coh>,
    {
        one_shape(coherence, roughness, material, prepared, g)
    }
}

impl PolarizationModel for Full {
    type Throughput<T: Real> = Mueller<T>;

    #[inline]
    fn evaluate_mueller<T, S, Coh, R>(
        coherence: &Coh,
        roughness: &R,
        material: &S,
        prepared: &PreparedPacket<T, Self, Coh>,
        g: &Geometry<T>,
    ) -> MuellerResponse<T, Mueller<T>>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        R: RoughnessWeights<T, S::Psd, Coh>,
    {
        if !Coh::USES_SHAPE || prepared.single_shape {
            matrix::one_shape(coherence, roughness, material, prepared, g)
        } else {
            matrix::full(coherence, roughness, material, prepared, g)
        }
    }
    const LEVEL: PolarizationLevel = PolarizationLevel::Full;
    type Output<T: Real> = Response<T>;

    /// With one shape (or without shapes) the three channels' weights are one and the same:
    /// the [`OneShape`] plan; otherwise all three sections and the channel logarithms.
    #[inline]
    fn plan<T: Real>(packet: &WavePacket<T>, uses_shape: bool) -> PreparationPlan {
        let single = packet.has_single_shape();
        let three = uses_shape && !single;
        PreparationPlan(Plan {
            sections: [three, three, uses_shape],
            rotation: true,
            channel_logs: three,
            single_shape: single,
        })
    }

    #[inline]
    fn evaluate<T, S, Coh, R>(
        coherence: &Coh,
        roughness: &R,
        material: &S,
        prepared: &PreparedPacket<T, Self, Coh>,
        g: &Geometry<T>,
    ) -> Response<T>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        R: RoughnessWeights<T, S::Psd, Coh>,
    {
        let material = material.parts();
        if !Coh::USES_SHAPE || prepared.single_shape {
            return one_shape(coherence, roughness, material, prepared, g);
        }
        let psd = &material.psd;
        let f = front(psd, prepared, g);
        let (attenuation, ln_front) = (f.attenuation, f.ln_front);
        let log_weights = |i: usize| {
            let xi = prepared.sections[i].as_ref();
            (
                coherence.log_specular_weight(xi, &g.h_t),
                roughness.log_scatter_weight(coherence, psd, psd_xi(g, xi).as_ref(), g),
            )
        };
        let ((xs, xd), (ys, yd), (hs, hd)) = (log_weights(0), log_weights(1), log_weights(2));
        let (spec_in, spec_m) = prepared.channel_mix(xs, ys, hs);
        let (scat_in, scat_m) = prepared.channel_mix(xd, yd, hd);
        let (spec_ln, scat_ln) = (ln_front + spec_m, f.scatter::<R>().1 + scat_m);
        // Off the specular lobe its weight underflows: skip the specular pBSDF there.
        let specular = if prepared.is_dark(spec_ln) {
            Vector4::zeros()
        } else {
            prepared.scaled(
                onto_cone(material.specular.mueller(g).0 * (spec_in * g.cos_o)),
                spec_ln,
            )
        };
        let scattered = if prepared.is_dark(scat_ln) {
            Vector4::zeros()
        } else {
            prepared.scaled(
                onto_cone(material.scatter.mueller(g).0 * (scat_in * g.cos_o)),
                scat_ln,
            )
        };
        Response {
            specular: Stokes(specular),
            scattered: Stokes(scattered),
            attenuation,
            side: g.side,
        }
    }
}

#[cfg(test)]
mod tests;
