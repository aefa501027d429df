//! Anisotropic Gaussians, their products, convolutions and Fourier transforms (Lemma S2.1,
//! Corollary S2.2).
//!
//! # Conventions
//! ```text
//! g^Σ(x) = exp(−½ xᵀ Σ⁻¹ x)                      unnormalised, Σ symmetric positive definite
//! F{f}(q) = (2π)^{−n/2} ∫ f(x) e^{−i q·x} dⁿx      unitary Fourier transform
//! (f * h)(x) = (2π)^{−n/2} ∫ f(y) h(x − y) dⁿy    convolution, so that F{f·h} = F{f} * F{h}
//! ```
//! The dimension `N` is a const generic: `N = 2` for surfaces (tangent plane), `N = 3` for volumes.
//!
//! Everything is evaluated through the Cholesky factor `Σ = L Lᵀ` (computed once, at
//! construction): `xᵀΣ⁻¹x = |L⁻¹x|²` by a triangular solve, `ln|Σ| = 2 Σᵢ ln Lᵢᵢ`. Neither the
//! inverse nor the determinant is formed by cofactors, so eigenvalues from 10⁻¹² to 10¹² and
//! anisotropy to 10⁶ stay finite; values that underflow return `0` while [`Gaussian::log_value`]
//! stays accurate.

use nalgebra::{Rotation, SMatrix, SVector};
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::numerics::{cholesky, is_nan, log_det_from_cholesky, solve_lower};
use crate::real::Real;

/// An anisotropic, centred Gaussian `g^Σ(x) = exp(−½ xᵀΣ⁻¹x)` in `N` dimensions.
///
/// # Formula
/// ```text
/// g^Σ(x) = exp(−½ xᵀ Σ⁻¹ x) = exp(−½ |L⁻¹ x|²),   Σ = L Lᵀ (Cholesky)
/// ```
/// Σ is validated once (finite, symmetric, positive definite); afterwards every operation is
/// infallible and allocation-free.
///
/// # Examples
/// ```
/// use gmueller::gaussian::Gaussian;
/// use nalgebra::{Matrix2, Vector2};
/// let g = Gaussian::new(Matrix2::new(2.0_f64, 0.5, 0.5, 1.0)).unwrap();
/// let x = Vector2::new(0.3, -0.4);
/// let inv = Matrix2::new(2.0_f64, 0.5, 0.5, 1.0).try_inverse().unwrap();
/// let direct = (-0.5 * (x.transpose() * inv * x)[0]).exp();
/// assert!((g.value(&x) - direct).abs() < 1e-14);
/// assert!((g.log_det() - 1.75_f64.ln()).abs() < 1e-14);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gaussian<T: Real, const N: usize> {
    cov: SMatrix<T, N, N>,
    chol: SMatrix<T, N, N>,
    log_det: T,
}

/// A Gaussian times a positive constant: `e^{log_scale} · g^Σ(x)`.
///
/// Returned by the closed forms whose result carries a constant (convolution, Fourier transform,
/// marginalisation). The constant is kept as a logarithm so it cannot overflow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaledGaussian<T: Real, const N: usize> {
    /// Natural logarithm of the constant factor.
    pub log_scale: T,
    /// The Gaussian shape.
    pub gaussian: Gaussian<T, N>,
}

impl<T: Real, const N: usize> ScaledGaussian<T, N> {
    /// `e^{log_scale} g^Σ(x)`; `0` where it underflows (also at huge or infinite `x`), never NaN
    /// for a non-NaN `x` as long as `log_scale < +∞` (true for every `ScaledGaussian` this crate
    /// returns: their `log_scale` is finite or `−∞`).
    #[inline]
    #[must_use]
    pub fn value(&self, x: &SVector<T, N>) -> T {
        (self.log_scale + self.gaussian.log_value(x)).exp()
    }

    /// `log_scale + ln g^Σ(x)`, accurate where [`Self::value`] underflows; `−∞` where
    /// [`Gaussian::log_value`] is, with the same NaN rule as [`Self::value`].
    #[inline]
    #[must_use]
    pub fn log_value(&self, x: &SVector<T, N>) -> T {
        self.log_scale + self.gaussian.log_value(x)
    }

    /// The constant factor `e^{log_scale}`.
    #[inline]
    #[must_use]
    pub fn scale(&self) -> T {
        self.log_scale.exp()
    }
}

