//! The channel weights and their mix in lanes: `ln K = c − ½ |L⁻¹ h_t|²` for a Gaussian
//! weight (the smooth-surface lobe `ln 2π + ln g^Ξ(h_t) − ½ ln|Ξ|`, and the closed-form blur of a
//! Gaussian PSD `ln 2π + ln ∫ p 𝒩_Ξ(h_t − ·)`), the `Full` level's channel mix
//! (`PreparedPacket::channel_mix`), the projection onto the cone of valid Stokes vectors
//! (`onto_cone`) and the final scale.

use pulp::Simd;

use super::super::prep::{LobePrep, LogGaussian, MAX_COMPONENTS};
use crate::real::Real;
use crate::simd::exp::vexp;

/// `c − ½ |L⁻¹ h|²` at `h = (h0, h1)`: forward substitution with the scalar's operations up to
/// the cancellation (`solve_lower`: `y₀ = h₀/ℓ₀₀` a true division, `h₁ − ℓ₁₀ y₀` with the
/// product and the difference rounded apart), so that the difference is the scalar's bit for
/// bit for the same `h`; then the product with `1/ℓ₁₁` (within 1 ulp of the scalar's quotient:
/// `ε y₁²` in `m`, no cancellation after it).
/// With reciprocals and a fused `h₁ − ℓ₁₀ y₀` (as before) the lanes differed from the scalar by
/// `ε (|ℓ₁₀ y₀| + |h₁ − ℓ₁₀ y₀|)²/ℓ₁₁²`, which the cancellation in `h₁ − ℓ₁₀ y₀` makes far
/// larger than `ε m` for a strongly anisotropic blur (`tests/interaction/batch/lobes.rs` found
/// 3.3e-5 relative in f32 at a correlation covariance of condition ≈ 110).
#[inline(always)]
pub(crate) fn log_gaussian<S: Simd, F: Real>(
    s: S,
    g: &LogGaussian<F>,
    h0: F::V<S>,
    h1: F::V<S>,
) -> F::V<S> {
    log_gaussian_with::<S, F>(s, &log_gaussian_lanes::<S, F>(s, g), h0, h1)
}

/// The constants of a [`LogGaussian`] as vectors (`c`, `ℓ₀₀`, `ℓ₁₀`, `1/ℓ₁₁`): splatted
/// ([`log_gaussian_lanes`]), or one per lane (the per-lane pass, `batch::per_lane`).
#[derive(Clone, Copy)]
pub(crate) struct LogGaussianLanes<V> {
    pub(crate) c: V,
    pub(crate) l00: V,
    pub(crate) l10: V,
    pub(crate) inv_l11: V,
}

/// `g`'s constants on every lane.
#[inline(always)]
pub(crate) fn log_gaussian_lanes<S: Simd, F: Real>(
    s: S,
    g: &LogGaussian<F>,
) -> LogGaussianLanes<F::V<S>> {
    let c = |v: F| F::vsplat(s, v);
    LogGaussianLanes {
        c: c(g.c),
        l00: c(g.l00),
        l10: c(g.l10),
        inv_l11: c(g.inv_l11),
    }
}

/// [`log_gaussian`] of constants given per lane.
#[inline(always)]
pub(crate) fn log_gaussian_with<S: Simd, F: Real>(
    s: S,
    g: &LogGaussianLanes<F::V<S>>,
    h0: F::V<S>,
    h1: F::V<S>,
) -> F::V<S> {
    let y0 = F::vdiv(s, h0, g.l00);
    let y1 = F::vmul(s, F::vsub(s, h1, F::vmul(s, g.l10, y0)), g.inv_l11);
    let m = F::vmul_add(s, y0, y0, F::vmul(s, y1, y1));
    F::vneg_mul_add(s, F::vsplat(s, F::lit(0.5)), m, g.c)
}

/// `ln f` for `1 ≤ f ≤ MAX_COMPONENTS` (8): the series `2 atanh z`, `z = (f − 1)/(f + 1)`, to
/// `z¹¹` (within `8e-3` at `f = 8`), then two Halley steps `y ← y + 2 (f − eʸ)/(f + eʸ)` (cubic:
/// `8e-3 → 1e-7 → 1e-22`, below the rounding of the last step, which leaves `|Δ| ≲ 3 ε`).
#[inline(always)]
pub(crate) fn ln_small<S: Simd, F: Real>(s: S, f: F::V<S>) -> F::V<S> {
    let c = |v: f64| F::vsplat(s, F::lit(v));
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let one = c(1.0);
    let z = F::vdiv(s, sub(s, f, one), add(s, f, one));
    let z2 = mul(s, z, z);
    let mut poly = c(1.0 / 11.0);
    for k in [9.0, 7.0, 5.0, 3.0, 1.0] {
        poly = F::vmul_add(s, poly, z2, c(1.0 / k));
    }
    let mut y = mul(s, add(s, z, z), poly);
    for _ in 0..2 {
        let e = vexp::<S, F>(s, y);
        let d = F::vdiv(s, sub(s, f, e), add(s, f, e));
        y = add(s, y, add(s, d, d));
    }
    y
}

