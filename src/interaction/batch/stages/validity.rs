//! The fast validity test of an exit direction, scalar and in lanes: finite, of moderate size,
//! and with `r·n̂ > 64 ε max|r_i|` (at an interface `|r·n̂|`, either side), far enough from 0
//! that the sign of the normalised direction's `cos θ_o` is that of `r·n̂` whatever the
//! rounding. Directions it does not clear go to the exact test ([`Incidence::check_exact`],
//! i.e. `Geometry::new` or `Geometry::at_interface`).

use pulp::Simd;

use super::super::prep::Incidence;
use crate::real::Real;

/// The size range `[MIN_POSITIVE / ε, MAX / 4]` of the fast test (`ε m` stays normal, `3 m`
/// finite); both bounds are powers of two, exact in `F`.
#[inline(always)]
fn size_range<F: Real>() -> (F, F) {
    (F::MIN_POSITIVE / F::EPSILON, F::MAX / F::lit(4.0))
}

/// `true` when `(x, y, z)` is certainly an accepted exit direction.
#[inline]
pub(crate) fn clearly_valid<F: Real>(p: &Incidence<F>, x: F, y: F, z: F) -> bool {
    clearly_valid_about(&p.n, p.interface.is_some(), [x, y, z])
}

/// [`clearly_valid`] about the unit normal `n` (either side of it when `either_side`): also the
/// test of a direction to the source, which `Geometry::new` accepts on the same terms.
#[inline]
pub(crate) fn clearly_valid_about<F: Real>(
    n: &nalgebra::Vector3<F>,
    either_side: bool,
    [x, y, z]: [F; 3],
) -> bool {
    let (lo, hi) = size_range::<F>();
    let m = x.abs().max(y.abs()).max(z.abs());
    let d = x * n.x + y * n.y + z * n.z;
    let d = if either_side { d.abs() } else { d };
    x.is_finite()
        && y.is_finite()
        && z.is_finite()
        && m >= lo
        && m <= hi
        && d > F::lit(64.0) * F::EPSILON * m
}

/// [`clearly_valid`] on every lane.
#[inline(always)]
pub(crate) fn clearly_valid_lanes<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    x: F::V<S>,
    y: F::V<S>,
    z: F::V<S>,
) -> F::M<S> {
    clearly_valid_lanes_about::<S, F>(s, &p.n, p.interface.is_some(), [x, y, z])
}

/// [`clearly_valid_about`] on every lane.
#[inline(always)]
pub(crate) fn clearly_valid_lanes_about<S: Simd, F: Real>(
    s: S,
    n: &nalgebra::Vector3<F>,
    either_side: bool,
    [x, y, z]: [F::V<S>; 3],
) -> F::M<S> {
    let c = |v: F| F::vsplat(s, v);
    let (lo, hi) = size_range::<F>();
    let zero = c(F::zero());
    let finite = |v: F::V<S>| F::veq(s, F::vsub(s, v, v), zero);
    let m = F::vmax(s, F::vmax(s, F::vabs(s, x), F::vabs(s, y)), F::vabs(s, z));
    let d = F::vadd(
        s,
        F::vadd(s, F::vmul(s, x, c(n.x)), F::vmul(s, y, c(n.y))),
        F::vmul(s, z, c(n.z)),
    );
    let d = if either_side { F::vabs(s, d) } else { d };
    let and = F::vand::<S>;
    and(
        s,
        and(s, and(s, finite(x), finite(y)), finite(z)),
        and(
            s,
            and(s, F::vle(s, c(lo), m), F::vle(s, m, c(hi))),
            F::vlt(s, F::vmul(s, c(F::lit(64.0) * F::EPSILON), m), d),
        ),
    )
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;
    use pulp::Simd;

    use super::super::fixture::{PerWidth, Scene, chunks, every_width, lanes_of, load, scenes};
    use super::*;

    /// Every lane agrees with the scalar test, and whatever it clears `Geometry::new` accepts;
    /// on the fixture's exits plus non-finite, zero, tiny, huge and grazing ones.
    struct Check<F: Real>(Vec<Scene<F>>);

    impl<F: Real> PerWidth for Check<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for sc in &self.0 {
                let mut e = sc.exits.clone();
                let big = F::MAX / F::lit(2.0);
                for v in [
                    Vector3::new(F::lit(f64::NAN), F::zero(), F::one()),
                    Vector3::new(F::zero(), F::zero(), F::lit(f64::INFINITY)),
                    Vector3::zeros(),
                    Vector3::new(F::zero(), F::zero(), F::MIN_POSITIVE),
                    Vector3::new(F::zero(), F::zero(), big),
                    Vector3::new(F::one(), F::zero(), F::EPSILON),
                    Vector3::new(F::one(), F::zero(), F::lit(100.0) * F::EPSILON),
                    Vector3::new(F::one(), F::zero(), -F::one()),
                ] {
                    e.push(v);
                }
                chunks::<S, F>(e.len(), |i, len| {
                    let col = |k: usize| -> Vec<F> { e[i..i + len].iter().map(|v| v[k]).collect() };
                    let (x, y, z) = (col(0), col(1), col(2));
                    let m = clearly_valid_lanes::<S, F>(
                        s,
                        &sc.prep,
                        load::<S, F>(s, &x),
                        load::<S, F>(s, &y),
                        load::<S, F>(s, &z),
                    );
                    let ones = F::vselect(s, m, F::vlit(s, 1.0), F::vlit(s, 0.0));
                    let got = lanes_of::<S, F>(s, ones);
                    for l in 0..len {
                        let want = clearly_valid(&sc.prep, x[l], y[l], z[l]);
                        assert_eq!(got[l] == F::one(), want, "{what}: exit {}", i + l);
                        if want {
                            assert!(sc.prep.check_exact(e[i + l]).is_ok(), "{what}: {}", i + l);
                        }
                    }
                });
            }
        }
    }

    #[test]
    fn lanes_match_the_scalar_test_at_every_width() {
        every_width(&Check(scenes::<f64>()));
        every_width(&Check(scenes::<f32>()));
    }
}
