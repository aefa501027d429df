//! The weight of a direction in lanes: `cos θ_o · exp(E)` with the exponent
//! `E = ln(σ²|Λ|^{1/2}) + ln(2π (2k cos θ_i)²/λ²) + ln S0 − ½ |L⁻¹ h_t|² − (k σ (cos θ_i + cos θ_o))²`
//! — the Gaussian PSD at `h_t` (`GaussianPsd::log_value`), the Debye–Waller factor and the
//! constant prefactor summed before one vector exponential.

use pulp::Simd;

use super::super::prep::PlaneWavePrep;
use super::{dot3, splat3};
use crate::real::Real;
use crate::simd::exp::vexp;

/// The exponent `E` at the unit exits `r` with `cos θ_o = cos_o`.
#[inline(always)]
pub(crate) fn log_weight<S: Simd, F: Real>(
    s: S,
    p: &PlaneWavePrep<F>,
    r: [F::V<S>; 3],
    cos_o: F::V<S>,
) -> F::V<S> {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul, div) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>, F::vdiv::<S>);
    let sv = splat3::<S, F>(s, p.s);
    let kk = c(p.k);
    let h = [
        mul(s, add(s, r[0], sv[0]), kk),
        mul(s, add(s, r[1], sv[1]), kk),
        mul(s, add(s, r[2], sv[2]), kk),
    ];
    let h0 = dot3::<S, F>(s, h, splat3::<S, F>(s, p.t1));
    let h1 = dot3::<S, F>(s, h, splat3::<S, F>(s, p.t2));
    let y0 = div(s, h0, c(p.l00));
    let y1 = div(s, sub(s, h1, mul(s, c(p.l10), y0)), c(p.l11));
    let maha = add(s, mul(s, y0, y0), mul(s, y1, y1));
    let log_p = add(s, c(p.log_scale), mul(s, c(F::lit(-0.5)), maha));
    let v = mul(s, kk, add(s, c(p.cos_i), cos_o));
    let log_alpha = F::vneg_mul_add(s, mul(s, v, v), c(p.variance), c(F::zero()));
    add(s, log_p, log_alpha)
}

/// The weight `cos θ_o · exp(E)` (see [`log_weight`]).
#[inline(always)]
pub(crate) fn weight<S: Simd, F: Real>(
    s: S,
    p: &PlaneWavePrep<F>,
    r: [F::V<S>; 3],
    cos_o: F::V<S>,
) -> F::V<S> {
    let e = log_weight::<S, F>(s, p, r, cos_o);
    F::vmul(s, cos_o, vexp::<S, F>(s, e))
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;
    use pulp::Simd;

    use super::super::fixture::{PerWidth, Scene, chunks, every_width, lanes_of, load, scenes};
    use super::*;
    use crate::psd::Psd;

    /// `E` against the scalar sum of `GaussianPsd::log_value(h_t)` (relative to its value at
    /// 0), `ln α` and the prepared constant, in `f64`, within `8 ε (1 + Σ|terms|)`; the weight
    /// against `cos θ_o · exp(E)` within `4 ε (4 + Σ|terms|)` relative.
    struct Check<F: Real>(Vec<Scene<F>>);

    impl<F: Real> PerWidth for Check<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for sc in &self.0 {
                let p = &sc.prep;
                let eps = F::EPSILON.to_f64();
                let log0 = sc.psd.log_value(&Vector2::zeros()).to_f64();
                chunks::<S, F>(sc.exits.len(), |i, len| {
                    let g: Vec<_> = (i..i + len).map(|j| sc.geometry(j)).collect();
                    let col = |f: &dyn Fn(usize) -> F| -> Vec<F> { (0..len).map(f).collect() };
                    let l = |f: &dyn Fn(usize) -> F| load::<S, F>(s, &col(f));
                    let r = [
                        l(&|j| g[j].exit[0]),
                        l(&|j| g[j].exit[1]),
                        l(&|j| g[j].exit[2]),
                    ];
                    let co = l(&|j| g[j].cos_o);
                    let e = lanes_of::<S, F>(s, log_weight::<S, F>(s, p, r, co));
                    let w = lanes_of::<S, F>(s, weight::<S, F>(s, p, r, co));
                    for j in 0..len {
                        let gj = &g[j];
                        let (k, ci, c_o) = (gj.k.to_f64(), gj.cos_i.to_f64(), gj.cos_o.to_f64());
                        let terms = [
                            p.log_scale.to_f64(),
                            sc.psd.log_value(&gj.h_t).to_f64() - log0,
                            -(k * (ci + c_o)).powi(2) * sc.psd.variance().to_f64(),
                        ];
                        let want: f64 = terms.iter().sum();
                        let mag: f64 = terms.iter().map(|t| t.abs()).sum();
                        let got = e[j].to_f64();
                        let tol = 8.0 * eps * (1.0 + mag);
                        assert!(
                            (got - want).abs() <= tol,
                            "{what}: exit {}: E {got} vs {want}",
                            i + j
                        );
                        let ww = c_o * want.exp();
                        let tol = 4.0 * eps * (4.0 + mag) * ww + F::MIN_POSITIVE.to_f64() * c_o;
                        assert!(
                            (w[j].to_f64() - ww).abs() <= tol,
                            "{what}: exit {}: w {:e} vs {ww:e}",
                            i + j,
                            w[j].to_f64()
                        );
                    }
                });
            }
        }
    }

    #[test]
    fn lanes_match_the_scalar_exponent_at_every_width() {
        every_width(&Check(scenes::<f64>()));
        every_width(&Check(scenes::<f32>()));
    }
}
