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
    let x = F::vmin(s, F::vmax(s, x, c(F::EXP_LO)), c(F::EXP_HI));
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
    let n1 = F::vsub(s, F::vmul_add(s, nf, c(0.5), shifter), shifter);
    let n2 = F::vsub(s, nf, n1);
    F::vmul(s, F::vmul(s, p, F::vpow2(s, n1)), F::vpow2(s, n2))
}
