//! Gaussian and Gaussian-mixture PSDs, and the smooth (Dirac) surface; closed-form blurs.

use nalgebra::{SMatrix, SVector};

use super::{BlurMethod, ClosedForm, Psd};
use crate::error::Error;
use crate::gaussian::{Gaussian, cholesky, in_normal_range, mahalanobis_from_cholesky};
use crate::real::Real;

/// The PSD of a Gaussian-correlated random field: `R(x) = σ² g^Λ(x)`, `p(ζ) = σ² |Λ|^{1/2} g^{Λ⁻¹}(ζ)`.
///
/// # Formula
/// ```text
/// R(x) = σ² exp(−½ xᵀΛ⁻¹x)   ⇒   p(ζ) = σ² |Λ|^{1/2} exp(−½ ζᵀΛζ)
/// isotropic, Λ = ℓ² I:  p(ζ) = σ² ℓⁿ exp(−½ ℓ² |ζ|²)          (n = 2: FORMALISM's q² ℓ² e^{−½ℓ²|ζ|²})
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

impl<T: Real, const N: usize> GaussianPsd<T, N> {
    /// From the autocorrelation `R(x) = σ² g^Λ(x)`: variance `σ²` and correlation shape `Λ`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] for a negative or non-finite variance;
    /// validation errors of `Λ⁻¹`.
    pub fn from_autocorrelation(variance: T, correlation: &Gaussian<T, N>) -> Result<Self, Error> {
        check_nonnegative("variance", variance)?;
        let spectral = correlation.inverse()?;
        Ok(Self::from_spectrum_parts(variance, spectral))
    }

    /// From the spectral shape: `p(ζ) = σ² |Λ|^{1/2} g^{P}(ζ)` with `P = Λ⁻¹` given directly.
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] for a negative or non-finite variance.
    pub fn from_spectral_shape(variance: T, spectral: Gaussian<T, N>) -> Result<Self, Error> {
        check_nonnegative("variance", variance)?;
        Ok(Self::from_spectrum_parts(variance, spectral))
    }

    fn from_spectrum_parts(variance: T, spectral: Gaussian<T, N>) -> Self {
        Self {
            variance,
            spectral,
            log_amplitude: variance.ln() - T::lit(0.5) * spectral.log_det(),
        }
    }

    /// Isotropic: rms height `σ`, correlation length `ℓ` with `R(r) = σ² exp(−r²/(2ℓ²))`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `σ ≥ 0` and `ℓ > 0`, finite.
    pub fn isotropic(rms_height: T, correlation_length: T) -> Result<Self, Error> {
        check_nonnegative("rms height", rms_height)?;
        check_positive("correlation length", correlation_length)?;
        let spectral = Gaussian::isotropic(T::one() / correlation_length)?;
        Ok(Self::from_spectrum_parts(rms_height * rms_height, spectral))
    }

    /// SCATMECH's parameters: `C(r) = σ² exp(−r²/L²)`, L the 1/e correlation length (`ℓ = L/√2`).
    ///
    /// # Errors
    /// As [`GaussianPsd::isotropic`].
    pub fn from_scatmech(rms_height: T, one_over_e_length: T) -> Result<Self, Error> {
        Self::isotropic(rms_height, one_over_e_length / T::lit(2.0).sqrt())
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

    /// The Cholesky factor `L` of `Λ⁻¹ + Σ` and `|L⁻¹h|²` (`None` when the sum overflows).
    #[inline]
    fn blur_parts(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> Option<(SMatrix<T, N, N>, T)> {
        let sum: SMatrix<T, N, N> = self.spectral.covariance() + cov.covariance();
        let l = cholesky(&sum).ok()?;
        let m = mahalanobis_from_cholesky(&l, h);
        Some((l, m))
    }

    /// [`Self::log_normalized_blur`] from [`Self::blur_parts`].
    #[inline]
    fn log_normalized_from_parts(&self, l: &SMatrix<T, N, N>, m: T) -> T {
        let log_det_sum = crate::gaussian::log_det_from_cholesky(l);
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
        let Some((l, m)) = self.blur_parts(cov, h) else {
            return T::zero();
        };
        let prod = (0..N).fold(T::one(), |p, i| p * l[(i, i)]);
        let v = self.variance;
        if in_normal_range(prod) && in_normal_range(v) && m <= T::lit(100.0) {
            v / prod * (T::lit(-0.5) * m).exp()
        } else {
            self.log_normalized_from_parts(&l, m).exp()
        }
    }
}

impl<T: Real, const N: usize> Psd<T, N> for GaussianPsd<T, N> {
    #[inline]
    fn value(&self, zeta: &SVector<T, N>) -> T {
        self.log_value(zeta).exp()
    }
    #[inline]
    fn variance(&self) -> T {
        self.variance
    }
    /// The smallest diagonal entry of the spectral Cholesky factor.
    #[inline]
    fn feature_width(&self) -> T {
        let l = self.spectral.cholesky_factor();
        (0..N).fold(T::max_value().unwrap_or(T::one()), |m, i| m.min(l[(i, i)]))
    }
}

impl<T: Real, const N: usize> BlurMethod<T, N, GaussianPsd<T, N>> for ClosedForm {
    #[inline]
    fn blur(&self, psd: &GaussianPsd<T, N>, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        psd.log_blur(cov, h).exp()
    }
    #[inline]
    fn normalized_blur(
        &self,
        psd: &GaussianPsd<T, N>,
        cov: &Gaussian<T, N>,
        h: &SVector<T, N>,
    ) -> T {
        psd.normalized_blur_value(cov, h)
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
    /// # Errors
    /// [`Error::OutOfRange`] for an empty list.
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
    #[inline]
    fn variance(&self) -> T {
        self.variance
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

impl<T: Real, const N: usize> BlurMethod<T, N, GaussianMixturePsd<T, N>> for ClosedForm {
    #[inline]
    fn blur(&self, psd: &GaussianMixturePsd<T, N>, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        psd.components
            .iter()
            .fold(T::zero(), |acc, c| acc + ClosedForm.blur(c, cov, h))
    }
    #[inline]
    fn normalized_blur(
        &self,
        psd: &GaussianMixturePsd<T, N>,
        cov: &Gaussian<T, N>,
        h: &SVector<T, N>,
    ) -> T {
        psd.components.iter().fold(T::zero(), |acc, c| {
            acc + ClosedForm.normalized_blur(c, cov, h)
        })
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
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] unless `weight ≥ 0`, finite.
    pub fn new(weight: T) -> Result<Self, Error> {
        check_nonnegative("specular weight", weight)?;
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
}

impl<T: Real, const N: usize> BlurMethod<T, N, Smooth<T>> for ClosedForm {
    #[inline]
    fn blur(&self, psd: &Smooth<T>, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        psd.weight * cov.value(h)
    }
    /// `w g^Σ(h) |Σ|^{−1/2}`, in log space.
    #[inline]
    fn normalized_blur(&self, psd: &Smooth<T>, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        psd.weight * (cov.log_value(h) - T::lit(0.5) * cov.log_det()).exp()
    }
}
