//! The S2.20 kernel at a chosen model level.

use core::marker::PhantomData;

use super::coherence::{CoherenceModel, CoherenceWeights};
use super::geometry::{self, Geometry};
use super::material::Surface;
use super::polarization::{MuellerResponse, PolarizationModel};
use super::prepared::PreparedPacket;
use super::roughness::{FirstOrder, RoughnessModel, RoughnessWeights};
use crate::error::Error;
use crate::frame::Frame;
use crate::numerics::unit_direction;
use crate::packet::{WavePacket, same_wavenumber};
use crate::real::Real;

/// The S2.20 kernel at a chosen model level: polarization `Pol` ([`super::Intensity`],
/// [`super::OneShape`], [`super::Full`]), coherence `Coh` ([`super::PlaneWave`],
/// [`super::Partial`]`<B>` with its blur method `B`, [`super::Incoherent`]) and roughness
/// `Rough` ([`FirstOrder`] by default, [`super::roughness::KirchhoffSeries`],
/// [`super::roughness::Geometric`]: how far beyond first order in the heights,
/// [`super::roughness::RoughnessLevel`]).
///
/// `Kernel::<Full, Partial>::default()` blurs with [`crate::psd::ClosedForm`]; another blur
/// method goes into the coherence model: `Kernel::<Full, _>::new(Partial(GaussHermite::new(8)?))`.
/// To choose the level at run time, see [`super::Level`] ([`super::Level::dispatch_rough`] with
/// the roughness level too). The roughness level
/// is a third type: `Kernel::<Full, Partial, KirchhoffSeries>::default()`, or
/// [`Kernel::with_roughness`].
///
/// # Examples
/// ```
/// use gmueller::frame::Frame;
/// use gmueller::interaction::{Full, Geometry, Kernel, Partial, RoughSurface};
/// use gmueller::interaction::pbsdf::{FresnelReflection, RayleighRice};
/// use gmueller::packet::{CoherenceShape, WavePacket};
/// use gmueller::psd::GaussianPsd;
/// use gmueller::stokes::Stokes;
/// use nalgebra::Vector3;
/// use num_complex::Complex;
///
/// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
/// let travel = Vector3::new(0.5_f64, 0.0, -(0.75_f64).sqrt()); // 30° incidence
/// let frame = Frame::sp(travel, Vector3::z()).unwrap();
/// let packet = WavePacket::from_stokes(
///     Stokes::unpolarized(1.0).unwrap(),
///     CoherenceShape::isotropic(10.0).unwrap(), frame, 0.5).unwrap();
/// let glass = Complex::new(1.5, 0.0);
/// let material = RoughSurface {
///     psd: GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap(), // σ = 10 nm, ℓ = 2 µm
///     specular: FresnelReflection::new(glass).unwrap(),
///     scatter: RayleighRice::new(glass).unwrap(),
/// };
/// let kernel = Kernel::<Full, Partial>::default();
/// let exit = Vector3::new(0.6, 0.1, 0.79);
/// let g = Geometry::new(packet.wavenumber(), &surface, -travel, exit).unwrap();
/// let r = kernel.evaluate(&material, &packet, &g);
/// assert!(r.scattered.s0() > 0.0 && r.scattered.s0().is_finite());
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Kernel<Pol, Coh, Rough = FirstOrder> {
    coherence: Coh,
    roughness: Rough,
    _polarization: PhantomData<Pol>,
}

impl<Pol: PolarizationModel, Coh: CoherenceModel> Kernel<Pol, Coh> {
    /// A first-order kernel with the coherence model `coherence` (e.g.
    /// `Partial(GaussHermite::new(8)?)`).
    #[must_use]
    pub fn new(coherence: Coh) -> Self {
        Self {
            coherence,
            roughness: FirstOrder,
            _polarization: PhantomData,
        }
    }
}

impl<Pol: PolarizationModel, Coh: CoherenceModel, Rough: RoughnessModel> Kernel<Pol, Coh, Rough> {
    /// The same kernel at the roughness level `roughness` (e.g.
    /// `KirchhoffSeries::new(1e-4)?`).
    #[must_use]
    pub fn with_roughness<R: RoughnessModel>(self, roughness: R) -> Kernel<Pol, Coh, R> {
        Kernel {
            coherence: self.coherence,
            roughness,
            _polarization: PhantomData,
        }
    }

    /// The coherence model (with its blur method for [`super::Partial`]).
    #[must_use]
    pub fn coherence(&self) -> &Coh {
        &self.coherence
    }

    /// The roughness model (with its tolerance for [`super::roughness::KirchhoffSeries`]).
    #[must_use]
    pub fn roughness(&self) -> &Rough {
        &self.roughness
    }