/// `ln Σⱼ Kⱼ` of the Gaussian components `comps` (`ln Kⱼ` by [`log_gaussian`]): one
/// component's logarithm as is, else `m + ln Σⱼ e^{ln Kⱼ − m}` with `m = maxⱼ ln Kⱼ` (the sum
/// lies in `[1, comps.len()]`, [`ln_small`]); `−∞` where every component is.
#[inline(always)]
pub(crate) fn mixture_log<S: Simd, F: Real>(
    s: S,
    comps: &[LogGaussian<F>],
    h0: F::V<S>,
    h1: F::V<S>,
) -> F::V<S> {
    let first = log_gaussian::<S, F>(s, &comps[0], h0, h1);
    if comps.len() == 1 {
        return first;
    }
    let mut logs = [first; MAX_COMPONENTS];
    let mut m = first;
    for (l, g) in logs.iter_mut().zip(comps).skip(1) {
        *l = log_gaussian::<S, F>(s, g, h0, h1);
        m = F::vmax(s, m, *l);
    }
    let mut sum = F::vsplat(s, F::zero());
    for l in &logs[..comps.len()] {
        sum = F::vadd(s, sum, vexp::<S, F>(s, F::vsub(s, *l, m)));
    }
    let out = F::vadd(s, m, ln_small::<S, F>(s, sum));
    let dark = F::vlt(s, m, F::vsplat(s, -F::MAX));
    F::vselect(s, dark, m, out)
}

/// The `Full` level's channel mix of the weights `ln K_x`, `ln K_y`, `ln K_½`: the effective
/// vector `T v̂` and the logarithm `m` of its scale
/// (see `PreparedPacket::channel_mix`; `m = −∞` gives an unspecified vector, which the caller's
/// dark test discards).
#[inline(always)]
pub(crate) fn channel_mix<S: Simd, F: Real>(
    s: S,
    p: &LobePrep<F>,
    lx: F::V<S>,
    ly: F::V<S>,
    lh: F::V<S>,
) -> ([F::V<S>; 4], F::V<S>) {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let half = c(F::lit(0.5));
    let ax = add(s, lx, c(p.ln_sx));
    let ay = add(s, ly, c(p.ln_sy));
    let cap = sub(s, mul(s, add(s, lx, ly), half), c(p.ln_mu_max));
    let ah = F::vmin(
        s,
        add(s, F::vmin(s, lh, cap), c(p.ln_c)),
        mul(s, add(s, ax, ay), half),
    );
    let m = F::vmax(s, ax, ay);
    let rx = vexp::<S, F>(s, sub(s, ax, m));
    let ry = vexp::<S, F>(s, sub(s, ay, m));
    let rh = vexp::<S, F>(s, sub(s, ah, m));
    let two_rh = add(s, rh, rh);
    let v = [
        add(s, rx, ry),
        sub(s, rx, ry),
        mul(s, two_rh, c(p.phase.0)),
        mul(s, two_rh, c(p.phase.1)),
    ];
    (mat_vec::<S, F>(s, &p.t, v), m)
}

/// `[P, Q, S2, S3]` of a Stokes vector, `P, Q = (S0 ± S1)/2` (the input of
/// `stokes::assemble_vector`).
#[inline(always)]
pub(crate) fn halves<S: Simd, F: Real>(s: S, v: [F::V<S>; 4]) -> [F::V<S>; 4] {
    let half = F::vsplat(s, F::lit(0.5));
    [
        F::vmul(s, F::vadd(s, v[0], v[1]), half),
        F::vmul(s, F::vsub(s, v[0], v[1]), half),
        v[2],
        v[3],
    ]
}

/// `M v` for a per-packet 4×4 matrix `M`.
#[inline(always)]
pub(crate) fn mat_vec<S: Simd, F: Real>(
    s: S,
    m: &nalgebra::Matrix4<F>,
    v: [F::V<S>; 4],
) -> [F::V<S>; 4] {
    let c = |i: usize| core::array::from_fn(|j| F::vsplat(s, m[(i, j)]));
    let row = |i: usize| row::<S, F>(s, c(i), v);
    [row(0), row(1), row(2), row(3)]
}

