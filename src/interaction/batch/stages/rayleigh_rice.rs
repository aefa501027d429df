//! The Rayleigh–Rice factors `ss, ps, sp, pp` in lanes, as `RayleighRice::factors` (the
//! per-packet part — `q_i`, `ε − 1`, `D₁`, `D₃` — precomputed), in `num_complex`'s order and
//! without fused multiply–adds: Germer's reflection factors ([`factors`]) and Elson's
//! transmission factors at a dielectric interface ([`transmission_factors`]).

use pulp::Simd;

use super::super::prep::{Incidence, TransmissionConsts};
use crate::real::Real;
use crate::simd::complex::{C, Cx};

/// The per-packet terms of the reflection factors that depend on the incident direction
/// (`sin²θ_i`, `q_i`, `D₁/t`, `D₃/t²`, `−(ε − 1)/t² · q_i/t` of [`Incidence`]), as vectors:
/// splatted from one incidence ([`incident_terms`]), or one per lane (the per-lane pass,
/// `batch::per_lane`).
#[derive(Clone, Copy)]
pub(crate) struct IncidentTerms<V> {
    pub(crate) si2: V,
    pub(crate) qi: C<V>,
    pub(crate) d1s: C<V>,
    pub(crate) d3s: C<V>,
    pub(crate) neg_em1s_qis: C<V>,
}

/// The [`IncidentTerms`] of `p` on every lane.
#[inline(always)]
pub(crate) fn incident_terms<S: Simd, F: Real>(s: S, p: &Incidence<F>) -> IncidentTerms<F::V<S>> {
    let cx = Cx(s);
    IncidentTerms {
        si2: F::vsplat(s, p.si2),
        qi: cx.splat::<F>(p.qi),
        d1s: cx.splat::<F>(p.d1s),
        d3s: cx.splat::<F>(p.d3s),
        neg_em1s_qis: cx.splat::<F>(p.neg_em1s_qis),
    }
}

/// `[ss, ps, sp, pp]` at `cos θ_o`, `sin²θ_o`, `q_o` and the azimuth `(cos φ, sin φ)`.
#[inline(always)]
pub(crate) fn factors<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    cos_o: F::V<S>,
    so2: F::V<S>,
    qo: C<F::V<S>>,
    azimuth: (F::V<S>, F::V<S>),
) -> [C<F::V<S>>; 4] {
    let terms = incident_terms::<S, F>(s, p);
    factors_with::<S, F>(s, p, &terms, cos_o, so2, qo, azimuth)
}

/// [`factors`] with the incident direction's terms given per lane (`terms`); `ε` and the scale
/// are `p`'s.
#[inline(always)]
pub(crate) fn factors_with<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    terms: &IncidentTerms<F::V<S>>,
    cos_o: F::V<S>,
    so2: F::V<S>,
    qo: C<F::V<S>>,
    (cos_phi, sin_phi): (F::V<S>, F::V<S>),
) -> [C<F::V<S>>; 4] {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let cx = Cx(s);
    let e = cx.splat::<F>(p.e);
    let (inv, inv2) = (c(p.scale.inv), c(p.scale.inv2));
    let (d1s, d3s) = (terms.d1s, terms.d3s);
    let d2 = C {
        re: add(s, qo.re, cos_o),
        im: qo.im,
    };
    let d4 = C {
        re: add(s, mul(s, c(p.e.re), cos_o), qo.re),
        im: add(s, mul(s, c(p.e.im), cos_o), qo.im),
    };
    let (d2s, d4s) = (cx.scale::<F>(d2, inv), cx.scale::<F>(d4, inv2));
    let inv_ss = cx.recip::<F>(cx.mul::<F>(d1s, d2s));
    let inv_pp = cx.recip::<F>(cx.mul::<F>(d3s, d4s));
    let both = cx.mul::<F>(inv_ss, inv_pp);
    let em1s = cx.splat::<F>(p.em1s);
    let ss = cx.scale::<F>(cx.mul::<F>(em1s, inv_ss), cos_phi);
    let sq = F::vsqrt(s, mul(s, terms.si2, so2));
    let qoqi = cx.scale::<F>(cx.mul::<F>(qo, terms.qi), cos_phi);
    let es = cx.scale::<F>(e, sq);
    let inner = C {
        re: sub(s, es.re, qoqi.re),
        im: sub(s, es.im, qoqi.im),
    };
    let pp = cx.mul::<F>(cx.mul::<F>(em1s, cx.scale::<F>(inner, inv2)), inv_pp);
    let ps = cx.scale::<F>(
        cx.mul::<F>(terms.neg_em1s_qis, cx.mul::<F>(cx.mul::<F>(d1s, d4s), both)),
        sin_phi,
    );
    let sp = cx.scale::<F>(
        cx.mul::<F>(
            cx.mul::<F>(cx.splat::<F>(p.neg_em1s), cx.scale::<F>(qo, inv)),
            cx.mul::<F>(cx.mul::<F>(d2s, d3s), both),
        ),
        sin_phi,
    );
    [ss, ps, sp, pp]
}

