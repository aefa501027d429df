//! Gaussian and Gaussian-mixture PSDs, and the smooth (Dirac) surface; closed-form blurs.

use nalgebra::{SMatrix, SVector};

use super::{BlurMethod, ClosedForm, ClosedFormBlur, CorrelationPowers, Form, Psd, Shape};
use crate::error::Error;
use crate::gaussian::{Gaussian, cholesky_of_sum, mahalanobis_from_cholesky};
use crate::numerics::{in_normal_range, log_det_from_cholesky, log_sum_exp};
use crate::real::Real;

/// The PSD of a Gaussian-correlated random field: `R(x) = σ² g^Λ(x)`, `p(ζ) = σ² |Λ|^{1/2} g^{Λ⁻¹}(ζ)`.
///
/// # Formula
/// ```text
/// R(x) = σ² exp(−½ xᵀΛ⁻¹x)   ⇒   p(ζ) = σ² |Λ|^{1/2} exp(−½ ζᵀΛζ)
/// isotropic, Λ = ℓ² I:  p(ζ) = σ² ℓⁿ exp(−½ ℓ² |ζ|²)          (n = 2: the main paper's q² ℓ² e^{−½ℓ²|ζ|²})
/// blur:  (p * g^Σ)(h) = σ² |Λ|^{1/2} (|Λ⁻¹| |Σ| / |Λ⁻¹ + Σ|)^{1/2} g^{Λ⁻¹ + Σ}(h)
/// ```
/// Parameters: rms height σ, correlation length ℓ in the `exp(−r²/(2ℓ²))` sense. SCATMECH's
/// `C(r) = σ² exp(−r²/L²)` (L the 1/e length) is `ℓ = L/√2` ([`GaussianPsd::from_scatmech`]),
/// and its `S(f) = π σ² L² exp(−(π L f)²)` equals `2π p(2πf)` for n = 2.
///
/// # Examples
/// ```
/// use gmueller::psd::{GaussianPsd, Psd};
/// use nalgebra::Vector2;
/// let p = GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap();
/// let f = Vector2::new(0.1_f64, 0.05); // cycles/µm
/// let (sigma, l) = (0.01_f64, 2.0 * 2f64.sqrt()); // SCATMECH's 1/e length L = √2 ℓ
/// let scatmech = std::f64::consts::PI * sigma * sigma * l * l
///     * (-(std::f64::consts::PI * l).powi(2) * f.norm_squared()).exp();
/// assert!((p.value_cycles(&f) - scatmech).abs() < 1e-14 * scatmech);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussianPsd<T: Real, const N: usize> {
    variance: T,
    /// `g^{Λ⁻¹}`: the spectral shape (covariance in ζ).
    spectral: Gaussian<T, N>,
    /// `ln(σ² |Λ|^{1/2}) = ln σ² − ½ ln|Λ⁻¹|`.
    log_amplitude: T,
}

fn check_positive<T: Real>(what: &'static str, v: T) -> Result<(), Error> {
    check_range(what, v, v > T::zero(), "(0, ∞)")
}

fn check_nonnegative<T: Real>(what: &'static str, v: T) -> Result<(), Error> {
    check_range(what, v, v >= T::zero(), "[0, ∞)")
}

/// `NonFinite` for NaN/∞, `OutOfRange` (with `expected`) when `ok` is false.
fn check_range<T: Real>(
    what: &'static str,
    v: T,
    ok: bool,
    expected: &'static str,
) -> Result<(), Error> {
    if !v.is_finite() {
        Err(Error::NonFinite { what })
    } else if ok {
        Ok(())
    } else {
        Err(Error::OutOfRange {
            what,
            value: v.to_f64(),
            expected,
        })
    }
}

/// `Err(OutOfRange { what, value, expected })` unless `ok`.
fn require(ok: bool, what: &'static str, value: f64, expected: &'static str) -> Result<(), Error> {
    if ok {
        Ok(())
    } else {
        Err(Error::OutOfRange {
            what,
            value,
            expected,
        })
    }
}

