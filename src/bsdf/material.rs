//! One material type a renderer can hold: [`Material`], a rough surface with its model level
//! chosen at run time, behind one object-safe interface.
//!
//! [`super::Bsdf`] is generic over the PSD, the two pBSDFs and the three model levels, so a
//! scene with several material kinds needs generic vertex code with the layer's trait bounds.
//! A [`Material`] owns its [`RoughSurface`](crate::interaction::RoughSurface) and the kernel
//! of its [`Level`] (and roughness level), monomorphised once when it is built
//! ([`Level::dispatch`], [`Level::dispatch_rough`]); a call costs one dynamic dispatch and then
//! runs the static [`super::Bsdf`] of that choice, so the answers are those of the static form
//! bit for bit (`tests/bsdf/material.rs`). Every throughput is a [`Mueller`] matrix: at the
//! intensity level the matrix with `M₀₀` alone ([`Throughput::to_mueller`]), which acts on `S0`
//! and leaves the light unpolarized.
//!
//! A call takes the shading point ([`ShadingPoint`]: frame and wavelength) and builds the
//! static [`super::Bsdf`] there (a few comparisons; no allocation). The methods are those of a
//! renderer's BSDF interface — eval, sample and pdf, forward (light to exit) and backward (exit
//! to light) — with the conventions of [`super::Bsdf`]: `exit` is r̂, the unit direction the
//! light leaves along (toward the camera in a backward tracer), `to_source` is ŝ, toward the
//! light; weights map the incident s/p frame to [`crate::interaction::Geometry::exit_sp`].
//!
//! # Two-sided opaque surfaces
//! An opaque material ([`Material::is_opaque`]: no transmission) is lit and seen from the side
//! its frame's normal points to; [`super::Bsdf`] refuses the other side. With
//! [`Material::two_sided`] the back reflects as the front does (Mitsuba's `twosided`): where
//! the direction the call starts from — `exit` for the backward calls, the light's direction
//! for the forward ones — lies below the surface, the call runs in the flipped frame
//! `(x̂, −ŷ, −n̂)` (right-handed; the returned geometry's frames are those of that frame).
//!
//! # Examples
//! ```
//! use gmueller::bsdf::{Material, ShadingPoint, SurfaceCoherence};
//! use gmueller::frame::Frame;
//! use gmueller::interaction::{Level, RoughConductor, RoughDielectric};
//! use gmueller::psd::GaussianPsd;
//! use num_complex::Complex;
//! use nalgebra::Vector3;
//!
//! let psd = GaussianPsd::<f32, 2>::isotropic(0.01, 2.0)?;
//! // Materials of different kinds and levels in one collection.
//! let materials = [
//!     Material::new(RoughDielectric::new(psd, 1.5)?, Level::ALL[7]), // Full · Partial
//!     Material::new(RoughConductor::new(psd, Complex::new(0.2, 3.5))?, Level::ALL[1])
//!         .two_sided(true),
//! ];
//! let at = ShadingPoint::new(Frame::from_normal(Vector3::z())?, 0.5)?;
//! let sky = SurfaceCoherence::new(20.0)?;
//! let to_camera = Vector3::new(0.3, 0.1, 0.95).normalize();
//! for m in &materials {
//!     if let Some(s) = m.sample_incident(&at, to_camera, &sky, 0.3, [0.6, 0.2])? {
//!         let pdf = m.pdf_incident(&at, to_camera, &sky, s.sample.direction)?;
//!         assert!(s.sample.lobe.delta || (pdf - s.sample.pdf).abs() <= 1e-5 * pdf);
//!         assert!(s.weight.matrix()[(0, 0)] >= 0.0);
//!     }
//! }
//! // The back of the two-sided conductor reflects like its front.
//! let below = Vector3::new(0.3, 0.1, -0.95).normalize();
//! assert!(materials[1].sample_incident(&at, below, &sky, 0.3, [0.6, 0.2]).is_ok());
//! assert!(materials[0].is_opaque() == false && materials[1].is_opaque());
//! # Ok::<(), gmueller::Error>(())
//! ```

use core::fmt::Debug;

use nalgebra::Vector3;

use super::sampler::{SamplesSoa, UniformsSoa};
use super::vertex::{IncidentVertex, LightEval, ShadingPoint, SideFn, VertexQuery, to_mueller};
use super::{
    Bsdf, BsdfSample, BsdfSurface, BsdfValue, DirectionSample, Interface, LobeFlags, LobeSampler,
    Part, SampledLobe, SurfaceCoherence,
};
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::batch::{DirectionsSoa, ExitFramesSoa, LobesSoa, StokesSoa};
use crate::interaction::coherence::{CoherenceLevel, CoherenceWeights};
use crate::interaction::polarization::{PolarizationLevel, PolarizationModel, Throughput};
use crate::interaction::roughness::{FirstOrder, Geometric, RoughnessWeights};
use crate::interaction::{
    Full, Geometry, Incoherent, Intensity, Kernel, Level, OneShape, Partial, PlaneWave, Roughness,
    Side,
};
use crate::mueller::Mueller;
use crate::packet::WavePacket;
use crate::psd::{BlurMethod, ClosedForm, CorrelationPowers};
use crate::real::Real;
use crate::stokes::Stokes;