/// The Cholesky factor of the sum of two Gaussians' covariances, `A + B`; `None` unless it is
/// positive definite.
///
/// # Formula (N = 2)
/// ```text
/// plain:  L = chol(A + B), kept when its last pivot ℓ₂₂² ≥ (A + B)₂₂ / 16 (≤ 16 ε lost to the
///         cancellation in (A + B)₂₂ − ℓ₂₁²)
/// else:   A + B = M Mᵀ,   M = [L_a  L_b]  (2×4, columns c₁ … c₄)
///         ℓ₁₁ = |M₁|,   ℓ₂₁ = M₁·M₂ / ℓ₁₁,   ℓ₂₂ = √|A + B| / ℓ₁₁,   |A + B| = Σ_{i<j} det[cᵢ cⱼ]²
/// ```
/// (`M₁`, `M₂` the rows of `M`; Cauchy–Binet for the determinant, each minor by
/// [`Real::diff_of_products`]). Why: the section of the coherence by the surface at grazing
/// incidence has a condition number of `1/cos²θ_i` ≈ 3·10⁷ at 89.99°, beyond `1/ε₃₂`; adding
/// it to the PSD's spectral covariance as matrices and factoring the sum lost the small
/// eigenvalue in `f32` (the blur came out 0). The plain factorisation is kept where it is
/// accurate, which is almost everywhere, because it is cheaper. Other `N`: the plain one.
#[inline(always)]
pub(crate) fn cholesky_of_sum<T: Real, const N: usize>(
    a: &Gaussian<T, N>,
    b: &Gaussian<T, N>,
) -> Option<SMatrix<T, N, N>> {
    let sum = a.cov + b.cov;
    if N != 2 {
        return cholesky(&sum).ok();
    }
    let (s00, s10, s11) = (sum[(0, 0)], sum[(1, 0)], sum[(1, 1)]);
    let l00 = s00.sqrt();
    let l10 = s10 / l00;
    let d = s11 - l10 * l10;
    if s00 > T::zero() && d * T::lit(16.0) >= s11 && d.is_finite() && l10.is_finite() {
        let mut l = SMatrix::<T, N, N>::zeros();
        l[(0, 0)] = l00;
        l[(1, 0)] = l10;
        l[(1, 1)] = d.sqrt();
        return Some(l);
    }
    // The factors by value: passing references out of line kept the hot path from holding the
    // two Gaussians in registers (the mixture blur ran 2× slower with the cold call present).
    cholesky_of_sum_from_factors(a.chol, b.chol)
}

/// The Cauchy–Binet branch of [`cholesky_of_sum`] (`N = 2`).
#[inline(always)]
fn cholesky_of_sum_from_factors<T: Real, const N: usize>(
    la: SMatrix<T, N, N>,
    lb: SMatrix<T, N, N>,
) -> Option<SMatrix<T, N, N>> {
    let (r1, r2) = (
        [la[(0, 0)], la[(0, 1)], lb[(0, 0)], lb[(0, 1)]],
        [la[(1, 0)], la[(1, 1)], lb[(1, 0)], lb[(1, 1)]],
    );
    let mut det = T::zero();
    for i in 0..4 {
        for j in (i + 1)..4 {
            let m = T::diff_of_products(r1[i], r2[j], r1[j], r2[i]);
            det += m * m;
        }
    }
    let dot = |a: &[T; 4], b: &[T; 4]| (0..4).fold(T::zero(), |s, k| s + a[k] * b[k]);
    let l11 = dot(&r1, &r1).sqrt();
    let l21 = dot(&r1, &r2) / l11;
    let l22 = det.sqrt() / l11;
    if !(l11 > T::zero()
        && l22 > T::zero()
        && l11.is_finite()
        && l22.is_finite()
        && l21.is_finite())
    {
        return None;
    }
    let mut l = SMatrix::<T, N, N>::zeros();
    l[(0, 0)] = l11;
    l[(1, 0)] = l21;
    l[(1, 1)] = l22;
    Some(l)
}

/// `|L⁻¹x|²` for a lower-triangular Cholesky factor `L`: never NaN for finite `x` (`+∞` when the
/// value exceeds the range), `+∞` for an infinite `x`, NaN only for a NaN `x`.
///
/// The plain substitution can meet `0 · ∞` (an overflowed `yᵢ` times a zero entry of `L`) at huge
/// finite `x`; only then is `x` rescaled by its largest entry and the squared norm assembled in
/// log space (`(s |y|)²` with `y = L⁻¹(x/s)`), so the common path costs one comparison.
#[inline]
pub(crate) fn mahalanobis_from_cholesky<T: Real, const N: usize>(
    l: &SMatrix<T, N, N>,
    x: &SVector<T, N>,
) -> T {
    let m = solve_lower(l, x).norm_squared();
    if is_nan(m) {
        rescaled_quadratic(x, |v| solve_lower(l, v))
    } else {
        m
    }
}

/// `|A x|²` for a linear map `apply = A` (finite entries), by rescaling: `x = s x̂` with
/// `s = max|xᵢ|`, then `(s |A x̂|)²` with the product formed in log space. NaN for a NaN `x`,
/// `+∞` for an infinite `x` or when `|A x̂|` itself overflows (the true value is then beyond the
/// range of `T` for every `A` of moderately bounded entries).
#[cold]
fn rescaled_quadratic<T: Real, const N: usize>(
    x: &SVector<T, N>,
    apply: impl Fn(&SVector<T, N>) -> SVector<T, N>,
) -> T {
    if x.iter().any(|&v| is_nan(v)) {
        return T::lit(f64::NAN);
    }
    let s = x.amax();
    if !s.is_finite() {
        return T::lit(f64::INFINITY);
    }
    if s == T::zero() {
        return T::zero();
    }
    let y = apply(&(x / s));
    if y.iter().any(|v| !v.is_finite()) {
        return T::lit(f64::INFINITY);
    }
    scaled_norm_sq(s.ln(), &y)
}

