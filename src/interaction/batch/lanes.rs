//! The vector arithmetic of the batch kernel: the per-type lane operations (`ExpLanes`), the
//! exponential, complex numbers in lanes and small 3-vector helpers.

use num_complex::Complex;
use pulp::Simd;

use crate::mueller::batch::Lanes;

/// What the kernel needs beyond [`Lanes`]: division, square root, comparisons, selects, and
/// the exponential's per-type constants and `2ⁿ`.
pub(crate) trait ExpLanes: Lanes {
    /// A lane mask.
    type M<S: Simd>: Copy;
    /// `ln(smallest subnormal / 2)` rounded down and `ln(max)` rounded up: the clamp of [`vexp`].
    const EXP_LO: f64;
    const EXP_HI: f64;
    /// `1.5 · 2^(mantissa bits)`: adding it rounds to an integer.
    const SHIFTER: f64;
    /// `ln 2 = LN2_HI + LN2_LO`, `LN2_HI` with enough trailing zeros that `n · LN2_HI` is exact.
    const LN2_HI: f64;
    const LN2_LO: f64;
    /// Taylor coefficients `1/j!` from the highest degree down to `j = 0`.
    const EXP_POLY: &'static [f64];
    /// The size range `[MIN_POSITIVE / ε, MAX / 4]` of the fast validity test (`ε m` stays
    /// normal, `3 m` finite).
    const MIN_SIZE: f64;
    const MAX_SIZE: f64;
    fn vdiv<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    fn vsqrt<S: Simd>(s: S, a: Self::V<S>) -> Self::V<S>;
    fn vabs<S: Simd>(s: S, a: Self::V<S>) -> Self::V<S>;
    fn vmin<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    fn vmax<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    fn vlt<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S>;
    fn vle<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S>;
    fn veq<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S>;
    fn vand<S: Simd>(s: S, a: Self::M<S>, b: Self::M<S>) -> Self::M<S>;
    fn vnot<S: Simd>(s: S, a: Self::M<S>) -> Self::M<S>;
    /// Whether any lane of `m` is set.
    fn vany<S: Simd>(s: S, m: Self::M<S>) -> bool;
    fn vselect<S: Simd>(s: S, m: Self::M<S>, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    /// `2ⁿ` for integral `n` with `n + bias` a valid biased exponent (normal result).
    fn vpow2<S: Simd>(s: S, n: Self::V<S>) -> Self::V<S>;
}

macro_rules! impl_exp_lanes {
    ($t:ty, $v:ident, $m:ident, $div:ident, $sqrt:ident, $abs:ident, $min:ident, $max:ident,
     $lt:ident, $le:ident, $eq:ident, $and:ident, $not:ident, $first:ident, $select:ident,
     $lanes:ident) => {
        type M<S: Simd> = S::$m;
        #[inline(always)]
        fn vdiv<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S> {
            s.$div(a, b)
        }
        #[inline(always)]
        fn vsqrt<S: Simd>(s: S, a: Self::V<S>) -> Self::V<S> {
            s.$sqrt(a)
        }
        #[inline(always)]
        fn vabs<S: Simd>(s: S, a: Self::V<S>) -> Self::V<S> {
            s.$abs(a)
        }
        #[inline(always)]
        fn vmin<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S> {
            s.$min(a, b)
        }
        #[inline(always)]
        fn vmax<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S> {
            s.$max(a, b)
        }
        #[inline(always)]
        fn vlt<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S> {
            s.$lt(a, b)
        }
        #[inline(always)]
        fn vle<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S> {
            s.$le(a, b)
        }
        #[inline(always)]
        fn veq<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S> {
            s.$eq(a, b)
        }
        #[inline(always)]
        fn vand<S: Simd>(s: S, a: Self::M<S>, b: Self::M<S>) -> Self::M<S> {
            s.$and(a, b)
        }
        #[inline(always)]
        fn vnot<S: Simd>(s: S, a: Self::M<S>) -> Self::M<S> {
            s.$not(a)
        }
        #[inline(always)]
        fn vany<S: Simd>(s: S, m: Self::M<S>) -> bool {
            s.$first(m) < S::$lanes
        }
        #[inline(always)]
        fn vselect<S: Simd>(s: S, m: Self::M<S>, a: Self::V<S>, b: Self::V<S>) -> Self::V<S> {
            s.$select(m, a, b)
        }
    };
}

impl ExpLanes for f64 {
    impl_exp_lanes!(
        f64,
        f64s,
        m64s,
        div_f64s,
        sqrt_f64s,
        abs_f64s,
        min_f64s,
        max_f64s,
        less_than_f64s,
        less_than_or_equal_f64s,
        equal_f64s,
        and_m64s,
        not_m64s,
        first_true_m64s,
        select_f64s,
        F64_LANES
    );
    // exp(x) rounds to 0 below ln(2⁻¹⁰⁷⁵) ≈ −745.133 and overflows above ≈ 709.783.
    const MIN_SIZE: f64 = f64::MIN_POSITIVE / f64::EPSILON;
    const MAX_SIZE: f64 = f64::MAX / 4.0;
    const EXP_LO: f64 = -746.0;
    const EXP_HI: f64 = 710.0;
    const SHIFTER: f64 = 6755399441055744.0; // 1.5 · 2⁵²
    // fdlibm's split: LN2_HI has 21 trailing zero bits.
    const LN2_HI: f64 = 6.93147180369123816490e-01;
    const LN2_LO: f64 = 1.90821492927058770002e-10;
    const EXP_POLY: &'static [f64] = &[
        1.0 / 6227020800.0,
        1.0 / 479001600.0,
        1.0 / 39916800.0,
        1.0 / 3628800.0,
        1.0 / 362880.0,
        1.0 / 40320.0,
        1.0 / 5040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
        1.0,
    ];
    #[inline(always)]
    fn vpow2<S: Simd>(s: S, n: Self::V<S>) -> Self::V<S> {
        // t = (n + 1023) · 2³² + 1.5 · 2⁵² holds the biased exponent in the upper 32 bits of
        // each lane (0x43380000 + n + 1023) and zeros below; shifting every 32-bit half left by
        // 20 moves it to bits 52–62 and clears the 0x4338 (and leaves the lower half 0).
        let biased = s.add_f64s(n, s.splat_f64s(1023.0));
        let t = s.mul_add_e_f64s(
            biased,
            s.splat_f64s(4294967296.0),
            s.splat_f64s(Self::SHIFTER),
        );
        if core::mem::size_of::<S::u32s>() == core::mem::size_of::<S::f64s>() {
            let u: S::u32s = pulp::bytemuck::cast(t);
            let u = s.wrapping_dyn_shl_u32s(u, s.splat_u32s(20));
            pulp::bytemuck::cast(u)
        } else {
            // One-lane back-end (u32 narrower than f64): (bits(n + 1023 + 1.5·2⁵²) − bits(1.5·2⁵²))·2⁵².
            let t = s.add_f64s(biased, s.splat_f64s(Self::SHIFTER));
            let u: S::u64s = pulp::bytemuck::cast(t);
            let u = s.sub_u64s(u, s.splat_u64s(Self::SHIFTER.to_bits()));
            let u = s.mul_u64s(u, s.splat_u64s(1 << 52));
            pulp::bytemuck::cast(u)
        }
    }
}

