//! Pearson's chi-square test of a direction sampler against a density per solid angle, in
//! both hemispheres of a surface: the bins are cells of a Cartesian grid in the projected-disk
//! coordinates `u = (d·t̂₁, d·t̂₂)` of each hemisphere (edges refined about the lobe centres),
//! their expected probabilities adaptive Gauss–Legendre quadrature (`quadrature.rs`) of
//! `pdf_ω(d(u))/|cos θ|` over the cell, and every draw that falls in no cell (a delta lobe, an
//! evanescent draw) counts in one more bin whose probability is the rest.
//!
//! Use it for any sampler of directions about a surface: a pdf that disagrees with what
//! `sample` returns (a missing Jacobian, a truncation mass left out) fails it. The bins' edges
//! ([`edges`]) are refined around the lobes so that narrow lobes are resolved.
//!
//! ```
//! use gmueller::verify::chi2::{Disk, Grid, edges, test};
//! use gmueller::verify::rng::SplitMix64;
//! use nalgebra::Vector3;
//! // Cosine-weighted directions over the upper hemisphere: pdf = cos θ / π.
//! let disk = Disk { t1: Vector3::x(), t2: Vector3::y(), n: Vector3::z() };
//! let grid = Grid { side: 1.0, ex: edges(8, &[], &[]), ey: edges(8, &[], &[]) };
//! let mut rng = SplitMix64(7);
//! let mut cosine = |_| {
//!     let (r, phi) = (rng.unit().sqrt(), std::f64::consts::TAU * rng.unit());
//!     Some(Vector3::new(r * phi.cos(), r * phi.sin(), (1.0 - r * r).sqrt()))
//! };
//! let right = |d: &Vector3<f64>| d.z / std::f64::consts::PI;
//! assert!(test(&disk, &[grid.clone()], &right, 20_000, &mut cosine).passes());
//! // A uniform pdf (1/2π) for the same draws is rejected.
//! let wrong = |_: &Vector3<f64>| 1.0 / std::f64::consts::TAU;
//! assert!(!test(&disk, &[grid], &wrong, 20_000, &mut cosine).passes());
//! ```

use nalgebra::{Vector2, Vector3};

use super::quadrature::integrate;

/// The standard normal 99.9 % quantile.
pub const Z_999: f64 = 3.090232306167814;

/// The 99.9 % quantile of χ² with `dof ≥ 1` degrees of freedom: [`chi2_quantile`]`(dof, 0.999)`.
#[must_use]
pub fn chi2_quantile_999(dof: usize) -> f64 {
    chi2_quantile(dof, 0.999)
}

