//! The exit s vector and the exit azimuth `(cos φ, sin φ)` in lanes, as `Frame::sp_unit(r̂, n̂)`
//! and `Geometry::exit_azimuth`: `c = r̂ × n̂` normalised when `|c|² ≥ 1/64`, re-orthogonalised
//! against r̂ when `√ε ≤ |c| < 1/8`; within `√ε` of the normal the scalar frame code, lane by
//! lane.

use nalgebra::Vector3;
use pulp::Simd;

use super::super::prep::Incidence;
use super::{div3, dot3, splat3};
use crate::real::Real;

/// The exit s vector, `(cos φ, sin φ)` and the lanes within `√ε` of the normal, of the unit
/// exits `r`, all in lanes: the s vector and azimuth are those of the scalar code except on the
/// lanes of the mask, where `Frame::sp_unit` falls back to a tangent of n̂ (the caller takes
/// the scalar code there).
pub(crate) struct ExitFrame<S: Simd, F: Real> {
    pub(crate) s_out: [F::V<S>; 3],
    pub(crate) cos_phi: F::V<S>,
    pub(crate) sin_phi: F::V<S>,
    pub(crate) rho: F::V<S>,
    pub(crate) normal: F::M<S>,
}

/// The azimuth axes `(n̂ × ŝ_in, n̂ × (n̂ × ŝ_in))` as vectors.
pub(crate) type AzimuthAxes<V> = ([V; 3], [V; 3]);

/// [`ExitFrame`] of the unit exits `r`.
#[inline(always)]
pub(crate) fn exit_frame<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    r: [F::V<S>; 3],
) -> ExitFrame<S, F> {
    let axes = (splat3::<S, F>(s, p.u_az), splat3::<S, F>(s, p.v_az));
    exit_frame_with::<S, F>(s, p, axes, r)
}

/// [`exit_frame`] with the azimuth axes `(n̂ × ŝ_in, n̂ × (n̂ × ŝ_in))` given per lane (the
/// per-lane pass, `batch::per_lane`: each lane its own incident direction); the normal and
/// `√ε` are `p`'s.
#[inline(always)]
pub(crate) fn exit_frame_with<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    (u_az, v_az): AzimuthAxes<F::V<S>>,
    r: [F::V<S>; 3],
) -> ExitFrame<S, F> {
    let c = |v: F| F::vsplat(s, v);
    let (sub, mul) = (F::vsub::<S>, F::vmul::<S>);
    let zero = c(F::zero());
    let n = splat3::<S, F>(s, p.n);
    let cr = [
        sub(s, mul(s, r[1], n[2]), mul(s, r[2], n[1])),
        sub(s, mul(s, r[2], n[0]), mul(s, r[0], n[2])),
        sub(s, mul(s, r[0], n[1]), mul(s, r[1], n[0])),
    ];
    let c2 = dot3::<S, F>(s, cr, cr);
    let rho = F::vsqrt(s, c2);
    let mut s_out = div3::<S, F>(s, cr, rho);
    let near = F::vlt(s, c2, c(F::lit(1.0 / 64.0)));
    if F::vany(s, near) {
        let o = orthogonalize::<S, F>(s, cr, r);
        for j in 0..3 {
            s_out[j] = F::vselect(s, near, o[j], s_out[j]);
        }
    }
    let cos_phi = sub(s, zero, dot3::<S, F>(s, s_out, v_az));
    let sin_phi = dot3::<S, F>(s, s_out, u_az);
    let normal = F::vlt(s, rho, c(p.parallel_tol));
    ExitFrame {
        s_out,
        cos_phi,
        sin_phi,
        rho,
        normal,
    }
}