/// `(e^{log_s} |w|)²` for finite `w`, formed in log space so that neither the scale nor the
/// squares over- or underflow on the way (the result itself may be `+∞` or `0`).
#[inline]
fn scaled_norm_sq<T: Real, const N: usize>(log_s: T, w: &SVector<T, N>) -> T {
    let r = w.amax();
    if r == T::zero() {
        return T::zero();
    }
    let n = (w / r).norm(); // in [1, √N]
    (T::lit(2.0) * (log_s + r.ln() + n.ln())).exp()
}

/// `L⁻¹` of a lower-triangular `L`, column by column.
fn lower_inverse<T: Real, const N: usize>(l: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let mut inv = SMatrix::<T, N, N>::zeros();
    for j in 0..N {
        let mut e = SVector::<T, N>::zeros();
        e[j] = T::one();
        inv.set_column(j, &solve_lower(l, &e));
    }
    inv
}

/// `ln |det B|` by Gaussian elimination with partial pivoting (no cofactors), as the sum of the
/// logarithms of the pivots so that it neither over- nor underflows; `−∞` for a zero pivot.
fn log_abs_det<T: Real, const N: usize>(b: &SMatrix<T, N, N>) -> T {
    let mut a = *b;
    let mut log_det = T::zero();
    for j in 0..N {
        let mut piv = j;
        for i in (j + 1)..N {
            if a[(i, j)].abs() > a[(piv, j)].abs() {
                piv = i;
            }
        }
        a.swap_rows(j, piv);
        let d = a[(j, j)];
        if d == T::zero() {
            return T::lit(f64::NEG_INFINITY);
        }
        log_det += d.abs().ln();
        for i in (j + 1)..N {
            let f = a[(i, j)] / d;
            for k in j..N {
                let v = a[(j, k)];
                a[(i, k)] -= f * v;
            }
        }
    }
    log_det
}

/// `ln (2π)`.
fn ln_two_pi<T: Real>() -> T {
    T::lit(core::f64::consts::TAU.ln())
}

impl<T: Real> Gaussian<T, 2> {
    /// The Gaussian of the mirrored variable `D x`, `D = diag(1, −1)`: covariance `D Σ D`
    /// (exact: the off-diagonal entries of `Σ` and of its Cholesky factor negated).
    #[must_use]
    pub(crate) fn mirrored_y(&self) -> Self {
        let flip = |m: &SMatrix<T, 2, 2>| {
            let mut m = *m;
            m[(0, 1)] = -m[(0, 1)];
            m[(1, 0)] = -m[(1, 0)];
            m
        };
        Self {
            cov: flip(&self.cov),
            chol: flip(&self.chol),
            log_det: self.log_det,
        }
    }
}

impl<T: Real, const N: usize> Gaussian<T, N> {
    /// Builds `g^Σ` from its covariance (shape) matrix Σ.
    ///
    /// Σ is symmetrised as `(Σ + Σᵀ)/2` after checking that the asymmetry is at most
    /// `√ε · max|Σᵢⱼ|` (round-off from a product such as `Q Θ Qᵀ`).
    ///
    /// # Errors
    /// - [`Error::NonFinite`] if an entry is NaN or infinite;
    /// - [`Error::NotHermitian`] if Σ is not symmetric to that tolerance;
    /// - [`Error::NotPositiveDefinite`] if the Cholesky factorisation meets a non-positive pivot
    ///   (reported as `min_eigenvalue`).
    pub fn new(cov: SMatrix<T, N, N>) -> Result<Self, Error> {
        ensure_finite("Gaussian covariance", cov.iter().copied())?;
        let scale = cov.amax();
        let asym = (cov - cov.transpose()).amax();
        if asym > T::EPSILON.sqrt() * scale {
            return Err(Error::NotHermitian {
                what: "Gaussian covariance",
                asymmetry: asym.to_f64(),
            });
        }
        let cov = (cov + cov.transpose()) * T::lit(0.5);
        let chol = cholesky(&cov).map_err(|pivot| Error::NotPositiveDefinite {
            what: "Gaussian covariance",
            min_eigenvalue: pivot.to_f64(),
        })?;
        let log_det = log_det_from_cholesky(&chol);
        Ok(Self { cov, chol, log_det })
    }

    /// A Gaussian from the lower-triangular Cholesky factor `L` of its covariance (`Σ = L Lᵀ`),
    /// built by the caller in a numerically careful way: `None` unless every diagonal entry is
    /// positive and finite and `L Lᵀ` is finite. Skips every other check (the kernel's hot path).
    #[inline]
    pub(crate) fn from_cholesky(l: SMatrix<T, N, N>) -> Option<Self> {
        for i in 0..N {
            if !(l[(i, i)] > T::zero() && l[(i, i)].is_finite()) {
                return None;
            }
        }
        let cov = l * l.transpose();
        if !cov.iter().all(|x| x.is_finite()) {
            return None;
        }
        let log_det = log_det_from_cholesky(&l);
        Some(Self {
            cov,
            chol: l,
            log_det,
        })
    }

