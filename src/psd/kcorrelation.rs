//! The K-correlation ("ABC", "fractal") PSD and its Gaussian-mixture fit.

use nalgebra::SVector;

use super::special::{ln_gamma, ln_gamma_ratio};
use super::{Form, GaussianMixturePsd, GaussianPsd, Psd, Shape};
use crate::error::Error;
use crate::gaussian::Gaussian;
use crate::real::Real;

/// The K-correlation PSD `p(ζ) = σ² c (1 + T|ζ|²)^{−(γ+1)/2}` on `ℝᴺ`.
///
/// # Formula
/// ```text
/// p(ζ) = σ² c (1 + T|ζ|²)^{−ν},   ν = (γ + 1)/2,   c = (2T)^{n/2} Γ(ν) / Γ(ν − n/2)
/// n = 2:  c = (γ − 1) T     (the main paper's unit-integral (γ−1)T/(2π), times 2π for ∫p = (2π)σ²)
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
    /// `ln c`, the normalisation per unit variance (kept in f64: `c` alone may exceed `T`).
    log_norm: f64,
}

/// `NonFinite` for NaN/∞, `OutOfRange` otherwise.
pub(super) fn bad<T: Real>(what: &'static str, v: T, expected: &'static str) -> Error {
    if v.is_finite() {
        Error::OutOfRange {
            what,
            value: v.to_f64(),
            expected,
        }
    } else {
        Error::NonFinite { what }
    }
}

