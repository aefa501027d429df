//! The light–matter interaction kernel of S2.20: a wave packet meets rough matter.
//!
//! # Formula (surface form, n = 2, constants decided by the tests; see the crate Errata)
//! ```text
//! L_o = (cos θ_o / λ²) · α · [ M_spec T Σ_α K^spec_α S_α  +  M_scat T Σ_α K_α S_α ]
//!
//! K_α      = |Σ_α|^{1/2} ∫ p(q) g^{Ξ_α}(h_t − q) d²q  = 2π |Σ_α|^{1/2} (p * g^{Ξ_α})(h_t)
//! K^spec_α = 2π |Σ_α|^{1/2} g^{Ξ_α}(h_t)               (the same with p = 2π δ: a smooth mean surface)
//! Ξ_α      = T_tᵀ Q Θ_α⁻¹ Qᵀ T_t,  Σ_α = Ξ_α⁻¹            (S2.18 restricted to the tangent plane)
//! α        = exp(−(k σ (cos θ_i + cos θ_o))²)             (Debye–Waller roughness attenuation)
//! S_x = S_x (1, 1, 0, 0),  S_y = S_y (1, −1, 0, 0),  S_½ = (0, 0, S2, S3)          (S2.16)
//! ```
//! with `h = k(r̂ + ŝ)` (ŝ toward the source) and `h_t` its tangential part, `Q = [x̂ ŷ k̂]` the
//! packet frame (packet → world), `T_t = [t̂₁ t̂₂]` the surface tangents, `p` the PSD of the
//! height field (unitary transform, [`crate::psd`]) and `σ² = R(0)` its variance, `T` the
//! rotation (S2.4) from the packet frame to the incident s/p frame, `M` the pBSDFs (S2.19) from
//! the incident to the exit s/p frame. The output is a classical Stokes radiance in the exit
//! s/p frame ([`Geometry::exit_sp`]) per unit incident irradiance measured across the beam.
//!
//! `Ξ_α` is the 2-D *section* of the 3-D inverse coherence (the packet's coherence function
//! evaluated at separations that lie in the surface), not the marginal: the kernel needs the
//! two-point field at pairs of points *on* the surface. For oblique incidence it stretches
//! the coherence footprint by `1/cos θ_i` in the plane of incidence.
//!
//! # Limits
//! - **Plane wave** (coherence area → ∞): `|Σ|^{1/2} g^{Ξ} → 2π δ`, so `K → 2π p(h_t)` and
//!   the specular lobe becomes a Dirac delta; with [`RayleighRice`] this is the classical
//!   Rayleigh–Rice BRDF — what a renderer without coherence computes.
//! - **Incoherent** (coherence width ≪ correlation length): the Gaussian is much wider than `p`,
//!   `K → |Σ|^{1/2} g^{Ξ}(h_t) ∫p`: the lobe is set by the coherence alone.
//!
//! # Model levels (types, monomorphised)
//! - Polarization: [`Scalar`] (S0 only, `M₀₀`) · [`OneShape`] (Stokes, `Θ_½` for every
//!   channel) · [`Full`] (`Θ_x`, `Θ_y`, `Θ_½`).
//! - Coherence: [`PlaneWave`] · [`Partial`] · [`Incoherent`].
//! - Blur: any [`BlurMethod`] for the PSD (closed form, mixture fit, Gauss–Hermite, adaptive).
//! - Precision: `T = f32` or `f64`.
//!
//! # Numerics (what makes every output a valid Stokes vector)
//! - **Log-space weights.** Every channel weight is computed as a logarithm
//!   ([`CoherenceModel::log_scatter_weight`], [`BlurMethod::log_normalized_blur`],
//!   [`Psd::log_value`]) and combined with `ln S0`, `ln(cos θ_o/λ²)` and `ln α` before anything
//!   is exponentiated; the 4×4 products run on numbers of order one, and `S0 e^{…}` is applied
//!   once at the end. A far tail of a bright packet (weight ~1e-47 in `f32`, `S0 = 1e25`) is
//!   therefore not lost, and a result in the subnormal range keeps its degree of polarization
//!   (the exponent then absorbs `u₀` too, so every entry rounds once). A result beyond the
//!   largest number of the type is `±∞` (never NaN; entries that are 0 stay 0).
//! - **The [`Full`] level's channel mix.** For a realizable packet the exact weights satisfy
//!   `K_½² |μ|² ≤ K_x K_y` (Cauchy–Schwarz over the positive semidefinite spectral matrix, see
//!   [`crate::packet`]); the kernel caps `K_½` at that bound, which makes the effective Stokes
//!   vector valid by construction. Where computed weights break the inequality — nearly
//!   proportional shapes rounded separately in `f32`, per-channel quadrature errors of
//!   [`crate::psd::GaussHermite`] — the cap moves `K_½` by less than their own error.
//! - **Accurate sections.** `Ξ_α` is built from its Cholesky factor by Cauchy–Binet minors
//!   ([`surface_inverse_coherence`]), the blur's `Λ⁻¹ + Ξ_α` from the two factors, and the 2×2
//!   determinants of the shapes exactly in `f32` ([`Real::diff_of_products`], powers-of-two
//!   scaling): grazing incidence does not depend on the azimuth of the plane of incidence, and
//!   the `f32` sections of 10⁶-anisotropic shapes agree with `f64` to ~1e-8.
//!
//! Tested in `tests/extremes.rs` and `docs/numerical.md` (the crate docs, "Numerical
//! behaviour"), against independent oracles in `tests/interaction_channels.rs`,
//! `tests/interaction_s2_10.rs` and `tests/interaction_reference.rs`.
//!
//! # Cost
//! A call splits into per-packet work — the sections `Ξ_α` (one 2×2 Cholesky each: three at
//! [`Full`], one below, none for [`PlaneWave`]) and the rotation `T` to the incident s/p frame —
//! and per-exit work: per channel one blur and one specular-lobe exponential, the Debye–Waller
//! factor, and the two pBSDFs (the specular one skipped where its weight underflows to 0).
//! [`Kernel::evaluate`] does both; for one packet and many exit directions (a lobe, a grid, a
//! light sample and a BSDF sample) [`Kernel::prepare`] the packet once and call
//! [`Kernel::evaluate_prepared`] per direction: the results are bit for bit the same. Measured
//! costs per level are in the README ("Accuracy and speed") and `benches/kernel.rs`.

