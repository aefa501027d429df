//! Each pair's own constants, built in lanes: those of its direction to the source (the
//! incidence — ŝ, `cos θ_i`, the incident s/p frame's ŝ and the azimuth axes —, the
//! Rayleigh–Rice factors' incident terms, the scattered part's constant exponent, the Fresnel
//! reflection matrix and the specular frame) and those of its coherence width (the `½`
//! channel's specular and scattered weights of the section `I/w²`) — the fields of
//! `prep::lane_row` that `LobePrep::lane_row_of` builds one pair at a time, with the same
//! operations in the same order (nalgebra's and `num_complex`'s, unfused), so the same values
//! bit for bit.
//!
//! The three logarithms per pair (`ln (2k cos θ_i)²`, `ln|Ξ|` and `ln|Λ⁻¹ + Ξ|` through the
//! products of their Cholesky factors' diagonals) call the library `ln` lane by lane, so that
//! they too are the scalar ones exactly.
//!
//! A lane is flagged where the lanes would not reproduce the scalar code: an incidence or a
//! specular direction within `√ε` of the normal (`Frame::sp_unit` falls back to a tangent of
//! n̂ there), a Fresnel square root off the plain `hypot` branch, a Fresnel denominator of
//! zero, a product of Cholesky diagonals outside `[1e-30, 1e30]` (the sum-of-logarithms
//! branch), the Cauchy–Binet branch of the Cholesky factor of `Λ⁻¹ + Ξ`, a constant that is
//! not finite. The caller then builds that vector's constants one
//! pair at a time.

use num_complex::Complex;
use pulp::Simd;

use super::super::partial::{RowMaker, load};
use super::super::per_lane::{Gathered, MAX_LANES};
use super::super::prep::{LobePrep, incoherent_shift};
use super::super::stages::azimuth::exit_frame_with;
use super::super::stages::channels::LogGaussianLanes;
use super::super::stages::fresnel::exit_q;
use super::super::stages::rayleigh_rice::IncidentTerms;
use super::super::stages::specular::SpecularLanes;
use super::super::stages::{div3, dot3, splat3};
use crate::numerics::HYPOT_PLAIN;
use crate::real::Real;
use crate::simd::complex::{C, Cx};

/// What every pair of a call shares: the constants of one pair's `LobePrep` (the head: the
/// normal, the permittivity and its scale, `ln_spec`, the tolerances) and the Fresnel index.
pub(super) struct Shared<'a, F: Real> {
    pub(super) head: &'a LobePrep<F>,
    /// `η²` of the Fresnel index (`fresnel::coefficients`' `eta * eta`).
    pub(super) eta2: Complex<F>,
    /// The PSD's spectral covariance `Λ⁻¹` (`[0][0]`, `[1][0]`, `[1][1]`), `ln|Λ⁻¹|` and
    /// `ln(σ²|Λ|^{1/2})`.
    spectral: [F; 3],
    spectral_log_det: F,
    log_amplitude: F,
    /// `ln ∫p − ln 2π` at the incoherent level (`LobePrep::incoherent`).
    incoherent_shift: Option<F>,
}

impl<'a, F: Real> Shared<'a, F> {
    pub(super) fn new(head: &'a LobePrep<F>, maker: &RowMaker<'_, F>) -> Self {
        let shape = maker.psd.spectral_shape();
        let a = shape.covariance();
        Self {
            head,
            eta2: maker.indices.0 * maker.indices.0,
            spectral: [a[(0, 0)], a[(1, 0)], a[(1, 1)]],
            spectral_log_det: shape.log_det(),
            log_amplitude: maker.psd.log_amplitude(),
            incoherent_shift: maker.incoherent.map(incoherent_shift),
        }
    }
}

/// `ln x` lane by lane with the library logarithm (the scalar code's, exactly).
#[inline(always)]
fn ln_lanes<S: Simd, F: Real>(s: S, x: F::V<S>) -> F::V<S> {
    let lanes = F::width::<S>();
    let mut buf = [F::zero(); MAX_LANES];
    F::store_partial(s, &mut buf[..lanes], x);
    for v in &mut buf[..lanes] {
        *v = v.ln();
    }
    F::load_partial(s, &buf[..lanes])
}

