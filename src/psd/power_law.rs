//! The band-limited power-law ("fractal") PSD of polished optics.

use nalgebra::SVector;

use super::gaussian_psd::variance_of;
use super::kcorrelation::bad;
use super::special::ln_gamma;
use super::{Form, Psd, Shape};
use crate::error::Error;
use crate::real::Real;

/// The band-limited power-law PSD `p(ζ) = c |ζ|^{−α}` for `ζ_min ≤ |ζ| ≤ ζ_max`, 0 elsewhere,
/// on `ℝᴺ` — the isotropic fractal PSD measured on polished and diamond-turned optics between
/// the lowest and highest spatial frequencies an instrument resolves.
///
/// # Formula
/// ```text
/// p(ζ) = c |ζ|^{−α}   (ζ_min ≤ |ζ| ≤ ζ_max),   0 elsewhere,   α > n
/// ∫ p dⁿζ = c S_{n−1} (ζ_min^{n−α} − ζ_max^{n−α}) / (α − n) = (2π)^{n/2} σ²
/// S_{n−1} = 2π^{n/2}/Γ(n/2)        (2π for n = 2, 4π for n = 3)
/// in cycles per length (f = ζ/2π):  S(f) = K f^{−α},   ∫ S dⁿf = σ²,   K = (2π)^{n/2−α} c
/// ```
/// `α > n`: for `n = 2` this is the fractal range `2 < α < 4` of surfaces (Church, Appl. Opt.
/// 27, 1518 (1988); fractal dimension `D = (8 − α)/2`) and beyond, for `n = 3` the media whose
/// correlation decays as a power.
///
/// # Form
/// The PSD names the K-correlation `(1 + T|ζ|²)^{−(γ+1)/2}` with `T = 1/ζ_min²`, `γ = α − 1`
/// as its closest form ([`Form::closest`]): the same `|ζ|^{−α}` tail beyond `ζ_min`, and a
/// support (all of `ℝᴺ`) that covers the band. The BSDF sampler and the medium's sampler draw
/// from it and weigh by `p` itself (unbiased; the draws that land outside the band weigh 0),
/// and the medium places its quadrature nodes by it. Its blur has no closed form: a partially
/// coherent kernel blurs it by quadrature ([`super::GaussHermite`], [`super::Adaptive`]), and the
/// plane-wave and incoherent levels need no blur.
///
/// # Accuracy of the blur
/// The band's edges are steps, which a fixed-order [`super::GaussHermite`] does not resolve
/// within a few blur widths of an edge (order 24, blur width ~0.8 against `ζ_min = 2`: 3 % off
/// at the inner edge, 17 % inside the hole; within 1e-4 four widths away —
/// `tests/psd/power_law.rs`). [`super::Adaptive`] resolves them (to 2e-3 of a lattice sum,
/// the lattice's own error). In a random medium at the partially coherent level, order 6 left the
/// phase function's normalisation 6 % off at a 4 µm coherence (blur `ζ_min/4`), order 12 within
/// 2.5 standard errors of 1 (0.9997 ± 0.0031 and 1.0077 ± 0.0031 with two seeds): use order 12 or
/// more there.
///
/// # Examples
/// A surface measured in cycles per µm (`f` from 0.01 to 1 µm⁻¹, `α = 2.6`, 1 nm rms):
/// ```
/// use gmueller::psd::{PowerLaw, Psd};
/// use nalgebra::Vector2;
/// use std::f64::consts::TAU;
/// let (sigma, alpha, f_min, f_max) = (1e-3_f64, 2.6, 0.01, 1.0);
/// let p = PowerLaw::<f64, 2>::from_cycles(sigma, alpha, f_min, f_max)?;
/// // S(f) = K f^{−α} with ∫ S d²f = σ²: K = σ² (α − 2) / (2π (f_min^{2−α} − f_max^{2−α})).
/// let k = sigma * sigma * (alpha - 2.0) / (TAU * (f_min.powf(2.0 - alpha) - f_max.powf(2.0 - alpha)));
/// let f = Vector2::new(0.3, 0.4);
/// assert!((p.value_cycles(&f) / (k * 0.5f64.powf(-alpha)) - 1.0).abs() < 1e-12);
/// assert_eq!(p.value_cycles(&Vector2::new(2.0, 0.0)), 0.0); // beyond the band
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerLaw<T: Real, const N: usize> {
    variance: T,
    alpha: T,
    zeta_min: T,
    zeta_max: T,
    /// `ζ_min²`, `ζ_max²` (the band test on `|ζ|²`).
    band2: (T, T),
    /// `ln c` (`−∞` for `σ = 0`).
    ln_c: T,
}