/// `M v` for a 4×4 matrix given per lane (`m[i][j]` the lanes of `M_ij`).
#[inline(always)]
pub(crate) fn mat_vec_with<S: Simd, F: Real>(
    s: S,
    m: &[[F::V<S>; 4]; 4],
    v: [F::V<S>; 4],
) -> [F::V<S>; 4] {
    [
        row::<S, F>(s, m[0], v),
        row::<S, F>(s, m[1], v),
        row::<S, F>(s, m[2], v),
        row::<S, F>(s, m[3], v),
    ]
}

/// One row `m` of `M v`.
#[inline(always)]
fn row<S: Simd, F: Real>(s: S, m: [F::V<S>; 4], v: [F::V<S>; 4]) -> F::V<S> {
    F::vmul_add(
        s,
        m[0],
        v[0],
        F::vmul_add(
            s,
            m[1],
            v[1],
            F::vmul_add(s, m[2], v[2], F::vmul(s, m[3], v[3])),
        ),
    )
}

/// `u` onto the cone of valid Stokes vectors, as the scalar `onto_cone` but without its
/// divisions where the squares allow: the polarized part `u_p` scaled by `u₀/√|u_p|²` where
/// `|u_p|² > u₀²` (one quotient and one root, computed only for a vector with such a lane), 0
/// where `u₀ ≤ 0`. A positive lane whose `u₀²` is not a normal number or whose `|u_p|²` is not
/// finite takes the scalar's operations ([`onto_cone_exact`]); the other lanes of its vector
/// keep theirs, so that no lane's result depends on its neighbours.
///
/// Against the scalar (which tests `Σ(u_k/u₀)² > 1` and multiplies by `1/√Σ(u_k/u₀)²`): `u₀`
/// and the zero vector bit for bit; each `u_k` within `6 ε |u_k|` (where both scale, within
/// `2.25 ε` of the exact projection against the scalar's `3.25 ε`; where the two tests, each a
/// few ε from the exact one, decide differently, `|u_p|/u₀` is within a few ε of 1 and so is
/// the factor); the result in the cone, `|u_p|² ≤ u₀² (1 + 4.5 ε)`
/// (`lobe_tests::onto_cone_matches_the_scalar_projection*`). This took 5 divisions and a
/// square root per lane (bit for bit the scalar's); now none in the common case.
#[inline(always)]
pub(crate) fn onto_cone<S: Simd, F: Real>(s: S, u: [F::V<S>; 4]) -> [F::V<S>; 4] {
    let c = |x: F| F::vsplat(s, x);
    let (zero, one) = (c(F::zero()), c(F::one()));
    let and = F::vand::<S>;
    let pos = F::vlt(s, zero, u[0]);
    let u02 = F::vmul(s, u[0], u[0]);
    let pol2 = F::vmul_add(
        s,
        u[1],
        u[1],
        F::vmul_add(s, u[2], u[2], F::vmul(s, u[3], u[3])),
    );
    // Squares normal and finite (NaN fails): the comparison below is relative.
    let safe = and(
        s,
        and(
            s,
            F::vle(s, c(F::MIN_POSITIVE), u02),
            F::vle(s, u02, c(F::MAX)),
        ),
        F::vle(s, pol2, c(F::MAX)),
    );
    let over = and(s, pos, F::vlt(s, u02, pol2));
    let f = if F::vany(s, over) {
        F::vselect(s, over, F::vdiv(s, u[0], F::vsqrt(s, pol2)), one)
    } else {
        one
    };
    let fast = [
        F::vselect(s, pos, u[0], zero),
        F::vselect(s, pos, F::vmul(s, u[1], f), zero),
        F::vselect(s, pos, F::vmul(s, u[2], f), zero),
        F::vselect(s, pos, F::vmul(s, u[3], f), zero),
    ];
    let exact = and(s, pos, F::vnot(s, safe));
    if F::vany(s, exact) {
        // Only the lanes that need them take the scalar's operations: every lane's result is
        // its own, whatever its neighbours (a batch of any length gives the same entries).
        // (Explicit selects: a closure around SIMD calls is not inlined into the
        // target-feature code.)
        let e = onto_cone_exact::<S, F>(s, u);
        return [
            F::vselect(s, exact, e[0], fast[0]),
            F::vselect(s, exact, e[1], fast[1]),
            F::vselect(s, exact, e[2], fast[2]),
            F::vselect(s, exact, e[3], fast[3]),
        ];
    }
    fast
}