/// A rough surface at a model level chosen at run time: what a renderer stores per material
/// (module docs).
#[derive(Debug)]
pub struct Material<T: Real> {
    model: Box<dyn Shade<T>>,
    level: Level,
    opaque: bool,
    two_sided: bool,
}

impl<T: Real> Material<T> {
    /// `surface` at the first-order `level` (Partial coherence blurs in closed form,
    /// [`ClosedForm`]: Gaussian PSDs and their mixtures, gratings, smooth surfaces; other PSDs
    /// take [`Material::with_blur`]).
    #[must_use]
    pub fn new<S>(surface: S, level: Level) -> Self
    where
        S: BsdfSurface<T> + Debug + Send + Sync + 'static,
        ClosedForm: BlurMethod<T, 2, S::Psd>,
    {
        Self::with_blur(surface, level, ClosedForm)
    }

    /// `surface` at the first-order `level`, Partial coherence blurring by `blur` (e.g.
    /// [`crate::psd::GaussHermite`] for a K-correlation PSD).
    #[must_use]
    pub fn with_blur<S, B>(surface: S, level: Level, blur: B) -> Self
    where
        S: BsdfSurface<T> + Debug + Send + Sync + 'static,
        B: BlurMethod<T, 2, S::Psd> + Clone + Debug + Send + Sync + 'static,
    {
        let opaque = surface.parts().specular.transmission_index().is_none();
        Self {
            model: build(surface, level, blur, FirstOrder),
            level,
            opaque,
            two_sided: false,
        }
    }

    /// `surface` at `level` and the roughness level `roughness` (beyond first order: the PSDs
    /// whose autocorrelation powers are known, [`CorrelationPowers`]), Partial coherence
    /// blurring in closed form.
    #[must_use]
    pub fn with_roughness<S>(surface: S, level: Level, roughness: Roughness) -> Self
    where
        S: BsdfSurface<T, Psd: CorrelationPowers<T>> + Debug + Send + Sync + 'static,
        ClosedForm:
            BlurMethod<T, 2, S::Psd> + BlurMethod<T, 2, <S::Psd as CorrelationPowers<T>>::Power>,
    {
        let opaque = surface.parts().specular.transmission_index().is_none();
        let model = match roughness {
            Roughness::FirstOrder => build(surface, level, ClosedForm, FirstOrder),
            Roughness::Series(series) => build(surface, level, ClosedForm, series),
            Roughness::Geometric => build(surface, level, ClosedForm, Geometric),
        };
        Self {
            model,
            level,
            opaque,
            two_sided: false,
        }
    }

    /// `surface` evaluated by a kernel chosen by type (any blur method or roughness level).
    #[must_use]
    pub fn from_kernel<S, Pol, Coh, Rough>(surface: S, kernel: Kernel<Pol, Coh, Rough>) -> Self
    where
        S: BsdfSurface<T> + Debug + Send + Sync + 'static,
        Pol: PolarizationModel + Send + Sync + 'static,
        Coh: CoherenceWeights<T, S::Psd> + Send + Sync + 'static,
        Rough: RoughnessWeights<T, S::Psd, Coh> + Send + Sync + 'static,
    {
        let opaque = surface.parts().specular.transmission_index().is_none();
        Self {
            model: Box::new(Model { surface, kernel }),
            level: Level::new(Pol::LEVEL, Coh::LEVEL),
            opaque,
            two_sided: false,
        }
    }

    /// This material with its back reflecting as its front (opaque materials only; an
    /// interface has two sides of its own and ignores it). Module docs.
    #[must_use]
    pub fn two_sided(mut self, two_sided: bool) -> Self {
        self.two_sided = two_sided;
        self
    }

    /// The model level.
    #[must_use]
    pub fn level(&self) -> Level {
        self.level
    }

    /// `true` for a surface without transmission.
    #[must_use]
    pub fn is_opaque(&self) -> bool {
        self.opaque
    }

    /// The lobes this material has at its level ([`super::Bsdf::flags`]).
    #[must_use]
    pub fn flags(&self) -> LobeFlags {
        self.model.flags()
    }

    /// The shading point to run a call in: flipped for a two-sided opaque material where
    /// `from` lies below the surface.
    fn side(&self, at: &ShadingPoint<T>, from: &Vector3<T>) -> ShadingPoint<T> {
        if self.two_sided && self.opaque && from.dot(&at.frame.k()) < T::zero() {
            at.flipped()
        } else {
            *at
        }
    }

    /// A packet arriving from `to_source` with the surface coherence `coherence`, carrying
    /// `stokes` in the incident s/p frame, at the wavelength of the source's medium
    /// ([`super::Bsdf::surface_packet`]: the horizon rule on both sides of an interface).
    ///
    /// # Errors
    /// As [`super::Bsdf::surface_packet`].
    pub fn surface_packet(
        &self,
        at: &ShadingPoint<T>,
        stokes: Stokes<T>,
        to_source: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
    ) -> Result<WavePacket<T>, Error> {
        self.model
            .surface_packet(&self.side(at, &to_source), stokes, to_source, coherence)
    }