    /// The Gaussian of covariance `s Σ` (`s > 0`): Cholesky factor `√s L`, `ln|sΣ| = ln|Σ| + N ln s`;
    /// `None` unless `s` is positive and finite and the result's factor and covariance are finite
    /// and positive definite. No factorisation (the hot path of the Kirchhoff series, whose
    /// terms are one spectral shape scaled by the order `n`).
    #[inline]
    pub(crate) fn scaled(&self, s: T) -> Option<Self> {
        if !(s > T::zero() && s.is_finite()) {
            return None;
        }
        let root = s.sqrt();
        let chol = self.chol * root;
        let cov = self.cov * s;
        for i in 0..N {
            if !(chol[(i, i)] > T::zero() && chol[(i, i)].is_finite()) {
                return None;
            }
        }
        if !cov.iter().all(|x| x.is_finite()) {
            return None;
        }
        Some(Self {
            cov,
            chol,
            log_det: self.log_det + T::lit(N as f64) * s.ln(),
        })
    }

    /// The isotropic Gaussian `g^{s² I}` of standard deviation `s`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `s` is finite and positive.
    pub fn isotropic(s: T) -> Result<Self, Error> {
        if !(s > T::zero() && s.is_finite()) {
            return Err(Error::OutOfRange {
                what: "Gaussian standard deviation",
                value: s.to_f64(),
                expected: "(0, ∞)",
            });
        }
        Self::new(SMatrix::<T, N, N>::identity() * (s * s))
    }

    /// The covariance (shape) matrix Σ.
    #[inline]
    #[must_use]
    pub fn covariance(&self) -> &SMatrix<T, N, N> {
        &self.cov
    }

    /// The lower-triangular Cholesky factor `L`, `Σ = L Lᵀ`.
    #[inline]
    #[must_use]
    pub fn cholesky_factor(&self) -> &SMatrix<T, N, N> {
        &self.chol
    }

    /// `ln |Σ| = 2 Σᵢ ln Lᵢᵢ`.
    #[inline]
    #[must_use]
    pub fn log_det(&self) -> T {
        self.log_det
    }

    /// `|Σ|`, through the log-determinant (may overflow to ∞ or underflow to 0 at extreme scales;
    /// prefer [`Self::log_det`]).
    #[inline]
    #[must_use]
    pub fn det(&self) -> T {
        self.log_det.exp()
    }

    /// The precision matrix `Σ⁻¹ = L⁻ᵀ L⁻¹`, from the triangular inverse.
    #[must_use]
    pub fn precision(&self) -> SMatrix<T, N, N> {
        let li = lower_inverse(&self.chol);
        li.transpose() * li
    }

    /// The squared Mahalanobis distance `xᵀ Σ⁻¹ x = |L⁻¹x|²`.
    ///
    /// Defined for every `x`: in `[0, ∞)` for finite `x`, `+∞` where the value exceeds the range
    /// of `T` (e.g. `|x|` near `T::MAX`, or a huge `x` against a tiny Σ) and for an infinite `x`;
    /// NaN only when `x` has a NaN entry. (The plain substitution would give NaN from `0 · ∞`
    /// at huge finite `x`; that case is recomputed with `x` rescaled.)
    ///
    /// # Examples
    /// ```
    /// use gmueller::gaussian::Gaussian;
    /// use nalgebra::{Matrix2, Vector2};
    /// let g = Gaussian::new(Matrix2::new(1e-20_f64, 0.0, 0.0, 1.0)).unwrap();
    /// assert_eq!(g.mahalanobis_sq(&Vector2::new(1e300, 1.0)), f64::INFINITY);
    /// assert_eq!(g.value(&Vector2::new(1e300, 1.0)), 0.0);
    /// assert!((g.mahalanobis_sq(&Vector2::new(1e-10, 2.0)) - 5.0).abs() < 1e-14);
    /// ```
    #[inline]
    #[must_use]
    pub fn mahalanobis_sq(&self, x: &SVector<T, N>) -> T {
        mahalanobis_from_cholesky(&self.chol, x)
    }

    /// `ln g^Σ(x) = −½ xᵀΣ⁻¹x`, accurate where [`Self::value`] underflows.
    ///
    /// In `(−∞, 0]` for finite `x`: a finite negative number while `xᵀΣ⁻¹x` is representable,
    /// `−∞` beyond (see [`Self::mahalanobis_sq`]); never NaN unless `x` has a NaN entry.
    #[inline]
    #[must_use]
    pub fn log_value(&self, x: &SVector<T, N>) -> T {
        -T::lit(0.5) * self.mahalanobis_sq(x)
    }