/// `x` in `[1e-30, 1e30]` (`numerics::cholesky::in_normal_range`).
#[inline(always)]
fn normal_range<S: Simd, F: Real>(s: S, x: F::V<S>) -> F::M<S> {
    F::vand(
        s,
        F::vle(s, F::vsplat(s, F::lit(1e-30)), x),
        F::vle(s, x, F::vsplat(s, F::lit(1e30))),
    )
}

/// The `½` channel's constants (`LobePrep::channels_of`) of the sections `I/w²`, `iw = 1/w`
/// per lane, with the operations of `Gaussian::from_cholesky`, `spec_channel`,
/// `cholesky_of_sum`'s plain branch and `GaussianPsd::log_normalized_blur` at `h = 0`; and the
/// lanes flagged where those take another branch (a product of factors outside
/// `[1e-30, 1e30]`, the Cauchy–Binet branch of the sum) or a constant is not finite.
#[inline(always)]
fn channel_lanes<S: Simd, F: Real>(
    s: S,
    shared: &Shared<'_, F>,
    iw: F::V<S>,
) -> (ChannelLanes<F::V<S>>, F::M<S>) {
    let k = |v: F| F::vsplat(s, v);
    let (add, sub, mul, div) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>, F::vdiv::<S>);
    let (zero, one, half, two) = (k(F::zero()), k(F::one()), k(F::lit(0.5)), k(F::lit(2.0)));
    let ln2pi = k(crate::interaction::coherence::ln_two_pi::<F>());
    // Ξ = L Lᵀ with L = diag(1/w, 1/w); ln|Ξ| = 2 ln((1 · ℓ₀₀) ℓ₁₁).
    let iw2 = add(s, mul(s, iw, iw), mul(s, zero, zero));
    let prod = mul(s, mul(s, one, iw), iw);
    let spec = LogGaussianLanes {
        c: sub(
            s,
            ln2pi,
            mul(s, half, mul(s, two, ln_lanes::<S, F>(s, prod))),
        ),
        l00: iw,
        l10: zero,
        inv_l11: div(s, one, iw),
    };
    // The Cholesky factor of Λ⁻¹ + Ξ (Ξ's off-diagonal `+0`).
    let [a00, a10, a11] = shared.spectral;
    let s00 = add(s, k(a00), iw2);
    let s10 = add(s, k(a10), zero);
    let s11 = add(s, k(a11), iw2);
    let l00 = F::vsqrt(s, s00);
    let l10 = div(s, s10, l00);
    let d = sub(s, s11, mul(s, l10, l10));
    let plain = F::vand(
        s,
        F::vand(
            s,
            F::vlt(s, zero, s00),
            F::vle(s, s11, mul(s, d, k(F::lit(16.0)))),
        ),
        F::vand(s, finite::<S, F>(s, d), finite::<S, F>(s, l10)),
    );
    let l11 = F::vsqrt(s, d);
    let prod_sum = mul(s, mul(s, one, l00), l11);
    // `ln K = ln 2π + ln(σ²|Λ|^{1/2}) + ½ (ln|Λ⁻¹| − ln|Λ⁻¹ + Ξ| − |L⁻¹ 0|²)`.
    let lds = mul(s, two, ln_lanes::<S, F>(s, prod_sum));
    let m = zero;
    let blur = add(
        s,
        k(shared.log_amplitude),
        mul(s, half, sub(s, sub(s, k(shared.spectral_log_det), lds), m)),
    );
    let mut scat = LogGaussianLanes {
        c: add(s, ln2pi, blur),
        l00,
        l10,
        inv_l11: div(s, one, l11),
    };
    if let Some(shift) = shared.incoherent_shift {
        scat = LogGaussianLanes {
            c: add(s, spec.c, k(shift)),
            ..spec
        };
    }
    let mut ok = F::vand(
        s,
        plain,
        F::vand(
            s,
            normal_range::<S, F>(s, prod),
            normal_range::<S, F>(s, prod_sum),
        ),
    );
    let inv_l00 = div(s, one, l00);
    for v in [
        spec.c,
        iw,
        spec.inv_l11,
        scat.c,
        l00,
        l10,
        l11,
        inv_l00,
        scat.inv_l11,
    ] {
        ok = F::vand(s, ok, finite::<S, F>(s, v));
    }
    ((spec, scat), F::vnot(s, ok))
}

