//! The scattering coefficient `σ_s` of a medium for one incident packet: the integral of the
//! differential scattering over the sphere of exit directions.
//!
//! # Formula
//! ```text
//! σ_s = (1/S0) ∫_{S²} [dI/dV(r̂)]₀ dΩ = (1/k²) ∫_{|v| ≤ 2k} f(r̂(v)) d²v,   f = [dI/dV]₀/S0
//!     = (|L|/k²) ∫₀^{2π} dψ ∫₀^{ρ_max(ψ)} f(r̂(L ρ ê_ψ)) ρ dρ,        ρ_max(ψ) = 2k/|L ê_ψ|
//! r̂(v) = (1 − 2a²) d̂ + 2a√(1 − a²) (v_x x̂ + v_y ŷ)/|v|,   a = |v|/2k        (Lambert, about d̂)
//! ```
//! `L` is the Cholesky factor of the lobe's covariance on the Lambert disk ([`super::lobes`]; a
//! larger eigenvalue beyond the disk's `(2k)²` capped there, so that the disk is not a sliver in
//! `z`), so that in `z = L⁻¹v` the lobe is round and of unit width. The integrand is evaluated
//! at `h = √(1 − a²) v − (|v|²/2k) d̂` formed from `v` (relative accuracy ε; `k(r̂ − d̂)` of a
//! rounded r̂ carries `ε k`). The rule: the trapezoid rule in ψ with
//! [`AZIMUTHS`] nodes — or one node when the integrand is symmetric about d̂ (an isotropic PSD
//! and isotropic transverse shapes): then the terms of the first row of `m̄ T` in `cos 2φ`,
//! `sin 2φ` integrate to 0 and are left out, and the rest does not depend on φ —,
//! 8-point Gauss–Legendre on radial panels
//! `[0, ρ₀], [ρ₀, 2ρ₀], …, [½, 1], [1, 2], [2, 3], …, [7, 8], [8, 16], [16, 32], …` up to
//! `ρ_max(ψ)` (unit steps over the Gaussian core), with `ρ₀ = ¼ min(1, s_min/s_max)`
//! (`s_min` the lobe's finest scale, `s_max` its widest). The square-root behaviour of `r̂(v)`
//! at the rim (the backward direction) is odd in `v` and cancels between `ψ` and `ψ + π`,
//! which the even node count pairs (in the symmetric case the integrand depends on `|v|²`
//! alone). Accuracy against adaptive quadrature on the sphere
//! (`tests/medium/born.rs`, `scattering_coefficient_against_adaptive_quadrature`): ≤ 3e-15 where
//! the integrand is symmetric, 4e-11–8e-11 for anisotropic media and coherence (1.8e-7 with 8
//! azimuths, 1e-15 with 32), 1e-7 for a Gauss–Hermite blur of a K-correlation PSD.

use nalgebra::{Vector2, Vector3};

use super::coherence::VolumeCoherence;
use super::lobes::{LobeModel, eigenvalues2};
use super::scatterer::Scatterer;
use super::scattering::Channels;
use crate::interaction::polarization::PolarizationModel;
use crate::psd::Psd;
use crate::real::Real;

/// The azimuths of the rule when the integrand is not symmetric about d̂.
pub(crate) const AZIMUTHS: usize = 16;

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