    /// The unnormalised value `g^Σ(x) = exp(−½ xᵀΣ⁻¹x)` (module conventions), in `[0, 1]`: `0` on
    /// underflow, at huge finite `x` and at infinite `x`; NaN only for a NaN entry of `x`.
    #[inline]
    #[must_use]
    pub fn value(&self, x: &SVector<T, N>) -> T {
        self.log_value(x).exp()
    }

    /// `ln` of the normalised density `(2π)^{−N/2} |Σ|^{−1/2} g^Σ(x)`; `−∞` where
    /// [`Self::log_value`] is, never NaN for a non-NaN `x`.
    #[inline]
    #[must_use]
    pub fn log_density(&self, x: &SVector<T, N>) -> T {
        self.log_value(x) - T::lit(0.5) * (T::lit(N as f64) * ln_two_pi::<T>() + self.log_det)
    }

    /// The normalised density `(2π)^{−N/2} |Σ|^{−1/2} g^Σ(x)`, integrating to 1 over `ℝᴺ`; `0`
    /// where [`Self::value`] is (and `+∞` only if `|Σ|^{−1/2}` itself overflows at `x ≈ 0`).
    #[inline]
    #[must_use]
    pub fn density(&self, x: &SVector<T, N>) -> T {
        self.log_density(x).exp()
    }

    /// `ln ∫ g^Σ dᴺx = (N/2) ln 2π + ½ ln|Σ|`.
    #[inline]
    #[must_use]
    pub fn log_integral(&self) -> T {
        T::lit(0.5) * (T::lit(N as f64) * ln_two_pi::<T>() + self.log_det)
    }

    /// `g^{Σ⁻¹}(q) = exp(−½ qᵀ Σ q) = exp(−½ |Lᵀq|²)` in log form, without inverting anything.
    ///
    /// In `(−∞, 0]` for finite `q` (`−∞` where `qᵀΣq` exceeds the range), never NaN unless `q`
    /// has a NaN entry (huge `q` is rescaled, as in [`Self::mahalanobis_sq`]).
    #[inline]
    #[must_use]
    pub fn log_value_of_inverse(&self, q: &SVector<T, N>) -> T {
        let lt = self.chol.transpose();
        let m = (lt * q).norm_squared();
        let m = if is_nan(m) {
            rescaled_quadratic(q, |v| lt * v)
        } else {
            m
        };
        -T::lit(0.5) * m
    }

    /// The Gaussian with inverse covariance, `g^{Σ⁻¹}`.
    ///
    /// # Errors
    /// [`Error::NotPositiveDefinite`] if Σ⁻¹ is not representable (extreme scales in f32).
    pub fn inverse(&self) -> Result<Self, Error> {
        Self::new(self.precision())
    }

    /// The Gaussian in rotated coordinates: `g^Σ(Rᵀx) = g^{R Σ Rᵀ}(x)`.
    ///
    /// With `R` mapping local to world coordinates (`x_world = R x_local`), this turns a shape
    /// given in local coordinates into world coordinates.
    ///
    /// # Errors
    /// Only if round-off makes `R Σ Rᵀ` fail validation (practically never).
    pub fn rotated(&self, r: &Rotation<T, N>) -> Result<Self, Error> {
        let m = r.matrix();
        Self::new(m * self.cov * m.transpose())
    }

    /// Composition with a linear map: `g^Σ(B x) = g^{B⁻¹ Σ B⁻ᵀ}(x)`.
    ///
    /// # Errors
    /// [`Error::Singular`] if `B` is not invertible; otherwise as [`Gaussian::new`].
    pub fn compose_linear(&self, b: &SMatrix<T, N, N>) -> Result<Self, Error> {
        ensure_finite("linear map B", b.iter().copied())?;
        let binv = b.try_inverse().ok_or(Error::Singular {
            what: "linear map B",
        })?;
        // B⁻¹ L (B⁻¹ L)ᵀ keeps the product symmetric positive by construction.
        let f = binv * self.chol;
        Self::new(f * f.transpose())
    }

    /// Product of two centred Gaussians: `g^A(x) g^B(x) = g^C(x)`, `C = (A⁻¹ + B⁻¹)⁻¹`.
    ///
    /// # Formula
    /// ```text
    /// g^A g^B = g^{(A⁻¹ + B⁻¹)⁻¹}          (no constant factor)
    /// ```
    /// Computed from the precisions (a sum of positive matrices, no cancellation).
    ///
    /// # Errors
    /// Only if the result is not representable (extreme scales in f32).
    pub fn product(&self, other: &Self) -> Result<Self, Error> {
        let prec = self.precision() + other.precision();
        let pl = cholesky(&((prec + prec.transpose()) * T::lit(0.5))).map_err(|p| {
            Error::NotPositiveDefinite {
                what: "product precision",
                min_eigenvalue: p.to_f64(),
            }
        })?;
        let li = lower_inverse(&pl);
        Self::new(li.transpose() * li)
    }

