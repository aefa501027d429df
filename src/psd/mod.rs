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
//! # Forms
//! Every PSD declares its [`Form`] ([`Psd::form`]): which [`Shape`] it is, or the closest one.
//! That is all the BSDF sampler, the medium and the kernel's SIMD lanes read of it, so a new
//! PSD is one file ([`PowerLaw`] is: it names the K-correlation as its closest form).
//!
//! # Blur methods
//! A blur method is a type implementing [`BlurMethod`]; the choice is monomorphised:
//! - [`ClosedForm`]: exact, for every PSD implementing [`ClosedFormBlur`] — [`GaussianPsd`],
//!   [`GaussianMixturePsd`], [`Grating`], [`Smooth`], and a downstream crate's own PSDs;
//! - mixture fit: [`KCorrelation::mixture_fit`] builds a [`GaussianMixturePsd`] once, then
//!   [`ClosedForm`] applies;
//! - [`GaussHermite`]: tensor Gauss–Hermite quadrature of a fixed order, any PSD (e.g. the
//!   band-limited power law [`PowerLaw`], which has no closed form);
//! - [`Adaptive`]: nested adaptive Gauss–Kronrod to a relative tolerance — the reference.

mod autocorrelation;
mod form;
mod gaussian_psd;
mod grating;
mod kcorrelation;
mod power_law;
mod powers;
mod quadrature;
pub(crate) mod special;

pub use autocorrelation::{Autocorrelation, matern};
pub use form::{Form, Shape};
pub use gaussian_psd::{GaussianMixturePsd, GaussianPsd, Smooth};
pub use grating::{Grating, OrderCutoff, bessel_j};
pub use kcorrelation::KCorrelation;
pub use power_law::PowerLaw;
pub use powers::CorrelationPowers;
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

    /// The PSD's spectral form: its shape, exactly or the closest one ([`Form`]). The BSDF
    /// sampler, the medium and the kernel's SIMD lanes read the PSD through it.
    #[must_use]
    fn form(&self) -> Form<'_, T, N>;

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

    /// `true` when this method's blur of a Gaussian PSD is the exact closed form (as
    /// [`ClosedForm`]'s), so that a caller may use an equivalent closed form of its own (the
    /// Kirchhoff series sums all its orders in one,
    /// [`crate::interaction::roughness::KirchhoffSeries`]); `false` by default (quadratures).
    #[inline]
    #[must_use]
    fn exact_for_gaussians(&self) -> bool {
        false
    }
}

/// The exact, closed-form blur: the [`BlurMethod`] of every PSD that implements
/// [`ClosedFormBlur`] (in this crate: [`GaussianPsd`], [`GaussianMixturePsd`], [`Grating`],
/// [`Smooth`]; in any other crate: its own PSDs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ClosedForm;

