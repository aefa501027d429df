//! The Kirchhoff series' scattered weights in lanes (`KirchhoffSeries`' `Terms::sum` for a
//! Gaussian PSD blurred in closed form): per channel `ln Σ_{n≥1} (w_n/g) K[p_n]`, every order
//! from the closed form of [`SeriesPrep`], `g = (vσ)²` per lane.
//!
//! # Formula
//! ```text
//! ln t_n = −g + (n − 1) ln g + k_n − (n c₁ + c₀) e_n        (t₁ = e^{−g} K[p])
//! k_n = ln 2πσ² − ½ ln|nA + Ξ| − ln n!,   e_n = ½/|nA + Ξ|,   c₁ = h_tᵀadj(A)h_t,   c₀ = h_tᵀadj(Ξ)h_t
//! ln Σ t_n = m + ln Σ_{n=1}^{N} e^{ln t_n − m},   m = max_n ln t_n
//! ```
//! Two passes over the orders: the first finds `m` and the last order `N` of the vector, the
//! second sums. A lane's sum may stop at `n` once `t_n ≤ t_{n−1}/2` and `t_n ≤ (tol/2) e^m`: the
//! terms are log-concave in `n` (module docs of `interaction::roughness`), so the rest is at
//! most `t_n Σ_{j≥1} 2^{−j} = t_n ≤ (tol/2) × the sum`. The per-direction kernel stops by the
//! same kind of bound (`t_n r/(1 − r) ≤ (tol/2) × the partial sum`) from the largest term up and
//! down, so the two sums are each within `tol/2` of the whole series, and within `tol` of each
//! other. The vector sums to the last lane's `N` (the others only gain accuracy).
//!
//! Redone by the per-direction kernel: lanes with `g` not normal or `g ≥ g_max` (the switch to
//! the geometric limit, or the lanes' range: `g < 64` in `f64`, `16` in `f32`, where `g`,
//! `(n − 1) ln g` and `ln n!`, each `~g ln g` before they cancel, are rounded in the lanes'
//! type while the per-direction kernel sums in `f64`), and lanes whose sum has not stopped by
//! order [`SERIES_ORDERS`] (far tails, where the orders that dominate lie far above `g`).

use pulp::Simd;

use super::super::prep::{SERIES_ORDERS, SeriesChannel, SeriesPrep};
use crate::real::Real;
use crate::simd::exp::vexp_nonpositive;
use crate::simd::ln::vln;

/// `(a h₀ + b h₁)² + (c h₀)²`.
#[inline(always)]
fn quad<S: Simd, F: Real>(s: S, q: &[F; 3], h0: F::V<S>, h1: F::V<S>) -> F::V<S> {
    let c = |v: F| F::vsplat(s, v);
    let u = F::vmul_add(s, c(q[0]), h0, F::vmul(s, c(q[1]), h1));
    let w = F::vmul(s, c(q[2]), h0);
    F::vmul_add(s, u, u, F::vmul(s, w, w))
}

/// `−g + (n − 1) ln g` at order `n = i + 1` (`−g` at `n = 1`).
#[inline(always)]
fn base<S: Simd, F: Real>(s: S, i: usize, neg_g: F::V<S>, ln_g: F::V<S>) -> F::V<S> {
    if i == 0 {
        neg_g
    } else {
        F::vmul_add(s, F::vsplat(s, F::lit(i as f64)), ln_g, neg_g)
    }
}

/// `ln t_n` of one channel at order `n = i + 1` from the lane part `b` ([`base`]):
/// `b + k_n − (n c₁ + c₀) e_n`.
#[inline(always)]
fn term<S: Simd, F: Real>(
    s: S,
    ch: &SeriesChannel<F>,
    i: usize,
    b: F::V<S>,
    c1: F::V<S>,
    c0: F::V<S>,
) -> F::V<S> {
    let c = |v: F| F::vsplat(s, v);
    let q = F::vmul_add(s, c(F::lit((i + 1) as f64)), c1, c0);
    F::vneg_mul_add(s, q, c(ch.half_inv_det[i]), F::vadd(s, b, c(ch.k[i])))
}

