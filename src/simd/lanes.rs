//! The per-type lane vocabulary: one SIMD vector of `f32` or `f64` under a [`pulp::Simd`]
//! back-end, its arithmetic, comparisons, selects and partial loads and stores, and the one
//! run-time dispatch entry of the crate.

use pulp::{Simd, WithSimd};

mod sealed {
    /// Implemented for `f32` and `f64` only.
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// The lane vocabulary of `f32` and `f64` (sealed): the vector type `V<S>` of
/// `S::F32_LANES` / `S::F64_LANES` lanes of a [`pulp::Simd`] back-end, its mask type `M<S>`,
/// and the operations the batch kernels are written in. [`crate::real::Real`] has it as a
/// supertrait, so every kernel generic over `T: Real` can run in lanes.
///
/// `vmul_add` / `vneg_mul_add` are fused where the instruction set has FMA and `a b + c`
/// otherwise (pulp's plain `mul_add` would call a slow software fma on the scalar back-end).
pub trait Lanes: Copy + Send + Sync + 'static + sealed::Sealed {
    /// One SIMD vector of `Self`.
    type V<S: Simd>: Copy;
    /// A lane mask of `V<S>`.
    type M<S: Simd>: Copy;
    /// `ln(smallest subnormal / 2)` rounded down: the lower clamp of the vector exponential.
    const EXP_LO: f64;
    /// `ln(max)` rounded up: the upper clamp of the vector exponential.
    const EXP_HI: f64;
    /// `ln(MIN_POSITIVE)` rounded up to an integer: the lower clamp of `vexp_nonpositive`
    /// (`2ⁿ` normal for `n = round(x/ln 2)`).
    const EXP_NORMAL_LO: f64;
    /// `1.5 · 2^(mantissa bits)`: adding it rounds to an integer.
    const SHIFTER: f64;
    /// `ln 2 = LN2_HI + LN2_LO`, `LN2_HI` with enough trailing zeros that `n · LN2_HI` is exact.
    const LN2_HI: f64;
    /// The low part of `ln 2` (see [`Lanes::LN2_HI`]).
    const LN2_LO: f64;
    /// Taylor coefficients `1/j!` of the exponential from the highest degree down to `j = 0`.
    const EXP_POLY: &'static [f64];
    /// The vector logarithm's `Lg₁ … Lg_J` from the highest degree down: `R(z) = z Σⱼ Lgⱼ zʲ⁻¹`
    /// approximates `ln((1 + s)/(1 − s)) − 2s` as `s R(s²)` for `|s| ≤ 3 − 2√2`.
    const LOG_POLY: &'static [f64];
    /// `π/2 = PIO2[0] + PIO2[1] + PIO2[2]` (Cody–Waite): the first two parts with enough trailing
    /// zeros that `n · PIO2[0]`, `n · PIO2[1]` are exact for `|n| < 2²⁰` (f64) or `2⁸` (f32).
    const PIO2: [f64; 3];
    /// `S₁ … S_J` of `sin r ≈ r + r³ Σⱼ Sⱼ r²⁽ʲ⁻¹⁾` on `[−π/4, π/4]`, highest degree first.
    const SIN_POLY: &'static [f64];
    /// `C₁ … C_J` of `cos r ≈ 1 − r²/2 + r⁴ Σⱼ Cⱼ r²⁽ʲ⁻¹⁾` on `[−π/4, π/4]`, highest degree first.
    const COS_POLY: &'static [f64];

