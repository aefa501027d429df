//! A batch of backward vertices ([`super::Material::incident_vertices`]): every lane its own
//! shading point, exit, light direction and random numbers, as a wavefront renderer's paths
//! are — [`super::Material::incident_vertex`] for each, with the two evaluations of every
//! vertex (the light's value and the drawn direction's weight) done together in SIMD lanes.
//!
//! # What runs where
//! Per lane, one at a time: the backward sampler's build, its density of the light's
//! direction, the draw, and the geometries (as `incident_vertex`). Then, for all lanes at
//! once, the Mueller matrices of every (light, exit) and (drawn direction, exit) pair:
//! [`crate::interaction::Kernel::evaluate_pairs_mueller`] in the lanes' own shading frames
//! (the directions taken to local coordinates, where the s/p frames and so the matrices are
//! the same up to rounding), each pair's coherence width by the horizon rule, the coherent
//! lobe divided by its mass where it is not 0 (a zero stays zero). A drawn direction's weight
//! is `M/p` from that matrix. A Dirac lobe's draw, and every lane of a material with a
//! transmission side or a kernel the pairs do not run in lanes (the Kirchhoff series, a
//! mixture PSD, a quadrature blur, a plane wave), take `incident_vertex`'s own path.
//!
//! # Agreement
//! The directions, densities, lobes, geometries, attenuations and errors are
//! `incident_vertex`'s bit for bit (the same scalar code). The values and weights are those of
//! the lane's local coordinates: each equals the one-at-a-time evaluation
//! ([`super::Material::eval_incident`] in the frame of the unit axes, at the local directions)
//! within the batch kernel's bound of `M₀₀` ([`crate::interaction::Kernel::evaluate_batch`];
//! the `1/E` and `1/p` add `8 ε M₀₀`). Where the scale of a part alone underflows, the part is
//! 0 (the scalar BSDF form's rule, which the lanes follow); the lanes' scale and the
//! one-at-a-time scale round differently, so near the smallest normal number either may be 0
//! where the other is not (below `10⁴ MIN_POSITIVE`). Against `incident_vertex` in world
//! coordinates they also carry the kernel's conditioning under the rounding of that rotation
//! (a few `ε` per direction): negligible except in a narrow specular lobe near the horizon,
//! where `M` changes by `√(2E) δ √(2π p/cos θ_i)` relatively for a direction moved by `δ`
//! (`E` the sample's exponent in the lobe, `p` its density) — measured up to 3·10⁻¹¹ in `f64`
//! and 1·10⁻² in `f32` at `cos θ_i ≈ 0.01`, `p ≈ 10⁷ sr⁻¹` (`tests/bsdf/vertices.rs`). A lane
//! whose local direction to the source rounds below the surface (within `ε` of it) goes one at
//! a time.

use nalgebra::{Matrix4, Vector3};

use super::vertex::{IncidentVertex, LightEval, MuellerSample, SideFn, VertexQuery, to_mueller};
use super::{Bsdf, BsdfKernel, BsdfSample, BsdfSurface, BsdfValue, SurfaceCoherence};
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::Geometry;
use crate::interaction::batch::{DirectionsSoa, MuellerLobesSoa, MuellerSoa, PairsSoa};
use crate::interaction::polarization::{
    MuellerResponse, PolarizationModel, Throughput, ln_attenuation,
};
use crate::mueller::Mueller;
use crate::numerics::unit_direction;
use crate::psd::Psd;
use crate::real::Real;

/// Lanes per pass (two pairs each: the light's and the drawn direction's); the buffers live on
/// the stack.
pub(super) const LANES: usize = 64;

/// What one lane asks of the pairs.
#[derive(Clone, Copy)]
enum Ask<T: Real> {
    /// Nothing (no light, or answered one at a time).
    None,
    /// The pair at this index, with the geometry of the world frame.
    Pair(usize, Geometry<T>),
}

/// One lane between the passes.
struct Lane<T: Real> {
    light: Ask<T>,
    light_pdf: T,
    /// The light's value answered one at a time (an error, or no lanes).
    light_done: Option<Result<LightEval<T>, Error>>,
    sample: Ask<T>,
    drawn: Option<super::DirectionSample<T>>,
    /// The vertex answered one at a time (an error of the sampler, a Dirac draw's weight).
    done: Option<Result<Option<MuellerSample<T>>, Error>>,
    /// The whole vertex one at a time (a local direction rounded below the surface).
    alone: bool,
}

