//! The vector exponential `vexp`: Cody–Waite reduction, a Taylor polynomial and a two-step
//! scaling by `2ⁿ`, branch-free, on every lane.

use pulp::Simd;

use super::Lanes;

/// `eˣ` on every lane, within 2 ulp of the correctly rounded value over the whole range
/// (subnormal results included; 0 below the underflow threshold and for −∞, +∞ above the
/// overflow threshold).
///
/// # Formula
/// ```text
/// n = round(x / ln 2),  r = x − n LN2_HI − n LN2_LO   (|r| ≤ ln 2 / 2, Cody–Waite)
/// eˣ = (Σ_{j ≤ J} rʲ/j!) · 2^{n₁} · 2^{n₂},  n₁ = round(n/2), n₂ = n − n₁
/// ```
/// J = 13 (f64, truncation ≤ 0.02 ulp) or 7 (f32, ≤ 0.13 ulp); the two-step scaling keeps both
/// factors normal, so results in the subnormal range are rounded once. NaN gives an unspecified
/// value (the kernels never pass one).
#[inline(always)]
pub(crate) fn vexp<S: Simd, F: Lanes>(s: S, x: F::V<S>) -> F::V<S> {
    let c = |v: f64| F::vlit(s, v);
    let (p, nf) = reduced::<S, F>(s, F::vmin(s, F::vmax(s, x, c(F::EXP_LO)), c(F::EXP_HI)));
    let shifter = c(F::SHIFTER);
    let n1 = F::vsub(s, F::vmul_add(s, nf, c(0.5), shifter), shifter);
    let n2 = F::vsub(s, nf, n1);
    F::vmul(s, F::vmul(s, p, F::vpow2(s, n1)), F::vpow2(s, n2))
}

/// `eˣ` for `x ≤ 0` with one scaling step: [`vexp`]'s reduction and polynomial, `x` clamped to
/// `[ln MIN_POSITIVE, 0]` so that `2ⁿ` is normal. Within 2 ulp of the correctly rounded value
/// where `eˣ ≥ MIN_POSITIVE`; below, a value in `[MIN_POSITIVE/2, 2 MIN_POSITIVE]` (for terms
/// of a sum whose largest term is 1, where that is below the sum's rounding). Positive `x`
/// gives 1, NaN an unspecified value. Six operations fewer than [`vexp`] (the series lanes
/// call it once per order and channel).
#[inline(always)]
pub(crate) fn vexp_nonpositive<S: Simd, F: Lanes>(s: S, x: F::V<S>) -> F::V<S> {
    let c = |v: f64| F::vlit(s, v);
    let (p, nf) = reduced::<S, F>(s, F::vmin(s, F::vmax(s, x, c(F::EXP_NORMAL_LO)), c(0.0)));
    F::vmul(s, p, F::vpow2(s, nf))
}

/// The Cody–Waite reduction and the polynomial shared by [`vexp`] and [`vexp_nonpositive`]:
/// `(Σ_{j ≤ J} rʲ/j!, n)` with `eˣ = Σ · 2ⁿ` for the clamped `x`.
#[inline(always)]
fn reduced<S: Simd, F: Lanes>(s: S, x: F::V<S>) -> (F::V<S>, F::V<S>) {
    let c = |v: f64| F::vlit(s, v);
    let shifter = c(F::SHIFTER);
    let nf = F::vsub(
        s,
        F::vmul_add(s, x, c(core::f64::consts::LOG2_E), shifter),
        shifter,
    );
    let r = F::vneg_mul_add(s, nf, c(F::LN2_HI), x);
    let r = F::vneg_mul_add(s, nf, c(F::LN2_LO), r);
    let mut p = c(F::EXP_POLY[0]);
    for &k in &F::EXP_POLY[1..] {
        p = F::vmul_add(s, p, r, c(k));
    }
    (p, nf)
}

#[cfg(test)]
mod tests {
    use pulp::Simd;

    use super::*;
    use crate::simd::check::{Float, on_back_ends, ulps};
    use crate::simd::driver::LaneMap;

    struct ExpNonPositive;

    impl<F: Lanes> LaneMap<F, 1, 1> for ExpNonPositive {
        #[inline(always)]
        fn eval<S: Simd>(&self, s: S, x: [F::V<S>; 1]) -> [F::V<S>; 1] {
            [vexp_nonpositive::<S, F>(s, x[0])]
        }
    }

    /// Against the standard library's `exp` (in f64, rounded to `F`): within 2 ulp down to
    /// `ln MIN_POSITIVE`, in `[MIN_POSITIVE/2, 2 MIN_POSITIVE]` below, 1 above 0; on every
    /// back-end.
    fn check<F: Float>(lo: f64, n: usize) {
        let normal_lo = F::EXP_NORMAL_LO;
        let mut xs: Vec<F> = (0..=n).map(|i| F::of(lo * i as f64 / n as f64)).collect();
        xs.extend([normal_lo, 0.0, -0.0, 1.0, 1e30, -1e30].map(F::of));
        let mut worst = 0;
        on_back_ends(&ExpNonPositive, &xs, |what, [got]| {
            for (&x, &g) in xs.iter().zip(got) {
                let (xf, gf) = (x.f64(), g.f64());
                if xf >= 0.0 {
                    assert_eq!(gf, 1.0, "{what}: e^{xf:e}");
                } else if xf >= normal_lo {
                    let u = ulps(g, F::of(xf.exp()));
                    worst = worst.max(u);
                    assert!(u <= 2, "{what}: e^{xf:e} = {gf:e}, {u} ulp");
                } else {
                    let mp = if F::EPS < 1e-10 {
                        f64::MIN_POSITIVE
                    } else {
                        f64::from(f32::MIN_POSITIVE)
                    };
                    assert!(
                        gf >= 0.5 * mp && gf <= 2.0 * mp,
                        "{what}: e^{xf:e} = {gf:e}"
                    );
                }
            }
        });
        println!("vexp_nonpositive: max {worst} ulp");
    }

    #[test]
    fn vexp_nonpositive_f64_within_2_ulp() {
        check::<f64>(-750.0, 300_000);
    }

    #[test]
    fn vexp_nonpositive_f32_within_2_ulp() {
        check::<f32>(-110.0, 300_000);
    }
}