pub mod batch;
pub mod exitant;
pub mod geometry;
pub mod pbsdf;
pub mod sampling;

use core::marker::PhantomData;

use nalgebra::{Matrix2, Matrix4, Vector2, Vector3, Vector4};

pub use exitant::{exitant_packet, exitant_shape};
pub use geometry::Geometry;
pub use pbsdf::{
    ConstantMueller, FresnelReflection, IdealDiffuse, Pbsdf, PhaseScreen, RayleighRice,
};

use crate::error::Error;
use crate::frame::{Frame, frame_change_mueller};
use crate::gaussian::Gaussian;
use crate::packet::{Channel, WavePacket};
use crate::psd::{BlurMethod, Psd};
use crate::real::Real;
use crate::stokes::Stokes;

mod sealed {
    pub trait Sealed {}
}

/// How much of the polarization a kernel keeps (a model level).
pub trait PolarizationModel: sealed::Sealed + Copy + Default {
    /// Which level.
    const LEVEL: PolarizationLevel;
}

/// The polarization levels, as values (for reports).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PolarizationLevel {
    /// S0 only.
    Scalar,
    /// Full Stokes, one shape matrix (`Θ_½`) for every channel.
    OneShape,
    /// Full S2.20: `Θ_x`, `Θ_y`, `Θ_½`.
    Full,
}

/// Intensity only: `L₀ = (cos θ_o/λ²) α M₀₀ K S0` with `K` from `Θ_½`. No frames, no 4×4 products.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Scalar;
/// Stokes vectors with one coherence shape, `Θ_½`, for all channels: `L = … M T K S`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OneShape;
/// The full S2.20 with a shape matrix per channel.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Full;

impl sealed::Sealed for Scalar {}
impl sealed::Sealed for OneShape {}
impl sealed::Sealed for Full {}
impl PolarizationModel for Scalar {
    const LEVEL: PolarizationLevel = PolarizationLevel::Scalar;
}
impl PolarizationModel for OneShape {
    const LEVEL: PolarizationLevel = PolarizationLevel::OneShape;
}
impl PolarizationModel for Full {
    const LEVEL: PolarizationLevel = PolarizationLevel::Full;
}

/// How the kernel treats spatial coherence (a model level).
///
/// The weights are computed as logarithms (`ln K`, `ln K^spec`): the kernel combines them with
/// the Stokes vector's own magnitude before anything is exponentiated, so a weight far below
/// the smallest number of the type still weighs a bright packet (module docs, "Numerics").
pub trait CoherenceModel: sealed::Sealed + Copy + Default {
    /// Whether the packet's shape matrices enter at all.
    const USES_SHAPE: bool;