    /// A sample of a distant disk source of solid angle `Ω` along `to_source` (the sun), at
    /// the wavelength of the source's medium ([`super::Bsdf::distant_packet`]).
    ///
    /// # Errors
    /// As [`super::Bsdf::distant_packet`].
    pub fn distant_packet(
        &self,
        at: &ShadingPoint<T>,
        stokes: Stokes<T>,
        solid_angle: T,
        to_source: Vector3<T>,
    ) -> Result<WavePacket<T>, Error> {
        self.model
            .distant_packet(&self.side(at, &to_source), stokes, solid_angle, to_source)
    }

    /// The throughput for `light` leaving along `exit`, per lobe, in BSDF form
    /// ([`super::Bsdf::eval`] of the prepared packet).
    ///
    /// # Errors
    /// As [`super::Bsdf::new`], [`super::Bsdf::prepare`] and [`super::Bsdf::eval`].
    pub fn eval(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        exit: Vector3<T>,
    ) -> Result<BsdfValue<T, Mueller<T>>, Error> {
        let from = -light.frame().k();
        self.model.eval(&self.side(at, &from), light, exit)
    }

    /// `M(ŝ → r̂)` for unpolarized light of unit irradiance arriving from `to_source` with the
    /// surface coherence `coherence` and leaving along `exit` (what the backward weights
    /// divide by the pdf: for multiple importance sampling and light sampling).
    ///
    /// # Errors
    /// As [`super::Bsdf::surface_packet`] and [`Material::eval`].
    pub fn eval_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        to_source: Vector3<T>,
    ) -> Result<BsdfValue<T, Mueller<T>>, Error> {
        self.model
            .eval_incident(&self.side(at, &exit), exit, coherence, to_source)
    }

    /// Draws the direction the light comes from for light leaving along `exit` with the
    /// surface coherence `coherence`, with its weight ([`super::Bsdf::sample_incident`]).
    /// `None` for an evanescent draw.
    ///
    /// # Errors
    /// As [`super::Bsdf::sample_incident`].
    pub fn sample_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        u_lobe: T,
        u: [T; 2],
    ) -> Result<Option<BsdfSample<T, Mueller<T>>>, Error> {
        self.model
            .sample_incident(&self.side(at, &exit), exit, coherence, u_lobe, u)
    }

    /// The density (per solid angle) with which [`Material::sample_incident`] draws
    /// `to_source` (0 for a Dirac lobe's direction).
    ///
    /// # Errors
    /// As [`super::Bsdf::incident_sampler`].
    pub fn pdf_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        to_source: Vector3<T>,
    ) -> Result<T, Error> {
        self.model
            .pdf_incident(&self.side(at, &exit), exit, coherence, to_source)
    }

    /// One vertex of a backward path tracer from one build of the backward sampler (what
    /// Mitsuba's `eval_pdf` and `sample` give in two calls, and [`Material::eval_incident`],
    /// [`Material::pdf_incident`] and [`Material::sample_incident`] in three, each building the
    /// sampler): for next-event estimation, the value and the sampler's density of the light's
    /// direction `to_light` (`None`: no light sample); and the continuation drawn from
    /// `u_lobe`, `u`. Bit for bit the three calls' answers (`tests/bsdf/material.rs`).
    ///
    /// # Errors
    /// As [`Material::sample_incident`]; the light's value carries [`Material::eval_incident`]'s
    /// own error (a light direction it refuses), so that the continuation survives it.
    ///
    /// # Examples
    /// ```
    /// use gmueller::bsdf::{Material, ShadingPoint, SurfaceCoherence};
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Level, RoughConductor};
    /// use gmueller::psd::GaussianPsd;
    /// use nalgebra::Vector3;
    /// use num_complex::Complex;
    ///
    /// let gold = RoughConductor::new(
    ///     GaussianPsd::isotropic(0.01, 1.0)?,
    ///     Complex::new(0.47, 2.4),
    /// )?;
    /// let m = Material::new(gold, Level::ALL[7]); // Full · Partial
    /// let at = ShadingPoint::new(Frame::from_normal(Vector3::z())?, 0.55)?;
    /// let sky = SurfaceCoherence::new(20.0)?;
    /// let to_camera = Vector3::new(0.3, 0.0, 1.0);
    /// let to_light = Vector3::new(-0.3, 0.1, 1.0);
    /// let v = m.incident_vertex(&at, to_camera, &sky, Some(to_light), 0.3, [0.6, 0.2])?;
    /// let light = v.light.unwrap()?;
    /// assert_eq!(light.pdf, m.pdf_incident(&at, to_camera, &sky, to_light)?);
    /// assert!(light.value.response.total().matrix()[(0, 0)] > 0.0);
    /// let next = v.sample.expect("a propagating draw");
    /// assert!(next.sample.pdf > 0.0);
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn incident_vertex(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        to_light: Option<Vector3<T>>,
        u_lobe: T,
        u: [T; 2],
    ) -> Result<IncidentVertex<T>, Error> {
        let value = to_light.map(|d| self.eval_incident(at, exit, coherence, d));
        let mut pdf = T::zero();
        let mut sample = None;
        self.with_incident(at, exit, coherence, &mut |sampler, weight| {
            if let Some(d) = &to_light {
                pdf = sampler.pdf(d);
            }
            if let Some(s) = sampler.sample(u_lobe, u) {
                let (w, g) = weight(&s)?;
                sample = Some(BsdfSample {
                    sample: s,
                    weight: w,
                    geometry: g,
                });
            }
            Ok(())
        })?;
        Ok(IncidentVertex {
            light: value.map(|v| v.map(|value| LightEval { value, pdf })),
            sample,
        })
    }

    /// The brute-force twin of [`Material::sample_incident`]: the direction the light comes
    /// from drawn uniformly over the exit's hemisphere (opaque materials, density `1/2π`) or
    /// the sphere (interfaces, `1/4π`), weighted by [`Material::eval_incident`]`/p`.
    ///
    /// Its mean weight estimates the same integral as `sample_incident`'s, without importance
    /// sampling (a reference for a renderer's or a sampler's tests; it never draws a Dirac
    /// lobe, so it sees only what the BSDF has in `eval`). `u` is uniform in `[0, 1)²`; `None`
    /// for a draw within `√ε` of the surface's plane (its density is kept, so the estimator
    /// stays unbiased up to that band).
    ///
    /// # Errors
    /// As [`Material::eval_incident`].
    pub fn sample_incident_uniform(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        u: [T; 2],
    ) -> Result<Option<BsdfSample<T, Mueller<T>>>, Error> {
        let (one, two) = (T::one(), T::lit(2.0));
        let n = at.frame.k();
        let (z, pdf) = if self.opaque {
            let up = if exit.dot(&n) < T::zero() { -one } else { one };
            (u[0] * up, one / T::two_pi())
        } else {
            (one - two * u[0], one / (two * T::two_pi()))
        };
        if z.abs() <= T::EPSILON.sqrt() {
            return Ok(None);
        }
        let rho = (one - z * z).max(T::zero()).sqrt();
        let (sin, cos) = (T::two_pi() * u[1]).sin_cos();
        let f = &at.frame;
        let direction = f.x() * (rho * cos) + f.y() * (rho * sin) + n * z;
        let v = self.eval_incident(at, exit, coherence, direction)?;
        let side = if z * exit.dot(&n) > T::zero() {
            Side::Reflection
        } else {
            Side::Transmission
        };
        Ok(Some(BsdfSample {
            sample: DirectionSample {
                direction,
                pdf,
                lobe: SampledLobe {
                    side,
                    part: Part::Scattered,
                    delta: false,
                },
                delta_weight: T::zero(),
            },
            weight: v.response.total().scaled(T::one() / pdf),
            geometry: v.geometry,
        }))
    }

    /// Draws an exit direction for `light` with its weight ([`super::Bsdf::sample_exit`]).
    ///
    /// # Errors
    /// As [`super::Bsdf::prepare`] and [`super::Bsdf::sample_exit`].
    pub fn sample_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        u_lobe: T,
        u: [T; 2],
    ) -> Result<Option<BsdfSample<T, Mueller<T>>>, Error> {
        let from = -light.frame().k();
        self.model
            .sample_exit(&self.side(at, &from), light, u_lobe, u)
    }

    /// The density with which [`Material::sample_exit`] draws `exit`.
    ///
    /// # Errors
    /// As [`super::Bsdf::prepare`] and [`super::Bsdf::exit_sampler`].
    pub fn pdf_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        exit: Vector3<T>,
    ) -> Result<T, Error> {
        let from = -light.frame().k();
        self.model.pdf_exit(&self.side(at, &from), light, exit)
    }

    /// Draws an exit direction for `light` for every element of `u`, with each draw's weight
    /// applied to the light's Stokes vector: [`super::Bsdf::sample_exit_batch`] (the draws in
    /// SIMD lanes for Gaussian lobes, the weights by the kernel's batch evaluation at first
    /// order; no allocation).
    ///
    /// # Errors
    /// As [`super::Bsdf::sample_exit_batch`].
    pub fn sample_exit_batch(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        u: UniformsSoa<'_, T>,
        samples: SamplesSoa<'_, T>,
        weights: StokesSoa<'_, T>,
    ) -> Result<(), Error> {
        let from = -light.frame().k();
        self.model
            .sample_exit_batch(&self.side(at, &from), light, u, samples, weights)
    }

    /// [`Material::eval_incident`] for a batch of pairs, as Stokes vectors of unpolarized light
    /// of unit irradiance: element `i` is the light arriving from `to_source[i]` with the
    /// surface coherence `coherence`, leaving along `exits[i]` — both lobes into `out` (each
    /// exit's s/p frame; `S0` only at the intensity levels), the exit s vectors into `frames`
    /// when given ([`super::Bsdf::eval_stokes_pairs`]: the pairs in SIMD lanes on opaque
    /// surfaces where the kernel has them). What a wavefront renderer's next-event estimation
    /// of an unpolarized light needs, every lane its own light direction and exit; a renderer
    /// whose lanes have their own shading frames passes the directions in local coordinates
    /// with one frame. A two-sided material takes the pairs whose exit is below the frame on
    /// its flipped side, as `eval_incident` does. Allocates nothing.
    ///
    /// # Errors
    /// As [`super::Bsdf::eval_stokes_pairs`]; a two-sided material with exits on both sides
    /// may have written some pairs before the error.
    pub fn eval_incident_pairs(
        &self,
        at: &ShadingPoint<T>,
        coherence: &SurfaceCoherence<T>,
        to_source: DirectionsSoa<'_, T>,
        exits: DirectionsSoa<'_, T>,
        out: &mut LobesSoa<'_, T>,
        frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error> {
        let n = to_source.len();
        let below = |i: usize| {
            let r = Vector3::new(exits.x[i], exits.y[i], exits.z[i]);
            self.side(at, &r) != *at
        };
        let lengths = crate::interaction::batch::check_lengths(
            &exits,
            core::slice::from_ref(out),
            frames.as_deref(),
        )
        .is_ok()
            && exits.x.len() >= n
            && to_source.y.len() >= n
            && to_source.z.len() >= n;
        // (Short slices: the error of the one-sided path.)
        if !(self.two_sided && self.opaque && lengths && (0..n).any(below)) {
            return self
                .model
                .eval_stokes_pairs(at, coherence, (to_source, exits), out, frames);
        }
        two_sided_pairs(self, at, coherence, (to_source, exits), (out, frames))
    }

    /// [`Material::incident_vertex`] for a batch of vertices, every lane its own shading point,
    /// exit, light direction and uniforms (what a wavefront renderer's paths are): `out[i]` is
    /// what `incident_vertex(&q.at, q.exit, coherence, q.to_light, q.u_lobe, q.u)` returns for
    /// `q = queries[i]`, each lane's error its own. The samplers are built and drawn one lane
    /// at a time; the two evaluations of every vertex — the light's value and the drawn
    /// direction's weight — run together in SIMD lanes
    /// ([`crate::interaction::Kernel::evaluate_pairs_mueller`], on opaque surfaces at first
    /// order with a Gaussian PSD; other materials and Dirac draws as `incident_vertex`). The
    /// directions, densities, lobes and geometries are `incident_vertex`'s bit for bit; the
    /// values and weights agree within the batch kernel's documented bound of `M₀₀`
    /// (`tests/bsdf/vertices.rs`). Lanes with the same wavelength, in runs, are evaluated
    /// together. Allocates nothing (64 lanes per pass, on the stack).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when `out` is shorter than `queries` (nothing is written). A
    /// lane's own error is in its `out` entry, as `incident_vertex` gives it.
    ///
    /// # Examples
    /// ```
    /// use gmueller::bsdf::{Material, ShadingPoint, SurfaceCoherence, VertexQuery};
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Level, RoughConductor};
    /// use gmueller::psd::GaussianPsd;
    /// use nalgebra::Vector3;
    /// use num_complex::Complex;
    ///
    /// let gold = RoughConductor::new(GaussianPsd::isotropic(0.01, 1.0)?, Complex::new(0.47, 2.4))?;
    /// let m = Material::new(gold, Level::ALL[7]); // Full · Partial
    /// let sky = SurfaceCoherence::new(20.0)?;
    /// // Two vertices, each with its own shading frame.
    /// let queries = [
    ///     VertexQuery {
    ///         at: ShadingPoint::new(Frame::from_normal(Vector3::z())?, 0.55)?,
    ///         exit: Vector3::new(0.3, 0.0, 1.0),
    ///         to_light: Some(Vector3::new(-0.3, 0.1, 1.0)),
    ///         u_lobe: 0.3,
    ///         u: [0.6, 0.2],
    ///     },
    ///     VertexQuery {
    ///         at: ShadingPoint::new(Frame::from_normal(Vector3::new(0.2, 0.0, 1.0))?, 0.55)?,
    ///         exit: Vector3::new(0.0, 0.4, 1.0),
    ///         to_light: None,
    ///         u_lobe: 0.8,
    ///         u: [0.1, 0.9],
    ///     },
    /// ];
    /// let mut out = [const { Ok(gmueller::bsdf::IncidentVertex { light: None, sample: None }) }; 2];
    /// m.incident_vertices(&sky, &queries, &mut out)?;
    /// for (q, v) in queries.iter().zip(&out) {
    ///     let one = m.incident_vertex(&q.at, q.exit, &sky, q.to_light, q.u_lobe, q.u)?;
    ///     let (a, b) = (v.as_ref().unwrap().sample.unwrap(), one.sample.unwrap());
    ///     assert_eq!(a.sample, b.sample);
    ///     let (wa, wb) = (a.weight.matrix(), b.weight.matrix());
    ///     assert!((wa - wb).abs().max() <= 1e-12 * wb[(0, 0)]);
    /// }
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn incident_vertices(
        &self,
        coherence: &SurfaceCoherence<T>,
        queries: &[VertexQuery<T>],
        out: &mut [Result<IncidentVertex<T>, Error>],
    ) -> Result<(), Error> {
        if out.len() < queries.len() {
            return Err(Error::OutOfRange {
                what: "incident_vertices output length",
                value: out.len() as f64,
                expected: "at least as long as queries",
            });
        }
        self.model
            .incident_vertices(&|at, from| self.side(at, from), coherence, queries, out);
        Ok(())
    }

    /// Runs `visit` with the backward sampler of this shading point and the weight of a
    /// direction it draws ([`super::Bsdf::incident_sampler`], [`super::Bsdf::incident_weight`]
    /// of one `Bsdf`): what a wavelength bundle ([`super::Bundle`]) needs of each wavelength.
    pub(crate) fn with_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        visit: &mut Visit<'_, T>,
    ) -> Result<(), Error> {
        self.model
            .with_incident(&self.side(at, &exit), exit, coherence, visit)
    }

    /// Runs `visit` with the forward sampler of `light` and the weight of a direction it draws
    /// ([`super::Bsdf::exit_sampler`], [`super::Bsdf::exit_weight`] of one prepared packet).
    pub(crate) fn with_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        visit: &mut Visit<'_, T>,
    ) -> Result<(), Error> {
        let from = -light.frame().k();
        self.model.with_exit(&self.side(at, &from), light, visit)
    }
}

