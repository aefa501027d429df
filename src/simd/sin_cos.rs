//! The vector sine and cosine `vsin_cos`: quadrant reduction by a three-part Cody–Waite `π/2`,
//! minimax polynomials on `[−π/4, π/4]`, and the quadrant's swap and signs by selects,
//! branch-free, on every lane.

use pulp::Simd;

use super::Lanes;

/// `(sin x, cos x)` on every lane for `|x| ≤ 2π`, within 1 ulp of the standard library's
/// `sin_cos` *relative to each result* as measured, the zeros of sine and cosine at multiples
/// of `π/2` included: every f32 of `[−2π, 2π]`, and 4 · 10⁵ f64 points (uniform, `2π u`, the
/// multiples of `π/4` with their neighbours), on every back-end (see the tests). The three
/// parts of `π/2` resolve it far below the distance of any float of this range from a
/// multiple of `π/2`, so the reduced argument keeps its relative accuracy there.
///
/// # Formula
/// ```text
/// n = round(x · 2/π)
/// r = y + t,  y = (x − n P₀) − n P₁,  t = ((x − n P₀) − y − n P₁) − n P₂
///     (π/2 = P₀ + P₁ + P₂, Lanes::PIO2: x − n P₀ and n P₁ exact, t the rounding error of y
///     and the third part, |t| ≪ |y|)
/// z = y²,  sin r ≈ y + (y z S(z) + t (1 − z/2)),  S(z) = Σⱼ Sⱼ zʲ⁻¹
///          cos r ≈ w + (((1 − w) − z/2) + (z² C(z) − y t)),  w = 1 − z/2,  C(z) = Σⱼ Cⱼ zʲ⁻¹
/// q = n mod 4:  sin x = (sin r, cos r, −sin r, −cos r)_q,  cos x = (cos r, −sin r, −cos r, sin r)_q
/// ```
/// `Sⱼ`, `Cⱼ` are fdlibm's (f64, degree 13 and 14) or Cephes' (f32, degree 7 and 8), see
/// [`Lanes::SIN_POLY`]; `((1 − w) − z/2)` recovers the rounding error of `w` (fdlibm's
/// `__kernel_cos`). `q` comes from `n` by float operations (no integer conversion).
/// Beyond `2π`: still 1 ulp on `|x| ≤ 64π` (4 · 10⁵ points each type, measured); the
/// reduction's products are exact up to `|n| < 2²⁰` (f64) or `2⁸` (f32, `|x| ≲ 400`), beyond
/// which the values are unspecified (NaN for huge `|x|`). ±∞ and NaN give NaN; `sin(−0)` is
/// `+0`. No panic.
#[inline(always)]
pub(crate) fn vsin_cos<S: Simd, F: Lanes>(s: S, x: F::V<S>) -> (F::V<S>, F::V<S>) {
    let c = |v: f64| F::vlit(s, v);
    let shifter = c(F::SHIFTER);
    let n = F::vsub(
        s,
        F::vmul_add(s, x, c(core::f64::consts::FRAC_2_PI), shifter),
        shifter,
    );
    // Cody–Waite: r0 = x − n P₀ is exact (Sterbenz), so is n P₁; y = r0 − n P₁ rounds, and t
    // takes its error (Fast2Sum: |r0| ≥ |n P₁| unless the subtraction is exact) and −n P₂.
    let r0 = F::vneg_mul_add(s, n, c(F::PIO2[0]), x);
    let w1 = F::vmul(s, n, c(F::PIO2[1]));
    let y = F::vsub(s, r0, w1);
    let t = F::vsub(s, F::vsub(s, r0, y), w1);
    let t = F::vneg_mul_add(s, n, c(F::PIO2[2]), t);

    let z = F::vmul(s, y, y);
    let hz = F::vmul(s, c(0.5), z);
    let mut ps = c(F::SIN_POLY[0]);
    for &k in &F::SIN_POLY[1..] {
        ps = F::vmul_add(s, ps, z, c(k));
    }
    let mut pc = c(F::COS_POLY[0]);
    for &k in &F::COS_POLY[1..] {
        pc = F::vmul_add(s, pc, z, c(k));
    }
    // sin r = y + (y z S(z) + t (1 − z/2))
    let sin_tail = F::vmul_add(s, F::vmul(s, y, z), ps, F::vneg_mul_add(s, hz, t, t));
    let sin_r = F::vadd(s, y, sin_tail);
    // cos r = w + (((1 − w) − z/2) + (z² C(z) − y t))
    let w = F::vsub(s, c(1.0), hz);
    let cos_tail = F::vneg_mul_add(s, y, t, F::vmul(s, F::vmul(s, z, z), pc));
    let cos_r = F::vadd(
        s,
        w,
        F::vadd(s, F::vsub(s, F::vsub(s, c(1.0), w), hz), cos_tail),
    );

    // q = n − 4 round((n − 1.5)/4) ∈ {0, 1, 2, 3} (no ties: (n − 1.5)/4 is never a half-integer).
    let h = F::vmul_add(s, n, c(0.25), c(-0.375));
    let h = F::vsub(s, F::vadd(s, h, shifter), shifter);
    let q = F::vneg_mul_add(s, h, c(4.0), n);
    // Odd q swaps sine and cosine; q ∈ {2, 3} negates the sine, q ∈ {1, 2} the cosine.
    let odd = F::veq(s, F::vabs(s, F::vsub(s, q, c(2.0))), c(1.0));
    let neg_sin = F::vle(s, c(2.0), q);
    let neg_cos = F::vle(s, F::vabs(s, F::vsub(s, q, c(1.5))), c(0.5));
    let sin_x = F::vselect(s, odd, cos_r, sin_r);
    let cos_x = F::vselect(s, odd, sin_r, cos_r);
    let sin_x = F::vselect(s, neg_sin, F::vmul(s, sin_x, c(-1.0)), sin_x);
    let cos_x = F::vselect(s, neg_cos, F::vmul(s, cos_x, c(-1.0)), cos_x);
    (sin_x, cos_x)
}

