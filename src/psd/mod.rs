//! Power spectral densities of random matter, and their blur by Gaussians (S2.14–S2.17).
//!
//! # Conventions
//! ```text
//! p(ζ) = F{R}(ζ) = (2π)^{−n/2} ∫ R(x) e^{−i ζ·x} dⁿx        unitary transform, ζ in rad/length
//! ∫ p(ζ) dⁿζ = (2π)^{n/2} R(0) = (2π)^{n/2} σ²               (Fourier inversion at x = 0)
//! (p * g^Σ)(h) = (2π)^{−n/2} ∫ p(ζ) g^Σ(h − ζ) dⁿζ           the blur; g^Σ UNNORMALISED
//! ```
//! `R` is the stationary autocorrelation, `σ² = R(0)` its variance (for a height field, the
//! squared rms height). The blur is the quantity S2.17 needs: the kernel term is
//! `(2π)^{n/2} |Θ|^{1/2} (p * g^Ξ)(h)` with `Ξ = Q Θ⁻¹ Qᵀ` (S2.18) and — see the errata —
//! the constant `(2π)^{n/2}`, not the printed `8π³`.
//!
//! Converting from the "cycles per length" PSD of SCATMECH and most optics texts,
//! `S(f) = ∫ R(x) e^{−2πi f·x} dⁿx` (so `∫ S dⁿf = σ²`): `S(f) = (2π)^{n/2} p(2π f)`
//! ([`Psd::value_cycles`]).
//!
//! # Blur methods
//! A blur method is a type implementing [`BlurMethod`]; the choice is monomorphised:
//! - [`ClosedForm`]: exact, for [`GaussianPsd`], [`GaussianMixturePsd`], [`Grating`], [`Smooth`];
//! - mixture fit: [`KCorrelation::mixture_fit`] builds a [`GaussianMixturePsd`] once, then
//!   [`ClosedForm`] applies;
//! - [`GaussHermite`]: tensor Gauss–Hermite quadrature of a fixed order, any PSD;
//! - [`Adaptive`]: nested adaptive Gauss–Kronrod to a relative tolerance — the reference.

mod gaussian_psd;
mod grating;
mod kcorrelation;
mod quadrature;
pub(crate) mod special;

pub use gaussian_psd::{GaussianMixturePsd, GaussianPsd, Smooth};
pub use grating::{Grating, OrderCutoff, bessel_j};
pub use kcorrelation::KCorrelation;
pub use quadrature::{Adaptive, GaussHermite};

use nalgebra::SVector;

use crate::gaussian::Gaussian;
use crate::real::Real;

/// `(2π)^{n/2}` as `T`.
#[inline]
#[must_use]
pub fn two_pi_pow_half_n<T: Real>(n: usize) -> T {
    T::lit(core::f64::consts::TAU.powf(0.5 * n as f64))
}

/// A stationary power spectral density `p = F{R}` on `ℝᴺ` (`N = 2` surfaces, `N = 3` volumes).
///
/// # Formula
/// ```text
/// p(ζ) = (2π)^{−n/2} ∫ R(x) e^{−iζ·x} dⁿx,     ∫ p dⁿζ = (2π)^{n/2} R(0)
/// ```
/// Singular (Dirac) parts — grating orders, the smooth surface — are not visible to
/// [`Psd::value`]; they enter only through [`Psd::integral`] and the closed-form blur.
pub trait Psd<T: Real, const N: usize> {
    /// The absolutely continuous part of `p(ζ)`, ζ in rad/length (0 for pure Dirac PSDs).
    #[must_use]
    fn value(&self, zeta: &SVector<T, N>) -> T;

    /// `ln p(ζ)` of the absolutely continuous part (`−∞` where it is 0). The default is
    /// `ln(value)`; the closed-form PSDs override it with a form that stays accurate where
    /// [`Psd::value`] underflows (the kernel's coherence weights are formed in log space).
    #[inline]
    #[must_use]
    fn log_value(&self, zeta: &SVector<T, N>) -> T {
        self.value(zeta).ln()
    }

    /// The variance `σ² = R(0)` (squared rms height for a height field).
    #[must_use]
    fn variance(&self) -> T;

    /// `∫ p dⁿζ = (2π)^{n/2} R(0)` under the unitary transform (Dirac parts included).
    #[inline]
    #[must_use]
    fn integral(&self) -> T {
        two_pi_pow_half_n::<T>(N) * self.variance()
    }

    /// The PSD in cycles per length, `S(f) = (2π)^{n/2} p(2π f)`, normalised as `∫ S dⁿf = σ²`
    /// (SCATMECH's convention).
    #[inline]
    #[must_use]
    fn value_cycles(&self, f: &SVector<T, N>) -> T {
        two_pi_pow_half_n::<T>(N) * self.value(&(f * T::two_pi()))
    }

