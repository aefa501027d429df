//! The lobes of the kernel as distributions of the tangential scattering vector `h_t`: what
//! the sampler draws, each with its exact density.
//!
//! # Formula
//! ```text
//! specular:            K^spec ∝ 𝒩(h_t; 0, Ξ)                         (Partial, Incoherent)
//! scattered, Partial:  K ∝ (p * 𝒩_Ξ)(h_t)
//!   Gaussian PSD  p = 2π σ² 𝒩(·; 0, C_p)      ⇒  𝒩(h_t; 0, C_p + Ξ)
//!   mixture       p = Σ_j 2π σ_j² 𝒩(·; 0, C_j) ⇒  Σ_j (σ_j²/σ²) 𝒩(h_t; 0, C_j + Ξ)
//!   grating       p = 2π Σ_m η_m δ(· − ζ_m)    ⇒  Σ_m (η_m/Σ η) 𝒩(h_t; ζ_m, Ξ)
//!   K-correlation p ∝ (1 + T|ζ|²)^{−(γ+1)/2}   ⇒  ½ q_T,γ(h_t) + ½ 𝒩(h_t; 0, I/((γ+1)T) + Ξ)
//! scattered, PlaneWave: the same with Ξ = 0 (grating orders become Dirac deltas)
//! q_T,γ(h) = T (γ−1)/(2π) (1 + T|h|²)^{−(γ+1)/2}                       (unit mass on ℝ²)
//! ```
//! Every lobe is untruncated on ℝ² (no table, nothing to build but a 2×2 Cholesky factor); a
//! draw whose direction would be evanescent is rejected by the sampler, so that its density
//! is the lobe's own, restricted to the propagating directions (it integrates to the lobe's
//! mass there, ≤ 1).

use nalgebra::{Matrix2, Vector2};

use crate::real::Real;

/// `ln 2π`.
#[inline]
fn ln_two_pi<T: Real>() -> T {
    T::lit(core::f64::consts::TAU.ln())
}

/// A uniform clamped into `(0, 1]` for a logarithm (NaN → 1).
#[inline]
fn open_unit<T: Real>(v: T) -> T {
    let v = T::one() - v; // (0, 1] for v ∈ [0, 1)
    if v >= T::MIN_POSITIVE {
        v.min(T::one())
    } else {
        T::MIN_POSITIVE
    }
}

/// A Gaussian lobe `𝒩(h; c, L Lᵀ)` in the plane of `h_t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GaussLobe<T: Real> {
    pub(crate) centre: Vector2<T>,
    /// Lower-triangular Cholesky factor (l₀₀, l₁₀, l₁₁).
    pub(crate) l: [T; 3],
    /// `1/(2π l₀₀ l₁₁)`, the density at the centre.
    pub(crate) norm: T,
}

impl<T: Real> GaussLobe<T> {
    /// The lobe of covariance `cov` (symmetrised) about `centre`; `None` unless `cov` is
    /// positive definite with a normal determinant scale.
    #[inline]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN must fail the test too"
    )]
    pub(crate) fn new(centre: Vector2<T>, cov: &Matrix2<T>) -> Option<Self> {
        let a = cov[(0, 0)];
        let b = (cov[(0, 1)] + cov[(1, 0)]) * T::lit(0.5);
        let d = cov[(1, 1)];
        if !(a > T::zero() && a.is_finite() && d.is_finite()) {
            return None;
        }
        let l00 = a.sqrt();
        let l10 = b / l00;
        let r = d - l10 * l10;
        if !(r > T::zero()) {
            return None;
        }
        let l11 = r.sqrt();
        let norm = (T::two_pi() * l00 * l11).recip();
        (norm.is_finite() && norm >= T::MIN_POSITIVE).then_some(Self {
            centre,
            l: [l00, l10, l11],
            norm,
        })
    }

    /// A lower bound of the lobe's standard deviation along its narrowest axis: the smallest
    /// singular value of `L` is at least `|l₀₀ l₁₁| / ‖L‖_F`.
    #[inline]
    pub(crate) fn narrowest(&self) -> T {
        let [a, b, c] = self.l;
        (a * c).abs() / (a * a + b * b + c * c).sqrt()
    }

    /// A draw from two uniforms in `[0, 1)` (Box–Muller).
    #[inline]
    pub(crate) fn sample(&self, u: [T; 2]) -> Vector2<T> {
        let r = (-T::lit(2.0) * open_unit(u[0]).ln()).sqrt();
        let (s, c) = (T::two_pi() * u[1]).sin_cos();
        let (z0, z1) = (r * c, r * s);
        let [l00, l10, l11] = self.l;
        self.centre + Vector2::new(l00 * z0, l10 * z0 + l11 * z1)
    }

    /// `𝒩(h; c, L Lᵀ)`.
    #[inline]
    pub(crate) fn density(&self, h: &Vector2<T>) -> T {
        let [l00, l10, l11] = self.l;
        let z0 = (h.x - self.centre.x) / l00;
        let z1 = (h.y - self.centre.y - l10 * z0) / l11;
        self.norm * (-T::lit(0.5) * (z0 * z0 + z1 * z1)).exp()
    }
}

/// The isotropic power lobe `q_T,γ(h) = T (γ−1)/(2π) (1 + T|h|²)^{−(γ+1)/2}` (the K-correlation
/// PSD's own shape, unit mass on ℝ²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PowerLobe<T: Real> {
    t: T,
    /// `2/(γ − 1)`.
    inv_half_exp: T,
    /// `−(γ + 1)/2`.
    neg_exp: T,
    /// `ln(T (γ − 1)/(2π))`.
    ln_norm: T,
}

impl<T: Real> PowerLobe<T> {
    #[inline]
    pub(crate) fn new(t: T, gamma: T) -> Self {
        let gm1 = gamma - T::one();
        Self {
            t,
            inv_half_exp: T::lit(2.0) / gm1,
            neg_exp: -(gamma + T::one()) * T::lit(0.5),
            ln_norm: (t * gm1).ln() - ln_two_pi::<T>(),
        }
    }

    /// A draw: `T|h|² = (1 − v)^{−2/(γ−1)} − 1` (the inverse radial CDF
    /// `F = 1 − (1 + T|h|²)^{−(γ−1)/2}`), the angle uniform.
    #[inline]
    pub(crate) fn sample(&self, u: [T; 2]) -> Vector2<T> {
        let rho2 = (-self.inv_half_exp * open_unit(u[0]).ln()).exp_m1();
        let r = (rho2.max(T::zero()) / self.t).sqrt();
        let (s, c) = (T::two_pi() * u[1]).sin_cos();
        Vector2::new(r * c, r * s)
    }

    /// `ln q_T,γ(h)`.
    #[inline]
    pub(crate) fn log_density(&self, h: &Vector2<T>) -> T {
        self.ln_norm + self.neg_exp * (self.t * h.norm_squared()).ln_1p()
    }
}
