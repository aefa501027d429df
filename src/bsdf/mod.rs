//! The layer a renderer calls: the kernel of [`crate::interaction`] as a BSDF — evaluation in
//! Mueller form with lobe flags, sampling and pdf in both tracing directions, and the
//! coherence one sample of light carries. `docs/renderer.md` is the guide.
//!
//! # Radiometry
//! ```text
//! M(ŝ → r̂) = f(ŝ → r̂) · cos θ_i          (per unit incident irradiance across the beam)
//! L_o(r̂)   = M S                          (S the beam irradiance of a packet: radiance × solid angle)
//! L_o(r̂)   = ∫ M(ŝ → r̂) L_i(ŝ) dω_s       (backward: an estimate is M L_i / p(ŝ))
//! ρ(ŝ)     = ∫ M(ŝ → r̂) cos θ_o dω_o / cos θ_i    (the albedo; forward: M cos θ_o/(cos θ_i p(r̂)))
//! ```
//! [`Bsdf::eval`] returns `M` (Mitsuba's `BSDF::eval` convention, `f · |cos|` of the light
//! direction), as a throughput: a Mueller matrix at the Stokes levels, `M₀₀` at the intensity
//! level ([`Throughput`]). In transmission `M` is radiance in the exit medium: it carries the
//! `n²` of radiance across the interface.
//!
//! # Frames
//! `M` acts on Stokes vectors in the incident packet's frame and returns them in the exit s/p
//! frame ([`Geometry::exit_sp`] of [`BsdfValue::geometry`]): `x̂ = ŝ_perp` (perpendicular to the
//! plane of exitance), `ŷ = p̂`, `k̂ = r̂`. The source helpers ([`sources`], [`Bsdf::surface_packet`])
//! build packets in the incident s/p frame ([`Geometry::incident_sp`]), where the rotation `T`
//! of the kernel is the identity; a path's throughput is chained with
//! [`Throughput::frame_change`] from one vertex's exit frame to the next vertex's incident
//! frame (the same ray). S3 follows this crate's `e^{−iωt}` (Mitsuba 3 prints the opposite sign:
//! [`crate::frame::convention`]).
//!
//! # Lobes
//! Each evaluation holds the coherent specular lobe (mirror or Snell direction, widened by the
//! coherence) and the scattered part separately
//! ([`crate::interaction::polarization::MuellerResponse`]), on the side of the exit direction. At
//! the plane-wave level the specular lobe (and a grating's orders) are Dirac deltas: `eval` leaves
//! them out and [`Bsdf::flags`] says
//! [`LobeFlags::DELTA`]; the samplers draw them with their probability and return their
//! throughput ([`BsdfSample`]).
//!
//! # Roughness
//! The roughness level is the kernel's third type parameter (`Kernel<Pol, Coh, Rough>`,
//! default [`crate::interaction::roughness::FirstOrder`]: first-order results are bit for bit those
//! of before the parameter existed). Beyond first order
//! ([`crate::interaction::roughness::KirchhoffSeries`],
//! [`crate::interaction::roughness::Geometric`],
//! [`crate::interaction::roughness::KirchhoffQuadrature`]) use a material with the tangent-plane
//! scatterer, [`crate::interaction::KirchhoffDielectric`] or
//! [`crate::interaction::KirchhoffConductor`]; [`Bsdf::eval`] is then the kernel's
//! `evaluate_mueller` at that level, bit for bit. The samplers' scattered part proposes the
//! series' orders instead of the first-order lobe: for a Gaussian PSD, the Poisson weights of the
//! orders at the side's specular `g₀ = (vσ)²` grouped into at most six lobes `𝒩(0, n̄ C_p + Ξ)`
//! (the first-order lobe as `g₀ → 0`, the geometric slope lobe as `g₀ → ∞`); for PSDs without
//! that lobe (the quadrature level's K-correlations and mixtures) the first-order lobes plus a
//! 25 % share of the projected disk. Either is drawn exactly and [`LobeSampler::pdf`] is its
//! density (Pearson's chi-square for 20 proposals, `vσ ≈ 1, 3, 10`, both directions and sides,
//! total internal reflection, the plane wave, a geometric conductor, a K-correlation:
//! `tests/bsdf/rough.rs`). Furnace of lossless rough glass at `vσ ≈ 1, 3, 10`, incidence 0–60°
//! and from inside: the sampler's estimate agrees with quadrature within 4 standard errors; the
//! albedo is 0.993–1.003 (the tangent plane has no shadowing, so it is not exactly
//! conservative); the variance at equal sample count is 1.6–13 000× (`vσ ≈ 1`), 17–570×
//! (`vσ ≈ 3`) and 31–46 000× (`vσ ≈ 10`) below the first-order proposal's. At `vσ ≈ 10` toward
//! grazing exits the tangent plane's `1/cos²θ_o` makes the weights grow like `1/cos θ_o`, which
//! no projected-disk proposal follows (relative standard error 5·10⁻³–10⁻² in 20 000 draws).
//! Chosen at run time: [`crate::interaction::Level::dispatch_rough`].
//!
//! # Reciprocity
//! The plane-wave level is reciprocal, `M(b → a) = D M(a → b)ᵀ D` with `D = diag(1, 1, −1, 1)`
//! in reflection (and `f_t(i → o)/n_o² = f_t(o → i)/n_i²` across an interface, in the same
//! `D`-transposed form; `tests/bsdf/reciprocity.rs`: residuals ≤ 3.4e-13). The partially
//! coherent kernel is **not**: the incident footprint (the section `Ξ` of the light's
//! coherence) enters, and it belongs to the light, not to the exit direction. With a
//! direction-dependent footprint (the sun's van Cittert–Zernike packet, fixed widths across
//! the beam) both parts deviate — 0.6–6.5 % 0.1–0.5° off the mirror at sunlight coherence, by
//! factors up to 10¹⁴ in far tails at 1 µm; with [`SurfaceCoherence::fixed`] (the same
//! `Ξ = I/σ²` from every direction) the scattered part is reciprocal to rounding (6e-16) and
//! only the coherent lobe deviates (its `cos θ_o`, its mass `E` and the Fresnel factor at
//! `θ_i`). Over the whole angular range (`reciprocity_over_the_angular_range`: the relative
//! deviation of `f(r̂ → ŝ)` from `D f(ŝ → r̂)ᵀ D`, r̂ within two lobe widths of ŝ's mirror, rough
//! gold and glass in reflection):
//!
//! | coherence | 0° | 15° | 30° | 45° | 60° | 75° | 85° | 89° |
//! |---|---|---|---|---|---|---|---|---|
//! | 20 µm, horizon rule (gold / glass) | 0.0 / 0.0 % | 0.4 / 0.6 % | 0.9 / 1.7 % | 1.8 / 3.4 % | 3.5 / 5.4 % | 8.6 / 11.3 % | 6.7 / 7.1 % | 1.3 / 1.3 % |
//! | 2 µm, horizon rule | 0.3 / 0.4 % | 2.9 / 4.7 % | 6.3 / 11.4 % | 12 / 22 % | 22 / 32 % | 19 / 23 % | 6.8 / 7.2 % | 1.3 / 1.3 % |
//! | 20 µm fixed | 0.0 / 0.0 % | 0.4 / 0.6 % | 0.9 / 1.7 % | 1.9 / 3.5 % | 3.4 / 5.4 % | 6.6 / 10 % | 23 / 27 % | 91 / 98 % |
//! | 2 µm fixed | 0.5 / 0.7 % | 4.4 / 6.4 % | 9.7 / 18 % | 21 / 41 % | 44 / 79 % | 104 / 187 % | 1237 / 1807 % | 87 / 90 % |
//!
//! A backward tracer therefore samples ŝ for a given r̂ ([`Bsdf::incident_sampler`]) but always
//! **evaluates in the physical direction**, `M(ŝ → r̂)` with the coherence of the light arriving
//! along ŝ — never `M(r̂ → ŝ)` with the roles swapped: under uniform light of 1 µm surface
//! coherence the swapped estimate of rough glass misses the physical one (which agrees with
//! quadrature within one standard error) by 5–490 standard errors, 0.6–4 %
//! (`tests/bsdf/reciprocity.rs`).
//!
//! # Near the horizon
//! The kernel's coherent lobe is a Gaussian in the tangential wave vector, of width `1/(k w)` in
//! the projected disk. Near the horizon part of it lies beyond the propagating directions and
//! the exit cosine varies across it: its share of the incident power is `F · E`, `F` the
//! Fresnel share and
//! ```text
//! E = ∫_{|u|<1} √(1 − |u|²) 𝒩_Σ(u − c) d²u / √(1 − |c|²)       (Σ = Ξ/k², c the lobe's centre)
//! ```
//! (0.27–6.8 for lossless interfaces at 85–89° with 2–100 µm of surface coherence). `E` is also
//! the irradiance the light's propagating plane-wave components deliver onto the surface,
//! relative to the `cos θ_i` the kernel assumes. This layer divides the coherent lobe of each
//! side by its `E` ([`Incident::specular_mass`], computed by [`Bsdf::prepare`]: a second-order
//! expansion, or a 576-node quadrature within reach of the horizon or for lobes wider than
//! about `1/24` of the disk): a lossless interface then keeps `R + T = 1` at every incidence
//! (within 8.7·10⁻⁵ in `f64`, 3.8·10⁻⁴ in `f32`, up to 89°, for the sun, 2–100 µm, with and
//! without the horizon rule: `tests/bsdf/horizon.rs`). For a packet with two shapes
//! (`Θ_x ≠ Θ_y`) `E` averages the channels' masses with their intensities, not with their
//! Fresnel shares: within 7.2·10⁻³ of 1 in the same test (every packet of the source helpers
//! has one shape). What remains: the lobe carries the Fresnel matrix of its centre (not each
//! plane wave's own), and the scattered part is not normalised (first order, a `(kσ)²`
//! effect). The kernel itself ([`crate::interaction`]) stays the seed's S2.20, unnormalised.
//! Backward, the white furnace then depends on `q = k w cos²θ` alone and exceeds 1 by
//! `≈ 2/q²`; [`SurfaceCoherence`]'s horizon rule keeps `q ≥ 16` (within 0.9 % up to 89°).
//!
//! # Cost (no heap allocation anywhere)
//! [`Bsdf::prepare`] once per light packet (the kernel's per-packet work), then [`Bsdf::eval`]
//! per exit direction; a sampler is built per shading point (a 2×2 Cholesky factor per lobe,
//! one Fresnel evaluation) and draws in closed form. Measured in `benches/bsdf.rs`.