/// The weight of a drawn direction at one shading point, as a Mueller matrix, with its
/// geometry ([`Material::with_incident`], [`Material::with_exit`]).
pub(crate) type WeightFn<'w, T> =
    dyn Fn(&DirectionSample<T>) -> Result<(Mueller<T>, Geometry<T>), Error> + 'w;

/// What [`Material::with_incident`] and [`Material::with_exit`] run with the sampler and the
/// weight function.
pub(crate) type Visit<'v, T> =
    dyn FnMut(&LobeSampler<'_, T>, &WeightFn<'_, T>) -> Result<(), Error> + 'v;

/// The object-safe face of one monomorphised [`Model`].
trait Shade<T: Real>: Send + Sync + Debug {
    fn flags(&self) -> LobeFlags;
    fn surface_packet(
        &self,
        at: &ShadingPoint<T>,
        stokes: Stokes<T>,
        to_source: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
    ) -> Result<WavePacket<T>, Error>;
    fn distant_packet(
        &self,
        at: &ShadingPoint<T>,
        stokes: Stokes<T>,
        solid_angle: T,
        to_source: Vector3<T>,
    ) -> Result<WavePacket<T>, Error>;
    fn eval(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        exit: Vector3<T>,
    ) -> Result<BsdfValue<T, Mueller<T>>, Error>;
    fn eval_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        to_source: Vector3<T>,
    ) -> Result<BsdfValue<T, Mueller<T>>, Error>;
    fn sample_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        u_lobe: T,
        u: [T; 2],
    ) -> Result<Option<BsdfSample<T, Mueller<T>>>, Error>;
    fn pdf_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        to_source: Vector3<T>,
    ) -> Result<T, Error>;
    fn sample_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        u_lobe: T,
        u: [T; 2],
    ) -> Result<Option<BsdfSample<T, Mueller<T>>>, Error>;
    fn pdf_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        exit: Vector3<T>,
    ) -> Result<T, Error>;
    fn sample_exit_batch(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        u: UniformsSoa<'_, T>,
        samples: SamplesSoa<'_, T>,
        weights: StokesSoa<'_, T>,
    ) -> Result<(), Error>;
    fn with_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        visit: &mut Visit<'_, T>,
    ) -> Result<(), Error>;
    fn with_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        visit: &mut Visit<'_, T>,
    ) -> Result<(), Error>;
    fn eval_stokes_pairs(
        &self,
        at: &ShadingPoint<T>,
        coherence: &SurfaceCoherence<T>,
        pairs: (DirectionsSoa<'_, T>, DirectionsSoa<'_, T>),
        out: &mut LobesSoa<'_, T>,
        frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>;
    fn incident_vertices(
        &self,
        side: &SideFn<'_, T>,
        coherence: &SurfaceCoherence<T>,
        queries: &[VertexQuery<T>],
        out: &mut [Result<IncidentVertex<T>, Error>],
    );
}

