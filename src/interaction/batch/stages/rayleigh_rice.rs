//! The Rayleigh–Rice factors `ss, ps, sp, pp` in lanes, as `RayleighRice::factors` (the
//! per-packet part — `q_i`, `ε − 1`, `D₁`, `D₃` — precomputed), in `num_complex`'s order and
//! without fused multiply–adds.

use pulp::Simd;

use super::super::prep::Incidence;
use crate::real::Real;
use crate::simd::complex::{C, Cx};

/// `[ss, ps, sp, pp]` at `cos θ_o`, `sin²θ_o`, `q_o` and the azimuth `(cos φ, sin φ)`.
#[inline(always)]
pub(crate) fn factors<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    cos_o: F::V<S>,
    so2: F::V<S>,
    qo: C<F::V<S>>,
    (cos_phi, sin_phi): (F::V<S>, F::V<S>),
) -> [C<F::V<S>>; 4] {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let cx = Cx(s);
    let e = cx.splat::<F>(p.e);
    let (d1, d3) = (cx.splat::<F>(p.d1), cx.splat::<F>(p.d3));
    let d2 = C {
        re: add(s, qo.re, cos_o),
        im: qo.im,
    };
    let d4 = C {
        re: add(s, mul(s, c(p.e.re), cos_o), qo.re),
        im: add(s, mul(s, c(p.e.im), cos_o), qo.im),
    };
    let inv_ss = cx.recip::<F>(cx.mul::<F>(d1, d2));
    let inv_pp = cx.recip::<F>(cx.mul::<F>(d3, d4));
    let both = cx.mul::<F>(inv_ss, inv_pp);
    let em1 = cx.splat::<F>(p.em1);
    let ss = cx.scale::<F>(cx.mul::<F>(em1, inv_ss), cos_phi);
    let sq = F::vsqrt(s, mul(s, c(p.si2), so2));
    let qoqi = cx.scale::<F>(cx.mul::<F>(qo, cx.splat::<F>(p.qi)), cos_phi);
    let es = cx.scale::<F>(e, sq);
    let inner = C {
        re: sub(s, es.re, qoqi.re),
        im: sub(s, es.im, qoqi.im),
    };
    let pp = cx.mul::<F>(cx.mul::<F>(em1, inner), inv_pp);
    let ps = cx.scale::<F>(
        cx.mul::<F>(
            cx.splat::<F>(p.neg_em1_qi),
            cx.mul::<F>(cx.mul::<F>(d1, d4), both),
        ),
        sin_phi,
    );
    let sp = cx.scale::<F>(
        cx.mul::<F>(
            cx.mul::<F>(cx.splat::<F>(p.neg_em1), qo),
            cx.mul::<F>(cx.mul::<F>(d2, d3), both),
        ),
        sin_phi,
    );
    [ss, ps, sp, pp]
}

#[cfg(test)]
mod tests {
    use num_complex::Complex;
    use pulp::Simd;

    use super::super::fixture::{
        PerWidth, Scene, chunks, every_width, lanes_of, load, same, scenes,
    };
    use super::*;
    use crate::numerics::principal_sqrt;

    /// The four factors bit for bit `RayleighRice::factors` of `Geometry::for_packet`, from
    /// the scalar `cos θ_o`, `q_o` and azimuth.
    struct Check<F: Real>(Vec<Scene<F>>);

    impl<F: Real> PerWidth for Check<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for sc in &self.0 {
                chunks::<S, F>(sc.exits.len(), |i, len| {
                    let g: Vec<_> = (i..i + len).map(|j| sc.geometry(j)).collect();
                    let col = |f: &dyn Fn(usize) -> F| -> Vec<F> { (0..len).map(f).collect() };
                    let so2 = |j: usize| (F::one() - g[j].cos_o * g[j].cos_o).max(F::zero());
                    let q = |j: usize| {
                        principal_sqrt(sc.prep.e - Complex::new(F::one(), F::zero()) * so2(j))
                    };
                    let l = |f: &dyn Fn(usize) -> F| load::<S, F>(s, &col(f));
                    let f = factors::<S, F>(
                        s,
                        &sc.prep,
                        l(&|j| g[j].cos_o),
                        l(&so2),
                        C {
                            re: l(&|j| q(j).re),
                            im: l(&|j| q(j).im),
                        },
                        (l(&|j| g[j].exit_azimuth().0), l(&|j| g[j].exit_azimuth().1)),
                    );
                    for (k, z) in f.iter().enumerate() {
                        let (re, im) = (lanes_of::<S, F>(s, z.re), lanes_of::<S, F>(s, z.im));
                        for j in 0..len {
                            let want = sc.scatter.factors(&g[j])[(k / 2, k % 2)];
                            assert!(
                                same(re[j], want.re) && same(im[j], want.im),
                                "{what}: exit {}, factor {k}",
                                i + j
                            );
                        }
                    }
                });
            }
        }
    }

    #[test]
    fn lanes_match_factors_bit_for_bit_at_every_width() {
        every_width(&Check(scenes::<f64>()));
        every_width(&Check(scenes::<f32>()));
    }
}
