//! The coherent specular lobe near the horizon: its mass over the propagating directions, by
//! which the renderer layer normalises it.
//!
//! # Formula
//! In the projected-disk coordinates `u` of the exit direction (its tangential components,
//! `|u| < 1` propagating), the kernel's coherent lobe is `𝒩_Σ(u − c) · F` times the ratio of the
//! exit's cosine to the centre's, with `c` the mirror (or Snell) direction and `Σ = Ξ/k²` the
//! section of the light's coherence in these units. Its share of the incident power is
//! ```text
//! E = ∫_{|u|<1} √(1 − |u|²) 𝒩_Σ(u − c) d²u / √(1 − |c|²)
//! ```
//! `E → 1` as the lobe narrows; near the horizon part of the Gaussian lies beyond the disk and
//! the cosine varies across it, so `E` may be far from 1 (0.27–6.8 for a lossless interface at
//! 85–89° with 2–100 µm of surface coherence). `E` is also the irradiance the light's plane-wave
//! components actually deliver onto the surface, relative to the `cos θ_i` the kernel assumes
//! (components beyond the disk are evanescent and carry none), so dividing the lobe by `E`
//! makes it a response per unit of delivered irradiance.
//!
//! # Evaluation
//! With `e = c/|c|` the radial direction, `f = √(1 − |c|²)` the centre's cosine, and the lobe's
//! radial and tangential variances `s_rr = eᵀΣe`, `s_tt`, the small parameter is
//! `t = max(√s_rr / f², √s_tt / f)`. For `t ≤ 1/24`, the second-order expansion about `c`
//! ```text
//! E ≈ 1 − ½ (s_rr / f⁴ + s_tt / f²)
//! ```
//! (the Hessian of `√(1 − |u|²)` at `c` is `−diag(1/f³, 1/f)` in `(e, e⊥)`), whose next term is
//! about `2 t⁴ < 6·10⁻⁶`. For `t ≤ 1/12` (where the horizon lies at least 6 standard deviations
//! from the centre: every lobe under the horizon rule, whose `t ≤ 1/Q = 1/16`) the 8 × 8-point
//! Gauss–Hermite rule of the lobe's own Gaussian (64 square roots; within 2·10⁻⁸ of a
//! brute-force midpoint rule, `rules_against_brute_force`). Otherwise Gauss–Legendre in
//! `(e, e⊥)` coordinates: the tangential
//! offset `x` over the lobe's seven standard deviations (cut at `|x| < 1`), and for each `x`
//! the radial coordinate `y = a sin ψ` (`a = √(1 − x²)`), in which the horizon is `ψ = ±π/2`
//! and `√(a² − y²) = a cos ψ` is smooth, over the seven standard deviations of the conditional
//! Gaussian of `y` given `x`; 3 × 8 nodes each (576 exponentials and sines: a few µs, which
//! made the path tracer 3.7× slower when it also served `1/24 < t ≤ 1/12`). Against adaptive
//! quadrature (scipy, 1e-11) of the same integral: 1.5·10⁻⁶ (expansion, the sun at 85°),
//! 9·10⁻⁶ (rule, the sun at 88°), but 5.8·10⁻⁵ at θ = 0.8, `t = 1/12`; for `t > 1/12` (fixed
//! widths narrow against the horizon only) it differs from the midpoint rule by up to 1·10⁻⁴,
//! which of the two is off there is not settled. Against the verification kit's hemisphere
//! quadrature of the kernel's own lobe (`tests/bsdf/horizon.rs`): within 6.9·10⁻⁶ over 0–89° and
//! 2 µm to sunlight. Everything in `f64`.

use nalgebra::{Matrix2, Vector2};

use crate::numerics::GL8;

/// The expansion is used for `t ≤ 1/TAYLOR_INVERSE_REACH` (module docs).
const TAYLOR_INVERSE_REACH: f64 = 24.0;
/// Gauss–Hermite is used for `t ≤ 1/HERMITE_INVERSE_REACH`, where the horizon lies at least
/// `HERMITE_INVERSE_REACH/2` = 6 standard deviations from the centre (module docs).
const HERMITE_INVERSE_REACH: f64 = 12.0;
/// The 8-point Gauss–Hermite rule for the standard normal density (probabilists' Hermite
/// polynomials): nodes and weights (`numpy.polynomial.hermite_e.hermegauss(8)`, weights
/// divided by `√(2π)`; its moments are checked in the tests).
const GH8: [(f64, f64); 8] = [
    (-4.144_547_186_125_894_5, 0.000_112_614_538_375_367_65),
    (-2.802_485_861_287_541_6, 0.009_635_220_120_788_258),
    (-1.636_519_042_435_108, 0.117_239_907_661_759_05),
    (-0.539_079_811_351_375_1, 0.373_012_257_679_077_36),
    (0.539_079_811_351_375_1, 0.373_012_257_679_077_36),
    (1.636_519_042_435_108, 0.117_239_907_661_759_05),
    (2.802_485_861_287_541_6, 0.009_635_220_120_788_258),
    (4.144_547_186_125_894_5, 0.000_112_614_538_375_367_65),
];
/// The quadrature covers this many standard deviations of the lobe.
const REACH: f64 = 7.0;
/// Gauss–Legendre panels (of 8 nodes) per coordinate.
const PANELS: usize = 3;

