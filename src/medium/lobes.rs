//! The lobe of a packet's scattering in a medium, as the scattering-coefficient quadrature
//! and the sampler see it: the transverse covariance of the scattered lobe in `h`, and radial
//! lobes on the Lambert disk of exit directions.
//!
//! # Formula
//! ```text
//! v = (2k/|r̂ + d̂|) (r̂·x̂, r̂·ŷ),   |v| = |h| = k|r̂ − d̂| ∈ [0, 2k],   d²v = k² dΩ    (Lambert's equal-area map about d̂)
//! lobe covariance in v ≈ h_⊥:  PlaneWave Λ⊥,  Partial Λ⊥ + Ξ⊥,  Incoherent Ξ⊥     (Λ the PSD's spectral covariance)
//! Gaussian radial lobe:  g(v) = exp(−|v|²/2s²)/(2πs²),               mass in the disk F(2k) = 1 − e^{−2k²/s²}
//! power radial lobe:     g(v) = (β−1)/(πs²) (1 + |v|²/s²)^{−β},        F(2k) = 1 − (1 + 4k²/s²)^{1−β}
//! ```
//! `⊥` is the block in the packet's transverse basis (x̂, ŷ); `Ξ⊥ = Θ⊥_½⁻¹`.

use nalgebra::{Matrix2, Matrix3};

use super::spectrum::VolumeLobes;
use crate::frame::Frame;
use crate::gaussian::Gaussian;
use crate::interaction::CoherenceLevel;
use crate::real::Real;

/// `(λ_min, λ_max)` of a symmetric 2×2 matrix.
#[inline]
pub(crate) fn eigenvalues2<T: Real>(m: &Matrix2<T>) -> (T, T) {
    let half = T::lit(0.5);
    let mean = (m[(0, 0)] + m[(1, 1)]) * half;
    let r = ((m[(0, 0)] - m[(1, 1)]) * half).hypot((m[(0, 1)] + m[(1, 0)]) * half);
    ((mean - r).max(T::zero()), mean + r)
}

/// `Pᵀ A P`, `P = [x̂ ŷ]`: the transverse block of a world 3×3 matrix in the packet basis.
#[inline]
fn transverse<T: Real>(a: &Matrix3<T>, f: &Frame<T>) -> Matrix2<T> {
    let (x, y) = (f.x, f.y);
    let ax = a * x;
    let ay = a * y;
    let off = (x.dot(&ay) + y.dot(&ax)) * T::lit(0.5);
    Matrix2::new(x.dot(&ax), off, off, y.dot(&ay))
}

/// `true` when `a ∝ I` to 64 ε.
#[inline]
fn isotropic3<T: Real>(a: &Matrix3<T>) -> bool {
    let mean = a.trace() / T::lit(3.0);
    (a - Matrix3::identity() * mean).amax() <= T::lit(64.0) * T::EPSILON * mean.abs()
}

/// `true` when `a ∝ I` to 64 ε.
#[inline]
fn isotropic2<T: Real>(a: &Matrix2<T>) -> bool {
    let mean = (a[(0, 0)] + a[(1, 1)]) * T::lit(0.5);
    (a - Matrix2::identity() * mean).amax() <= T::lit(64.0) * T::EPSILON * mean.abs()
}

/// A radial lobe on the Lambert disk (module formula).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Radial<T: Real> {
    /// `s²` (rad²/length²).
    pub(crate) s2: T,
    /// `β` of a power lobe; `None` for a Gaussian lobe.
    pub(crate) beta: Option<T>,
    /// The lobe's share of the mixture.
    pub(crate) weight: T,
}

/// The lobe of one packet in one medium (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LobeModel<T: Real> {
    /// Lower Cholesky factor of the transverse lobe covariance (packet basis).
    pub(crate) l: Matrix2<T>,
    /// The smallest feature scale of the lobe (rad/length).
    pub(crate) s_min: T,
    /// The integrand is symmetric about d̂ (isotropic PSD, `Θ⊥ ∝ I` in every used channel).
    pub(crate) axial: bool,
    /// Radial lobes for the sampler (weights sum to 1 over the first `n`).
    pub(crate) radial: [Radial<T>; 4],
    pub(crate) n: usize,
}

