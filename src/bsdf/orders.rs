//! The scattered lobes beyond first order: the Kirchhoff series' orders as a finite mixture of
//! widened lobes, and the projected-disk lobe that keeps every direction drawable.
//!
//! # Formula
//! For a Gaussian PSD of spectral covariance `C_p` the series' scattered part is, as a function
//! of `h_t` (`crate::interaction::roughness::KirchhoffSeries`; `Ξ` the section of the coherence, 0
//! for a plane wave; the incoherent level has the single lobe `𝒩(0, Ξ)` at every roughness level),
//! ```text
//! Σ_{n≥1} (w_n(g)/g) K[p_n](h_t) ∝ Σ_{n≥1} w_n(g) 𝒩(h_t; 0, n C_p + Ξ),    w_n = e^{−g} gⁿ/n!,  g = (vσ)²
//! ```
//! with `g` varying over the exit directions through `v`. The proposal fixes `g` at its value
//! `g₀` at the side's specular direction (`h_t = 0`: `v = 2k cos θ` in reflection,
//! `k_a cos θ_a − k_b cos θ_b` in transmission, the phase factor of the part probabilities)
//! and groups the Poisson orders `n ≥ 1` (probabilities `w_n/(1 − e^{−g₀})`) into at most
//! [`ORDER_LOBES`] bins of about equal mass (a bin is closed once the cumulative mass passes its
//! share and its own mass is at least `1/(4·ORDER_LOBES)`; the last takes the rest, up to
//! `n = g₀ + 8√g₀ + 8`); each bin becomes one lobe of its mean order `n̄_j`:
//! ```text
//! p_h(h_t) = Σ_j P_j 𝒩(h_t; 0, n̄_j C_p + Ξ)
//! ```
//! Above `g₀ = 40` the orders are `𝒩(g₀, g₀)` to within the bins' width, and the bins are the
//! six equal-mass bins of that normal, at their conditional means `g₀ + √g₀ m_j`. Every scale
//! is capped where the lobe's standard deviation would pass twice the diameter of the
//! propagating disk (there it is flat on the disk anyway). At `g₀ → 0` the mixture is the single
//! first-order lobe `𝒩(0, C_p + Ξ)`; at `g₀ ≫ 1` it is the geometric level's slope lobe
//! `𝒩(0, g₀ C_p + Ξ)`. Any such mixture is exact to draw from and has the density above: it
//! needs only to resemble the kernel, not equal it.
//!
//! # The disk lobe (PSDs without a series lobe)
//! For the PSDs whose orders have no lobe here (Gaussian mixtures, the K-correlation: the
//! quadrature level), the scattered part draws the first-order lobes (too narrow once
//! `vσ ≳ 1`) and, with probability [`DISK_SHARE`], a uniform point of the side's projected disk
//! (`p_ω = cos θ/π`), so that every propagating direction keeps a density of at least
//! `DISK_SHARE · P_part cos θ/π` however wide the kernel's lobe grows. The Gaussian series'
//! lobes have no disk lobe: they cover ℝ², and a disk share only adds a variance floor (the
//! furnace of `tests/bsdf/rough.rs` measured the relative standard error at `vσ = 1`, normal
//! incidence: 5.5·10⁻⁶ without it, 2.0·10⁻⁴ with a share of 1 %, 4.5·10⁻⁴ with 5 %; no case
//! improved with it).

use nalgebra::{Matrix2, Vector2};

use super::lobes::GaussLobe;
use crate::real::Real;

/// The most lobes the orders are grouped into.
pub(crate) const ORDER_LOBES: usize = 6;

/// The share of the projected-disk lobe in the scattered part beyond first order, for PSDs
/// without a series lobe (module docs).
pub(crate) const DISK_SHARE: f64 = 0.25;

/// From this `g₀` on, the orders are grouped as the normal `𝒩(g₀, g₀)`.
const NORMAL_FROM: f64 = 40.0;

