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
//! the last order built ([`SeriesPrep::orders`]: `ĝ + 12√ĝ + 24` for the largest `g` of the
//! packet's exits, at most `SERIES_ORDERS`, 160; far tails, where the orders that dominate lie
//! far above `g`).

use pulp::Simd;

use super::super::prep::{SeriesChannel, SeriesPrep};
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
    let orders = p.orders;
    let mut last = orders;
    for i in 0..orders {
        let b = base::<S, F>(s, i, neg_g, ln_g);
        // The stop test every 4 orders (and at the last): once met it holds at every later
        // order (the ratios fall, the terms fall, m stays).
        let test = i % 4 == 3 || i + 1 == orders;
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
        let up = if matches!(interface, Some((_, true))) {
            1.0
        } else {
            -1.0
        };
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
                        series: core::slice::from_ref(&Some(series)),
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

    /// Exits over the hemisphere of side `z` (`cos θ_o ≥ 0.05`).
    fn hemisphere(n: usize, z: f64) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|i| {
                let c = 0.05 + 0.95 * ((i * 37 % n) as f64 + 0.5) / n as f64;
                let p = std::f64::consts::TAU * (i as f64 + 0.5) / n as f64;
                let sn = (1.0 - c * c).sqrt();
                Vector3::new(sn * p.cos(), sn * p.sin(), z * c)
            })
            .collect()
    }

    /// The lanes against the per-direction series kernel with the same tolerance, on a rough
    /// conductor and a glass interface lit from above and from below, at `vσ ≈ 0.3, 1, 3` and
    /// 6 in the mirror direction (`v = 2k cos 35°`, λ = 0.5 µm), near the lobes and over the
    /// hemisphere.
    ///
    /// Bound per Stokes parameter of a lobe of `S0 = L` (the exit's one-at-a-time value), in
    /// units `u = ε (4 + |ln L|) L + MIN_POSITIVE`: `|Δ| ≤ 8 u + tol L` (the first-order lanes'
    /// `4 ε (4 + |ln L| + 2 |ln S0|)` with `S0 = 1`, doubled for the unpolarized-weight factor
    /// `L̂/L` the integration tests bound separately, plus the two sums' truncations, each
    /// within `tol/2`). Measured: f64 (tol 10⁻¹²) at most 0.43 tol L; f32 (tol 10⁻⁶) at most
    /// 2.2 u near the lobes. Redone lanes: none near the lobes; over the hemisphere only those
    /// whose sum needs more orders than were built (`SeriesPrep::orders`) or whose `g` is out of the lanes' range.
    #[test]
    fn lanes_match_the_per_direction_series() {
        let cases = [(0.015, true), (0.05, true), (0.15, true), (0.3, false)];
        for (sigma, f32_in_lanes) in cases {
            for iface in [None, Some((1.5, false)), Some((1.5, true))] {
                let z = if iface.is_some() { -1.0 } else { 1.0 };
                let lobe: Vec<_> = near(0.3, 97, z)
                    .into_iter()
                    .chain(near(0.3, 97, 1.0))
                    .collect();
                let wide: Vec<_> = hemisphere(61, 1.0)
                    .into_iter()
                    .chain(hemisphere(61, z))
                    .collect();
                let what = format!("σ {sigma}, interface {iface:?}");
                for (exits, near_lobe) in [(&lobe, true), (&wide, false)] {
                    let (tol, units) = (1e-12, 1e-12 / (f64::EPSILON * 4.0));
                    let (r, w) = run::<f64, Full>(sigma, tol, iface, exits);
                    assert!(w <= 8.0 + units, "f64 Full {what}: {w} units");
                    assert!(!near_lobe || r == 0, "f64 Full {what}: {r} lanes redone");
                    let (r, w) = run::<f64, Intensity>(sigma, tol, iface, exits);
                    assert!(w <= 8.0 + units, "f64 Intensity {what}: {w} units");
                    assert!(
                        !near_lobe || r == 0,
                        "f64 Intensity {what}: {r} lanes redone"
                    );
                    let (r, w) = run::<f32, Full>(sigma, 1e-6, iface, exits);
                    assert!(
                        w <= 8.0 + 1e-6 / f64::from(f32::EPSILON) / 4.0,
                        "f32 {what}: {w} units"
                    );
                    // Near the lobes every lane stays in lanes, but for a rare one whose S0 is
                    // at the edge of the normal range; beyond the f32 lanes' g every lane is
                    // redone in reflection (the overlapping last vector counts some twice; in
                    // transmission v = k (cos θ_i − η cos θ_o) is smaller).
                    if near_lobe && (f32_in_lanes || iface.is_none()) {
                        let ok = if f32_in_lanes {
                            r <= 2
                        } else {
                            r >= exits.len()
                        };
                        assert!(ok, "f32 {what}: {r} lanes redone");
                    }
                }
            }
        }
    }
}