/// A surface with its kernel.
#[derive(Debug)]
struct Model<S, Pol, Coh, Rough> {
    surface: S,
    kernel: Kernel<Pol, Coh, Rough>,
}

/// A sample with a Mueller weight.
fn sample_to_mueller<T: Real, M: Throughput<T>>(s: BsdfSample<T, M>) -> BsdfSample<T, Mueller<T>> {
    BsdfSample {
        sample: s.sample,
        weight: s.weight.to_mueller(),
        geometry: s.geometry,
    }
}

impl<T, S, Pol, Coh, Rough> Shade<T> for Model<S, Pol, Coh, Rough>
where
    T: Real,
    S: BsdfSurface<T> + Debug + Send + Sync,
    Pol: PolarizationModel + Send + Sync,
    Coh: CoherenceWeights<T, S::Psd> + Send + Sync,
    Rough: RoughnessWeights<T, S::Psd, Coh> + Send + Sync,
{
    fn flags(&self) -> LobeFlags {
        // The flags do not depend on the frame or the wavelength.
        Frame::new(Vector3::x(), Vector3::y(), Vector3::z())
            .and_then(|f| Bsdf::new(&self.surface, self.kernel.clone(), f, T::one()))
            .map_or(LobeFlags::REFLECTION, |b| b.flags())
    }

    fn surface_packet(
        &self,
        at: &ShadingPoint<T>,
        stokes: Stokes<T>,
        to_source: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
    ) -> Result<WavePacket<T>, Error> {
        Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?
            .surface_packet(stokes, to_source, coherence)
    }

    fn distant_packet(
        &self,
        at: &ShadingPoint<T>,
        stokes: Stokes<T>,
        solid_angle: T,
        to_source: Vector3<T>,
    ) -> Result<WavePacket<T>, Error> {
        Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?.distant_packet(
            stokes,
            solid_angle,
            to_source,
        )
    }

    fn eval(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        exit: Vector3<T>,
    ) -> Result<BsdfValue<T, Mueller<T>>, Error> {
        let b = Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?;
        b.eval(&b.prepare(light)?, exit).map(to_mueller)
    }

    fn eval_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        to_source: Vector3<T>,
    ) -> Result<BsdfValue<T, Mueller<T>>, Error> {
        let b = Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?;
        b.eval(&b.prepare_surface(to_source, coherence)?, exit)
            .map(to_mueller)
    }

    fn sample_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        u_lobe: T,
        u: [T; 2],
    ) -> Result<Option<BsdfSample<T, Mueller<T>>>, Error> {
        let b = Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?;
        Ok(b.sample_incident(exit, coherence, u_lobe, u)?
            .map(sample_to_mueller))
    }

    fn pdf_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        to_source: Vector3<T>,
    ) -> Result<T, Error> {
        let b = Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?;
        Ok(b.incident_sampler(exit, coherence)?.pdf(&to_source))
    }

    fn sample_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        u_lobe: T,
        u: [T; 2],
    ) -> Result<Option<BsdfSample<T, Mueller<T>>>, Error> {
        let b = Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?;
        Ok(b.sample_exit(&b.prepare(light)?, u_lobe, u)?
            .map(sample_to_mueller))
    }

    fn pdf_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        exit: Vector3<T>,
    ) -> Result<T, Error> {
        let b = Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?;
        Ok(b.exit_sampler(&b.prepare(light)?)?.pdf(&exit))
    }

    fn sample_exit_batch(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        u: UniformsSoa<'_, T>,
        samples: SamplesSoa<'_, T>,
        weights: StokesSoa<'_, T>,
    ) -> Result<(), Error> {
        Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?
            .sample_exit_batch(light, u, samples, weights)
    }

    fn eval_stokes_pairs(
        &self,
        at: &ShadingPoint<T>,
        coherence: &SurfaceCoherence<T>,
        (to_source, exits): (DirectionsSoa<'_, T>, DirectionsSoa<'_, T>),
        out: &mut LobesSoa<'_, T>,
        frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error> {
        Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?
            .eval_stokes_pairs(coherence, to_source, exits, out, frames)
    }

    fn with_incident(
        &self,
        at: &ShadingPoint<T>,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        visit: &mut Visit<'_, T>,
    ) -> Result<(), Error> {
        let b = Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?;
        let sampler = b.incident_sampler(exit, coherence)?;
        visit(&sampler, &|s| {
            let (w, g) = b.incident_weight(exit, coherence, s)?;
            Ok((w.to_mueller(), g))
        })
    }

    fn incident_vertices(
        &self,
        side: &SideFn<'_, T>,
        coherence: &SurfaceCoherence<T>,
        queries: &[VertexQuery<T>],
        out: &mut [Result<IncidentVertex<T>, Error>],
    ) {
        super::vertices::incident_vertices(
            &self.surface,
            &self.kernel,
            side,
            coherence,
            queries,
            out,
        );
    }

    fn with_exit(
        &self,
        at: &ShadingPoint<T>,
        light: &WavePacket<T>,
        visit: &mut Visit<'_, T>,
    ) -> Result<(), Error> {
        let b = Bsdf::new(&self.surface, self.kernel.clone(), at.frame, at.wavelength)?;
        let incident = b.prepare(light)?;
        let sampler = b.exit_sampler(&incident)?;
        visit(&sampler, &|s| {
            let (w, g) = b.exit_weight(&incident, s)?;
            Ok((w.to_mueller(), g))
        })
    }
}

