//! Wavelength bundles: one sampled direction serves `N` wavelengths ([`Bundle`]), as pbrt-v4's
//! `SampledWavelengths` (4 wavelengths carried together) and Mitsuba 3's spectral variants do,
//! weighted by hero-wavelength spectral multiple importance sampling (Wilkie, Nawaz, Droske,
//! Weidlich & Hanika 2014, "Hero Wavelength Spectral Sampling", EGSR). The Mueller matrix is
//! per wavelength; the direction, the shading frame and the geometry's frames are shared.
//!
//! # Formula
//! ```text
//! L  = the live wavelengths of the bundle,  n = |L|,  h ∈ L the hero
//! ŝ ~ p_h                                             (the hero's sampler draws the direction)
//! p̄(ŝ) = (1/n) Σ_{j∈L} p_j(ŝ)                         (the bundle's pdf)
//! w_i  = M_i(ŝ → r̂) / p̄(ŝ)                             (backward weight of wavelength i ∈ L)
//! w_i  = M_i(ŝ → r̂) cos θ_o / (cos θ_i p̄(r̂))           (forward, r̂ drawn for a light from ŝ)
//! E[w_i] = (1/n) Σ_{h∈L} ∫ p_h M_i / p̄ dω = ∫_{p̄>0} M_i dω     (h uniform in L)
//! ```
//! where `p_j` is the density (per solid angle) of wavelength `j`'s own sampler
//! ([`Material::pdf_incident`], [`Material::pdf_exit`]; Dirac lobes excluded) and `M_i` its
//! throughput in BSDF form ([`Material::eval_incident`], [`Material::eval`]). This is the
//! one-sample multiple importance sampling estimator with the balance heuristic over the
//! bundle's samplers (Veach 1997, §9.2.4): the weight of every live wavelength is unbiased
//! **provided the hero is uniformly distributed over the live wavelengths, independently of
//! the uniforms that draw the direction** — e.g. a stratified set of wavelengths rotated by
//! one uniform (pbrt-v4's `SampleVisibleWavelengths`, hero at index 0), or a fixed set of
//! bins with the hero chosen by [`Bundle::choose_hero`] from a fresh uniform. With a hero
//! that is always the same wavelength the weights are biased wherever the `p_j` differ. With
//! `N = 1` the weight is that of the single-wavelength call (backward bit for bit, forward to
//! rounding).
//!
//! # Delta lobes
//! A Dirac lobe (the plane-wave level's specular lobe; a grating's orders) is drawn with a
//! probability `P_j`, not a density, and its weight is its integral `I_j` over directions
//! ([`super::Bsdf::incident_weight`], [`super::Bsdf::exit_weight`]).
//! - **Reflected specular delta.** The mirror direction does not depend on the wavelength:
//!   every live wavelength keeps it, `w_i = I_i / P̄` with `P̄ = (1/n) Σ_{j∈L} P_j` (each `P_j`
//!   the probability with which wavelength `j`'s sampler chooses that lobe). `pdfs[j] = P_j`,
//!   `pdf = P̄`.
//! - **Dispersive deltas** — the transmitted specular delta (Snell's direction depends on
//!   `η(λ)`) and every scattered delta (grating orders depend on `λ`; a smooth PSD's order at
//!   the mirror direction is treated so too, conservatively): no other wavelength has a lobe in
//!   that direction, so the secondary wavelengths are **terminated**, as pbrt-v4's
//!   `SampledWavelengths::TerminateSecondary` does: `alive` keeps the hero alone, the other
//!   weights are zero, and `w_h = n I_h / P_h` (`pdf = P_h/n`, pbrt's pdf divided by the
//!   number of wavelengths). Wavelength `i` reaches that lobe only as the hero, with
//!   probability `1/n`, so under the same uniform-hero condition its expectation is again
//!   `I_i`. The renderer must keep the terminated wavelengths dead for the rest of the path
//!   (pass [`BundleSample::alive`] to the next vertex's bundle, [`Bundle::with_alive`]); the
//!   hero is then the only live wavelength and `p̄` its own pdf.
//!
//! Whether a delta is dispersive is read from the hero's [`SampledLobe`]: `Side::Reflection`
//! with `Part::Specular` is shared, anything else is terminated. Terminating is always
//! unbiased; it only spends the bundle. At a shared delta every wavelength's integral is taken
//! at the hero's mirror direction (each wavelength's own sampler returns the mirror to within
//! a few ε: its map from `h_t` to directions rounds with its own wavenumber).
//!
//! # Variance
//! The weights are unbiased, not as good as each wavelength's own sampler: `M_i/p̄` is flat
//! only where every `p_j` follows `M_i`. With one surface coherence width (µm) and one PSD for
//! the whole bundle, the coherent lobe's width `1/(k w)` and the scattered lobes' widths in
//! direction go as `λ`, so the `p_j` of a bundle spread over the visible differ by the ratio
//! of its wavelengths. Measured under uniform light (`tests/bsdf/bundle.rs`, 0.4–0.75 µm,
//! 5 µm of coherence, equal numbers of draws) the variance of a wavelength's `M₀₀` weight was
//! 1.2–18× the single-wavelength sampler's for rough glass at Full·Partial (8 wavelengths),
//! 5.5–135× for rough gold at Intensity·Partial (4; its own sampler is nearly exact there) and
//! 37–215× for glass at a plane wave, where 95 % of the draws are the transmitted delta and
//! terminate. A renderer's light adds the same variance to both; the bundle's gain is the
//! `N` wavelengths per path (colour noise, path reuse), not the weights. A coherence width
//! proportional to the wavelength ([`BundleCoherence`]: an array of one `SurfaceCoherence`
//! per wavelength) keeps the coherent lobes' angular widths equal: for the same glass
//! (Full·Partial, from above, 5 µm at 0.55 µm) the variance ratio fell from 1.21–5.00 to
//! 1.03–1.98 in one run (`weights_are_unbiased_per_wavelength_with_a_uniform_hero`).
//!
//! # Frames and geometry
//! The shading frame and the directions are shared, so are the s/p frames of the geometry:
//! every weight maps Stokes vectors in [`Geometry::incident_sp`] to [`Geometry::exit_sp`] of
//! the one [`BundleSample::geometry`] (the hero's; its wavenumber and relative index are the
//! hero's). [`super::PathThroughput::advance`] takes it as for a single wavelength.
//!
//! # Cost
//! No heap allocation (arrays of `N`). Per call: the hero's sampler is built once, draws once
//! and weighs once; each other live wavelength builds its own sampler (its `p_j`, or its `P_j`
//! at a shared delta) and weighs the direction once; a dispersive delta skips the
//! secondaries. The loop over the wavelengths is scalar: the per-wavelength cost is about that
//! of a single-wavelength call. Measured (`benches/bundle.rs`, medians of three runs on a
//! loaded two-core machine, ±10 %): a backward draw of 8 wavelengths took 0.92–0.96× the
//! time of 8 single-wavelength `Material::sample_incident` calls (rough glass and gold,
//! Full·Partial and Intensity·Partial, f32 and f64; 7.2–11.5 µs per bundle), 4 wavelengths
//! 0.88–0.99×: the secondaries' `pdf` costs a little less than a draw. SIMD across the
//! wavelengths (issue 37 asks for ≤ 0.35× per wavelength at 8) is not attempted here.
//!
//! # Examples
//! ```
//! use gmueller::bsdf::{Bundle, Material, SurfaceCoherence};
//! use gmueller::frame::Frame;
//! use gmueller::interaction::{Level, RoughDielectric};
//! use gmueller::psd::GaussianPsd;
//! use gmueller::spectral::Glass;
//! use nalgebra::Vector3;
//!
//! // Rough N-BK7 at four wavelengths (µm): one material per wavelength.
//! let lambdas = [0.45, 0.525, 0.6, 0.675];
//! let psd = GaussianPsd::<f64, 2>::isotropic(0.01, 2.0)?;
//! let glass = lambdas.map(|l| {
//!     RoughDielectric::new(psd, Glass::NBk7.index(l)).map(|m| Material::new(m, Level::ALL[7]))
//! });
//! let glass = [&glass[0], &glass[1], &glass[2], &glass[3]].map(|m| m.as_ref().unwrap());
//! let frame = Frame::from_normal(Vector3::z())?;
//! // The hero drawn uniformly among the four (here from the uniform 0.6: index 2).
//! let bundle = Bundle::new(glass, frame, lambdas)?.choose_hero(0.6);
//! assert_eq!(bundle.hero(), 2);
//! let sky = SurfaceCoherence::new(20.0)?;
//! let to_camera = Vector3::new(0.3, 0.1, 0.95).normalize();
//! if let Some(s) = bundle.sample_incident(to_camera, &sky, 0.3, [0.6, 0.2])? {
//!     // The bundle's pdf is the mean of the four wavelengths' own pdfs.
//!     let mean = s.pdfs.iter().sum::<f64>() / 4.0;
//!     assert!((s.pdf - mean).abs() <= 1e-12 * mean);
//!     // Each weight is that wavelength's M(ŝ → r̂) over the bundle's pdf.
//!     for i in 0..4 {
//!         let m = glass[i].eval_incident(bundle.point(i), to_camera, &sky, s.direction)?;
//!         let (a, b) = (s.weights[i].m00() * s.pdf, m.response.total().m00());
//!         assert!(s.alive[i] && (a - b).abs() <= 1e-12 * b);
//!     }
//!     // The same pdfs as the single-wavelength calls.
//!     let p = bundle.pdf_incident(to_camera, &sky, s.direction)?;
//!     assert_eq!(p.pdfs, s.pdfs);
//! }
//! # Ok::<(), gmueller::Error>(())
//! ```