/// The series' log weights of the `NC` channels `chans` (indices into `x, y, ½`: `[2]` with
/// one channel, `[0, 1, 2]` with three) at `h_t = (h0, h1)` for the phase factors `v`, and the
/// lanes the per-direction kernel must redo. (`NC` a constant, so that the channels' running
/// values stay in registers.)
#[inline(always)]
pub(crate) fn log_weights<S: Simd, F: Real, const NC: usize>(
    s: S,
    p: &SeriesPrep<F>,
    chans: [usize; NC],
    v: F::V<S>,
    (h0, h1): (F::V<S>, F::V<S>),
    variance: F,
) -> ([F::V<S>; NC], F::M<S>) {
    let c = |x: F| F::vsplat(s, x);
    let (add, sub) = (F::vadd::<S>, F::vsub::<S>);
    let ninf = c(crate::interaction::coherence::neg_infinity::<F>());
    let g = F::vmul(s, F::vmul(s, v, v), c(variance));
    // Lanes outside [MIN_POSITIVE, g_max) (NaN too) go to the per-direction kernel; their
    // values here are never written.
    let inside = F::vand(
        s,
        F::vle(s, c(F::MIN_POSITIVE), g),
        F::vlt(s, g, c(p.g_max)),
    );
    let neg_g = F::vneg_mul_add(s, g, c(F::one()), c(F::zero()));
    let ln_g = vln::<S, F>(s, g);
    let c1 = quad::<S, F>(s, &p.psd_quad, h0, h1);
    let ch = chans.map(|a| &p.channels[a]);
    let mut c0 = [c1; NC];
    for j in 0..NC {
        c0[j] = quad::<S, F>(s, &ch[j].quad, h0, h1);
    }
    // Pass 1: the largest term and the last order.
    let neg_ln2 = c(-F::lit(core::f64::consts::LN_2));
    let mut m = [ninf; NC];
    let mut prev = [ninf; NC];
    let outside = F::vnot(s, inside);
    let mut stopped = [outside; NC];
    let mut last = SERIES_ORDERS;
    for i in 0..SERIES_ORDERS {
        let b = base::<S, F>(s, i, neg_g, ln_g);
        // The stop test every 4 orders (and at the last): once met it holds at every later
        // order (the ratios fall, the terms fall, m stays).
        let test = i % 4 == 3 || i + 1 == SERIES_ORDERS;
        let mut all = outside;
        for j in 0..NC {
            let t = term::<S, F>(s, ch[j], i, b, c1, c0[j]);
            m[j] = F::vmax(s, m[j], t);
            if test {
                let falling = F::vle(s, sub(s, t, prev[j]), neg_ln2);
                let small = F::vle(s, t, add(s, m[j], c(p.ln_half_tol)));
                stopped[j] = F::vor(s, stopped[j], F::vand(s, falling, small));
                all = if j == 0 {
                    stopped[0]
                } else {
                    F::vand(s, all, stopped[j])
                };
            }
            prev[j] = t;
        }
        if test && !F::vany(s, F::vnot(s, all)) {
            last = i + 1;
            break;
        }
    }
    let mut redo = outside;
    for st in stopped {
        redo = F::vor(s, redo, F::vnot(s, st));
    }
    // Pass 2: the sums relative to the largest term.
    let mut sum = [c(F::zero()); NC];
    for i in 0..last {
        let b = base::<S, F>(s, i, neg_g, ln_g);
        for j in 0..NC {
            let t = term::<S, F>(s, ch[j], i, b, c1, c0[j]);
            sum[j] = add(s, sum[j], vexp_nonpositive::<S, F>(s, sub(s, t, m[j])));
        }
    }
    let mut out = [ninf; NC];
    for j in 0..NC {
        // The sum lies in [1, last] where m is finite; elsewhere the lane is dark (−∞) or
        // redone.
        let lit = F::vlt(s, c(-F::MAX), m[j]);
        let ln = add(s, m[j], vln::<S, F>(s, sum[j]));
        out[j] = F::vselect(s, lit, ln, ninf);
    }
    (out, redo)
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;
    use num_complex::Complex;

    use super::super::super::partial::{PartialLobes, lane_prep, scalar_exit, series_prep};
    use super::super::super::{DirectionsSoa, LobesSoa, StokesSoa};
    use crate::frame::Frame;
    use crate::interaction::pbsdf::{FresnelInterface, RayleighRice};
    use crate::interaction::polarization::PolarizationModel;
    use crate::interaction::roughness::KirchhoffSeries;
    use crate::interaction::{Full, Intensity, Kernel, Partial, RoughConductor, RoughSurface};
    use crate::packet::{CoherenceShape, WavePacket};
    use crate::psd::GaussianPsd;
    use crate::real::Real;
    use crate::stokes::Stokes;

    /// The lanes of the series kernel against the per-direction kernel (the same tolerance),
    /// exit by exit, on `exits`; returns how many lanes were redone one at a time and the
    /// largest `|Δ|/S0` over both lobes' Stokes parameters.
    fn run<T: Real, Pol: PolarizationModel>(
        sigma: f64,
        tolerance: f64,
        interface: Option<(f64, bool)>,
        exits: &[Vector3<f64>],
    ) -> (usize, f64) {
        let theta_i = 35f64.to_radians();
        let up = if matches!(interface, Some((_, true))) { 1.0 } else { -1.0 };
        let travel = Vector3::new(theta_i.sin(), 0.0, up * theta_i.cos()).map(T::lit);
        let frame = Frame::sp(travel, Vector3::z())
            .unwrap()
            .rotated(T::lit(0.4));
        let packet = WavePacket::new(
            Stokes::new(T::one(), T::lit(0.3), T::lit(0.2), -T::lit(0.3)).unwrap(),
            CoherenceShape::isotropic(T::lit(3.0)).unwrap(),
            CoherenceShape::isotropic(T::lit(4.5)).unwrap(),
            frame,
            T::lit(0.5),
        )
        .unwrap();
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let psd = GaussianPsd::<T, 2>::isotropic(T::lit(sigma), T::lit(1.2)).unwrap();
        let kernel = Kernel::<Pol, Partial>::default()
            .with_roughness(KirchhoffSeries::new(tolerance).unwrap());
        let d: [Vec<T>; 3] = core::array::from_fn(|k| exits.iter().map(|e| T::lit(e[k])).collect());
        let n = exits.len();
        let mut cols = vec![vec![T::zero(); n]; 8];
        let mut redone = 0;
        let mut worst = 0.0f64;
        macro_rules! go {
            ($material:expr, $eta:expr) => {{
                let material = $material;
                let facing = match $eta {
                    Some(_) => surface.facing(&-packet.direction()),
                    None => surface,
                };
                let prepared = kernel.prepare(&packet, &facing).unwrap();
                let prep = lane_prep(&kernel, &material, &prepared, &packet, &surface, $eta)
                    .expect("lane constants");
                let series = series_prep(&kernel, &material, &prepared, &prep)
                    .expect("a series kernel")
                    .expect("series lane constants");
                {
                    let [a, b, c, dd, e, f, g, h] = &mut cols[..] else {
                        unreachable!()
                    };
                    let mut out = LobesSoa {
                        specular: StokesSoa { s: [a, b, c, dd] },
                        scattered: StokesSoa { s: [e, f, g, h] },
                    };
                    let mut scalar = |_: usize, i: usize| {
                        redone += 1;
                        scalar_exit(
                            &kernel,
                            &material,
                            &prepared,
                            &packet,
                            (&surface, $eta),
                            exits[i].map(T::lit),
                        )
                    };
                    crate::simd::dispatch(PartialLobes {
                        preps: core::slice::from_ref(&prep),
                        series: Some(&series),
                        exits: DirectionsSoa {
                            x: &d[0],
                            y: &d[1],
                            z: &d[2],
                        },
                        outs: core::slice::from_mut(&mut out),
                        frames: None,
                        scalar: &mut scalar,
                    })
                    .unwrap();
                }
                for (i, e) in exits.iter().enumerate() {
                    let (sp, sc, _) = scalar_exit(
                        &kernel,
                        &material,
                        &prepared,
                        &packet,
                        (&surface, $eta),
                        e.map(T::lit),
                    )
                    .unwrap();
                    for (lobe, want) in [sp, sc].iter().enumerate() {
                        let s0 = want[0].to_f64();
                        for k in 0..4 {
                            let got = cols[4 * lobe + k][i].to_f64();
                            // In units of the first-order lanes' bound without its
                            // constant: ε (4 + |ln L|) L + MIN_POSITIVE.
                            let eps = T::EPSILON.to_f64();
                            let ln_l = if s0 > 0.0 { s0.ln().abs() } else { 0.0 };
                            let unit = eps * (4.0 + ln_l) * s0 + T::MIN_POSITIVE.to_f64();
                            let rel = (got - want[k].to_f64()).abs() / unit;
                            if rel > worst && std::env::var("SERIES_DEBUG").is_ok() {
                                println!("  exit {i} {e:?} lobe {lobe} S{k}: got {got:e} want {:e} (S0 {s0:e})", want[k].to_f64());
                            }
                            worst = worst.max(rel);
                        }
                    }
                }
            }};
        }
        match interface {
            None => go!(
                RoughConductor::new(psd, Complex::new(T::lit(0.47), T::lit(2.4))).unwrap(),
                None::<T>
            ),
            Some((eta, _)) => go!(
                RoughSurface {
                    psd,
                    specular: FresnelInterface::new(T::lit(eta)).unwrap(),
                    scatter: RayleighRice::new(Complex::new(T::lit(eta), T::zero())).unwrap(),
                },
                Some(T::lit(eta))
            ),
        }
        (redone, worst)
    }

    /// Exits within ±`spread` rad of the mirror direction of 35° incidence, on the side `z`.
    fn near(spread: f64, n: usize, z: f64) -> Vec<Vector3<f64>> {
        let theta = 35f64.to_radians();
        (0..n)
            .map(|i| {
                let a = theta + (i as f64 / n as f64 - 0.5) * 2.0 * spread;
                let p = ((i * 7 % n) as f64 / n as f64 - 0.5) * 2.0 * spread;
                Vector3::new(a.sin() * p.cos(), a.sin() * p.sin(), z * a.cos())
            })
            .collect()
    }

    #[test]
    fn bench_scene() {
        let exits = near(0.13, 1024, 1.0);
        let t = std::time::Instant::now();
        let (r, w) = run::<f64, Full>(0.046, 1e-6, None, &exits);
        println!("bench scene: redone {r}, worst {w:e}, {:?}", t.elapsed());
    }

    #[test]
    fn lanes_match_the_per_direction_series() {
        // σ of vσ ≈ 0.3, 1, 3 (and 6 in f64) at 0.5 µm near the mirror direction.
        for sigma in [0.0066, 0.022, 0.066] {
            for iface in [None, Some((1.5, false)), Some((1.5, true))] {
                let exits = near(0.3, 97, if iface.is_some() { -1.0 } else { 1.0 });
                let exits: Vec<_> = exits.iter().chain(&near(0.3, 97, 1.0)).copied().collect();
                let (r, w) = run::<f64, Full>(sigma, 1e-12, iface, &exits);
                println!("f64 Full σ {sigma} {iface:?}: redone {r}, worst {w:e}");
                let (r, w) = run::<f64, Intensity>(sigma, 1e-12, iface, &exits);
                println!("f64 Int σ {sigma} {iface:?}: redone {r}, worst {w:e}");
                let (r, w) = run::<f32, Full>(sigma, 1e-6, iface, &exits);
                println!("f32 Full σ {sigma} {iface:?}: redone {r}, worst {w:e}");
            }
        }
    }
}
