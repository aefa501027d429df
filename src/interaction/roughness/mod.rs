//! The roughness levels of the kernel (a model level): how the phase `v z` that the heights
//! imprint on the light enters the scattered part — at first order, as the whole Kirchhoff
//! series, or in its geometric-optics limit.
//!
//! # Formula
//! With `C = cos θ_o/λ_t²`, `M` the scattering pBSDF, `T` the rotation to the incident s/p
//! frame, `K[q]` the coherence level's weight of a PSD `q` ([`CoherenceWeights`]: `2π q(h_t)`,
//! the blurred `2π (q * 𝒩_Ξ)(h_t)`, or the incoherent one), `g = (vσ)²` and the Poisson weights
//! `w_n = e^{−g} gⁿ/n!`:
//! ```text
//! FirstOrder:       L_scat = C α M T K[p]                              α = e^{−g}
//! KirchhoffSeries:  L_scat = C M T Σ_{n≥1} (w_n/g) K[p_n]              p_n = F{σ² ρⁿ}
//! Geometric:        L_scat = C M T ((1 − e^{−g})/g) K[p_g]             (the single power n = g)
//! ```
//! (`ρ = R/σ²`; [`CorrelationPowers`]). Why: for Gaussian heights the phase screen's two-point
//! average is `⟨e^{iv(z₁ − z₂)}⟩ = e^{−g} e^{g ρ(ξ)} = e^{−g} + Σ_{n≥1} w_n ρⁿ(ξ)`, so its spectrum
//! is the coherent `e^{−g}` (the specular part, unchanged at every level) plus
//! `Σ w_n F{ρⁿ} = (v²/g) Σ w_n p_n`; the `v²` is the pBSDF's ([`super::pbsdf::PhaseScreen`]:
//! `M = |r|² v² I₄`). The `n = 1` term is `α v² p`: **the first-order kernel is exactly the
//! series' first term**, so the series is a strict extension (`w_1/g = α`). Where `g → ∞` the
//! weights concentrate at `n ≈ g ± √g` and the sum tends to its single term `n = g`, the
//! spectrum of `e^{−g(1 − ρ)} ≈ ρ^g`: for Gaussian `ρ` a Gaussian of slope covariance `σ²Λ⁻¹`
//! (`σ²/ℓ²` per axis), the Beckmann slope distribution; its weight `(1 − e^{−g})/g` keeps the
//! diffuse power at `1 − α`. The levels agree on the specular part `C α M_spec T K^spec`.
//!
//! Every term is blurred by the packet's coherence through the same S2.20 machinery (the
//! coherence level's weight of the term's PSD, for every channel of the polarization level),
//! and the series is summed in log space, so `e^{−g}` far below the range of `T` and `gⁿ/n!`
//! far above it never meet.
//!
//! Here: the level markers [`FirstOrder`] (the kernel's default), [`KirchhoffSeries`],
//! [`Geometric`] and [`KirchhoffQuadrature`], their traits ([`RoughnessModel`], the weights
//! [`RoughnessWeights`]) and values ([`RoughnessLevel`]; the run-time selector with parameters is
//! [`super::Roughness`]), what the series returns (its sum and the orders summed, [`SeriesSum`]), and the Debye–Waller
//! attenuation `α` of the specular part ([`roughness_attenuation`]).
//!
//! # Truncation (the tolerance of [`KirchhoffSeries`])
//! The terms `t_n = (w_n/g) K[p_n]` of a Gaussian PSD are log-concave in `n` for the plane-wave
//! and the partially coherent closed-form weights: `ln t_n = ln w_n − ½ ln|nΛ⁻¹ + Ξ| −
//! ½ h_tᵀ(nΛ⁻¹ + Ξ)⁻¹h_t + const`, whose second difference is at most
//! `ln[(n + 1)³/(n (n + 2)²)] < 0`. So the ratios `t_{n+1}/t_n` fall with `n`: the sum starts at
//! the largest term (found by bisection on the sign of `t_{n+1} − t_n`) and goes up and down
//! until the geometric bound on the rest, `t_n r/(1 − r)` with `r` the last ratio, is at most
//! `tolerance/2` of the partial sum on each side. The result is then within `tolerance` of the
//! whole series (relative), and the number of terms grows like `√g` around `n ≈ g` (`g ≫ 1`)
//! plus the bisection's `2 log₂ g` — see the guide `gmueller::guide::roughness` for measured counts and costs.
//! For the incoherent level every `K[p_n]` is the same (each `p_n` has the variance σ²), and
//! the sum is `K[p] (1 − e^{−g})/g` in closed form. For a Gaussian PSD with the plane-wave
//! weight or [`crate::psd::ClosedForm`]'s, every order's weight comes from one closed form,
//! `ln K[p_n] = ln 2πσ² − ½ ln(n²|A| + n tr(adj(A)Ξ) + |Ξ|) − ½ (n h_tᵀadj(A)h_t +
//! h_tᵀadj(Ξ)h_t)/(n²|A| + …)` (`A = Λ⁻¹`; every coefficient a sum of squares of Cholesky
//! products, evaluated in f64): one logarithm per order. Other blur methods
//! ([`crate::psd::BlurMethod::exact_for_gaussians`] false) blur a power per order. With a
//! quadrature blur the terms are log-concave only to the quadrature's accuracy, and so is the
//! bound.

