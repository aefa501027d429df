//! The unit exit direction r̂ and `cos θ_o = r̂·n̂` in lanes, as `geometry::unit` and
//! `Geometry::new`: divided by the largest |component|, then by the norm, unfused.

use pulp::Simd;

use super::super::prep::Incidence;
use super::{div3, dot3, splat3};
use crate::real::Real;

/// `(r̂, cos θ_o)` of the (validated) exits `(x, y, z)`.
#[inline(always)]
pub(crate) fn exit_direction<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    x: F::V<S>,
    y: F::V<S>,
    z: F::V<S>,
) -> ([F::V<S>; 3], F::V<S>) {
    let div = F::vdiv::<S>;
    let m = F::vmax(s, F::vmax(s, F::vabs(s, x), F::vabs(s, y)), F::vabs(s, z));
    let u = [div(s, x, m), div(s, y, m), div(s, z, m)];
    let norm = F::vsqrt(s, dot3::<S, F>(s, u, u));
    let r = div3::<S, F>(s, u, norm);
    let cos_o = dot3::<S, F>(s, r, splat3::<S, F>(s, p.n));
    (r, cos_o)
}

#[cfg(test)]
mod tests {
    use pulp::Simd;

    use super::super::fixture::{
        PerWidth, Scene, chunks, every_width, lanes_of, load, same, scenes,
    };
    use super::*;

    /// r̂ and `cos θ_o` bit for bit those of `Geometry::for_packet`.
    struct Check<F: Real>(Vec<Scene<F>>);

    impl<F: Real> PerWidth for Check<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for sc in &self.0 {
                chunks::<S, F>(sc.exits.len(), |i, len| {
                    let col = |k: usize| -> Vec<F> {
                        sc.exits[i..i + len].iter().map(|v| v[k]).collect()
                    };
                    let (r, cos_o) = exit_direction::<S, F>(
                        s,
                        &sc.prep,
                        load::<S, F>(s, &col(0)),
                        load::<S, F>(s, &col(1)),
                        load::<S, F>(s, &col(2)),
                    );
                    let r = r.map(|v| lanes_of::<S, F>(s, v));
                    let cos_o = lanes_of::<S, F>(s, cos_o);
                    for l in 0..len {
                        let g = sc.geometry(i + l);
                        assert!(same(cos_o[l], g.cos_o), "{what}: exit {}", i + l);
                        for (k, rk) in r.iter().enumerate() {
                            assert!(same(rk[l], g.exit[k]), "{what}: exit {}, r{k}", i + l);
                        }
                    }
                });
            }
        }
    }

    #[test]
    fn lanes_match_geometry_bit_for_bit_at_every_width() {
        every_width(&Check(scenes::<f64>()));
        every_width(&Check(scenes::<f32>()));
    }
}