mod batch;
mod bundle;
mod flags;
mod horizon;
mod interface;
mod lobes;
mod material;
mod model;
mod orders;
mod path;
mod sampler;
pub mod sources;
mod vertex;
mod vertices;

pub use bundle::{Bundle, BundleCoherence, BundlePdf, BundleSample, BundleValues};
pub use flags::LobeFlags;
pub use interface::Interface;
pub use material::Material;
pub use model::{BsdfKernel, BsdfSurface};
pub use path::PathThroughput;
pub use sampler::{
    DirectionSample, LobeSampler, NO_LOBE, Part, SampledLobe, SamplesSoa, UniformsSoa,
};
pub use sources::{HORIZON_RULE_Q, SurfaceCoherence, area_light, distant_disk};
pub use vertex::{IncidentVertex, LightEval, ShadingPoint, VertexQuery};

use nalgebra::{Matrix2, Unit, Vector3};

use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::Incidence;
use crate::interaction::coherence::{CoherenceLevel, CoherenceModel};
use crate::interaction::pbsdf::Pbsdf;
use crate::interaction::polarization::{
    KernelOutput, MuellerResponse, PolarizationModel, Throughput,
};
use crate::interaction::roughness::{RoughnessLevel, RoughnessModel};
use crate::interaction::{Geometry, PreparedPacket, Side, flush_to_normal, throughput_scaled};
use crate::mueller::Mueller;
use crate::numerics::unit_direction;
use crate::packet::WavePacket;
use crate::psd::{Psd, Shape};
use crate::real::Real;
use crate::stokes::Stokes;
use sampler::Setup;