use nalgebra::Vector3;

use super::material::{Visit, WeightFn};
use super::{
    BsdfValue, DirectionSample, LobeSampler, Material, Part, SampledLobe, ShadingPoint,
    SurfaceCoherence,
};
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::polarization::Throughput;
use crate::interaction::{Geometry, Side};
use crate::mueller::Mueller;
use crate::packet::WavePacket;
use crate::real::Real;

/// The surface coherence of the light arriving at each wavelength of a bundle (the backward
/// calls): one [`SurfaceCoherence`] for all, or an array of one per wavelength. A width
/// proportional to the wavelength (as the sun's, `w = λ/√(π Ω)`) keeps the coherent lobe's
/// angular width `1/(k w)` the same at every wavelength, so the wavelengths' pdfs agree on
/// it (module docs, "Variance").
pub trait BundleCoherence<T: Real, const N: usize> {
    /// The coherence of wavelength `i`.
    fn of(&self, i: usize) -> &SurfaceCoherence<T>;
}

impl<T: Real, const N: usize> BundleCoherence<T, N> for SurfaceCoherence<T> {
    #[inline]
    fn of(&self, _: usize) -> &SurfaceCoherence<T> {
        self
    }
}

impl<T: Real, const N: usize> BundleCoherence<T, N> for [SurfaceCoherence<T>; N] {
    #[inline]
    fn of(&self, i: usize) -> &SurfaceCoherence<T> {
        &self[i]
    }
}