    /// The number of lanes of `V<S>`.
    fn width<S: Simd>() -> usize;
    /// `x` on every lane.
    fn vsplat<S: Simd>(s: S, x: Self) -> Self::V<S>;
    /// The `f64` literal `x` rounded to `Self`, on every lane.
    fn vlit<S: Simd>(s: S, x: f64) -> Self::V<S>;
    /// `a + b`.
    fn vadd<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    /// `a − b`.
    fn vsub<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    /// `a b`.
    fn vmul<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    /// `a / b`.
    fn vdiv<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    /// `a b + c`.
    fn vmul_add<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>, c: Self::V<S>) -> Self::V<S>;
    /// `c − a b`.
    fn vneg_mul_add<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>, c: Self::V<S>) -> Self::V<S>;
    /// `√a`.
    fn vsqrt<S: Simd>(s: S, a: Self::V<S>) -> Self::V<S>;
    /// `|a|`.
    fn vabs<S: Simd>(s: S, a: Self::V<S>) -> Self::V<S>;
    /// `min(a, b)`.
    fn vmin<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    /// `max(a, b)`.
    fn vmax<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    /// `a < b`.
    fn vlt<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S>;
    /// `a ≤ b`.
    fn vle<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S>;
    /// `a = b`.
    fn veq<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::M<S>;
    /// `a ∨ b` of two masks (De Morgan, from [`Lanes::vand`] and [`Lanes::vnot`]).
    #[inline(always)]
    fn vor<S: Simd>(s: S, a: Self::M<S>, b: Self::M<S>) -> Self::M<S> {
        Self::vnot(s, Self::vand(s, Self::vnot(s, a), Self::vnot(s, b)))
    }
    /// `a ∧ b`.
    fn vand<S: Simd>(s: S, a: Self::M<S>, b: Self::M<S>) -> Self::M<S>;
    /// `¬a`.
    fn vnot<S: Simd>(s: S, a: Self::M<S>) -> Self::M<S>;
    /// Whether any lane of `m` is set.
    fn vany<S: Simd>(s: S, m: Self::M<S>) -> bool;
    /// `a` where `m` is set, `b` elsewhere.
    fn vselect<S: Simd>(s: S, m: Self::M<S>, a: Self::V<S>, b: Self::V<S>) -> Self::V<S>;
    /// `2ⁿ` for integral `n` with `n + bias` a valid biased exponent (normal result).
    fn vpow2<S: Simd>(s: S, n: Self::V<S>) -> Self::V<S>;
    /// `(k, m)` with `x = 2ᵏ m`, `k` integral and `m ∈ [√½, √2)` (the threshold `√2` taken on
    /// the leading 20 (f64) or 23 (f32) bits of the mantissa), for positive normal finite `x`;
    /// unspecified (finite, no panic) for other `x`. Bit operations only: `m` is exact.
    fn vfrexp<S: Simd>(s: S, x: Self::V<S>) -> (Self::V<S>, Self::V<S>);
    /// Whole vectors first, then the remainder.
    fn vsplit<S: Simd>(x: &[Self]) -> (&[Self::V<S>], &[Self]);
    /// [`Lanes::vsplit`] for mutable slices.
    fn vsplit_mut<S: Simd>(x: &mut [Self]) -> (&mut [Self::V<S>], &mut [Self]);
    /// Loads a remainder shorter than a vector (other lanes zero).
    fn load_partial<S: Simd>(s: S, x: &[Self]) -> Self::V<S>;
    /// Stores the first `x.len()` lanes.
    fn store_partial<S: Simd>(s: S, x: &mut [Self], v: Self::V<S>);
}

/// Runs `op` with the best instruction set of this CPU ([`pulp::Arch::dispatch`]: AVX-512 on
/// x86-64-v4 (pulp's `x86-v4` feature, stable since Rust 1.89), AVX2 + FMA on x86-64-v3, NEON
/// on aarch64, a scalar back-end otherwise), detected at run time.
#[inline]
pub fn dispatch<Op: WithSimd>(op: Op) -> Op::Output {
    pulp::Arch::new().dispatch(op)
}

macro_rules! impl_lanes {
    ($t:ty, $v:ident, $m:ident, $splat:ident, $add:ident, $sub:ident, $mul:ident, $div:ident,
     $fma:ident, $fnma:ident, $sqrt:ident, $abs:ident, $min:ident, $max:ident, $lt:ident,
     $le:ident, $eq:ident, $and:ident, $not:ident, $first:ident, $select:ident, $split:ident,
     $split_mut:ident, $lanes:ident, $load:ident, $store:ident) => {
        type V<S: Simd> = S::$v;
        type M<S: Simd> = S::$m;
        #[inline(always)]
        fn width<S: Simd>() -> usize {
            S::$lanes
        }
        #[inline(always)]
        fn vsplat<S: Simd>(s: S, x: Self) -> Self::V<S> {
            s.$splat(x)
        }
        #[inline(always)]
        fn vlit<S: Simd>(s: S, x: f64) -> Self::V<S> {
            s.$splat(x as $t)
        }
        #[inline(always)]
        fn vadd<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S> {
            s.$add(a, b)
        }
        #[inline(always)]
        fn vsub<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S> {
            s.$sub(a, b)
        }
        #[inline(always)]
        fn vmul<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S> {
            s.$mul(a, b)
        }
        #[inline(always)]
        fn vdiv<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>) -> Self::V<S> {
            s.$div(a, b)
        }
        #[inline(always)]
        fn vmul_add<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>, c: Self::V<S>) -> Self::V<S> {
            s.$fma(a, b, c)
        }
        #[inline(always)]
        fn vneg_mul_add<S: Simd>(s: S, a: Self::V<S>, b: Self::V<S>, c: Self::V<S>) -> Self::V<S> {
            s.$fnma(a, b, c)
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
        #[inline(always)]
        fn vsplit<S: Simd>(x: &[Self]) -> (&[Self::V<S>], &[Self]) {
            S::$split(x)
        }
        #[inline(always)]
        fn vsplit_mut<S: Simd>(x: &mut [Self]) -> (&mut [Self::V<S>], &mut [Self]) {
            S::$split_mut(x)
        }
        #[inline(always)]
        fn load_partial<S: Simd>(s: S, x: &[Self]) -> Self::V<S> {
            s.$load(x)
        }
        #[inline(always)]
        fn store_partial<S: Simd>(s: S, x: &mut [Self], v: Self::V<S>) {
            s.$store(x, v)
        }
    };
}