    /// `ln K` of the scattered-channel weight `K` (see the module formula); `−∞` where `K = 0`.
    #[must_use]
    fn log_scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
        psd: &P,
        blur: &B,
        xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
    ) -> T;

    /// `ln K^spec` of the specular-channel weight (`−∞` for a plane wave, whose lobe is a
    /// delta).
    #[must_use]
    fn log_specular_weight<T: Real>(xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T;

    /// The scattered-channel weight `K` itself (`exp(ln K)` by default; the models of this
    /// crate override it with the cheaper linear forms, 0 where `K` underflows).
    #[inline]
    #[must_use]
    fn scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
        psd: &P,
        blur: &B,
        xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
    ) -> T {
        Self::log_scatter_weight(psd, blur, xi, h_t).exp()
    }

    /// The specular-channel weight `K^spec = exp(ln K^spec)` (0 for a plane wave).
    #[inline]
    #[must_use]
    fn specular_weight<T: Real>(xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        Self::log_specular_weight(xi, h_t).exp()
    }
}

/// The fully coherent (plane-wave) limit: `K = 2π p(h_t)`; the classical BRDF.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PlaneWave;
/// Partial coherence, S2.20: `K = 2π |Σ|^{1/2} (p * g^Ξ)(h_t)`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Partial;
/// The incoherent limit: `K = |Σ|^{1/2} g^Ξ(h_t) ∫p`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Incoherent;

impl sealed::Sealed for PlaneWave {}
impl sealed::Sealed for Partial {}
impl sealed::Sealed for Incoherent {}

/// `ln 2π`.
#[inline]
fn ln_two_pi<T: Real>() -> T {
    T::lit(core::f64::consts::TAU.ln())
}

/// `ln` of the smallest positive subnormal number of `T` (`ln(ε · MIN_POSITIVE)`).
#[inline]
fn ln_smallest_subnormal<T: Real>() -> f64 {
    (T::EPSILON.to_f64() * T::MIN_POSITIVE.to_f64()).ln()
}

/// `−∞` (the logarithm of a zero weight).
#[inline]
fn neg_infinity<T: Real>() -> T {
    -T::MAX * T::lit(2.0)
}

/// `ln(2π |Σ|^{1/2} g^Ξ(h)) = ln 2π + ln g^Ξ(h) − ½ ln|Ξ|` (the smooth-surface lobe).
#[inline]
fn log_smooth_lobe<T: Real>(xi: &Gaussian<T, 2>, h_t: &Vector2<T>) -> T {
    ln_two_pi::<T>() + xi.log_value(h_t) - T::lit(0.5) * xi.log_det()
}

impl CoherenceModel for PlaneWave {
    const USES_SHAPE: bool = false;
    #[inline]
    fn log_scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
        psd: &P,
        _blur: &B,
        _xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
    ) -> T {
        ln_two_pi::<T>() + psd.log_value(h_t)
    }
    #[inline]
    fn log_specular_weight<T: Real>(_xi: Option<&Gaussian<T, 2>>, _h_t: &Vector2<T>) -> T {
        neg_infinity()
    }
    #[inline]
    fn scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
        psd: &P,
        _blur: &B,
        _xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
    ) -> T {
        T::two_pi() * psd.value(h_t)
    }
}

impl CoherenceModel for Partial {
    const USES_SHAPE: bool = true;
    #[inline]
    fn log_scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
        psd: &P,
        blur: &B,
        xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
    ) -> T {
        match xi {
            // K = 2π |Σ|^{1/2} (p * g^Ξ)(h) with |Σ| = 1/|Ξ|: 2π times the normalised blur,
            // which never forms the tiny (p * g^Ξ) of a wide coherence area.
            Some(xi) => ln_two_pi::<T>() + blur.log_normalized_blur(psd, xi, h_t),
            None => ln_two_pi::<T>() + psd.log_value(h_t),
        }
    }
    #[inline]
    fn scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
        psd: &P,
        blur: &B,
        xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
    ) -> T {
        match xi {
            Some(xi) => T::two_pi() * blur.normalized_blur(psd, xi, h_t),
            None => T::two_pi() * psd.value(h_t),
        }
    }
    #[inline]
    fn log_specular_weight<T: Real>(xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        xi.map_or(neg_infinity(), |xi| log_smooth_lobe(xi, h_t))
    }
}

impl CoherenceModel for Incoherent {
    const USES_SHAPE: bool = true;
    #[inline]
    fn log_scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
        psd: &P,
        _blur: &B,
        xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
    ) -> T {
        match xi {
            Some(xi) => log_smooth_lobe(xi, h_t) + psd.integral().ln() - ln_two_pi::<T>(),
            None => ln_two_pi::<T>() + psd.log_value(h_t),
        }
    }
    #[inline]
    fn scatter_weight<T: Real, P: Psd<T, 2>, B: BlurMethod<T, 2, P>>(
        psd: &P,
        _blur: &B,
        xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
    ) -> T {
        match xi {
            Some(xi) => log_smooth_lobe(xi, h_t).exp() * psd.integral() / T::two_pi(),
            None => T::two_pi() * psd.value(h_t),
        }
    }
    #[inline]
    fn log_specular_weight<T: Real>(xi: Option<&Gaussian<T, 2>>, h_t: &Vector2<T>) -> T {
        xi.map_or(neg_infinity(), |xi| log_smooth_lobe(xi, h_t))
    }
}