#[cfg(test)]
mod tests {
    use core::f64::consts::{FRAC_PI_4, TAU};

    use pulp::Simd;

    use super::vsin_cos;
    use crate::simd::Lanes;
    use crate::simd::check::{Float, Worst, on_back_ends, track, ulps};
    use crate::simd::driver::LaneMap;

    struct SinCos;

    impl<F: Lanes> LaneMap<F, 1, 2> for SinCos {
        #[inline(always)]
        fn eval<S: Simd>(&self, s: S, x: [F::V<S>; 1]) -> [F::V<S>; 2] {
            let (sin, cos) = vsin_cos::<S, F>(s, x[0]);
            [sin, cos]
        }
    }

    /// The worst cases of `vsin_cos` on every back-end against the standard library's
    /// `sin_cos`, for sine and cosine: in ulps of the result, in ulps of the result where
    /// `|result| ≥ 2⁻¹⁰`, and the absolute error in ulps of 1.
    struct Errors<F> {
        rel: [Worst<F>; 2],
        rel_away: [Worst<F>; 2],
        abs: [f64; 2],
    }

    fn errors<F: Float>(xs: &[F]) -> Errors<F> {
        let zero = F::of(0.0);
        let none = (0, zero, zero, zero);
        let mut e = Errors {
            rel: [none; 2],
            rel_away: [none; 2],
            abs: [0.0; 2],
        };
        let want: Vec<(F, F)> = xs.iter().map(|x| x.std_sin_cos()).collect();
        on_back_ends(&SinCos, xs, |_, got| {
            for (i, (&x, &(ws, wc))) in xs.iter().zip(&want).enumerate() {
                for (j, (g, w)) in [(got[0][i], ws), (got[1][i], wc)].into_iter().enumerate() {
                    let u = ulps(g, w);
                    track(&mut e.rel[j], u, x, g, w);
                    if w.f64().abs() >= 2f64.powi(-10) {
                        track(&mut e.rel_away[j], u, x, g, w);
                    }
                    e.abs[j] = e.abs[j].max((g.f64() - w.f64()).abs() / F::EPS);
                }
            }
        });
        e
    }

    fn report<F: Float>(what: &str, n: usize, e: &Errors<F>) {
        for (j, f) in ["sin", "cos"].into_iter().enumerate() {
            let (u, x, g, w) = e.rel[j];
            println!(
                "{what} {f}, {n} points: max {u} ulp at x = {x:e} ({g:e}, std {w:e}); \
                 {} ulp where |{f}| ≥ 2⁻¹⁰; absolute {:.3} ulp(1)",
                e.rel_away[j].0, e.abs[j]
            );
        }
    }

    /// `n` points uniform on `[−2π, 2π]`, `2π u` for `u = i/n`, the multiples of `π/4` with 4
    /// neighbours on either side, and `specials`.
    fn points<F: Float>(n: usize, up: fn(F) -> F, down: fn(F) -> F, specials: &[F]) -> Vec<F> {
        let mut xs: Vec<F> = (0..n)
            .map(|i| F::of(-TAU + 2.0 * TAU * (i as f64 + 0.5) / n as f64))
            .collect();
        xs.extend((0..n).map(|i| F::of(TAU * (i as f64 / n as f64))));
        for k in -8..=8 {
            let x = F::of(f64::from(k) * FRAC_PI_4);
            let (mut u, mut d) = (x, x);
            xs.push(x);
            for _ in 0..4 {
                u = up(u);
                d = down(d);
                xs.extend([u, d]);
            }
        }
        xs.extend_from_slice(specials);
        xs
    }