/// [`onto_cone`] with the scalar `onto_cone`'s operations, so its result bit for bit, at every
/// magnitude: with `a_k = u_k/u₀` (times the reciprocal `1/u₀`, or divided where that
/// overflows), the polarized part scaled by `1/√Σa_k²` where `Σa_k² > 1`, 0 where `u₀ ≤ 0`.
#[inline(always)]
fn onto_cone_exact<S: Simd, F: Real>(s: S, u: [F::V<S>; 4]) -> [F::V<S>; 4] {
    let c = |x: F| F::vsplat(s, x);
    let (zero, one) = (c(F::zero()), c(F::one()));
    let inv = F::vdiv(s, one, u[0]);
    let finite = F::vle(s, inv, c(F::MAX));
    let ratio = |x: F::V<S>| F::vselect(s, finite, F::vmul(s, x, inv), F::vdiv(s, x, u[0]));
    let (a, b, d) = (ratio(u[1]), ratio(u[2]), ratio(u[3]));
    let r2 = F::vadd(
        s,
        F::vadd(s, F::vmul(s, a, a), F::vmul(s, b, b)),
        F::vmul(s, d, d),
    );
    let over = F::vlt(s, one, r2);
    let f = F::vselect(s, over, F::vdiv(s, one, F::vsqrt(s, r2)), one);
    let pos = F::vlt(s, zero, u[0]);
    [
        F::vselect(s, pos, u[0], zero),
        F::vselect(s, pos, F::vmul(s, u[1], f), zero),
        F::vselect(s, pos, F::vmul(s, u[2], f), zero),
        F::vselect(s, pos, F::vmul(s, u[3], f), zero),
    ]
}

/// A 4×4 matrix in lanes, by columns (`[j][i]` the lanes of `M_ij`).
pub(crate) type MatrixLanes<S, F> = [[<F as crate::simd::Lanes>::V<S>; 4]; 4];

/// `m · e^{ln_e}` for the columns of a Mueller matrix (`m[j]` column `j`, `m[0][0] = M₀₀` its
/// largest entry), under the scalar BSDF form's rules (`prepared::throughput_scaled`, whose
/// `flush_to_normal` is the rule for small entries of every throughput): 0 where the part is
/// dark (`ln_e` below the smallest subnormal number, or NaN) or `e^{ln_e}` below the smallest
/// normal number; then, by `M₀₀ e`, 0 below the smallest normal number, the entries below it
/// set to 0 from `MIN_POSITIVE/ε` on, unchanged in between (the largest entry taken as `M₀₀`:
/// the rules agree up to the rounding of the band's edges, within `MIN_POSITIVE`). The mask
/// is of the lanes the scalar kernel must redo: lit with `e^{ln_e}` beyond the largest
/// number (where the scalar kernel folds each entry into the exponent).
#[inline(always)]
pub(crate) fn scaled_matrix<S: Simd, F: Real>(
    s: S,
    p: &LobePrep<F>,
    m: MatrixLanes<S, F>,
    ln_e: F::V<S>,
) -> (MatrixLanes<S, F>, F::M<S>) {
    let c = |x: F| F::vsplat(s, x);
    let tiny = c(F::MIN_POSITIVE);
    let e = vexp::<S, F>(s, ln_e);
    let lit = F::vand(s, F::vle(s, c(p.ln_dark), ln_e), F::vle(s, tiny, e));
    let redo = F::vand(s, lit, F::vlt(s, c(F::MAX), e));
    let m00 = F::vmul(s, m[0][0], e);
    let lit = F::vand(s, lit, F::vle(s, tiny, m00));
    let flush = F::vle(s, c(F::MIN_POSITIVE / F::EPSILON), m00);
    let col = scaled_column::<S, F>;
    let k = (e, lit, flush);
    (
        [
            col(s, m[0], k),
            col(s, m[1], k),
            col(s, m[2], k),
            col(s, m[3], k),
        ],
        redo,
    )
}

/// One column of [`scaled_matrix`]: each entry `x e`, 0 where the part is not `lit` or, under
/// `flush`, where `|x e|` is below the smallest normal number.
#[inline(always)]
fn scaled_column<S: Simd, F: Real>(
    s: S,
    v: [F::V<S>; 4],
    (e, lit, flush): (F::V<S>, F::M<S>, F::M<S>),
) -> [F::V<S>; 4] {
    let k = (e, lit, flush);
    [
        scaled_entry::<S, F>(s, v[0], k),
        scaled_entry::<S, F>(s, v[1], k),
        scaled_entry::<S, F>(s, v[2], k),
        scaled_entry::<S, F>(s, v[3], k),
    ]
}