impl ExpLanes for f32 {
    impl_exp_lanes!(
        f32,
        f32s,
        m32s,
        div_f32s,
        sqrt_f32s,
        abs_f32s,
        min_f32s,
        max_f32s,
        less_than_f32s,
        less_than_or_equal_f32s,
        equal_f32s,
        and_m32s,
        not_m32s,
        first_true_m32s,
        select_f32s,
        F32_LANES
    );
    // exp(x) rounds to 0 below ln(2⁻¹⁵⁰) ≈ −103.972 and overflows above ≈ 88.723.
    const MIN_SIZE: f64 = (f32::MIN_POSITIVE / f32::EPSILON) as f64;
    const MAX_SIZE: f64 = (f32::MAX / 4.0) as f64;
    const EXP_LO: f64 = -104.0;
    const EXP_HI: f64 = 89.0;
    const SHIFTER: f64 = 12582912.0; // 1.5 · 2²³
    // Cephes' split: LN2_HI = 0.693359375 has 15 trailing zero bits.
    const LN2_HI: f64 = 0.693359375;
    const LN2_LO: f64 = -2.12194440e-4;
    const EXP_POLY: &'static [f64] = &[
        1.0 / 5040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
        1.0,
    ];
    #[inline(always)]
    fn vpow2<S: Simd>(s: S, n: Self::V<S>) -> Self::V<S> {
        // t = n + 127 + 1.5 · 2²³ has bits 0x4B400000 + n + 127; shifting left by 23 moves
        // n + 127 into the exponent field and the 0x4B4 out of the word.
        let t = s.add_f32s(
            s.add_f32s(n, s.splat_f32s(127.0)),
            s.splat_f32s(Self::SHIFTER as f32),
        );
        let u: S::u32s = pulp::bytemuck::cast(t);
        let u = s.wrapping_dyn_shl_u32s(u, s.splat_u32s(23));
        pulp::bytemuck::cast(u)
    }
}

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
/// value (the kernel never passes one).
#[inline(always)]
pub(crate) fn vexp<S: Simd, F: ExpLanes>(s: S, x: F::V<S>) -> F::V<S> {
    let c = |v: f64| F::vsplat(s, F::lit(v));
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

/// A complex number as two vectors.
#[derive(Clone, Copy)]
pub(super) struct C<V> {
    pub(super) re: V,
    pub(super) im: V,
}

/// Complex arithmetic on vectors, with `num_complex`'s operations in its order and without
/// fused multiply–adds, so that the Rayleigh–Rice factors round exactly as the scalar ones.
#[derive(Clone, Copy)]
pub(super) struct Cx<S>(pub(super) S);

impl<S: Simd> Cx<S> {
    #[inline(always)]
    pub(super) fn splat<F: ExpLanes>(self, z: Complex<F>) -> C<F::V<S>> {
        C {
            re: F::vsplat(self.0, z.re),
            im: F::vsplat(self.0, z.im),
        }
    }
    /// `(a.re b.re − a.im b.im) + i (a.re b.im + a.im b.re)`.
    #[inline(always)]
    pub(super) fn mul<F: ExpLanes>(self, a: C<F::V<S>>, b: C<F::V<S>>) -> C<F::V<S>> {
        let s = self.0;
        C {
            re: F::vsub(s, F::vmul(s, a.re, b.re), F::vmul(s, a.im, b.im)),
            im: F::vadd(s, F::vmul(s, a.re, b.im), F::vmul(s, a.im, b.re)),
        }
    }
    /// `z · t` for real `t`.
    #[inline(always)]
    pub(super) fn scale<F: ExpLanes>(self, z: C<F::V<S>>, t: F::V<S>) -> C<F::V<S>> {
        C {
            re: F::vmul(self.0, z.re, t),
            im: F::vmul(self.0, z.im, t),
        }
    }
    /// `1/z = z̄/|z|²` with one division ([`super::pbsdf`]'s `recip`).
    #[inline(always)]
    pub(super) fn recip<F: ExpLanes>(self, z: C<F::V<S>>) -> C<F::V<S>> {
        let s = self.0;
        let n2 = F::vadd(s, F::vmul(s, z.re, z.re), F::vmul(s, z.im, z.im));
        let inv = F::vdiv(s, F::vsplat(s, F::one()), n2);
        C {
            re: F::vmul(s, z.re, inv),
            im: F::vmul(s, F::vsub(s, F::vsplat(s, F::zero()), z.im), inv),
        }
    }
}

/// `Re(x ȳ) = x.re y.re + x.im y.im` (one fused multiply–add).
#[inline(always)]
pub(super) fn re_conj<S: Simd, F: ExpLanes>(s: S, x: C<F::V<S>>, y: C<F::V<S>>) -> F::V<S> {
    F::vmul_add(s, x.re, y.re, F::vmul(s, x.im, y.im))
}

/// `Im(x ȳ) = x.im y.re − x.re y.im` (one fused multiply–add).
#[inline(always)]
pub(super) fn im_conj<S: Simd, F: ExpLanes>(s: S, x: C<F::V<S>>, y: C<F::V<S>>) -> F::V<S> {
    F::vneg_mul_add(s, x.re, y.im, F::vmul(s, x.im, y.re))
}

/// `(a · b + c · d) + e · f` without fusing (nalgebra's 3-vector dot product order).
#[inline(always)]
pub(super) fn dot3<S: Simd, F: ExpLanes>(s: S, a: [F::V<S>; 3], b: [F::V<S>; 3]) -> F::V<S> {
    F::vadd(
        s,
        F::vadd(s, F::vmul(s, a[0], b[0]), F::vmul(s, a[1], b[1])),
        F::vmul(s, a[2], b[2]),
    )
}

/// `v − k (v·k)` normalised, twice (`frame.rs`'s `orthogonalize`), unfused.
#[inline(always)]
pub(super) fn orthogonalize<S: Simd, F: ExpLanes>(
    s: S,
    v: [F::V<S>; 3],
    k: [F::V<S>; 3],
) -> [F::V<S>; 3] {
    let once = orthogonalize_step::<S, F>(s, v, k);
    orthogonalize_step::<S, F>(s, once, k)
}

/// One step of [`orthogonalize`]. (Functions rather than closures or `array::map` throughout
/// the vector code: they are `inline(always)`, so nothing is compiled outside pulp's
/// `#[target_feature]` function.)
#[inline(always)]
pub(super) fn orthogonalize_step<S: Simd, F: ExpLanes>(
    s: S,
    v: [F::V<S>; 3],
    k: [F::V<S>; 3],
) -> [F::V<S>; 3] {
    let d = dot3::<S, F>(s, v, k);
    let a = [
        F::vsub(s, v[0], F::vmul(s, k[0], d)),
        F::vsub(s, v[1], F::vmul(s, k[1], d)),
        F::vsub(s, v[2], F::vmul(s, k[2], d)),
    ];
    let norm = F::vsqrt(s, dot3::<S, F>(s, a, a));
    div3::<S, F>(s, a, norm)
}

/// `v / d` component by component (true divisions, as nalgebra's `Vector3 / T`).
#[inline(always)]
pub(super) fn div3<S: Simd, F: ExpLanes>(s: S, v: [F::V<S>; 3], d: F::V<S>) -> [F::V<S>; 3] {
    [
        F::vdiv(s, v[0], d),
        F::vdiv(s, v[1], d),
        F::vdiv(s, v[2], d),
    ]
}