    /// Where `p` peaks (a breakpoint hint for quadrature); the origin by default.
    #[inline]
    #[must_use]
    fn peak(&self) -> SVector<T, N> {
        SVector::zeros()
    }

    /// The width of `p`'s narrowest feature around [`Psd::peak`] (rad/length), a grading hint for
    /// [`Adaptive`]; `0` (no hint) by default.
    #[inline]
    #[must_use]
    fn feature_width(&self) -> T {
        T::zero()
    }

    /// `(p * g^Σ)(h)` with the method `method` (see [`BlurMethod`]).
    #[inline]
    #[must_use]
    fn blur_with<M: BlurMethod<T, N, Self>>(
        &self,
        method: &M,
        cov: &Gaussian<T, N>,
        h: &SVector<T, N>,
    ) -> T
    where
        Self: Sized,
    {
        method.blur(self, cov, h)
    }
}

/// A way to compute the blur `(p * g^Σ)(h)` of a PSD `P`.
///
/// # Formula
/// ```text
/// (p * g^Σ)(h) = (2π)^{−n/2} ∫ p(ζ) g^Σ(h − ζ) dⁿζ = |Σ|^{1/2} E_{u∼𝒩(0,I)}[ p(h − L u) ]
/// ```
/// with `g^Σ` unnormalised and `Σ = L Lᵀ`. Implementations allocate nothing per call.
pub trait BlurMethod<T: Real, const N: usize, P: ?Sized> {
    /// `(p * g^Σ)(h)`; finite for finite input, `0` on underflow.
    #[must_use]
    fn blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T;

    /// The PSD smoothed by the *normalised* Gaussian density of covariance Σ:
    /// `∫ p(ζ) 𝒩_Σ(h − ζ) dⁿζ = |Σ|^{−1/2} (p * g^Σ)(h)`, which tends to `p(h)` as `Σ → 0`.
    ///
    /// # Formula
    /// ```text
    /// 𝒩_Σ(x) = (2π)^{−n/2} |Σ|^{−1/2} g^Σ(x)
    /// ∫ p(ζ) 𝒩_Σ(h − ζ) dⁿζ = |Σ|^{−1/2} (p * g^Σ)(h) = E_{u∼𝒩(0,I)}[ p(h − L u) ]
    /// ```
    /// This is the quantity the S2.17/S2.20 coherence terms need (`K = (2π)^{n/2} ×` it, with
    /// `Σ = Ξ`). Computing it as `blur · |Σ|^{−1/2}` is a `0 · ∞` round trip when the coherence
    /// is wide (`|Ξ| → 0`): the blur underflows (in f32 below ~1e-38) while the product is a
    /// normal number. The default does exactly that round trip (in log space for the factor);
    /// every blur method of this crate overrides it with a form that never leaves the scale of
    /// the result (log space for the closed forms, the plain expectation for the quadratures).
    ///
    /// # Examples
    /// ```
    /// use gmueller::gaussian::Gaussian;
    /// use gmueller::psd::{BlurMethod, ClosedForm, GaussianPsd, Psd};
    /// use nalgebra::Vector2;
    /// let p = GaussianPsd::<f32, 2>::isotropic(1e-3, 1.0).unwrap();
    /// let h = Vector2::new(110f32.sqrt(), 0.0);
    /// // A coherence width of 10⁸ (length): |Σ|^{1/2} = 1e-16, and p(h) ≈ 1.3e-30.
    /// let wide = Gaussian::<f32, 2>::isotropic(1e-8).unwrap();
    /// let n = ClosedForm.normalized_blur(&p, &wide, &h);
    /// assert!((n / p.value(&h) - 1.0).abs() < 1e-5); // → p(h) as Σ → 0
    /// assert_eq!(ClosedForm.blur(&p, &wide, &h), 0.0); // the un-normalised blur underflows
    /// ```
    #[inline]
    #[must_use]
    fn normalized_blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.blur(psd, cov, h) * (T::lit(-0.5) * cov.log_det()).exp()
    }

    /// `ln` of [`BlurMethod::normalized_blur`] (`−∞` where it is 0), the form the kernel uses.
    /// The default is `ln(normalized_blur)`, so it is `−∞` wherever the value underflows; the
    /// closed forms of this crate override it with a log-space form that stays accurate far
    /// below the smallest number of the type (a tail of `p` 10⁻⁵⁰ down, say, still weighs a
    /// Stokes vector of 10⁴⁰ in `f32`). The quadrature methods keep the default.
    #[inline]
    #[must_use]
    fn log_normalized_blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.normalized_blur(psd, cov, h).ln()
    }
}

/// The exact, closed-form blur (Gaussian, Gaussian-mixture, grating and smooth PSDs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ClosedForm;