/// The pairs of one pass, in the lanes' local coordinates: direction to the source, exit, `1/w`.
struct Pairs<T> {
    s: [[T; 2 * LANES]; 3],
    r: [[T; 2 * LANES]; 3],
    inv_w: [T; 2 * LANES],
    n: usize,
}

/// `d` in the coordinates of `f`.
fn local<T: Real>(f: &Frame<T>, d: &Vector3<T>) -> Vector3<T> {
    Vector3::new(d.dot(&f.x()), d.dot(&f.y()), d.dot(&f.k()))
}

impl<'m, T, S, K> Bsdf<'m, T, S, K>
where
    T: Real,
    S: BsdfSurface<T>,
    K: BsdfKernel<T, S::Psd>,
{
    /// The checks and geometry of `eval_incident` (`prepare_surface` then `eval`) for light
    /// from `to_source` leaving along `exit`, in its order: the unit direction to the source and
    /// its wavenumber, then the unit exit and the geometry.
    fn incident_geometry(
        &self,
        to_source: &Vector3<T>,
        exit: &Vector3<T>,
        what: &'static str,
    ) -> Result<Geometry<T>, Error> {
        let s = unit_direction(to_source, what)?;
        let k = self.wavenumber(&s)?;
        let r = unit_direction(exit, "exit direction")?;
        self.geometry_at(k, &s, &r)
    }

    /// Adds the pair `(s, r)` (world coordinates, any length, checked: `s` above an opaque
    /// surface) to `pairs` in `f`'s local coordinates, with the coherence width
    /// `prepare_surface` gives the local `s` in this (the local) frame: the inputs of
    /// [`super::Material::eval_incident`] at the local directions, bit for bit; returns its
    /// index.
    fn push_pair(
        &self,
        pairs: &mut Pairs<T>,
        coherence: &SurfaceCoherence<T>,
        f: &Frame<T>,
        (s, r): (&Vector3<T>, &Vector3<T>),
    ) -> Result<usize, Error> {
        let sl = unit_direction(&local(f, s), "direction to the source")?.into_inner();
        let rl = local(f, r);
        let i = pairs.n;
        for c in 0..3 {
            pairs.s[c][i] = sl[c];
            pairs.r[c][i] = rl[c];
        }
        let k = self.wavenumber(&sl)?;
        let w = self.width_of(&sl, k, coherence);
        pairs.inv_w[i] = w.recip();
        pairs.n += 1;
        Ok(i)
    }

    /// The coherent lobe's mass for pair `i` of `pairs` (local coordinates, this the local
    /// frame), as `prepare_surface` has it.
    fn pair_mass(&self, pairs: &Pairs<T>, i: usize) -> T {
        let sl = Vector3::new(pairs.s[0][i], pairs.s[1][i], pairs.s[2][i]);
        let prepared = self
            .kernel
            .kernel()
            .prepare_unpolarized_isotropic(self.k[0], pairs.inv_w[i]);
        let facing = self.surface.facing(&sl);
        self.specular_mass(&prepared, &sl, &facing, false, [true, false])[0]
    }
}

/// `incident_vertex` for every query (module docs): the vertices into `out[..queries.len()]`,
/// each lane's frame flipped by `side` first (a two-sided material's exit below).
pub(super) fn incident_vertices<T, S, K>(
    surface: &S,
    kernel: &K,
    side: &SideFn<'_, T>,
    coherence: &SurfaceCoherence<T>,
    queries: &[VertexQuery<T>],
    out: &mut [Result<IncidentVertex<T>, Error>],
) where
    T: Real,
    S: BsdfSurface<T>,
    K: BsdfKernel<T, S::Psd>,
{
    let identity = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).expect("the unit axes");
    for (qs, os) in queries.chunks(LANES).zip(out.chunks_mut(LANES)) {
        // Lanes of one wavelength at a time.
        let mut start = 0;
        while start < qs.len() {
            let lambda = qs[start].at.wavelength();
            // (At least one: a shading point's wavelength is finite, so equals itself.)
            let len = qs[start..]
                .iter()
                .take_while(|q| q.at.wavelength() == lambda)
                .count()
                .max(1);
            let range = start..start + len;
            pass(
                (surface, kernel, side, &identity),
                coherence,
                &qs[range.clone()],
                &mut os[range],
            );
            start += len;
        }
    }
}