impl Lanes for f64 {
    impl_lanes!(
        f64,
        f64s,
        m64s,
        splat_f64s,
        add_f64s,
        sub_f64s,
        mul_f64s,
        div_f64s,
        mul_add_e_f64s,
        negate_mul_add_e_f64s,
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
        as_simd_f64s,
        as_mut_simd_f64s,
        F64_LANES,
        partial_load_f64s,
        partial_store_f64s
    );
    // exp(x) rounds to 0 below ln(2⁻¹⁰⁷⁵) ≈ −745.133 and overflows above ≈ 709.783.
    const EXP_LO: f64 = -746.0;
    const EXP_HI: f64 = 710.0;
    // ln(2⁻¹⁰²²) ≈ −708.396.
    const EXP_NORMAL_LO: f64 = -708.0;
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
    // fdlibm 5.3 e_log.c (Sun Microsystems, 1993): Lg1 … Lg7, |error of R| < 2⁻⁵⁸·⁴⁵.
    const LOG_POLY: &'static [f64] = &[
        1.479819860511658591e-01,
        1.531383769920937332e-01,
        1.818357216161805012e-01,
        2.222219843214978396e-01,
        2.857142874366239149e-01,
        3.999999999940941908e-01,
        6.666666666666735130e-01,
    ];
    // fdlibm 5.3 e_rem_pio2.c: pio2_1 and pio2_2 (33 bits each), pio2_2t; the three sum to
    // π/2 within 1.1e-37.
    const PIO2: [f64; 3] = [
        1.57079632673412561417e+00,
        6.07710050630396597660e-11,
        2.02226624879595063154e-21,
    ];
    // fdlibm 5.3 k_sin.c: S1 … S6, |sin x / x − (1 + S1 x² + … + S6 x¹²)| ≤ 2⁻⁵⁸ on [−π/4, π/4].
    const SIN_POLY: &'static [f64] = &[
        1.58969099521155010221e-10,
        -2.50507602534068634195e-08,
        2.75573137070700676789e-06,
        -1.98412698298579493134e-04,
        8.33333333332248946124e-03,
        -1.66666666666666324348e-01,
    ];
    // fdlibm 5.3 k_cos.c: C1 … C6, |cos x − (1 − x²/2 + C1 x⁴ + … + C6 x¹⁴)| ≤ 2⁻⁵⁸ on [−π/4, π/4].
    const COS_POLY: &'static [f64] = &[
        -1.13596475577881948265e-11,
        2.08757232129817482790e-09,
        -2.75573143513906633035e-07,
        2.48015872894767294178e-05,
        -1.38888888888741095749e-03,
        4.16666666666666019037e-02,
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
    #[inline(always)]
    fn vfrexp<S: Simd>(s: S, x: Self::V<S>) -> (Self::V<S>, Self::V<S>) {
        // Adding 0x3ff00000 − 0x3fe6a09e to the upper word carries into the exponent field
        // exactly when the mantissa's upper 20 bits are ≥ those of √2 (0x6a09e); the field then
        // holds k + 1023, and the mantissa bits plus 0x3fe6a09e in the upper word rebuild
        // m = x 2⁻ᵏ ∈ [√½, √2) (musl's reduction in log.c).
        let u: S::u64s = pulp::bytemuck::cast(x);
        let u = s.add_u64s(u, s.splat_u64s((0x3ff00000 - 0x3fe6a09e) << 32));
        let m = s.add_u64s(
            s.and_u64s(u, s.splat_u64s(0x000f_ffff_ffff_ffff)),
            s.splat_u64s(0x3fe6a09e << 32),
        );
        // The upper word shifted right by 20 (the exponent field, below the sign) into the
        // mantissa of 2²⁰, where its bit 0 weighs 1: the double 2²⁰ + k + 1023.
        let e = shr_u32_halves(s, u, 20);
        let e = s.or_u64s(
            s.and_u64s(e, s.splat_u64s(0x0000_0fff_0000_0000)),
            s.splat_u64s(1048576.0_f64.to_bits()),
        );
        let k = s.sub_f64s(pulp::bytemuck::cast(e), s.splat_f64s(1048576.0 + 1023.0));
        (k, pulp::bytemuck::cast(m))
    }
}