/// One material at `N` wavelengths of one shading point, sampled with one direction for all
/// (module docs): per wavelength `i` the [`Material`] built for that wavelength and its
/// [`ShadingPoint`] (the shared frame at `wavelengths[i]`), the hero (whose sampler draws the
/// direction) and which wavelengths are still alive on the path.
///
/// The materials must be one surface at the bundle's wavelengths (the same kind, level,
/// roughness and two-sidedness; the indices of refraction may differ): the constructor
/// checks the level, opacity and lobe flags.
///
/// # Examples
/// ```
/// use gmueller::bsdf::{Bundle, Material, SurfaceCoherence};
/// use gmueller::frame::Frame;
/// use gmueller::interaction::{Level, RoughConductor};
/// use gmueller::psd::GaussianPsd;
/// use gmueller::spectral::Metal;
/// use nalgebra::Vector3;
///
/// let psd = GaussianPsd::<f32, 2>::isotropic(0.012, 1.5)?;
/// let lambdas = [0.45f32, 0.55, 0.65, 0.75];
/// let gold = lambdas
///     .map(|l| Material::new(RoughConductor::new(psd, Metal::Au.index(l)).unwrap(), Level::ALL[1]));
/// let frame = Frame::from_normal(Vector3::z())?;
/// let bundle = Bundle::new([&gold[0], &gold[1], &gold[2], &gold[3]], frame, lambdas)?;
/// let sky = SurfaceCoherence::new(20.0)?;
/// // The light in the mirror direction of the camera: the coherent lobe.
/// let (to_camera, to_light) = (Vector3::new(0.3, 0.0, 0.95), Vector3::new(-0.3, 0.0, 0.95));
/// // Light sampling: the bundle's pdf of the light's direction, for MIS, and M per wavelength.
/// let p = bundle.pdf_incident(to_camera, &sky, to_light)?;
/// let m = bundle.eval_incident(to_camera, &sky, to_light)?;
/// assert!(p.pdf > 0.0 && m.iter().all(|v| v.is_some()));
/// // The coherent lobe's peak goes as R(λ)/λ² (its width is 1/(k w)): λ² M₀₀ follows
/// // gold's reflectance, which is more than twice as high in the red as in the blue.
/// let r = |i: usize| m[i].unwrap().response.total().m00() * lambdas[i] * lambdas[i];
/// assert!(r(3) > 2.0 * r(0));
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy)]
pub struct Bundle<'a, T: Real, const N: usize> {
    materials: [&'a Material<T>; N],
    points: [ShadingPoint<T>; N],
    hero: usize,
    alive: [bool; N],
}