/// The scattering vector `h = k(r̂(v) − d̂)` and `cos Θ` of the Lambert-disk point `v` (packet
/// basis), formed from `v` without the exit direction:
/// `h = √(1 − a²) (v_x x̂ + v_y ŷ) − (|v|²/2k) d̂`, `cos Θ = 1 − 2a²`, `a = |v|/2k`. Relative
/// accuracy ε in every component: `k(r̂ − d̂)` from a rounded r̂ carries an absolute error `ε k`,
/// which in `f32` is a thousandth of a lobe 2.7·10³ λ wide.
#[inline]
pub(crate) fn scattering_vector<T: Real>(
    x: &Vector3<T>,
    y: &Vector3<T>,
    d: &Vector3<T>,
    v: Vector2<T>,
    k: T,
) -> (Vector3<T>, T) {
    let n2 = v.norm_squared();
    let a2 = (n2 / (T::lit(4.0) * k * k)).min(T::one());
    let h = (x * v.x + y * v.y) * (T::one() - a2).sqrt() - d * (n2 / (k + k)).min(k + k);
    (h, T::one() - a2 - a2)
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
    // Symmetric about d̂: one azimuth, the φ-dependent terms (which integrate to 0) left out.
    let n_psi = if model.axial { 1 } else { AZIMUTHS };
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
        let wn = w.norm();
        let dir_t = w / wn;
        let rho_max = (k + k) / wn;
        let (mut a, mut b) = (T::zero(), rho0.min(rho_max));
        for _ in 0..MAX_PANELS {
            let half = (b - a) * T::lit(0.5);
            let mid = (a + b) * T::lit(0.5);
            for &(x, wt) in &GL8 {
                for sign in [-T::one(), T::one()] {
                    let rho = mid + sign * half * T::lit(x);
                    let weight = half * T::lit(wt) * rho;
                    let (h, cos_theta) = scattering_vector(&f.x, &f.y, &f.k, w * rho, k);
                    let (value, ln_e) = channels.intensity_part(
                        coherence,
                        psd,
                        scatterer,
                        (&h, cos_theta),
                        (dir_t.x, dir_t.y),
                        model.axial,
                    );
                    let ln = ln_e + weight.ln();
                    total.add(ln, value);
                    if rho > three {
                        far.add(ln, value);
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
    let ln_det_l = l[(0, 0)].ln() + l[(1, 1)].ln();
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

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix2, Vector3};
    use num_complex::Complex;

    use super::super::scatterer::{Dipole, Scatterer};
    use super::super::scattering::Channels;
    use crate::frame::Frame;
    use crate::interaction::polarization::PolarizationModel;
    use crate::interaction::{Full, Intensity, OneShape, Partial};
    use crate::jones::JonesMatrix;
    use crate::mueller::Mueller;
    use crate::packet::{CoherenceShape, WavePacket};
    use crate::psd::{ClosedForm, GaussianPsd};
    use crate::stokes::Stokes;

    /// A scatterer with every entry of its first row non-zero (a diattenuating retarder).
    struct Elliptic;
    impl Scatterer<f64> for Elliptic {
        fn mueller(&self, c: f64) -> Mueller<f64> {
            let j = nalgebra::Matrix2::new(
                Complex::new(1.0, 0.2),
                Complex::new(0.3 * c, -0.1),
                Complex::new(-0.2, 0.4),
                Complex::new(0.6, 0.5 * c),
            );
            Mueller::from_jones(&JonesMatrix::from_matrix(j).unwrap())
        }
    }

    /// The frame-free integrand of `σ_s` equals the first entry of the framed Stokes form, for a
    /// polarized two-shape packet, at every level, for the dipole and a scatterer with a full
    /// first row (so the signs of the `cos 2φ`, `sin 2φ` terms are checked).
    fn run<Pol: PolarizationModel, M: Scatterer<f64>>(m: &M) {
        let f = Frame::from_direction_and_x(Vector3::new(0.3, -0.2, 0.9), Vector3::x()).unwrap();
        let p = WavePacket::new(
            Stokes::new(1.0, 0.3, 0.4, -0.5).unwrap(),
            CoherenceShape::new(Matrix2::new(4.0, 1.0, 1.0, 3.0)).unwrap(),
            CoherenceShape::new(Matrix2::new(5.0, 0.5, 0.5, 3.5)).unwrap(),
            f,
            0.5,
        )
        .unwrap()
        .with_longitudinal_coherence(2.0)
        .unwrap();
        let psd = GaussianPsd::<f64, 3>::isotropic(1e-3, 0.4).unwrap();
        let coh = Partial(ClosedForm);
        let ch = Channels::<f64, Pol, Partial>::new(&p, &psd, &coh).unwrap();
        // From 0.08 rad: exactly forward the frames are the fallback's, where only a symmetric
        // scatterer (not `Elliptic`) is independent of them.
        for i in 1..40 {
            let t = 0.08 * f64::from(i);
            let phi = 0.37 * f64::from(i);
            let (c, s) = (phi.cos(), phi.sin());
            let r = (f.k * t.cos() + (f.x * c + f.y * s) * t.sin()).normalize();
            let h = (r - f.k) * p.wavenumber();
            let (value, ln) = ch.intensity_part(&coh, &psd, m, (&h, r.dot(&f.k)), (c, s), false);
            let (u, ln_s) = ch.stokes_part(&coh, &psd, m, &ch.geometry(r));
            let (a, b) = (value * ln.exp(), u[0] * ln_s.exp());
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1e-300),
                "{i}: {a:e} vs {b:e}"
            );
        }
    }

    #[test]
    fn intensity_part_is_the_first_stokes_entry() {
        run::<Full, _>(&Dipole);
        run::<Full, _>(&Elliptic);
        run::<OneShape, _>(&Elliptic);
        run::<Intensity, _>(&Elliptic);
    }
}