/// Each 32-bit half of every 64-bit lane of `u` shifted right by `n` (pulp has no 64-bit shifts).
#[inline(always)]
fn shr_u32_halves<S: Simd>(s: S, u: S::u64s, n: u32) -> S::u64s {
    if core::mem::size_of::<S::u32s>() == core::mem::size_of::<S::u64s>() {
        let h: S::u32s = pulp::bytemuck::cast(u);
        pulp::bytemuck::cast(s.wrapping_dyn_shr_u32s(h, s.splat_u32s(n)))
    } else {
        // One-lane back-end (u32 narrower than f64): the two halves as two u32 vectors.
        let [a, b]: [S::u32s; 2] = pulp::bytemuck::cast(u);
        let n = s.splat_u32s(n);
        pulp::bytemuck::cast([s.wrapping_dyn_shr_u32s(a, n), s.wrapping_dyn_shr_u32s(b, n)])
    }
}

impl Lanes for f32 {
    impl_lanes!(
        f32,
        f32s,
        m32s,
        splat_f32s,
        add_f32s,
        sub_f32s,
        mul_f32s,
        div_f32s,
        mul_add_e_f32s,
        negate_mul_add_e_f32s,
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
        as_simd_f32s,
        as_mut_simd_f32s,
        F32_LANES,
        partial_load_f32s,
        partial_store_f32s
    );
    // exp(x) rounds to 0 below ln(2⁻¹⁵⁰) ≈ −103.972 and overflows above ≈ 88.723.
    const EXP_LO: f64 = -104.0;
    const EXP_HI: f64 = 89.0;
    // ln(2⁻¹²⁶) ≈ −87.337.
    const EXP_NORMAL_LO: f64 = -87.0;
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
    // FreeBSD msun e_logf.c / k_logf.h: Lg1 … Lg4 = 0xaaaaaa.0p-24, 0xccce13.0p-25,
    // 0x91e9ee.0p-25, 0xf89e26.0p-26 (exact in f32), |error of R| < 2⁻³⁴·²⁴.
    const LOG_POLY: &'static [f64] = &[
        0.24279078841209412,
        0.2849878668785095,
        0.40000972151756287,
        0.6666666269302368,
    ];
    // π/2 rounded to 16 significant bits (the last four happen to be zero), the remainder to 16
    // (n · PIO2[0], n · PIO2[1] exact for |n| < 2⁸) and the rest to f32 (computed with mpmath);
    // the three sum to π/2 within 1.3e-18.
    const PIO2: [f64; 3] = [
        1.57080078125,
        -4.454399459064007e-06,
        -5.564431554416771e-11,
    ];
    // Cephes 2.8 sinf.c (S. L. Moshier): sincof, on [−π/4, π/4].
    const SIN_POLY: &'static [f64] = &[-1.9515295891e-4, 8.3321608736e-3, -1.6666654611e-1];
    // Cephes 2.8 sinf.c: coscof, on [−π/4, π/4].
    const COS_POLY: &'static [f64] = &[
        2.443315711809948e-5,
        -1.388731625493765e-3,
        4.166664568298827e-2,
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
    #[inline(always)]
    fn vfrexp<S: Simd>(s: S, x: Self::V<S>) -> (Self::V<S>, Self::V<S>) {
        // As for f64 on the whole word: adding 0x3f800000 − 0x3f3504f3 carries into the
        // exponent field exactly when the mantissa is ≥ that of √2 (0x3504f3) (musl's logf.c).
        let u: S::u32s = pulp::bytemuck::cast(x);
        let u = s.add_u32s(u, s.splat_u32s(0x3f800000 - 0x3f3504f3));
        let m = s.add_u32s(
            s.and_u32s(u, s.splat_u32s(0x007f_ffff)),
            s.splat_u32s(0x3f3504f3),
        );
        // The exponent field (and sign) into the mantissa of 2²³: the float 2²³ + k + 127.
        let e = s.wrapping_dyn_shr_u32s(u, s.splat_u32s(23));
        let e = s.or_u32s(e, s.splat_u32s(8388608.0_f32.to_bits()));
        let k = s.sub_f32s(pulp::bytemuck::cast(e), s.splat_f32s(8388608.0 + 127.0));
        (k, pulp::bytemuck::cast(m))
    }
}