/// A direction drawn for a [`Bundle`], with one weight per wavelength (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BundleSample<T: Real, const N: usize> {
    /// The drawn unit direction (backward: toward the source, ŝ; forward: the exit r̂).
    pub direction: Vector3<T>,
    /// The hero's lobe (a Dirac lobe when `lobe.delta`: then `pdfs` and `pdf` are
    /// probabilities).
    pub lobe: SampledLobe,
    /// The hero's index.
    pub hero: usize,
    /// Per wavelength, its own sampler's density at `direction` (`p_j`), or at a shared delta
    /// the probability of choosing it (`P_j`); 0 for a dead or terminated wavelength.
    pub pdfs: [T; N],
    /// The bundle's pdf: the mean of `pdfs` over the live wavelengths (`p̄`, or `P̄`); after a
    /// termination, the hero's probability over the number of wavelengths that were alive.
    pub pdf: T,
    /// Per wavelength, the Monte Carlo weight with the bundle's pdf: backward
    /// `M_i(ŝ → r̂)/p̄`, forward `M_i cos θ_o/(cos θ_i p̄)`; at a delta the lobe's integral in
    /// place of `M_i`; zero for a dead or terminated wavelength. Maps the incident s/p frame
    /// of `geometry` to its exit s/p frame.
    pub weights: [Mueller<T>; N],
    /// The wavelengths alive after this vertex: the bundle's, less the secondaries a
    /// dispersive delta terminated.
    pub alive: [bool; N],
    /// The hero's geometry of the sampled pair of directions (the frames every weight uses).
    pub geometry: Geometry<T>,
}

impl<T: Real, const N: usize> BundleSample<T, N> {
    /// The number of wavelengths alive after this vertex (1 after a termination).
    #[must_use]
    pub fn live(&self) -> usize {
        self.alive.iter().filter(|&&a| a).count()
    }
}

/// The densities of a direction for a [`Bundle`]: per wavelength and the bundle's mean.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BundlePdf<T: Real, const N: usize> {
    /// Per wavelength, its own sampler's density (per solid angle; 0 for a dead wavelength or
    /// a Dirac lobe's direction), bit for bit the single-wavelength call's.
    pub pdfs: [T; N],
    /// `p̄ = (1/n) Σ_{j live} p_j`, the density of [`Bundle::sample_incident`] (or
    /// [`Bundle::sample_exit`]) with a uniformly chosen hero: for multiple importance
    /// sampling against light sampling.
    pub pdf: T,
}

/// What [`Bundle::eval_incident`] and [`Bundle::eval`] return: per wavelength its throughput
/// in BSDF form with its geometry (the single-wavelength call's, bit for bit), `None` for a
/// dead wavelength.
pub type BundleValues<T, const N: usize> = [Option<BsdfValue<T, Mueller<T>>>; N];

/// The array `[f(0), …, f(N − 1)]`, or the first error (`N ≥ 1`).
fn try_array<X: Copy, const N: usize>(
    mut f: impl FnMut(usize) -> Result<X, Error>,
) -> Result<[X; N], Error> {
    let first = f(0)?;
    let mut out = [first; N];
    for (i, x) in out.iter_mut().enumerate().skip(1) {
        *x = f(i)?;
    }
    Ok(out)
}

/// `Side::Reflection` with `Part::Specular`: the one Dirac lobe whose direction (the mirror)
/// is the same at every wavelength.
fn shared_delta(lobe: &SampledLobe) -> bool {
    lobe.side == Side::Reflection && lobe.part == Part::Specular
}

