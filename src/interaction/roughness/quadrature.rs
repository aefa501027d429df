//! The Kirchhoff phase screen by quadrature of its two-point integral: the series of every
//! order at once, for any PSD whose autocorrelation is known in space (K-correlation,
//! Gaussian mixtures), to a tolerance.

use core::marker::PhantomData;

use nalgebra::{Matrix2, Vector2};

use super::{
    CoherenceLevel, CoherenceWeights, Geometry, RoughnessLevel, RoughnessModel, RoughnessWeights,
    neg_infinity, sealed,
};
use crate::error::Error;
use crate::gaussian::Gaussian;
use crate::numerics::GL8;
use crate::psd::Autocorrelation;
use crate::real::Real;

/// The Kirchhoff (phase-screen) scattered weight of any PSD with a spatial autocorrelation
/// ([`Autocorrelation`]: Gaussian, Gaussian mixtures, K-correlation of any γ), by direct
/// quadrature of the two-point integral to a relative `tolerance`: the same quantity as
/// [`super::KirchhoffSeries`] (all orders of `e^{gρ}`), without the series.
///
/// # Formula
/// ```text
/// K̃(h_t) = σ² ∫ e^{−g} (e^{gρ(ξ)} − 1)/g · c(ξ) · cos(h_t·ξ) d²ξ        g = (vσ)²
/// c(ξ) = exp(−½ ξᵀΞξ)  (partially coherent),   1  (plane wave)
/// incoherent:  K̃ = K[p] (1 − e^{−g})/g                                 (as the series)
/// ```
/// (`= Σ_n (w_n/g) K[p_n]` term by term; `Ξ` the section of the coherence by the surface; the
/// `Partial` level's blur method is not used: the coherence enters the integrand exactly.)
///
/// # Quadrature and accuracy
/// Polar coordinates about ξ = 0, where the integrand is smooth even for the exponential
/// correlation's cusp: in the angle the trapezoid rule on `[0, π)` (the integrand is even),
/// doubled until two successive sums agree to `tolerance/10`; in the radius composite
/// 8-point Gauss–Legendre on panels no wider than a quarter of the finest scale (the
/// oscillation `π/|h_t|`, the integrand's core where `g (1 − ρ)` reaches 1 — `ℓ/√g` for a
/// smooth ρ, `ℓ/g` at the exponential's cusp —, the coherence width; found by bisection on ρ),
/// doubled until two successive sums agree to `tolerance`, out to where the integrand's
/// envelope falls below `10⁻³ tolerance` of its peak. The tolerance is relative to the
/// integral of the envelope: in far tails, where the oscillation cancels most of it, the
/// relative error of `K̃` itself is larger (as for every quadrature blur). Cost: 10⁴–10⁵
/// integrand evaluations, about 2 ms for the exponential correlation at any `g` (measured for
/// g = 10⁻²…10⁸) and 15–20 ms for a K-correlation of non-half-integer `ν` (each ρ an integral,
/// [`crate::psd::matern`]) — a reference level; for Gaussian PSDs the series is exact and far
/// cheaper.
///
/// # Examples
/// ```
/// use gmueller::interaction::{Geometry, Intensity, Kernel, Partial, RoughSurface};
/// use gmueller::interaction::pbsdf::PhaseScreen;
/// use gmueller::interaction::roughness::{KirchhoffQuadrature, KirchhoffSeries};
/// # use gmueller::frame::Frame;
/// # use gmueller::packet::{CoherenceShape, WavePacket};
/// # use gmueller::stokes::Stokes;
/// # use nalgebra::Vector3;
/// use gmueller::psd::GaussianPsd;
/// # let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
/// # let travel = Vector3::new(0.5, 0.0, -(0.75_f64).sqrt());
/// # let packet = WavePacket::from_stokes(Stokes::unpolarized(1.0)?,
/// #     CoherenceShape::isotropic(1.5)?, Frame::sp(travel, Vector3::z())?, 0.5)?;
/// let m = RoughSurface { psd: GaussianPsd::<f64, 2>::isotropic(0.05, 1.0)?,
///     specular: PhaseScreen::new(1.0)?, scatter: PhaseScreen::new(1.0)? };
/// let g = Geometry::for_packet(&packet, &surface, Vector3::new(0.6, 0.1, 0.79))?;
/// let by_series = Kernel::<Intensity, Partial>::default()
///     .with_roughness(KirchhoffSeries::new(1e-9)?).evaluate(&m, &packet, &g).scattered;
/// let by_quadrature = Kernel::<Intensity, Partial>::default()
///     .with_roughness(KirchhoffQuadrature::new(1e-7)?).evaluate(&m, &packet, &g).scattered;
/// assert!((by_quadrature / by_series - 1.0).abs() < 1e-5);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KirchhoffQuadrature {
    tolerance: f64,
}

