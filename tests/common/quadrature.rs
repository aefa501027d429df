//! An adaptive Gauss–Legendre integrator, independent of the crate's quadrature
//! (`src/psd/quadrature.rs` uses tabulated Gauss–Kronrod nodes): the nodes and weights here are
//! computed at run time by Newton iteration on the Legendre polynomials, nothing is copied from
//! a table. Each panel is integrated with the 8- and the 12-point rules; their difference bounds
//! the error of the 8-point rule (and so, very loosely, of the 12-point one that is returned), and
//! a panel whose difference exceeds its share of the tolerance is bisected.
#![allow(
    dead_code,
    reason = "each test binary uses a different subset of the helpers"
)]

use std::f64::consts::PI;
use std::sync::OnceLock;

/// An n-point Gauss–Legendre rule on `[−1, 1]`.
#[derive(Debug, Clone)]
pub struct GaussLegendre {
    pub nodes: Vec<f64>,
    pub weights: Vec<f64>,
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence `k P_k = (2k − 1) x P_{k−1} − (k − 1) P_{k−2}`
/// and `P_n' = n (x P_n − P_{n−1}) / (x² − 1)` (|x| < 1).
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let n = n as f64;
    (p1, n * (x * p1 - p0) / (x * x - 1.0))
}

/// The `n`-point rule (`n ≥ 1`): each root of `P_n` by Newton's method from the Tricomi-type
/// guess `cos(π (i − ¼)/(n + ½))`, weight `2 / ((1 − x²) P_n'(x)²)`.
pub fn gauss_legendre(n: usize) -> GaussLegendre {
    assert!(n >= 1);
    let (mut nodes, mut weights) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 1..=n {
        let mut x = (PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
        let mut converged = false;
        for _ in 0..100 {
            let (p, dp) = legendre(n, x);
            let dx = p / dp;
            x -= dx;
            // Quadratic convergence: a step below 1e-15 leaves an error far below one ulp.
            if dx.abs() <= 1e-15 {
                converged = true;
                break;
            }
        }
        assert!(converged, "Newton did not converge for root {i} of P_{n}");
        let (_, dp) = legendre(n, x);
        nodes.push(x);
        weights.push(2.0 / ((1.0 - x * x) * dp * dp));
    }
    GaussLegendre { nodes, weights }
}

fn rule8() -> &'static GaussLegendre {
    static R: OnceLock<GaussLegendre> = OnceLock::new();
    R.get_or_init(|| gauss_legendre(8))
}
fn rule12() -> &'static GaussLegendre {
    static R: OnceLock<GaussLegendre> = OnceLock::new();
    R.get_or_init(|| gauss_legendre(12))
}

/// `rule` mapped onto `[a, b]`.
pub fn apply(rule: &GaussLegendre, f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64) -> f64 {
    let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
    let s: f64 = rule
        .nodes
        .iter()
        .zip(&rule.weights)
        .map(|(x, w)| w * f(c + h * x))
        .sum();
    s * h
}

fn adapt(f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64, tol: f64, depth: u32) -> f64 {
    let lo = apply(rule8(), f, a, b);
    let hi = apply(rule12(), f, a, b);
    // Relative floor: |G12 − G8| grossly overestimates the G12 error once it is near round-off.
    if (hi - lo).abs() <= tol.max(1e-14 * hi.abs()) || depth > 30 {
        return hi;
    }
    let m = 0.5 * (a + b);
    adapt(f, a, m, 0.5 * tol, depth + 1) + adapt(f, m, b, 0.5 * tol, depth + 1)
}

/// Adaptive G8/G12 on `[a, b]` split first into `panels` equal pieces; absolute tolerance `tol`.
pub fn integrate(f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64, panels: usize, tol: f64) -> f64 {
    let w = (b - a) / panels as f64;
    (0..panels)
        .map(|i| {
            let lo = a + w * i as f64;
            adapt(f, lo, lo + w, tol / panels as f64, 0)
        })
        .sum()
}