    #[test]
    fn vsin_cos_f64_within_1_ulp_of_each_result() {
        let specials = [
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            1e-300,
            2f64.powi(-30),
            -2f64.powi(-30),
            TAU * (1.0 - 2f64.powi(-53)),
            TAU.next_down(),
            -TAU.next_down(),
        ];
        let xs = points(200_000, f64::next_up, f64::next_down, &specials);
        let e = errors(&xs);
        report("vsin_cos f64", xs.len(), &e);
        for w in e.rel {
            let (u, x, g, w) = w;
            assert!(u <= 1, "x = {x:e}: {g:e}, std {w:e}: {u} ulp");
        }
    }

    #[test]
    fn vsin_cos_f32_within_1_ulp_of_each_result() {
        let specials = [
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-30,
            2f32.powi(-14),
            -2f32.powi(-14),
            core::f32::consts::TAU * (1.0 - 2f32.powi(-24)),
            core::f32::consts::TAU.next_down(),
            -core::f32::consts::TAU.next_down(),
        ];
        let xs = points(200_000, f32::next_up, f32::next_down, &specials);
        let e = errors(&xs);
        report("vsin_cos f32", xs.len(), &e);
        for w in e.rel {
            let (u, x, g, w) = w;
            assert!(u <= 1, "x = {x:e}: {g:e}, std {w:e}: {u} ulp");
        }
    }

    /// Beyond `2π`: within 1 ulp on `|x| ≤ 64π` too.
    #[test]
    fn vsin_cos_within_1_ulp_on_64_pi() {
        let n = 400_000;
        let f = |i: usize| -64.0 * TAU / 2.0 + 64.0 * TAU * (i as f64 + 0.5) / n as f64;
        let xs: Vec<f64> = (0..n).map(f).collect();
        let e64 = errors(&xs);
        report("vsin_cos f64 |x| ≤ 64π", n, &e64);
        let xs: Vec<f32> = (0..n).map(|i| f(i) as f32).collect();
        let e32 = errors(&xs);
        report("vsin_cos f32 |x| ≤ 64π", n, &e32);
        for u in [e64.rel.map(|w| w.0), e32.rel.map(|w| w.0)].concat() {
            assert!(u <= 1, "{u} ulp");
        }
    }

    /// ±∞ and NaN give NaN; huge arguments run too (their values are unspecified).
    #[test]
    fn vsin_cos_of_non_finite_is_nan() {
        let xs = [f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 1e300, -1e300];
        on_back_ends(&SinCos, &xs, |what, out| {
            for o in out {
                assert!(o[..3].iter().all(|v| v.is_nan()), "{what}: {o:?}");
            }
        });
        let xs = [f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1e30, -1e30];
        on_back_ends(&SinCos, &xs, |what, out| {
            for o in out {
                assert!(o[..3].iter().all(|v| v.is_nan()), "{what}: {o:?}");
            }
        });
    }

    /// Every f32 in `[−2π, 2π]` (≈ 2.2 · 10⁹ inputs); slow, run on demand.
    #[test]
    #[ignore = "exhaustive, slow (7 min): cargo test --lib simd::sin_cos -- --ignored"]
    fn vsin_cos_f32_exhaustive() {
        let hi = core::f32::consts::TAU.to_bits();
        let mut rel = [0_u64; 2];
        let mut rel_away = [0_u64; 2];
        let mut abs = [0.0_f64; 2];
        for sign in [0, 0x8000_0000_u32] {
            let mut start = 0;
            while start <= hi {
                let end = hi.min(start + (1 << 22) - 1);
                let xs: Vec<f32> = (start..=end).map(|b| f32::from_bits(b | sign)).collect();
                let e = errors(&xs);
                for j in 0..2 {
                    if e.rel[j].0 > rel[j] {
                        rel[j] = e.rel[j].0;
                    }
                    rel_away[j] = rel_away[j].max(e.rel_away[j].0);
                    abs[j] = abs[j].max(e.abs[j]);
                }
                start = end + 1;
            }
        }
        println!(
            "vsin_cos f32, every input in [−2π, 2π]: sin {} ulp ({} where |sin| ≥ 2⁻¹⁰, \
             absolute {:.3} ulp(1)), cos {} ulp ({}, {:.3})",
            rel[0], rel_away[0], abs[0], rel[1], rel_away[1], abs[1]
        );
        assert!(rel[0] <= 1 && rel[1] <= 1);
    }
}