impl KirchhoffQuadrature {
    /// The quadrature to the relative `tolerance` (see the type docs).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `10⁻¹² ≤ tolerance < 1`.
    pub fn new(tolerance: f64) -> Result<Self, Error> {
        if !((1e-12..1.0).contains(&tolerance)) {
            return Err(Error::OutOfRange {
                what: "Kirchhoff quadrature tolerance",
                value: tolerance,
                expected: "[1e-12, 1)",
            });
        }
        Ok(Self { tolerance })
    }

    /// The relative tolerance.
    #[must_use]
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }
}

impl Default for KirchhoffQuadrature {
    /// Tolerance 10⁻⁶.
    fn default() -> Self {
        Self { tolerance: 1e-6 }
    }
}

impl sealed::Sealed for KirchhoffQuadrature {}

impl RoughnessModel for KirchhoffQuadrature {
    const LEVEL: RoughnessLevel = RoughnessLevel::KirchhoffQuadrature;
    const CARRIES_ATTENUATION: bool = true;
}

/// `ψ(ρ) = e^{−g} (e^{gρ} − 1)/g` (`ρ` at `g = 0`), without cancellation.
#[inline]
fn psi(g: f64, rho: f64) -> f64 {
    if g == 0.0 {
        return rho;
    }
    let x = g * rho;
    if x > 1.0 {
        ((-g * (1.0 - rho)).exp() - (-g).exp()) / g
    } else {
        (-g).exp() * x.exp_m1() / g
    }
}

/// The integral `∫ ψ(ρ(ξ)) c(ξ) cos(h·ξ) d²ξ` (module formula, without `σ²`).
struct Integrand<'a, T: Real, P> {
    psd: &'a P,
    g: f64,
    xi: Matrix2<f64>,
    h: Vector2<f64>,
    tolerance: f64,
    _real: PhantomData<T>,
}

impl<T: Real, P: Autocorrelation<T>> Integrand<'_, T, P> {
    fn at(&self, r: f64, phi: f64) -> f64 {
        let (s, c) = phi.sin_cos();
        let x = Vector2::new(r * c, r * s);
        let rho = self.psd.normalized_autocorrelation(&x.map(T::lit)).to_f64();
        let coherence = (-0.5 * x.dot(&(self.xi * x))).exp();
        psi(self.g, rho) * coherence * self.h.dot(&x).cos()
    }

    /// `∫₀^{2π} … dφ` at radius `r` (twice the trapezoid on `[0, π)`), doubled to convergence.
    fn ring(&self, r: f64) -> f64 {
        let mut m = 16usize;
        let mut sum: f64 = (0..m)
            .map(|j| self.at(r, core::f64::consts::PI * j as f64 / m as f64))
            .sum();
        let mut prev = sum * core::f64::consts::TAU / m as f64;
        while m < 1 << 16 {
            // The odd nodes of the doubled rule.
            let add: f64 = (0..m)
                .map(|j| {
                    self.at(
                        r,
                        core::f64::consts::PI * (2 * j + 1) as f64 / (2 * m) as f64,
                    )
                })
                .sum();
            sum += add;
            m *= 2;
            let now = sum * core::f64::consts::TAU / m as f64;
            let scale = (0..4)
                .map(|j| self.at(r, core::f64::consts::FRAC_PI_4 * j as f64).abs())
                .fold(now.abs(), f64::max);
            if (now - prev).abs() <= 0.1 * self.tolerance * scale {
                return now;
            }
            prev = now;
        }
        prev
    }

    /// `∫₀^R ring(r) r dr` on `panels` Gauss–Legendre panels.
    fn radial(&self, radius: f64, panels: usize) -> f64 {
        let w = radius / panels as f64;
        (0..panels)
            .map(|i| {
                let mid = w * (i as f64 + 0.5);
                GL8.iter()
                    .map(|(x, wt)| {
                        let r = mid + 0.5 * w * x;
                        wt * r * self.ring(r)
                    })
                    .sum::<f64>()
                    * 0.5
                    * w
            })
            .sum()
    }
}

/// The section as a 2×2 matrix (0 for a plane wave).
fn section_matrix<T: Real>(xi: Option<&Gaussian<T, 2>>) -> Matrix2<f64> {
    xi.map_or(Matrix2::zeros(), |x| x.covariance().map(|v| v.to_f64()))
}