/// `σ²` from `σ`: finite, and positive unless `σ = 0`.
pub(super) fn variance_of<T: Real>(what: &'static str, rms_height: T) -> Result<T, Error> {
    check_nonnegative(what, rms_height)?;
    let v = rms_height * rms_height;
    require(
        v.is_finite() && (v > T::zero() || rms_height == T::zero()),
        what,
        rms_height.to_f64(),
        "σ² a finite number, > 0 unless σ = 0",
    )?;
    Ok(v)
}

/// `g^{I/ℓ²}` from `ℓ`: `1/ℓ²` finite and positive.
fn isotropic_spectrum<T: Real, const N: usize>(
    what: &'static str,
    length: T,
) -> Result<Gaussian<T, N>, Error> {
    check_positive(what, length)?;
    let inv = T::one() / length;
    let out_of_range = Error::OutOfRange {
        what,
        value: length.to_f64(),
        expected: "1/ℓ² a finite number > 0",
    };
    if !(inv.is_finite() && (inv * inv).is_finite() && inv * inv > T::zero()) {
        return Err(out_of_range);
    }
    Gaussian::isotropic(inv).map_err(|_| out_of_range)
}

impl<T: Real, const N: usize> GaussianPsd<T, N> {
    /// From the autocorrelation `R(x) = σ² g^Λ(x)`: variance `σ²` and correlation shape `Λ`.
    ///
    /// The derived quantities are checked too (see [`GaussianPsd::from_spectral_shape`]).
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] for a negative or non-finite variance;
    /// [`Error::OutOfRange`] naming `Λ` if `Λ⁻¹` is not representable (a finite positive
    /// definite matrix); as [`GaussianPsd::from_spectral_shape`] for the peak and integral.
    pub fn from_autocorrelation(variance: T, correlation: &Gaussian<T, N>) -> Result<Self, Error> {
        check_nonnegative("variance", variance)?;
        let spectral = correlation.inverse().map_err(|_| Error::OutOfRange {
            what: "correlation shape Λ",
            value: correlation.covariance().amax().to_f64(),
            expected: "Λ⁻¹ representable (finite, positive definite)",
        })?;
        Self::from_spectrum_parts(variance, spectral, "variance σ² and correlation shape Λ")
    }

    /// From the spectral shape: `p(ζ) = σ² |Λ|^{1/2} g^{P}(ζ)` with `P = Λ⁻¹` given directly.
    ///
    /// Derived quantities checked at construction: the peak `p(0) = σ² |Λ|^{1/2}` must be a
    /// finite `T` and `∫p = (2π)^{n/2} σ²` finite. The peak may underflow: the amplitude is held
    /// as a logarithm, so [`GaussianPsd::log_value`] and the log-space blurs stay exact while
    /// [`Psd::value`] returns 0.
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] for a negative or non-finite variance;
    /// [`Error::OutOfRange`] naming `σ²` and `P` when the peak or the integral overflows.
    pub fn from_spectral_shape(variance: T, spectral: Gaussian<T, N>) -> Result<Self, Error> {
        check_nonnegative("variance", variance)?;
        Self::from_spectrum_parts(variance, spectral, "variance σ² and spectral shape P")
    }

    /// The PSD from validated parts, after checking the peak and the integral (see
    /// [`GaussianPsd::from_spectral_shape`]); `scale_name` names the inputs in the error.
    fn from_spectrum_parts(
        variance: T,
        spectral: Gaussian<T, N>,
        scale_name: &'static str,
    ) -> Result<Self, Error> {
        let log_amplitude = variance.ln() - T::lit(0.5) * spectral.log_det();
        // The amplitude is held as a logarithm: a peak below the range of T is fine (values
        // underflow to 0 and the log forms stay exact); one above it is not.
        require(
            log_amplitude.exp().is_finite(),
            scale_name,
            (variance.to_f64().ln() - 0.5 * spectral.log_det().to_f64()).exp(),
            "peak p(0) = σ²|Λ|^{1/2} finite",
        )?;
        let integral = super::two_pi_pow_half_n::<T>(N) * variance;
        require(
            integral.is_finite(),
            scale_name,
            integral.to_f64(),
            "∫p = (2π)^{n/2} σ² finite",
        )?;
        Ok(Self {
            variance,
            spectral,
            log_amplitude,
        })
    }

    /// Isotropic: rms height `σ`, correlation length `ℓ` with `R(r) = σ² exp(−r²/(2ℓ²))`.
    ///
    /// Besides the inputs, the derived quantities must be representable in `T`: `σ²` (finite,
    /// and `> 0` unless `σ = 0`), the spectral covariance `I/ℓ²` (finite, `> 0`), the peak
    /// `p(0) = σ² ℓⁿ` (finite; it may underflow, see [`GaussianPsd::from_spectral_shape`]) and
    /// `∫p = (2π)^{n/2} σ²` (finite).
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] unless `σ ≥ 0` and `ℓ > 0`, finite;
    /// [`Error::OutOfRange`] naming the rms height when `σ²` over- or underflows (f32
    /// `σ = 10²⁰` or `10⁻³⁰`), naming the correlation length when `1/ℓ²` does (f32
    /// `ℓ = 10⁻²⁰` or `10²³`), naming both when the peak or the integral overflows.
    ///
    /// # Examples
    /// ```
    /// use gmueller::psd::GaussianPsd;
    /// assert!(GaussianPsd::<f32, 2>::isotropic(1e20, 1.0).is_err()); // σ² = 1e40 > f32::MAX
    /// assert!(GaussianPsd::<f32, 2>::isotropic(1e15, 1e15).is_err()); // p(0) = σ²ℓ² = 1e60
    /// assert!(GaussianPsd::<f64, 2>::isotropic(1e15, 1e15).is_ok());
    /// ```
    pub fn isotropic(rms_height: T, correlation_length: T) -> Result<Self, Error> {
        let variance = variance_of("rms height", rms_height)?;
        let spectral = isotropic_spectrum("correlation length", correlation_length)?;
        Self::from_spectrum_parts(variance, spectral, "rms height σ and correlation length ℓ")
    }

    /// SCATMECH's parameters: `C(r) = σ² exp(−r²/L²)`, L the 1/e correlation length (`ℓ = L/√2`).
    ///
    /// # Errors
    /// As [`GaussianPsd::isotropic`], naming the 1/e correlation length.
    pub fn from_scatmech(rms_height: T, one_over_e_length: T) -> Result<Self, Error> {
        let variance = variance_of("rms height", rms_height)?;
        check_positive("1/e correlation length", one_over_e_length)?;
        let spectral = isotropic_spectrum(
            "1/e correlation length",
            one_over_e_length / T::lit(2.0).sqrt(),
        )?;
        Self::from_spectrum_parts(variance, spectral, "rms height σ and 1/e length L")
    }

    /// `ln(σ²|Λ|^{1/2})`, the logarithm of the peak `p(0)` without the `(2π)^{n/2}`.
    #[inline]
    pub(crate) fn log_amplitude(&self) -> T {
        self.log_amplitude
    }

    /// The spectral shape `g^{Λ⁻¹}` (covariance in frequency space).
    #[must_use]
    pub fn spectral_shape(&self) -> &Gaussian<T, N> {
        &self.spectral
    }

    /// `ln p(ζ)`, accurate where [`Psd::value`] underflows.
    #[inline]
    #[must_use]
    pub fn log_value(&self, zeta: &SVector<T, N>) -> T {
        self.log_amplitude + self.spectral.log_value(zeta)
    }

    /// `ln (p * g^Σ)(h)` in closed form (see the type's formula).
    #[inline]
    #[must_use]
    pub fn log_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.log_normalized_blur(cov, h) + T::lit(0.5) * cov.log_det()
    }

    /// `ln ∫ p(ζ) 𝒩_Σ(h − ζ) dⁿζ = ln (p * g^Σ)(h) − ½ ln|Σ|` in closed form
    /// ([`BlurMethod::normalized_blur`]); `|Σ|` cancels analytically, so nothing large or tiny
    /// is formed even as `Σ → 0` (where it tends to [`Self::log_value`]).
    ///
    /// # Formula
    /// ```text
    /// ln ∫ p 𝒩_Σ(h − ·) = ln(σ²|Λ|^{1/2}) + ½ (ln|Λ⁻¹| − ln|Λ⁻¹ + Σ|) − ½ hᵀ(Λ⁻¹ + Σ)⁻¹h
    /// ```
    #[inline]
    #[must_use]
    pub fn log_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        match self.blur_parts(cov, h) {
            Some((l, m)) => self.log_normalized_from_parts(&l, m),
            // Only reachable by overflow of the sum at extreme scales.
            None => T::min_value().unwrap_or(T::zero()),
        }
    }

    /// The Cholesky factor `L` of `Λ⁻¹ + Σ` (from the two factors, see
    /// [`crate::gaussian::cholesky_of_sum`]) and `|L⁻¹h|²` (`None` when the sum overflows).
    #[inline(always)]
    fn blur_parts(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> Option<(SMatrix<T, N, N>, T)> {
        let l = cholesky_of_sum(&self.spectral, cov)?;
        let m = mahalanobis_from_cholesky(&l, h);
        Some((l, m))
    }

    /// [`Self::log_normalized_blur`] from [`Self::blur_parts`].
    #[inline]
    fn log_normalized_from_parts(&self, l: &SMatrix<T, N, N>, m: T) -> T {
        let log_det_sum = log_det_from_cholesky(l);
        self.log_amplitude + T::lit(0.5) * (self.spectral.log_det() - log_det_sum - m)
    }

    /// `∫ p(ζ) 𝒩_Σ(h − ζ) dⁿζ` ([`BlurMethod::normalized_blur`]), without logarithms where
    /// nothing can over- or underflow.
    ///
    /// # Formula
    /// ```text
    /// ∫ p 𝒩_Σ(h − ·) = σ² / ∏ᵢ Lᵢᵢ · exp(−½ |L⁻¹h|²),    L Lᵀ = Λ⁻¹ + Σ
    /// ```
    /// (the exponential of [`Self::log_normalized_blur`], whose `ln|Λ|` terms cancel). Used
    /// when `σ²` and `∏ Lᵢᵢ` lie in `[10⁻³⁰, 10³⁰]` and `|L⁻¹h|² ≤ 100`, so every
    /// intermediate is a normal number in f32 and f64; otherwise the log-space form is used.
    #[inline]
    #[must_use]
    pub fn normalized_blur_value(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.normalized_blur_forms(cov, h).0
    }

    /// [`Self::normalized_blur_value`] with, where that value came from the log-space form,
    /// the logarithm it exponentiated: bit for bit [`Self::log_normalized_blur`], from the same
    /// Cholesky factor (`None` where the value is the linear form). The kernel's scalar path
    /// reads the logarithm when the linear weight is out of its range, rather than factoring
    /// `Λ⁻¹ + Σ` a second time.
    #[inline]
    pub(crate) fn normalized_blur_forms(
        &self,
        cov: &Gaussian<T, N>,
        h: &SVector<T, N>,
    ) -> (T, Option<T>) {
        let Some((l, m)) = self.blur_parts(cov, h) else {
            // As `log_normalized_blur` answers an overflowing sum.
            return (T::zero(), Some(T::min_value().unwrap_or(T::zero())));
        };
        let prod = (0..N).fold(T::one(), |p, i| p * l[(i, i)]);
        let v = self.variance;
        if in_normal_range(prod) && in_normal_range(v) && m <= T::lit(100.0) {
            (v / prod * (T::lit(-0.5) * m).exp(), None)
        } else {
            let ln = self.log_normalized_from_parts(&l, m);
            (ln.exp(), Some(ln))
        }
    }
}