impl<T: Real> LobeModel<T> {
    /// The model of a PSD's lobe for a packet of frame `frame` and (where the level uses it)
    /// inverse coherence `xi` (`Ξ_½`, world), at the coherence level `level`; `channels_axial`
    /// says whether every channel's transverse shape is isotropic.
    pub(crate) fn new(
        lobes: VolumeLobes<'_, T>,
        level: CoherenceLevel,
        xi: Option<&Gaussian<T, 3>>,
        frame: &Frame<T>,
        channels_axial: bool,
        k: T,
    ) -> Self {
        let xi_t = xi.map(|x| transverse(x.covariance(), frame));
        let add = |a: Matrix2<T>| match (level, xi_t) {
            (CoherenceLevel::Partial, Some(x)) => a + x,
            (CoherenceLevel::Incoherent, Some(x)) => x,
            _ => a,
        };
        let coherence_axial = level == CoherenceLevel::PlaneWave || channels_axial;
        // The sampler's lobes may not be narrower than a direction of T resolves.
        let floor = (T::lit(64.0) * T::EPSILON * k).powi(2);
        let mut radial = [Radial {
            s2: T::one(),
            beta: None,
            weight: T::zero(),
        }; 4];
        let (cov, s_min, psd_axial, n) = match lobes {
            VolumeLobes::Gaussian(lambda) => {
                let a = add(transverse(&lambda, frame));
                let (e1, e2) = eigenvalues2(&a);
                radial[0] = Radial {
                    s2: e2.max(floor),
                    beta: None,
                    weight: T::one(),
                };
                let mut n = 1;
                if e2 > T::lit(4.0) * e1 {
                    radial[0].weight = T::lit(0.5);
                    radial[1] = Radial {
                        s2: e1.max(floor),
                        beta: None,
                        weight: T::lit(0.5),
                    };
                    n = 2;
                }
                (a, e1.sqrt(), isotropic3(&lambda), n)
            }
            VolumeLobes::Mixture(components) => {
                let total: T = components
                    .iter()
                    .fold(T::zero(), |s, c| s + crate::psd::Psd::<T, 3>::variance(c));
                let mut second = Matrix2::zeros();
                let (mut lo, mut hi) = (T::MAX, T::zero());
                let mut axial = true;
                for c in components {
                    let lambda = c.spectral_shape().covariance();
                    axial &= isotropic3(lambda);
                    let w = crate::psd::Psd::<T, 3>::variance(c) / total;
                    let a = add(transverse(lambda, frame));
                    second += a * w;
                    let (e1, e2) = eigenvalues2(&a);
                    lo = lo.min(e1);
                    hi = hi.max(e2);
                }
                // Up to four Gaussian lobes at scales spread geometrically over [lo, hi]; each
                // component counts toward the first scale at least as wide as its own.
                let n = if hi <= T::lit(4.0) * lo { 1 } else { 4 };
                let ratio = if n == 1 { T::one() } else { hi / lo.max(floor) };
                for (b, r) in radial.iter_mut().enumerate().take(n) {
                    let s2 = if n == 1 {
                        hi
                    } else {
                        lo.max(floor) * ratio.powf(T::lit(b as f64 / 3.0))
                    };
                    *r = Radial {
                        s2: s2.max(floor),
                        beta: None,
                        weight: T::zero(),
                    };
                }
                for c in components {
                    let w = crate::psd::Psd::<T, 3>::variance(c) / total;
                    let a = add(transverse(c.spectral_shape().covariance(), frame));
                    let e2 = eigenvalues2(&a).1;
                    let b = (0..n)
                        .find(|&b| radial[b].s2 * T::lit(1.000001) >= e2)
                        .unwrap_or(n - 1);
                    radial[b].weight += w;
                }
                (second, lo.sqrt(), axial, n)
            }
            VolumeLobes::KCorrelation { t, gamma } => {
                let core = Matrix2::identity() / t;
                let a = add(core);
                let (e1, e2) = eigenvalues2(&a);
                let nu = (gamma + T::one()) * T::lit(0.5);
                radial[0] = match level {
                    CoherenceLevel::Incoherent => Radial {
                        s2: e2.max(floor),
                        beta: None,
                        weight: T::one(),
                    },
                    _ => Radial {
                        s2: e2.max(floor),
                        beta: Some(nu),
                        weight: T::one(),
                    },
                };
                (a, e1.sqrt(), true, 1)
            }
        };
        let l = cholesky2(&cov);
        Self {
            l,
            s_min,
            axial: psd_axial && coherence_axial,
            radial,
            n,
        }
    }

    /// `true` when the transverse shape `theta` is isotropic (for `channels_axial`).
    #[inline]
    pub(crate) fn isotropic_shape(theta: &Matrix2<T>) -> bool {
        isotropic2(theta)
    }
}

/// The lower Cholesky factor of a 2×2 SPD matrix (a tiny diagonal floor where it is singular).
#[inline]
fn cholesky2<T: Real>(a: &Matrix2<T>) -> Matrix2<T> {
    let l00 = a[(0, 0)].max(T::MIN_POSITIVE).sqrt();
    let l10 = (a[(1, 0)] + a[(0, 1)]) * T::lit(0.5) / l00;
    let r = (a[(1, 1)] - l10 * l10)
        .max(a[(1, 1)] * T::EPSILON)
        .max(T::MIN_POSITIVE);
    Matrix2::new(l00, T::zero(), l10, r.sqrt())
}
