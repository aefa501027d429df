//! The normalised autocorrelation `ρ = R/σ²` of a height PSD, in the spatial domain: what the
//! Kirchhoff phase screen needs for PSDs whose powers `F{ρⁿ}` have no closed form
//! ([`crate::interaction::roughness::KirchhoffQuadrature`]).

use nalgebra::Vector2;

use super::special::ln_gamma;
use super::{GaussianMixturePsd, GaussianPsd, KCorrelation, Psd};
use crate::real::Real;

/// A height PSD whose normalised autocorrelation `ρ(ξ) = R(ξ)/σ²` (`ρ(0) = 1`) can be evaluated
/// in the spatial domain (separations ξ in the PSD's surface frame, length units).
///
/// # Formula
/// ```text
/// R(ξ) = (2π)⁻¹ ∫ p(ζ) e^{iζ·ξ} d²ζ,   ρ = R/R(0)
/// Gaussian R = σ² g^Λ:                   ρ(ξ) = exp(−½ ξᵀΛ⁻¹ξ)
/// Gaussian mixture Σⱼ σⱼ² g^{Λⱼ}:        ρ(ξ) = Σⱼ (σⱼ²/σ²) exp(−½ ξᵀΛⱼ⁻¹ξ)
/// K-correlation (n = 2), ν = (γ − 1)/2:  ρ(r) = 2^{1−ν}/Γ(ν) s^ν K_ν(s),  s = r/√T  (Matérn)
/// ```
pub trait Autocorrelation<T: Real>: Psd<T, 2> {
    /// `ρ(ξ) = R(ξ)/σ²` (1 at ξ = 0; 0 for a PSD of zero variance).
    #[must_use]
    fn normalized_autocorrelation(&self, xi: &Vector2<T>) -> T;

    /// A radius beyond which `|ρ| ≤ level` in every direction (`0 < level < 1`), for the range
    /// of spatial quadratures.
    #[must_use]
    fn decay_radius(&self, level: T) -> T;
}

impl<T: Real> Autocorrelation<T> for GaussianPsd<T, 2> {
    /// `exp(−½ ξᵀΛ⁻¹ξ)`, `Λ⁻¹` the spectral covariance.
    #[inline]
    fn normalized_autocorrelation(&self, xi: &Vector2<T>) -> T {
        self.spectral_shape().log_value_of_inverse(xi).exp()
    }
    /// `√(2 ln(1/level) λ_max(Λ))`.
    fn decay_radius(&self, level: T) -> T {
        let c = self.spectral_shape().covariance();
        let (a, b, d) = (c[(0, 0)], c[(0, 1)], c[(1, 1)]);
        let half = T::lit(0.5);
        let lmin = (a + d) * half - ((a - d) * (a - d) * T::lit(0.25) + b * b).sqrt();
        // λ_max(Λ) = 1/λ_min(Λ⁻¹), the latter from the determinant where it rounds to 0.
        let lmin = if lmin > T::zero() {
            lmin
        } else {
            (a * d - b * b) / (a + d)
        };
        (T::lit(2.0) * (-level.ln()) / lmin).sqrt()
    }
}

impl<T: Real> Autocorrelation<T> for GaussianMixturePsd<T, 2> {
    /// `Σⱼ (σⱼ²/σ²) ρⱼ(ξ)`.
    fn normalized_autocorrelation(&self, xi: &Vector2<T>) -> T {
        let total = self.variance();
        if total <= T::zero() {
            return T::zero();
        }
        self.components().iter().fold(T::zero(), |acc, c| {
            acc + c.variance() / total * c.normalized_autocorrelation(xi)
        })
    }
    /// The largest component radius.
    fn decay_radius(&self, level: T) -> T {
        self.components()
            .iter()
            .fold(T::zero(), |m, c| m.max(c.decay_radius(level)))
    }
}

impl<T: Real> Autocorrelation<T> for KCorrelation<T, 2> {
    /// The Matérn function of `s = |ξ|/√T` with `ν = (γ − 1)/2` ([`matern`]).
    fn normalized_autocorrelation(&self, xi: &Vector2<T>) -> T {
        let s = xi.norm().to_f64() / self.t().to_f64().sqrt();
        T::lit(matern(self.nu_2d(), s))
    }
    /// From the Matérn tail `ρ ≈ 2^{1−ν}/Γ(ν) (s/2)^{ν−½}√(π/2)… e^{−s}`: the `s` where
    /// `e^{−s} s^{max(ν − ½, 0)}` reaches `level`, found by a few fixed-point steps, times 1.2.
    fn decay_radius(&self, level: T) -> T {
        let nu = self.nu_2d();
        let target = -level.to_f64().ln() + (ln_gamma(nu).max(0.0));
        let mut s = target.max(1.0);
        for _ in 0..20 {
            s = target + (nu - 0.5).max(0.0) * s.max(1.0).ln();
        }
        T::lit(1.2 * s * self.t().to_f64().sqrt())
    }
}