impl<T: Real, const N: usize> KCorrelation<T, N> {
    /// From the variance `σ²`, the squared length `T` and the exponent `γ > n − 1`.
    ///
    /// Besides the inputs, the derived quantities are checked: the peak `p(0) = σ² c` must be a
    /// finite `T`, and positive unless `σ² = 0` (not flushed to zero), and `∫p = (2π)^{n/2} σ²`
    /// finite. `c` is computed in log space with `ln Γ(ν)/Γ(ν − n/2)` free of cancellation, so
    /// every finite `γ > n − 1` gives a finite `ln c` (≈ (n/2) ln(2Tν) for large ν).
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] unless `σ² ≥ 0`, `T > 0`, `γ > n − 1`, all
    /// finite; [`Error::OutOfRange`] naming `σ², T, γ` when the peak `p(0)` over- or
    /// underflows `T` (e.g. `T = 10³⁰⁸`, `γ = 3` in f64) or `∫p` overflows.
    ///
    /// # Examples
    /// ```
    /// use gmueller::psd::KCorrelation;
    /// // n = 2: p(0) = σ² (γ − 1) T.
    /// let k = KCorrelation::<f64, 2>::new(1.0, 1e308, 2.0).unwrap();
    /// assert!((k.peak_value() / 1e308 - 1.0).abs() < 1e-13);
    /// assert!(KCorrelation::<f64, 2>::new(1.0, 1e308, 3.0).is_err()); // p(0) = 2e308
    /// assert!(KCorrelation::<f32, 2>::new(1.0, 1e38, 5.0).is_err()); // p(0) = 4e38
    /// ```
    pub fn new(variance: T, t: T, gamma: T) -> Result<Self, Error> {
        Self::build(variance, t, gamma, "K-correlation σ², T, γ")
    }

    /// [`Self::new`], with `scale_name` naming the parameters in the error on the peak.
    fn build(variance: T, t: T, gamma: T, scale_name: &'static str) -> Result<Self, Error> {
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
        let nu = 0.5 * gamma.to_f64() + 0.5;
        // c = (2T)^{n/2} Γ(ν)/Γ(ν − n/2), in logs (2T itself may overflow).
        let log_c =
            0.5 * n * (core::f64::consts::LN_2 + t.to_f64().ln()) + ln_gamma_ratio(nu, 0.5 * n);
        let sigma2 = variance.to_f64();
        let log_peak = sigma2.ln() + log_c;
        let plain = sigma2 * log_c.exp();
        let peak_value = T::lit(if plain.is_finite() && plain > f64::MIN_POSITIVE {
            plain
        } else {
            log_peak.exp()
        });
        let peak_ok = if sigma2 == 0.0 {
            log_c.is_finite()
        } else {
            peak_value.is_finite() && peak_value > T::zero()
        };
        if !peak_ok {
            return Err(Error::OutOfRange {
                what: scale_name,
                value: log_peak.exp(),
                expected: "peak p(0) = σ²(2T)^{n/2}Γ(ν)/Γ(ν − n/2) finite, and > 0 unless σ² = 0",
            });
        }
        let integral = super::two_pi_pow_half_n::<T>(N) * variance;
        if !integral.is_finite() {
            return Err(Error::OutOfRange {
                what: scale_name,
                value: integral.to_f64(),
                expected: "∫p = (2π)^{n/2} σ² finite",
            });
        }
        Ok(Self {
            variance,
            t,
            gamma,
            nu: T::lit(nu),
            peak_value,
            log_norm: log_c,
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

    /// The Matérn order of the 2-D autocorrelation, `ν = (γ − 1)/2` (the PSD's exponent
    /// `(γ + 1)/2` less `n/2 = 1`).
    #[must_use]
    pub(crate) fn nu_2d(&self) -> f64 {
        self.nu.to_f64() - 1.0
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
    /// [`Error::OutOfRange`] unless `2 ≤ m ≤ 400`; [`Error::OutOfRange`] naming `T` and `γ` when
    /// a component is not representable in `T` (its width `(2 sⱼ T)^{−1/2}` or variance over- or
    /// underflows, e.g. f32 `T ≥ 10³⁶`) or the measured error is not finite.
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
            // p(0)·rel·(2sT)^{−n/2}; in logs where the plain product leaves the f64 range.
            let plain = self.peak_value.to_f64() * rel * (2.0 * s * tt).powf(-0.5 * n);
            let two_st = core::f64::consts::LN_2 + s.ln() + tt.ln();
            let var_j = if plain.is_finite() && plain > f64::MIN_POSITIVE {
                plain
            } else {
                (sigma2.ln() + self.log_norm + rel.ln() - 0.5 * n * two_st).exp()
            };
            let width = T::lit((-0.5 * two_st).exp());
            let unrepresentable = Error::OutOfRange {
                what: "K-correlation T, γ (mixture component)",
                value: tt,
                expected: "components representable in the scalar type: width (2sT)^{−1/2} \
                           and variance finite and > 0",
            };
            let var_t = T::lit(var_j);
            if sigma2 > 0.0 && !(var_t > T::zero() && var_t.is_finite()) {
                return Err(unrepresentable);
            }
            let shape = Gaussian::isotropic(width).map_err(|_| unrepresentable.clone())?;
            comps
                .push(GaussianPsd::from_spectral_shape(var_t, shape).map_err(|_| unrepresentable)?);
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
        if !err.is_finite() {
            return Err(Error::OutOfRange {
                what: "K-correlation T, γ (mixture fit)",
                value: err,
                expected: "a finite measured fit error",
            });
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
    /// The derived `T` and `σ²` must be finite, and positive where the inputs are; then the checks
    /// of [`KCorrelation::new`] apply, with errors naming `A, B, C`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] unless `A ≥ 0`, `B > 0`, `C > 2`, all finite;
    /// [`Error::OutOfRange`] naming `B` when `T = B²/(4π²)` over- or underflows, naming
    /// `A, B, C` when `σ²` or the peak over- or underflows.
    pub fn from_abc(a: T, b: T, c: T) -> Result<Self, Error> {
        let two = T::lit(2.0);
        if !(c.is_finite() && c > two) {
            return Err(bad("ABC exponent C", c, "(2, ∞)"));
        }
        if !(b.is_finite() && b > T::zero()) {
            return Err(bad("ABC length B", b, "(0, ∞)"));
        }
        if !(a.is_finite() && a >= T::zero()) {
            return Err(bad("ABC amplitude A", a, "[0, ∞)"));
        }
        let t = b * b / (T::two_pi() * T::two_pi());
        if !(t.is_finite() && t > T::zero()) {
            return Err(Error::OutOfRange {
                what: "ABC length B",
                value: b.to_f64(),
                expected: "T = B²/(4π²) finite and > 0",
            });
        }
        // σ² = 2π A/((C − 2) B²), in f64 logs (B² and C − 2 may over- or underflow T).
        let (a64, b64, c64) = (a.to_f64(), b.to_f64(), c.to_f64());
        let plain = core::f64::consts::TAU * a64 / ((c64 - 2.0) * b64 * b64);
        let variance = T::lit(
            if a == T::zero() || (plain.is_finite() && plain > f64::MIN_POSITIVE) {
                plain
            } else {
                (core::f64::consts::TAU.ln() + a64.ln() - (c64 - 2.0).ln() - 2.0 * b64.ln()).exp()
            },
        );
        if a > T::zero() && !(variance.is_finite() && variance > T::zero()) {
            return Err(Error::OutOfRange {
                what: "ABC parameters A, B, C",
                value: variance.to_f64(),
                expected: "σ² = 2πA/((C − 2)B²) finite and > 0",
            });
        }
        Self::build(variance, t, c - T::one(), "ABC parameters A, B, C")
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
    #[inline]
    fn form(&self) -> Form<'_, T, N> {
        Form::exact(Shape::KCorrelation {
            t: self.t,
            gamma: self.gamma,
        })
    }
    /// `1/√T`, the scale of the spectral core.
    #[inline]
    fn feature_width(&self) -> T {
        T::one() / self.t.sqrt()
    }
}