/// `[ss, ps, sp, pp]` of Elson's transmission factors (`RayleighRice::factors` on the
/// transmission side, for a real permittivity `ε` seen from the source) at `cos θ_o`, measured
/// in the exit medium, and the azimuth `(cos φ, sin φ)`: with `κ = η sin θ_o`,
/// `q_o = η cos θ_o` and `a_o = √(1 − ε sin²θ_o)` (`+i√(ε sin²θ_o − 1)` for an exit evanescent
/// in the medium of incidence),
/// ```text
/// ss = (ε−1) cos φ / (D₁D₂),                 D₂ = q_o + a_o
/// pp = (ε−1) η (q_i a_o cos φ + κ sin θ_i) / (D₃D₄),   D₄ = q_o + ε a_o
/// ps = −(ε−1) q_i sin φ / (D₃D₂)
/// sp = (ε−1) η a_o sin φ / (D₁D₄)
/// ```
/// in the scalar's order of operations (bit for bit).
#[inline(always)]
pub(crate) fn transmission_factors<S: Simd, F: Real>(
    s: S,
    p: &Incidence<F>,
    t: &TransmissionConsts<F>,
    cos_o: F::V<S>,
    (cos_phi, sin_phi): (F::V<S>, F::V<S>),
) -> [C<F::V<S>>; 4] {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let cx = Cx(s);
    let zero = c(F::zero());
    let half = c(F::lit(0.5));
    let index = cx.splat::<F>(t.index);
    let so = F::vsqrt(
        s,
        F::vmax(s, sub(s, c(F::one()), mul(s, cos_o, cos_o)), zero),
    );
    let kappa = cx.scale::<F>(index, so);
    let qo = cx.scale::<F>(index, cos_o);
    // a_o = principal_sqrt(1 − ε so²) with Im = +0 (ε real): |a| is the modulus exactly, as
    // the scalar hypot(a, 0) on either branch.
    let a = sub(s, c(F::one()), mul(s, c(p.e.re), mul(s, so, so)));
    let abs_a = F::vabs(s, a);
    let nonneg = F::vle(s, zero, a);
    let ao = C {
        re: F::vselect(s, nonneg, F::vsqrt(s, mul(s, add(s, abs_a, a), half)), zero),
        im: F::vselect(s, nonneg, zero, F::vsqrt(s, mul(s, sub(s, abs_a, a), half))),
    };
    let e = cx.splat::<F>(p.e);
    let em1s = cx.splat::<F>(p.em1s);
    let (inv, inv2, inv3) = (c(p.scale.inv), c(p.scale.inv2), c(p.scale.inv3));
    let (d1s, d3s) = (cx.splat::<F>(p.d1s), cx.splat::<F>(p.d3s));
    let sum = |a: C<F::V<S>>, b: C<F::V<S>>| C {
        re: add(s, a.re, b.re),
        im: add(s, a.im, b.im),
    };
    let d2s = cx.scale::<F>(sum(qo, ao), inv);
    let d4s = cx.scale::<F>(sum(qo, cx.mul::<F>(e, ao)), inv3);
    let ss = cx.mul::<F>(
        cx.scale::<F>(em1s, cos_phi),
        cx.recip::<F>(cx.mul::<F>(d1s, d2s)),
    );
    let em1_index = cx.mul::<F>(em1s, cx.splat::<F>(t.index_s));
    let qi_ao = cx.scale::<F>(cx.mul::<F>(cx.splat::<F>(p.qi), ao), cos_phi);
    let inner = cx.scale::<F>(sum(qi_ao, cx.scale::<F>(kappa, c(t.sin_i))), inv2);
    let pp = cx.mul::<F>(
        cx.mul::<F>(em1_index, inner),
        cx.recip::<F>(cx.mul::<F>(d3s, d4s)),
    );
    let ps = cx.mul::<F>(
        cx.scale::<F>(cx.splat::<F>(p.neg_em1s_qis), sin_phi),
        cx.recip::<F>(cx.mul::<F>(d3s, d2s)),
    );
    let sp = cx.mul::<F>(
        cx.scale::<F>(cx.mul::<F>(em1_index, cx.scale::<F>(ao, inv)), sin_phi),
        cx.recip::<F>(cx.mul::<F>(d1s, d4s)),
    );
    [ss, ps, sp, pp]
}