#![expect(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "every guard must send a NaN down its zero or −∞ branch"
)]

mod quadrature;

pub use super::attenuation::roughness_attenuation;
pub use quadrature::KirchhoffQuadrature;

use core::fmt::Debug;

use nalgebra::{Matrix2, Vector2};

use super::coherence::{CoherenceLevel, CoherenceWeights, neg_infinity};
use super::geometry::Geometry;
use crate::error::Error;
use crate::gaussian::Gaussian;
use crate::psd::{CorrelationPowers, Psd};
use crate::real::Real;

pub(crate) mod sealed {
    pub trait Sealed {
        /// The Kirchhoff series' `(tolerance, geometric_from)` for the batch kernel's lanes
        /// (`interaction::batch::stages::series`); `None` at every other level.
        #[inline]
        fn lane_series(&self) -> Option<(f64, f64)> {
            None
        }
    }
}

/// The roughness levels, as values (for reports).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RoughnessLevel {
    /// First order in the heights (Born, Rayleigh–Rice): valid while `vσ ≲ 0.3`.
    FirstOrder,
    /// The Kirchhoff (phase-screen) series, to a tolerance: every `vσ`.
    KirchhoffSeries,
    /// The series' geometric-optics limit (the slope distribution): `vσ ≫ 1`.
    Geometric,
    /// The same phase screen as the series, by quadrature of its two-point integral: any PSD
    /// with a spatial autocorrelation (K-correlation, mixtures), every `vσ`.
    KirchhoffQuadrature,
}

/// How the kernel treats the heights' phase (a model level, see the module formula).
pub trait RoughnessModel: sealed::Sealed + Clone + Debug {
    /// Which level.
    const LEVEL: RoughnessLevel;
    /// `true` when the level's scattered weights carry the roughness attenuation themselves
    /// (the series: `Σ (w_n/g) K[p_n]`), so the kernel does not apply `α` to them again.
    const CARRIES_ATTENUATION: bool;
}

/// The scattered-part weights of a roughness level for a PSD `P` and a coherence level `Coh`.
///
/// `xi` is the section of the coherence as the PSD sees it (mirrored for light from below, as
/// the kernel passes it), `g` the geometry (its [`Geometry::phase_factor`] `v` and the PSD's
/// `h_t`).
pub trait RoughnessWeights<T: Real, P: Psd<T, 2>, Coh: CoherenceWeights<T, P>>:
    RoughnessModel
{
    /// `ln` of the weight: `ln K[p]` at first order, `ln Σ (w_n/g) K[p_n]` for the series, and
    /// so on (module formula); `−∞` where it is 0.
    #[must_use]
    fn log_scatter_weight(
        &self,
        coherence: &Coh,
        psd: &P,
        xi: Option<&Gaussian<T, 2>>,
        g: &Geometry<T>,
    ) -> T;

    /// The weight itself: `exp(ln K̃)` by default (0 or `∞` out of range); first order
    /// overrides it with the coherence level's cheaper linear form.
    #[inline]
    #[must_use]
    fn scatter_weight(
        &self,
        coherence: &Coh,
        psd: &P,
        xi: Option<&Gaussian<T, 2>>,
        g: &Geometry<T>,
    ) -> T {
        self.log_scatter_weight(coherence, psd, xi, g).exp()
    }
}