/// The normalised Matérn correlation `ρ(s) = 2^{1−ν}/Γ(ν) s^ν K_ν(s)` (`ρ(0) = 1`), the
/// autocorrelation of the 2-D K-correlation PSD with `ν = (γ − 1)/2`.
///
/// # Formula
/// ```text
/// ρ(s) = Γ(ν)⁻¹ ∫₀^∞ t^{ν−1} exp(−t − s²/(4t)) dt        (from K_ν = K_{−ν}'s integral)
/// ν = ½: e^{−s};   ν = 3/2: (1 + s) e^{−s};   ν = 5/2: (1 + s + s²/3) e^{−s}
/// ```
/// The half-integer orders are exact; any other `ν > 0` integrates in `u = ln t` with the
/// trapezoid rule (the integrand decays double-exponentially on both sides, so the rule
/// converges geometrically; nodes every half width of the peak, at most 1/4 apart, until it
/// falls below 10⁻¹⁸ of it): relative error below 10⁻¹² (tested against the half-integer forms
/// and `K₁`). Cost: 20–400 exponentials (small `ν` and `s` take the most).
#[must_use]
pub fn matern(nu: f64, s: f64) -> f64 {
    let s = s.abs();
    if s == 0.0 {
        return 1.0;
    }
    let half = |k: f64| (nu - k).abs() < 1e-15;
    if half(0.5) {
        return (-s).exp();
    }
    if half(1.5) {
        return (1.0 + s) * (-s).exp();
    }
    if half(2.5) {
        return (1.0 + s + s * s / 3.0) * (-s).exp();
    }
    // f(u) = ν u − e^u − s² e^{−u}/4, peak where f'(u) = 0: e^u = (ν + √(ν² + s²))/2.
    let q = 0.25 * s * s;
    let t_star = 0.5 * (nu + (nu * nu + s * s).sqrt());
    let u_star = t_star.ln();
    let f = |u: f64| nu * u - u.exp() - q * (-u).exp();
    let f_star = f(u_star);
    let width = 1.0 / (t_star + q / t_star).sqrt();
    // At most 1/4: for small s the left tail e^{νu} ends in the double-exponential cut-off
    // e^{−s²e^{−u}/4}, a feature of width ~1 in u far from the peak.
    let h = (0.5 * width).min(0.25);
    let mut sum = 1.0; // the peak, relative to e^{f_star}
    for dir in [1.0, -1.0] {
        let mut k = 1.0;
        loop {
            let term = (f(u_star + dir * k * h) - f_star).exp();
            sum += term;
            if term < 1e-18 || k > 1e6 {
                break;
            }
            k += 1.0;
        }
    }
    (f_star + (sum * h).ln() - ln_gamma(nu)).exp()
}

#[cfg(test)]
mod tests {
    use super::matern;

    /// The trapezoid form against the half-integer closed forms (ν nudged by 10⁻¹⁴ so that the
    /// integral is used) and `ρ(1) = K₁(1)` for ν = 1 (`K₁(1) = 0.60190723019723457…`,
    /// Abramowitz & Stegun table 9.8): 1e-12 relative.
    #[test]
    fn matern_integral_matches_closed_forms() {
        for s in [1e-6_f64, 0.01, 0.3, 1.0, 4.0, 20.0, 60.0] {
            for (nu, exact) in [
                (0.5, (-s).exp()),
                (1.5, (1.0 + s) * (-s).exp()),
                (2.5, (1.0 + s + s * s / 3.0) * (-s).exp()),
            ] {
                let got = matern(nu + 2e-15, s);
                assert!(
                    (got / exact - 1.0).abs() < 1e-12,
                    "ν {nu}, s {s}: {got} vs {exact}"
                );
            }
        }
        let k1 = 0.601_907_230_197_234_57;
        assert!((matern(1.0, 1.0) / k1 - 1.0).abs() < 1e-12);
        assert_eq!(matern(0.7, 0.0), 1.0);
    }
}