/// The boxed model of `surface` at `level` with the blur method `blur` (Partial coherence) and
/// the roughness level `rough`: one monomorphised [`Model`] per arm.
fn build<T, S, B, R>(surface: S, level: Level, blur: B, rough: R) -> Box<dyn Shade<T>>
where
    T: Real,
    S: BsdfSurface<T> + Debug + Send + Sync + 'static,
    B: BlurMethod<T, 2, S::Psd> + Clone + Debug + Send + Sync + 'static,
    R: RoughnessWeights<T, S::Psd, PlaneWave>
        + RoughnessWeights<T, S::Psd, Partial<B>>
        + RoughnessWeights<T, S::Psd, Incoherent>
        + Send
        + Sync
        + 'static,
{
    use CoherenceLevel as C;
    use PolarizationLevel as Pl;
    fn boxed<T, S, Pol, Coh, R>(surface: S, kernel: Kernel<Pol, Coh, R>) -> Box<dyn Shade<T>>
    where
        T: Real,
        S: BsdfSurface<T> + Debug + Send + Sync + 'static,
        Pol: PolarizationModel + Send + Sync + 'static,
        Coh: CoherenceWeights<T, S::Psd> + Send + Sync + 'static,
        R: RoughnessWeights<T, S::Psd, Coh> + Send + Sync + 'static,
    {
        Box::new(Model { surface, kernel })
    }
    let (plane, partial) = (PlaneWave, Partial(blur));
    match (level.polarization, level.coherence) {
        (Pl::Intensity, C::PlaneWave) => boxed(
            surface,
            Kernel::<Intensity, _>::new(plane).with_roughness(rough),
        ),
        (Pl::Intensity, C::Partial) => boxed(
            surface,
            Kernel::<Intensity, _>::new(partial).with_roughness(rough),
        ),
        (Pl::Intensity, C::Incoherent) => boxed(
            surface,
            Kernel::<Intensity, _>::new(Incoherent).with_roughness(rough),
        ),
        (Pl::OneShape, C::PlaneWave) => boxed(
            surface,
            Kernel::<OneShape, _>::new(plane).with_roughness(rough),
        ),
        (Pl::OneShape, C::Partial) => boxed(
            surface,
            Kernel::<OneShape, _>::new(partial).with_roughness(rough),
        ),
        (Pl::OneShape, C::Incoherent) => boxed(
            surface,
            Kernel::<OneShape, _>::new(Incoherent).with_roughness(rough),
        ),
        (Pl::Full, C::PlaneWave) => {
            boxed(surface, Kernel::<Full, _>::new(plane).with_roughness(rough))
        }
        (Pl::Full, C::Partial) => boxed(
            surface,
            Kernel::<Full, _>::new(partial).with_roughness(rough),
        ),
        (Pl::Full, C::Incoherent) => boxed(
            surface,
            Kernel::<Full, _>::new(Incoherent).with_roughness(rough),
        ),
    }
}