/// First order in the heights (the crate's kernel before the series; the default):
/// `L_scat = C α M T K[p]`. With [`super::pbsdf::RayleighRice`] the Rayleigh–Rice (Born) level,
/// with [`super::pbsdf::PhaseScreen`] the first term of the Kirchhoff series. Valid while
/// `vσ ≲ 0.3`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FirstOrder;

/// The Kirchhoff (phase-screen) series of a surface with Gaussian heights, summed to a relative
/// `tolerance` (module docs, "Truncation"), optionally replaced by its geometric-optics limit
/// where `g = (vσ)²` reaches [`KirchhoffSeries::geometric_from`].
///
/// # Examples
/// ```
/// use gmueller::frame::Frame;
/// use gmueller::interaction::{Geometry, Intensity, Kernel, Partial, RoughSurface};
/// use gmueller::interaction::pbsdf::PhaseScreen;
/// use gmueller::interaction::roughness::{FirstOrder, KirchhoffSeries};
/// use gmueller::packet::{CoherenceShape, WavePacket};
/// use gmueller::psd::GaussianPsd;
/// use gmueller::stokes::Stokes;
/// use nalgebra::Vector3;
///
/// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
/// let travel = Vector3::new(0.5, 0.0, -(0.75_f64).sqrt());
/// let packet = WavePacket::from_stokes(Stokes::unpolarized(1.0)?,
///     CoherenceShape::isotropic(2.0)?, Frame::sp(travel, Vector3::z())?, 0.5)?;
/// let screen = |sigma: f64| -> Result<_, gmueller::Error> { Ok(RoughSurface {
///     psd: GaussianPsd::<f64, 2>::isotropic(sigma, 1.0)?,
///     specular: PhaseScreen::new(1.0)?, scatter: PhaseScreen::new(1.0)? }) };
/// let g = Geometry::for_packet(&packet, &surface, Vector3::new(0.6, 0.1, 0.79))?;
/// let first = Kernel::<Intensity, Partial>::default();
/// let series = Kernel::<Intensity, Partial, KirchhoffSeries>::default();
/// // Smooth (vσ ≈ 0.01): the series is the first-order kernel.
/// let (a, b) = (first.evaluate(&screen(0.0005)?, &packet, &g).scattered,
///     series.evaluate(&screen(0.0005)?, &packet, &g).scattered);
/// assert!((a / b - 1.0).abs() < 1e-4);
/// // Rough (vσ ≈ 1): the higher orders carry the wide-angle light that first order misses.
/// let (a, b) = (first.evaluate(&screen(0.04)?, &packet, &g).scattered,
///     series.evaluate(&screen(0.04)?, &packet, &g).scattered);
/// assert!(b > 1.2 * a);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KirchhoffSeries {
    tolerance: f64,
    geometric_from: f64,
}

/// The geometric-optics limit of the Kirchhoff series (`vσ ≫ 1`): the single power `n = g`,
/// `L_scat = C M T ((1 − e^{−g})/g) K[p_g]` — for a Gaussian PSD the Beckmann slope
/// distribution of covariance `σ²Λ⁻¹`, blurred by the coherence. Its relative error against
/// the series falls like `1/g` in the lobe (measured in `tests/interaction/roughness/series.rs`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Geometric;

impl sealed::Sealed for FirstOrder {}
impl sealed::Sealed for KirchhoffSeries {
    #[inline]
    fn lane_series(&self) -> Option<(f64, f64)> {
        Some((self.tolerance, self.geometric_from))
    }
}
impl sealed::Sealed for Geometric {}

impl RoughnessModel for FirstOrder {
    const LEVEL: RoughnessLevel = RoughnessLevel::FirstOrder;
    const CARRIES_ATTENUATION: bool = false;
}
impl RoughnessModel for KirchhoffSeries {
    const LEVEL: RoughnessLevel = RoughnessLevel::KirchhoffSeries;
    const CARRIES_ATTENUATION: bool = true;
}
impl RoughnessModel for Geometric {
    const LEVEL: RoughnessLevel = RoughnessLevel::Geometric;
    const CARRIES_ATTENUATION: bool = true;
}