#[cfg(test)]
mod tests {
    use num_complex::Complex;

    use crate::numerics::principal_sqrt;
    use pulp::Simd;

    use nalgebra::Vector3;

    use super::super::fixture::{
        PerWidth, Scene, chunks, every_width, lanes_of, load, same, scenes, seeded_exits,
    };
    use super::*;
    use crate::frame::Frame;
    use crate::interaction::pbsdf::RayleighRice;
    use crate::interaction::{Geometry, Side};
    use crate::packet::{CoherenceShape, WavePacket};
    use crate::stokes::Stokes;

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

    /// A packet through a glass interface (from above or from below) and exits on the
    /// transmission side with their scalar geometries.
    struct Crossing<F: Real> {
        inc: Incidence<F>,
        consts: TransmissionConsts<F>,
        scatter: RayleighRice<F>,
        geometries: Vec<Geometry<F>>,
    }

    /// Glass (η = 1.5, 1.33) and a high index (η = 2.4), lit from the air and from inside, at
    /// normal, oblique and grazing incidence; the exits cover the Snell direction, the normal
    /// and (from the air) the directions beyond the critical angle, where `a_o` is imaginary.
    fn crossings<F: Real>() -> Vec<Crossing<F>> {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let mut out = Vec::new();
        for eta in [1.5, 1.33, 2.4] {
            for (theta_i, below) in [
                (0.0_f64, false),
                (0.7, false),
                (1.5, false),
                (0.4, true),
                (0.9, true),
            ] {
                let scatter = RayleighRice::new(Complex::new(F::lit(eta), F::zero())).unwrap();
                let seen = scatter.permittivity_seen(below);
                let up = if below { -1.0 } else { 1.0 };
                let to_source = Vector3::new(-theta_i.sin(), 0.0, up * theta_i.cos()).map(F::lit);
                let oriented = if below { surface.reversed() } else { surface };
                let packet = WavePacket::from_stokes(
                    Stokes::new(F::one(), F::zero(), F::zero(), F::zero()).unwrap(),
                    CoherenceShape::isotropic(F::lit(5.0)).unwrap(),
                    Frame::sp(-to_source, oriented.k()).unwrap(),
                    F::lit(0.5),
                )
                .unwrap();
                let inc = Incidence::new(seen, &packet, &oriented).unwrap();
                let k = packet.wavenumber();
                let geometries = seeded_exits(theta_i, 61, 1.55)
                    .into_iter()
                    .map(|r| {
                        let exit = Vector3::new(r.x, r.y, -up * r.z).map(F::lit);
                        // From the packet's own direction, as the kernel builds both.
                        let from = -packet.direction();
                        let g =
                            Geometry::at_interface(k, &surface, F::lit(eta), from, exit).unwrap();
                        assert_eq!(g.side(), Side::Transmission);
                        assert_eq!(g.incident_from_below(), below);
                        assert!(same(g.cos_i(), inc.cos_i));
                        g
                    })
                    .collect::<Vec<_>>();
                // From the air, exits beyond the critical angle (imaginary a_o) are among them.
                let evanescent = geometries.iter().filter(|g| {
                    let so2 = 1.0 - g.cos_o().to_f64().powi(2);
                    eta * eta * so2 > 1.0
                });
                assert!(below || evanescent.count() > 5);
                out.push(Crossing {
                    consts: TransmissionConsts::new(&inc).unwrap(),
                    inc,
                    scatter,
                    geometries,
                });
            }
        }
        out
    }