/// Pairs of a two-sided material with exits on both sides ([`Material::eval_incident_pairs`]):
/// per chunk of at most `CHUNK` pairs, the pairs of each side gathered into buffers on the
/// stack, evaluated on that side's shading point, and scattered back.
fn two_sided_pairs<T: Real>(
    m: &Material<T>,
    at: &ShadingPoint<T>,
    coherence: &SurfaceCoherence<T>,
    (to_source, exits): (DirectionsSoa<'_, T>, DirectionsSoa<'_, T>),
    (out, mut frames): (&mut LobesSoa<'_, T>, Option<&mut ExitFramesSoa<'_, T>>),
) -> Result<(), Error> {
    const CHUNK: usize = 64;
    let n = to_source.len();
    // The intensity levels write S0 alone.
    let stokes_len = if m.level().polarization == PolarizationLevel::Intensity {
        1
    } else {
        4
    };
    let flipped = at.flipped();
    for start in (0..n).step_by(CHUNK) {
        let end = (start + CHUNK).min(n);
        for down in [false, true] {
            let mut idx = [0usize; CHUNK];
            let mut count = 0;
            for i in start..end {
                let r = Vector3::new(exits.x[i], exits.y[i], exits.z[i]);
                if (r.dot(&at.frame.k()) < T::zero()) == down {
                    idx[count] = i;
                    count += 1;
                }
            }
            if count == 0 {
                continue;
            }
            let mut dirs = [[T::zero(); CHUNK]; 6];
            for (j, &i) in idx[..count].iter().enumerate() {
                let v = [
                    to_source.x[i],
                    to_source.y[i],
                    to_source.z[i],
                    exits.x[i],
                    exits.y[i],
                    exits.z[i],
                ];
                for (d, x) in dirs.iter_mut().zip(v) {
                    d[j] = x;
                }
            }
            let mut lobes = [[T::zero(); CHUNK]; 11];
            {
                let [s0, s1, s2, r0, r1, r2] = &dirs;
                let [a0, a1, a2, a3, b0, b1, b2, b3, f0, f1, f2] = &mut lobes;
                let mut o = LobesSoa {
                    specular: StokesSoa {
                        s: [
                            &mut a0[..count],
                            &mut a1[..count],
                            &mut a2[..count],
                            &mut a3[..count],
                        ],
                    },
                    scattered: StokesSoa {
                        s: [
                            &mut b0[..count],
                            &mut b1[..count],
                            &mut b2[..count],
                            &mut b3[..count],
                        ],
                    },
                };
                let mut f = ExitFramesSoa {
                    s: [&mut f0[..count], &mut f1[..count], &mut f2[..count]],
                };
                let side = if down { &flipped } else { at };
                let pairs = (
                    DirectionsSoa {
                        x: &s0[..count],
                        y: &s1[..count],
                        z: &s2[..count],
                    },
                    DirectionsSoa {
                        x: &r0[..count],
                        y: &r1[..count],
                        z: &r2[..count],
                    },
                );
                let want_frames = frames.is_some();
                m.model.eval_stokes_pairs(
                    side,
                    coherence,
                    pairs,
                    &mut o,
                    want_frames.then_some(&mut f),
                )?;
            }
            for (j, &i) in idx[..count].iter().enumerate() {
                for c in 0..stokes_len {
                    out.specular.s[c][i] = lobes[c][j];
                    out.scattered.s[c][i] = lobes[4 + c][j];
                }
                if let Some(f) = frames.as_deref_mut() {
                    for c in 0..3 {
                        f.s[c][i] = lobes[8 + c][j];
                    }
                }
            }
        }
    }
    Ok(())
}