impl<T: Real, const N: usize> Psd<T, N> for GaussianPsd<T, N> {
    #[inline]
    fn value(&self, zeta: &SVector<T, N>) -> T {
        self.log_value(zeta).exp()
    }
    #[inline]
    fn log_value(&self, zeta: &SVector<T, N>) -> T {
        GaussianPsd::log_value(self, zeta)
    }
    #[inline]
    fn variance(&self) -> T {
        self.variance
    }
    #[inline]
    fn form(&self) -> Form<'_, T, N> {
        Form::exact(Shape::Gaussian(self))
    }
    /// The smallest diagonal entry of the spectral Cholesky factor.
    #[inline]
    fn feature_width(&self) -> T {
        let l = self.spectral.cholesky_factor();
        (0..N).fold(T::max_value().unwrap_or(T::one()), |m, i| m.min(l[(i, i)]))
    }
}

impl<T: Real, const N: usize> ClosedFormBlur<T, N> for GaussianPsd<T, N> {
    #[inline]
    fn closed_form_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.log_blur(cov, h).exp()
    }
    #[inline]
    fn closed_form_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.normalized_blur_value(cov, h)
    }
    #[inline]
    fn closed_form_log_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        GaussianPsd::log_normalized_blur(self, cov, h)
    }
}

/// `ρˣ = g^{Λ/x}`: the spectral covariance `x Λ⁻¹` and the amplitude `σ² |Λ|^{1/2} x⁻¹`
/// (no factorisation: the spectral Cholesky factor scaled by `√x`).
///
/// # Examples
/// ```
/// use gmueller::psd::{CorrelationPowers, GaussianPsd, Psd};
/// use nalgebra::Vector2;
/// let p = GaussianPsd::<f64, 2>::isotropic(0.05, 2.0)?;
/// // ρ³ of R = σ² e^{−r²/2ℓ²} is the Gaussian of correlation length ℓ/√3.
/// let cubed = p.correlation_power(3.0).unwrap();
/// let direct = GaussianPsd::<f64, 2>::isotropic(0.05, 2.0 / 3f64.sqrt())?;
/// let z = Vector2::new(0.7, -0.2);
/// assert!((cubed.value(&z) / direct.value(&z) - 1.0).abs() < 1e-14);
/// assert_eq!(cubed.variance(), p.variance());
/// # Ok::<(), gmueller::Error>(())
/// ```
impl<T: Real> CorrelationPowers<T> for GaussianPsd<T, 2> {
    type Power = Self;
    #[inline]
    fn correlation_power(&self, x: T) -> Option<Self> {
        let spectral = self.spectral.scaled(x)?;
        Some(Self {
            variance: self.variance,
            spectral,
            log_amplitude: self.log_amplitude - x.ln(),
        })
    }
    #[inline]
    fn gaussian_spectrum(&self) -> Option<(T, nalgebra::Matrix2<T>)> {
        Some((self.variance, *self.spectral.cholesky_factor()))
    }
}

