//! `q_o = √(ε − sin²θ_o)` (principal branch) in lanes, the exit-side square root of the
//! Rayleigh–Rice factors, as `numerics::principal_sqrt` on its plain `hypot` branch, without
//! branches (`Im ε ≥ 0` always).

use pulp::Simd;

use super::super::prep::Incidence;
use crate::real::Real;
use crate::simd::complex::C;

/// `(sin²θ_o, q_o)` of the exits with `cos θ_o = cos_o`.
#[inline(always)]
pub(crate) fn exit_q<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    cos_o: F::V<S>,
) -> (F::V<S>, C<F::V<S>>) {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul, div) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>, F::vdiv::<S>);
    let zero = c(F::zero());
    let one = c(F::one());
    let so2 = F::vmax(s, sub(s, one, mul(s, cos_o, cos_o)), zero);
    let a = sub(s, c(p.e.re), so2);
    let abs_a = F::vabs(s, a);
    let modulus = if p.real_eps {
        abs_a
    } else {
        F::vsqrt(s, add(s, mul(s, a, a), c(p.eim2)))
    };
    let big = F::vsqrt(s, mul(s, add(s, modulus, abs_a), c(F::lit(0.5))));
    // `Im ε/2 / big`: with a real ε, `±0/big` is `Im ε/2` itself (`big > 0` where selected).
    let half_im = if p.real_eps {
        c(p.eim_half)
    } else {
        div(s, c(p.eim_half), big)
    };
    let small = F::vselect(s, F::vlt(s, zero, big), half_im, zero);
    let nonneg = F::vle(s, zero, a);
    let qo = C {
        re: F::vselect(s, nonneg, big, small),
        im: F::vselect(s, nonneg, small, big),
    };
    (so2, qo)
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

    /// `q_o` bit for bit `principal_sqrt(ε − sin²θ_o)` of `RayleighRice::factors`, on the
    /// fixture's `cos θ_o` plus 0, 1 and the values where `Re ε − sin²θ_o` changes sign.
    struct Check<F: Real>(Vec<Scene<F>>);

    impl<F: Real> PerWidth for Check<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for sc in &self.0 {
                let e = sc.prep.e;
                let mut cos: Vec<F> = (0..sc.exits.len()).map(|i| sc.geometry(i).cos_o).collect();
                cos.extend([F::zero(), F::one(), F::lit(0.5), F::lit(1e-3)]);
                if e.re < F::one() && e.re > F::zero() {
                    let c0 = (F::one() - e.re).sqrt();
                    cos.extend([
                        c0,
                        c0 * (F::one() + F::EPSILON),
                        c0 * (F::one() - F::EPSILON),
                    ]);
                }
                chunks::<S, F>(cos.len(), |i, len| {
                    let (so2, q) = exit_q::<S, F>(s, &sc.prep, load::<S, F>(s, &cos[i..i + len]));
                    let so2 = lanes_of::<S, F>(s, so2);
                    let (re, im) = (lanes_of::<S, F>(s, q.re), lanes_of::<S, F>(s, q.im));
                    for l in 0..len {
                        let co = cos[i + l];
                        let want_so2 = (F::one() - co * co).max(F::zero());
                        let want = principal_sqrt(e - Complex::new(F::one(), F::zero()) * want_so2);
                        assert!(same(so2[l], want_so2), "{what}: cos θ_o {}", co.to_f64());
                        assert!(
                            same(re[l], want.re) && same(im[l], want.im),
                            "{what}: cos θ_o {}: {} {} vs {want}",
                            co.to_f64(),
                            re[l].to_f64(),
                            im[l].to_f64()
                        );
                    }
                });
            }
        }
    }

    #[test]
    fn lanes_match_principal_sqrt_bit_for_bit_at_every_width() {
        every_width(&Check(scenes::<f64>()));
        every_width(&Check(scenes::<f32>()));
    }
}