impl<T: Real, P: Psd<T, 2>, Coh: CoherenceWeights<T, P>> RoughnessWeights<T, P, Coh>
    for FirstOrder
{
    #[inline]
    fn log_scatter_weight(
        &self,
        coherence: &Coh,
        psd: &P,
        xi: Option<&Gaussian<T, 2>>,
        g: &Geometry<T>,
    ) -> T {
        coherence.log_scatter_weight(psd, xi, &g.psd_h())
    }
    #[inline]
    fn scatter_weight(
        &self,
        coherence: &Coh,
        psd: &P,
        xi: Option<&Gaussian<T, 2>>,
        g: &Geometry<T>,
    ) -> T {
        coherence.scatter_weight(psd, xi, &g.psd_h())
    }
}

/// The default tolerance of [`KirchhoffSeries`].
const DEFAULT_TOLERANCE: f64 = 1e-6;

/// The measured bound on the geometric limit's relative error in the lobe, times `g`: the
/// largest `|series/geometric − 1|` where the series is at least 1 % of its peak is
/// `2.1/g … 2.2/g` for `g` from 10 to 1000, plane wave and partially coherent
/// (`tests/interaction/roughness/series.rs`, `series_large_g_limit_is_the_geometric_level`);
/// rounded up.
pub(crate) const GEOMETRIC_ERROR_TIMES_G: f64 = 2.5;

/// Beyond this `g` the series is never summed (the geometric limit is used whatever the
/// tolerance: its error is then below `2.5·10⁻⁷` in the lobe, and the series would need more
/// than `4·10⁴` orders).
pub(crate) const SERIES_MAX_G: f64 = 1e7;

/// The largest order the series visits (a guard against non-finite input; above
/// [`SERIES_MAX_G`] + 20√g).
const MAX_ORDER: u64 = 1 << 24;

impl Default for KirchhoffSeries {
    /// Tolerance 10⁻⁶ (the geometric limit from `g = 2.5·10⁶`, [`KirchhoffSeries::new`]).
    fn default() -> Self {
        Self {
            tolerance: DEFAULT_TOLERANCE,
            geometric_from: GEOMETRIC_ERROR_TIMES_G / DEFAULT_TOLERANCE,
        }
    }
}

impl KirchhoffSeries {
    /// The series summed to the relative `tolerance` (module docs, "Truncation"), replaced by
    /// its geometric-optics limit where that is within the tolerance in the lobe: from
    /// `g = 2.5/tolerance` (the limit's measured error is at most `2.2/g` where the lobe is above
    /// 1 % of its peak; in the far tails it is larger). There the series would cost `~12√g`
    /// orders, the limit one. [`KirchhoffSeries::with_geometric_from`] moves the switch (`+∞`:
    /// never, up to `g = 10⁷`, beyond which the limit is always used: its error is then below
    /// `2.5·10⁻⁷`).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `0 < tolerance < 1`.
    pub fn new(tolerance: f64) -> Result<Self, Error> {
        if !(tolerance > 0.0 && tolerance < 1.0) {
            return Err(Error::OutOfRange {
                what: "Kirchhoff series tolerance",
                value: tolerance,
                expected: "(0, 1)",
            });
        }
        Ok(Self {
            tolerance,
            geometric_from: GEOMETRIC_ERROR_TIMES_G / tolerance,
        })
    }

    /// The series, replaced by its geometric-optics limit ([`Geometric`]) where `g = (vσ)² ≥
    /// g_from` (`+∞`: only beyond `g = 10⁷`). The limit's error falls like `1/g` in the lobe and
    /// is larger in the far tails (measured in `tests/interaction/roughness/series.rs`); it costs
    /// one term instead of `~12√g`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `g_from > 0` (NaN is refused; `+∞` is allowed).
    pub fn with_geometric_from(self, g_from: f64) -> Result<Self, Error> {
        if !(g_from > 0.0) {
            return Err(Error::OutOfRange {
                what: "Kirchhoff series switch to the geometric limit, g",
                value: g_from,
                expected: "(0, ∞]",
            });
        }
        Ok(Self {
            geometric_from: g_from,
            ..self
        })
    }

    /// The relative tolerance.
    #[must_use]
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The `g = (vσ)²` from which the geometric limit is used (`+∞`: never).
    #[must_use]
    pub fn geometric_from(&self) -> f64 {
        self.geometric_from
    }

