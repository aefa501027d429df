//! Where the lobe lanes ([`super::partial`]) read the per-packet constants that depend on the
//! incident direction: from one [`LobePrep`], the same on every lane (the batch over exits of
//! one packet), or one [`LobePrep`] per lane ([`Gathered`]: every lane its own incident
//! direction and exit, the per-lane pass of [`super::pairs`]).
//!
//! A [`LobePrep`] splats its constants where a stage reads them, as the stages did before this
//! trait; [`Gathered`] holds each constant as a vector, lane `j` from lane `j`'s `LobePrep`. The
//! stages' operations are the same in both, so a lane of the per-lane pass is bit for bit what
//! the batch over exits gives for the same `LobePrep` and exit.
//!
//! What a per-lane pass may vary is listed by the trait: the direction to the source, the
//! azimuth axes, `cos θ_i`, the Rayleigh–Rice factors' incident terms, the specular and
//! scattered channel weights' constants of the `½` channel, the scattered part's constant
//! exponent and the Fresnel matrix with the specular frame. Everything else (the wavenumber,
//! the permittivity and its scale, the PSD's variance, the level, the mixture's size, the
//! effective vector) is read from the first lane's `LobePrep`, and [`Gathered::new`] refuses
//! lanes on which it differs.

use pulp::Simd;

use super::partial::MAX_LANES;
use super::prep::LobePrep;
use super::stages;
use super::stages::channels::{LogGaussianLanes, log_gaussian_lanes};
use super::stages::rayleigh_rice::{IncidentTerms, incident_terms};
use crate::real::Real;
use crate::simd::complex::C;

/// The per-packet constants the lobe lanes may read per lane (module docs).
pub(crate) trait LaneConsts<S: Simd, F: Real> {
    /// ŝ, the unit direction to the source.
    fn to_source(&self, s: S) -> [F::V<S>; 3];
    /// `(n̂ × ŝ_in, n̂ × (n̂ × ŝ_in))`, the azimuth axes.
    fn azimuth_axes(&self, s: S) -> ([F::V<S>; 3], [F::V<S>; 3]);
    /// `cos θ_i`.
    fn cos_i(&self, s: S) -> F::V<S>;
    /// The incident terms of the reflection factors.
    fn terms(&self, s: S) -> IncidentTerms<F::V<S>>;
    /// `ln K^spec_½`'s constants.
    fn spec_half(&self, s: S) -> LogGaussianLanes<F::V<S>>;
    /// `ln K_½`'s constants (the PSD's only component).
    fn scat_half(&self, s: S) -> LogGaussianLanes<F::V<S>>;
    /// The scattered part's constant exponent in reflection (`LobePrep::ln_scat`).
    fn ln_scat(&self, s: S) -> F::V<S>;
    /// `M₀₀` of the Fresnel reflection matrix.
    fn fresnel_m00(&self, s: S) -> F::V<S>;
    /// The reflected specular Stokes vector before the projection onto the cone:
    /// [`stages::specular::fresnel_stokes`] with this packet's (or lane's) Fresnel matrix and
    /// specular frame.
    fn fresnel_stokes(
        &self,
        s: S,
        r: [F::V<S>; 3],
        s_out: [F::V<S>; 3],
        v: [F::V<S>; 4],
    ) -> [F::V<S>; 4];
}