impl<'a, T: Real, const N: usize> Bundle<'a, T, N> {
    /// The bundle of `materials[i]` at `wavelengths[i]` (µm, in the medium above, as
    /// [`ShadingPoint::new`]) on the shading frame `frame`; hero 0, every wavelength alive.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for `N = 0` and unless every wavelength is finite and positive;
    /// [`Error::Unrealizable`] when the materials differ in level, opacity or lobe flags (they
    /// must be one surface at the bundle's wavelengths).
    pub fn new(
        materials: [&'a Material<T>; N],
        frame: Frame<T>,
        wavelengths: [T; N],
    ) -> Result<Self, Error> {
        if N == 0 {
            return Err(Error::OutOfRange {
                what: "number of wavelengths in a bundle",
                value: 0.0,
                expected: "≥ 1",
            });
        }
        let points = try_array(|i| ShadingPoint::new(frame, wavelengths[i]))?;
        let first = materials[0];
        if materials.iter().any(|m| {
            m.level() != first.level()
                || m.is_opaque() != first.is_opaque()
                || m.flags() != first.flags()
        }) {
            return Err(Error::Unrealizable {
                reason: "a bundle's materials differ in level, opacity or lobe flags \
                         (they must be one surface at the bundle's wavelengths)",
            });
        }
        Ok(Self {
            materials,
            points,
            hero: 0,
            alive: [true; N],
        })
    }

    /// This bundle with `hero` as the hero.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when `hero ≥ N` or the wavelength `hero` is dead.
    pub fn with_hero(mut self, hero: usize) -> Result<Self, Error> {
        if hero >= N || !self.alive[hero] {
            return Err(Error::OutOfRange {
                what: "hero index of a bundle (beyond N, or a dead wavelength)",
                value: hero as f64,
                expected: "< N, and a live wavelength",
            });
        }
        self.hero = hero;
        Ok(self)
    }

    /// This bundle with the hero chosen uniformly among the live wavelengths by one uniform
    /// `u ∈ [0, 1)`: the `⌊u n⌋`-th live wavelength (`n` live; `u` clamped, NaN as 0). With a
    /// fresh uniform per path this is the condition under which the weights are unbiased
    /// (module docs).
    #[must_use]
    pub fn choose_hero(mut self, u: T) -> Self {
        let n = self.live();
        let u = if u >= T::zero() {
            u.min(T::one())
        } else {
            T::zero()
        };
        let k = (u * T::lit(n as f64)).floor().to_f64();
        let k = if k >= 0.0 { (k as usize).min(n - 1) } else { 0 };
        if let Some(i) = (0..N).filter(|&i| self.alive[i]).nth(k) {
            self.hero = i;
        }
        self
    }

    /// This bundle with only the wavelengths `alive` alive (e.g. [`BundleSample::alive`] of
    /// the previous vertex); the hero moves to the first live wavelength if it is dead.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when no wavelength is alive.
    pub fn with_alive(mut self, alive: [bool; N]) -> Result<Self, Error> {
        let Some(first) = alive.iter().position(|&a| a) else {
            return Err(Error::OutOfRange {
                what: "live wavelengths of a bundle",
                value: 0.0,
                expected: "at least one",
            });
        };
        if !alive[self.hero] {
            self.hero = first;
        }
        self.alive = alive;
        Ok(self)
    }

    /// The hero's index.
    #[must_use]
    pub fn hero(&self) -> usize {
        self.hero
    }

    /// Which wavelengths are alive.
    #[must_use]
    pub fn alive(&self) -> [bool; N] {
        self.alive
    }

    /// The number of live wavelengths, `n ≥ 1`.
    #[must_use]
    pub fn live(&self) -> usize {
        self.alive.iter().filter(|&&a| a).count()
    }

    /// The shading point of wavelength `i`.
    ///
    /// # Panics
    /// If `i ≥ N`.
    #[must_use]
    pub fn point(&self, i: usize) -> &ShadingPoint<T> {
        &self.points[i]
    }

    /// The material of wavelength `i`.
    ///
    /// # Panics
    /// If `i ≥ N`.
    #[must_use]
    pub fn material(&self, i: usize) -> &'a Material<T> {
        self.materials[i]
    }

    /// The wavelengths (µm, in the medium above).
    #[must_use]
    pub fn wavelengths(&self) -> [T; N] {
        self.points.map(|p| p.wavelength())
    }

