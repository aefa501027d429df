//! The scattering coefficient `σ_s` of a medium for one incident packet: the integral of the
//! differential scattering over the sphere of exit directions.
//!
//! # Formula
//! ```text
//! σ_s = (1/S0) ∫_{S²} [dI/dV(r̂)]₀ dΩ = (1/k²) ∫_{|v| ≤ 2k} f(r̂(v)) d²v,   f = [dI/dV]₀/S0
//!     = (|L|/k²) ∫₀^{2π} dψ ∫₀^{ρ_max(ψ)} f(r̂(L ρ ê_ψ)) ρ dρ,        ρ_max(ψ) = 2k/|L ê_ψ|
//! r̂(v) = (1 − 2a²) d̂ + 2a√(1 − a²) (v_x x̂ + v_y ŷ)/|v|,   a = |v|/2k        (Lambert, about d̂)
//! ```
//! `L` is the Cholesky factor of the lobe's transverse covariance ([`super::lobes`]), so that
//! in `z = L⁻¹v` the lobe is round and of unit width. The rule: the trapezoid rule in ψ (4
//! nodes when the integrand is symmetric about d̂ — an isotropic PSD and isotropic transverse
//! shapes, where the integrand holds only the harmonics 0 and ±2 of the rotation `T` and 4
//! nodes are exact — [`AZIMUTHS`] otherwise), 8-point Gauss–Legendre on radial panels
//! `[0, ρ₀], [ρ₀, 2ρ₀], …, [½, 1], [1, 2], [2, 3], …, [7, 8], [8, 16], [16, 32], …` up to
//! `ρ_max(ψ)` (unit steps over the Gaussian core), with `ρ₀ = ¼ min(1, s_min/s_max)`
//! (`s_min` the lobe's finest scale, `s_max` its widest). The square-root behaviour of `r̂(v)`
//! at the rim (the backward direction) is odd in `v` and cancels between `ψ` and `ψ + π`,
//! which the even node counts pair. Accuracy against adaptive quadrature on the sphere:
//! `tests/medium.rs` (`scattering_coefficient_against_adaptive_quadrature`).

use nalgebra::{Vector2, Vector3};

use super::coherence::VolumeCoherence;
use super::lobes::{LobeModel, eigenvalues2};
use super::scatterer::Scatterer;
use super::scattering::Channels;
use crate::interaction::PolarizationModel;
use crate::psd::Psd;
use crate::real::Real;

/// The azimuths of the rule when the integrand is not symmetric about d̂.
pub(crate) const AZIMUTHS: usize = 32;

/// 8-point Gauss–Legendre on `[−1, 1]`: the positive nodes and their weights (Abramowitz &
/// Stegun, Table 25.4).
const GL8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362_0),
    (0.525_532_409_916_329_0, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// At most this many radial panels per azimuth (a lobe ~`2⁵⁰` times narrower than the sphere).
const MAX_PANELS: usize = 64;

/// `−∞` as a finite-arithmetic-safe logarithm of 0.
#[inline]
pub(crate) fn neg_inf<T: Real>() -> T {
    -T::MAX * T::lit(2.0)
}

/// The radial edge after `b` (z units, the lobe of unit width): doubling below 1, unit steps
/// over the Gaussian core `[1, 8]`, doubling beyond (power-law tails, the sphere).
#[inline]
fn next_edge<T: Real>(b: T) -> T {
    let (one, eight) = (T::one(), T::lit(8.0));
    if b < one {
        (b + b).min(one)
    } else if b < eight {
        (b + one).floor().min(eight)
    } else {
        b + b
    }
}

/// A sum of positive terms `v e^{ln}` kept as `e^m s`.
#[derive(Debug, Clone, Copy)]
struct LogSum<T: Real> {
    m: T,
    s: T,
}

impl<T: Real> LogSum<T> {
    fn new() -> Self {
        Self {
            m: neg_inf(),
            s: T::zero(),
        }
    }
    #[inline]
    fn add(&mut self, ln: T, v: T) {
        if !(v > T::zero() && ln > neg_inf::<T>() && ln.is_finite()) {
            return;
        }
        if ln > self.m {
            self.s = self.s * (self.m - ln).exp() + v;
            self.m = ln;
        } else {
            self.s += v * (ln - self.m).exp();
        }
    }
    fn ln(&self) -> T {
        if self.s > T::zero() {
            self.m + self.s.ln()
        } else {
            neg_inf()
        }
    }
}

/// `ln σ_s` and the fraction of it from beyond three lobe widths (`|z| > 3`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Coefficient<T: Real> {
    pub(crate) ln_sigma: T,
    pub(crate) far: T,
}