/// `(cos φ, sin φ)` of the unit exits `r`.
#[inline(always)]
pub(crate) fn exit_azimuth<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    r: [F::V<S>; 3],
) -> (F::V<S>, F::V<S>) {
    let ExitFrame {
        mut cos_phi,
        mut sin_phi,
        rho,
        normal,
        ..
    } = exit_frame::<S, F>(s, p, r);
    if F::vany(s, normal) {
        // Within √ε of the normal: the scalar frame code, lane by lane.
        let lanes = F::width::<S>();
        let mut buf = [[F::zero(); 6]; 16];
        let mut lane = [F::zero(); 16];
        for (j, v) in [r[0], r[1], r[2], rho, cos_phi, sin_phi]
            .into_iter()
            .enumerate()
        {
            F::store_partial(s, &mut lane[..lanes], v);
            for (b, &x) in buf.iter_mut().zip(&lane[..lanes]) {
                b[j] = x;
            }
        }
        for b in &mut buf[..lanes] {
            if b[3] < p.parallel_tol {
                (b[4], b[5]) = p.azimuth_scalar(Vector3::new(b[0], b[1], b[2]));
            }
        }
        for (l, b) in lane.iter_mut().zip(&buf[..lanes]) {
            *l = b[4];
        }
        cos_phi = F::load_partial(s, &lane[..lanes]);
        for (l, b) in lane.iter_mut().zip(&buf[..lanes]) {
            *l = b[5];
        }
        sin_phi = F::load_partial(s, &lane[..lanes]);
    }
    (cos_phi, sin_phi)
}

/// `v − k (v·k)` normalised, twice (`frame.rs`'s `orthogonalize`), unfused.
#[inline(always)]
fn orthogonalize<S: Simd, F: Real>(s: S, v: [F::V<S>; 3], k: [F::V<S>; 3]) -> [F::V<S>; 3] {
    let once = orthogonalize_step::<S, F>(s, v, k);
    orthogonalize_step::<S, F>(s, once, k)
}

/// One step of [`orthogonalize`]. (Functions rather than closures or `array::map` throughout
/// the vector code: they are `inline(always)`, so nothing is compiled outside pulp's
/// `#[target_feature]` function.)
#[inline(always)]
fn orthogonalize_step<S: Simd, F: Real>(s: S, v: [F::V<S>; 3], k: [F::V<S>; 3]) -> [F::V<S>; 3] {
    let d = dot3::<S, F>(s, v, k);
    let a = [
        F::vsub(s, v[0], F::vmul(s, k[0], d)),
        F::vsub(s, v[1], F::vmul(s, k[1], d)),
        F::vsub(s, v[2], F::vmul(s, k[2], d)),
    ];
    let norm = F::vsqrt(s, dot3::<S, F>(s, a, a));
    div3::<S, F>(s, a, norm)
}

#[cfg(test)]
mod tests {
    use pulp::Simd;

    use super::super::fixture::{
        PerWidth, Scene, chunks, every_width, lanes_of, load, same, scenes,
    };
    use super::*;

    /// `(cos φ, sin φ)` bit for bit `Geometry::exit_azimuth` of `Geometry::for_packet`, from
    /// the scalar r̂ (every band of `Frame::sp`, the normal included).
    struct Check<F: Real>(Vec<Scene<F>>);

    impl<F: Real> PerWidth for Check<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for sc in &self.0 {
                chunks::<S, F>(sc.exits.len(), |i, len| {
                    let g: Vec<_> = (i..i + len).map(|j| sc.geometry(j)).collect();
                    let col = |k: usize| -> Vec<F> { g.iter().map(|g| g.exit[k]).collect() };
                    let r = [
                        load::<S, F>(s, &col(0)),
                        load::<S, F>(s, &col(1)),
                        load::<S, F>(s, &col(2)),
                    ];
                    let (c, sn) = exit_azimuth::<S, F>(s, &sc.prep, r);
                    let (c, sn) = (lanes_of::<S, F>(s, c), lanes_of::<S, F>(s, sn));
                    for l in 0..len {
                        let (wc, ws) = g[l].exit_azimuth();
                        assert!(same(c[l], wc), "{what}: exit {}, cos φ", i + l);
                        assert!(same(sn[l], ws), "{what}: exit {}, sin φ", i + l);
                    }
                });
            }
        }
    }

    #[test]
    fn lanes_match_exit_azimuth_bit_for_bit_at_every_width() {
        every_width(&Check(scenes::<f64>()));
        every_width(&Check(scenes::<f32>()));
    }
}
