//! The material of the paper, `(p, M)`: a rough surface's PSD and its two pBSDFs, and the
//! complete materials a renderer names (rough and smooth dielectrics and conductors).

use nalgebra::Vector3;
use num_complex::Complex;

use super::geometry::Geometry;
use super::pbsdf::{FresnelInterface, FresnelReflection, Pbsdf, RayleighRice, TangentPlane};
use crate::error::Error;
use crate::frame::Frame;
use crate::packet::WavePacket;
use crate::psd::{Psd, Smooth};
use crate::real::Real;

/// A rough surface: the PSD of its height field, the pBSDF of its mean (specular) interface
/// and the pBSDF of its first-order scattering — the material `(p, M)` of the paper.
#[derive(Debug, Clone, PartialEq)]
pub struct RoughSurface<P, Sp, Sc> {
    /// The height PSD `p` (unitary transform; `R(0) = σ²` the squared rms height).
    pub psd: P,
    /// The specular pBSDF (e.g. [`super::pbsdf::FresnelReflection`],
    /// [`super::pbsdf::FresnelInterface`]).
    pub specular: Sp,
    /// The scattering pBSDF (e.g. [`super::pbsdf::RayleighRice`], [`super::pbsdf::PhaseScreen`]).
    pub scatter: Sc,
}

/// A rough surface as the kernel's functions take it: its PSD and its two pBSDFs as
/// associated types, so that generic code names one bound, `S: Surface<T>`, where it named
/// three (`P: Psd<T, 2>, Sp: Pbsdf<T>, Sc: Pbsdf<T>`), and the levels' bounds read
/// `Coh: CoherenceWeights<T, S::Psd>`. Implemented by every [`RoughSurface`] of such parts.
pub trait Surface<T: Real> {
    /// The height PSD.
    type Psd: Psd<T, 2>;
    /// The specular pBSDF.
    type Specular: Pbsdf<T>;
    /// The scattering pBSDF.
    type Scatter: Pbsdf<T>;

    /// The surface's parts.
    fn parts(&self) -> &RoughSurface<Self::Psd, Self::Specular, Self::Scatter>;
}

impl<T, P, Sp, Sc> Surface<T> for RoughSurface<P, Sp, Sc>
where
    T: Real,
    P: Psd<T, 2>,
    Sp: Pbsdf<T>,
    Sc: Pbsdf<T>,
{
    type Psd = P;
    type Specular = Sp;
    type Scatter = Sc;

    #[inline]
    fn parts(&self) -> &Self {
        self
    }
}

/// A rough interface between two lossless dielectrics of relative index
/// `η = n_below/n_above`: Fresnel reflection and transmission for the coherent lobes,
/// first-order (Rayleigh–Rice) scattering in reflection and transmission, from either side.
/// Build it with [`RoughDielectric::new`] and its geometries with [`RoughDielectric::geometry`].
///
/// One exit direction gives one side: the kernel's response
/// ([`super::polarization::Response::side`]) holds the coherent (mirror or Snell) lobe and the
/// scattered part of that side, so the four lobes are reflected/transmitted × specular/scattered.
/// Under total internal reflection (from the dense side beyond the critical angle) the
/// transmitted specular lobe is 0 and the scattered transmission into propagating directions
/// remains.
///
/// # Absorption
/// `η` is real: the radiance of a transmitted beam in an absorbing medium is not defined at the
/// interface (it decays along the path), and SCATMECH refuses absorbing substrates in
/// transmission for the same reason. A weakly absorbing dielectric (`κ ≪ n`) is modelled by its
/// real part at the interface and Beer–Lambert attenuation `exp(−4πκ d/λ₀)` along the path `d`
/// inside, applied by the renderer: the interface's reflectance changes only at second order,
/// `|R(n + iκ) − R(n)| ≤ 3κ²` for `n ≥ 1.2` and `≤ 0.4κ²` for `n ≥ 1.5`, at every incidence
/// (measured for κ ≤ 0.05 in `tests/interaction/transmission.rs`; largest 2.7κ² at n = 1.2,
/// 80°). For metals use [`RoughConductor`].
pub type RoughDielectric<T, P> = RoughSurface<P, FresnelInterface<T>, RayleighRice<T>>;