/// The smallest radius at which `ρ ≤ level` along the axes and the diagonals (bisection on
/// ρ, which falls with the distance for the PSDs of this crate), from [`Autocorrelation::decay_radius`]
/// as the bracket; 0 where the bracket is not finite.
fn radius_where<T: Real, P: Autocorrelation<T>>(psd: &P, level: f64) -> f64 {
    let hi0 = psd
        .decay_radius(T::lit(level.clamp(1e-300, 1.0 - 1e-16)))
        .to_f64();
    if !(hi0 > 0.0 && hi0.is_finite()) {
        return 0.0;
    }
    let rho = |r: f64, phi: f64| {
        let x = Vector2::new(r * phi.cos(), r * phi.sin()).map(T::lit);
        psd.normalized_autocorrelation(&x).to_f64()
    };
    let mut out: f64 = 0.0;
    for k in 0..4 {
        let phi = core::f64::consts::FRAC_PI_4 * f64::from(k);
        let mut hi = hi0;
        // The bracket holds `ρ(hi) ≤ level` (decay_radius), widened if a direction needs it.
        let mut grow = 0;
        while rho(hi, phi) > level && grow < 60 {
            hi *= 2.0;
            grow += 1;
        }
        let mut lo = 0.0;
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if rho(mid, phi) > level {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-6 * hi {
                break;
            }
        }
        out = out.max(hi);
    }
    out
}

/// `ln K̃` by quadrature (see [`KirchhoffQuadrature`]).
fn log_weight<T: Real, P: Autocorrelation<T>>(
    tolerance: f64,
    psd: &P,
    xi: &Matrix2<f64>,
    h: Vector2<f64>,
    g: f64,
) -> T {
    let sigma2 = psd.variance().to_f64();
    if !(sigma2 > 0.0 && g.is_finite()) {
        return neg_infinity();
    }
    let eps = 1e-3 * tolerance;
    let ln_eps = -eps.ln();
    // Where ψ(ρ) falls below ε of its peak (1 − e^{−g})/g: ρ ≤ 1 − ln(1/ε)/g for large g,
    // ρ ≤ ε (e^g − 1)/g otherwise.
    let level = if g > ln_eps {
        1.0 - ln_eps / g
    } else {
        (eps * if g > 0.0 { g.exp_m1() / g } else { 1.0 }).min(0.5)
    };
    let r_rho = radius_where(psd, level);
    let e = xi.symmetric_eigen().eigenvalues;
    let (lmin, lmax) = (e.min().max(0.0), e.max().max(0.0));
    let r_coh = if lmin > 0.0 {
        (2.0 * ln_eps / lmin).sqrt()
    } else {
        f64::INFINITY
    };
    let radius = r_rho.min(r_coh);
    if !(radius > 0.0 && radius.is_finite()) {
        return neg_infinity();
    }
    // The finest radial scale: the integrand's core, where g (1 − ρ) reaches 1 (ℓ/√g for a
    // smooth ρ, ℓ/g at the exponential's cusp), the oscillation, the coherence width.
    let core = radius_where(psd, (1.0 - 1.0 / g.max(1.0)).max(0.5));
    let mut scale = core;
    if h.norm() > 0.0 {
        scale = scale.min(core::f64::consts::PI / h.norm());
    }
    if lmax > 0.0 {
        scale = scale.min(1.0 / lmax.sqrt());
    }
    let f = Integrand::<T, P> {
        psd,
        g,
        xi: *xi,
        h,
        tolerance,
        _real: PhantomData,
    };
    let mut panels = ((4.0 * radius / scale).ceil() as usize).clamp(4, 1 << 14);
    let mut prev = f.radial(radius, panels);
    let mut now = prev;
    for _ in 0..6 {
        panels *= 2;
        now = f.radial(radius, panels);
        let envelope = (1.0 - (-g).exp()) / g.max(1e-300) * core * core;
        if (now - prev).abs() <= tolerance * now.abs().max(1e-3 * envelope) {
            break;
        }
        prev = now;
    }
    if now > 0.0 {
        T::lit(now.ln() + sigma2.ln())
    } else {
        neg_infinity()
    }
}

impl<T, P, Coh> RoughnessWeights<T, P, Coh> for KirchhoffQuadrature
where
    T: Real,
    P: Autocorrelation<T>,
    Coh: CoherenceWeights<T, P>,
{
    fn log_scatter_weight(
        &self,
        coherence: &Coh,
        psd: &P,
        xi: Option<&Gaussian<T, 2>>,
        g: &Geometry<T>,
    ) -> T {
        let v = g.phase_factor();
        let gg = ((v * v) * psd.variance()).to_f64();
        let h = g.psd_h();
        match Coh::LEVEL {
            CoherenceLevel::Incoherent => {
                coherence.log_scatter_weight(psd, xi, &h)
                    + T::lit(super::ln_diffuse_fraction_over_g(gg))
            }
            CoherenceLevel::PlaneWave => log_weight(
                self.tolerance,
                psd,
                &Matrix2::zeros(),
                h.map(|x| x.to_f64()),
                gg,
            ),
            CoherenceLevel::Partial => log_weight(
                self.tolerance,
                psd,
                &section_matrix(xi),
                h.map(|x| x.to_f64()),
                gg,
            ),
        }
    }
}