/// The exit direction of the Lambert-disk point `v` (packet basis) about `d̂`.
#[inline]
pub(crate) fn direction<T: Real>(
    x: &Vector3<T>,
    y: &Vector3<T>,
    d: &Vector3<T>,
    v: Vector2<T>,
    k: T,
) -> Vector3<T> {
    let n = v.norm();
    let a2 = (n / (k + k)).powi(2).min(T::one());
    let cos = T::one() - a2 - a2;
    let sin = (T::lit(4.0) * a2 * (T::one() - a2)).sqrt();
    let (c, s) = if n > T::zero() {
        (v.x / n, v.y / n)
    } else {
        (T::one(), T::zero())
    };
    let r = d * cos + (x * c + y * s) * sin;
    r / r.norm()
}

/// `σ_s` of the packet behind `channels` (module formula).
pub(crate) fn scattering_coefficient<T, P, M, Pol, Coh>(
    channels: &Channels<T, Pol, Coh>,
    coherence: &Coh,
    psd: &P,
    scatterer: &M,
    model: &LobeModel<T>,
) -> Coefficient<T>
where
    T: Real,
    P: Psd<T, 3>,
    M: Scatterer<T>,
    Pol: PolarizationModel,
    Coh: VolumeCoherence<T, P>,
{
    let k = channels.k;
    let f = &channels.frame;
    let n_psi = if model.axial { 4 } else { AZIMUTHS };
    let l = model.l;
    let (_, e_max) = eigenvalues2(&(l * l.transpose()));
    let ratio = model.s_min / e_max.sqrt();
    let rho0 = if ratio.is_finite() && ratio > T::zero() {
        ratio.min(T::one()) * T::lit(0.25)
    } else {
        T::lit(0.25)
    };
    let mut total = LogSum::new();
    let mut far = LogSum::new();
    let three = T::lit(3.0);
    for j in 0..n_psi {
        let psi = T::two_pi() * (T::lit(j as f64) + T::lit(0.5)) / T::lit(n_psi as f64);
        let (s, c) = psi.sin_cos();
        let w = l * Vector2::new(c, s);
        let rho_max = (k + k) / w.norm();
        let (mut a, mut b) = (T::zero(), rho0.min(rho_max));
        for _ in 0..MAX_PANELS {
            let half = (b - a) * T::lit(0.5);
            let mid = (a + b) * T::lit(0.5);
            for &(x, wt) in &GL8 {
                for sign in [-T::one(), T::one()] {
                    let rho = mid + sign * half * T::lit(x);
                    let weight = half * T::lit(wt) * rho;
                    let r = direction(&f.x, &f.y, &f.k, w * rho, k);
                    let g = channels.geometry(r);
                    let (u, ln_e) = channels.stokes_part(coherence, psd, scatterer, &g);
                    let ln = ln_e + weight.ln();
                    total.add(ln, u[0]);
                    if rho > three {
                        far.add(ln, u[0]);
                    }
                }
            }
            if b >= rho_max {
                break;
            }
            a = b;
            b = next_edge(b).min(rho_max);
        }
    }
    let ln_total = total.ln();
    let ln_det_l = (l[(0, 0)] * l[(1, 1)]).ln();
    let ln_sigma =
        ln_total + (T::two_pi() / T::lit(n_psi as f64)).ln() + ln_det_l - T::lit(2.0) * k.ln();
    let far = if ln_total > neg_inf::<T>() {
        (far.ln() - ln_total).exp().min(T::one())
    } else {
        T::zero()
    };
    Coefficient {
        ln_sigma: if ln_total > neg_inf::<T>() {
            ln_sigma
        } else {
            neg_inf()
        },
        far,
    }
}