    /// The series' weight `Σ_{n≥1} (w_n/g) K[p_n]` at `h_t` for the phase factor `v`, with the
    /// orders it summed (module docs, "Truncation"): what the kernel computes for the
    /// scattered part below the switch to the geometric limit, for studies of the truncation
    /// and its cost. The switch ([`KirchhoffSeries::geometric_from`]) is not applied here,
    /// except beyond `g = 10⁷`, where the geometric limit is returned (`first = last = 0`).
    ///
    /// # Formula
    /// ```text
    /// ln Σ_{n = first}^{last} (w_n/g) K[p_n],   w_n = e^{−g} gⁿ/n!,   g = (vσ)²
    /// ```
    #[must_use]
    pub fn sum<T, P, Coh>(
        &self,
        coherence: &Coh,
        psd: &P,
        xi: Option<&Gaussian<T, 2>>,
        h_t: &Vector2<T>,
        v: T,
    ) -> SeriesSum<T>
    where
        T: Real,
        P: CorrelationPowers<T>,
        Coh: CoherenceWeights<T, P> + CoherenceWeights<T, P::Power>,
    {
        let g = ((v * v) * psd.variance()).to_f64();
        if g >= SERIES_MAX_G {
            return SeriesSum {
                log_weight: geometric_log_weight(coherence, psd, xi, h_t, v),
                first: 0,
                last: 0,
            };
        }
        if matches!(Coh::LEVEL, CoherenceLevel::Incoherent) {
            return SeriesSum {
                log_weight: coherence.log_scatter_weight(psd, xi, h_t)
                    + T::lit(ln_diffuse_fraction_over_g(g)),
                first: 1,
                last: 1,
            };
        }
        Terms::new(coherence, psd, xi, h_t, g).sum(self.tolerance)
    }
}

/// What [`KirchhoffSeries::sum`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeriesSum<T> {
    /// `ln Σ (w_n/g) K[p_n]` (`−∞` where the sum is 0).
    pub log_weight: T,
    /// The lowest order summed.
    pub first: u64,
    /// The highest order summed.
    pub last: u64,
}

impl<T: Real> SeriesSum<T> {
    /// The number of orders summed.
    #[must_use]
    pub fn terms(&self) -> u64 {
        self.last + 1 - self.first
    }
}

/// `ln((1 − e^{−g})/g)`, `0` at `g = 0` (the diffuse fraction of the phase screen, per `g`).
fn ln_diffuse_fraction_over_g(g: f64) -> f64 {
    if g < 1e-8 {
        -0.5 * g
    } else {
        (-(-g).exp_m1()).ln() - g.ln()
    }
}

/// `n!` for `n ≤ 20` (exact in f64: below 2⁵³ up to 18!, and 19!, 20! are even multiples
/// whose rounding is below 10⁻¹⁶ relative).
const FACTORIALS: [f64; 21] = [
    1.0,
    1.0,
    2.0,
    6.0,
    24.0,
    120.0,
    720.0,
    5040.0,
    40320.0,
    362880.0,
    3628800.0,
    39916800.0,
    479001600.0,
    6227020800.0,
    87178291200.0,
    1307674368000.0,
    20922789888000.0,
    355687428096000.0,
    6402373705728000.0,
    121645100408832000.0,
    2432902008176640000.0,
];

/// `ln n!`: one logarithm of the exact factorial for `n ≤ 20`, Stirling's series beyond
/// (`x = n + 1 ≥ 22`: the first neglected term, `1/(1188 x⁹)`, is below 10⁻¹⁵).
pub(crate) fn ln_factorial(n: u64) -> f64 {
    if n <= 20 {
        return FACTORIALS[n as usize].ln();
    }
    let x = (n + 1) as f64;
    let (r, r2) = (x.recip(), x.recip() * x.recip());
    (x - 0.5) * x.ln() - x
        + 0.5 * core::f64::consts::TAU.ln()
        + r * (1.0 / 12.0 - r2 * (1.0 / 360.0 - r2 * (1.0 / 1260.0 - r2 / 1680.0)))
}

