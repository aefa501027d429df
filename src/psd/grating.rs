//! Periodic gratings: diffraction orders with efficiencies, blurred into Gaussian lobes.

use nalgebra::SVector;

use super::{BlurMethod, ClosedForm, Psd};
use crate::error::Error;
use crate::gaussian::Gaussian;
use crate::real::Real;

/// Bessel functions `J_0(a), …, J_M(a)` of integer order (f64), by Miller's backward recurrence.
///
/// # Formula
/// ```text
/// J_{k−1}(a) = (2k/a) J_k(a) − J_{k+1}(a),    normalised by  J_0 + 2 Σ_{k≥1} J_{2k} = 1
/// ```
/// Started at an even index `K ≥ max(M, a) + 20 + √(40 max(M, a))` (Numerical Recipes'
/// `bessj` rule), rescaled to avoid overflow. `J_m(−a) = (−1)^m J_m(a)`. Accurate to ~1e-15
/// absolute for `|a| ≤ 10³`.
///
/// # Examples
/// ```
/// use gmueller::psd::bessel_j;
/// let j = bessel_j(2, 1.0);
/// // Abramowitz & Stegun, Table 9.1: J0(1), J1(1), J2(1).
/// assert!((j[0] - 0.7651976865579666).abs() < 1e-15);
/// assert!((j[1] - 0.4400505857449335).abs() < 1e-15);
/// assert!((j[2] - 0.1149034849319005).abs() < 1e-15);
/// ```
#[must_use]
pub fn bessel_j(max_order: usize, a: f64) -> Vec<f64> {
    let mut out = vec![0.0; max_order + 1];
    if !a.is_finite() {
        return out;
    }
    let x = a.abs();
    if x < 1e-5 {
        // Two series terms: J_m(x) = (x/2)^m/m! (1 − (x/2)²/(m+1) + …), error ~ x⁴ relative.
        let mut term = 1.0;
        for (m, v) in out.iter_mut().enumerate() {
            if m > 0 {
                term *= 0.5 * x / m as f64;
            }
            *v = term * (1.0 - 0.25 * x * x / (m + 1) as f64);
            if a < 0.0 && m % 2 == 1 {
                *v = -*v;
            }
        }
        return out;
    }
    let big = (max_order as f64).max(x);
    let mut k = (big + 20.0 + (40.0 * big).sqrt()) as usize;
    k += k % 2;
    let (mut jp, mut j) = (0.0_f64, 1e-300_f64); // J_{k+1}, J_k (arbitrary scale)
    let mut norm = 0.0_f64; // J_0 + 2 Σ J_{2i}, on the running scale
    for i in (1..=k).rev() {
        let jm = (2.0 * i as f64 / x) * j - jp;
        jp = j;
        j = jm; // now j = J_{i−1}
        let idx = i - 1;
        if idx <= max_order {
            out[idx] = j;
        }
        if idx % 2 == 0 && idx > 0 {
            norm += 2.0 * j;
        }
        if j.abs() > 1e250 {
            jp *= 1e-250;
            j *= 1e-250;
            norm *= 1e-250;
            for v in out.iter_mut() {
                *v *= 1e-250;
            }
        }
    }
    norm += j; // J_0
    for (m, v) in out.iter_mut().enumerate() {
        *v /= norm;
        if a < 0.0 && m % 2 == 1 {
            *v = -*v;
        }
    }
    out
}

/// Which diffraction orders a [`Grating`] keeps.
///
/// Rule: orders are taken in increasing `|m|` (both signs together), keeping only those with
/// `|ζ_m| ≤ max_frequency`, and the enumeration stops once the efficiency not yet kept,
/// `total − Σ_kept η`, is at most `tail`, or at `|m| = 100 000`. A typical `max_frequency` is `2k`
/// (every order that can reach a propagating direction for some incidence), `tail = 1e-12`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrderCutoff<T: Real> {
    /// Largest kept order frequency `|ζ_m|` (rad/length).
    pub max_frequency: T,
    /// Stop once the remaining efficiency is at most this.
    pub tail: T,
}

