//! The lobe of a packet's scattering in a medium, as the scattering-coefficient quadrature
//! and the sampler see it: the transverse covariance of the scattered lobe in `h`, and radial
//! lobes on the Lambert disk of exit directions.
//!
//! # Formula
//! ```text
//! v = (2k/|r̂ + d̂|) (r̂·x̂, r̂·ŷ),   |v| = |h| = k|r̂ − d̂| ∈ [0, 2k],   d²v = k² dΩ    (Lambert's equal-area map about d̂)
//! h = √(1 − a²) v − (|v|²/2k) d̂,   a = |v|/2k                                     (on the sphere)
//! 3-D lobe covariance C in h (packet basis):  PlaneWave Λ,  Partial Λ + Ξ,  Incoherent Ξ   (Λ the PSD's spectral covariance)
//! hᵀC⁻¹h ≈ vᵀPv + a² (c_zz − p) |v|²,   P = (C⁻¹)⊥ = (C⊥ − c cᵀ/C_zz)⁻¹,  c_zz = (C⁻¹)_zz
//! lobe covariance in v:  (P + q I)⁻¹,   q = √(c_zz − p_min)/2k  (0 unless c_zz > p_min)
//! Gaussian radial lobe:  g(v) = exp(−|v|²/2s²)/(2πs²),               mass in the disk F(2k) = 1 − e^{−2k²/s²}
//! power radial lobe:     g(v) = (β−1)/(πs²) (1 + |v|²/s²)^{−β},        F(2k) = 1 − (1 + 4k²/s²)^{1−β}
//! ```
//! `⊥` is the block in the packet's transverse basis (x̂, ŷ); `Ξ = blockdiag(Θ⊥_½⁻¹, Ξ_zz)` in
//! that basis, exact (from the packet, in `f64`: the transverse block of a world-axes `Ξ` rounded
//! to `f32` is noise once `Ξ_zz/λ_min(Θ⊥⁻¹) ≳ 1/ε₃₂`, issue 36). The lobe on the sphere is the
//! slice of the 3-D lobe at `h·d̂ = 0` (precision `P`), narrowed by the quartic term where the
//! lobe is narrower along d̂ than across it — the lobe edge `|v|² = 2k/√(c_zz − p)` as an
//! isotropic precision `q` (a long `σ_zz` at the `Incoherent` level: width `√(2k/σ_zz)`, not `1/w`).
//! An isotropic `C` gives `hᵀC⁻¹h = |v|²/s²` exactly (`|h| = |v|`), and `q = 0`.

use nalgebra::{Matrix2, Matrix3};

use super::basis::PacketXi;
use super::spectrum::VolumeLobes;
use crate::frame::Frame;
use crate::interaction::coherence::CoherenceLevel;
use crate::real::Real;

/// `(λ_min, λ_max)` of a symmetric 2×2 matrix.
#[inline]
pub(crate) fn eigenvalues2<T: Real>(m: &Matrix2<T>) -> (T, T) {
    let half = T::lit(0.5);
    let mean = (m[(0, 0)] + m[(1, 1)]) * half;
    let r = ((m[(0, 0)] - m[(1, 1)]) * half).hypot((m[(0, 1)] + m[(1, 0)]) * half);
    ((mean - r).max(T::zero()), mean + r)
}

/// `Qᵀ A Q`, `Q = [x̂ ŷ d̂]`: a world 3×3 matrix in the packet basis, in `f64`.
#[inline]
fn packet_basis<T: Real>(a: &Matrix3<T>, f: &Frame<T>) -> Matrix3<f64> {
    let q = Matrix3::from_columns(&[f.x, f.y, f.k]).map(|x| x.to_f64());
    let m = q.transpose() * a.map(|x| x.to_f64()) * q;
    (m + m.transpose()) * 0.5
}

/// The inverse of a 2×2 SPD matrix (`f64`).
#[inline]
fn inverse2(m: &Matrix2<f64>) -> Matrix2<f64> {
    let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
    Matrix2::new(m[(1, 1)], -m[(0, 1)], -m[(1, 0)], m[(0, 0)]) / det
}

/// The transverse covariance (in `v`, packet basis) of a 3-D Gaussian lobe of covariance `c`
/// (in `h`, packet basis) restricted to the sphere of exit directions (module formula): the
/// conditional covariance `S` of the slice `h_z = 0`, narrowed by the curvature term where the
/// lobe is narrower along d̂ than across it.
fn on_sphere(c: &Matrix3<f64>, k: f64) -> Matrix2<f64> {
    let ct = c.fixed_view::<2, 2>(0, 0).into_owned();
    let cz = c.fixed_view::<2, 1>(0, 2).into_owned();
    let czz = c[(2, 2)];
    // S = C⊥ − c cᵀ/C_zz: the covariance of the slice (the inverse of the precision's
    // transverse block).
    let s = if czz > 0.0 {
        ct - cz * cz.transpose() / czz
    } else {
        ct
    };
    let s = (s + s.transpose()) * 0.5;
    // (C⁻¹)_zz = 1/(C_zz − cᵀ C⊥⁻¹ c): the precision along d̂.
    let d = czz - (cz.transpose() * inverse2(&ct) * cz)[(0, 0)];
    let p_zz = if d > 0.0 { d.recip() } else { f64::INFINITY };
    let (_, s_max) = eigenvalues2(&s);
    let excess = p_zz - s_max.recip();
    if excess.is_nan() || excess <= 0.0 {
        return s;
    }
    // Q(v) ≈ vᵀPv + (c_zz − p)|v|⁴/4k²: the quartic edge |v|² = 2k/√(c_zz − p) as an
    // isotropic precision q, P + qI; S(I + qS)⁻¹ is its inverse. (An infinite p_zz: the
    // longitudinal variance lost to rounding in f64; q is then as large as f64 allows.)
    let q = (excess.sqrt() / (k + k)).min(f64::MAX.sqrt());
    let m = s * inverse2(&(Matrix2::identity() + s * q));
    (m + m.transpose()) * 0.5
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
    /// `ln` of the largest `F(d̂)` (per steradian, the scale of the phase matrix forward,
    /// where every lobe the model names peaks) that a lobe of this model can have once `σ_s`
    /// has resolved it: `64 · c · max(k²/(2π s_min²), 1/4π)`, `c = 2ν` for a power lobe
    /// (`(1 + T|q|²)^{−ν}` puts `2(ν − 1)` times a Gaussian's share of its mass in the core),
    /// 1 otherwise. ([`super::PhaseFunction::prepare`] refuses a packet whose `F(d̂)` exceeds it.)
    pub(crate) ln_peak: T,
    pub(crate) n: usize,
}