    /// Evaluates S2.20 for `packet` leaving along `g.exit` (see the module formula).
    ///
    /// `g` must have been built for this packet: `g.k` its wavenumber and `g.to_source` its
    /// reversed propagation direction (e.g. by [`Geometry::for_packet`]). For several exit
    /// directions of one packet, [`Kernel::prepare`] once and [`Kernel::evaluate_prepared`]
    /// per direction give the same result without repeating the per-packet work.
    #[must_use]
    pub fn evaluate<T, S>(
        &self,
        material: &S,
        packet: &WavePacket<T>,
        g: &Geometry<T>,
    ) -> Pol::Output<T>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        debug_assert!(
            same_wavenumber(packet.wavenumber(), g.k),
            "Kernel::evaluate: the geometry was built for k = {:e}, the packet has k = {:e}",
            g.k.to_f64(),
            packet.wavenumber().to_f64()
        );
        let prepared = self.prepare_unchecked(packet, &g.surface, &g.incident_sp);
        self.evaluate_prepared(material, &prepared, g)
    }

    /// [`Kernel::evaluate`], after checking that `g` belongs to `packet`: the same wavenumber
    /// and the source direction `ŝ = −k̂` of the packet.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when `g.k()` differs from the packet's wavenumber by more than a
    /// few ulps (a geometry built for another wavelength, or for the packet's wavelength in the
    /// other medium), or when `g.to_source()` is not the packet's reversed direction (within
    /// `64 ε`).
    pub fn try_evaluate<T, S>(
        &self,
        material: &S,
        packet: &WavePacket<T>,
        g: &Geometry<T>,
    ) -> Result<Pol::Output<T>, Error>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        check_geometry(packet, g)?;
        Ok(self.evaluate(material, packet, g))
    }

    /// The kernel in BSDF form ([`MuellerResponse`]): a throughput per lobe per unit incident
    /// irradiance, acting on Stokes vectors in the packet's frame and giving Stokes radiances in
    /// the exit s/p frame ([`Geometry::exit_sp`]). `evaluate_mueller(..).apply(&packet.stokes())`
    /// equals [`Kernel::evaluate`] up to rounding wherever its scale is a normal number.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Full, Geometry, Kernel, Partial, RoughDielectric};
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    ///
    /// let glass = RoughDielectric::new(GaussianPsd::<f64, 2>::isotropic(0.01, 2.0)?, 1.5)?;
    /// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
    /// let travel = Vector3::new(0.5, 0.0, -(0.75_f64).sqrt());
    /// let s = Stokes::new(1.0, 0.3, -0.2, 0.5)?;
    /// let packet = WavePacket::from_stokes(s, CoherenceShape::isotropic(10.0)?,
    ///     Frame::sp(travel, Vector3::z())?, 0.5)?;
    /// let kernel = Kernel::<Full, Partial>::default();
    /// let g = glass.geometry_for_packet(&packet, &surface, Vector3::new(0.45, 0.05, 0.89))?;
    /// let m = kernel.evaluate_mueller(&glass, &packet, &g);
    /// let direct = kernel.evaluate(&glass, &packet, &g).scattered;
    /// let via_matrix = m.apply(&s).scattered;
    /// assert!((via_matrix.vector() - direct.vector()).norm() <= 1e-12 * direct.s0());
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    #[must_use]
    pub fn evaluate_mueller<T, S>(
        &self,
        material: &S,
        packet: &WavePacket<T>,
        g: &Geometry<T>,
    ) -> MuellerResponse<T, Pol::Throughput<T>>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        let prepared = self.prepare_unchecked(packet, &g.surface, &g.incident_sp);
        self.evaluate_mueller_prepared(material, &prepared, g)
    }

    /// [`Kernel::evaluate_mueller`] with the per-packet work done by [`Kernel::prepare`].
    #[must_use]
    pub fn evaluate_mueller_prepared<T, S>(
        &self,
        material: &S,
        prepared: &PreparedPacket<T, Pol, Coh>,
        g: &Geometry<T>,
    ) -> MuellerResponse<T, Pol::Throughput<T>>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        debug_assert!(
            same_wavenumber(prepared.k, g.k),
            "Kernel::evaluate_mueller_prepared: geometry k = {:e}, prepared packet k = {:e}",
            g.k.to_f64(),
            prepared.k.to_f64()
        );
        Pol::evaluate_mueller(&self.coherence, &self.roughness, material, prepared, g)
    }

    /// The per-packet part of the kernel at this model level — the sections `Ξ_α` of the
    /// packet's coherence by the surface (Cholesky-factored) and the rotation `T` from the
    /// packet frame to the incident s/p frame — computed once for any number of exit
    /// directions ([`Kernel::evaluate_prepared`]).
    ///
    /// `surface` must face the source, as the geometries of the packet do: for light arriving
    /// from below an interface ([`Geometry::at_interface`]) pass `surface.facing(&-packet.direction())`
    /// ([`Frame::facing`]), the frame [`Geometry::surface`] returns.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when the packet does not travel toward the surface
    /// (`k̂ · n̂ ≥ 0`), as [`Geometry::for_packet`] would report for every exit direction.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Full, Geometry, Kernel, Partial, RoughSurface};
    /// use gmueller::interaction::pbsdf::PhaseScreen;
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    ///
    /// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// let travel = Vector3::new(0.5_f64, 0.0, -(0.75_f64).sqrt());
    /// let packet = WavePacket::from_stokes(
    ///     Stokes::unpolarized(1.0).unwrap(), CoherenceShape::isotropic(3.0).unwrap(),
    ///     Frame::sp(travel, Vector3::z()).unwrap(), 0.5).unwrap();
    /// let material = RoughSurface {
    ///     psd: GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap(),
    ///     specular: PhaseScreen::new(0.04).unwrap(),
    ///     scatter: PhaseScreen::new(0.04).unwrap(),
    /// };
    /// let kernel = Kernel::<Full, Partial>::default();
    /// let prepared = kernel.prepare(&packet, &surface).unwrap();
    /// for exit in [Vector3::new(0.5, 0.0, 0.87), Vector3::new(0.3, 0.2, 0.93)] {
    ///     let g = Geometry::for_packet(&packet, &surface, exit).unwrap();
    ///     let once = kernel.evaluate(&material, &packet, &g).total().s0();
    ///     let many = kernel.evaluate_prepared(&material, &prepared, &g).total().s0();
    ///     assert!((once - many).abs() <= 1e-12 * once);
    /// }
    /// ```
    pub fn prepare<T: Real>(
        &self,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
    ) -> Result<PreparedPacket<T, Pol, Coh>, Error> {
        let to_source =
            unit_direction(&-packet.direction(), "direction to the source")?.into_inner();
        let (_, incident_sp) = geometry::incidence(&to_source, surface)?;
        Ok(self.prepare_unchecked(packet, surface, &incident_sp))
    }

    /// [`Kernel::prepare`] for unpolarized light of unit `S0` and wavenumber `k`, whose frame
    /// is the incident s/p frame and whose coherence section on the surface is `I/w²`
    /// (`inverse_width` = `1/w`): `PreparedPacket::unpolarized_isotropic`. The caller
    /// vouches for the direction (the renderer layer's backward weights).
    #[inline]
    pub(crate) fn prepare_unpolarized_isotropic<T: Real>(
        &self,
        k: T,
        inverse_width: T,
    ) -> PreparedPacket<T, Pol, Coh> {
        PreparedPacket::unpolarized_isotropic(k, inverse_width, Coh::USES_SHAPE)
    }

    /// [`Kernel::prepare`] with the incident s/p frame already built.
    fn prepare_unchecked<T: Real>(
        &self,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
        incident_sp: &Frame<T>,
    ) -> PreparedPacket<T, Pol, Coh> {
        let plan = Pol::plan(packet, Coh::USES_SHAPE).0;
        PreparedPacket::new(packet, surface, incident_sp, plan)
    }

    /// [`Kernel::evaluate`] with the per-packet work done by [`Kernel::prepare`]; `g` must be
    /// a geometry of that packet on that surface (e.g. [`Geometry::for_packet`]).
    #[must_use]
    pub fn evaluate_prepared<T, S>(
        &self,
        material: &S,
        prepared: &PreparedPacket<T, Pol, Coh>,
        g: &Geometry<T>,
    ) -> Pol::Output<T>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        debug_assert!(
            same_wavenumber(prepared.k, g.k),
            "Kernel::evaluate_prepared: geometry k = {:e}, prepared packet k = {:e}",
            g.k.to_f64(),
            prepared.k.to_f64()
        );
        Pol::evaluate(&self.coherence, &self.roughness, material, prepared, g)
    }
}

/// `Ok` when `g` was built for `packet`: its wavenumber and its reversed direction.
#[expect(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "a NaN must fail the test too"
)]
pub(crate) fn check_geometry<T: Real>(
    packet: &WavePacket<T>,
    g: &Geometry<T>,
) -> Result<(), Error> {
    if !same_wavenumber(packet.wavenumber(), g.k) {
        return Err(Error::OutOfRange {
            what: "geometry wavenumber (built for another wavelength or medium than the packet's)",
            value: g.k.to_f64(),
            expected: "the packet's wavenumber 2π/λ (in the medium of incidence)",
        });
    }
    let off = (g.to_source + packet.direction()).norm();
    if !(off <= T::lit(64.0) * T::EPSILON) {
        return Err(Error::OutOfRange {
            what: "geometry source direction (not the packet's reversed direction)",
            value: off.to_f64(),
            expected: "|ŝ + k̂| ≤ 64 ε",
        });
    }
    Ok(())
}
