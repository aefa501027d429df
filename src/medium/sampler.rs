//! Sampling exit directions for a packet scattered in a medium, with the exact density of what
//! is drawn.
//!
//! # Formula
//! ```text
//! p(r̂) = w_u/(4π) + (1 − w_u) k² Σ_j c_j g_j(v)/F_j(2k),     |v| = k|r̂ − d̂|,  Σ_j c_j = 1
//! ```
//! a mixture of the uniform sphere (the defensive part, and the whole proposal in the Rayleigh
//! regime) and radial lobes on Lambert's disk about d̂ (Gaussian or power law,
//! [`super::lobes`]), each truncated to the disk `|v| ≤ 2k` with its exact mass. `d²v = k² dΩ`
//! makes `k² g(v)/F` a density per steradian. Drawing: one uniform chooses the part, one the
//! radius by the truncated radial CDF (closed form), one the azimuth; the draw is never empty.
//! The uniform weight is `w_u = min(1, max(0.05, (s_max/2k)², 1.5 f_far))`, `s_max` the widest
//! lobe and `f_far` the share of `σ_s` beyond three lobe widths ([`super::coefficient`]).

use nalgebra::{Vector2, Vector3};

use super::coefficient::direction;
use super::lobes::LobeModel;
use crate::frame::Frame;
use crate::real::Real;

/// A uniform in `[0, 1)` clamped into `[0, 1 − ε/2]` (NaN → 0).
#[inline]
fn unit<T: Real>(u: T) -> T {
    let top = T::one() - T::EPSILON * T::lit(0.5);
    if u >= T::zero() {
        u.min(top)
    } else {
        T::zero()
    }
}

/// One truncated radial lobe.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Part<T: Real> {
    /// Probability of choosing it (the uniform part's share included in the others' sum).
    prob: T,
    s2: T,
    beta: Option<T>,
    /// `F(2k)`, the lobe's mass in the disk.
    mass: T,
    /// `ln(k² norm / F(2k))`, `norm` the lobe's density at `v = 0`.
    ln_scale: T,
}

/// The mixture (module formula).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DirectionMixture<T: Real> {
    w_uniform: T,
    parts: [Part<T>; 4],
    n: usize,
}

impl<T: Real> DirectionMixture<T> {
    /// From the lobe model, the wavenumber and the far share of `σ_s`.
    pub(crate) fn new(model: &LobeModel<T>, k: T, far: T) -> Self {
        let u2 = T::lit(4.0) * k * k;
        let s2_max = model.radial[..model.n]
            .iter()
            .fold(T::zero(), |m, r| m.max(r.s2));
        let mut w_uniform = (s2_max / u2)
            .max(T::lit(0.05))
            .max(T::lit(1.5) * far)
            .min(T::one());
        if !w_uniform.is_finite() {
            w_uniform = T::one();
        }
        let mut parts = [Part {
            prob: T::zero(),
            s2: T::one(),
            beta: None,
            mass: T::one(),
            ln_scale: T::zero(),
        }; 4];
        let ln_k2 = T::lit(2.0) * k.ln();
        for (p, r) in parts.iter_mut().zip(&model.radial[..model.n]) {
            let x = u2 / r.s2;
            let (mass, ln_norm) = match r.beta {
                None => (-(-x * T::lit(0.5)).exp_m1(), -(T::two_pi() * r.s2).ln()),
                Some(b) => (
                    -((T::one() - b) * x.ln_1p()).exp_m1(),
                    ((b - T::one()) / (T::pi() * r.s2)).ln(),
                ),
            };
            *p = Part {
                prob: (T::one() - w_uniform) * r.weight,
                s2: r.s2,
                beta: r.beta,
                mass,
                ln_scale: ln_k2 + ln_norm - mass.ln(),
            };
        }
        Self {
            w_uniform,
            parts,
            n: model.n,
        }
    }

    /// The uniform part's weight `w_u`.
    pub(crate) fn uniform_weight(&self) -> T {
        self.w_uniform
    }

    /// The density per steradian of `r` (a finite unit vector) for light along `frame.k`.
    #[inline]
    pub(crate) fn pdf(&self, frame: &Frame<T>, k: T, r: &Vector3<T>) -> T {
        let u2 = ((r - frame.k) * k).norm_squared().min(T::lit(4.0) * k * k);
        let mut p = self.w_uniform / (T::lit(4.0) * T::pi());
        for part in &self.parts[..self.n] {
            if part.prob > T::zero() {
                let x = u2 / part.s2;
                let ln_g = match part.beta {
                    None => -x * T::lit(0.5),
                    Some(b) => -b * x.ln_1p(),
                };
                p += part.prob * (part.ln_scale + ln_g).exp();
            }
        }
        p
    }

    /// A direction from three uniforms in `[0, 1)`: `u_part` chooses the part, `u` the radius
    /// and the azimuth about d̂ (`frame.k`).
    #[inline]
    pub(crate) fn sample(&self, frame: &Frame<T>, k: T, u_part: T, u: [T; 2]) -> Vector3<T> {
        let (up, u1, u2) = (unit(u_part), unit(u[0]), unit(u[1]));
        // a² = |v|²/4k² of the chosen part.
        let mut a2 = u1; // the uniform sphere: |v|² uniform on [0, 4k²]
        let mut cum = self.w_uniform;
        if up >= cum {
            for (i, part) in self.parts[..self.n].iter().enumerate() {
                cum += part.prob;
                if up < cum || i + 1 == self.n {
                    let t = u1 * part.mass;
                    let rho2 = match part.beta {
                        None => -T::lit(2.0) * part.s2 * (-t).ln_1p(),
                        Some(b) => part.s2 * ((-t).ln_1p() / (T::one() - b)).exp_m1(),
                    };
                    a2 = (rho2 / (T::lit(4.0) * k * k)).min(T::one()).max(T::zero());
                    break;
                }
            }
        }
        let (s, c) = (T::two_pi() * u2).sin_cos();
        // |v| = 2k a; the direction depends on v/|v| and a² only.
        let v = Vector2::new(c, s) * (T::lit(2.0) * k * a2.sqrt());
        if v.norm() > T::zero() {
            direction(&frame.x, &frame.y, &frame.k, v, k)
        } else {
            frame.k
        }
    }
}