/// A rough conductor (or any opaque interface) of complex relative index `η = n + iκ`: Fresnel
/// reflection for the coherent lobe and first-order (Rayleigh–Rice) scattering, in reflection
/// only. Build it with [`RoughConductor::new`].
pub type RoughConductor<T, P> = RoughSurface<P, FresnelReflection<T>, RayleighRice<T>>;

/// A rough dielectric interface for the roughness levels beyond first order
/// ([`super::roughness::KirchhoffSeries`], [`super::roughness::Geometric`]): Fresnel reflection
/// and transmission for the coherent lobes and the Kirchhoff tangent-plane scatterer
/// ([`TangentPlane`]: the Fresnel matrix of the facet at the half vector) for the scattered part,
/// from either side. At first
/// order it agrees with [`RoughDielectric`] near the specular directions; away from them the
/// tangent plane is the model the series and its geometric (microfacet) limit are derived for.
/// Build it with [`KirchhoffDielectric::new`].
pub type KirchhoffDielectric<T, P> =
    RoughSurface<P, FresnelInterface<T>, TangentPlane<FresnelInterface<T>>>;

/// A rough conductor for the roughness levels beyond first order: Fresnel reflection and the
/// tangent-plane scatterer with Fresnel facets ([`KirchhoffDielectric`]'s opaque twin). Build it
/// with [`KirchhoffConductor::new`].
pub type KirchhoffConductor<T, P> =
    RoughSurface<P, FresnelReflection<T>, TangentPlane<FresnelReflection<T>>>;

/// The smooth limit of [`RoughDielectric`]: a flat interface (only the coherent lobes, widened
/// by the coherence; no roughness attenuation).
pub type SmoothDielectric<T> = RoughDielectric<T, Smooth<T>>;

/// The smooth limit of [`RoughConductor`]: a flat mirror of complex index.
pub type SmoothConductor<T> = RoughConductor<T, Smooth<T>>;

impl<T: Real, P: Psd<T, 2>> RoughSurface<P, FresnelInterface<T>, RayleighRice<T>> {
    /// A rough dielectric interface of relative index `eta = n_below/n_above` with the height
    /// PSD `psd`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`]/[`Error::NonFinite`] unless `eta` is finite and positive with `1/η`
    /// finite.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Full, Kernel, Partial, RoughDielectric, Side};
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    ///
    /// // Rough glass (σ = 10 nm, ℓ = 2 µm) below z = 0; light from the air at 30°.
    /// let glass = RoughDielectric::new(GaussianPsd::<f64, 2>::isotropic(0.01, 2.0)?, 1.5)?;
    /// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
    /// let travel = Vector3::new(0.5, 0.0, -(0.75_f64).sqrt());
    /// let packet = WavePacket::from_stokes(
    ///     Stokes::unpolarized(1.0)?, CoherenceShape::isotropic(10.0)?,
    ///     Frame::sp(travel, Vector3::z())?, 0.5)?;
    /// let kernel = Kernel::<Full, Partial>::default();
    /// let below = Vector3::new(0.3, 0.1, -0.95); // a direction inside the glass
    /// let g = glass.geometry_for_packet(&packet, &surface, below)?;
    /// let r = kernel.evaluate(&glass, &packet, &g);
    /// assert_eq!(r.side, Side::Transmission);
    /// assert!(r.scattered.s0() > 0.0);
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn new(psd: P, eta: T) -> Result<Self, Error> {
        Ok(Self {
            psd,
            specular: FresnelInterface::new(eta)?,
            scatter: RayleighRice::new(Complex::new(eta, T::zero()))?,
        })
    }

    /// `η = n_below/n_above`.
    #[must_use]
    pub fn relative_index(&self) -> T {
        self.specular.relative_index()
    }

    /// The geometry of light from `to_source` leaving along `exit` at this interface
    /// ([`Geometry::at_interface`] with the material's `η`): either side, reflection or
    /// transmission.
    ///
    /// # Errors
    /// As [`Geometry::at_interface`].
    pub fn geometry(
        &self,
        k: T,
        surface: &Frame<T>,
        to_source: Vector3<T>,
        exit: Vector3<T>,
    ) -> Result<Geometry<T>, Error> {
        Geometry::at_interface(k, surface, self.relative_index(), to_source, exit)
    }