    /// Product of two shifted Gaussians:
    /// `g^A(x − a) g^B(x − b) = e^{log_scale} g^C(x − c)`; returns `(scaled g^C, c)`.
    ///
    /// # Formula
    /// ```text
    /// C = (A⁻¹ + B⁻¹)⁻¹,  c = C (A⁻¹ a + B⁻¹ b),  log_scale = −½ (a − b)ᵀ (A + B)⁻¹ (a − b)
    /// ```
    ///
    /// `log_scale` is finite or `−∞` (shifts so far apart that the factor underflows; the
    /// [`ScaledGaussian`] then evaluates to `0`), never NaN.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if `a` or `b` has a NaN or infinite entry, or if the centre `c`
    /// overflows (shifts near `T::MAX`); otherwise as [`Gaussian::product`].
    pub fn product_shifted(
        &self,
        a: &SVector<T, N>,
        other: &Self,
        b: &SVector<T, N>,
    ) -> Result<(ScaledGaussian<T, N>, SVector<T, N>), Error> {
        ensure_finite("shift a", a.iter().copied())?;
        ensure_finite("shift b", b.iter().copied())?;
        let c = self.product(other)?;
        let centre = c.cov * (self.precision() * a + other.precision() * b);
        ensure_finite("product centre c (overflow)", centre.iter().copied())?;
        let sum = Self::new(self.cov + other.cov)?;
        // a − b may overflow for finite shifts: halve first (exact), the quadratic form is ×4.
        let d = a - b;
        let log_scale = if d.iter().all(|v| v.is_finite()) {
            sum.log_value(&d)
        } else {
            let h = T::lit(0.5);
            T::lit(4.0) * sum.log_value(&(a * h - b * h))
        };
        Ok((
            ScaledGaussian {
                log_scale,
                gaussian: c,
            },
            centre,
        ))
    }

    /// Convolution with the crate's convention: `g^A * g^B = (|A||B|/|A+B|)^{1/2} g^{A+B}`.
    ///
    /// # Formula
    /// ```text
    /// (g^A * g^B)(x) = (2π)^{−n/2} ∫ g^A(y) g^B(x − y) dⁿy = (|A| |B| / |A + B|)^{1/2} g^{A+B}(x)
    /// ```
    ///
    /// # Errors
    /// Only if `A + B` is not representable.
    pub fn convolve(&self, other: &Self) -> Result<ScaledGaussian<T, N>, Error> {
        let sum = Self::new(self.cov + other.cov)?;
        Ok(ScaledGaussian {
            log_scale: T::lit(0.5) * (self.log_det + other.log_det - sum.log_det),
            gaussian: sum,
        })
    }

    /// The unitary Fourier transform `F{g^Σ} = |Σ|^{1/2} g^{Σ⁻¹}`.
    ///
    /// # Errors
    /// Only if Σ⁻¹ is not representable. For evaluation use [`Self::log_fourier_at`], which
    /// never inverts.
    pub fn fourier(&self) -> Result<ScaledGaussian<T, N>, Error> {
        Ok(ScaledGaussian {
            log_scale: T::lit(0.5) * self.log_det,
            gaussian: self.inverse()?,
        })
    }

    /// `ln F{g^Σ}(q) = ½ ln|Σ| − ½ qᵀΣq`.
    #[inline]
    #[must_use]
    pub fn log_fourier_at(&self, q: &SVector<T, N>) -> T {
        T::lit(0.5) * self.log_det + self.log_value_of_inverse(q)
    }