    /// Draws the direction the light comes from for light leaving along `exit` with the
    /// surface coherence `coherence` (one for every wavelength, or one each:
    /// [`BundleCoherence`]), with the hero's sampler, and weighs it for every live wavelength
    /// (module docs; [`Material::sample_incident`] per wavelength). `None` for an evanescent
    /// draw.
    ///
    /// # Errors
    /// As [`Material::sample_incident`] and [`Material::pdf_incident`] of each live
    /// wavelength (a zero or non-finite `exit`, a direction below an opaque surface, …).
    pub fn sample_incident(
        &self,
        exit: Vector3<T>,
        coherence: &impl BundleCoherence<T, N>,
        u_lobe: T,
        u: [T; 2],
    ) -> Result<Option<BundleSample<T, N>>, Error> {
        self.sample(u_lobe, u, |i, visit| {
            self.materials[i].with_incident(&self.points[i], exit, coherence.of(i), visit)
        })
    }

    /// The density of [`Bundle::sample_incident`] at `to_source` per wavelength
    /// ([`Material::pdf_incident`]) and the bundle's mean.
    ///
    /// # Errors
    /// As [`Material::pdf_incident`] of each live wavelength.
    pub fn pdf_incident(
        &self,
        exit: Vector3<T>,
        coherence: &impl BundleCoherence<T, N>,
        to_source: Vector3<T>,
    ) -> Result<BundlePdf<T, N>, Error> {
        self.pdf(|i| {
            self.materials[i].pdf_incident(&self.points[i], exit, coherence.of(i), to_source)
        })
    }

    /// `M_i(ŝ → r̂)` per live wavelength ([`Material::eval_incident`]; `None` for a dead one).
    ///
    /// # Errors
    /// As [`Material::eval_incident`] of each live wavelength.
    pub fn eval_incident(
        &self,
        exit: Vector3<T>,
        coherence: &impl BundleCoherence<T, N>,
        to_source: Vector3<T>,
    ) -> Result<BundleValues<T, N>, Error> {
        self.values(|i| {
            self.materials[i].eval_incident(&self.points[i], exit, coherence.of(i), to_source)
        })
    }

    /// Draws an exit direction for the light `lights[i]` (the packet of wavelength `i`, all
    /// arriving along one direction) with the hero's sampler and weighs it for every live
    /// wavelength (module docs; [`Material::sample_exit`] per wavelength). `None` for an
    /// evanescent draw.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when a live packet arrives along another direction than the
    /// hero's (by more than `64 ε`); as [`Material::sample_exit`] and [`Material::pdf_exit`]
    /// of each live wavelength.
    pub fn sample_exit(
        &self,
        lights: &[WavePacket<T>; N],
        u_lobe: T,
        u: [T; 2],
    ) -> Result<Option<BundleSample<T, N>>, Error> {
        self.same_direction(lights)?;
        self.sample(u_lobe, u, |i, visit| {
            self.materials[i].with_exit(&self.points[i], &lights[i], visit)
        })
    }

    /// The density of [`Bundle::sample_exit`] at `exit` per wavelength
    /// ([`Material::pdf_exit`]) and the bundle's mean.
    ///
    /// # Errors
    /// As [`Bundle::sample_exit`].
    pub fn pdf_exit(
        &self,
        lights: &[WavePacket<T>; N],
        exit: Vector3<T>,
    ) -> Result<BundlePdf<T, N>, Error> {
        self.same_direction(lights)?;
        self.pdf(|i| self.materials[i].pdf_exit(&self.points[i], &lights[i], exit))
    }

    /// The throughput of `lights[i]` leaving along `exit` per live wavelength
    /// ([`Material::eval`]; `None` for a dead one).
    ///
    /// # Errors
    /// As [`Bundle::sample_exit`] and [`Material::eval`].
    pub fn eval(
        &self,
        lights: &[WavePacket<T>; N],
        exit: Vector3<T>,
    ) -> Result<BundleValues<T, N>, Error> {
        self.same_direction(lights)?;
        self.values(|i| self.materials[i].eval(&self.points[i], &lights[i], exit))
    }