/// A periodic grating: `p = (2π)^{n/2} Σ_m η_m δ(ζ − ζ_m)`, blurred into Gaussian lobes.
///
/// # Formula
/// ```text
/// R(x) = Σ_m η_m e^{i ζ_m·x}  ⇒  p(ζ) = (2π)^{n/2} Σ_m η_m δ(ζ − ζ_m),   R(0) = Σ_m η_m
/// (p * g^Σ)(h) = Σ_m η_m g^Σ(h − ζ_m)
/// 1-D, period Λ, direction d̂:   ζ_m = m (2π/Λ) d̂
/// sinusoidal phase φ(x) = a sin(2πx/Λ):     η_m = J_m(a)²
/// binary phase, depth φ₀, duty D:           η_0 = 1 − 2D(1−D)(1 − cos φ₀),
///                                           η_m = 2(1 − cos φ₀) sin²(π m D)/(π m)²
/// crossed (two 1-D profiles added):        η_{m₁m₂} = η_{m₁} η_{m₂},  ζ = ζ_{m₁} + ζ_{m₂}
/// ```
/// `R` here is the correlation of the interface's reflection function `e^{iφ}`, so `Σ η_m = 1`
/// for a lossless phase grating; [`Psd::variance`] is the efficiency actually kept. [`Psd::value`]
/// (the continuous part) is 0; use [`ClosedForm`] to blur.
#[derive(Debug, Clone, PartialEq)]
pub struct Grating<T: Real, const N: usize> {
    orders: Vec<(SVector<T, N>, T)>,
    kept: T,
    dropped: T,
}

impl<T: Real, const N: usize> Grating<T, N> {
    fn from_efficiencies(
        period: T,
        direction: &SVector<T, N>,
        cutoff: OrderCutoff<T>,
        eta: impl Fn(usize) -> f64,
    ) -> Result<Self, Error> {
        if !(period.is_finite() && period > T::zero()) {
            return Err(Error::OutOfRange {
                what: "grating period",
                value: period.to_f64(),
                expected: "(0, ∞)",
            });
        }
        let norm = direction.norm();
        if !(norm.is_finite() && norm > T::zero()) {
            return Err(Error::InvalidBasis {
                reason: "grating direction must be a non-zero finite vector",
            });
        }
        if !(cutoff.max_frequency >= T::zero() && cutoff.tail >= T::zero()) {
            return Err(Error::OutOfRange {
                what: "order cutoff",
                value: cutoff.max_frequency.min(cutoff.tail).to_f64(),
                expected: "max_frequency ≥ 0 and tail ≥ 0",
            });
        }
        let g = direction / norm * (T::two_pi() / period);
        let gnorm = g.norm().to_f64();
        let mut orders = Vec::new();
        let mut kept = 0.0_f64;
        for m in 0..=100_000usize {
            let remaining = 1.0 - kept;
            if m > 0 && remaining <= cutoff.tail.to_f64() {
                break;
            }
            if m as f64 * gnorm > cutoff.max_frequency.to_f64() {
                break;
            }
            let e = eta(m);
            let signs: &[f64] = if m == 0 { &[1.0] } else { &[1.0, -1.0] };
            for &s in signs {
                if e <= 0.0 {
                    continue;
                }
                orders.push((g * T::lit(s * m as f64), T::lit(e)));
                kept += e;
            }
        }
        Ok(Self {
            kept: T::lit(kept),
            dropped: T::lit((1.0 - kept).max(0.0)),
            orders,
        })
    }

    /// A sinusoidal phase grating `φ(x) = a sin(2π d̂·x/Λ)`: `η_m = J_m(a)²`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a non-positive period, a non-finite `a` or a negative cutoff;
    /// [`Error::InvalidBasis`] for a zero direction.
    pub fn sinusoidal(
        period: T,
        direction: &SVector<T, N>,
        phase_amplitude: T,
        cutoff: OrderCutoff<T>,
    ) -> Result<Self, Error> {
        let a = phase_amplitude.to_f64();
        if !a.is_finite() || a.abs() > 1e4 {
            return Err(Error::OutOfRange {
                what: "phase amplitude",
                value: a,
                expected: "|a| ≤ 1e4",
            });
        }
        let period_f = period.to_f64();
        let mmax = if period_f > 0.0 {
            ((cutoff.max_frequency.to_f64() * period_f / core::f64::consts::TAU).min(1e5)) as usize
        } else {
            0
        };
        let j = bessel_j(mmax.min(a.abs() as usize + 200), a);
        Self::from_efficiencies(period, direction, cutoff, |m| {
            j.get(m).map_or(0.0, |v| v * v)
        })
    }