/// The conditional means `m_j = 6 (φ(z_j) − φ(z_{j+1}))` of the six equal-mass bins of the
/// standard normal (`z_j = Φ⁻¹(j/6)`; checked by quadrature in the tests below).
const NORMAL_BIN_MEANS: [f64; ORDER_LOBES] = [
    -1.499_105_643_684_260_2,
    -0.682_493_004_367_646_4,
    -0.212_055_034_356_689_5,
    0.212_055_034_356_689_5,
    0.682_493_004_367_646_4,
    1.499_105_643_684_260_2,
];

/// The orders `n ≥ 1` of a Poisson distribution of mean `g₀`, grouped into bins `(probability,
/// mean order)` (module docs), with their count. `g₀ ≤ 0` or NaN gives the first order alone.
#[expect(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "a NaN must give the first order"
)]
pub(crate) fn poisson_orders(g0: f64) -> ([(f64, f64); ORDER_LOBES], usize) {
    let mut out = [(0.0, 1.0); ORDER_LOBES];
    if !(g0 > 1e-12) {
        out[0] = (1.0, 1.0);
        return (out, 1);
    }
    if g0 >= NORMAL_FROM {
        let share = 1.0 / ORDER_LOBES as f64;
        let sd = g0.sqrt();
        for (o, m) in out.iter_mut().zip(NORMAL_BIN_MEANS) {
            *o = (share, g0 + sd * m);
        }
        return (out, ORDER_LOBES);
    }
    let last = (g0 + 8.0 * g0.sqrt() + 8.0).ceil() as u64;
    let min_mass = 0.25 / ORDER_LOBES as f64;
    // P(n = 1 | n ≥ 1) = g₀ e^{−g₀}/(1 − e^{−g₀}).
    let mut p = g0 / g0.exp_m1();
    let (mut count, mut mass, mut moment, mut cum) = (0usize, 0.0, 0.0, 0.0);
    for n in 1..=last {
        let nf = n as f64;
        if n > 1 {
            p *= g0 / nf;
        }
        mass += p;
        moment += p * nf;
        cum += p;
        let share = (count + 1) as f64 / ORDER_LOBES as f64;
        let close = count + 1 < ORDER_LOBES && cum >= share && mass >= min_mass;
        if (close || n == last) && mass > 0.0 {
            out[count] = (mass, moment / mass);
            count += 1;
            mass = 0.0;
            moment = 0.0;
        }
    }
    let total: f64 = out[..count].iter().map(|(w, _)| w).sum();
    for o in &mut out[..count] {
        o.0 /= total;
    }
    (out, count)
}

/// The series' lobes of one side: `(P_j, 𝒩(0, n̄_j C_p + Ξ))` (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OrderLobes<T: Real> {
    /// `(P_j, lobe)`; the first `count` are the mixture.
    pub(crate) lobes: [(T, GaussLobe<T>); ORDER_LOBES],
    pub(crate) count: usize,
}

impl<T: Real> OrderLobes<T> {
    /// The lobes of a Gaussian PSD of spectral covariance `cp`, blurred by `blur`, for the
    /// series at `g0` on a side whose propagating disk has radius `k` (its wavenumber); `None`
    /// when a covariance over- or underflows.
    pub(crate) fn new(g0: T, cp: &Matrix2<T>, blur: Option<&Matrix2<T>>, k: T) -> Option<Self> {
        let (orders, count) = poisson_orders(g0.to_f64());
        // The cap on the scale: the lobe's standard deviation (along C_p's trace) at 4k.
        let cap = (T::lit(16.0) * k * k / (cp[(0, 0)] + cp[(1, 1)])).to_f64();
        let first = GaussLobe::new(Vector2::zeros(), &blur.map_or(*cp, |b| cp + b))?;
        let mut lobes = [(T::zero(), first); ORDER_LOBES];
        for (l, (w, n)) in lobes.iter_mut().zip(&orders[..count]) {
            let c = cp * T::lit(n.min(cap).max(1.0));
            *l = (
                T::lit(*w),
                GaussLobe::new(Vector2::zeros(), &blur.map_or(c, |b| c + b))?,
            );
        }
        Some(Self { lobes, count })
    }