impl<T: Real> LobeModel<T> {
    /// The model of a PSD's lobe for a packet of frame `frame` and (where the level uses it)
    /// inverse coherence `xi` (`Ξ_½`, packet basis), at the coherence level `level`;
    /// `channels_axial` says whether every channel's transverse shape is isotropic.
    pub(crate) fn new(
        lobes: VolumeLobes<'_, T>,
        level: CoherenceLevel,
        xi: Option<&PacketXi>,
        frame: &Frame<T>,
        channels_axial: bool,
        k: T,
    ) -> Self {
        let xi = xi.map(PacketXi::matrix);
        let kf = k.to_f64();
        // The lobe's covariance in h (packet basis) for a PSD covariance Λ (packet basis), on
        // the sphere, rounded to T.
        let lobe = |lambda: Matrix3<f64>| -> Matrix2<T> {
            let c = match (level, xi) {
                (CoherenceLevel::Partial, Some(x)) => lambda + x,
                (CoherenceLevel::Incoherent, Some(x)) => x,
                _ => lambda,
            };
            on_sphere(&c, kf).map(T::lit)
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
                let a = lobe(packet_basis(&lambda, frame));
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
                    let a = lobe(packet_basis(lambda, frame));
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
                    let a = lobe(packet_basis(c.spectral_shape().covariance(), frame));
                    let e2 = eigenvalues2(&a).1;
                    let b = (0..n)
                        .find(|&b| radial[b].s2 * T::lit(1.000001) >= e2)
                        .unwrap_or(n - 1);
                    radial[b].weight += w;
                }
                (second, lo.sqrt(), axial, n)
            }
            VolumeLobes::KCorrelation { t, gamma } => {
                let a = lobe(Matrix3::identity() / t.to_f64());
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
        let l = quadrature_factor(&cov, k);
        let s2 = (s_min * s_min).max(floor);
        let c = radial[0]
            .beta
            .map_or(T::one(), |nu| (nu + nu).max(T::one()));
        let base = (k * k / (T::two_pi() * s2)).max((T::lit(4.0) * T::pi()).recip());
        Self {
            l,
            s_min,
            axial: psd_axial && coherence_axial,
            radial,
            n,
            ln_peak: base.ln() + c.ln() + T::lit(64.0f64.ln()),
        }
    }

    /// `true` when the transverse shape `theta` is isotropic (for `channels_axial`).
    #[inline]
    pub(crate) fn isotropic_shape(theta: &Matrix2<T>) -> bool {
        isotropic2(theta)
    }
}

/// The lower Cholesky factor `L` of the quadrature's lobe: the lobe covariance `a` with its
/// larger eigenvalue capped at the disk's `(2k)²` (or at the smaller one, if that is wider),
/// factored in `f64` (a tiny floor where singular).
///
/// The cap: a lobe wider than the disk `|v| ≤ 2k` in one direction and narrower in the other
/// made the disk a sliver in `z = L⁻¹v` (semi-axes `2k/s₁ ≫ 1` and `2k/s₂ ≪ 1`), whose rim
/// `ρ_max(ψ)` peaks over ~`s₁/s₂` rad of azimuth: 16 azimuths missed it (`f32` and `f64`
/// differed by 4e-3 with coherence widths of 0.8 λ and 1e-3 λ). Capped, every semi-axis is at
/// least 1 lobe width.
#[inline]
fn quadrature_factor<T: Real>(a: &Matrix2<T>, k: T) -> Matrix2<T> {
    let m = a.map(|x| x.to_f64());
    let (p, q, r) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
    let half = 0.5 * (p + r);
    let rad = (0.5 * (p - r)).hypot(q);
    let hi = half + rad;
    let lo = if hi > 0.0 {
        (p * r - q * q).max(0.0) / hi
    } else {
        0.0
    };
    let phi = 0.5 * q.atan2(0.5 * (p - r));
    let (sn, cs) = phi.sin_cos();
    // A lobe wider than the disk in both directions is left as it is (round enough in z).
    let cap = (2.0 * k.to_f64()).powi(2).max(lo);
    let tiny = f64::from(f32::MIN_POSITIVE);
    let (e1, e2) = (hi.min(cap).max(tiny), lo.min(cap).max(tiny));
    // R diag(e1, e2) Rᵀ, R = [[c, −s], [s, c]], and its Cholesky factor (det = e1 e2 exactly).
    let c00 = e1 * cs * cs + e2 * sn * sn;
    let c10 = (e1 - e2) * cs * sn;
    let l00 = c00.sqrt();
    let l = Matrix2::new(l00, 0.0, c10 / l00, (e1 * e2 / c00).sqrt());
    l.map(T::lit)
}