impl<S: Simd, F: Real> LaneConsts<S, F> for LobePrep<F> {
    #[inline(always)]
    fn to_source(&self, s: S) -> [F::V<S>; 3] {
        stages::splat3::<S, F>(s, self.inc.s)
    }
    #[inline(always)]
    fn azimuth_axes(&self, s: S) -> ([F::V<S>; 3], [F::V<S>; 3]) {
        (
            stages::splat3::<S, F>(s, self.inc.u_az),
            stages::splat3::<S, F>(s, self.inc.v_az),
        )
    }
    #[inline(always)]
    fn cos_i(&self, s: S) -> F::V<S> {
        F::vsplat(s, self.inc.cos_i)
    }
    #[inline(always)]
    fn terms(&self, s: S) -> IncidentTerms<F::V<S>> {
        incident_terms::<S, F>(s, &self.inc)
    }
    #[inline(always)]
    fn spec_half(&self, s: S) -> LogGaussianLanes<F::V<S>> {
        log_gaussian_lanes::<S, F>(s, &self.spec[2])
    }
    #[inline(always)]
    fn scat_half(&self, s: S) -> LogGaussianLanes<F::V<S>> {
        log_gaussian_lanes::<S, F>(s, &self.scat[2][0])
    }
    #[inline(always)]
    fn ln_scat(&self, s: S) -> F::V<S> {
        F::vsplat(s, self.ln_scat)
    }
    #[inline(always)]
    fn fresnel_m00(&self, s: S) -> F::V<S> {
        F::vsplat(s, self.fresnel[(0, 0)])
    }
    #[inline(always)]
    fn fresnel_stokes(
        &self,
        s: S,
        r: [F::V<S>; 3],
        s_out: [F::V<S>; 3],
        v: [F::V<S>; 4],
    ) -> [F::V<S>; 4] {
        stages::specular::fresnel_stokes::<S, F>(
            s,
            (&self.fresnel, &self.spec_frame, self.flip_tol),
            r,
            s_out,
            v,
        )
    }
}

/// The per-lane constants of one vector of lanes, lane `j` from `preps[j]` (a shorter slice
/// repeats its first element on the remaining lanes).
pub(crate) struct Gathered<S: Simd, F: Real> {
    to_source: [F::V<S>; 3],
    u_az: [F::V<S>; 3],
    v_az: [F::V<S>; 3],
    cos_i: F::V<S>,
    terms: IncidentTerms<F::V<S>>,
    spec: LogGaussianLanes<F::V<S>>,
    scat: LogGaussianLanes<F::V<S>>,
    ln_scat: F::V<S>,
    fresnel: [[F::V<S>; 4]; 4],
    /// ŝ, p̂ and r̂ of the specular frame.
    spec_frame: [[F::V<S>; 3]; 3],
    flip_tol: F,
}


/// The number of per-lane constants ([`flat`]).
const FIELDS: usize = 53;

/// One lane's per-lane constants in the order [`Gathered::new`] reads them.
#[inline(always)]
fn flat<F: Real>(q: &LobePrep<F>) -> [F; FIELDS] {
    let i = &q.inc;
    let (sp, sc) = (&q.spec[2], &q.scat[2][0]);
    let m = &q.fresnel;
    let (fs, fp, fk) = (q.spec_frame.x(), q.spec_frame.y(), q.spec_frame.k());
    [
        i.s.x, i.s.y, i.s.z, i.u_az.x, i.u_az.y, i.u_az.z, i.v_az.x, i.v_az.y, i.v_az.z,
        i.cos_i, i.si2, i.qi.re, i.qi.im, i.d1s.re, i.d1s.im, i.d3s.re, i.d3s.im,
        i.neg_em1s_qis.re, i.neg_em1s_qis.im, sp.c, sp.l00, sp.l10, sp.inv_l11, sc.c, sc.l00,
        sc.l10, sc.inv_l11, q.ln_scat, m[(0, 0)], m[(0, 1)], m[(0, 2)], m[(0, 3)], m[(1, 0)],
        m[(1, 1)], m[(1, 2)], m[(1, 3)], m[(2, 0)], m[(2, 1)], m[(2, 2)], m[(2, 3)], m[(3, 0)],
        m[(3, 1)], m[(3, 2)], m[(3, 3)], fs.x, fs.y, fs.z, fp.x, fp.y, fp.z, fk.x, fk.y, fk.z,
    ]
}