    /// A binary (rectangular) phase grating of depth `φ₀` and duty cycle `D ∈ (0, 1)`.
    ///
    /// # Errors
    /// As [`Grating::sinusoidal`], plus [`Error::OutOfRange`] for `D ∉ (0, 1)`.
    pub fn rectangular(
        period: T,
        direction: &SVector<T, N>,
        phase_depth: T,
        duty: T,
        cutoff: OrderCutoff<T>,
    ) -> Result<Self, Error> {
        let (p0, d) = (phase_depth.to_f64(), duty.to_f64());
        if !(d > 0.0 && d < 1.0 && p0.is_finite()) {
            return Err(Error::OutOfRange {
                what: "duty cycle",
                value: d,
                expected: "(0, 1), with a finite phase depth",
            });
        }
        let c = 1.0 - p0.cos();
        Self::from_efficiencies(period, direction, cutoff, |m| {
            if m == 0 {
                1.0 - 2.0 * d * (1.0 - d) * c
            } else {
                let x = core::f64::consts::PI * m as f64;
                2.0 * c * (x * d).sin().powi(2) / (x * x)
            }
        })
    }

    /// A crossed grating from two 1-D gratings (phase profiles added): orders are sums, efficiencies
    /// products. Orders whose product efficiency is below `min_efficiency` are dropped.
    #[must_use]
    pub fn crossed(a: &Self, b: &Self, min_efficiency: T) -> Self {
        let mut orders = Vec::with_capacity(a.orders.len() * b.orders.len());
        let mut kept = T::zero();
        for (za, ea) in &a.orders {
            for (zb, eb) in &b.orders {
                let e = *ea * *eb;
                if e > T::zero() && e >= min_efficiency {
                    orders.push((za + zb, e));
                    kept += e;
                }
            }
        }
        let dropped = (T::one() - kept).max(T::zero());
        Self {
            orders,
            kept,
            dropped,
        }
    }

    /// The kept orders `(ζ_m, η_m)`.
    #[must_use]
    pub fn orders(&self) -> &[(SVector<T, N>, T)] {
        &self.orders
    }

    /// `1 − Σ_kept η` (the efficiency the cutoff dropped, for a lossless grating).
    #[must_use]
    pub fn dropped_efficiency(&self) -> T {
        self.dropped
    }
}

impl<T: Real, const N: usize> Psd<T, N> for Grating<T, N> {
    #[inline]
    fn value(&self, _zeta: &SVector<T, N>) -> T {
        T::zero()
    }
    #[inline]
    fn variance(&self) -> T {
        self.kept
    }
}

impl<T: Real, const N: usize> BlurMethod<T, N, Grating<T, N>> for ClosedForm {
    #[inline]
    fn blur(&self, psd: &Grating<T, N>, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        psd.orders
            .iter()
            .fold(T::zero(), |acc, (z, e)| acc + *e * cov.value(&(h - z)))
    }
    /// `Σ e_m g^Σ(h − ζ_m) |Σ|^{−1/2}`, each term in log space.
    #[inline]
    fn normalized_blur(&self, psd: &Grating<T, N>, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        let half_log_det = T::lit(0.5) * cov.log_det();
        psd.orders.iter().fold(T::zero(), |acc, (z, e)| {
            acc + *e * (cov.log_value(&(h - z)) - half_log_det).exp()
        })
    }
    /// Log-sum-exp over the orders of `ln e_m + ln g^Σ(h − ζ_m) − ½ ln|Σ|`.
    #[inline]
    fn log_normalized_blur(
        &self,
        psd: &Grating<T, N>,
        cov: &Gaussian<T, N>,
        h: &SVector<T, N>,
    ) -> T {
        let half_log_det = T::lit(0.5) * cov.log_det();
        super::log_sum_exp(
            psd.orders
                .iter()
                .map(|(z, e)| e.ln() + cov.log_value(&(h - z)) - half_log_det),
        )
    }
}