/// A material at one shading point, for one wavelength, at the kernel's model level: what a
/// renderer calls (module docs).
///
/// `Bsdf<'m, T, S, K>`: the scalar `T`, the surface `S` (a [`crate::interaction::RoughSurface`], borrowed for
/// `'m`: [`BsdfSurface`] names its PSD and pBSDFs) and the kernel `K` (a [`crate::interaction::Kernel`]:
/// [`BsdfKernel`] names its levels). Code generic over it needs two bounds,
/// `S: BsdfSurface<T>, K: BsdfKernel<T, S::Psd>` ([`model`](BsdfSurface) docs); a renderer
/// that holds materials of several kinds and levels uses the type-erased [`Material`].
///
/// `surface` is the shading frame (t̂₁, t̂₂, n̂) ([`Frame::from_normal`] builds one from a normal);
/// for a dielectric n̂ points into the medium "above" (out of the glass for glass in air,
/// [`crate::interaction::RoughDielectric`]'s `η = n_below/n_above`); an opaque material is lit
/// and seen from the side n̂ points to. `wavelength` is the light's wavelength in the medium
/// above (the vacuum wavelength for an object in air); below an interface it is `λ/η`.
///
/// # Examples
/// ```
/// use gmueller::bsdf::{Bsdf, SurfaceCoherence};
/// use gmueller::frame::Frame;
/// use gmueller::interaction::{Full, Kernel, Partial, RoughDielectric};
/// use gmueller::psd::GaussianPsd;
/// use gmueller::stokes::Stokes;
/// use nalgebra::Vector3;
///
/// let glass = RoughDielectric::new(GaussianPsd::<f64, 2>::isotropic(0.01, 2.0)?, 1.5)?;
/// let frame = Frame::from_normal(Vector3::z())?;
/// let bsdf = Bsdf::new(&glass, Kernel::<Full, Partial>::default(), frame, 0.5)?;
/// // Backward: the camera looks along −r̂; draw the direction the light comes from.
/// let to_camera = Vector3::new(0.3, 0.1, 0.95);
/// let sky = SurfaceCoherence::new(20.0)?; // 20 µm on the surface
/// let sampler = bsdf.incident_sampler(to_camera, &sky)?;
/// if let Some(s) = sampler.sample(0.4, [0.2, 0.7]) {
///     assert!((sampler.pdf(&s.direction) - s.pdf).abs() <= 1e-12 * s.pdf || s.lobe.delta);
///     // The light arriving along s.direction, with the assumed coherence, evaluated in the
///     // physical direction (ŝ → r̂):
///     let light = bsdf.surface_packet(Stokes::unpolarized(1.0)?, s.direction, &sky)?;
///     let v = bsdf.eval(&bsdf.prepare(&light)?, to_camera)?;
///     assert!(v.response.total().matrix()[(0, 0)] >= 0.0);
/// }
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy)]
pub struct Bsdf<'m, T: Real, S, K> {
    material: &'m S,
    kernel: K,
    surface: Frame<T>,
    /// The wavenumbers above and below (`η k` below an interface, as [`Geometry`] derives it;
    /// the one above for an opaque surface): the shading point owns them, and the packets it
    /// builds carry them exactly.
    k: [T; 2],
    eta: Option<T>,
}

/// A light packet prepared at a shading point ([`Bsdf::prepare`]): the kernel's per-packet
/// work, the direction to the source and the medium it arrives in.
///
/// # Reuse
/// An `Incident` borrows nothing: it serves every [`Bsdf`] with the same material (the same
/// value: the one it was prepared with or a copy), kernel, shading frame and wavelength, which
/// answer with it exactly as the one that prepared it (`tests/bsdf/material.rs`,
/// `an_incident_serves_every_bsdf_of_the_same_shading_point`). With another frame, wavelength,
/// kernel or material its numbers are of another shading point and the answers are wrong:
/// debug builds assert that the wavenumbers agree (`Kernel::evaluate_mueller_prepared`),
/// release builds check nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incident<T: Real, Pol, Coh> {
    prepared: PreparedPacket<T, Pol, Coh>,
    to_source: Vector3<T>,
    facing: Frame<T>,
    from_below: bool,
    /// The incident side of every exit's geometry (`cos θ_i`, the incident s/p frame), built
    /// once here rather than per exit; `None` where ŝ has none (the exits' geometries then
    /// report the error).
    incidence: Option<Incidence<T>>,
    /// `E` of the coherent lobe on each side (reflected, transmitted): module docs,
    /// "Near the horizon".
    specular_mass: [T; 2],
}

impl<T: Real, Pol, Coh> Incident<T, Pol, Coh> {
    /// ŝ, the unit direction toward the source.
    #[must_use]
    pub fn to_source(&self) -> Vector3<T> {
        self.to_source
    }

    /// The kernel's per-packet work. The kernel evaluated with it directly gives the coherent
    /// lobe without the normalisation [`Incident::specular_mass`] of this layer.
    #[must_use]
    pub fn prepared(&self) -> &PreparedPacket<T, Pol, Coh> {
        &self.prepared
    }

    /// `E`, the share of the incident power that the kernel's coherent specular lobe on `side`
    /// carries over the propagating directions, relative to the Fresnel share (module docs,
    /// "Near the horizon"): [`Bsdf::eval`] and the weights divide that lobe by it. 1 at the
    /// plane-wave level, for a side without a propagating specular direction (total internal
    /// reflection), and for an opaque surface's transmission.
    #[must_use]
    pub fn specular_mass(&self, side: Side) -> T {
        self.specular_mass[usize::from(side == Side::Transmission)]
    }

    /// The coherent lobe of a kernel response on `side`, divided by its mass.
    #[inline]
    fn normalise<M: Throughput<T>>(&self, r: MuellerResponse<T, M>) -> MuellerResponse<T, M> {
        let mass = self.specular_mass(r.side);
        if mass == T::one() {
            r
        } else {
            r.specular_scaled(mass.recip())
        }
    }
}

/// [`Bsdf::eval`]'s answer: the kernel in BSDF form and the geometry it was evaluated in
/// (its [`Geometry::exit_sp`] is the output frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfValue<T: Real, M> {
    /// The specular and scattered throughputs, per unit incident irradiance.
    pub response: MuellerResponse<T, M>,
    /// The geometry (frames, angles, side).
    pub geometry: Geometry<T>,
}

/// A sampled direction with its Monte Carlo weight ([`Bsdf::sample_exit`],
/// [`Bsdf::sample_incident`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfSample<T: Real, M> {
    /// The direction, its pdf and lobe.
    pub sample: DirectionSample<T>,
    /// The Monte Carlo weight: forward, the fraction of the incident power carried,
    /// `M cos θ_o/(cos θ_i p)`; backward, the radiance throughput `M/p` (module docs). For a
    /// delta lobe, the lobe's integral in place of `M`, divided by its probability.
    pub weight: M,
    /// The geometry of the sampled pair of directions (frames: `weight` maps the incident
    /// packet's frame to [`Geometry::exit_sp`]).
    pub geometry: Geometry<T>,
}