/// The lobe's mass `E` (module docs) for the covariance `sigma` (in projected-disk units,
/// any orthonormal tangent basis) and centre `c` (same basis). 1 for a centre on or beyond the
/// horizon (no propagating partner: the lobe is then not normalised) and for a covariance that
/// is not positive definite.
#[must_use]
#[expect(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "a NaN must fail the test too"
)]
pub(crate) fn lobe_mass(sigma: &Matrix2<f64>, c: &Vector2<f64>) -> f64 {
    let rho = c.norm();
    if !(rho < 1.0) {
        return 1.0;
    }
    let f2 = (1.0 - rho) * (1.0 + rho);
    let f = f2.sqrt();
    let e = if rho > 0.0 {
        c / rho
    } else {
        Vector2::new(1.0, 0.0)
    };
    let ep = Vector2::new(-e.y, e.x);
    let srr = e.dot(&(sigma * e));
    let stt = ep.dot(&(sigma * ep));
    let srt = e.dot(&(sigma * ep));
    let det = srr * stt - srt * srt;
    if !(srr > 0.0 && stt > 0.0 && det > 0.0 && det.is_finite()) {
        return 1.0;
    }
    let t = (srr.sqrt() / f2).max(stt.sqrt() / f);
    if t <= 1.0 / TAYLOR_INVERSE_REACH {
        return 1.0 - 0.5 * (srr / (f2 * f2) + stt / f2);
    }
    if t <= 1.0 / HERMITE_INVERSE_REACH {
        return hermite(rho, f, srr, srt, det);
    }
    quadrature(rho, f, stt, srt, det)
}

/// `E` by the 8 × 8-point Gauss–Hermite rule of the lobe's own Gaussian, in the basis
/// `(e, e⊥)`: `(y, x) = L ξ` with `L` the Cholesky factor of the covariance (radial first).
/// The integrand `√(1 − |u|²)` is analytic within the horizon, ≥ 6 standard deviations away
/// here, beyond the rule's outermost node (4.14).
fn hermite(rho: f64, f: f64, srr: f64, srt: f64, det: f64) -> f64 {
    let l11 = srr.sqrt();
    let (l21, l22) = (srt / l11, (det / srr).sqrt());
    let f2 = f * f;
    let mut total = 0.0;
    for &(a, wa) in &GH8 {
        let y = l11 * a;
        // 1 − |u|² = f² − y (2ρ + y) − x², without forming 1 − ρ² again.
        let base = f2 - y * (2.0 * rho + y);
        let mut inner = 0.0;
        for &(b, wb) in &GH8 {
            let x = l21 * a + l22 * b;
            inner += wb * (base - x * x).max(0.0).sqrt();
        }
        total += wa * inner;
    }
    total / f
}