/// The `½` channel's specular and scattered constants in lanes.
type ChannelLanes<V> = (LogGaussianLanes<V>, LogGaussianLanes<V>);

/// `r_s`, `r_p` in lanes and the lanes where they are not the scalar ones ([`fresnel_r`]).
struct Reflection<V, M> {
    rs: C<V>,
    rp: C<V>,
    bad: M,
}

/// `-x` exactly, the sign of a zero included (`−0 − x`).
#[inline(always)]
fn neg<S: Simd, F: Real>(s: S, x: F::V<S>) -> F::V<S> {
    F::vsub(s, F::vsplat(s, -F::zero()), x)
}

/// `a × b` (nalgebra's order).
#[inline(always)]
fn cross<S: Simd, F: Real>(s: S, a: [F::V<S>; 3], b: [F::V<S>; 3]) -> [F::V<S>; 3] {
    let (sub, mul) = (F::vsub::<S>, F::vmul::<S>);
    [
        sub(s, mul(s, a[1], b[2]), mul(s, a[2], b[1])),
        sub(s, mul(s, a[2], b[0]), mul(s, a[0], b[2])),
        sub(s, mul(s, a[0], b[1]), mul(s, a[1], b[0])),
    ]
}

/// `|x| ≤ MAX` (false for ±∞ and NaN).
#[inline(always)]
fn finite<S: Simd, F: Real>(s: S, x: F::V<S>) -> F::M<S> {
    F::vle(s, F::vabs(s, x), F::vsplat(s, F::MAX))
}

/// `a + b`, `a − b` and `a / b` of complex lanes, as `num_complex`.
#[inline(always)]
fn cadd<S: Simd, F: Real>(s: S, a: C<F::V<S>>, b: C<F::V<S>>) -> C<F::V<S>> {
    C {
        re: F::vadd(s, a.re, b.re),
        im: F::vadd(s, a.im, b.im),
    }
}

#[inline(always)]
fn csub<S: Simd, F: Real>(s: S, a: C<F::V<S>>, b: C<F::V<S>>) -> C<F::V<S>> {
    C {
        re: F::vsub(s, a.re, b.re),
        im: F::vsub(s, a.im, b.im),
    }
}

#[inline(always)]
fn cdiv<S: Simd, F: Real>(s: S, a: C<F::V<S>>, b: C<F::V<S>>) -> C<F::V<S>> {
    let (add, sub, mul, div) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>, F::vdiv::<S>);
    let n2 = add(s, mul(s, b.re, b.re), mul(s, b.im, b.im));
    let re = add(s, mul(s, a.re, b.re), mul(s, a.im, b.im));
    let im = sub(s, mul(s, a.im, b.re), mul(s, a.re, b.im));
    C {
        re: div(s, re, n2),
        im: div(s, im, n2),
    }
}

/// `|a|²` as `num_complex::norm_sqr`.
#[inline(always)]
fn norm_sqr<S: Simd, F: Real>(s: S, a: C<F::V<S>>) -> F::V<S> {
    F::vadd(s, F::vmul(s, a.re, a.re), F::vmul(s, a.im, a.im))
}

/// `a == 0` (both parts).
#[inline(always)]
fn is_zero<S: Simd, F: Real>(s: S, a: C<F::V<S>>) -> F::M<S> {
    let zero = F::vsplat(s, F::zero());
    F::vand(s, F::veq(s, a.re, zero), F::veq(s, a.im, zero))
}

#[inline(always)]
fn conj<S: Simd, F: Real>(s: S, a: C<F::V<S>>) -> C<F::V<S>> {
    C {
        re: a.re,
        im: neg::<S, F>(s, a.im),
    }
}