    /// Rejects live packets that do not arrive along the hero's direction.
    fn same_direction(&self, lights: &[WavePacket<T>; N]) -> Result<(), Error> {
        let d = lights[self.hero].direction();
        for (light, _) in lights.iter().zip(self.alive).filter(|(_, a)| *a) {
            let off = (light.direction() - d).norm();
            #[expect(
                clippy::neg_cmp_op_on_partial_ord,
                reason = "a NaN must fail the test too"
            )]
            if !(off <= T::lit(64.0) * T::EPSILON) {
                return Err(Error::OutOfRange {
                    what: "direction of a bundle wavelength's light (|k̂ − k̂_hero|)",
                    value: off.to_f64(),
                    expected: "≤ 64 ε: one ray for every wavelength",
                });
            }
        }
        Ok(())
    }

    /// `pdf(i)` for the live wavelengths and their mean.
    fn pdf(
        &self,
        mut pdf: impl FnMut(usize) -> Result<T, Error>,
    ) -> Result<BundlePdf<T, N>, Error> {
        let mut pdfs = [T::zero(); N];
        let mut sum = T::zero();
        for i in (0..N).filter(|&i| self.alive[i]) {
            pdfs[i] = pdf(i)?;
            sum += pdfs[i];
        }
        Ok(BundlePdf {
            pdfs,
            pdf: sum / T::lit(self.live() as f64),
        })
    }

    /// `value(i)` for the live wavelengths.
    fn values<X: Copy>(
        &self,
        mut value: impl FnMut(usize) -> Result<X, Error>,
    ) -> Result<[Option<X>; N], Error> {
        let mut out = [None; N];
        for i in (0..N).filter(|&i| self.alive[i]) {
            out[i] = Some(value(i)?);
        }
        Ok(out)
    }

    /// The bundle's draw (module docs): `run(i, visit)` runs `visit` with wavelength `i`'s
    /// sampler and weight function.
    fn sample(
        &self,
        u_lobe: T,
        u: [T; 2],
        mut run: impl FnMut(usize, &mut Visit<'_, T>) -> Result<(), Error>,
    ) -> Result<Option<BundleSample<T, N>>, Error> {
        let h = self.hero;
        // The hero draws, and weighs its draw with pdf 1: `M_h` (forward `M_h cos θ_o/cos θ_i`),
        // or its delta's integral `I_h`.
        let mut drawn = None;
        run(h, &mut |sampler: &LobeSampler<'_, T>,
                     weight: &WeightFn<'_, T>| {
            if let Some(s) = sampler.sample(u_lobe, u) {
                let (m, g) = weight(&DirectionSample { pdf: T::one(), ..s })?;
                drawn = Some((s, m, g));
            }
            Ok(())
        })?;
        let Some((s, m_h, geometry)) = drawn else {
            return Ok(None);
        };
        let zero = <Mueller<T> as Throughput<T>>::zero();
        let mut values = [zero; N];
        let mut pdfs = [T::zero(); N];
        values[h] = m_h;
        pdfs[h] = s.pdf;
        let live = T::lit(self.live() as f64);
        let unit = DirectionSample { pdf: T::one(), ..s };
        let (alive, pdf) = if !s.lobe.delta || shared_delta(&s.lobe) {
            for i in (0..N).filter(|&i| i != h && self.alive[i]) {
                run(
                    i,
                    &mut |sampler: &LobeSampler<'_, T>, weight: &WeightFn<'_, T>| {
                        // Its own density at ŝ, or the probability of its reflected specular delta.
                        pdfs[i] = if s.lobe.delta {
                            sampler.part_probabilities()[0]
                        } else {
                            sampler.pdf(&s.direction)
                        };
                        values[i] = weight(&unit)?.0;
                        Ok(())
                    },
                )?;
            }
            // Summed in index order, as `Bundle::pdf_incident` and `Bundle::pdf_exit` do: the
            // same number bit for bit.
            let sum = (0..N)
                .filter(|&i| self.alive[i])
                .fold(T::zero(), |a, i| a + pdfs[i]);
            (self.alive, sum / live)
        } else {
            // A dispersive delta: the secondaries are terminated (module docs).
            let mut alive = [false; N];
            alive[h] = true;
            (alive, s.pdf / live)
        };
        // As the single-wavelength weight: `M · (1/p)`, small entries flushed.
        let inv = T::one() / pdf;
        let mut weights = [zero; N];
        for i in (0..N).filter(|&i| alive[i]) {
            weights[i] = values[i].scaled(inv).flushed();
        }
        Ok(Some(BundleSample {
            direction: s.direction,
            lobe: s.lobe,
            hero: h,
            pdfs,
            pdf,
            weights,
            alive,
            geometry,
        }))
    }
}