/// The `p` quantile of χ² with `dof ≥ 1` degrees of freedom, `0 < p < 1`: the `x` with
/// `P(k/2, x/2) = p`, `P` the regularized lower incomplete gamma function.
///
/// # Formula
/// ```text
/// P(a, y) = e^{−y} y^a/Γ(a + 1) · Σ_{n≥0} yⁿ/((a + 1)(a + 2)⋯(a + n))     (a = k/2: Γ by recursion)
/// start:  x₀ = k (1 − 2/(9k) + z_p √(2/(9k)))³                            (Wilson & Hilferty 1931)
/// ```
/// then bisection on `P(k/2, x/2) − p` to a relative width of 1e-12. (Wilson–Hilferty alone is
/// 0.6 % high at k = 10 for p = 0.999, 0.04 % at k = 100.)
///
/// # Panics
/// If `dof = 0` or `p` is outside `(0, 1)`.
#[must_use]
pub fn chi2_quantile(dof: usize, p: f64) -> f64 {
    assert!(dof >= 1 && p > 0.0 && p < 1.0, "dof {dof}, p {p}");
    let a = dof as f64 / 2.0;
    let cdf = |x: f64| regularized_lower_gamma(a, x / 2.0);
    let k = dof as f64;
    let z = normal_quantile(p);
    let x0 = (k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3)).max(1e-3);
    let (mut lo, mut hi) = (x0, x0);
    while cdf(lo) > p {
        lo *= 0.5;
    }
    while cdf(hi) < p {
        hi *= 2.0;
    }
    while hi - lo > 1e-12 * hi {
        let mid = 0.5 * (lo + hi);
        if cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `P(a, y)` for `a = k/2` (integer or half-integer) by its power series; `ln Γ(a + 1)` by the
/// recursion `Γ(a + 1) = a Γ(a)` from `Γ(1) = 1` or `Γ(½) = √π`.
fn regularized_lower_gamma(a: f64, y: f64) -> f64 {
    if y <= 0.0 {
        return 0.0;
    }
    let mut ln_gamma = if (a - a.floor()).abs() < 0.25 {
        0.0
    } else {
        0.5 * std::f64::consts::PI.ln()
    };
    let mut b = a - a.floor()
        + if (a - a.floor()).abs() < 0.25 {
            1.0
        } else {
            0.0
        };
    // Now Γ(b) is e^{ln_gamma} (b = 1 or ½); raise b to a + 1.
    while b < a + 1.0 - 0.25 {
        ln_gamma += b.ln();
        b += 1.0;
    }
    let (mut term, mut sum, mut n) = (1.0f64, 1.0f64, 1.0f64);
    while term > 1e-17 * sum {
        term *= y / (a + n);
        sum += term;
        n += 1.0;
    }
    (-y + a * y.ln() - ln_gamma + sum.ln()).exp().min(1.0)
}

/// The standard normal quantile (Acklam's rational approximation, relative error < 1.2e-9):
/// only a starting point here.
fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383577518672690e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// Pearson's statistic with bins of expected count < 5 pooled; returns (χ², dof).
pub fn chi_square(counts: &[usize], probs: &[f64], n: usize) -> (f64, usize) {
    let (mut chi2, mut bins) = (0.0, 0);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (&o, &p) in counts.iter().zip(probs) {
        let e = p * n as f64;
        if e < 5.0 {
            pool_o += o as f64;
            pool_e += e;
        } else {
            chi2 += (o as f64 - e).powi(2) / e;
            bins += 1;
        }
    }
    if pool_e > 0.0 || pool_o > 0.0 {
        // An empty expectation with observed draws is an infinite discrepancy.
        chi2 += if pool_e > 0.0 {
            (pool_o - pool_e).powi(2) / pool_e
        } else {
            f64::INFINITY
        };
        bins += 1;
    }
    (chi2, bins.max(1) - 1)
}

/// The surface's tangent frame and normal (caller's orientation).
#[derive(Debug, Clone, Copy)]
pub struct Disk {
    /// First tangent.
    pub t1: Vector3<f64>,
    /// Second tangent.
    pub t2: Vector3<f64>,
    /// Normal (`t̂₁ × t̂₂`).
    pub n: Vector3<f64>,
}

impl Disk {
    /// The direction of `u` in hemisphere `side` (+1 along n̂, −1 against), `None` outside the disk.
    pub fn direction(&self, u: Vector2<f64>, side: f64) -> Option<Vector3<f64>> {
        let r2 = u.norm_squared();
        (r2 < 1.0).then(|| self.t1 * u.x + self.t2 * u.y + self.n * (side * (1.0 - r2).sqrt()))
    }
    /// `(hemisphere, u)` of a direction.
    pub fn coords(&self, d: &Vector3<f64>) -> (f64, Vector2<f64>) {
        let side = if d.dot(&self.n) >= 0.0 { 1.0 } else { -1.0 };
        (side, Vector2::new(d.dot(&self.t1), d.dot(&self.t2)))
    }
}

/// Edges on `[−1, 1]`: a uniform grid of `coarse` cells plus `c ± w·m` for each centre `c`,
/// width `w` and multiple `m` given, sorted and deduplicated.
pub fn edges(coarse: usize, centres: &[(f64, f64)], multiples: &[f64]) -> Vec<f64> {
    let mut e: Vec<f64> = (0..=coarse)
        .map(|i| -1.0 + 2.0 * i as f64 / coarse as f64)
        .collect();
    for &(c, w) in centres {
        for &m in multiples {
            for x in [c - w * m, c + w * m] {
                if x > -1.0 && x < 1.0 {
                    e.push(x);
                }
            }
        }
        if c > -1.0 && c < 1.0 {
            e.push(c);
        }
    }
    e.sort_by(f64::total_cmp);
    e.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    e
}

/// The grid of one hemisphere.
#[derive(Debug, Clone)]
pub struct Grid {
    /// `+1` for the hemisphere along n̂, `−1` for the one against it.
    pub side: f64,
    /// Cell edges in `u₁ = d·t̂₁`, sorted, within `[−1, 1]`.
    pub ex: Vec<f64>,
    /// Cell edges in `u₂ = d·t̂₂`.
    pub ey: Vec<f64>,
}

impl Grid {
    fn cell(&self, u: &Vector2<f64>) -> Option<usize> {
        let find = |e: &[f64], x: f64| {
            let i = e.partition_point(|&v| v <= x);
            (i > 0 && i < e.len()).then(|| i - 1)
        };
        let ix = find(&self.ex, u.x)?;
        let iy = find(&self.ey, u.y)?;
        Some(ix * (self.ey.len() - 1) + iy)
    }
    fn cells(&self) -> usize {
        (self.ex.len() - 1) * (self.ey.len() - 1)
    }
}

/// The expected probability of every cell of `grids`, then that of the rest.
pub fn probabilities(
    disk: &Disk,
    grids: &[Grid],
    pdf: &dyn Fn(&Vector3<f64>) -> f64,
    tol: f64,
) -> Vec<f64> {
    let mut p = Vec::new();
    for g in grids {
        for ix in 0..g.ex.len() - 1 {
            for iy in 0..g.ey.len() - 1 {
                let (x0, x1, y0, y1) = (g.ex[ix], g.ex[ix + 1], g.ey[iy], g.ey[iy + 1]);
                // Cells wholly outside the disk hold nothing.
                let nearest = Vector2::new(0.0_f64.clamp(x0, x1), 0.0_f64.clamp(y0, y1));
                if nearest.norm_squared() >= 1.0 {
                    p.push(0.0);
                    continue;
                }
                // The disk's edge bounds the inner range, so the integrands stay smooth.
                let mut outer = |x: f64| {
                    let half = (1.0 - x * x).max(0.0).sqrt();
                    let (lo, hi) = (y0.max(-half), y1.min(half));
                    if hi <= lo {
                        return 0.0;
                    }
                    let mut inner = |y: f64| {
                        disk.direction(Vector2::new(x, y), g.side)
                            .map_or(0.0, |d| pdf(&d) / d.dot(&disk.n).abs())
                    };
                    integrate(&mut inner, lo, hi, 1, 0.1 * tol)
                };
                p.push(integrate(&mut outer, x0, x1, 1, tol));
            }
        }
    }
    let total: f64 = p.iter().sum();
    p.push((1.0 - total).max(0.0));
    p
}

/// Counts of `n` draws (`None`: no direction, counted in the rest) in the cells of `grids`.
pub fn counts(
    disk: &Disk,
    grids: &[Grid],
    n: usize,
    draw: &mut dyn FnMut(usize) -> Option<Vector3<f64>>,
) -> Vec<usize> {
    let total: usize = grids.iter().map(Grid::cells).sum();
    let mut c = vec![0usize; total + 1];
    for i in 0..n {
        let bin = draw(i).and_then(|d| {
            let (side, u) = disk.coords(&d);
            let mut offset = 0;
            for g in grids {
                if g.side == side {
                    return g.cell(&u).map(|k| offset + k);
                }
                offset += g.cells();
            }
            None
        });
        c[bin.unwrap_or(total)] += 1;
    }
    c
}

/// The outcome of one chi-square test.
#[derive(Debug, Clone, Copy)]
pub struct Outcome {
    /// Pearson's statistic.
    pub chi2: f64,
    /// Its degrees of freedom (bins after pooling, less one).
    pub dof: usize,
    /// The 99.9 % quantile of χ² with `dof` degrees of freedom.
    pub quantile: f64,
}

impl Outcome {
    /// `χ² ≤` the 99.9 % quantile: a correct sampler fails with probability 1e-3 per seed (so
    /// tests run from fixed seeds).
    #[must_use]
    pub fn passes(&self) -> bool {
        self.chi2 <= self.quantile
    }
}

/// The chi-square test of `draw` against `pdf` (module docs).
pub fn test(
    disk: &Disk,
    grids: &[Grid],
    pdf: &dyn Fn(&Vector3<f64>) -> f64,
    n: usize,
    draw: &mut dyn FnMut(usize) -> Option<Vector3<f64>>,
) -> Outcome {
    let p = probabilities(disk, grids, pdf, 1e-8);
    let c = counts(disk, grids, n, draw);
    let (chi2, dof) = chi_square(&c, &p, n);
    Outcome {
        chi2,
        dof,
        quantile: chi2_quantile_999(dof.max(1)),
    }
}