    /// Lemma S2.1 (corrected): the unitary Fourier transform of `ξ ↦ g^Σ(B ξ)`, evaluated at `q`.
    ///
    /// # Formula
    /// ```text
    /// F{g^Σ(B ·)}(q) = |Σ|^{1/2} / |det B| · g^{Σ⁻¹}(B⁻ᵀ q)          (S2.1, corrected)
    /// ```
    /// The printed lemma has `B⁻¹ q` and `|B|`: the argument must be `B⁻ᵀ q` (the two agree only
    /// for symmetric `B`), and `|B|` is `|det B|` (test `lemma_s2_1_printed_form_fails`).
    ///
    /// The result is finite and `≥ 0`, or `+∞` when it exceeds the range of `T` (`|det B|` below
    /// `|Σ|^{1/2}/T::MAX`); never NaN. `B` is rescaled by its largest entry before it is
    /// inverted, so `B = 10⁻²⁰⁰ I` is not mistaken for a singular matrix.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if `B` or `q` has a NaN or infinite entry; [`Error::Singular`] if `B`
    /// is singular (a zero pivot, or an inverse that is not representable).
    ///
    /// # Examples
    /// ```
    /// use gmueller::gaussian::Gaussian;
    /// use nalgebra::{Matrix2, Vector2};
    /// let g = Gaussian::new(Matrix2::new(1.0_f64, 0.2, 0.2, 0.5)).unwrap();
    /// let b = Matrix2::new(1.0, 2.0, 0.0, 1.0);
    /// let q = Vector2::new(0.3, 0.7);
    /// // Same thing as the transform of the composed Gaussian g^{B⁻¹ΣB⁻ᵀ}:
    /// let composed = g.compose_linear(&b).unwrap();
    /// let lemma = g.fourier_of_linear_map(&b, &q).unwrap();
    /// assert!((lemma - composed.log_fourier_at(&q).exp()).abs() < 1e-14);
    /// ```
    #[doc(alias = "lemma_s2_1")]
    #[doc(alias = "S2.1")]
    pub fn fourier_of_linear_map(
        &self,
        b: &SMatrix<T, N, N>,
        q: &SVector<T, N>,
    ) -> Result<T, Error> {
        ensure_finite("linear map B", b.iter().copied())?;
        ensure_finite("frequency q", q.iter().copied())?;
        let singular = Error::Singular {
            what: "linear map B",
        };
        // B = s B̂ with max|B̂ᵢⱼ| = 1: B⁻ᵀ = B̂⁻ᵀ/s, ln|det B| = N ln s + ln|det B̂|.
        let s = b.amax();
        if s == T::zero() {
            return Err(singular);
        }
        let bn = b / s;
        let inv = bn.transpose().try_inverse().ok_or(singular.clone())?;
        let log_det_bn = log_abs_det(&bn);
        if !(log_det_bn.is_finite() && inv.iter().all(|v| v.is_finite())) {
            return Err(singular);
        }
        let log_det_b = T::lit(N as f64) * s.ln() + log_det_bn;
        // g^{Σ⁻¹}(B⁻ᵀq) = exp(−½ |Lᵀ B̂⁻ᵀ q|² / s²); |q| is rescaled too where that overflows.
        let arg = inv * q / s;
        let log_g = if arg.iter().all(|v| v.is_finite()) {
            self.log_value_of_inverse(&arg)
        } else {
            let r = q.amax();
            let w = self.chol.transpose() * (inv * (q / r));
            -T::lit(0.5) * scaled_norm_sq(r.ln() - s.ln(), &w)
        };
        Ok((T::lit(0.5) * self.log_det + log_g - log_det_b).exp())
    }

    /// Corollary S2.2: the Fourier transform of one packet term `e^{−i k ŝ·ξ} g^Θ(Qᵀ ξ)`.
    ///
    /// `self` is `g^Θ` in the packet's **local** coordinates; `q_local_to_world` is `Q`, with
    /// `ξ_world = Q ξ_local` (so `Ξ = Q Θ⁻¹ Qᵀ`, S2.18); `k_s` is the vector `k ŝ`, with ŝ pointing
    /// from the surface toward the source (the packet travels along −ŝ, hence the phase
    /// `e^{−i k ŝ·ξ}`).
    ///
    /// # Formula
    /// ```text
    /// F{e^{−ik ŝ·ξ} g^Θ(Qᵀξ)}(q) = |Θ|^{1/2} g^{Θ⁻¹}(Qᵀ(q + k ŝ)) = |Θ|^{1/2} g^{Q Θ⁻¹ Qᵀ}(q + k ŝ)   (S2.2)
    /// ```
    /// The seed's sign `q + kŝ` holds for this phase under the transform kernel `e^{−iq·x}`
    /// (test `corollary_s2_2_matches_quadrature_*`). The value is finite and `≥ 0` for finite
    /// input (`0` where it underflows, also when `q + kŝ` overflows), never NaN.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if `k_s`, `q` or the rotation has a NaN or infinite entry.
    #[doc(alias = "corollary_s2_2")]
    #[doc(alias = "S2.2")]
    pub fn fourier_of_packet_term(
        &self,
        q_local_to_world: &Rotation<T, N>,
        k_s: &SVector<T, N>,
        q: &SVector<T, N>,
    ) -> Result<T, Error> {
        let qt = q_local_to_world.matrix().transpose();
        ensure_finite("rotation Q", qt.iter().copied())?;
        ensure_finite("wave vector k ŝ", k_s.iter().copied())?;
        ensure_finite("frequency q", q.iter().copied())?;
        let sum = q + k_s;
        let log_g = if sum.iter().all(|v| v.is_finite()) {
            self.log_value_of_inverse(&(qt * sum))
        } else {
            // q + kŝ overflows: halve both (exact); the quadratic form is ×4.
            let h = T::lit(0.5);
            T::lit(4.0) * self.log_value_of_inverse(&(qt * (q * h + k_s * h)))
        };
        Ok((T::lit(0.5) * self.log_det + log_g).exp())
    }

