//! Pearson's chi-square test of a direction sampler against a density per solid angle, in
//! both hemispheres of a surface: the bins are cells of a Cartesian grid in the projected-disk
//! coordinates `u = (d·t̂₁, d·t̂₂)` of each hemisphere (edges refined about the lobe centres),
//! their expected probabilities adaptive Gauss–Legendre quadrature (`quadrature.rs`) of
//! `pdf_ω(d(u))/|cos θ|` over the cell, and every draw that falls in no cell (a delta lobe, an
//! evanescent draw) counts in one more bin whose probability is the rest.
#![allow(
    dead_code,
    reason = "each test binary uses a different subset of the helpers"
)]

use nalgebra::{Vector2, Vector3};

use super::quadrature::integrate;

/// The standard normal 99.9 % quantile.
pub const Z_999: f64 = 3.090232306167814;

/// The 99.9 % quantile of χ² with `dof` degrees of freedom, Wilson & Hilferty (1931):
/// `χ²_p ≈ k (1 − 2/(9k) + z_p √(2/(9k)))³` (relative error < 1e-3 for k ≥ 10).
pub fn chi2_quantile_999(dof: usize) -> f64 {
    let k = dof as f64;
    k * (1.0 - 2.0 / (9.0 * k) + Z_999 * (2.0 / (9.0 * k)).sqrt()).powi(3)
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
    pub t1: Vector3<f64>,
    pub t2: Vector3<f64>,
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
    pub side: f64,
    pub ex: Vec<f64>,
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
    pub chi2: f64,
    pub dof: usize,
    pub quantile: f64,
}

impl Outcome {
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