/// A rough surface: the PSD of its height field, the pBSDF of its mean (specular) interface
/// and the pBSDF of its first-order scattering — the material `(p, M)` of the paper.
#[derive(Debug, Clone, PartialEq)]
pub struct RoughSurface<P, Sp, Sc> {
    /// The height PSD `p` (unitary transform; `R(0) = σ²` the squared rms height).
    pub psd: P,
    /// The specular pBSDF (e.g. [`FresnelReflection`]).
    pub specular: Sp,
    /// The scattering pBSDF (e.g. [`RayleighRice`], [`PhaseScreen`]).
    pub scatter: Sc,
}

/// The kernel's answer for one exit direction: Stokes radiances in the exit s/p frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Response<T: Real> {
    /// The coherent specular (direct) lobe, attenuation included.
    pub specular: Stokes<T>,
    /// The scattered (diffuse) part, attenuation included.
    pub scattered: Stokes<T>,
    /// The roughness (Debye–Waller) attenuation `α` applied to both parts.
    pub attenuation: T,
}

impl<T: Real> Response<T> {
    /// `specular + scattered`.
    #[must_use]
    pub fn total(&self) -> Stokes<T> {
        Stokes(self.specular.0 + self.scattered.0)
    }
}

/// The S2.20 kernel at a chosen model level (`Pol`, `Coh`) with blur method `B`.
///
/// # Examples
/// ```
/// use gmueller::frame::Frame;
/// use gmueller::interaction::{Full, Geometry, Kernel, Partial, FresnelReflection, RayleighRice, RoughSurface};
/// use gmueller::packet::{CoherenceShape, WavePacket};
/// use gmueller::psd::{ClosedForm, GaussianPsd};
/// use gmueller::stokes::Stokes;
/// use nalgebra::Vector3;
/// use num_complex::Complex;
///
/// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
/// let travel = Vector3::new(0.5_f64, 0.0, -(0.75_f64).sqrt()); // 30° incidence
/// let frame = Frame::sp(travel, Vector3::z()).unwrap();
/// let packet = WavePacket::from_stokes(
///     Stokes::unpolarized(1.0).unwrap(),
///     CoherenceShape::isotropic(10.0).unwrap(), frame, 0.5).unwrap();
/// let glass = Complex::new(1.5, 0.0);
/// let material = RoughSurface {
///     psd: GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap(), // σ = 10 nm, ℓ = 2 µm
///     specular: FresnelReflection::new(glass).unwrap(),
///     scatter: RayleighRice::new(glass).unwrap(),
/// };
/// let kernel = Kernel::<Full, Partial, ClosedForm>::new(ClosedForm);
/// let exit = Vector3::new(0.6, 0.1, 0.79);
/// let g = Geometry::new(packet.wavenumber(), &surface, -travel, exit).unwrap();
/// let r = kernel.evaluate(&material, &packet, &g);
/// assert!(r.scattered.s0() > 0.0 && r.scattered.s0().is_finite());
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Kernel<Pol, Coh, B> {
    blur: B,
    _levels: PhantomData<(Pol, Coh)>,
}

impl<Pol: PolarizationModel, Coh: CoherenceModel, B> Kernel<Pol, Coh, B> {
    /// A kernel that blurs non-Gaussian PSDs with `blur`.
    #[must_use]
    pub fn new(blur: B) -> Self {
        Self {
            blur,
            _levels: PhantomData,
        }
    }

    /// The blur method.
    #[must_use]
    pub fn blur_method(&self) -> &B {
        &self.blur
    }

    /// Evaluates S2.20 for `packet` leaving along `g.exit` (see the module formula).
    ///
    /// `g` must have been built for this packet: `g.k` its wavenumber and `g.to_source` its
    /// reversed propagation direction (e.g. by [`Geometry::for_packet`]). For several exit
    /// directions of one packet, [`Kernel::prepare`] once and [`Kernel::evaluate_prepared`]
    /// per direction give the same result without repeating the per-packet work.
    #[must_use]
    pub fn evaluate<T, P, Sp, Sc>(
        &self,
        material: &RoughSurface<P, Sp, Sc>,
        packet: &WavePacket<T>,
        g: &Geometry<T>,
    ) -> Response<T>
    where
        T: Real,
        P: Psd<T, 2>,
        B: BlurMethod<T, 2, P>,
        Sp: Pbsdf<T>,
        Sc: Pbsdf<T>,
    {
        let prepared = PreparedPacket::new(packet, &g.surface, &g.incident_sp);
        self.evaluate_prepared(material, &prepared, g)
    }

