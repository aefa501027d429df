//! The coherence models of the kernel (a model level): how the packet's spatial coherence
//! enters the channel weights `K` (scattered) and `K^spec` (specular) of S2.20, and the
//! coherence terms of S2.17 on their own.
//!
//! ```text
//! PlaneWave:   K = 2π p(h_t),                         K^spec = 0 (a Dirac delta)
//! Partial<B>:  K = 2π |Σ|^{1/2} (p * g^Ξ)(h_t),        K^spec = 2π |Σ|^{1/2} g^Ξ(h_t)
//! Incoherent:  K = |Σ|^{1/2} g^Ξ(h_t) ∫p,              K^spec = 2π |Σ|^{1/2} g^Ξ(h_t)
//! ```
//! (`Σ = Ξ⁻¹`, the section of the coherence by the surface, [`surface_inverse_coherence`]).
//! Only [`Partial`] blurs the PSD, so only it carries a [`BlurMethod`] (`ClosedForm` by default).
//!
//! Here: the level markers [`PlaneWave`], [`Partial`] and [`Incoherent`] (also re-exported at the
//! top of [`super`], for `Kernel::<Pol, Coh>`), their traits ([`CoherenceModel`], the weights
//! [`CoherenceWeights`]) and values ([`CoherenceLevel`]), the coherence terms of S2.17 on their
//! own ([`surface_coherence_term`], [`volume_coherence_term`]) and the section `Ξ_α` of a packet's
//! coherence by the surface ([`surface_inverse_coherence`]).

use core::fmt::Debug;

use nalgebra::{Vector2, Vector3};

use crate::error::Error;
use crate::frame::Frame;
use crate::gaussian::Gaussian;
use crate::packet::{Channel, WavePacket};
use crate::psd::{BlurMethod, ClosedForm, Psd, two_pi_pow_half_n};
use crate::real::Real;

pub use super::section::surface_inverse_coherence;

pub(crate) mod sealed {
    pub trait Sealed {}
}

/// The coherence levels, as values (for reports and run-time selection, [`super::Level`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CoherenceLevel {
    /// The fully coherent limit: the classical BRDF.
    PlaneWave,
    /// Partial coherence (S2.20).
    Partial,
    /// The incoherent limit.
    Incoherent,
}

/// How the kernel treats spatial coherence (a model level): what every coherence model is,
/// whatever the PSD.
pub trait CoherenceModel: sealed::Sealed + Clone + Debug {
    /// Which level.
    const LEVEL: CoherenceLevel;
    /// Whether the packet's shape matrices enter at all.
    const USES_SHAPE: bool;