/// `ln K[p_n]` of a Gaussian PSD for every order `n` at once, for the plane-wave and the
/// closed-form partially coherent weights (in f64):
/// ```text
/// ln K[p_n] = ln 2π + ln σ² − ½ ln|nA + Ξ| − ½ h_tᵀ(nA + Ξ)⁻¹h_t          (A = Λ⁻¹, Ξ = 0: plane wave)
/// |nA + Ξ| = n² |A| + n tr(adj(A) Ξ) + |Ξ|,   h_tᵀ adj(nA + Ξ) h_t = n h_tᵀadj(A)h_t + h_tᵀadj(Ξ)h_t
/// ```
/// (2×2 identities; `adj(M) = J M Jᵀ`, `J` the quarter turn). Every coefficient is a sum of
/// squares from the Cholesky factors — `|A| = (L₁₁L₂₂)²`, `tr(adj(A)Ξ) = ‖L_Ξᵀ J L_A‖²`,
/// `h_tᵀadj(A)h_t = |L_Aᵀ Jᵀ h_t|²` — so nothing cancels, even for the ill-conditioned sections
/// of grazing incidence. One logarithm per order instead of a blur.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GaussianTerms {
    pub(crate) ln_front: f64,
    pub(crate) d2: f64,
    pub(crate) d1: f64,
    pub(crate) d0: f64,
    c1: f64,
    c0: f64,
}

impl GaussianTerms {
    pub(crate) fn new<T: Real>(
        sigma2: T,
        la: &Matrix2<T>,
        xi: Option<&Gaussian<T, 2>>,
        h: &Vector2<T>,
    ) -> Option<Self> {
        let la = la.map(|x| x.to_f64());
        let lx = xi.map_or(Matrix2::zeros(), |x| {
            x.cholesky_factor().map(|v| v.to_f64())
        });
        let h = h.map(|x| x.to_f64());
        let j = Matrix2::new(0.0, 1.0, -1.0, 0.0);
        let jh = j.transpose() * h;
        let out = Self {
            ln_front: core::f64::consts::TAU.ln() + sigma2.to_f64().ln(),
            d2: (la[(0, 0)] * la[(1, 1)]).powi(2),
            d1: (lx.transpose() * j * la).norm_squared(),
            d0: (lx[(0, 0)] * lx[(1, 1)]).powi(2),
            c1: (la.transpose() * jh).norm_squared(),
            c0: (lx.transpose() * jh).norm_squared(),
        };
        let ok = [out.d2, out.d1, out.d0, out.c1, out.c0]
            .iter()
            .all(|x| x.is_finite())
            && out.d2 > 0.0
            && out.ln_front.is_finite();
        ok.then_some(out)
    }

    /// `ln K[p_n]`.
    #[inline]
    fn ln_k(&self, n: f64) -> f64 {
        let det = (n * self.d2 + self.d1) * n + self.d0;
        self.ln_front - 0.5 * det.ln() - 0.5 * (n * self.c1 + self.c0) / det
    }
}

/// The terms `ln t_n = ln(w_n/g) + ln K[p_n]` of one evaluation, with a two-entry memory (the
/// bisection and the sum ask for neighbours).
///
/// The terms, the search for the largest and the sum are in `f64` whatever `T` (only the
/// final logarithm is rounded to `T`): in the far tails of a long-correlated surface the
/// logarithms reach ~10⁶ (ℓ ≈ 10⁷ λ, `vσ` ≈ 70, 0.5° off the specular direction: −1.24·10⁶),
/// where an `f32` spacing of 0.125 is wider than the step between neighbouring orders — the
/// mode search stopped on a plateau of equal rounded terms thousands of orders below the
/// largest, and the sum, relative to that term, overflowed to `+∞` (issue 36).
struct Terms<'a, T: Real, P, Coh> {
    coherence: &'a Coh,
    psd: &'a P,
    xi: Option<&'a Gaussian<T, 2>>,
    h_t: &'a Vector2<T>,
    g: f64,
    ln_g: f64,
    memo: [(u64, f64); 2],
    next: usize,
    /// The closed form of every order's weight, where the PSD is a Gaussian and the
    /// coherence weight its closed form.
    gaussian: Option<GaussianTerms>,
}

