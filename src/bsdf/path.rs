//! The state of a backward path: the product of the vertex throughputs, the frame its input
//! side is expressed in (`docs/renderer.md` §3), and the light gathered so far.
//!
//! # Formula
//! A camera path `x₀ (camera) ← x₁ ← x₂ …` carries `Tₙ`, the Mueller matrix from the light
//! arriving at vertex `n` (in that vertex's incident s/p frame `Fₙ`) to the Stokes vector the
//! camera reads (in the camera frame `F₀`):
//! ```text
//! T₀ = I  (frame F₀),
//! Tₙ₊₁ = Tₙ · C(exit_spₙ → Fₙ) · Wₙ,     Fₙ₊₁ = incident_spₙ
//! contribution of light S (in frame F) through a vertex throughput M with geometry g:
//!     Tₙ · C(exit_sp(g) → Fₙ) · M · S
//! ```
//! `C(a → b)` is [`frame_change_mueller`], `Wₙ` the vertex's sample weight and `M` an `eval`
//! (light sampling). The contribution is projected onto the Stokes cone (`|S_pol| ≤ S0`),
//! whose rounding a chain of products in `f32` may leave by a few ε.
//!
//! The `gather_*` methods add contributions to the path's radiance (a sum of vectors in the
//! cone stays in it) and count, instead of adding, any that is not finite: a renderer's pixel
//! is never poisoned by one bad sample, and [`PathThroughput::rejected`] tells how many there
//! were (0 is the crate's promise for finite input; the tests hold it).

use super::BsdfValue;
use crate::frame::{Frame, frame_change_mueller};
use crate::interaction::{Geometry, onto_cone};
use crate::mueller::Mueller;
use crate::packet::WavePacket;
use crate::real::Real;
use crate::stokes::Stokes;

/// A backward path's throughput and frame (module docs).
///
/// # Examples
/// ```
/// use gmueller::bsdf::{Material, PathThroughput, ShadingPoint, SurfaceCoherence};
/// use gmueller::frame::Frame;
/// use gmueller::interaction::{Level, RoughConductor};
/// use gmueller::psd::GaussianPsd;
/// use gmueller::stokes::Stokes;
/// use nalgebra::Vector3;
/// use num_complex::Complex;
///
/// let gold = Material::new(
///     RoughConductor::new(GaussianPsd::isotropic(0.01, 2.0)?, Complex::new(0.2, 3.5))?,
///     Level::ALL[7],
/// );
/// let at = ShadingPoint::new(Frame::from_normal(Vector3::z())?, 0.55)?;
/// let to_camera = Vector3::new(0.2, 0.0, 1.0).normalize();
/// // The camera reads Stokes vectors in its own frame (its k̂ along the ray, toward the eye).
/// let mut path = PathThroughput::new(Frame::sp(to_camera, Vector3::z())?);
/// // Light sampling: the sun, unpolarized, through the vertex.
/// let sun = Vector3::new(-0.3, 0.1, 1.0).normalize();
/// let light = gold.distant_packet(&at, Stokes::unpolarized(1.0)?, 6.8e-5, sun)?;
/// let v = gold.eval(&at, &light, to_camera)?;
/// let seen = path.contribution(&v.response.total(), &v.geometry, &light.stokes());
/// assert!(seen.s0() >= 0.0);
/// path.gather_light(&v, &light); // the same, added to the path's radiance
/// assert_eq!(path.radiance(), seen);
/// // BSDF sampling: continue the path.
/// let sky = SurfaceCoherence::new(20.0)?;
/// if let Some(s) = gold.sample_incident(&at, to_camera, &sky, 0.5, [0.3, 0.8])? {
///     path.advance(&s.weight, &s.geometry);
///     assert_eq!(path.frame(), s.geometry.incident_sp());
/// }
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathThroughput<T: Real> {
    t: Mueller<T>,
    frame: Frame<T>,
    radiance: Stokes<T>,
    rejected: usize,
}

impl<T: Real> PathThroughput<T> {
    /// The identity in the camera's frame (the frame the sensor reads Stokes vectors in).
    #[must_use]
    pub fn new(camera: Frame<T>) -> Self {
        Self {
            t: Mueller::identity(),
            frame: camera,
            radiance: Stokes::from_vector_unchecked(nalgebra::Vector4::zeros()),
            rejected: 0,
        }
    }

    /// The throughput so far, from light in [`PathThroughput::frame`] to the camera's reading.
    #[must_use]
    pub fn matrix(&self) -> &Mueller<T> {
        &self.t
    }

    /// The frame light arriving at the current vertex is expressed in.
    #[must_use]
    pub fn frame(&self) -> &Frame<T> {
        &self.frame
    }