/// A sum of Gaussian PSDs, `p = Σⱼ pⱼ`, each `pⱼ` a [`GaussianPsd`]; closed-form blur.
///
/// Allocates its component list once, at construction; evaluation and blur allocate nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussianMixturePsd<T: Real, const N: usize> {
    components: Vec<GaussianPsd<T, N>>,
    variance: T,
}

impl<T: Real, const N: usize> GaussianMixturePsd<T, N> {
    /// From its components.
    ///
    /// The sums must stay representable: the total variance `Σⱼ σⱼ²`, the integral
    /// `(2π)^{n/2} Σⱼ σⱼ²` and the peak `p(0) = Σⱼ pⱼ(0)` finite.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for an empty list, and naming the mixture components when one of
    /// those sums overflows.
    pub fn new(components: Vec<GaussianPsd<T, N>>) -> Result<Self, Error> {
        if components.is_empty() {
            return Err(Error::OutOfRange {
                what: "number of mixture components",
                value: 0.0,
                expected: "≥ 1",
            });
        }
        let variance = components
            .iter()
            .fold(T::zero(), |acc, c| acc + c.variance());
        let peak = components
            .iter()
            .fold(T::zero(), |acc, c| acc + c.log_amplitude.exp());
        let integral = super::two_pi_pow_half_n::<T>(N) * variance;
        require(
            variance.is_finite() && integral.is_finite() && peak.is_finite(),
            "mixture components",
            variance.to_f64() + peak.to_f64(),
            "Σⱼσⱼ², (2π)^{n/2}Σⱼσⱼ² and the peak Σⱼpⱼ(0) finite",
        )?;
        Ok(Self {
            components,
            variance,
        })
    }

