//! Quadrature over the exit hemisphere in exit-tangent coordinates (`∫ f cos θ_o dω = ∫ f d²r_t`),
//! shared by the energy tests of reflection and transmission.
#![allow(
    dead_code,
    reason = "each test binary uses a different subset of the helpers"
)]

use std::f64::consts::TAU;

use nalgebra::{Vector2, Vector3};

use super::gauss_legendre;

/// Which hemisphere: above the surface z = 0 (reflection from above) or below it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hemisphere {
    /// `r̂_z > 0`.
    Above,
    /// `r̂_z < 0`.
    Below,
}

/// `∫ f(r̂) d²r_t` over the hemisphere `|r_t| < 1` (= `∫ f cos θ_o dω`), in polar coordinates
/// centred on the lobe's point `r_t0`: trapezoid in the angle, Gauss–Legendre on radial panels
/// refined geometrically toward the centre (narrow lobes) and toward the rim (the `√` of `cos θ_o`).
pub fn hemisphere_integral(
    r0: Vector2<f64>,
    n_angle: usize,
    side: Hemisphere,
    f: &mut dyn FnMut(Vector3<f64>) -> [f64; 2],
) -> [f64; 2] {
    let (gx, gw) = gauss_legendre(12);
    let sign = match side {
        Hemisphere::Above => 1.0,
        Hemisphere::Below => -1.0,
    };
    let mut total = [0.0; 2];
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
        let mut radial = [0.0; 2];
        for pair in breaks.windows(2) {
            let (a, c) = (pair[0], pair[1]);
            let (mid, half) = ((a + c) * 0.5, (c - a) * 0.5);
            for (x, w) in gx.iter().zip(&gw) {
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