    /// The per-packet part of the kernel at this model level — the sections `Ξ_α` of the
    /// packet's coherence by the surface (Cholesky-factored) and the rotation `T` from the
    /// packet frame to the incident s/p frame — computed once for any number of exit
    /// directions ([`Kernel::evaluate_prepared`]).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when the packet does not travel toward the surface
    /// (`k̂ · n̂ ≥ 0`), as [`Geometry::for_packet`] would report for every exit direction.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Full, Geometry, Kernel, Partial, PhaseScreen, RoughSurface};
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::psd::{ClosedForm, GaussianPsd};
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    ///
    /// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// let travel = Vector3::new(0.5_f64, 0.0, -(0.75_f64).sqrt());
    /// let packet = WavePacket::from_stokes(
    ///     Stokes::unpolarized(1.0).unwrap(), CoherenceShape::isotropic(3.0).unwrap(),
    ///     Frame::sp(travel, Vector3::z()).unwrap(), 0.5).unwrap();
    /// let material = RoughSurface {
    ///     psd: GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap(),
    ///     specular: PhaseScreen::new(0.04).unwrap(),
    ///     scatter: PhaseScreen::new(0.04).unwrap(),
    /// };
    /// let kernel = Kernel::<Full, Partial, ClosedForm>::new(ClosedForm);
    /// let prepared = kernel.prepare(&packet, &surface).unwrap();
    /// for exit in [Vector3::new(0.5, 0.0, 0.87), Vector3::new(0.3, 0.2, 0.93)] {
    ///     let g = Geometry::for_packet(&packet, &surface, exit).unwrap();
    ///     let once = kernel.evaluate(&material, &packet, &g).total().s0();
    ///     let many = kernel.evaluate_prepared(&material, &prepared, &g).total().s0();
    ///     assert!((once - many).abs() <= 1e-12 * once);
    /// }
    /// ```
    pub fn prepare<T: Real>(
        &self,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
    ) -> Result<PreparedPacket<T, Pol, Coh>, Error> {
        let to_source = geometry::unit(-packet.direction(), "direction to the source")?;
        let (_, incident_sp) = geometry::incidence(&to_source, surface)?;
        Ok(PreparedPacket::new(packet, surface, &incident_sp))
    }