/// One entry of [`scaled_column`].
#[inline(always)]
fn scaled_entry<S: Simd, F: Real>(
    s: S,
    x: F::V<S>,
    (e, lit, flush): (F::V<S>, F::M<S>, F::M<S>),
) -> F::V<S> {
    let y = F::vmul(s, x, e);
    let small = F::vlt(s, F::vabs(s, y), F::vsplat(s, F::MIN_POSITIVE));
    let kept = F::vand(s, lit, F::vnot(s, F::vand(s, flush, small)));
    F::vselect(s, kept, y, F::vsplat(s, F::zero()))
}

/// `u · e^{ln_e}` with the lanes where the part is dark (`ln_e` below the smallest subnormal
/// number, or NaN) or negligible (its `S0` below half the smallest normal number) set to 0, and
/// the mask of the lanes the scalar kernel must redo: lit, not negligible, and `e^{ln_e}`
/// outside the normal range (where the scalar kernel folds `|u|` into the exponent instead),
/// or a positive `S0` of the result below the smallest normal number.
///
/// A negligible part written as 0 is within the absolute term (`MIN_POSITIVE`) of the lanes'
/// documented bound: the per-direction kernel's value is a valid Stokes vector of `S0` below
/// `MIN_POSITIVE/2 · (1 + O(ε))`. Where `e^{ln_e}` is subnormal its `S0` is tested as
/// `u₀ e^{ln_e + 64 ln 2} < 2⁶³ MIN_POSITIVE` (the scaled exponential normal for every lit
/// `ln_e`, so the test is relative, not on subnormal rounding). Without it, the lit lanes whose
/// `S0` is subnormal — a shell of exits around each lobe, wider in `f32` — went to the scalar
/// kernel one at a time.
#[inline(always)]
pub(crate) fn scaled<S: Simd, F: Real>(
    s: S,
    p: &LobePrep<F>,
    u: [F::V<S>; 4],
    ln_e: F::V<S>,
) -> ([F::V<S>; 4], F::M<S>) {
    let c = |x: F| F::vsplat(s, x);
    let zero = c(F::zero());
    let half_normal = F::MIN_POSITIVE * F::lit(0.5);
    let lit = F::vle(s, c(p.ln_dark), ln_e);
    let e = vexp::<S, F>(s, ln_e);
    let normal = F::vand(s, F::vle(s, c(F::MIN_POSITIVE), e), F::vle(s, e, c(F::MAX)));
    let s0 = F::vmul(s, u[0], e);
    // Negligible: S0 < MIN_POSITIVE/2, from the scaled exponential where e is subnormal.
    let small = F::vlt(s, e, c(F::MIN_POSITIVE));
    let negligible = if F::vany(s, F::vand(s, lit, small)) {
        let two64 = F::lit(18446744073709551616.0);
        let es = vexp::<S, F>(
            s,
            F::vadd(s, ln_e, c(F::lit(64.0 * core::f64::consts::LN_2))),
        );
        let scaled_s0 = F::vmul(s, u[0], es);
        let (a, b) = (
            F::vand(s, small, F::vlt(s, scaled_s0, c(half_normal * two64))),
            F::vand(s, F::vnot(s, small), F::vlt(s, s0, c(half_normal))),
        );
        F::vor(s, a, b)
    } else {
        F::vlt(s, s0, c(half_normal))
    };
    let lit = F::vand(s, lit, F::vnot(s, negligible));
    // A positive S0 below the smallest normal number: the scalar kernel moves the subnormal
    // vector back into the cone (`prepared::subnormal_onto_cone`).
    let tiny = F::vand(s, F::vlt(s, zero, s0), F::vlt(s, s0, c(F::MIN_POSITIVE)));
    let redo = F::vand(s, lit, F::vnot(s, F::vand(s, normal, F::vnot(s, tiny))));
    (
        [
            F::vselect(s, lit, F::vmul(s, u[0], e), zero),
            F::vselect(s, lit, F::vmul(s, u[1], e), zero),
            F::vselect(s, lit, F::vmul(s, u[2], e), zero),
            F::vselect(s, lit, F::vmul(s, u[3], e), zero),
        ],
        redo,
    )
}
