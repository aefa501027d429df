//! The K-correlation ("ABC", "fractal") PSD and its Gaussian-mixture fit.

use nalgebra::SVector;

use super::special::ln_gamma;
use super::{GaussianMixturePsd, GaussianPsd, Psd};
use crate::error::Error;
use crate::gaussian::Gaussian;
use crate::real::Real;

/// The K-correlation PSD `p(ζ) = σ² c (1 + T|ζ|²)^{−(γ+1)/2}` on `ℝᴺ`.
///
/// # Formula
/// ```text
/// p(ζ) = σ² c (1 + T|ζ|²)^{−ν},   ν = (γ + 1)/2,   c = (2T)^{n/2} Γ(ν) / Γ(ν − n/2)
/// n = 2:  c = (γ − 1) T     (FORMALISM's unit-integral (γ−1)T/(2π), times (2π) for ∫p = (2π)σ²)
/// ```
/// so that `∫ p dⁿζ = (2π)^{n/2} σ²`; this needs `γ > n − 1` (finite variance).
///
/// SCATMECH's ABC model (n = 2, `f` in cycles/length), `S(f) = A / (1 + (B f)²)^{C/2}`, is
/// `T = B²/(4π²)`, `γ = C − 1`, `σ² = 2π A / ((C − 2) B²)` ([`KCorrelation::from_abc`]),
/// from `S(f) = 2π p(2πf)`.
///
/// # Examples
/// ```
/// use gmueller::psd::{KCorrelation, Psd};
/// use nalgebra::Vector2;
/// let (a, b, c) = (1e-4_f64, 50.0_f64, 3.0_f64); // SCATMECH ABC: µm⁴, µm, dimensionless
/// let p = KCorrelation::<f64, 2>::from_abc(a, b, c).unwrap();
/// let f = Vector2::new(0.02_f64, 0.01);
/// let s = a / (1.0 + b * b * f.norm_squared()).powf(c / 2.0);
/// assert!((p.value_cycles(&f) - s).abs() < 1e-13 * s);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KCorrelation<T: Real, const N: usize> {
    variance: T,
    t: T,
    gamma: T,
    nu: T,
    /// `σ² c`, i.e. `p(0)`.
    peak_value: T,
    /// `c`, the normalisation per unit variance.
    norm: T,
}

impl<T: Real, const N: usize> KCorrelation<T, N> {
    /// From the variance `σ²`, the squared length `T` and the exponent `γ > n − 1`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] unless `σ² ≥ 0`, `T > 0`, `γ > n − 1`.
    pub fn new(variance: T, t: T, gamma: T) -> Result<Self, Error> {
        let bad = |what, v: T, expected| {
            if v.is_finite() {
                Error::OutOfRange {
                    what,
                    value: v.to_f64(),
                    expected,
                }
            } else {
                Error::NonFinite { what }
            }
        };
        if !(variance.is_finite() && variance >= T::zero()) {
            return Err(bad("variance", variance, "[0, ∞)"));
        }
        if !(t.is_finite() && t > T::zero()) {
            return Err(bad("K-correlation T", t, "(0, ∞)"));
        }
        let n = N as f64;
        if !(gamma.is_finite() && gamma.to_f64() > n - 1.0) {
            return Err(bad("K-correlation γ", gamma, "(n − 1, ∞)"));
        }
        let nu = 0.5 * (gamma.to_f64() + 1.0);
        let log_c = 0.5 * n * (2.0 * t.to_f64()).ln() + ln_gamma(nu) - ln_gamma(nu - 0.5 * n);
        Ok(Self {
            variance,
            t,
            gamma,
            nu: T::lit(nu),
            peak_value: variance * T::lit(log_c.exp()),
            norm: T::lit(log_c.exp()),
        })
    }

    /// `T` (length², the squared correlation scale).
    #[must_use]
    pub fn t(&self) -> T {
        self.t
    }