    /// The components.
    #[must_use]
    pub fn components(&self) -> &[GaussianPsd<T, N>] {
        &self.components
    }
}

impl<T: Real, const N: usize> Psd<T, N> for GaussianMixturePsd<T, N> {
    #[inline]
    fn value(&self, zeta: &SVector<T, N>) -> T {
        self.components
            .iter()
            .fold(T::zero(), |acc, c| acc + c.value(zeta))
    }
    /// `ln Σⱼ pⱼ(ζ)` by log-sum-exp of the components' logarithms.
    #[inline]
    fn log_value(&self, zeta: &SVector<T, N>) -> T {
        log_sum_exp(self.components.iter().map(|c| c.log_value(zeta)))
    }
    #[inline]
    fn variance(&self) -> T {
        self.variance
    }
    #[inline]
    fn form(&self) -> Form<'_, T, N> {
        Form::exact(Shape::Mixture(&self.components))
    }
    /// The narrowest component's width.
    #[inline]
    fn feature_width(&self) -> T {
        self.components
            .iter()
            .fold(T::max_value().unwrap_or(T::one()), |m, c| {
                m.min(c.feature_width())
            })
    }
}

impl<T: Real, const N: usize> ClosedFormBlur<T, N> for GaussianMixturePsd<T, N> {
    #[inline]
    fn closed_form_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.components
            .iter()
            .fold(T::zero(), |acc, c| acc + ClosedForm.blur(c, cov, h))
    }
    #[inline]
    fn closed_form_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.components.iter().fold(T::zero(), |acc, c| {
            acc + ClosedForm.normalized_blur(c, cov, h)
        })
    }
    /// The logarithm of the linear sum where that is a safely normal number (one logarithm for
    /// the mixture), log-sum-exp of the components' logarithms otherwise (tails far below the
    /// type's range).
    #[inline]
    fn closed_form_log_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        let v = ClosedForm.normalized_blur(self, cov, h);
        if in_normal_range(v) {
            v.ln()
        } else {
            log_sum_exp(
                self.components
                    .iter()
                    .map(|c| c.log_normalized_blur(cov, h)),
            )
        }
    }
}