    /// What the camera reads of `light` (Stokes, in the frame `M` takes it in) passing a vertex
    /// throughput `m` of geometry `g` ([`super::Material::eval`]'s total and geometry): `T ·
    /// C(exit_sp(g) → F) · M · S`, projected onto the Stokes cone.
    #[must_use]
    pub fn contribution(&self, m: &Mueller<T>, g: &Geometry<T>, light: &Stokes<T>) -> Stokes<T> {
        let c = self.t.0 * frame_change_mueller(g.exit_sp(), &self.frame).0 * m.0 * light.vector();
        Stokes::from_vector_unchecked(onto_cone(c))
    }

    /// What the camera reads of `light` (Stokes, in frame `from`) arriving at the current
    /// vertex directly — an emitter or the sky hit by the path's last ray: `T · C(from → F) ·
    /// S`, projected onto the Stokes cone.
    #[must_use]
    pub fn arriving(&self, from: &Frame<T>, light: &Stokes<T>) -> Stokes<T> {
        let c = self.t.0 * frame_change_mueller(from, &self.frame).0 * light.vector();
        Stokes::from_vector_unchecked(onto_cone(c))
    }

    /// Continues the path through a vertex of sample weight `weight` and geometry `g`
    /// ([`super::Material::sample_incident`]): `T ← T · C(exit_sp(g) → F) · W`, `F ←
    /// incident_sp(g)`.
    pub fn advance(&mut self, weight: &Mueller<T>, g: &Geometry<T>) {
        self.t = Mueller(self.t.0 * frame_change_mueller(g.exit_sp(), &self.frame).0 * weight.0);
        self.frame = *g.incident_sp();
    }

    /// Adds to the path's radiance what the camera reads of a light sample `light` through the
    /// vertex evaluation `v` ([`super::Material::eval`] of that packet):
    /// [`PathThroughput::contribution`] of `v`'s total with the packet's Stokes vector.
    pub fn gather_light(&mut self, v: &BsdfValue<T, Mueller<T>>, light: &WavePacket<T>) {
        self.gather(self.contribution(&v.response.total(), &v.geometry, &light.stokes()));
    }

    /// Adds [`PathThroughput::arriving`] of `light` (Stokes, in frame `from`) to the path's
    /// radiance: an emitter or the sky hit by the path's last ray.
    pub fn gather_arriving(&mut self, from: &Frame<T>, light: &Stokes<T>) {
        self.gather(self.arriving(from, light));
    }

    /// Adds `c` (camera frame) to the radiance if it is finite, else counts it as rejected.
    pub fn gather(&mut self, c: Stokes<T>) {
        if c.vector().iter().all(|x| x.is_finite()) {
            self.radiance = Stokes::from_vector_unchecked(self.radiance.vector() + c.vector());
        } else {
            self.rejected += 1;
        }
    }

    /// The radiance gathered so far, in the camera's frame.
    #[must_use]
    pub fn radiance(&self) -> Stokes<T> {
        self.radiance
    }

    /// How many contributions [`PathThroughput::gather`] refused as not finite.
    #[must_use]
    pub fn rejected(&self) -> usize {
        self.rejected
    }

    /// Scales the throughput by `factor` (Russian roulette's `1/p_survive`).
    pub fn scale(&mut self, factor: T) {
        self.t = Mueller(self.t.0 * factor);
    }

    /// Russian roulette on `M₀₀` (what the path passes of unpolarized light): a path with
    /// `M₀₀ ≥ threshold` survives; below, it survives with probability `M₀₀/threshold` and is
    /// rescaled by its inverse, so the estimate stays unbiased. `u` is uniform in `[0, 1)`.
    /// Returns `false` when the path ends (also for `M₀₀ ≤ 0` or not finite: see
    /// [`PathThroughput::is_alive`]). A `threshold` that is not positive (or NaN) plays no
    /// roulette: every live path survives unscaled.
    ///
    /// Rescaling also keeps `f32` throughputs out of the subnormal range.
    pub fn roulette(&mut self, u: T, threshold: T) -> bool {
        if !self.is_alive() {
            return false;
        }
        // Not `threshold > 0` (NaN included): no roulette.
        if threshold.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
            return true;
        }
        let survive = (self.t.0[(0, 0)] / threshold).min(T::one());
        if u >= survive {
            return false;
        }
        if survive < T::one() {
            self.scale(T::one() / survive);
        }
        true
    }

    /// `true` while some light can still pass (`M₀₀ > 0`, finite): a renderer may stop the
    /// path otherwise.
    #[must_use]
    pub fn is_alive(&self) -> bool {
        let m00 = self.t.0[(0, 0)];
        m00 > T::zero() && self.t.0.iter().all(|x| x.is_finite())
    }
}