    /// Fourier transform of a shifted, modulated Gaussian `g^Σ(x − a) e^{i k·x}`, at `q`.
    ///
    /// # Formula
    /// ```text
    /// F{g^Σ(· − a) e^{i k·}}(q) = e^{−i (q − k)·a} |Σ|^{1/2} g^{Σ⁻¹}(q − k)
    /// ```
    /// Where the magnitude underflows the result is exactly `0`, whatever the phase.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if `a`, `k` or `q` has a NaN or infinite entry, or if the phase
    /// `(q − k)·a` overflows while the magnitude is not zero (the phase is then undefined).
    pub fn fourier_shifted_modulated(
        &self,
        a: &SVector<T, N>,
        k: &SVector<T, N>,
        q: &SVector<T, N>,
    ) -> Result<Complex<T>, Error> {
        ensure_finite("shift a", a.iter().copied())?;
        ensure_finite("modulation k", k.iter().copied())?;
        ensure_finite("frequency q", q.iter().copied())?;
        let d = q - k;
        let log_g = if d.iter().all(|v| v.is_finite()) {
            self.log_value_of_inverse(&d)
        } else {
            // q − k overflows: halve both (exact); the quadratic form is ×4.
            let h = T::lit(0.5);
            T::lit(4.0) * self.log_value_of_inverse(&(q * h - k * h))
        };
        let m = (T::lit(0.5) * self.log_det + log_g).exp();
        if m == T::zero() {
            return Ok(Complex::new(T::zero(), T::zero()));
        }
        let phase = -d.dot(a);
        ensure_finite("phase (q − k)·a (overflow)", [phase])?;
        let (s, c) = phase.sin_cos();
        Ok(Complex::new(m * c, m * s))
    }
}

impl<T: Real> Gaussian<T, 3> {
    /// The **marginal** in the `(x, y)` plane: `∫ g^Σ(x, y, z) dz = √(2π |Σ|/|Σ₂|) g^{Σ₂}(x, y)`,
    /// with `Σ₂` the upper-left 2×2 block of Σ.
    ///
    /// Use it when the third coordinate is *integrated out* — e.g. the transform of the
    /// marginal is the restriction of the 3-D transform to `q_z = 0`. Rotate first
    /// ([`Self::rotated`]) to marginalise onto another plane.
    ///
    /// # Errors
    /// Only on non-representable results.
    pub fn marginal_xy(&self) -> Result<ScaledGaussian<T, 2>, Error> {
        let block = self.cov.fixed_view::<2, 2>(0, 0).into_owned();
        let g = Gaussian::new(block)?;
        Ok(ScaledGaussian {
            log_scale: T::lit(0.5) * (ln_two_pi::<T>() + self.log_det - g.log_det),
            gaussian: g,
        })
    }

    /// The **section** (conditional, slice) in the plane `z = 0`: `g^Σ(x, y, 0) = g^{S}(x, y)`
    /// with `S = Σ₂ − Σ₂₃ Σ₃₃⁻¹ Σ₃₂` the Schur complement — the inverse of the `(x, y)` block of Σ⁻¹.
    ///
    /// Use it when the function is *evaluated on* the plane (a surface sees the packet's coherence
    /// only on its tangent plane); for oblique incidence it differs from
    /// [`Self::marginal_xy`]. No constant factor: `g^Σ(x, y, 0) = g^S(x, y)` exactly.
    ///
    /// # Errors
    /// Only on non-representable results.
    pub fn section_xy(&self) -> Result<Gaussian<T, 2>, Error> {
        // Reorder to (z, x, y): the trailing 2×2 block of the Cholesky factor is the Schur
        // complement's factor, computed without subtraction of large terms.
        let p = [2usize, 0, 1];
        let perm = SMatrix::<T, 3, 3>::from_fn(|i, j| self.cov[(p[i], p[j])]);
        let l = cholesky(&perm).map_err(|piv| Error::NotPositiveDefinite {
            what: "Gaussian covariance",
            min_eigenvalue: piv.to_f64(),
        })?;
        let l2 = l.fixed_view::<2, 2>(1, 1).into_owned();
        Gaussian::new(l2 * l2.transpose())
    }
}

#[cfg(test)]
mod tests {
    use super::Gaussian;
    use nalgebra::{Matrix2, Vector2};

    /// `mirrored_y` is the law of `D x` (`D = diag(1, −1)`): its density at `D x` is the
    /// original's at `x`, and it equals the Gaussian built from `D Σ D` directly.
    #[test]
    fn mirrored_y_is_the_gaussian_of_the_mirrored_variable() {
        let g = Gaussian::new(Matrix2::<f64>::new(2.0, 0.7, 0.7, 0.5)).unwrap();
        let m = g.mirrored_y();
        let direct = Gaussian::new(Matrix2::<f64>::new(2.0, -0.7, -0.7, 0.5)).unwrap();
        for x in [
            Vector2::<f64>::new(0.3, -1.1),
            Vector2::new(-2.0, 0.4),
            Vector2::zeros(),
        ] {
            let dx = Vector2::new(x.x, -x.y);
            assert!((m.log_value(&dx) - g.log_value(&x)).abs() < 1e-14);
            assert!((m.log_value(&x) - direct.log_value(&x)).abs() < 1e-14);
        }
        // Not the identity for a correlated Gaussian (the check above can fail).
        let x = Vector2::<f64>::new(1.0, 1.0);
        assert!((m.log_value(&x) - g.log_value(&x)).abs() > 0.1);
    }
}
