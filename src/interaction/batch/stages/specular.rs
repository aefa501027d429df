//! The specular pBSDF in lanes: `FresnelReflection::mueller` (or `FresnelInterface::mueller`
//! on either side), the Fresnel Mueller matrix (per packet) followed by the frame change from the specular s/p frame to each exit's s/p
//! frame (`frame_change_mueller`, S2.3–S2.4): its closest rotation (or reflection, when
//! `r̂·r̂_spec < −256 ε`) from the four dot products of the two frames' axes.

use pulp::Simd;

use super::channels::{mat_vec, mat_vec_with};
use super::{dot3, splat3};
use crate::frame::Frame;
use crate::real::Real;
use nalgebra::Matrix4;

/// `T(F_spec → F_exit) M_F v` for the unit exits `r` with exit s vectors `s_out`: `fresnel`
/// is `M_F`, `spec_frame` the specular s/p frame, and `r̂·r̂_spec < −flip_tol` a flipped frame
/// change.
#[inline(always)]
pub(crate) fn fresnel_stokes<S: Simd, F: Real>(
    s: S,
    (fresnel, spec_frame, flip_tol): (&Matrix4<F>, &Frame<F>, F),
    r: [F::V<S>; 3],
    s_out: [F::V<S>; 3],
    v: [F::V<S>; 4],
) -> [F::V<S>; 4] {
    let w = mat_vec::<S, F>(s, fresnel, v);
    let axes = [
        splat3::<S, F>(s, spec_frame.x()),
        splat3::<S, F>(s, spec_frame.y()),
        splat3::<S, F>(s, spec_frame.k()),
    ];
    frame_change::<S, F>(s, (&axes, flip_tol), r, s_out, w)
}

/// The Fresnel matrix (`fresnel[i][j]` the lanes of `M_ij`) and the specular frame's axes
/// (ŝ, p̂, `r̂_spec`) given per lane (the per-lane pass, `batch::per_lane`).
#[derive(Clone, Copy)]
pub(crate) struct SpecularLanes<V> {
    pub(crate) fresnel: [[V; 4]; 4],
    pub(crate) axes: [[V; 3]; 3],
}

/// [`fresnel_stokes`] with the Fresnel matrix and the specular frame given per lane.
#[inline(always)]
pub(crate) fn fresnel_stokes_with<S: Simd, F: Real>(
    s: S,
    (lanes, flip_tol): (&SpecularLanes<F::V<S>>, F),
    r: [F::V<S>; 3],
    s_out: [F::V<S>; 3],
    v: [F::V<S>; 4],
) -> [F::V<S>; 4] {
    let w = mat_vec_with::<S, F>(s, &lanes.fresnel, v);
    frame_change::<S, F>(s, (&lanes.axes, flip_tol), r, s_out, w)
}

/// `T(F_spec → F_exit) w`: the frame change of [`fresnel_stokes`] from the specular frame of
/// axes `[ŝ, p̂, r̂_spec]` (`axes`) to each exit's.
#[inline(always)]
fn frame_change<S: Simd, F: Real>(
    s: S,
    (axes, flip_tol): (&[[F::V<S>; 3]; 3], F),
    r: [F::V<S>; 3],
    s_out: [F::V<S>; 3],
    w: [F::V<S>; 4],
) -> [F::V<S>; 4] {
    let c = |x: F| F::vsplat(s, x);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    // p̂_out = r̂ × ŝ_out (Frame::sp_unit).
    let p_out = [
        sub(s, mul(s, r[1], s_out[2]), mul(s, r[2], s_out[1])),
        sub(s, mul(s, r[2], s_out[0]), mul(s, r[0], s_out[2])),
        sub(s, mul(s, r[0], s_out[1]), mul(s, r[1], s_out[0])),
    ];
    let [fs, fp, fk] = *axes;
    let a = dot3::<S, F>(s, s_out, fs);
    let b = dot3::<S, F>(s, s_out, fp);
    let cc = dot3::<S, F>(s, p_out, fs);
    let d = dot3::<S, F>(s, p_out, fp);
    let flip = F::vlt(s, dot3::<S, F>(s, fk, r), c(-flip_tol));
    let x = F::vselect(s, flip, sub(s, a, d), add(s, a, d));
    let y = F::vselect(s, flip, sub(s, c(F::zero()), add(s, b, cc)), sub(s, cc, b));
    // cos 2φ = (x² − y²)/(x² + y²), sin 2φ = 2xy/(x² + y²): one reciprocal, no root (the
    // scalar normalises (x, y) by its length first; `x² + y² ≈ 4` away from the lanes the
    // per-direction kernel redoes).
    let inv = F::vdiv(s, c(F::one()), F::vmul_add(s, x, x, mul(s, y, y)));
    let c2 = mul(s, F::vneg_mul_add(s, y, y, mul(s, x, x)), inv);
    let s2 = mul(s, mul(s, add(s, x, x), y), inv);
    let sign = F::vselect(s, flip, c(-F::one()), c(F::one()));
    let o1 = F::vneg_mul_add(s, s2, w[2], mul(s, c2, w[1]));
    let o2 = F::vmul_add(s, s2, w[1], mul(s, c2, w[2]));
    [w[0], o1, mul(s, o2, sign), mul(s, w[3], sign)]
}