    /// [`Kernel::evaluate`] with the per-packet work done by [`Kernel::prepare`]; `g` must be
    /// a geometry of that packet on that surface (e.g. [`Geometry::for_packet`]).
    #[must_use]
    pub fn evaluate_prepared<T, P, Sp, Sc>(
        &self,
        material: &RoughSurface<P, Sp, Sc>,
        prepared: &PreparedPacket<T, Pol, Coh>,
        g: &Geometry<T>,
    ) -> Response<T>
    where
        T: Real,
        P: Psd<T, 2>,
        B: BlurMethod<T, 2, P>,
        Sp: Pbsdf<T>,
        Sc: Pbsdf<T>,
    {
        let psd = &material.psd;
        // ln(α/λ²), λ = 2π/k: 2 ln k − 2 ln 2π − (vσ)². The factor cos θ_o ∈ (0, 1] multiplies
        // the Stokes vector instead (one logarithm less per exit; it cannot underflow it).
        let v = g.k * (g.cos_i + g.cos_o);
        let ln_alpha = -(v * v) * psd.variance();
        let attenuation = ln_alpha.exp();
        let ln_front = prepared.two_ln_k_over_2pi + ln_alpha;
        // The scattered part at the one-weight levels: the linear weight (one exponential) where
        // it and the whole scale S0 α K/λ² are safely normal, the log form otherwise.
        let one_weight_scatter = |u: Vector4<T>| {
            let kd = Coh::scatter_weight(psd, &self.blur, prepared.sections[2].as_ref(), &g.h_t);
            match prepared.linear_scale(kd, attenuation) {
                Some(e) => u * e,
                None => {
                    let ld = ln_front
                        + Coh::log_scatter_weight(
                            psd,
                            &self.blur,
                            prepared.sections[2].as_ref(),
                            &g.h_t,
                        );
                    if prepared.is_dark(ld) {
                        Vector4::zeros()
                    } else {
                        prepared.scaled(u, ld)
                    }
                }
            }
        };
        let log_weights = |xi: &Option<Gaussian<T, 2>>| {
            (
                Coh::log_specular_weight(xi.as_ref(), &g.h_t),
                Coh::log_scatter_weight(psd, &self.blur, xi.as_ref(), &g.h_t),
            )
        };
        let [xi_x, xi_y, xi_half] = &prepared.sections;
        let zero = Stokes(Vector4::zeros());
        match Pol::LEVEL {
            PolarizationLevel::Scalar => {
                // Off the specular lobe (and always for a plane wave) its weight is 0.
                let ls = ln_front + Coh::log_specular_weight(xi_half.as_ref(), &g.h_t);
                let s0 = |m00: T| Vector4::new(m00 * g.cos_o, T::zero(), T::zero(), T::zero());
                Response {
                    specular: if prepared.is_dark(ls) {
                        zero
                    } else {
                        Stokes(prepared.scaled(s0(material.specular.m00(g)), ls))
                    },
                    scattered: Stokes(one_weight_scatter(s0(material.scatter.m00(g)))),
                    attenuation,
                }
            }
            PolarizationLevel::Full if Coh::USES_SHAPE => {
                let ((xs, xd), (ys, yd), (hs, hd)) =
                    (log_weights(xi_x), log_weights(xi_y), log_weights(xi_half));
                let spec = prepared.channel_mix(xs, ys, hs);
                let scat = prepared.channel_mix(xd, yd, hd);
                self.finish(
                    material,
                    g,
                    prepared,
                    (spec.0, ln_front + spec.1),
                    (scat.0, ln_front + scat.1),
                    attenuation,
                )
            }
            // OneShape, and Full without shapes (the three channels' weights are then one and
            // the same): M T S K.
            PolarizationLevel::OneShape | PolarizationLevel::Full => {
                let ls = ln_front + Coh::log_specular_weight(xi_half.as_ref(), &g.h_t);
                let t = prepared.t_stokes * g.cos_o;
                let specular = if Coh::USES_SHAPE && !prepared.is_dark(ls) {
                    prepared.scaled(material.specular.mueller(g).0 * t, ls)
                } else {
                    Vector4::zeros()
                };
                Response {
                    specular: Stokes(specular),
                    scattered: Stokes(one_weight_scatter(material.scatter.mueller(g).0 * t)),
                    attenuation,
                }
            }
        }
    }

    /// `M · v cos θ_o · e^{ln_e} · S0` for the specular and scattered parts: `v` is the
    /// effective (normalised, valid) Stokes vector in the incident s/p frame and `ln_e` the
    /// logarithm of the remaining scalar factor, applied last ([`PreparedPacket::scaled`]).
    fn finish<T: Real, P, Sp: Pbsdf<T>, Sc: Pbsdf<T>>(
        &self,
        material: &RoughSurface<P, Sp, Sc>,
        g: &Geometry<T>,
        prepared: &PreparedPacket<T, Pol, Coh>,
        (spec_in, spec_ln): (Vector4<T>, T),
        (scat_in, scat_ln): (Vector4<T>, T),
        attenuation: T,
    ) -> Response<T> {
        // Off the specular lobe its weight underflows: skip the specular pBSDF there.
        let specular = if Coh::USES_SHAPE && !prepared.is_dark(spec_ln) {
            prepared.scaled(
                material.specular.mueller(g).0 * (spec_in * g.cos_o),
                spec_ln,
            )
        } else {
            Vector4::zeros()
        };
        let scattered = if prepared.is_dark(scat_ln) {
            Vector4::zeros()
        } else {
            prepared.scaled(material.scatter.mueller(g).0 * (scat_in * g.cos_o), scat_ln)
        };
        Response {
            specular: Stokes(specular),
            scattered: Stokes(scattered),
            attenuation,
        }
    }
}

/// The per-packet part of a [`Kernel`] at model level (`Pol`, `Coh`), from [`Kernel::prepare`].
///
/// Holds the packet's Stokes vector normalised by `S0` with the logarithms of its channel
/// intensities (for the log-space channel mix of [`Full`]), the rotation `T` (S2.4) from the
/// packet frame to the incident s/p frame, and the surface sections `Ξ_α` of the channels the
/// level uses (none for [`PlaneWave`]; `Ξ_½` only below [`Full`]), each with its Cholesky
/// factor. No heap allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedPacket<T: Real, Pol, Coh> {
    /// `S0` and `ln S0` (−∞ for a dark packet).
    s0: T,
    ln_s0: T,
    /// `1/λ² = (k/2π)²`.
    inv_lambda_sq: T,
    /// `ln(smallest subnormal) − ln S0`: a part whose `ln_e` lies below is 0.
    dark_below: T,
    /// `2 ln(k/2π) = −2 ln λ`.
    two_ln_k_over_2pi: T,
    /// `ln(S_x/S0)`, `ln(S_y/S0)`, `ln(|S2 + iS3|/(2 S0))` (−∞ where 0).
    ln_sx: T,
    ln_sy: T,
    ln_c: T,
    /// `(S2, S3)/|S2 + iS3|`, the phase of `μ` (0 where `S2 = S3 = 0`).
    phase: (T, T),
    t: Matrix4<T>,
    /// `T S/S0`.
    t_stokes: Vector4<T>,
    /// `Ξ_x`, `Ξ_y`, `Ξ_½` (`None` where unused or not positive definite).
    sections: [Option<Gaussian<T, 2>>; 3],
    _levels: PhantomData<(Pol, Coh)>,
}