    /// [`RoughDielectric::geometry`] for `packet` (its wavenumber in the medium it travels in,
    /// ŝ = −k̂).
    ///
    /// # Errors
    /// As [`Geometry::at_interface`].
    pub fn geometry_for_packet(
        &self,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
        exit: Vector3<T>,
    ) -> Result<Geometry<T>, Error> {
        Geometry::for_packet_at_interface(packet, surface, self.relative_index(), exit)
    }
}

impl<T: Real> RoughSurface<Smooth<T>, FresnelInterface<T>, RayleighRice<T>> {
    /// A flat dielectric interface of relative index `eta = n_below/n_above`.
    ///
    /// # Errors
    /// As [`RoughDielectric::new`].
    pub fn smooth(eta: T) -> Result<Self, Error> {
        Self::new(Smooth::new(T::zero())?, eta)
    }
}

impl<T: Real, P: Psd<T, 2>> RoughSurface<P, FresnelReflection<T>, RayleighRice<T>> {
    /// A rough conductor of complex relative index `eta = n + iκ` with the height PSD `psd`.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::OutOfRange`] unless `Re η > 0`, `Im η ≥ 0`, finite.
    pub fn new(psd: P, eta: Complex<T>) -> Result<Self, Error> {
        Ok(Self {
            psd,
            specular: FresnelReflection::new(eta)?,
            scatter: RayleighRice::new(eta)?,
        })
    }

    /// The geometry of light from `to_source` leaving along `exit` ([`Geometry::new`]:
    /// reflection on the side the frame's normal points to).
    ///
    /// # Errors
    /// As [`Geometry::new`].
    pub fn geometry(
        &self,
        k: T,
        surface: &Frame<T>,
        to_source: Vector3<T>,
        exit: Vector3<T>,
    ) -> Result<Geometry<T>, Error> {
        Geometry::new(k, surface, to_source, exit)
    }
}

impl<T: Real, P: Psd<T, 2>>
    RoughSurface<P, FresnelInterface<T>, TangentPlane<FresnelInterface<T>>>
{
    /// A rough dielectric interface of relative index `eta = n_below/n_above` with the height
    /// PSD `psd` and tangent-plane scattering ([`KirchhoffDielectric`]).
    ///
    /// # Errors
    /// As [`RoughDielectric::new`].
    ///
    /// # Examples
    /// ```
    /// use gmueller::interaction::{KirchhoffDielectric, RoughDielectric};
    /// use gmueller::psd::GaussianPsd;
    /// let psd = GaussianPsd::<f64, 2>::isotropic(0.1, 1.0)?; // vσ ≈ 2.5 at normal incidence
    /// let glass = KirchhoffDielectric::new(psd, 1.5)?;
    /// assert_eq!(glass.specular, RoughDielectric::new(psd, 1.5)?.specular);
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn new(psd: P, eta: T) -> Result<Self, Error> {
        let facet = FresnelInterface::new(eta)?;
        Ok(Self {
            psd,
            specular: facet,
            scatter: TangentPlane::new(facet),
        })
    }

    /// `η = n_below/n_above`.
    #[must_use]
    pub fn relative_index(&self) -> T {
        self.specular.relative_index()
    }
}

impl<T: Real, P: Psd<T, 2>>
    RoughSurface<P, FresnelReflection<T>, TangentPlane<FresnelReflection<T>>>
{
    /// A rough conductor of complex relative index `eta = n + iκ` with the height PSD `psd`
    /// and tangent-plane scattering ([`KirchhoffConductor`]).
    ///
    /// # Errors
    /// As [`RoughConductor::new`].
    pub fn new(psd: P, eta: Complex<T>) -> Result<Self, Error> {
        let facet = FresnelReflection::new(eta)?;
        Ok(Self {
            psd,
            specular: facet,
            scatter: TangentPlane::new(facet),
        })
    }
}

impl<T: Real> RoughSurface<Smooth<T>, FresnelReflection<T>, RayleighRice<T>> {
    /// A flat conductor (mirror) of complex relative index `eta = n + iκ`.
    ///
    /// # Errors
    /// As [`RoughConductor::new`].
    pub fn smooth(eta: Complex<T>) -> Result<Self, Error> {
        Self::new(Smooth::new(T::zero())?, eta)
    }
}