impl<T: Real, const N: usize> PowerLaw<T, N> {
    /// From the rms `σ` (`σ² = R(0)`, the squared rms height for a surface), the exponent
    /// `α > n` and the band `ζ_min < ζ_max` in rad/length.
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] unless `σ ≥ 0`, `α > n`,
    /// `0 < ζ_min < ζ_max`, all finite, with `σ²`, `ζ_max²` and `1/ζ_min²` finite in `T` and
    /// `σ² > 0` unless `σ = 0`; [`Error::OutOfRange`] when `c` or the peak `p(ζ_min)`
    /// overflows `T`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::psd::PowerLaw;
    /// assert!(PowerLaw::<f64, 2>::new(1e-3, 3.0, 0.1, 10.0).is_ok());
    /// assert!(PowerLaw::<f64, 2>::new(1e-3, 2.0, 0.1, 10.0).is_err()); // α ≤ n
    /// assert!(PowerLaw::<f64, 3>::new(1e-3, 3.0, 0.1, 10.0).is_err()); // α ≤ n
    /// assert!(PowerLaw::<f64, 2>::new(1e-3, 3.0, 10.0, 0.1).is_err()); // ζ_min ≥ ζ_max
    /// ```
    pub fn new(rms: T, exponent: T, zeta_min: T, zeta_max: T) -> Result<Self, Error> {
        let variance = variance_of("power-law rms σ", rms)?;
        let n = N as f64;
        if !(exponent.is_finite() && exponent.to_f64() > n) {
            return Err(bad("power-law exponent α", exponent, "(n, ∞)"));
        }
        if !(zeta_min.is_finite() && zeta_min > T::zero()) {
            return Err(bad("power-law band ζ_min", zeta_min, "(0, ∞)"));
        }
        let band2 = (zeta_min * zeta_min, zeta_max * zeta_max);
        let inv_min2 = band2.0.recip();
        if !(band2.0 > T::zero() && inv_min2.is_finite()) {
            return Err(bad(
                "power-law band ζ_min",
                zeta_min,
                "ζ_min² and 1/ζ_min² finite and > 0",
            ));
        }
        if !(zeta_max.is_finite() && zeta_max > zeta_min && band2.1.is_finite()) {
            return Err(bad(
                "power-law band ζ_max",
                zeta_max,
                "(ζ_min, ∞) with ζ_max² finite",
            ));
        }
        // ln c = ln((2π)^{n/2} σ²) + ln(α − n) − ln S_{n−1} − ln(ζ_min^{n−α} − ζ_max^{n−α}), the
        // last in logs: (n − α) ln ζ_min + ln(1 − (ζ_min/ζ_max)^{α−n}).
        let (a, lo, hi) = (exponent.to_f64(), zeta_min.to_f64(), zeta_max.to_f64());
        let ln_sphere =
            core::f64::consts::LN_2 + 0.5 * n * core::f64::consts::PI.ln() - ln_gamma(0.5 * n);
        let ln_band = (n - a) * lo.ln() + (-((a - n) * (lo / hi).ln()).exp()).ln_1p();
        let ln_c = 0.5 * n * core::f64::consts::TAU.ln() + variance.to_f64().ln() + (a - n).ln()
            - ln_sphere
            - ln_band;
        // The peak p(ζ_min) = c ζ_min^{−α} must be a finite T (and c itself).
        let ln_peak = ln_c - a * lo.ln();
        let max = T::MAX.to_f64().ln();
        if variance > T::zero() && !(ln_c < max && ln_peak < max) {
            return Err(Error::OutOfRange {
                what: "power-law σ, α, ζ_min, ζ_max",
                value: ln_peak.exp(),
                expected: "c and the peak p(ζ_min) = c ζ_min^{−α} finite",
            });
        }
        Ok(Self {
            variance,
            alpha: exponent,
            zeta_min,
            zeta_max,
            band2,
            ln_c: T::lit(ln_c),
        })
    }

    /// [`Self::new`] with the band in cycles per length, `f = ζ/2π` (the unit of most PSD
    /// measurements): `ζ_min = 2π f_min`, `ζ_max = 2π f_max`.
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn from_cycles(rms: T, exponent: T, f_min: T, f_max: T) -> Result<Self, Error> {
        Self::new(rms, exponent, f_min * T::two_pi(), f_max * T::two_pi())
    }

    /// The exponent `α`.
    #[must_use]
    pub fn exponent(&self) -> T {
        self.alpha
    }

    /// The band `(ζ_min, ζ_max)` (rad/length).
    #[must_use]
    pub fn band(&self) -> (T, T) {
        (self.zeta_min, self.zeta_max)
    }
}

impl<T: Real, const N: usize> Psd<T, N> for PowerLaw<T, N> {
    #[inline]
    fn value(&self, zeta: &SVector<T, N>) -> T {
        self.log_value(zeta).exp()
    }
    /// `ln c − (α/2) ln|ζ|²` in the band, `−∞` outside it.
    #[inline]
    fn log_value(&self, zeta: &SVector<T, N>) -> T {
        let z2 = zeta.norm_squared();
        if z2 >= self.band2.0 && z2 <= self.band2.1 {
            self.ln_c - T::lit(0.5) * self.alpha * z2.ln()
        } else {
            T::lit(f64::NEG_INFINITY)
        }
    }
    #[inline]
    fn variance(&self) -> T {
        self.variance
    }
    /// `ζ_min`: the band's inner edge, where `p` peaks.
    #[inline]
    fn feature_width(&self) -> T {
        self.zeta_min
    }
    /// The K-correlation of `T = 1/ζ_min²`, `γ = α − 1`, as the closest form (type docs);
    /// [`Shape::Zero`] for `σ = 0`.
    #[inline]
    fn form(&self) -> Form<'_, T, N> {
        if self.variance > T::zero() {
            Form::closest(Shape::KCorrelation {
                t: self.band2.0.recip(),
                gamma: self.alpha - T::one(),
            })
        } else {
            Form::exact(Shape::Zero)
        }
    }
}