    /// `ln K^spec` of the specular-channel weight (`−∞` for a plane wave, whose lobe is a
    /// delta): the smooth mean surface's lobe, the same for every PSD.
    #[must_use]
    fn log_specular_weight<T: Real>(&self, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T;

    /// The specular-channel weight `K^spec = exp(ln K^spec)` (0 for a plane wave).
    #[inline]
    #[must_use]
    fn specular_weight<T: Real>(&self, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        self.log_specular_weight(xi, h_t).exp()
    }
}

/// The channel weights of a coherence model for a PSD `P`.
///
/// The weights are computed as logarithms (`ln K`, `ln K^spec`): the kernel combines them with
/// the Stokes vector's own magnitude before anything is exponentiated, so a weight far below
/// the smallest number of the type still weighs a bright packet (module docs of
/// [`crate::interaction`], "Numerics").
pub trait CoherenceWeights<T: Real, P: Psd<T, 2>>: CoherenceModel {
    /// `ln K` of the scattered-channel weight `K` (see the module formula); `−∞` where `K = 0`.
    #[must_use]
    fn log_scatter_weight(&self, psd: &P, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T;

    /// The scattered-channel weight `K` itself (`exp(ln K)` by default; the models of this
    /// crate override it with the cheaper linear forms, 0 where `K` underflows).
    #[inline]
    #[must_use]
    fn scatter_weight(&self, psd: &P, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        self.log_scatter_weight(psd, xi, h_t).exp()
    }

    /// `true` when the weight of a Gaussian PSD is its exact closed form (the plane wave; the
    /// partially coherent level with [`ClosedForm`]): the Kirchhoff series then evaluates all
    /// its orders by one closed form ([`super::roughness::KirchhoffSeries`]). `false` by default.
    #[inline]
    #[must_use]
    fn closed_form_gaussian(&self) -> bool {
        false
    }
}

/// The fully coherent (plane-wave) limit: `K = 2π p(h_t)`; the classical BRDF.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PlaneWave;

/// Partial coherence, S2.20: `K = 2π |Σ|^{1/2} (p * g^Ξ)(h_t)`, the PSD blurred by the blur
/// method `B` ([`ClosedForm`] by default: `Partial::default()` or `Partial(ClosedForm)`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Partial<B = ClosedForm>(pub B);

/// The incoherent limit: `K = |Σ|^{1/2} g^Ξ(h_t) ∫p`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Incoherent;

impl sealed::Sealed for PlaneWave {}
impl<B> sealed::Sealed for Partial<B> {}
impl sealed::Sealed for Incoherent {}

impl CoherenceModel for PlaneWave {
    const LEVEL: CoherenceLevel = CoherenceLevel::PlaneWave;
    const USES_SHAPE: bool = false;
    #[inline]
    fn log_specular_weight<T: Real>(&self, _xi: Option<&Gaussian<T, 2>>, _h: &Vector2<T>) -> T {
        neg_infinity()
    }
}
impl<B: Clone + Debug> CoherenceModel for Partial<B> {
    const LEVEL: CoherenceLevel = CoherenceLevel::Partial;
    const USES_SHAPE: bool = true;
    #[inline]
    fn log_specular_weight<T: Real>(&self, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        xi.map_or(neg_infinity(), |xi| log_smooth_lobe(xi, h_t))
    }
}
impl CoherenceModel for Incoherent {
    const LEVEL: CoherenceLevel = CoherenceLevel::Incoherent;
    const USES_SHAPE: bool = true;
    #[inline]
    fn log_specular_weight<T: Real>(&self, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        xi.map_or(neg_infinity(), |xi| log_smooth_lobe(xi, h_t))
    }
}

/// `ln 2π`.
#[inline]
pub(crate) fn ln_two_pi<T: Real>() -> T {
    T::lit(core::f64::consts::TAU.ln())
}

/// `ln` of the smallest positive subnormal number of `T` (`ln(ε · MIN_POSITIVE)`).
#[inline]
pub(crate) fn ln_smallest_subnormal<T: Real>() -> f64 {
    (T::EPSILON.to_f64() * T::MIN_POSITIVE.to_f64()).ln()
}

/// `−∞` (the logarithm of a zero weight).
#[inline]
pub(crate) fn neg_infinity<T: Real>() -> T {
    -T::MAX * T::lit(2.0)
}

/// `ln(2π |Σ|^{1/2} g^Ξ(h)) = ln 2π + ln g^Ξ(h) − ½ ln|Ξ|` (the smooth-surface lobe).
#[inline]
fn log_smooth_lobe<T: Real>(xi: &Gaussian<T, 2>, h_t: &Vector2<T>) -> T {
    ln_two_pi::<T>() + xi.log_value(h_t) - T::lit(0.5) * xi.log_det()
}

impl<T: Real, P: Psd<T, 2>> CoherenceWeights<T, P> for PlaneWave {
    #[inline]
    fn log_scatter_weight(&self, psd: &P, _xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        ln_two_pi::<T>() + psd.log_value(h_t)
    }
    #[inline]
    fn closed_form_gaussian(&self) -> bool {
        true
    }
    #[inline]
    fn scatter_weight(&self, psd: &P, _xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        T::two_pi() * psd.value(h_t)
    }
}

impl<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P> + Clone + Debug> CoherenceWeights<T, P>
    for Partial<B>
{
    #[inline]
    fn log_scatter_weight(&self, psd: &P, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        match xi {
            // K = 2π |Σ|^{1/2} (p * g^Ξ)(h) with |Σ| = 1/|Ξ|: 2π times the normalised blur,
            // which never forms the tiny (p * g^Ξ) of a wide coherence area.
            Some(xi) => ln_two_pi::<T>() + self.0.log_normalized_blur(psd, xi, h_t),
            None => ln_two_pi::<T>() + psd.log_value(h_t),
        }
    }
    #[inline]
    fn scatter_weight(&self, psd: &P, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        partial_scatter_weight(&self.0, psd, xi, h_t)
    }
    #[inline]
    fn closed_form_gaussian(&self) -> bool {
        self.0.exact_for_gaussians()
    }
}

/// `K = 2π ∫ p 𝒩_Ξ(h_t − ·)` (the plane-wave `2π p(h_t)` without a section), linear.
#[inline]
fn partial_scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
    blur: &B,
    psd: &P,
    xi: Option<&Gaussian<T, 2>>,
    h_t: &Vector2<T>,
) -> T {
    match xi {
        Some(xi) => T::two_pi() * blur.normalized_blur(psd, xi, h_t),
        None => T::two_pi() * psd.value(h_t),
    }
}

impl<T: Real, P: Psd<T, 2>> CoherenceWeights<T, P> for Incoherent {
    #[inline]
    fn log_scatter_weight(&self, psd: &P, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        match xi {
            Some(xi) => log_smooth_lobe(xi, h_t) + psd.integral().ln() - ln_two_pi::<T>(),
            None => ln_two_pi::<T>() + psd.log_value(h_t),
        }
    }
    #[inline]
    fn scatter_weight(&self, psd: &P, xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        match xi {
            Some(xi) => log_smooth_lobe(xi, h_t).exp() * psd.integral() / T::two_pi(),
            None => T::two_pi() * psd.value(h_t),
        }
    }
}

/// The surface coherence term of S2.17 for one packet channel, partially coherent:
/// `K_α = 2π |Σ_α|^{1/2} (p * g^{Ξ_α})(h_t) = |Σ_α|^{1/2} ∫ p(q) g^{Ξ_α}(h_t − q) d²q`.
///
/// This is the double-integral factor `∫ e^{−i h·ξ} R(ξ) g^{Θ_α}(Qᵀξ) d²ξ` of S2.15 for
/// separations ξ in the surface; the kernel multiplies it by `cos θ_o/λ²`, α and the pBSDF.
/// Falls back to the plane-wave value `2π p(h_t)` where [`surface_inverse_coherence`] is `None`.
#[must_use]
pub fn surface_coherence_term<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
    psd: &P,
    blur: &B,
    packet: &WavePacket<T>,
    channel: Channel,
    surface: &Frame<T>,
    h_t: &Vector2<T>,
) -> T {
    let xi = surface_inverse_coherence(packet, channel, surface);
    partial_scatter_weight(blur, psd, xi.as_ref(), h_t)
}