    /// The four transmission factors bit for bit `RayleighRice::factors` of
    /// `Geometry::at_interface`, from the scalar `cos θ_o` and azimuth.
    struct CheckTransmission<F: Real>(Vec<Crossing<F>>);

    impl<F: Real> PerWidth for CheckTransmission<F> {
        fn run<S: Simd>(&self, s: S, what: &str) {
            for (n, sc) in self.0.iter().enumerate() {
                let g = &sc.geometries;
                chunks::<S, F>(g.len(), |i, len| {
                    let l = |f: &dyn Fn(&Geometry<F>) -> F| {
                        let v: Vec<F> = g[i..i + len].iter().map(f).collect();
                        load::<S, F>(s, &v)
                    };
                    let f = transmission_factors::<S, F>(
                        s,
                        &sc.inc,
                        &sc.consts,
                        l(&|g| g.cos_o()),
                        (l(&|g| g.exit_azimuth().0), l(&|g| g.exit_azimuth().1)),
                    );
                    for (k, z) in f.iter().enumerate() {
                        let (re, im) = (lanes_of::<S, F>(s, z.re), lanes_of::<S, F>(s, z.im));
                        for j in 0..len {
                            let want = sc.scatter.factors(&g[i + j])[(k / 2, k % 2)];
                            assert!(
                                same(re[j], want.re) && same(im[j], want.im),
                                "{what}: crossing {n}, exit {}, factor {k}: {} {} vs {want}",
                                i + j,
                                re[j].to_f64(),
                                im[j].to_f64()
                            );
                        }
                    }
                });
            }
        }
    }

    #[test]
    fn lanes_match_transmission_factors_bit_for_bit_at_every_width() {
        every_width(&CheckTransmission(crossings::<f64>()));
        every_width(&CheckTransmission(crossings::<f32>()));
    }

    /// Only a real permittivity has transmission lanes.
    #[test]
    fn transmission_constants_need_a_real_permittivity() {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let packet = WavePacket::from_stokes(
            Stokes::new(1.0, 0.0, 0.0, 0.0).unwrap(),
            CoherenceShape::isotropic(5.0).unwrap(),
            Frame::sp(Vector3::new(0.3, 0.0, -1.0).normalize(), Vector3::z()).unwrap(),
            0.5,
        )
        .unwrap();
        let at = |e: Complex<f64>| Incidence::new(e, &packet, &surface).unwrap();
        assert!(TransmissionConsts::new(&at(Complex::new(2.25, 0.0))).is_some());
        assert!(TransmissionConsts::new(&at(Complex::new(2.25, 1e-3))).is_none());
    }
}
