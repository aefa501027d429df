//! Quadrature for oracles, independent of the crate's own: an adaptive Gauss–Legendre
//! integrator, the exit hemisphere in exit-tangent coordinates, and a trapezoid rule on a cube.
//!
//! The Gauss–Legendre integrator is independent of the crate's quadrature
//! (`src/psd/quadrature.rs` uses tabulated Gauss–Kronrod nodes): the nodes and weights here are
//! computed at run time by Newton iteration on the Legendre polynomials, nothing is copied from
//! a table. Each panel is integrated with the 8- and the 12-point rules; their difference bounds
//! the error of the 8-point rule (and so, very loosely, of the 12-point one that is returned), and
//! a panel whose difference exceeds its share of the tolerance is bisected.

use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

use nalgebra::{Vector2, Vector3};
use num_complex::Complex;

/// An n-point Gauss–Legendre rule on `[−1, 1]`.
#[derive(Debug, Clone)]
pub struct GaussLegendre {
    /// The roots of `P_n`, descending.
    pub nodes: Vec<f64>,
    /// The weights `2 / ((1 − x²) P_n'(x)²)`.
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

/// The `n`-point rule (`n ≥ 1`; panics for 0, or if Newton's method does not converge): each root of `P_n` by Newton's method from the Tricomi-type
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
///
/// A feature narrower than a panel can fall between the nodes of both rules, which then agree
/// on a wrong value and accept it (a peak of width 1e-3 on one panel `[−1, 1]` integrates to
/// ~0): choose `panels` so that each resolves the integrand's finest feature.
pub fn integrate(f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64, panels: usize, tol: f64) -> f64 {
    let w = (b - a) / panels as f64;
    (0..panels)
        .map(|i| {
            let lo = a + w * i as f64;
            adapt(f, lo, lo + w, tol / panels as f64, 0)
        })
        .sum()
}

/// Which hemisphere: above the surface z = 0 (reflection from above) or below it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hemisphere {
    /// `r̂_z > 0`.
    Above,
    /// `r̂_z < 0`.
    Below,
}

/// `∫ f(r̂) d²r_t` (two integrands at once) over the exit hemisphere `|r_t| < 1` (= `∫ f cos θ_o dω`), in polar coordinates
/// centred on the lobe's point `r_t0`: trapezoid in the angle, Gauss–Legendre on radial panels
/// refined geometrically toward the centre (narrow lobes) and toward the rim (the `√` of `cos θ_o`).
pub fn hemisphere_integral(
    r0: Vector2<f64>,
    n_angle: usize,
    side: Hemisphere,
    f: &mut dyn FnMut(Vector3<f64>) -> [f64; 2],
) -> [f64; 2] {
    hemisphere_integral_n(r0, n_angle, side, f)
}

/// The albedo of a surface lit from a direction of incidence cosine `cos_i`: the fraction of the
/// incident power per Stokes channel that it sends into one hemisphere, as a Mueller matrix,
/// ```text
/// A = (1/cos θ_i) ∫ M(r̂) cos θ_o dω        (M the kernel's BSDF form: L_o = M S_i)
/// ```
/// by [`hemisphere_integral`]'s rule centred on the lobe's point `r0` (the tangential part of
/// its peak direction). With the kernel's convention (`L_o` per unit incident irradiance
/// measured across the beam, i.e. `f · cos θ_i`), the fraction of the power of an incident
/// Stokes vector `S` is `(A S)₀ / S₀`; [`super::check::max_transmittance`] is its largest value
/// over all `S`, which must not exceed 1 for passive matter (add the hemispheres of both sides
/// and the coherent lobes first).
pub fn hemisphere_albedo(
    cos_i: f64,
    r0: Vector2<f64>,
    n_angle: usize,
    side: Hemisphere,
    m: &mut dyn FnMut(Vector3<f64>) -> nalgebra::Matrix4<f64>,
) -> nalgebra::Matrix4<f64> {
    let entries = hemisphere_integral_n::<16>(r0, n_angle, side, &mut |r| {
        let v = m(r);
        core::array::from_fn(|i| v[i])
    });
    nalgebra::Matrix4::from_column_slice(&entries) / cos_i
}

/// [`hemisphere_integral`] for `N` integrands at once.
fn hemisphere_integral_n<const N: usize>(
    r0: Vector2<f64>,
    n_angle: usize,
    side: Hemisphere,
    f: &mut dyn FnMut(Vector3<f64>) -> [f64; N],
) -> [f64; N] {
    let rule = gauss_legendre(12);
    let (gx, gw) = (&rule.nodes, &rule.weights);
    let sign = match side {
        Hemisphere::Above => 1.0,
        Hemisphere::Below => -1.0,
    };
    let mut total = [0.0; N];
    for j in 0..n_angle {
        let psi = TAU * j as f64 / n_angle as f64;
        let u = Vector2::new(psi.cos(), psi.sin());
        let b = r0.dot(&u);
        let rho_max = -b + (b * b + 1.0 - r0.norm_squared()).sqrt();
        let mut breaks: Vec<f64> = vec![0.0, rho_max];
        for m in 1..=26 {
            breaks.push(rho_max * 0.5f64.powi(m));
        }
        for m in 2..=14 {
            breaks.push(rho_max * (1.0 - 0.5f64.powi(m)));
        }
        breaks.sort_by(f64::total_cmp);
        let mut radial = [0.0; N];
        for pair in breaks.windows(2) {
            let (a, c) = (pair[0], pair[1]);
            let (mid, half) = ((a + c) * 0.5, (c - a) * 0.5);
            for (x, w) in gx.iter().zip(gw) {
                let rho = mid + half * x;
                let rt = r0 + u * rho;
                let cz2 = 1.0 - rt.norm_squared();
                if cz2 <= 0.0 {
                    continue;
                }
                let v = f(Vector3::new(rt.x, rt.y, sign * cz2.sqrt()));
                for (acc, v) in radial.iter_mut().zip(v) {
                    *acc += w * half * rho * v;
                }
            }
        }
        for (t, r) in total.iter_mut().zip(radial) {
            *t += r * TAU / n_angle as f64;
        }
    }
    total
}

/// Trapezoid rule over `[−half, half]ᴺ` with `n ≥ 2` points per axis (every point at full
/// weight: for integrands that vanish at the faces), of a complex integrand.
pub fn cube_quad<const N: usize>(
    f: impl Fn(&nalgebra::SVector<f64, N>) -> Complex<f64>,
    half: f64,
    n: usize,
) -> Complex<f64> {
    let step = 2.0 * half / (n - 1) as f64;
    let mut idx = [0usize; N];
    let mut sum = Complex::new(0.0, 0.0);
    loop {
        let x = nalgebra::SVector::<f64, N>::from_fn(|d, _| -half + step * idx[d] as f64);
        sum += f(&x);
        let mut d = 0;
        loop {
            if d == N {
                return sum * step.powi(N as i32);
            }
            idx[d] += 1;
            if idx[d] < n {
                break;
            }
            idx[d] = 0;
            d += 1;
        }
    }
}
