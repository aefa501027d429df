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
//! exponent and the Fresnel matrix with the specular frame (a `prep::lane_row` per lane).
//! Everything else (the wavenumber, the permittivity and its scale, the PSD's variance, the
//! level, the effective vector) is read from one `LobePrep` of the same kernel, material,
//! wavenumber and surface, the same for every pair of a call.

use pulp::Simd;

use super::prep::{LANE_FIELDS, LobePrep};
use super::stages;
use super::stages::azimuth::AzimuthAxes;
use super::stages::channels::{LogGaussianLanes, log_gaussian_lanes};
use super::stages::rayleigh_rice::{IncidentTerms, incident_terms};
use super::stages::specular::SpecularLanes;
use crate::real::Real;
use crate::simd::complex::C;

/// The per-packet constants the lobe lanes may read per lane (module docs).
pub(crate) trait LaneConsts<S: Simd, F: Real> {
    /// ŝ, the unit direction to the source.
    fn to_source(&self, s: S) -> [F::V<S>; 3];
    /// `(n̂ × ŝ_in, n̂ × (n̂ × ŝ_in))`, the azimuth axes.
    fn azimuth_axes(&self, s: S) -> AzimuthAxes<F::V<S>>;
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
    fn azimuth_axes(&self, s: S) -> AzimuthAxes<F::V<S>> {
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
        let consts = (&self.fresnel, &self.spec_frame, self.flip_tol);
        stages::specular::fresnel_stokes::<S, F>(s, consts, r, s_out, v)
    }
}

/// The per-lane constants of one vector of lanes, lane `j` from `preps[j]` (a shorter slice
/// repeats its first element on the remaining lanes).
pub(crate) struct Gathered<S: Simd, F: Real> {
    pub(super) to_source: [F::V<S>; 3],
    pub(super) u_az: [F::V<S>; 3],
    pub(super) v_az: [F::V<S>; 3],
    pub(super) cos_i: F::V<S>,
    pub(super) terms: IncidentTerms<F::V<S>>,
    pub(super) spec: LogGaussianLanes<F::V<S>>,
    pub(super) scat: LogGaussianLanes<F::V<S>>,
    pub(super) ln_scat: F::V<S>,
    pub(super) specular: SpecularLanes<F::V<S>>,
    pub(super) flip_tol: F,
}

/// At most this many lanes in a vector (`f32` under AVX-512).
pub(crate) const MAX_LANES: usize = 16;

// The indices of `Gathered::new` are those of `prep::lane_row`'s 53 constants.
const _: () = assert!(LANE_FIELDS == 53);

impl<S: Simd, F: Real> Gathered<S, F> {
    /// The lanes' constants from their rows transposed, `cols[k][j]` constant `k` of
    /// `prep::lane_row` for lane `j` (every lane of the vector set), the constants the lanes
    /// share being `head`'s: a `LobePrep` of the same kernel, material, wavenumber and surface,
    /// of one shape and one PSD component, in reflection (not mirrored).
    #[inline(always)]
    pub(crate) fn new(head: &LobePrep<F>, cols: &[[F; MAX_LANES]; LANE_FIELDS]) -> Self {
        debug_assert!(
            !head.three && head.components == 1 && head.transmission.is_none() && !head.mirrored
        );
        let lanes = F::width::<S>();
        let v = |k: usize| F::vsplit::<S>(&cols[k][..lanes]).0[0];
        let v3 = |k: usize| [v(k), v(k + 1), v(k + 2)];
        let c = |k: usize| C {
            re: v(k),
            im: v(k + 1),
        };
        let lg = |k: usize| LogGaussianLanes {
            c: v(k),
            l00: v(k + 1),
            l10: v(k + 2),
            inv_l11: v(k + 3),
        };
        Self {
            to_source: v3(0),
            u_az: v3(3),
            v_az: v3(6),
            cos_i: v(9),
            terms: IncidentTerms {
                si2: v(10),
                qi: c(11),
                d1s: c(13),
                d3s: c(15),
                neg_em1s_qis: c(17),
            },
            spec: lg(19),
            scat: lg(23),
            ln_scat: v(27),
            specular: SpecularLanes {
                fresnel: [28, 32, 36, 40].map(|k| [v(k), v(k + 1), v(k + 2), v(k + 3)]),
                axes: [v3(44), v3(47), v3(50)],
            },
            flip_tol: head.flip_tol,
        }
    }
}

impl<S: Simd, F: Real> Gathered<S, F> {
    /// Lane `j`'s constants in `prep::lane_row`'s order, for every lane of the vector (the
    /// inverse of [`Gathered::new`]).
    #[cfg(test)]
    pub(crate) fn rows(&self, s: S) -> Vec<[F; LANE_FIELDS]> {
        let t = &self.terms;
        let (sp, sc, m, a) = (
            &self.spec,
            &self.scat,
            &self.specular.fresnel,
            &self.specular.axes,
        );
        let mut v = vec![];
        v.extend(self.to_source);
        v.extend(self.u_az);
        v.extend(self.v_az);
        v.extend([
            self.cos_i, t.si2, t.qi.re, t.qi.im, t.d1s.re, t.d1s.im, t.d3s.re,
        ]);
        v.extend([t.d3s.im, t.neg_em1s_qis.re, t.neg_em1s_qis.im]);
        v.extend([
            sp.c, sp.l00, sp.l10, sp.inv_l11, sc.c, sc.l00, sc.l10, sc.inv_l11,
        ]);
        v.push(self.ln_scat);
        v.extend(m.iter().flatten().copied());
        v.extend(a.iter().flatten().copied());
        assert_eq!(v.len(), LANE_FIELDS);
        let lanes = F::width::<S>();
        let mut rows = vec![[F::zero(); LANE_FIELDS]; lanes];
        let mut buf = [F::zero(); MAX_LANES];
        for (k, x) in v.into_iter().enumerate() {
            F::store_partial(s, &mut buf[..lanes], x);
            for (row, b) in rows.iter_mut().zip(&buf[..lanes]) {
                row[k] = *b;
            }
        }
        rows
    }
}

/// `p`'s per-lane constants (`prep::lane_row`), for a `LobePrep` built whole.
#[cfg(test)]
pub(crate) fn row_of<F: Real>(p: &LobePrep<F>) -> [F; LANE_FIELDS] {
    let (spec, scat) = (&p.spec[2], &p.scat[2][0]);
    super::prep::lane_row(&p.inc, (spec, scat), p.ln_scat, &p.fresnel, &p.spec_frame)
}

impl<S: Simd, F: Real> LaneConsts<S, F> for Gathered<S, F> {
    #[inline(always)]
    fn to_source(&self, _: S) -> [F::V<S>; 3] {
        self.to_source
    }
    #[inline(always)]
    fn azimuth_axes(&self, _: S) -> AzimuthAxes<F::V<S>> {
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
        self.specular.fresnel[0][0]
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
            (&self.specular, self.flip_tol),
            r,
            s_out,
            v,
        )
    }
}