    /// A draw: `v` in `[0, 1)` chooses the lobe, `u` the point.
    #[inline]
    pub(crate) fn sample(&self, v: T, u: [T; 2]) -> Vector2<T> {
        let mut acc = T::zero();
        for (w, l) in &self.lobes[..self.count - 1] {
            acc += *w;
            if v < acc {
                return l.sample(u);
            }
        }
        self.lobes[self.count - 1].1.sample(u)
    }

    /// `Σ_j P_j 𝒩(h; 0, n̄_j C_p + Ξ)`.
    #[inline]
    pub(crate) fn density(&self, h: &Vector2<T>) -> T {
        self.lobes[..self.count]
            .iter()
            .fold(T::zero(), |a, (w, l)| a + *w * l.density(h))
    }

    /// The narrowest standard deviation of the lobes (a lower bound, [`GaussLobe::narrowest`]).
    pub(crate) fn narrowest(&self) -> T {
        self.lobes[..self.count]
            .iter()
            .fold(T::MAX, |a, (_, l)| a.min(l.narrowest()))
    }
}

/// A uniform point of the unit disk from two uniforms in `[0, 1)` (radius `√u₀`).
#[inline]
pub(crate) fn disk_point<T: Real>(u: [T; 2]) -> Vector2<T> {
    let r = u[0].max(T::zero()).sqrt();
    let (s, c) = (T::two_pi() * u[1]).sin_cos();
    Vector2::new(r * c, r * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hard-coded conditional means of the normal's equal-mass bins, against a midpoint
    /// quadrature of `∫ z φ(z) dz` over each bin, the bins' edges found by bisection of the
    /// quadrature's own CDF.
    #[test]
    fn normal_bin_means_match_quadrature() {
        let phi = |z: f64| (-0.5 * z * z).exp() / core::f64::consts::TAU.sqrt();
        let (lo, hi, n) = (-12.0, 12.0, 2_400_000);
        let dz = (hi - lo) / n as f64;
        let mut bins = [(0.0, 0.0); ORDER_LOBES];
        let mut cum = 0.0;
        for i in 0..n {
            let z = lo + (i as f64 + 0.5) * dz;
            let p = phi(z) * dz;
            let j = ((cum + 0.5 * p) * ORDER_LOBES as f64).floor() as usize;
            let j = j.min(ORDER_LOBES - 1);
            bins[j].0 += p;
            bins[j].1 += p * z;
            cum += p;
        }
        for (j, (m, zm)) in bins.iter().enumerate() {
            let mean = zm / m;
            assert!(
                (mean - NORMAL_BIN_MEANS[j]).abs() < 1e-5,
                "bin {j}: {mean} vs {}",
                NORMAL_BIN_MEANS[j]
            );
        }
    }

    /// The grouped orders keep the Poisson distribution's mass (1) and mean (`g₀/(1 − e^{−g₀})`
    /// given `n ≥ 1`) for `g₀` from 10⁻⁹ to 10⁴, and the first order alone at 0.
    #[test]
    fn poisson_orders_keep_mass_and_mean() {
        for g0 in [1e-9, 1e-3, 0.1, 1.0, 3.0, 10.0, 39.0, 40.0, 100.0, 1e4] {
            let (o, n) = poisson_orders(g0);
            assert!((1..=ORDER_LOBES).contains(&n), "g₀ {g0}: {n} lobes");
            let mass: f64 = o[..n].iter().map(|x| x.0).sum();
            let mean: f64 = o[..n].iter().map(|x| x.0 * x.1).sum();
            let want = g0 / (-(-g0).exp_m1());
            assert!((mass - 1.0).abs() < 1e-12, "g₀ {g0}: mass {mass}");
            assert!(
                (mean / want - 1.0).abs() < 1e-9,
                "g₀ {g0}: mean {mean} vs {want}"
            );
            assert!(o[..n].iter().all(|x| x.0 > 0.0 && x.1 >= 1.0));
        }
        assert_eq!(poisson_orders(0.0).1, 1);
        assert_eq!(poisson_orders(f64::NAN).0[0], (1.0, 1.0));
    }
}