/// A PSD whose blur `(p * g^Σ)(h)` has a closed form; [`ClosedForm`] then blurs it.
///
/// The closed form lives on the PSD side, so a crate that defines a PSD can give it one: the
/// blanket `impl BlurMethod<T, N, P> for ClosedForm` covers every `P: ClosedFormBlur<T, N>`
/// (an `impl BlurMethod<T, N, MyPsd> for ClosedForm` would be rejected by the orphan rule,
/// E0210, since `ClosedForm` is not the downstream crate's type).
///
/// # Formula
/// ```text
/// closed_form_blur(Σ, h)                    = (p * g^Σ)(h)
/// closed_form_normalized_blur(Σ, h)         = |Σ|^{−1/2} (p * g^Σ)(h) = ∫ p(ζ) 𝒩_Σ(h − ζ) dⁿζ
/// closed_form_log_normalized_blur(Σ, h)     = ln of the line above
/// ```
/// Only the first is required; the defaults are those of [`BlurMethod`] (a `|Σ|^{−1/2}` round
/// trip and a plain logarithm). Override them where the blur spans more than the type's range
/// (wide coherence areas make `(p * g^Σ)` underflow long before the normalised blur does).
///
/// # Examples
/// A PSD defined outside `gmueller` — two Dirac orders at `±ζ₀` (a grating with only its first
/// orders) — with its closed form, used by the partially coherent kernel:
/// ```
/// use gmueller::gaussian::Gaussian;
/// use gmueller::frame::Frame;
/// use gmueller::interaction::{Geometry, Intensity, Kernel, Partial, RoughSurface};
/// use gmueller::interaction::pbsdf::PhaseScreen;
/// use gmueller::packet::{CoherenceShape, WavePacket};
/// use gmueller::psd::{BlurMethod, ClosedForm, ClosedFormBlur, Form, Psd, Shape};
/// use gmueller::real::Real;
/// use gmueller::stokes::Stokes;
/// use nalgebra::{SVector, Vector2, Vector3};
///
/// /// `p = (2π) w [δ(ζ − ζ₀) + δ(ζ + ζ₀)] / 2`: two orders of total weight `w`.
/// struct TwoOrders<T: Real> { orders: [(Vector2<T>, T); 2] }
///
/// impl<T: Real> TwoOrders<T> {
///     fn new(zeta0: Vector2<T>, weight: T) -> Self {
///         let half = T::lit(0.5) * weight;
///         Self { orders: [(zeta0, half), (-zeta0, half)] }
///     }
/// }
/// impl<T: Real> Psd<T, 2> for TwoOrders<T> {
///     fn value(&self, _zeta: &SVector<T, 2>) -> T { T::zero() } // no continuous part
///     fn variance(&self) -> T { self.orders[0].1 + self.orders[1].1 }
///     // Exactly the grating's form: the BSDF sampler draws its orders.
///     fn form(&self) -> Form<'_, T, 2> { Form::exact(Shape::Orders(&self.orders)) }
/// }
/// impl<T: Real> ClosedFormBlur<T, 2> for TwoOrders<T> {
///     // (p * g^Σ)(h) = (2π)^{−1} ∫ p(ζ) g^Σ(h − ζ) d²ζ = w [g^Σ(h − ζ₀) + g^Σ(h + ζ₀)] / 2
///     fn closed_form_blur(&self, cov: &Gaussian<T, 2>, h: &SVector<T, 2>) -> T {
///         self.orders.iter().fold(T::zero(), |s, (z, e)| s + *e * cov.value(&(h - z)))
///     }
/// }
///
/// let p = TwoOrders::new(Vector2::new(3.0_f64, 0.0), 1e-4);
/// let cov = Gaussian::<f64, 2>::isotropic(0.5)?; // Σ = 0.5² I
/// let h = Vector2::new(2.5, 0.1);
/// let exact = ClosedForm.blur(&p, &cov, &h);
/// let expected = 0.5e-4 * ((-0.5 * (0.25 + 0.01) / 0.25_f64).exp() + (-0.5 * (30.25 + 0.01) / 0.25_f64).exp());
/// assert!((exact / expected - 1.0).abs() < 1e-14);
/// let normalized = ClosedForm.normalized_blur(&p, &cov, &h);
/// assert!((normalized / (exact / 0.25) - 1.0).abs() < 1e-14); // |Σ|^{1/2} = 0.25
///
/// // The partially coherent kernel takes it like any PSD of the crate (`Partial` blurs with
/// // `ClosedForm` by default).
/// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
/// let travel = Vector3::new(0.0, 0.0, -1.0_f64);
/// let packet = WavePacket::from_stokes(
///     Stokes::unpolarized(1.0)?, CoherenceShape::isotropic(5.0)?,
///     Frame::sp(travel, Vector3::x())?, 0.5)?;
/// let material = RoughSurface {
///     psd: TwoOrders::new(Vector2::new(2.0, 0.0), 1e-4),
///     specular: PhaseScreen::new(1.0)?,
///     scatter: PhaseScreen::new(1.0)?,
/// };
/// let kernel = Kernel::<Intensity, Partial>::default();
/// // The first order leaves where the half-vector's tangential part is ζ₀: k sin θ = 2.
/// let sin_t = 2.0 / packet.wavenumber();
/// let order = Geometry::for_packet(&packet, &surface, Vector3::new(sin_t, 0.0, (1.0 - sin_t * sin_t).sqrt()))?;
/// let between = Geometry::for_packet(&packet, &surface, Vector3::new(0.5 * sin_t, 0.0, (1.0 - 0.25 * sin_t * sin_t).sqrt()))?;
/// let at_order = kernel.evaluate(&material, &packet, &order).scattered;
/// let off_order = kernel.evaluate(&material, &packet, &between).scattered;
/// assert!(at_order.is_finite() && at_order > 1e3 * off_order);
/// # Ok::<(), gmueller::Error>(())
/// ```
pub trait ClosedFormBlur<T: Real, const N: usize>: Psd<T, N> {
    /// `(p * g^Σ)(h)`, exact; finite for finite input, `0` on underflow.
    #[must_use]
    fn closed_form_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T;

    /// `∫ p(ζ) 𝒩_Σ(h − ζ) dⁿζ = |Σ|^{−1/2} (p * g^Σ)(h)` ([`BlurMethod::normalized_blur`]).
    #[inline]
    #[must_use]
    fn closed_form_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.closed_form_blur(cov, h) * (T::lit(-0.5) * cov.log_det()).exp()
    }

    /// `ln` of [`ClosedFormBlur::closed_form_normalized_blur`] (`−∞` where it is 0)
    /// ([`BlurMethod::log_normalized_blur`]).
    #[inline]
    #[must_use]
    fn closed_form_log_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.closed_form_normalized_blur(cov, h).ln()
    }
}

impl<T: Real, const N: usize, P: ClosedFormBlur<T, N> + ?Sized> BlurMethod<T, N, P> for ClosedForm {
    #[inline]
    fn blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        psd.closed_form_blur(cov, h)
    }
    #[inline]
    fn normalized_blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        psd.closed_form_normalized_blur(cov, h)
    }
    #[inline]
    fn log_normalized_blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        psd.closed_form_log_normalized_blur(cov, h)
    }
    #[inline]
    fn exact_for_gaussians(&self) -> bool {
        true
    }
}