/// A smooth (non-random) surface: `p = (2π)^{n/2} w δ(ζ)`, all power in the specular order.
///
/// # Formula
/// ```text
/// R(x) = w (constant)  ⇒  p(ζ) = (2π)^{n/2} w δ(ζ),   (p * g^Σ)(h) = w g^Σ(h)
/// ```
/// Semantics: the correlation of a perfectly smooth interface's reflection function is constant,
/// so the blur is the specular lobe, widened only by the light's coherence. `w = 1` is a mirror
/// (a grating of zero depth); `w = 0` scatters nothing. [`Psd::value`] (the continuous part) is 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Smooth<T: Real> {
    weight: T,
}

impl<T: Real> Smooth<T> {
    /// A smooth surface carrying `weight` (`R(0)`) in its specular order.
    ///
    /// The integral `∫p = (2π)^{n/2} w` must be finite for `n ≤ 3` (so `w ≤ T::MAX/(2π)^{3/2}`).
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] unless `weight ≥ 0`, finite;
    /// [`Error::OutOfRange`] if `(2π)^{3/2} w` overflows.
    pub fn new(weight: T) -> Result<Self, Error> {
        check_nonnegative("specular weight", weight)?;
        require(
            (super::two_pi_pow_half_n::<T>(3) * weight).is_finite(),
            "specular weight",
            weight.to_f64(),
            "∫p = (2π)^{n/2} w finite for n ≤ 3",
        )?;
        Ok(Self { weight })
    }
}

impl<T: Real, const N: usize> Psd<T, N> for Smooth<T> {
    #[inline]
    fn value(&self, _zeta: &SVector<T, N>) -> T {
        T::zero()
    }
    #[inline]
    fn variance(&self) -> T {
        self.weight
    }
    /// [`Shape::Origin`], or [`Shape::Zero`] for a weight of 0.
    #[inline]
    fn form(&self) -> Form<'_, T, N> {
        Form::exact(if self.weight > T::zero() {
            Shape::Origin
        } else {
            Shape::Zero
        })
    }
}

impl<T: Real, const N: usize> ClosedFormBlur<T, N> for Smooth<T> {
    #[inline]
    fn closed_form_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.weight * cov.value(h)
    }
    /// `w g^Σ(h) |Σ|^{−1/2}`, in log space.
    #[inline]
    fn closed_form_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.weight * (cov.log_value(h) - T::lit(0.5) * cov.log_det()).exp()
    }
    #[inline]
    fn closed_form_log_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.weight.ln() + cov.log_value(h) - T::lit(0.5) * cov.log_det()
    }
}
