//! The Stokes assembly in lanes: `w · M′ (T S)` from the Jones entries `a = ss, b = ps,
//! c = sp, d = pp` (S1.7 written out as in `mueller::batch`, with `P = (S0 + S1)/2` and
//! `Q = (S0 − S1)/2` of the effective `T S`), with fused multiply–adds.

use pulp::Simd;

use super::super::prep::PlaneWavePrep;
use crate::real::Real;
use crate::simd::complex::{C, im_conj, re_conj};

/// The four Stokes parameters `w · M′ (T S)` of the factors `[ss, ps, sp, pp]`.
#[inline(always)]
pub(crate) fn assemble<S: Simd, F: Real>(
    s: S,
    p: &PlaneWavePrep<F>,
    factors: [C<F::V<S>>; 4],
    w: F::V<S>,
) -> [F::V<S>; 4] {
    let c = |v: F| F::vsplat(s, v);
    let st = [
        c(p.stokes[0]),
        c(p.stokes[1]),
        c(p.stokes[2]),
        c(p.stokes[3]),
    ];
    assemble_vector::<S, F>(s, st, factors, w)
}

/// [`assemble`] for an effective Stokes vector that varies from lane to lane, given as
/// `[P, Q, S2, S3]` with `P = (S0 + S1)/2`, `Q = (S0 − S1)/2`.
#[inline(always)]
pub(crate) fn assemble_vector<S: Simd, F: Real>(
    s: S,
    [pw, qw, s2, s3]: [F::V<S>; 4],
    [ja, jb, jc, jd]: [C<F::V<S>>; 4],
    w: F::V<S>,
) -> [F::V<S>; 4] {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let fma = F::vmul_add::<S>;
    let (re, im) = (re_conj::<S, F>, im_conj::<S, F>);
    let aa = re(s, ja, ja);
    let bb = re(s, jb, jb);
    let cc = re(s, jc, jc);
    let dd = re(s, jd, jd);
    let (ab_r, ab_i) = (re(s, ja, jb), im(s, ja, jb));
    let (cd_r, cd_i) = (re(s, jc, jd), im(s, jc, jd));
    let (ac_r, nac_i) = (re(s, ja, jc), im(s, jc, ja));
    let (bd_r, bd_i) = (re(s, jb, jd), im(s, jb, jd));
    let (bc_r, nbc_i) = (re(s, jb, jc), im(s, jc, jb));
    let (ad_r, ad_i) = (re(s, ja, jd), im(s, ja, jd));
    let row_a = fma(
        s,
        aa,
        pw,
        fma(s, bb, qw, fma(s, ab_r, s2, mul(s, ab_i, s3))),
    );
    let row_b = fma(
        s,
        cc,
        pw,
        fma(s, dd, qw, fma(s, cd_r, s2, mul(s, cd_i, s3))),
    );
    let two = c(F::lit(2.0));
    let o2 = fma(
        s,
        two,
        fma(s, ac_r, pw, mul(s, bd_r, qw)),
        fma(s, add(s, bc_r, ad_r), s2, mul(s, add(s, ad_i, nbc_i), s3)),
    );
    let o3 = fma(
        s,
        two,
        F::vneg_mul_add(s, bd_i, qw, mul(s, nac_i, pw)),
        fma(s, sub(s, nbc_i, ad_i), s2, mul(s, sub(s, ad_r, bc_r), s3)),
    );
    [
        mul(s, add(s, row_a, row_b), w),
        mul(s, sub(s, row_a, row_b), w),
        mul(s, o2, w),
        mul(s, o3, w),
    ]
}