impl<S: Simd, F: Real> Gathered<S, F> {
    /// The constants of `preps` (at least one, at most one vector's worth), or `None` where a
    /// lane's constants differ from the first lane's in what the lanes read from the first
    /// (module docs), or the first is outside what the per-lane pass runs (three channels, a
    /// mixture PSD, a transmission side, a mirrored PSD).
    #[inline(always)]
    pub(crate) fn new(preps: &[&LobePrep<F>]) -> Option<Self> {
        let p = *preps.first()?;
        let lanes = F::width::<S>();
        let uniform = |q: &&LobePrep<F>| {
            let (a, b) = (&p.inc, &q.inc);
            a.k == b.k
                && a.e == b.e
                && a.n == b.n
                && a.t1 == b.t1
                && a.t2 == b.t2
                && q.three == p.three
                && q.intensity == p.intensity
                && q.components == p.components
                && q.variance == p.variance
                && q.ln_spec == p.ln_spec
                && q.t_stokes == p.t_stokes
                && q.transmission.is_none()
                && !q.mirrored
        };
        if p.three || p.components != 1 || preps.len() > lanes || !preps.iter().all(uniform) {
            return None;
        }
        let mut rows = [[F::zero(); FIELDS]; MAX_LANES];
        for (j, row) in rows[..lanes].iter_mut().enumerate() {
            *row = flat(preps.get(j).unwrap_or(&p));
        }
        let mut k = 0;
        let mut next = || {
            let mut b = [F::zero(); MAX_LANES];
            for (v, row) in b[..lanes].iter_mut().zip(&rows) {
                *v = row[k];
            }
            k += 1;
            F::vsplit::<S>(&b[..lanes]).0[0]
        };
        let mut v3 = || [next(), next(), next()];
        let (to_source, u_az, v_az) = (v3(), v3(), v3());
        let (cos_i, si2) = (next(), next());
        let mut c = || C {
            re: next(),
            im: next(),
        };
        let terms = IncidentTerms {
            si2,
            qi: c(),
            d1s: c(),
            d3s: c(),
            neg_em1s_qis: c(),
        };
        let mut lg = || LogGaussianLanes {
            c: next(),
            l00: next(),
            l10: next(),
            inv_l11: next(),
        };
        let (spec, scat) = (lg(), lg());
        let ln_scat = next();
        let fresnel = [0; 4].map(|_| [next(), next(), next(), next()]);
        let spec_frame = [0; 3].map(|_| [next(), next(), next()]);
        debug_assert_eq!(k, FIELDS);
        Some(Self {
            to_source,
            u_az,
            v_az,
            cos_i,
            terms,
            spec,
            scat,
            ln_scat,
            fresnel,
            spec_frame,
            flip_tol: p.flip_tol,
        })
    }
}

impl<S: Simd, F: Real> LaneConsts<S, F> for Gathered<S, F> {
    #[inline(always)]
    fn to_source(&self, _: S) -> [F::V<S>; 3] {
        self.to_source
    }
    #[inline(always)]
    fn azimuth_axes(&self, _: S) -> ([F::V<S>; 3], [F::V<S>; 3]) {
        (self.u_az, self.v_az)
    }
    #[inline(always)]
    fn cos_i(&self, _: S) -> F::V<S> {
        self.cos_i
    }
    #[inline(always)]
    fn terms(&self, _: S) -> IncidentTerms<F::V<S>> {
        self.terms
    }
    #[inline(always)]
    fn spec_half(&self, _: S) -> LogGaussianLanes<F::V<S>> {
        self.spec
    }
    #[inline(always)]
    fn scat_half(&self, _: S) -> LogGaussianLanes<F::V<S>> {
        self.scat
    }
    #[inline(always)]
    fn ln_scat(&self, _: S) -> F::V<S> {
        self.ln_scat
    }
    #[inline(always)]
    fn fresnel_m00(&self, _: S) -> F::V<S> {
        self.fresnel[0][0]
    }
    #[inline(always)]
    fn fresnel_stokes(
        &self,
        s: S,
        r: [F::V<S>; 3],
        s_out: [F::V<S>; 3],
        v: [F::V<S>; 4],
    ) -> [F::V<S>; 4] {
        stages::specular::fresnel_stokes_with::<S, F>(
            s,
            (&self.fresnel, &self.spec_frame, self.flip_tol),
            r,
            s_out,
            v,
        )
    }
}