/// `(r_s, r_p)` of `fresnel::coefficients(c, η)` for `c = cos θ_i` in `(0, 1]`, and the lanes
/// where the lanes do not reproduce it (the square root off the plain `hypot` branch, or a
/// denominator of zero).
#[inline(always)]
fn fresnel_r<S: Simd, F: Real>(s: S, eta2: Complex<F>, c: F::V<S>) -> Reflection<F::V<S>, F::M<S>> {
    let k = |v: F| F::vsplat(s, v);
    let (add, sub, mul, div) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>, F::vdiv::<S>);
    let (zero, half) = (F::zero(), F::lit(0.5));
    let c = F::vmin(s, F::vmax(s, c, k(zero)), k(F::one()));
    // q = principal_sqrt((η²_re − 1) + c², η²_im) on hypot's plain branch.
    let a = add(s, k(eta2.re - F::one()), mul(s, c, c));
    let b = eta2.im;
    let m = F::vmax(s, F::vabs(s, a), k(b.abs()));
    let plain = F::vand(
        s,
        F::vle(s, k(F::lit(HYPOT_PLAIN.0)), m),
        F::vle(s, m, k(F::lit(HYPOT_PLAIN.1))),
    );
    let r = F::vsqrt(s, add(s, mul(s, a, a), k(b * b)));
    let pos = F::vle(s, k(zero), a);
    let big = F::vsqrt(
        s,
        mul(s, F::vselect(s, pos, add(s, r, a), sub(s, r, a)), k(half)),
    );
    let bh = k(b * half);
    let signed = if b < zero { neg::<S, F>(s, big) } else { big };
    let small_pos = F::vselect(s, F::vlt(s, k(zero), big), div(s, bh, big), k(zero));
    let q = C {
        re: F::vselect(s, pos, big, div(s, bh, signed)),
        im: F::vselect(s, pos, small_pos, signed),
    };
    let cc = C { re: c, im: k(zero) };
    let e2c = C {
        re: mul(s, k(eta2.re), c),
        im: mul(s, k(eta2.im), c),
    };
    let ds = cadd::<S, F>(s, cc, q);
    let dp = cadd::<S, F>(s, e2c, q);
    let bad = F::vor(
        s,
        F::vnot(s, plain),
        F::vor(s, is_zero::<S, F>(s, ds), is_zero::<S, F>(s, dp)),
    );
    let rs = cdiv::<S, F>(s, csub::<S, F>(s, cc, q), ds);
    let rp = cdiv::<S, F>(s, csub::<S, F>(s, e2c, q), dp);
    Reflection { rs, rp, bad }
}

/// `Mueller::from_jones` of `diag(a, d)` (the off-diagonal entries zero), with its operations.
#[inline(always)]
fn diagonal_mueller<S: Simd, F: Real>(s: S, a: C<F::V<S>>, d: C<F::V<S>>) -> [[F::V<S>; 4]; 4] {
    let cx = Cx(s);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let z = F::vsplat(s, F::zero());
    let (b, c) = (C { re: z, im: z }, C { re: z, im: z });
    let (aa, bb, cc, dd) = (
        norm_sqr::<S, F>(s, a),
        norm_sqr::<S, F>(s, b),
        norm_sqr::<S, F>(s, c),
        norm_sqr::<S, F>(s, d),
    );
    let ac = cx.mul::<F>(a, conj::<S, F>(s, c));
    let bd = cx.mul::<F>(b, conj::<S, F>(s, d));
    let ab = cx.mul::<F>(a, conj::<S, F>(s, b));
    let cd = cx.mul::<F>(c, conj::<S, F>(s, d));
    let bc = cx.mul::<F>(b, conj::<S, F>(s, c));
    let ad = cx.mul::<F>(a, conj::<S, F>(s, d));
    let h11 = [
        add(s, aa, bb),
        sub(s, aa, bb),
        add(s, ab.re, ab.re),
        add(s, ab.im, ab.im),
    ];
    let h22 = [
        add(s, cc, dd),
        sub(s, cc, dd),
        add(s, cd.re, cd.re),
        add(s, cd.im, cd.im),
    ];
    let h12_3 = C {
        re: neg::<S, F>(s, sub(s, bc.im, ad.im)),
        im: sub(s, bc.re, ad.re),
    };
    let h12 = [
        cadd::<S, F>(s, ac, bd),
        csub::<S, F>(s, ac, bd),
        cadd::<S, F>(s, bc, ad),
        h12_3,
    ];
    let half = F::vsplat(s, F::lit(0.5));
    let mut out = [[z; 4]; 4];
    for l in 0..4 {
        out[0][l] = mul(s, half, add(s, h11[l], h22[l]));
        out[1][l] = mul(s, half, sub(s, h11[l], h22[l]));
        out[2][l] = h12[l].re;
        out[3][l] = neg::<S, F>(s, h12[l].im);
    }
    out
}