/// `S0` of [`assemble_vector`] for the effective vector `(1, 0, 0, 0)` (`P = Q = ½`, what the
/// Intensity level's constants hold): `(|a|² ½ + |b|² ½ + |c|² ½ + |d|² ½) w`, the operations
/// of [`assemble_vector`]'s `S0` with its terms in `S2`, `S3` left out. Bit for bit its `S0`
/// wherever the entries are finite: there those terms are `x · 0` (a zero), and
/// `fma(x, y, ±0)` rounds `x y` once, as `x · y` does.
#[inline(always)]
pub(crate) fn assemble_s0<S: Simd, F: Real>(
    s: S,
    [ja, jb, jc, jd]: [C<F::V<S>>; 4],
    w: F::V<S>,
) -> F::V<S> {
    let half = F::vsplat(s, F::lit(0.5));
    let (fma, mul) = (F::vmul_add::<S>, F::vmul::<S>);
    let re = re_conj::<S, F>;
    let row_a = fma(s, re(s, ja, ja), half, mul(s, re(s, jb, jb), half));
    let row_b = fma(s, re(s, jc, jc), half, mul(s, re(s, jd, jd), half));
    mul(s, F::vadd(s, row_a, row_b), w)
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector4;
    use pulp::Simd;

    use super::super::fixture::{PerWidth, Scene, chunks, every_width, lanes_of, load, scenes};
    use super::*;
    use crate::jones::JonesMatrix;
    use crate::mueller::Mueller;

    /// The four entries `a, b, c, d` of a vector's Rayleigh–Rice factors, in lanes.
    fn factor_lanes<S: Simd, F: Real>(
        s: S,
        f: &[nalgebra::Matrix2<num_complex::Complex<F>>],
    ) -> [C<F::V<S>>; 4] {
        let entry = |k: usize, im: bool| -> Vec<F> {
            f.iter()
                .map(|m| {
                    let z = m[(k / 2, k % 2)];
                    if im { z.im } else { z.re }
                })
                .collect()
        };
        let z = |k: usize| C {
            re: load::<S, F>(s, &entry(k, false)),
            im: load::<S, F>(s, &entry(k, true)),
        };
        [z(0), z(1), z(2), z(3)]
    }

    /// `w · M′ (T S)` against `Mueller::from_jones` of the scalar factors applied to the
    /// effective Stokes vector, in `f64`, within `16 ε M′₀₀ (|P| + |Q| + |S2| + |S3|) w`.
    struct Check<F: Real>(Vec<Scene<F>>);

    impl<F: Real> PerWidth for Check<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for sc in &self.0 {
                let p = &sc.prep;
                let st = p.stokes.map(|v| v.to_f64());
                let ts = Vector4::new(st[0] + st[1], st[0] - st[1], st[2], st[3]);
                let size: f64 = st.iter().map(|v| v.abs()).sum();
                chunks::<S, F>(sc.exits.len(), |i, len| {
                    let f: Vec<_> = (i..i + len)
                        .map(|j| sc.scatter.factors(&sc.geometry(j)))
                        .collect();
                    let w: Vec<F> = (0..len).map(|j| F::lit(0.5 + j as f64)).collect();
                    let out =
                        assemble::<S, F>(s, p, factor_lanes::<S, F>(s, &f), load::<S, F>(s, &w));
                    let out = out.map(|v| lanes_of::<S, F>(s, v));
                    for j in 0..len {
                        let m = Mueller::from_jones(&JonesMatrix(
                            f[j].map(|z| num_complex::Complex::new(z.re.to_f64(), z.im.to_f64())),
                        ))
                        .matrix();
                        let want = m * ts * w[j].to_f64();
                        let tol = 16.0 * F::EPSILON.to_f64() * m[(0, 0)] * size * w[j].to_f64();
                        for k in 0..4 {
                            let d = (out[k][j].to_f64() - want[k]).abs();
                            assert!(d <= tol, "{what}: exit {}, S{k}: {d:e} > {tol:e}", i + j);
                        }
                    }
                });
            }
        }
    }

    #[test]
    fn lanes_match_mueller_from_jones_at_every_width() {
        every_width(&Check(scenes::<f64>()));
        every_width(&Check(scenes::<f32>()));
    }

    /// [`assemble_s0`] is the `S0` of [`assemble_vector`] for the Intensity level's effective
    /// vector `(1, 0, 0, 0)`, bit for bit, on the factors of the fixture's scenes.
    struct S0<F: Real>(Vec<Scene<F>>);

    impl<F: Real> PerWidth for S0<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            let c = |v: F| F::vsplat(s, v);
            let half = F::lit(0.5);
            for sc in &self.0 {
                chunks::<S, F>(sc.exits.len(), |i, len| {
                    let f: Vec<_> = (i..i + len)
                        .map(|j| sc.scatter.factors(&sc.geometry(j)))
                        .collect();
                    let w: Vec<F> = (0..len).map(|j| F::lit(0.25 + 0.7 * j as f64)).collect();
                    let factors = factor_lanes::<S, F>(s, &f);
                    let wv = load::<S, F>(s, &w);
                    let full = assemble_vector::<S, F>(
                        s,
                        [c(half), c(half), c(F::zero()), c(F::zero())],
                        factors,
                        wv,
                    );
                    let (a, b) = (
                        lanes_of::<S, F>(s, full[0]),
                        lanes_of::<S, F>(s, assemble_s0::<S, F>(s, factors, wv)),
                    );
                    for j in 0..len {
                        assert_eq!(
                            a[j].to_f64().to_bits(),
                            b[j].to_f64().to_bits(),
                            "{what}: exit {}",
                            i + j
                        );
                    }
                });
            }
        }
    }

    #[test]
    fn s0_alone_is_the_s0_of_the_vector_at_every_width() {
        every_width(&S0(scenes::<f64>()));
        every_width(&S0(scenes::<f32>()));
    }
}
