//! One vertex of a backward path: where a material is shaded ([`ShadingPoint`]), what a
//! renderer asks of it ([`VertexQuery`]) and what it answers ([`IncidentVertex`]) — the types
//! of [`super::Material::incident_vertex`] and [`super::Material::incident_vertices`].

use nalgebra::Vector3;

use super::{BsdfSample, BsdfValue};
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::polarization::Throughput;
use crate::mueller::Mueller;
use crate::real::Real;

/// Where a material is shaded: the shading frame (its `k` axis the normal n̂; for an
/// interface, n̂ points into the medium above) and the wavelength in the medium above (µm; the
/// vacuum wavelength for an object in air). As [`super::Bsdf::new`]'s `surface` and
/// `wavelength`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadingPoint<T: Real> {
    pub(super) frame: Frame<T>,
    pub(super) wavelength: T,
}

impl<T: Real> ShadingPoint<T> {
    /// The shading point of `frame` at `wavelength`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless the wavelength is finite and positive (a material checks
    /// its own wavenumbers when it is shaded, as [`super::Bsdf::new`]).
    pub fn new(frame: Frame<T>, wavelength: T) -> Result<Self, Error> {
        if !(wavelength > T::zero() && wavelength.is_finite()) {
            return Err(Error::OutOfRange {
                what: "wavelength at the shading point",
                value: wavelength.to_f64(),
                expected: "finite and > 0",
            });
        }
        Ok(Self { frame, wavelength })
    }

    /// The shading frame.
    #[must_use]
    pub fn frame(&self) -> &Frame<T> {
        &self.frame
    }

    /// The wavelength in the medium above.
    #[must_use]
    pub fn wavelength(&self) -> T {
        self.wavelength
    }

    /// The point with its frame turned over, `(x̂, −ŷ, −n̂)` (right-handed).
    pub(super) fn flipped(&self) -> Self {
        Self {
            frame: self.frame.reversed(),
            wavelength: self.wavelength,
        }
    }
}

/// What [`super::Material::incident_vertex`] gives at one vertex of a backward path.
#[derive(Debug, Clone)]
pub struct IncidentVertex<T: Real> {
    /// For the light's direction: its value and density, or `eval_incident`'s error; `None`
    /// when no light direction was given.
    pub light: Option<Result<LightEval<T>, Error>>,
    /// The continuation, as [`super::Material::sample_incident`] draws and weighs it (`None` for an
    /// evanescent draw).
    pub sample: Option<BsdfSample<T, Mueller<T>>>,
}

/// The light's direction at one vertex of a backward path ([`IncidentVertex::light`]).
#[derive(Debug, Clone, Copy)]
pub struct LightEval<T: Real> {
    /// Its value, [`super::Material::eval_incident`].
    pub value: BsdfValue<T, Mueller<T>>,
    /// The backward sampler's density for it, [`super::Material::pdf_incident`] (0 for a Dirac
    /// lobe's direction): the other half of the multiple-importance weight.
    pub pdf: T,
}

/// A value in BSDF form with Mueller throughputs.
pub(super) fn to_mueller<T: Real, M: Throughput<T>>(
    v: BsdfValue<T, M>,
) -> BsdfValue<T, Mueller<T>> {
    let r = v.response;
    BsdfValue {
        response: crate::interaction::polarization::MuellerResponse {
            specular: r.specular.to_mueller(),
            scattered: r.scattered.to_mueller(),
            attenuation: r.attenuation,
            side: r.side,
        },
        geometry: v.geometry,
    }
}

/// One lane of [`super::Material::incident_vertices`]: the arguments of
/// [`super::Material::incident_vertex`] for one vertex of a backward path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexQuery<T: Real> {
    /// The shading frame and wavelength of the vertex.
    pub at: ShadingPoint<T>,
    /// The direction the light leaves along (toward the previous vertex or the camera).
    pub exit: Vector3<T>,
    /// The direction to a light for next-event estimation (`None`: no light sample).
    pub to_light: Option<Vector3<T>>,
    /// The uniform that chooses the lobe.
    pub u_lobe: T,
    /// The two uniforms of the point in the lobe.
    pub u: [T; 2],
}

/// The shading point a lane runs in, from its own and its exit (a two-sided material turns it
/// over for an exit below: `Material::side`).
pub(super) type SideFn<'a, T> = dyn Fn(&ShadingPoint<T>, &Vector3<T>) -> ShadingPoint<T> + 'a;

/// A drawn direction with a Mueller weight.
pub(super) type MuellerSample<T> = BsdfSample<T, Mueller<T>>;