/// The lane constants of the pairs arriving from `to_source` (any length, validated: finite,
/// non-zero, above the surface) with the inverse widths `iw` (validated: positive, finite),
/// and the lanes flagged (module docs). Lanes not flagged hold exactly what
/// `LobePrep::lane_row_of` gives for their pair.
#[inline(always)]
pub(super) fn lanes<S: Simd, F: Real>(
    s: S,
    shared: &Shared<'_, F>,
    to_source: [F::V<S>; 3],
    iw: F::V<S>,
) -> (Gathered<S, F>, F::M<S>) {
    let ((spec, scat), channels_flagged) = channel_lanes::<S, F>(s, shared, iw);
    let p = &shared.head.inc;
    let k = |v: F| F::vsplat(s, v);
    let (add, mul) = (F::vadd::<S>, F::vmul::<S>);
    let cx = Cx(s);
    // ŝ: `unit_by_largest` (the largest magnitude, then the norm).
    let [x, y, z] = to_source;
    let m = F::vmax(
        s,
        F::vmax(s, F::vmax(s, k(F::zero()), F::vabs(s, x)), F::vabs(s, y)),
        F::vabs(s, z),
    );
    let u = div3::<S, F>(s, to_source, m);
    let unit = div3::<S, F>(s, u, F::vsqrt(s, dot3::<S, F>(s, u, u)));
    let n = splat3::<S, F>(s, p.n);
    let cos_i = dot3::<S, F>(s, unit, n);
    // The incident s/p frame's ŝ (`Frame::sp_unit(−ŝ, n̂)`) and the azimuth axes.
    let axes = (n, n);
    let minus = [
        neg::<S, F>(s, unit[0]),
        neg::<S, F>(s, unit[1]),
        neg::<S, F>(s, unit[2]),
    ];
    let incident = exit_frame_with::<S, F>(s, p, axes, minus);
    let u_az = cross::<S, F>(s, n, incident.s_out);
    let v_az = cross::<S, F>(s, n, u_az);
    // The Rayleigh–Rice incident terms (`Incidence::from_direction`).
    let (si2, qi) = exit_q::<S, F>(s, p, cos_i);
    let (inv, inv2) = (k(p.scale.inv), k(p.scale.inv2));
    let d1s = C {
        re: mul(s, add(s, qi.re, cos_i), inv),
        im: mul(s, qi.im, inv),
    };
    let d3s = C {
        re: mul(s, add(s, mul(s, k(p.e.re), cos_i), qi.re), inv2),
        im: mul(s, add(s, mul(s, k(p.e.im), cos_i), qi.im), inv2),
    };
    let neg_em1s_qis = cx.mul::<F>(cx.splat::<F>(p.neg_em1s), cx.scale::<F>(qi, inv));
    // `ln_spec + ln (2k cos θ_i)²`, the logarithm lane by lane.
    let js = mul(s, k(F::lit(2.0) * p.k), cos_i);
    let ln_scat = add(
        s,
        k(shared.head.ln_spec),
        ln_lanes::<S, F>(s, mul(s, js, js)),
    );
    // The Fresnel reflection matrix and the specular frame (`specular_frame`).
    let r = fresnel_r::<S, F>(s, shared.eta2, cos_i);
    let (fresnel, fresnel_bad) = (diagonal_mueller::<S, F>(s, r.rs, r.rp), r.bad);
    let two_cos = add(s, cos_i, cos_i);
    let r_spec = [
        F::vsub(s, mul(s, n[0], two_cos), unit[0]),
        F::vsub(s, mul(s, n[1], two_cos), unit[1]),
        F::vsub(s, mul(s, n[2], two_cos), unit[2]),
    ];
    let spec_frame = exit_frame_with::<S, F>(s, p, axes, r_spec);
    let spec_p = cross::<S, F>(s, r_spec, spec_frame.s_out);
    let mut bad = F::vor(
        s,
        F::vor(s, incident.normal, spec_frame.normal),
        F::vor(s, fresnel_bad, F::vle(s, cos_i, k(F::zero()))),
    );
    bad = F::vor(s, bad, F::vnot(s, finite::<S, F>(s, ln_scat)));
    bad = F::vor(s, bad, channels_flagged);
    for row in &fresnel {
        for &v in row {
            bad = F::vor(s, bad, F::vnot(s, finite::<S, F>(s, v)));
        }
    }
    let g = Gathered {
        to_source: unit,
        u_az,
        v_az,
        cos_i,
        terms: IncidentTerms {
            si2,
            qi,
            d1s,
            d3s,
            neg_em1s_qis,
        },
        spec,
        scat,
        ln_scat,
        specular: SpecularLanes {
            fresnel,
            axes: [spec_frame.s_out, spec_p, r_spec],
        },
        flip_tol: shared.head.flip_tol,
    };
    (g, bad)
}