impl<T: Real, Pol: PolarizationModel, Coh: CoherenceModel> PreparedPacket<T, Pol, Coh> {
    fn new(packet: &WavePacket<T>, surface: &Frame<T>, incident_sp: &Frame<T>) -> Self {
        let section = |channel| {
            if Coh::USES_SHAPE {
                surface_inverse_coherence(packet, channel, surface)
            } else {
                None
            }
        };
        let sections = match Pol::LEVEL {
            PolarizationLevel::Full if Coh::USES_SHAPE => [
                section(Channel::X),
                section(Channel::Y),
                section(Channel::Half),
            ],
            _ => [None, None, section(Channel::Half)],
        };
        let stokes = packet.stokes().0;
        let s0 = stokes[0];
        let hat = if s0 > T::zero() {
            stokes / s0
        } else {
            Vector4::zeros()
        };
        let t = match Pol::LEVEL {
            PolarizationLevel::Scalar => Matrix4::identity(),
            _ => frame_change_mueller(packet.frame(), incident_sp).0,
        };
        // The channel intensities in log form, for the Full level's channel mix only.
        let (ln_sx, ln_sy, ln_c, phase) =
            if matches!(Pol::LEVEL, PolarizationLevel::Full) && Coh::USES_SHAPE {
                let half = T::lit(0.5);
                let c = hat[2].hypot(hat[3]);
                let phase = if c > T::zero() {
                    (hat[2] / c, hat[3] / c)
                } else {
                    (T::zero(), T::zero())
                };
                (
                    ((hat[0] + hat[1]) * half).ln(),
                    ((hat[0] - hat[1]) * half).ln(),
                    (c * half).ln(),
                    phase,
                )
            } else {
                (T::zero(), T::zero(), T::zero(), (T::zero(), T::zero()))
            };
        let k = packet.wavenumber();
        let ln_s0 = s0.ln();
        let k_over_2pi = k / T::two_pi();
        Self {
            s0,
            ln_s0,
            inv_lambda_sq: k_over_2pi * k_over_2pi,
            dark_below: T::lit(ln_smallest_subnormal::<T>()) - ln_s0,
            two_ln_k_over_2pi: T::lit(2.0) * (k.ln() - ln_two_pi::<T>()),
            ln_sx,
            ln_sy,
            ln_c,
            phase,
            t,
            t_stokes: t * hat,
            sections,
            _levels: PhantomData,
        }
    }