impl<'a, T, P, Coh> Terms<'a, T, P, Coh>
where
    T: Real,
    P: CorrelationPowers<T>,
    Coh: CoherenceWeights<T, P> + CoherenceWeights<T, P::Power>,
{
    fn new(
        coherence: &'a Coh,
        psd: &'a P,
        xi: Option<&'a Gaussian<T, 2>>,
        h_t: &'a Vector2<T>,
        g: f64,
    ) -> Self {
        Self {
            coherence,
            psd,
            xi,
            h_t,
            g,
            ln_g: g.ln(),
            memo: [(0, 0.0); 2],
            next: 0,
            gaussian: if CoherenceWeights::<T, P::Power>::closed_form_gaussian(coherence) {
                psd.gaussian_spectrum()
                    .and_then(|(s2, l)| GaussianTerms::new(s2, &l, xi, h_t))
            } else {
                None
            },
        }
    }

    /// `ln t_n` (`n ≥ 1`), in `f64`.
    fn at(&mut self, n: u64) -> f64 {
        if let Some(&(_, t)) = self.memo.iter().find(|(m, _)| *m == n) {
            return t;
        }
        let t = if let Some(gt) = &self.gaussian {
            let nf = n as f64;
            let lw = if n == 1 {
                -self.g
            } else {
                -self.g + (nf - 1.0) * self.ln_g - ln_factorial(n)
            };
            lw + gt.ln_k(nf)
        } else if n == 1 {
            // w_1/g = e^{−g} = α, and p_1 = p: the first-order term.
            -self.g
                + CoherenceWeights::<T, P>::log_scatter_weight(
                    self.coherence,
                    self.psd,
                    self.xi,
                    self.h_t,
                )
                .to_f64()
        } else {
            let nf = n as f64;
            // ln(w_n/g) = −g + (n − 1) ln g − ln n!, in f64 (the terms cancel to O(1) for g ≫ 1).
            let lw = -self.g + (nf - 1.0) * self.ln_g - ln_factorial(n);
            match self.psd.correlation_power(T::lit(nf)) {
                Some(p) => {
                    lw + CoherenceWeights::<T, P::Power>::log_scatter_weight(
                        self.coherence,
                        &p,
                        self.xi,
                        self.h_t,
                    )
                    .to_f64()
                }
                None => f64::NEG_INFINITY,
            }
        };
        self.memo[self.next] = (n, t);
        self.next ^= 1;
        t
    }

    /// `t_{n+1} > t_n` (false for NaN).
    fn rising(&mut self, n: u64) -> bool {
        let a = self.at(n);
        let b = self.at(n + 1);
        b > a
    }

    /// The order of the largest term: the smallest `n ≥ 1` with `t_{n+1} ≤ t_n` (the terms are
    /// log-concave, so the forward differences fall with `n`).
    fn mode(&mut self) -> u64 {
        if !(self.g > 0.0) {
            return 1;
        }
        let start = (self.g.floor() as u64).clamp(1, MAX_ORDER);
        let (mut lo, mut hi);
        if self.rising(start) {
            // Gallop up to a falling order, then bisect (lo rising, hi falling).
            lo = start;
            let mut step = 1;
            loop {
                hi = (lo + step).min(MAX_ORDER);
                if hi == MAX_ORDER || !self.rising(hi) {
                    break;
                }
                lo = hi;
                step *= 2;
            }
        } else {
            // Falling at `start`: the mode is in [1, start].
            if start == 1 || !self.rising(1) {
                return 1;
            }
            lo = 1;
            hi = start;
        }
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if self.rising(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// The sum to `tolerance` (module docs, "Truncation"), relative to the largest term met so
    /// far (the mode of the log-concave terms; should rounding of the terms put a larger one
    /// beside it, the sum is rescaled to that one instead of overflowing).
    fn sum(mut self, tolerance: f64) -> SeriesSum<T> {
        let m = self.mode();
        let t_mode = self.at(m);
        let mut tm = t_mode;
        if !(tm > f64::NEG_INFINITY) {
            return SeriesSum {
                log_weight: if tm < 0.0 { neg_infinity() } else { T::lit(tm) },
                first: m,
                last: m,
            };
        }
        let half_tol = 0.5 * tolerance;
        let mut s = 1.0_f64;
        // `s · e^{tm}` is the sum so far.
        let add = |t: f64, s: &mut f64, tm: &mut f64| -> f64 {
            if t > *tm {
                *s = *s * (*tm - t).exp() + 1.0;
                *tm = t;
                1.0
            } else {
                let rel = (t - *tm).exp();
                *s += rel;
                rel
            }
        };
        // Upward, then downward, each until the geometric bound on its rest is small.
        let (mut prev, mut n) = (tm, m);
        while n < MAX_ORDER {
            n += 1;
            let t = self.at(n);
            if !(t > f64::NEG_INFINITY) {
                break;
            }
            let rel = add(t, &mut s, &mut tm);
            let r = (t - prev).exp();
            if r < 1.0 && rel * r / (1.0 - r) <= half_tol * s {
                break;
            }
            prev = t;
        }
        let last = n;
        let (mut prev, mut n) = (t_mode, m);
        while n > 1 {
            n -= 1;
            let t = self.at(n);
            if !(t > f64::NEG_INFINITY) {
                break;
            }
            let rel = add(t, &mut s, &mut tm);
            let d = (t - prev).exp();
            if d < 1.0 && rel * d / (1.0 - d) <= half_tol * s {
                break;
            }
            prev = t;
        }
        SeriesSum {
            log_weight: T::lit(tm + s.ln()),
            first: n.min(m),
            last,
        }
    }
}

impl<T, P, Coh> RoughnessWeights<T, P, Coh> for KirchhoffSeries
where
    T: Real,
    P: CorrelationPowers<T>,
    Coh: CoherenceWeights<T, P> + CoherenceWeights<T, P::Power>,
{
    #[inline]
    fn log_scatter_weight(
        &self,
        coherence: &Coh,
        psd: &P,
        xi: Option<&Gaussian<T, 2>>,
        g: &Geometry<T>,
    ) -> T {
        let v = g.phase_factor();
        let gg = ((v * v) * psd.variance()).to_f64();
        if gg >= self.geometric_from || gg >= SERIES_MAX_G {
            return geometric_log_weight(coherence, psd, xi, &g.psd_h(), v);
        }
        self.sum(coherence, psd, xi, &g.psd_h(), v).log_weight
    }
}

/// `ln(((1 − e^{−g})/g) K[p_g])`, `g = (vσ)²` (the [`Geometric`] level; `−∞` at `g = 0`).
fn geometric_log_weight<T, P, Coh>(
    coherence: &Coh,
    psd: &P,
    xi: Option<&Gaussian<T, 2>>,
    h_t: &Vector2<T>,
    v: T,
) -> T
where
    T: Real,
    P: CorrelationPowers<T>,
    Coh: CoherenceWeights<T, P> + CoherenceWeights<T, P::Power>,
{
    let gt = (v * v) * psd.variance();
    let g = gt.to_f64();
    if !(g > 0.0) {
        return neg_infinity();
    }
    let front = T::lit(ln_diffuse_fraction_over_g(g));
    if matches!(Coh::LEVEL, CoherenceLevel::Incoherent) {
        // Every power has the variance σ²: the incoherent weight is K[p] for each.
        return front + CoherenceWeights::<T, P>::log_scatter_weight(coherence, psd, xi, h_t);
    }
    match psd.correlation_power(gt) {
        Some(p) => {
            front + CoherenceWeights::<T, P::Power>::log_scatter_weight(coherence, &p, xi, h_t)
        }
        None => neg_infinity(),
    }
}

impl<T, P, Coh> RoughnessWeights<T, P, Coh> for Geometric
where
    T: Real,
    P: CorrelationPowers<T>,
    Coh: CoherenceWeights<T, P> + CoherenceWeights<T, P::Power>,
{
    #[inline]
    fn log_scatter_weight(
        &self,
        coherence: &Coh,
        psd: &P,
        xi: Option<&Gaussian<T, 2>>,
        g: &Geometry<T>,
    ) -> T {
        geometric_log_weight(coherence, psd, xi, &g.psd_h(), g.phase_factor())
    }
}

#[cfg(test)]
mod tests {
    use super::ln_factorial;
    use crate::psd::special::ln_gamma;

    /// `ln n!` against the crate's Lanczos `ln Γ(n + 1)` (relative error ≈ 10⁻¹⁵) and, where
    /// both apply, against the sum of logarithms: 1e-13 relative from 0 to 10⁷.
    #[test]
    fn ln_factorial_matches_ln_gamma() {
        let mut sum = 0.0_f64;
        for n in 0..=2000u64 {
            if n > 0 {
                sum += (n as f64).ln();
            }
            let a = ln_factorial(n);
            assert!(
                (a - sum).abs() <= 1e-13 * sum.max(1.0),
                "n {n}: {a} vs Σ ln = {sum}"
            );
        }
        for n in [21u64, 22, 50, 1000, 123_456, 10_000_000] {
            let (a, b) = (ln_factorial(n), ln_gamma(n as f64 + 1.0));
            assert!((a - b).abs() <= 1e-13 * b, "n {n}: {a} vs lnΓ {b}");
        }
    }
}