/// `E` by the rule of the module docs, in the basis `(e, e⊥)`: the tangential offset `x`
/// by Gauss–Legendre over the lobe's reach, and for each `x` the radial coordinate
/// `y = a sin ψ` (`a = √(1 − x²)`: the horizon at ψ = ±π/2, where `√(a² − y²) = a cos ψ`)
/// by Gauss–Legendre in ψ over the reach of the conditional Gaussian of `y` given `x`.
fn quadrature(rho: f64, f: f64, stt: f64, srt: f64, det: f64) -> f64 {
    let sx = stt.sqrt();
    // y | x ~ 𝒩(ρ + (s_rt/s_tt) x, det/s_tt).
    let (slope, v) = (srt / stt, det / stt);
    let sv = v.sqrt();
    let x_hi = (REACH * sx).min(1.0);
    let mut total = 0.0;
    let dx = 2.0 * x_hi / PANELS as f64;
    for p in 0..PANELS {
        let mid = -x_hi + dx * (p as f64 + 0.5);
        for &(node, weight) in &GL8 {
            let x = mid + 0.5 * dx * node;
            let a2 = (1.0 - x) * (1.0 + x);
            if a2 <= 0.0 {
                continue;
            }
            let a = a2.sqrt();
            let mu = rho + slope * x;
            let lo = (mu - REACH * sv) / a;
            let hi = (mu + REACH * sv) / a;
            if lo >= 1.0 || hi <= -1.0 {
                continue;
            }
            let (psi_lo, psi_hi) = (lo.max(-1.0).asin(), hi.min(1.0).asin());
            let dpsi = (psi_hi - psi_lo) / PANELS as f64;
            let mut inner = 0.0;
            for q in 0..PANELS {
                let m = psi_lo + dpsi * (q as f64 + 0.5);
                for &(t, w) in &GL8 {
                    let (sp, cp) = (m + 0.5 * dpsi * t).sin_cos();
                    let d = a * sp - mu;
                    inner += w * cp * cp * (-0.5 * d * d / v).exp();
                }
            }
            inner *= 0.5 * dpsi * a2 / (core::f64::consts::TAU.sqrt() * sv);
            total += 0.5 * dx * weight * inner * (-0.5 * x * x / stt).exp();
        }
    }
    total / (core::f64::consts::TAU.sqrt() * sx * f)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Gauss–Hermite rule integrates the standard normal's moments exactly to degree 15.
    #[test]
    fn hermite_rule_moments() {
        let mut want = 1.0;
        for k in 0..8 {
            let got: f64 = GH8.iter().map(|(x, w)| w * x.powi(2 * k)).sum();
            assert!(
                (got - want).abs() <= 1e-12 * want,
                "E ξ^{}: {got} vs {want}",
                2 * k
            );
            want *= f64::from(2 * k + 1);
        }
        let odd: f64 = GH8.iter().map(|(x, w)| w * x.powi(7)).sum();
        assert!(odd.abs() < 1e-12);
    }

    /// `E` by brute force: the midpoint rule over ±10 standard deviations of the lobe's own
    /// Gaussian (independent of both rules), `m × m` cells.
    fn brute(rho: f64, f: f64, srr: f64, srt: f64, stt: f64, m: usize) -> f64 {
        let l11 = srr.sqrt();
        let (l21, l22) = (srt / l11, ((srr * stt - srt * srt) / srr).sqrt());
        let h = 20.0 / m as f64;
        let (mut total, mut mass) = (0.0, 0.0);
        for i in 0..m {
            let a = -10.0 + h * (i as f64 + 0.5);
            for j in 0..m {
                let b = -10.0 + h * (j as f64 + 0.5);
                let w = (-0.5 * (a * a + b * b)).exp();
                let (y, x) = (l11 * a, l21 * a + l22 * b);
                let v = f * f - y * (2.0 * rho + y) - x * x;
                total += w * v.max(0.0).sqrt();
                mass += w;
            }
        }
        total / (mass * f)
    }

    /// Gauss–Hermite (`1/24 < t ≤ 1/12`) and the horizon-adapted quadrature (`t > 1/12`)
    /// against the brute-force midpoint rule (600 × 600 cells over ±10σ): radial and
    /// tangential widths, correlations and centres from the normal to 89.5°. Gauss–Hermite is
    /// within 2e-8 (one run; and within 3e-11 of scipy's `dblquad` at θ = 0.8, `t = 1/12`, where
    /// the quadrature was 5.8e-5 off: why it was replaced there).
    #[test]
    fn rules_against_brute_force() {
        let (mut worst_h, mut worst_q, mut n) = (0.0_f64, 0.0_f64, 0);
        for &theta in &[0.0_f64, 0.3, 0.8, 1.2, 1.4, 1.5, 1.562] {
            let rho = theta.sin();
            let f2 = (1.0 - rho) * (1.0 + rho);
            let f = f2.sqrt();
            for &t in &[1.0 / 23.0, 1.0 / 16.0, 1.0 / 12.0, 1.0 / 10.0, 1.0 / 6.0] {
                for &(ratio, corr) in &[(1.0, 0.0), (0.3, 0.5), (0.05, -0.8), (1.0, 0.9)] {
                    let srr = (t * f2).powi(2);
                    let stt = (ratio * t * f).powi(2);
                    let srt = corr * (srr * stt).sqrt();
                    let det = srr * stt - srt * srt;
                    let want = brute(rho, f, srr, srt, stt, 600);
                    if t <= 1.0 / HERMITE_INVERSE_REACH {
                        worst_h = worst_h.max((hermite(rho, f, srr, srt, det) - want).abs());
                    } else {
                        worst_q = worst_q.max((quadrature(rho, f, stt, srt, det) - want).abs());
                    }
                    n += 1;
                }
            }
        }
        println!("{n} cases: Gauss–Hermite within {worst_h:e}, quadrature within {worst_q:e}");
        assert!(worst_h < 1e-7, "{worst_h:e}");
        // The quadrature's range cuts the lobe at the horizon (3–6 standard deviations),
        // where the midpoint rule's own error is of the order of this difference (1.0e-4 in
        // one run): printed, and bounded loosely (module docs, "Evaluation").
        assert!(worst_q < 1e-3, "{worst_q:e}");
    }

    /// The expansion and the quadrature agree where one hands over to the other, and the
    /// quadrature converges (its nodes halved in spacing change nothing at that level).
    #[test]
    fn expansion_meets_quadrature_at_the_hand_over() {
        for &theta in &[0.0_f64, 0.5, 1.2, 1.45, 1.5] {
            let rho = theta.sin();
            let f2 = (1.0 - rho) * (1.0 + rho);
            let f = f2.sqrt();
            // A radial variance at the hand-over t = 1/24, the tangential one below it.
            let srr = (f2 / TAYLOR_INVERSE_REACH).powi(2);
            let stt = (f / (2.0 * TAYLOR_INVERSE_REACH)).powi(2).min(srr);
            let taylor = 1.0 - 0.5 * (srr / (f2 * f2) + stt / f2);
            let quad = quadrature(rho, f, stt, 0.0, srr * stt);
            assert!(
                (taylor - quad).abs() < 1e-5,
                "θ = {theta}: expansion {taylor}, quadrature {quad}"
            );
        }
    }
}