/// The share of the wider specular lobe of the backward sampler where the horizon rule is
/// active, and its width relative to the lobe ([`Bsdf::incident_sampler`]).
const WIDE_SHARE: f64 = 0.25;
const WIDE_FACTOR: f64 = 2.0;

/// What [`Bsdf::sample_exit`] and [`Bsdf::sample_incident`] return: a weighted sample, `None`
/// for an evanescent draw.
pub type SampleResult<T, Pol> =
    Result<Option<BsdfSample<T, <Pol as PolarizationModel>::Throughput<T>>>, Error>;

/// What [`Bsdf::exit_weight`] and [`Bsdf::incident_weight`] return: the weight (a throughput
/// of the polarization level) and the geometry of the pair of directions.
pub type WeightResult<T, Pol> =
    Result<(<Pol as PolarizationModel>::Throughput<T>, Geometry<T>), Error>;

impl<'m, T, S, K> Bsdf<'m, T, S, K>
where
    T: Real,
    S: BsdfSurface<T>,
    K: BsdfKernel<T, S::Psd>,
{
    /// The material `material` at the shading frame `surface`, at `wavelength` (in the medium
    /// above; see the type docs), evaluated by `kernel`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless the wavelength is finite and positive with the wavenumbers
    /// of both media normal numbers.
    pub fn new(
        material: &'m S,
        kernel: K,
        surface: Frame<T>,
        wavelength: T,
    ) -> Result<Self, Error> {
        let k = T::two_pi() / wavelength;
        let eta = material.parts().specular.transmission_index();
        let normal = |x: T| x.is_finite() && x >= T::MIN_POSITIVE;
        if !(wavelength > T::zero() && normal(k) && eta.is_none_or(|e| normal(e * k))) {
            return Err(Error::OutOfRange {
                what: "wavelength at the shading point",
                value: wavelength.to_f64(),
                expected: "finite and > 0, with 2π/λ (and η 2π/λ) normal numbers",
            });
        }
        Ok(Self {
            material,
            kernel,
            surface,
            k: [k, eta.map_or(k, |e| k * e)],
            eta,
        })
    }

    /// The shading frame.
    #[must_use]
    pub fn surface(&self) -> &Frame<T> {
        &self.surface
    }

    /// The lobes this BSDF has at the kernel's coherence level ([`LobeFlags`]): what every
    /// packet sees whose section `Ξ` is representable in `T` (the tested ranges). A packet
    /// whose section over- or underflows is evaluated and sampled at the plane-wave level,
    /// with Dirac lobes: [`Bsdf::incident_flags`] gives the flags of a prepared packet.
    #[must_use]
    pub fn flags(&self) -> LobeFlags {
        self.flags_at(<K::Coh as CoherenceModel>::LEVEL == CoherenceLevel::PlaneWave)
    }

    /// The lobes for the prepared packet `incident`, as [`Bsdf::eval`] and
    /// [`Bsdf::exit_sampler`] treat it: [`Bsdf::flags`], except for a packet whose section `Ξ`
    /// of the coherence by the surface is not representable in `T` (`f32`: a coherence width
    /// of ~10¹¹ λ or more; [`crate::interaction::PreparedPacket::section`] is `None`), which
    /// the kernel and the sampler take at the plane-wave level: its specular lobe (and a
    /// grating's orders) are then [`LobeFlags::DELTA`], left out of `eval` and drawn as deltas
    /// — a renderer that skips multiple importance sampling on deltas must ask here.
    #[must_use]
    pub fn incident_flags(&self, incident: &Incident<T, K::Pol, K::Coh>) -> LobeFlags {
        let plane = <K::Coh as CoherenceModel>::LEVEL == CoherenceLevel::PlaneWave
            || (<K::Coh as CoherenceModel>::USES_SHAPE && incident.prepared.section().is_none());
        self.flags_at(plane)
    }

    /// The lobe flags with (`delta`) or without the plane wave's Dirac lobes.
    fn flags_at(&self, delta: bool) -> LobeFlags {
        let mut f = LobeFlags::REFLECTION;
        if self.eta.is_some() {
            f = f | LobeFlags::TRANSMISSION;
        }
        f = f | if delta {
            LobeFlags::DELTA
        } else {
            LobeFlags::COHERENT_SPECULAR
        };
        if self.material.parts().psd.variance() > T::zero() {
            f = f | match (self.material.parts().psd.form().shape(), delta) {
                (Shape::Zero, _) => LobeFlags::NONE,
                (Shape::Orders(_) | Shape::Origin, true) => LobeFlags::DELTA,
                _ => LobeFlags::SCATTERED,
            };
        }
        f
    }

    /// The wavenumber of the medium on the side of `direction` (pointing away from the
    /// surface): `2π/λ` above, `η 2π/λ` below an interface.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a direction in the plane of the surface, or below an opaque
    /// one.
    pub fn wavenumber(&self, direction: &Vector3<T>) -> Result<T, Error> {
        let c = direction.dot(&self.surface.k());
        if c > T::zero() {
            return Ok(self.k[0]);
        }
        match self.eta {
            Some(_) if c < T::zero() => Ok(self.k[1]),
            _ => Err(Error::OutOfRange {
                what: "direction at the shading point (in the surface's plane, or below an opaque surface)",
                value: c.to_f64(),
                expected: "> 0 (opaque), ≠ 0 (interface)",
            }),
        }
    }

    /// The wavelength of the medium on the side of `direction` (what a packet arriving from
    /// there must carry).
    ///
    /// # Errors
    /// As [`Bsdf::wavenumber`].
    pub fn wavelength(&self, direction: &Vector3<T>) -> Result<T, Error> {
        Ok(T::two_pi() / self.wavenumber(direction)?)
    }

    /// The geometry of light from `to_source` leaving along `exit` at this shading point
    /// ([`Geometry::at_interface`] for a dielectric, [`Geometry::new`] for an opaque surface),
    /// at the wavenumber of the source's medium.
    ///
    /// # Errors
    /// As those constructors, and as [`Bsdf::wavenumber`] for ŝ.
    pub fn geometry(&self, to_source: Vector3<T>, exit: Vector3<T>) -> Result<Geometry<T>, Error> {
        let k = self.wavenumber(&to_source)?;
        let s = unit_direction(&to_source, "direction to the source")?;
        let r = unit_direction(&exit, "exit direction")?;
        self.geometry_at(k, &s, &r)
    }

    /// [`Bsdf::geometry`] of unit directions, `k` the wavenumber of ŝ's medium.
    fn geometry_at(
        &self,
        k: T,
        s: &Unit<Vector3<T>>,
        r: &Unit<Vector3<T>>,
    ) -> Result<Geometry<T>, Error> {
        match self.eta {
            Some(eta) => Geometry::interface_units(k, &self.surface, eta, s, r),
            None => Geometry::opaque_units(k, &self.surface, s, r),
        }
    }

    /// [`Bsdf::geometry`] from a prepared incident light (its ŝ is unit) to the unit exit `r`.
    fn geometry_from(
        &self,
        incident: &Incident<T, K::Pol, K::Coh>,
        r: &Unit<Vector3<T>>,
    ) -> Result<Geometry<T>, Error> {
        let k = self.wavenumber(&incident.to_source)?;
        match &incident.incidence {
            // The geometry_at of ŝ bit for bit (`Geometry::leaving`), without rebuilding the
            // incident side.
            Some(inc) => Geometry::leaving(k, inc, self.eta, r),
            None => self.geometry_at(k, &Unit::new_unchecked(incident.to_source), r),
        }
    }

    /// The surface coherence width of light arriving from `to_source` under `coherence`
    /// ([`SurfaceCoherence`], "The horizon rule"): `σ` combined with the rule's `Q/(k cos²θ)`
    /// of the direction itself and, across an interface, of its Snell partner on the other
    /// side (whose lobe must fit that side's horizon too).
    ///
    /// # Errors
    /// As [`Bsdf::wavenumber`] for `to_source`, and for a zero or non-finite direction.
    pub fn surface_width(
        &self,
        to_source: &Vector3<T>,
        coherence: &SurfaceCoherence<T>,
    ) -> Result<T, Error> {
        let s = unit_direction(to_source, "direction to the source")?;
        Ok(self.width_of(&s, self.wavenumber(&s)?, coherence))
    }

    /// [`Bsdf::surface_width`] of the unit direction `s` in the medium of wavenumber `k`.
    fn width_of(&self, s: &Vector3<T>, k: T, coherence: &SurfaceCoherence<T>) -> T {
        let cos = s.dot(&self.surface.k()).abs();
        let partner = self.eta.and_then(|_| {
            let k_t = if s.dot(&self.surface.k()) > T::zero() {
                self.k[1]
            } else {
                self.k[0]
            };
            let ratio = k / k_t;
            let sin2 = (T::one() - cos) * (T::one() + cos) * ratio * ratio;
            (sin2 < T::one()).then(|| ((T::one() - sin2).sqrt(), k_t))
        });
        match partner {
            Some(t) => coherence.combined(&[(cos, k), t]),
            None => coherence.combined(&[(cos, k)]),
        }
    }

    /// A packet arriving from `to_source` with surface-isotropic coherence `coherence` at the
    /// wavelength of the source's medium, carrying `stokes` in the incident s/p frame: the
    /// width [`Bsdf::surface_width`] (the horizon rule on both sides of an interface) through
    /// [`SurfaceCoherence::packet`].
    ///
    /// # Errors
    /// As [`SurfaceCoherence::packet`] and [`Bsdf::surface_width`].
    pub fn surface_packet(
        &self,
        stokes: Stokes<T>,
        to_source: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
    ) -> Result<WavePacket<T>, Error> {
        let k = self.wavenumber(&to_source)?;
        let width = self.surface_width(&to_source, coherence)?;
        SurfaceCoherence::fixed(width)?
            .packet(stokes, to_source, &self.surface, T::two_pi() / k)
            .map(|p| p.at_wavenumber(k))
    }

    /// A sample of a distant disk source of solid angle `Ω` along `to_source`
    /// ([`sources::distant_disk`]) at the wavelength of the source's medium.
    ///
    /// # Errors
    /// As [`sources::distant_disk`] and [`Bsdf::wavenumber`].
    pub fn distant_packet(
        &self,
        stokes: Stokes<T>,
        solid_angle: T,
        to_source: Vector3<T>,
    ) -> Result<WavePacket<T>, Error> {
        let k = self.wavenumber(&to_source)?;
        distant_disk(
            stokes,
            solid_angle,
            to_source,
            &self.surface,
            T::two_pi() / k,
        )
        .map(|p| p.at_wavenumber(k))
    }

    /// The kernel's per-packet work for `packet` at this shading point.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when the packet's wavelength is not the one of the medium it
    /// arrives from ([`Bsdf::wavelength`] of `−k̂`, within 16 ulps): a packet built for another
    /// wavelength, or for the vacuum wavelength inside glass; as [`crate::interaction::Kernel::prepare`].
    pub fn prepare(&self, packet: &WavePacket<T>) -> Result<Incident<T, K::Pol, K::Coh>, Error> {
        // ŝ as the kernel's preparation normalises it (its incident frame is built from it).
        let s = unit_direction(&-packet.direction(), "direction to the source")?.into_inner();
        let k = self.wavenumber(&s)?;
        if !crate::packet::same_wavenumber(k, packet.wavenumber()) {
            return Err(Error::OutOfRange {
                what: "packet wavelength (not the wavelength of the medium it arrives from)",
                value: packet.wavelength().to_f64(),
                expected: "Bsdf::wavelength(−k̂): λ above the surface, λ/η below an interface",
            });
        }
        let facing = self.surface.facing(&s);
        let prepared = self.kernel.kernel().prepare(packet, &facing)?;
        Ok(self.incident(prepared, s, facing, [true; 2]))
    }

    /// The [`Incident`] of `prepared` arriving from the unit direction `s` (`facing`: the
    /// shading frame facing it), with the specular mass of the sides in `sides`.
    fn incident(
        &self,
        prepared: PreparedPacket<T, K::Pol, K::Coh>,
        s: Vector3<T>,
        facing: Frame<T>,
        sides: [bool; 2],
    ) -> Incident<T, K::Pol, K::Coh> {
        let from_below = s.dot(&self.surface.k()) < T::zero();
        let specular_mass = self.specular_mass(&prepared, &s, &facing, from_below, sides);
        // An opaque surface has no incident side below it (its geometries report the error).
        let incidence = Incidence::of(&s, &self.surface)
            .ok()
            .filter(|_| self.eta.is_some() || !from_below);
        Incident {
            prepared,
            to_source: s,
            facing,
            from_below,
            incidence,
            specular_mass,
        }
    }

    /// What [`Bsdf::prepare`] gives for the packet [`Bsdf::surface_packet`] builds for
    /// unpolarized light of unit irradiance arriving from `to_source` with the surface coherence
    /// `coherence` — the light the backward weights ([`Bsdf::incident_weight`]) and
    /// [`Material::eval_incident`] evaluate — without building the packet: its section
    /// on the surface is `I/w²` with `w` the [`Bsdf::surface_width`] of `to_source`, its Stokes
    /// vector `(1, 0, 0, 0)` in the incident s/p frame. The same numbers as the packet's path
    /// up to rounding (`tests/bsdf/eval.rs`, `prepare_surface_is_the_surface_packet_prepared`).
    ///
    /// # Errors
    /// As [`Bsdf::surface_width`].
    pub fn prepare_surface(
        &self,
        to_source: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
    ) -> Result<Incident<T, K::Pol, K::Coh>, Error> {
        self.surface_incident(to_source, coherence, [true; 2])
    }

    /// [`Bsdf::prepare_surface`] with the specular mass of the sides in `sides` (reflected,
    /// transmitted) alone; the others' are left at 1 (for a weight that reads one side).
    fn surface_incident(
        &self,
        to_source: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        sides: [bool; 2],
    ) -> Result<Incident<T, K::Pol, K::Coh>, Error> {
        let s = unit_direction(&to_source, "direction to the source")?;
        self.surface_incident_at(&s, coherence, sides)
    }

    /// [`Bsdf::surface_incident`] of a unit direction.
    fn surface_incident_at(
        &self,
        s: &Unit<Vector3<T>>,
        coherence: &SurfaceCoherence<T>,
        sides: [bool; 2],
    ) -> Result<Incident<T, K::Pol, K::Coh>, Error> {
        let s = s.into_inner();
        let k = self.wavenumber(&s)?;
        let width = self.width_of(&s, k, coherence);
        let facing = self.surface.facing(&s);
        let prepared = self
            .kernel
            .kernel()
            .prepare_unpolarized_isotropic(k, width.recip());
        Ok(self.incident(prepared, s, facing, sides))
    }

    /// `E` per side for a prepared packet (module docs, "Near the horizon"): `E` of each
    /// channel's section, averaged with the channels' intensities; 1 for a side not `wanted`.
    fn specular_mass(
        &self,
        prepared: &PreparedPacket<T, K::Pol, K::Coh>,
        s: &Vector3<T>,
        facing: &Frame<T>,
        from_below: bool,
        wanted: [bool; 2],
    ) -> [T; 2] {
        let mut channels = [(0.0, Matrix2::<f64>::zeros()); 2];
        let count = match (prepared.channel_sections(), prepared.section()) {
            _ if <K::Coh as CoherenceModel>::LEVEL == CoherenceLevel::PlaneWave => 0,
            (Some([(x, wx), (y, wy)]), _) => {
                channels = [
                    (wx.to_f64(), x.covariance().map(T::to_f64)),
                    (wy.to_f64(), y.covariance().map(T::to_f64)),
                ];
                2
            }
            (None, Some(xi)) => {
                channels[0] = (1.0, xi.covariance().map(T::to_f64));
                1
            }
            (None, None) => 0,
        };
        if count == 0 {
            return [T::one(); 2];
        }
        let k = prepared.wavenumber().to_f64();
        let st = nalgebra::Vector2::new(s.dot(&facing.x()).to_f64(), s.dot(&facing.y()).to_f64());
        let mass = |k_exit: f64| {
            let ratio = k / k_exit;
            let c = -st * ratio;
            let (mut e, mut w) = (0.0, 0.0);
            for (weight, xi) in &channels[..count] {
                e += weight * horizon::lobe_mass(&(xi / (k_exit * k_exit)), &c);
                w += weight;
            }
            let e = T::lit(e / w);
            if e > T::zero() && e.is_finite() && e.recip().is_finite() {
                e
            } else {
                T::one()
            }
        };
        let transmitted = match self.eta {
            Some(eta) if wanted[1] => {
                let eta = eta.to_f64();
                mass(if from_below { k / eta } else { k * eta })
            }
            _ => T::one(),
        };
        [if wanted[0] { mass(k) } else { T::one() }, transmitted]
    }

    /// The kernel in BSDF form for the prepared packet leaving along `exit`: `M(ŝ → r̂)` per
    /// lobe (module docs; Dirac lobes excluded).
    ///
    /// # Errors
    /// As [`Bsdf::geometry`].
    pub fn eval(
        &self,
        incident: &Incident<T, K::Pol, K::Coh>,
        exit: Vector3<T>,
    ) -> Result<BsdfValue<T, <K::Pol as PolarizationModel>::Throughput<T>>, Error> {
        self.eval_at(incident, &unit_direction(&exit, "exit direction")?)
    }

    /// [`Bsdf::eval`] toward the unit exit `r`.
    fn eval_at(
        &self,
        incident: &Incident<T, K::Pol, K::Coh>,
        r: &Unit<Vector3<T>>,
    ) -> Result<BsdfValue<T, <K::Pol as PolarizationModel>::Throughput<T>>, Error> {
        let g = self.geometry_from(incident, r)?;
        Ok(BsdfValue {
            response: incident.normalise(self.kernel.kernel().evaluate_mueller_prepared(
                self.material.parts(),
                &incident.prepared,
                &g,
            )),
            geometry: g,
        })
    }

    /// The kernel's Stokes form for the prepared packet leaving along `exit` (what
    /// `eval(..).response.apply(&packet.stokes())` equals, with the kernel's log-space range).
    ///
    /// # Errors
    /// As [`Bsdf::geometry`].
    pub fn eval_stokes(
        &self,
        incident: &Incident<T, K::Pol, K::Coh>,
        exit: Vector3<T>,
    ) -> Result<<K::Pol as PolarizationModel>::Output<T>, Error> {
        let g = self.geometry_from(incident, &unit_direction(&exit, "exit direction")?)?;
        let out =
            self.kernel
                .kernel()
                .evaluate_prepared(self.material.parts(), &incident.prepared, &g);
        let mass = incident.specular_mass(g.side());
        Ok(if mass == T::one() {
            out
        } else {
            out.specular_scaled(mass.recip())
        })
    }

    /// The sampler of exit directions for the prepared packet (forward tracing): its lobes are
    /// the packet's own (the sections `Ξ` of its coherence).
    ///
    /// # Errors
    /// [`Error::Unrealizable`] when a lobe covariance over- or underflows the type, or a lobe is
    /// narrower than `8ε` (machine epsilons of `T`) in the projected disk — too narrow for the
    /// float grid of directions there (`f32`: coherence wider than ~10⁵ λ; `f64`: ~10¹⁴ λ).
    pub fn exit_sampler(
        &self,
        incident: &Incident<T, K::Pol, K::Coh>,
    ) -> Result<LobeSampler<'m, T>, Error> {
        let prepared = &incident.prepared;
        let k = prepared.wavenumber();
        let k_across = self
            .eta
            .map(|e| if incident.from_below { k / e } else { k * e });
        let cos_i = incident.to_source.dot(&incident.facing.k());
        let reflectance = self
            .material
            .parts()
            .specular
            .reflectance(cos_i, incident.from_below);
        let section = prepared.section().map(|g| *g.covariance());
        let (level, specular) = match (<K::Coh as CoherenceModel>::USES_SHAPE, section) {
            (true, None) => (CoherenceLevel::PlaneWave, false),
            _ => (<K::Coh as CoherenceModel>::LEVEL, true),
        };
        let (channels, channel_count) = match (prepared.channel_sections(), section) {
            (Some([(x, wx), (y, wy)]), _) => {
                let total = wx + wy;
                (
                    [(wx / total, *x.covariance()), (wy / total, *y.covariance())],
                    2,
                )
            }
            (None, Some(xi)) => ([(T::one(), xi), (T::zero(), xi)], 1),
            (None, None) => ([(T::one(), Matrix2::identity()); 2], 0),
        };
        self.sampler(&Setup {
            known: incident.to_source,
            facing: incident.facing,
            k_known: k,
            k_across,
            forward: true,
            reflectance,
            variance: self.material.parts().psd.variance(),
            lobes: self.material.parts().psd.form().shape(),
            level,
            specular,
            channels,
            channel_count,
            // The scattered lobes live in the caller's frame: the section, given in the facing
            // frame, is mirrored when that frame is reversed (light from below).
            blur: if level == CoherenceLevel::PlaneWave {
                None
            } else {
                section.map(|b| {
                    if incident.from_below {
                        Matrix2::new(b[(0, 0)], -b[(0, 1)], -b[(1, 0)], b[(1, 1)])
                    } else {
                        b
                    }
                })
            },
            mirror: [incident.from_below; 2],
            rough: <K::Rough as RoughnessModel>::LEVEL != RoughnessLevel::FirstOrder,
        })
    }

    /// The sampler of directions to the source for light leaving along `exit` (backward
    /// tracing), for light arriving with the surface coherence `coherence` (module docs,
    /// "Reciprocity"; [`sources`]).
    ///
    /// # Errors
    /// As [`Bsdf::wavenumber`] for `exit`; as [`Bsdf::exit_sampler`] for the lobes.
    pub fn incident_sampler(
        &self,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
    ) -> Result<LobeSampler<'m, T>, Error> {
        self.incident_sampler_at(&unit_direction(&exit, "exit direction")?, coherence)
    }

    /// [`Bsdf::incident_sampler`] for the unit exit `r`.
    fn incident_sampler_at(
        &self,
        r: &Unit<Vector3<T>>,
        coherence: &SurfaceCoherence<T>,
    ) -> Result<LobeSampler<'m, T>, Error> {
        let r = r.into_inner();
        let k = self.wavenumber(&r)?;
        let below = r.dot(&self.surface.k()) < T::zero();
        let k_across = self.eta.map(|_| if below { self.k[0] } else { self.k[1] });
        let facing = self.surface.facing(&r);
        let cos_o = r.dot(&facing.k());
        // The width of light arriving along r̂'s mirror (the same angle, medium and Snell
        // partner as r̂): the reflected specular ŝ, and close to every ŝ the lobes reach.
        let width = self.width_of(&r, k, coherence);
        let xi = Matrix2::identity() * (width * width).recip();
        let plane = <K::Coh as CoherenceModel>::LEVEL == CoherenceLevel::PlaneWave;
        // Where the horizon rule sets the width (its term above σ) away from the normal, the
        // light's width varies across the lobe (narrower toward the horizon, wider toward the
        // normal): a quarter of the specular draws come from a lobe twice as wide, so that the
        // weights stay bounded.
        let base = coherence.width();
        let varies = width * width >= T::lit(2.0) * base * base && cos_o * cos_o <= T::lit(0.75);
        let (channels, channel_count) = if plane {
            ([(T::one(), xi), (T::zero(), xi)], 0)
        } else if varies {
            (
                [
                    (T::lit(1.0 - WIDE_SHARE), xi),
                    (T::lit(WIDE_SHARE), xi * T::lit(WIDE_FACTOR * WIDE_FACTOR)),
                ],
                2,
            )
        } else {
            ([(T::one(), xi), (T::zero(), xi)], 1)
        };
        self.sampler(&Setup {
            known: r,
            facing,
            k_known: k,
            k_across,
            forward: false,
            reflectance: self.material.parts().specular.reflectance(cos_o, below),
            variance: self.material.parts().psd.variance(),
            lobes: self.material.parts().psd.form().shape(),
            level: <K::Coh as CoherenceModel>::LEVEL,
            specular: true,
            channels,
            channel_count,
            blur: (!plane).then_some(xi),
            // Reflection uses the frame facing r̂ (reversed below), transmission its reverse.
            mirror: [below, !below],
            rough: <K::Rough as RoughnessModel>::LEVEL != RoughnessLevel::FirstOrder,
        })
    }

    fn sampler(&self, setup: &Setup<'m, T>) -> Result<LobeSampler<'m, T>, Error> {
        LobeSampler::new(setup).map_err(|reason| Error::Unrealizable { reason })
    }

    /// The integral of a Dirac lobe of geometry `g` and PSD weight `w`, times `factor`:
    /// `α M_part T w · factor`, its scale `α w factor` taken as one exponential (`α` may be far
    /// below the smallest number of `T` while the weight is not) and the result's small
    /// entries under the rule of [`Throughput::flushed`].
    fn delta_integral(
        &self,
        g: &Geometry<T>,
        lobe: &SampledLobe,
        w: T,
        t: &Mueller<T>,
        factor: T,
    ) -> Mueller<T> {
        let m = match lobe.part {
            Part::Specular => self.material.parts().specular.mueller(g),
            Part::Scattered => self.material.parts().scatter.mueller(g),
        };
        let v = g.phase_factor();
        let ln_alpha = -(v * v) * self.material.parts().psd.variance();
        let mt = (m * *t).0;
        let aw = ln_alpha.exp() * w;
        if aw >= T::MIN_POSITIVE && aw <= T::MAX {
            Mueller(flush_to_normal(mt * aw * factor))
        } else {
            Mueller(throughput_scaled(mt, ln_alpha + w.ln() + factor.ln()))
        }
    }

    /// The Monte Carlo weight of an exit direction `s` drawn by this packet's
    /// [`Bsdf::exit_sampler`]: the fraction of the incident power it carries,
    /// `M cos θ_o/(cos θ_i p)` (for a delta lobe its integral `α M_part T w` in place of `M`),
    /// a throughput from the packet's frame to the exit s/p frame, with the geometry.
    ///
    /// # Errors
    /// As [`Bsdf::geometry`].
    pub fn exit_weight(
        &self,
        incident: &Incident<T, K::Pol, K::Coh>,
        s: &DirectionSample<T>,
    ) -> WeightResult<T, K::Pol> {
        let d = unit_direction(&s.direction, "sampled direction")?;
        self.exit_weight_at(incident, s, &d)
    }

    /// [`Bsdf::exit_weight`] with the sample's direction `d` unit.
    fn exit_weight_at(
        &self,
        incident: &Incident<T, K::Pol, K::Coh>,
        s: &DirectionSample<T>,
        d: &Unit<Vector3<T>>,
    ) -> WeightResult<T, K::Pol> {
        let g = self.geometry_from(incident, d)?;
        let flux = g.cos_o() / g.cos_i();
        let weight = if s.lobe.delta {
            let t = Mueller(incident.prepared.t);
            let m = self.delta_integral(&g, &s.lobe, s.delta_weight, &t, flux / s.pdf);
            <K::Pol as PolarizationModel>::Throughput::<T>::from_mueller(&m)
        } else {
            let v = incident.normalise(self.kernel.kernel().evaluate_mueller_prepared(
                self.material.parts(),
                &incident.prepared,
                &g,
            ));
            v.total().scaled(flux / s.pdf).flushed()
        };
        Ok((weight, g))
    }

    /// The Monte Carlo weight of a direction to the source `s` drawn by
    /// [`Bsdf::incident_sampler`]`(exit, coherence)`: the radiance throughput `M(ŝ → r̂)/p(ŝ)`,
    /// evaluated in the physical direction for light arriving with `coherence` (for a delta
    /// lobe its integral over ŝ, `α M_part w (k_o² cos θ_o)/(k_i² cos θ_i)`), a throughput from
    /// the incident s/p frame of ŝ ([`Geometry::incident_sp`]) to the exit s/p frame, with the
    /// geometry.
    ///
    /// # Errors
    /// As [`Bsdf::surface_packet`] and [`Bsdf::geometry`].
    pub fn incident_weight(
        &self,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        s: &DirectionSample<T>,
    ) -> WeightResult<T, K::Pol> {
        let r = unit_direction(&exit, "exit direction")?;
        let d = unit_direction(&s.direction, "sampled direction")?;
        self.incident_weight_at(&r, coherence, s, &d)
    }

    /// [`Bsdf::incident_weight`] for the unit exit `exit`, the sample's direction `to_source`
    /// unit.
    fn incident_weight_at(
        &self,
        exit: &Unit<Vector3<T>>,
        coherence: &SurfaceCoherence<T>,
        s: &DirectionSample<T>,
        to_source: &Unit<Vector3<T>>,
    ) -> WeightResult<T, K::Pol> {
        if s.lobe.delta {
            let g = self.geometry_at(self.wavenumber(to_source)?, to_source, exit)?;
            // The delta's integral over ŝ: (k_o² cos θ_o)/(k_i² cos θ_i) times its integral over r̂.
            let ratio = g.relative_index();
            let jac = ratio * ratio * g.cos_o() / g.cos_i();
            let m = self.delta_integral(
                &g,
                &s.lobe,
                s.delta_weight,
                &Mueller::identity(),
                jac / s.pdf,
            );
            return Ok((
                <K::Pol as PolarizationModel>::Throughput::<T>::from_mueller(&m),
                g,
            ));
        }
        // Only the exit's side of the coherent lobe is evaluated: its mass alone.
        let reflected =
            s.direction.dot(&self.surface.k()) * exit.dot(&self.surface.k()) > T::zero();
        let light = self.surface_incident_at(to_source, coherence, [reflected, !reflected])?;
        let v = self.eval_at(&light, exit)?;
        Ok((
            v.response.total().scaled(T::one() / s.pdf).flushed(),
            v.geometry,
        ))
    }

    /// Draws an exit direction for the prepared packet and weighs it ([`Bsdf::exit_sampler`],
    /// [`Bsdf::exit_weight`]): the mean of the weight over draws is the albedo matrix. `None`
    /// for an evanescent draw.
    ///
    /// # Errors
    /// As [`Bsdf::exit_sampler`] and [`Bsdf::geometry`].
    pub fn sample_exit(
        &self,
        incident: &Incident<T, K::Pol, K::Coh>,
        u_lobe: T,
        u: [T; 2],
    ) -> SampleResult<T, K::Pol> {
        let Some(s) = self.exit_sampler(incident)?.sample(u_lobe, u) else {
            return Ok(None);
        };
        let d = unit_direction(&s.direction, "sampled direction")?;
        let (weight, geometry) = self.exit_weight_at(incident, &s, &d)?;
        Ok(Some(BsdfSample {
            sample: s,
            weight,
            geometry,
        }))
    }

    /// Draws a direction to the source for light leaving along `exit`, arriving with the
    /// surface coherence `coherence`, and weighs it ([`Bsdf::incident_sampler`],
    /// [`Bsdf::incident_weight`]). `None` for an evanescent draw.
    ///
    /// # Errors
    /// As [`Bsdf::incident_sampler`] and [`Bsdf::incident_weight`].
    pub fn sample_incident(
        &self,
        exit: Vector3<T>,
        coherence: &SurfaceCoherence<T>,
        u_lobe: T,
        u: [T; 2],
    ) -> SampleResult<T, K::Pol> {
        let r = unit_direction(&exit, "exit direction")?;
        let Some(s) = self.incident_sampler_at(&r, coherence)?.sample(u_lobe, u) else {
            return Ok(None);
        };
        let d = unit_direction(&s.direction, "sampled direction")?;
        let (weight, geometry) = self.incident_weight_at(&r, coherence, &s, &d)?;
        Ok(Some(BsdfSample {
            sample: s,
            weight,
            geometry,
        }))
    }
}