/// The volumetric coherence term of S2.17 (corrected constant) for one packet channel:
/// `K³_α = (2π)^{3/2} |Θ_α|^{1/2} (p * g^{Ξ_α})(h) = |Θ_α|^{1/2} ∫ p(q) g^{Ξ_α}(h − q) d³q`,
/// `Ξ_α = Q Θ_α⁻¹ Qᵀ` (S2.18) with `Q = [x̂ ŷ k̂]` mapping packet to world coordinates and `h`
/// the full 3-D `k(r̂ + ŝ)`.
///
/// # Errors
/// [`Error::Singular`] when the packet has unbounded longitudinal coherence (`Θ_α` is then not
/// a 3-D covariance: set `σ_zz` with [`WavePacket::with_longitudinal_coherence`]).
pub fn volume_coherence_term<T: Real, P: Psd<T, 3>, B: BlurMethod<T, 3, P>>(
    psd: &P,
    blur: &B,
    packet: &WavePacket<T>,
    channel: Channel,
    h: &Vector3<T>,
) -> Result<T, Error> {
    if packet.inverse_longitudinal_variance() == T::zero() {
        return Err(Error::Singular {
            what: "3-D shape matrix with unbounded longitudinal coherence",
        });
    }
    let xi = Gaussian::new(packet.world_precision(channel))?;
    // (2π)^{3/2} |Θ|^{1/2} (p * g^Ξ) with |Θ| = 1/|Ξ|: (2π)^{3/2} times the normalised blur.
    Ok(blur.normalized_blur(psd, &xi, h) * two_pi_pow_half_n::<T>(3))
}