    /// The [`Full`] level's effective Stokes vector `T v̂` (normalised) and the logarithm of
    /// its scale, from the channel weights `ln K_x`, `ln K_y`, `ln K_½`:
    /// ```text
    /// a_x = ln(K_x S_x/S0),  a_y = ln(K_y S_y/S0),  a_½ = min(ln(K_½ |S2+iS3|/(2S0)), ½(a_x + a_y))
    /// m = max(a_x, a_y),     r_α = e^{a_α − m}
    /// v̂ = (r_x + r_y, r_x − r_y, 2 r_½ cos arg μ, 2 r_½ sin arg μ),     v = S0 e^{m} v̂
    /// ```
    /// The `min` is the Cauchy–Schwarz inequality of the weights, `K_½² |μ|² ≤ K_x K_y`, which
    /// the exact S2.20 satisfies for every realizable packet (module docs of
    /// [`crate::packet`]: at every spatial frequency the spectral matrix is positive
    /// semidefinite, and K is its average against `p ≥ 0`); it makes `v̂` a valid Stokes vector
    /// by construction, `(r_x − r_y)² + 4 r_½² ≤ (r_x + r_y)²`. Where the computed weights
    /// break the inequality — rounding of nearly proportional shapes in `f32`, or per-channel
    /// quadrature errors of [`crate::psd::GaussHermite`] — it lowers `K_½` by no more than their
    /// own error: the exact weights satisfy it.
    #[inline]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN maximum must take the dark branch too"
    )]
    fn channel_mix(&self, lx: T, ly: T, lh: T) -> (Vector4<T>, T) {
        let ax = lx + self.ln_sx;
        let ay = ly + self.ln_sy;
        let ah = (lh + self.ln_c).min((ax + ay) * T::lit(0.5));
        let m = ax.max(ay);
        if !(m > neg_infinity()) {
            return (Vector4::zeros(), neg_infinity());
        }
        let rel = |a: T| if a == m { T::one() } else { (a - m).exp() };
        let (rx, ry, rh) = (rel(ax), rel(ay), rel(ah));
        let two_rh = rh * T::lit(2.0);
        let v = Vector4::new(
            rx + ry,
            rx - ry,
            two_rh * self.phase.0,
            two_rh * self.phase.1,
        );
        (self.t * v, m)
    }

    /// `S0 α K/λ²` when the weight `K` lies in [1e-30, 1e30] (so it has not lost digits to
    /// underflow) and the product is a normal number: the linear form of the scale of a
    /// one-weight part. `None` otherwise (the caller then takes the log form).
    #[inline]
    fn linear_scale(&self, weight: T, attenuation: T) -> Option<T> {
        if !crate::gaussian::in_normal_range(weight) {
            return None;
        }
        // Every partial product normal too: a subnormal one would keep only a few digits.
        let normal = |x: T| x >= T::MIN_POSITIVE && x <= T::MAX;
        let p = weight * attenuation * self.inv_lambda_sq;
        let e = p * self.s0;
        (normal(p) && normal(e)).then_some(e)
    }

    /// `true` when `S0 e^{ln_e}` is below the smallest subnormal number, so that the part is 0
    /// (the pBSDF need not be evaluated).
    #[inline]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN exponent must count as dark too"
    )]
    fn is_dark(&self, ln_e: T) -> bool {
        !(ln_e >= self.dark_below)
    }

    /// `u · S0 e^{ln_e}`, the scalar applied once at the end.
    ///
    /// When `S0 e^{ln_e}` is not a normal number, the magnitude of `u` is folded into the
    /// exponent first: `(u/u₀) · exp(ln_e + ln S0 + ln u₀)`. Every entry then rounds once, so a
    /// result that underflows into the subnormal range keeps its degree of polarization
    /// (`|u_pol|/u₀`), and one whose factors are below the smallest number of the type (a far
    /// tail of a bright packet) is not lost.
    #[inline]
    fn scaled(&self, u: Vector4<T>, ln_e: T) -> Vector4<T> {
        // exp(ln_e) · S0 would round exp(ln_e) first, with a subnormal's few digits when the
        // weight is tiny and S0 bright: one exponential of the sum instead.
        let e = (ln_e + self.ln_s0).exp();
        if (e >= T::MIN_POSITIVE && e <= T::MAX) || u[0] <= T::zero() {
            u * e
        } else {
            // An overflow stays an overflow (±∞), but an entry that is exactly 0 stays 0 rather
            // than becoming 0 · ∞ = NaN.
            let e = (ln_e + self.ln_s0 + u[0].ln()).exp();
            (u / u[0]).map(|x| if x == T::zero() { x } else { x * e })
        }
    }
}

impl<T: Real> Geometry<T> {
    /// The geometry of `packet` (its wavenumber, ŝ = −k̂) leaving along `exit`.
    ///
    /// # Errors
    /// As [`Geometry::new`].
    pub fn for_packet(
        packet: &WavePacket<T>,
        surface: &Frame<T>,
        exit: Vector3<T>,
    ) -> Result<Self, Error> {
        Self::new(packet.wavenumber(), surface, -packet.direction(), exit)
    }
}

/// The Debye–Waller roughness attenuation `α = exp(−(k σ (cos θ_i + cos θ_o))²)`, `σ² = R(0)`.
///
/// For a height field `z` the phase imprinted on reflection is `v z` with
/// `v = k (cos θ_i + cos θ_o)`, and for Gaussian heights `⟨e^{iv(z₁ − z₂)}⟩ = α e^{v² R(ξ)}`:
/// `α` is the coherent (specular) fraction; its first-order companion `α v² R(ξ)` is the
/// scattered part, so both carry `α` and their sum `α (1 + v²σ²) ≤ 1` conserves energy.
#[must_use]
pub fn roughness_attenuation<T: Real, P: Psd<T, 2>>(psd: &P, g: &Geometry<T>) -> T {
    let v = g.k * (g.cos_i + g.cos_o);
    (-(v * v) * psd.variance()).exp()
}

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
    Partial::scatter_weight(psd, blur, xi.as_ref(), h_t)
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
    Ok(blur.normalized_blur(psd, &xi, h) * crate::psd::two_pi_pow_half_n::<T>(3))
}