    /// `γ`.
    #[must_use]
    pub fn gamma(&self) -> T {
        self.gamma
    }

    /// `p(0) = σ² c`, the maximum of `p`.
    #[must_use]
    pub fn peak_value(&self) -> T {
        self.peak_value
    }

    /// A Gaussian-mixture approximation with `m ≥ 2` components, fitted once.
    ///
    /// # Formula
    /// ```text
    /// (1 + x)^{−ν} = Γ(ν)⁻¹ ∫ exp(ν t − eᵗ(1 + x)) dt        (scale mixture, s = eᵗ)
    ///            ≈ Γ(ν)⁻¹ Σⱼ h exp(ν tⱼ − sⱼ) exp(−sⱼ x),   tⱼ = t_min + j h,  x = T|ζ|²
    /// ```
    /// The trapezoid rule on this integrand (analytic in |Im t| < π/2) converges like
    /// `exp(−2π d/h)`; `h` and the truncation `[t_min, t_max]` are balanced for the given `m` at a
    /// design error `ε(h) = exp(−2.4π/h)`. The achieved uniform error
    /// `sup_ζ |p − p_m| / p(0)` is then measured at construction on a log-spaced radial grid
    /// (4000 points: 0 and `T|ζ|² ∈ [10⁻⁸, 10¹²]`, 200 per decade) and returned with the fit.
    ///
    /// # Error bound of the blur
    /// As the blur is a positive average of `p`, `|(p − p_m) * g^Σ|(h) ≤ sup|p − p_m| · |Σ|^{1/2}
    /// = error · p(0) · |Σ|^{1/2}` for every `h` (absolute, not relative: far in the tail the
    /// relative error grows, since every component decays like a Gaussian).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `2 ≤ m ≤ 400`.
    pub fn mixture_fit(&self, m: usize) -> Result<(GaussianMixturePsd<T, N>, f64), Error> {
        if !(2..=400).contains(&m) {
            return Err(Error::OutOfRange {
                what: "number of mixture components",
                value: m as f64,
                expected: "[2, 400]",
            });
        }
        let nu = self.nu.to_f64();
        let lg = ln_gamma(nu);
        // Design error and truncation for a step h.
        let range = |h: f64| {
            let ln_eps = -2.4 * core::f64::consts::PI / h;
            let t_min = (ln_eps + nu.ln() + lg) / nu;
            // s^{ν−1} e^{−s} = ε Γ(ν)  ⇒  s = −ln ε − ln Γ(ν) + (ν − 1) ln s  (fixed point).
            let mut s = (nu + 1.0).max(-ln_eps);
            for _ in 0..30 {
                s = (-ln_eps - lg + (nu - 1.0) * s.ln()).max(1e-3);
            }
            (t_min, s.ln())
        };
        let count = |h: f64| {
            let (a, b) = range(h);
            (b - a) / h + 1.0
        };
        let (mut lo, mut hi) = (1e-3_f64, 20.0_f64);
        for _ in 0..100 {
            let mid = (lo * hi).sqrt();
            if count(mid) > m as f64 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let h = hi;
        let (t_min, _) = range(h);
        let sigma2 = self.variance.to_f64();
        let c = self.norm.to_f64();
        let n = N as f64;
        let tt = self.t.to_f64();
        let mut comps = Vec::with_capacity(m);
        let mut fit = Vec::with_capacity(m); // (amplitude relative to p(0), s) in f64
        for j in 0..m {
            let t = t_min + j as f64 * h;
            let s = t.exp();
            let rel = h * (nu * t - s - lg).exp();
            fit.push((rel, s));
            // Component: p(0)·rel·exp(−s T |ζ|²) = σⱼ² |Λⱼ|^{1/2} g^{Pⱼ},  Pⱼ = I / (2 s T).
            let var_j = sigma2 * c * rel * (2.0 * s * tt).powf(-0.5 * n);
            let shape = Gaussian::isotropic(T::lit((2.0 * s * tt).sqrt().recip()))?;
            comps.push(GaussianPsd::from_spectral_shape(T::lit(var_j), shape)?);
        }
        // A-posteriori uniform error, relative to p(0).
        let mut err = 0.0_f64;
        for i in 0..4000 {
            let x = if i == 0 {
                0.0
            } else {
                10f64.powf(-8.0 + 20.0 * (i as f64) / 3999.0)
            };
            let exact = (1.0 + x).powf(-nu);
            let approx: f64 = fit.iter().map(|&(w, s)| w * (-s * x).exp()).sum();
            err = err.max((exact - approx).abs());
        }
        Ok((GaussianMixturePsd::new(comps)?, err))
    }

    /// The first `m` of 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256, 400 whose fit ([`KCorrelation::mixture_fit`]) has measured
    /// uniform error `sup|p − p_m|/p(0) ≤ tol`; returns the fit, `m` and the error.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] if no `m ≤ 400` reaches `tol` (in f64 the fit stalls near 1e-14).
    pub fn mixture_fit_to(
        &self,
        tol: f64,
    ) -> Result<(GaussianMixturePsd<T, N>, usize, f64), Error> {
        for m in [4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256, 400] {
            let (fit, err) = self.mixture_fit(m)?;
            if err <= tol {
                return Ok((fit, m, err));
            }
        }
        Err(Error::OutOfRange {
            what: "mixture-fit tolerance",
            value: tol,
            expected: "reachable with ≤ 400 components",
        })
    }
}

impl<T: Real> KCorrelation<T, 2> {
    /// From SCATMECH's ABC parameters: `S(f) = A / (1 + (B f)²)^{C/2}`, f in cycles/length.
    ///
    /// # Formula
    /// ```text
    /// T = B² / (4π²),   γ = C − 1,   σ² = 2π A / ((C − 2) B²)
    /// ```
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `A ≥ 0`, `B > 0`, `C > 2`.
    pub fn from_abc(a: T, b: T, c: T) -> Result<Self, Error> {
        let two = T::lit(2.0);
        if !(c.is_finite() && c > two) {
            return Err(Error::OutOfRange {
                what: "ABC exponent C",
                value: c.to_f64(),
                expected: "(2, ∞)",
            });
        }
        if !(b.is_finite() && b > T::zero()) {
            return Err(Error::OutOfRange {
                what: "ABC length B",
                value: b.to_f64(),
                expected: "(0, ∞)",
            });
        }
        let t = b * b / (T::two_pi() * T::two_pi());
        let variance = T::two_pi() * a / ((c - two) * b * b);
        Self::new(variance, t, c - T::one())
    }

    /// Back to SCATMECH's `(A, B, C)`.
    #[must_use]
    pub fn abc(&self) -> (T, T, T) {
        let b = self.t.sqrt() * T::two_pi();
        let c = self.gamma + T::one();
        let a = self.variance * (c - T::lit(2.0)) * b * b / T::two_pi();
        (a, b, c)
    }
}

impl<T: Real, const N: usize> Psd<T, N> for KCorrelation<T, N> {
    #[inline]
    fn value(&self, zeta: &SVector<T, N>) -> T {
        // (1 + x)^{−ν} = exp(−ν ln(1 + x)), ln_1p for small T|ζ|².
        self.peak_value * (-self.nu * (self.t * zeta.norm_squared()).ln_1p()).exp()
    }
    #[inline]
    fn log_value(&self, zeta: &SVector<T, N>) -> T {
        self.peak_value.ln() - self.nu * (self.t * zeta.norm_squared()).ln_1p()
    }
    #[inline]
    fn variance(&self) -> T {
        self.variance
    }
    /// `1/√T`, the scale of the spectral core.
    #[inline]
    fn feature_width(&self) -> T {
        T::one() / self.t.sqrt()
    }
}