/// The vector of pairs `start..start + count` (a short batch padded with pair 0, as
/// `partial::load`) of the directions `to_source` and inverse widths `inverse_width` in lanes
/// ([`lanes`]); `None` where a lane is flagged. `buf` is scratch.
#[inline(always)]
pub(super) fn gather<S: Simd, F: Real>(
    s: S,
    shared: &Shared<'_, F>,
    (to_source, inverse_width): ([&[F]; 3], &[F]),
    (start, count): (usize, usize),
    buf: &mut [[F; MAX_LANES]; 4],
) -> Option<Gathered<S, F>> {
    let [bx, by, bz, bw] = buf;
    let dir = [
        load::<S, F>(to_source[0], bx, start, count),
        load::<S, F>(to_source[1], by, start, count),
        load::<S, F>(to_source[2], bz, start, count),
    ];
    let iw = load::<S, F>(inverse_width, bw, start, count);
    let (g, flagged) = lanes::<S, F>(s, shared, dir, iw);
    (!F::vany(s, flagged)).then_some(g)
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix2, Vector3};
    use num_complex::Complex;
    use pulp::Simd;

    use super::super::super::partial::{RowMaker, lane_prep_at, row_maker};
    use super::super::super::prep::{LANE_FIELDS, LobePrep};
    use super::super::super::stages::fixture::{PerWidth, chunks, every_width, load};
    use super::{Shared, lanes};
    use crate::frame::Frame;
    use crate::gaussian::Gaussian;
    use crate::interaction::coherence::{CoherenceModel, CoherenceWeights};
    use crate::interaction::polarization::PolarizationModel;
    use crate::interaction::roughness::{RoughnessModel, RoughnessWeights};
    use crate::interaction::{
        Full, Incoherent, Intensity, Kernel, Partial, RoughConductor, RoughDielectric, Surface,
    };
    use crate::numerics::{same, splitmix64};
    use crate::psd::GaussianPsd;
    use crate::real::Real;

    /// One case: the shared constants' sources, and per direction its world vector, its tilt
    /// from the normal, its `1/w` and `LobePrep::lane_row_of`'s row.
    struct Case<'a, F: Real> {
        what: String,
        head: LobePrep<F>,
        maker: RowMaker<'a, F>,
        dirs: Vec<Vector3<F>>,
        tilt: Vec<f64>,
        inv_w: Vec<F>,
        want: Vec<Option<[F; LANE_FIELDS]>>,
    }

    fn uniform(st: &mut u64) -> f64 {
        (splitmix64(st) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Directions above `surface` (local polar angle, azimuth, length): random ones, and the
    /// bands of `Frame::sp_unit` (the normal, within `√ε`, the re-orthogonalised band below
    /// `|c| = 1/8`), grazing ones, and lengths from `1e-20` to `1e20`.
    fn directions(seed: u64) -> Vec<(f64, f64, f64)> {
        let mut st = seed;
        let mut out = vec![];
        for _ in 0..150 {
            let theta = 89.9f64.to_radians() * uniform(&mut st).sqrt();
            out.push((
                theta,
                std::f64::consts::TAU * uniform(&mut st),
                0.2 + 3.0 * uniform(&mut st),
            ));
        }
        let tilts = [
            0.0, 1e-12, 1e-9, 1e-7, 1e-5, 3e-4, 1e-3, 0.05, 0.12, 0.1253, 0.1254, 0.126, 0.2, 1.0,
            1.5, 1.5706,
        ];
        for (i, t) in tilts.into_iter().enumerate() {
            for len in [1e-20, 1.0, 1e20] {
                out.push((t, 0.37 + i as f64, len));
            }
        }
        out
    }

    fn case<'a, T, S, Pol, Coh, Rough>(
        kernel: &Kernel<Pol, Coh, Rough>,
        material: &'a S,
        surface: &Frame<T>,
        (seed, lambda): (u64, f64),
        what: &str,
    ) -> Case<'a, T>
    where
        T: Real,
        S: Surface<T>,
        Pol: PolarizationModel,
        Coh: CoherenceModel + CoherenceWeights<T, S::Psd>,
        Rough: RoughnessModel + RoughnessWeights<T, S::Psd, Coh>,
    {
        let k = T::lit(std::f64::consts::TAU / lambda);
        let maker = row_maker(kernel, material).expect("a kernel the lanes take");
        let (t1, t2, n) = (surface.x(), surface.y(), surface.k());
        let mut st = seed;
        let mut c = Case {
            what: what.to_string(),
            head: lane_prep_at(
                kernel,
                material,
                &kernel.prepare_unpolarized_isotropic(k, T::lit(0.1)),
                n + t1 * T::lit(0.3),
                surface,
                None,
            )
            .expect("the head"),
            maker,
            dirs: vec![],
            tilt: vec![],
            inv_w: vec![],
            want: vec![],
        };
        for (theta, phi, len) in directions(seed) {
            let (st_, ct) = theta.sin_cos();
            let local = |v: f64| T::lit(v * len);
            let d = t1 * local(st_ * phi.cos()) + t2 * local(st_ * phi.sin()) + n * local(ct);
            // Widths of 0.3 µm to 300 µm, and at the ends of the range the lanes take.
            // (1e-16: `ln|Ξ|` leaves the one-logarithm branch, the lane is flagged.)
            let inv_w = match c.dirs.len() % 17 {
                3 => T::lit(1e-14),
                4 => T::lit(1e14),
                5 => T::lit(1e-16),
                _ => T::lit(0.003 * 1000f64.powf(uniform(&mut st))),
            };
            let prepared = kernel.prepare_unpolarized_isotropic(k, inv_w);
            c.inv_w.push(inv_w);
            let m = &c.maker;
            let row = LobePrep::lane_row_of(&prepared, m.psd, m.indices, d, surface, m.incoherent);
            c.want.push(row);
            c.tilt.push(theta);
            c.dirs.push(d);
        }
        c
    }

    struct Check<'a, F: Real>(Vec<Case<'a, F>>);

    impl<F: Real> PerWidth for Check<'_, F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for c in &self.0 {
                let shared = Shared::new(&c.head, &c.maker);
                let (mut flagged, mut total) = (0, 0);
                chunks::<S, F>(c.dirs.len(), |i, len| {
                    let col = |f: &dyn Fn(usize) -> F| -> Vec<F> { (i..i + len).map(f).collect() };
                    let dir = [0, 1, 2].map(|k| load::<S, F>(s, &col(&|j| c.dirs[j][k])));
                    let iw = load::<S, F>(s, &col(&|j| c.inv_w[j]));
                    let (g, bad) = lanes::<S, F>(s, &shared, dir, iw);
                    let rows = g.rows(s);
                    let mut bad_lanes = [F::zero(); 16];
                    let one = F::vsplat(s, F::one());
                    let zero = F::vsplat(s, F::zero());
                    F::store_partial(
                        s,
                        &mut bad_lanes[..F::width::<S>()],
                        F::vselect(s, bad, one, zero),
                    );
                    for l in 0..len {
                        let j = i + l;
                        total += 1;
                        let near = c.tilt[j] < 4.0 * F::EPSILON.to_f64().sqrt();
                        let edge = c.inv_w[j] == F::lit(1e-16);
                        if bad_lanes[l] == F::one() {
                            flagged += 1;
                            assert!(
                                near || edge || c.want[j].is_none(),
                                "{what}: {}: direction {j} (tilt {:e}) flagged",
                                c.what,
                                c.tilt[j]
                            );
                            continue;
                        }
                        let want = c.want[j].expect("an unflagged lane has a row");
                        for (f, (a, b)) in rows[l].iter().zip(want).enumerate() {
                            assert!(
                                same(*a, b),
                                "{what}: {}: direction {j} (tilt {:e}), field {f}: {:e} vs {:e}",
                                c.what,
                                c.tilt[j],
                                a.to_f64(),
                                b.to_f64()
                            );
                        }
                    }
                });
                // Only the directions at the normal and the widths at the edge may leave the
                // lanes (checked above), and they are few.
                let near = c.tilt.iter().zip(&c.inv_w).filter(|(t, w)| {
                    **t < 4.0 * F::EPSILON.to_f64().sqrt() || **w == F::lit(1e-16)
                });
                let near = near.count();
                assert!(
                    flagged <= near && near * 5 < total,
                    "{what}: {}: {flagged} of {total} flagged",
                    c.what
                );
            }
        }
    }

    /// Gold (isotropic and anisotropic PSDs), silver and glass at `Full · Partial`, gold at
    /// `Intensity · Incoherent`, on a
    /// surface facing `+z` and on a tilted one, checked at every back-end.
    fn check_every_case<T: Real>(seed: u64) {
        let t = |x: f64| T::lit(x);
        let iso = GaussianPsd::<T, 2>::isotropic(t(0.02), t(1.0)).unwrap();
        let gold = RoughConductor::new(iso, Complex::new(t(0.47), t(2.4))).unwrap();
        let silver = RoughConductor::new(iso, Complex::new(t(0.05), t(3.4))).unwrap();
        let glass = RoughDielectric::new(iso, t(1.5)).unwrap();
        let aniso = GaussianPsd::<T, 2>::from_autocorrelation(
            t(4e-4),
            &Gaussian::new(Matrix2::new(t(2.0), t(0.6), t(0.6), t(0.5))).unwrap(),
        )
        .unwrap();
        let gold_aniso = RoughConductor::new(aniso, Complex::new(t(0.47), t(2.4))).unwrap();
        let flat = Frame::from_normal(Vector3::new(t(0.0), t(0.0), t(1.0))).unwrap();
        let tilted = Frame::from_normal(Vector3::new(t(0.3), t(-0.5), t(0.8))).unwrap();
        let mut out = vec![];
        for (f, frame) in [(&flat, "z"), (&tilted, "tilted")] {
            let full = Kernel::<Full, Partial>::default();
            let what = |m: &str| format!("{m}, {frame}");
            out.push(case(&full, &gold, f, (seed, 0.55), &what("gold")));
            out.push(case(&full, &silver, f, (seed ^ 1, 0.4), &what("silver")));
            out.push(case(&full, &glass, f, (seed ^ 2, 0.7), &what("glass")));
            let aniso = what("gold, anisotropic");
            out.push(case(&full, &gold_aniso, f, (seed ^ 4, 0.5), &aniso));
            let incoherent = Kernel::<Intensity, Incoherent>::default();
            out.push(case(
                &incoherent,
                &gold,
                f,
                (seed ^ 3, 0.55),
                &what("gold, incoherent"),
            ));
        }
        every_width(&Check(out));
    }

    /// The lanes' constants equal `LobePrep::lane_row_of`'s bit for bit on every lane they do
    /// not flag, at every back-end, and only directions at the normal are flagged.
    #[test]
    fn lanes_equal_lane_row_of_bit_for_bit() {
        check_every_case::<f64>(0xc0_5151);
        check_every_case::<f32>(0xc0_5152);
    }
}