/// One pass of [`incident_vertices`] over at most [`LANES`] queries of one wavelength.
fn pass<T, S, K>(
    (surface, kernel, side, identity): (&S, &K, &SideFn<'_, T>, &Frame<T>),
    coherence: &SurfaceCoherence<T>,
    queries: &[VertexQuery<T>],
    out: &mut [Result<IncidentVertex<T>, Error>],
) where
    T: Real,
    S: BsdfSurface<T>,
    K: BsdfKernel<T, S::Psd>,
{
    let mut pairs = Pairs {
        s: [[T::zero(); 2 * LANES]; 3],
        r: [[T::zero(); 2 * LANES]; 3],
        inv_w: [T::zero(); 2 * LANES],
        n: 0,
    };
    let vertex = |q: &VertexQuery<T>| -> Result<IncidentVertex<T>, Error> {
        let at = side(&q.at, &q.exit);
        let b = Bsdf::new(surface, kernel.clone(), *at.frame(), at.wavelength())?;
        let value = q.to_light.map(|d| {
            b.eval(&b.prepare_surface(d, coherence)?, q.exit)
                .map(to_mueller)
        });
        let sampler = b.incident_sampler(q.exit, coherence)?;
        let pdf = q.to_light.map_or(T::zero(), |d| sampler.pdf(&d));
        let sample = match sampler.sample(q.u_lobe, q.u) {
            Some(s) => {
                let (w, g) = b.incident_weight(q.exit, coherence, &s)?;
                Some(BsdfSample {
                    sample: s,
                    weight: w.to_mueller(),
                    geometry: g,
                })
            }
            None => None,
        };
        Ok(IncidentVertex {
            light: value.map(|v| v.map(|value| LightEval { value, pdf })),
            sample,
        })
    };
    let each_alone = |out: &mut [Result<IncidentVertex<T>, Error>]| {
        for (q, o) in queries.iter().zip(out.iter_mut()) {
            *o = vertex(q);
        }
    };
    // An unusable wavelength (every lane gives its own error), a transmission side or a
    // kernel the pairs do not run in lanes: lane by lane.
    let first = Bsdf::new(
        surface,
        kernel.clone(),
        *identity,
        queries[0].at.wavelength(),
    );
    let Some(first) = first
        .ok()
        .filter(|b| b.eta.is_none() && b.kernel.kernel().pairs_in_lanes(surface.parts()))
    else {
        each_alone(out);
        return;
    };
    // Pass 1, lane by lane: the sampler, the light's density, the draw, the checks and
    // geometries; the pairs to evaluate.
    let mut lanes: [Option<Lane<T>>; LANES] = [const { None }; LANES];
    for (q, lane) in queries.iter().zip(lanes.iter_mut()) {
        let mut l = Lane {
            light: Ask::None,
            light_pdf: T::zero(),
            light_done: None,
            sample: Ask::None,
            drawn: None,
            done: None,
            alone: false,
        };
        let at = side(&q.at, &q.exit);
        let b = match Bsdf::new(surface, kernel.clone(), *at.frame(), at.wavelength()) {
            Ok(b) => b,
            Err(e) => {
                l.done = Some(Err(e));
                *lane = Some(l);
                continue;
            }
        };
        if let Some(d) = q.to_light {
            match b.incident_geometry(&d, &q.exit, "direction to the source") {
                Ok(g) => match first.push_pair(&mut pairs, coherence, &b.surface, (&d, &q.exit)) {
                    Ok(i) => l.light = Ask::Pair(i, g),
                    Err(_) => l.alone = true,
                },
                Err(e) => l.light_done = Some(Err(e)),
            }
        }
        match b.incident_sampler(q.exit, coherence) {
            Err(e) => l.done = Some(Err(e)),
            Ok(sampler) => {
                if let Some(d) = &q.to_light {
                    l.light_pdf = sampler.pdf(d);
                }
                match sampler.sample(q.u_lobe, q.u) {
                    None => l.done = Some(Ok(None)),
                    Some(s) if s.lobe.delta => {
                        l.done = Some(b.incident_weight(q.exit, coherence, &s).map(|(w, g)| {
                            Some(BsdfSample {
                                sample: s,
                                weight: w.to_mueller(),
                                geometry: g,
                            })
                        }));
                    }
                    Some(s) => {
                        match b.incident_geometry(&s.direction, &q.exit, "sampled direction") {
                            Ok(g) => {
                                let (f, d) = (&b.surface, &s.direction);
                                match first.push_pair(&mut pairs, coherence, f, (d, &q.exit)) {
                                    Ok(i) => {
                                        l.sample = Ask::Pair(i, g);
                                        l.drawn = Some(s);
                                    }
                                    Err(_) => l.alone = true,
                                }
                            }
                            Err(e) => l.done = Some(Err(e)),
                        }
                    }
                }
            }
        }
        *lane = Some(l);
    }
    // Pass 2: every pair's Mueller matrices in lanes.
    let n = pairs.n;
    let mut m = [[T::zero(); 2 * LANES]; 32];
    if n > 0 {
        let (sp, sc) = m.split_at_mut(16);
        let mut sp = sp.iter_mut().map(|c| &mut c[..n]);
        let mut sc = sc.iter_mut().map(|c| &mut c[..n]);
        let mut lobes = MuellerLobesSoa {
            specular: MuellerSoa {
                m: core::array::from_fn(|_| sp.next().expect("16 columns")),
            },
            scattered: MuellerSoa {
                m: core::array::from_fn(|_| sc.next().expect("16 columns")),
            },
        };
        fn dirs<T>(d: &[[T; 2 * LANES]; 3], n: usize) -> DirectionsSoa<'_, T> {
            DirectionsSoa {
                x: &d[0][..n],
                y: &d[1][..n],
                z: &d[2][..n],
            }
        }
        let p = PairsSoa {
            to_source: dirs(&pairs.s, n),
            exit: dirs(&pairs.r, n),
            inverse_width: &pairs.inv_w[..n],
        };
        let done = first.kernel.kernel().evaluate_pairs_mueller(
            surface.parts(),
            first.k[0],
            identity,
            p,
            &mut lobes,
            None,
        );
        if done.is_err() {
            // Not expected (every pair was checked in its own frame): each lane alone.
            each_alone(out);
            return;
        }
    }
    // Pass 3: the values and weights.
    let variance = surface.parts().psd.variance();
    let response = |i: usize, g: &Geometry<T>| {
        let matrix = |base: usize| Mueller(Matrix4::from_fn(|r, c| m[base + 4 * r + c][i]));
        let from = <<K::Pol as PolarizationModel>::Throughput<T> as Throughput<T>>::from_mueller;
        let r = MuellerResponse {
            specular: from(&matrix(0)),
            scattered: from(&matrix(16)),
            attenuation: ln_attenuation(variance, g).exp(),
            side: g.side(),
        };
        // The coherent lobe over its mass where it is not 0 (a zero stays zero under the
        // positive finite `1/E`; the mass costs a quadrature near grazing).
        if (0..16).all(|e| m[e][i] == T::zero()) {
            return r;
        }
        let mass = first.pair_mass(&pairs, i);
        if mass == T::one() {
            r
        } else {
            r.specular_scaled(mass.recip())
        }
    };
    for ((q, lane), o) in queries.iter().zip(lanes.iter_mut()).zip(out.iter_mut()) {
        let l = lane.take().expect("every lane");
        if l.alone {
            *o = vertex(q);
            continue;
        }
        let light = match (l.light_done, l.light) {
            (Some(r), _) => Some(r),
            (None, Ask::Pair(i, g)) => {
                let r = response(i, &g);
                Some(Ok(LightEval {
                    value: to_mueller(BsdfValue {
                        response: r,
                        geometry: g,
                    }),
                    pdf: l.light_pdf,
                }))
            }
            (None, Ask::None) => None,
        };
        let sample = match (l.done, l.sample, l.drawn) {
            (Some(Err(e)), _, _) => {
                *o = Err(e);
                continue;
            }
            (Some(Ok(s)), _, _) => s,
            (None, Ask::Pair(i, g), Some(s)) => {
                let w = response(i, &g).total().scaled(T::one() / s.pdf).flushed();
                Some(BsdfSample {
                    sample: s,
                    weight: w.to_mueller(),
                    geometry: g,
                })
            }
            _ => None,
        };
        *o = Ok(IncidentVertex { light, sample });
    }
}
