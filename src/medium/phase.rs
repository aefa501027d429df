//! The medium in the form a volume path tracer calls: per packet a scattering coefficient,
//! per exit direction a Mueller phase matrix, sampling and its exact pdf (Mitsuba's
//! `PhaseFunction::eval/sample/pdf`).
//!
//! # Radiometry
//! ```text
//! dI/dV(r̂) = σ_s F(ŝ → r̂) S                   Stokes radiant intensity per unit volume (S: the packet's irradiance)
//! ∫_{S²} [F(ŝ → r̂) S]₀ dΩ = S0                 F per steradian, normalised on the packet's own S
//! L_s(x, r̂) = σ_s ∫ F(ŝ → r̂) L_i(x, ŝ) dω_s    in-scattered radiance (radiative transfer)
//! ```
//! `σ_s` (1/length) and `F` depend on the packet: on its coherence (the blur `K³`) and, for a
//! polarizing `m̄` or an anisotropic medium or coherence, on its Stokes vector. For a dark packet
//! (`S0 = 0`) both are those of unpolarized light of the same coherence. A backward tracer
//! evaluates `F(ŝ → r̂)` in the physical direction, with the coherence of the light arriving along
//! ŝ, as for surfaces (`docs/renderer.md`).
//!
//! # Frames
//! `F` acts on Stokes vectors in the **packet's frame** and returns them in the **exit
//! scattering-plane frame** `(ê_⊥, r̂ × ê_⊥, r̂)`, `ê_⊥ = d̂ × r̂/|d̂ × r̂|`
//! ([`super::ScatteringGeometry::exit_frame`]); it includes the rotation `T` from the packet
//! frame to the incident scattering-plane frame. Forward and backward: see
//! [`super::ScatteringGeometry`]. Along a path, chain with
//! [`crate::interaction::polarization::Throughput::frame_change`] from one vertex's exit frame to
//! the next packet's frame.

use nalgebra::{Matrix4, Vector3};

use super::RandomMedium;
use super::coefficient::{neg_inf, scattering_coefficient};
use super::coherence::VolumeCoherence;
use super::geometry::ScatteringGeometry;
use super::lobes::LobeModel;
use super::sampler::DirectionMixture;
use super::scatterer::Scatterer;
use super::scattering::Channels;
use super::spectrum::VolumeLobes;
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::Kernel;
use crate::interaction::coherence::CoherenceLevel;
use crate::interaction::polarization::{PolarizationModel, Throughput};
use crate::mueller::Mueller;
use crate::packet::{Channel, WavePacket};
use crate::psd::Psd;
use crate::real::Real;
use crate::stokes::Stokes;

/// A medium at a chosen model level, as a phase function (module docs).
///
/// # Examples
/// ```
/// use gmueller::frame::Frame;
/// use gmueller::interaction::{Full, Kernel, Partial};
/// use gmueller::interaction::polarization::Throughput;
/// use gmueller::medium::{Dipole, PhaseFunction, RandomMedium};
/// use gmueller::packet::{CoherenceShape, WavePacket};
/// use gmueller::psd::GaussianPsd;
/// use gmueller::stokes::Stokes;
/// use nalgebra::Vector3;
///
/// // δε with rms 1e-3 and a 0.2 µm correlation length; light of 0.5 µm with 20 µm transverse
/// // and 5 µm longitudinal coherence, travelling along +z.
/// let medium = RandomMedium::new(GaussianPsd::<f64, 3>::isotropic(1e-3, 0.2)?, Dipole);
/// let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
/// let light = WavePacket::from_stokes(
///     Stokes::unpolarized(1.0)?, CoherenceShape::isotropic(20.0)?, frame, 0.5)?
///     .with_longitudinal_coherence(5.0)?;
/// let phase = PhaseFunction::new(&medium, Kernel::<Full, Partial>::default());
/// let incident = phase.prepare(&light)?;
/// let sigma_s = incident.scattering_coefficient(); // 1/µm
/// assert!(sigma_s > 0.0);
/// let v = phase.eval(&incident, Vector3::new(0.0, 0.6, 0.8))?;
/// let f = v.apply(&light.stokes()); // F S per sr, valid, in v.geometry.exit_frame()
/// assert!(f.s0() > 0.0 && f.degree_of_polarization() < 1.0);
/// let s = phase.sample(&incident, 0.3, [0.7, 0.2]);
/// assert!((phase.pdf(&incident, &s.direction) - s.pdf).abs() <= 1e-12 * s.pdf);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy)]
pub struct PhaseFunction<'m, P, M, Pol, Coh> {
    medium: &'m RandomMedium<P, M>,
    kernel: Kernel<Pol, Coh>,
}

/// A packet prepared for one medium ([`PhaseFunction::prepare`]): its channel weights'
/// ingredients, its scattering coefficient and its direction sampler.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeIncident<T: Real, Pol, Coh> {
    pub(crate) channels: Channels<T, Pol, Coh>,
    /// For the phase matrix and `σ_s` (the packet's own, or unpolarized for a dark packet).
    pub(crate) phase_channels: Channels<T, Pol, Coh>,
    ln_sigma: T,
    sampler: DirectionMixture<T>,
}

impl<T: Real, Pol, Coh> VolumeIncident<T, Pol, Coh> {
    /// `σ_s` (1/length): the power scattered per unit length of travel per unit irradiance, for
    /// this packet (module docs).
    #[must_use]
    pub fn scattering_coefficient(&self) -> T {
        self.ln_sigma.exp()
    }

    /// `ln σ_s` (`−∞`-like for a medium that does not scatter), accurate where `σ_s` under- or
    /// overflows.
    #[must_use]
    pub fn ln_scattering_coefficient(&self) -> T {
        self.ln_sigma
    }

    /// The packet's frame (the input side of the phase matrix).
    #[must_use]
    pub fn frame(&self) -> &Frame<T> {
        &self.channels.frame
    }

    /// The weight `w_u` of the uniform (defensive) part of the sampler
    /// ([`PhaseFunction::sample`]).
    #[must_use]
    pub fn uniform_weight(&self) -> T {
        self.sampler.uniform_weight()
    }
}

/// [`PhaseFunction::eval`]'s answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseValue<T: Real, Th> {
    /// The phase matrix `F` (per steradian): a Mueller matrix at the Stokes levels, `F₀₀` at the
    /// intensity level ([`Throughput`]).
    pub phase: Th,
    /// The geometry: frames, scattering vector, angle.
    pub geometry: ScatteringGeometry<T>,
}

impl<T: Real, Th: Throughput<T>> PhaseValue<T, Th> {
    /// `F S`: the phase matrix applied to the light `light` (in the packet's frame; the
    /// packet's own Stokes vector, for which `F` was prepared), in the exit frame, a valid
    /// Stokes vector — projected onto the cone where rounding left it outside, as the surfaces'
    /// [`crate::interaction::polarization::MuellerResponse::apply`].
    ///
    /// The raw product `phase.apply(light)` rounds on its own: where the output is far below
    /// the input (polarized scattered light leaving near the dipole's null, `F S₀ ∝ cos²Θ`) the
    /// rounding of `F`'s entries is amplified by about `1/cos²Θ`, and in `f32` the raw product
    /// can leave the cone by a few `10⁻⁶` of `S0` (4.8e-6 at `Θ = 85°` in
    /// `tests/medium/extremes.rs`, `f_s_near_the_dipole_null`).
    #[must_use]
    pub fn apply(&self, light: &Th::Light) -> Th::Light {
        on_cone::<T, Th>(self.phase.apply(light))
    }
}

impl<T: Real, Th: Throughput<T>> PhaseSample<T, Th> {
    /// `weight · S`, the Monte Carlo estimate of the scattered light for `light` (the packet's
    /// own), a valid Stokes vector as [`PhaseValue::apply`].
    #[must_use]
    pub fn apply(&self, light: &Th::Light) -> Th::Light {
        on_cone::<T, Th>(self.weight.apply(light))
    }
}

/// A light of a throughput's level, moved onto the cone if it is a Stokes vector outside it.
#[inline]
fn on_cone<T: Real, Th: Throughput<T>>(light: Th::Light) -> Th::Light {
    match Th::light_stokes(&light) {
        Some(s) => Th::light(&Stokes(crate::interaction::onto_cone(s.0))),
        None => light,
    }
}

/// [`PhaseFunction::sample`]'s answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseSample<T: Real, Th> {
    /// The unit exit direction r̂.
    pub direction: Vector3<T>,
    /// Its density per steradian (exactly [`PhaseFunction::pdf`] of it).
    pub pdf: T,
    /// `F/pdf`, the Monte Carlo weight of the draw.
    pub weight: Th,
    /// The geometry of the draw (`weight` maps the packet frame to its exit frame).
    pub geometry: ScatteringGeometry<T>,
}

/// The scattered light of a packet in one direction ([`RandomMedium::differential_scattering`],
/// [`PhaseFunction::differential_scattering`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScatteredLight<T: Real, L> {
    /// `dI/dV`: the radiant intensity per unit volume (a Stokes vector in the exit frame at
    /// the Stokes levels, `S0` at the intensity level), for the packet's own irradiance `S`.
    pub light: L,
    /// The geometry: frames, scattering vector, angle.
    pub geometry: ScatteringGeometry<T>,
}

/// The light type of a polarization level: a Stokes vector, or an intensity.
pub type LevelLight<T, Pol> = <<Pol as PolarizationModel>::Throughput<T> as Throughput<T>>::Light;

/// `true` when every shape the level uses is isotropic.
fn channels_axial<T: Real>(packet: &WavePacket<T>, three: bool) -> bool {
    let iso = |c| LobeModel::<T>::isotropic_shape(&packet.shape(c));
    iso(Channel::Half) && (!three || (iso(Channel::X) && iso(Channel::Y)))
}

impl<'m, P, M, Pol, Coh> PhaseFunction<'m, P, M, Pol, Coh>
where
    Pol: PolarizationModel,
{
    /// The medium `medium` evaluated by `kernel` (its polarization and coherence levels).
    #[must_use]
    pub fn new(medium: &'m RandomMedium<P, M>, kernel: Kernel<Pol, Coh>) -> Self {
        Self { medium, kernel }
    }

    /// The medium.
    #[must_use]
    pub fn medium(&self) -> &RandomMedium<P, M> {
        self.medium
    }

    /// The per-packet work: the channel weights' ingredients, `σ_s` by quadrature over the
    /// sphere, and the sampler.
    ///
    /// # Formula
    /// ```text
    /// σ_s = (1/S0) ∫_{S²} [dI/dV(r̂)]₀ dΩ = (1/k²) ∫_{|v| ≤ 2k} f(r̂(v)) d²v,   f = [dI/dV]₀/S0
    /// r̂(v) = (1 − 2a²) d̂ + 2a√(1 − a²) (v_x x̂ + v_y ŷ)/|v|,   a = |v|/2k      (Lambert, about d̂)
    /// ```
    /// The rule works in `z = L⁻¹v`, `L` the Cholesky factor of the lobe's transverse covariance
    /// (the PSD's spectral covariance, plus the inverse coherence at the `Partial` level), where
    /// the lobe is round and of unit width: 8-point Gauss–Legendre on radial panels
    /// `[0, ρ₀], [ρ₀, 2ρ₀], …, [1, 2], [2, 3], …, [7, 8], [8, 16], …` up to the rim, and the
    /// trapezoid rule over 16 azimuths — one where the integrand is symmetric about d̂ (an
    /// isotropic PSD and isotropic transverse shapes), where the azimuth-dependent terms of
    /// the first row of `m̄ T` integrate to 0. Accuracy against adaptive quadrature on the
    /// sphere (`tests/medium/born.rs`): ≤ 3e-15 symmetric, ≤ 8e-11 for anisotropic media and
    /// coherence, 1e-7 with a Gauss–Hermite blur. Cost: 5–15 µs symmetric, 90–250 µs
    /// otherwise (`benches/medium.rs`; the plane-wave level ignores the shapes and is always
    /// symmetric for an isotropic PSD).
    ///
    /// # Errors
    /// [`Error::Singular`] at the `Incoherent` level for a packet with unbounded longitudinal
    /// coherence (set `σ_zz` with [`WavePacket::with_longitudinal_coherence`]);
    /// [`Error::NotPositiveDefinite`] when its inverse coherence is not representable;
    /// [`Error::Unrealizable`] when the quadrature of `σ_s` did not resolve the phase
    /// function's lobe (`F` forward beyond what a resolved lobe of the named shape allows: a
    /// PSD whose [`Psd::form`] names a lobe far wider than its own), where `F` would be ~∞,
    /// and at the `Partial` level when it found `σ_s = 0` for a PSD of positive variance (the
    /// blur's quadrature missed the PSD at every node) ([module docs](super), "When `σ_s` is 0
    /// or not representable").
    pub fn prepare<T>(&self, packet: &WavePacket<T>) -> Result<VolumeIncident<T, Pol, Coh>, Error>
    where
        T: Real,
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let (psd, coherence) = (&self.medium.psd, self.kernel.coherence());
        let channels = Channels::<T, Pol, Coh>::new(packet, psd, coherence)?;
        let phase_channels = if packet.stokes().s0() > T::zero() {
            channels.clone()
        } else {
            Channels::unpolarized(packet, psd, coherence)?
        };
        let model = LobeModel::new(
            VolumeLobes::of(self.medium.psd.form())?,
            Coh::LEVEL,
            phase_channels.xi_half.as_ref(),
            packet.frame(),
            channels_axial(packet, phase_channels.three),
            packet.wavenumber(),
        );
        let coefficient = scattering_coefficient(
            &phase_channels,
            self.kernel.coherence(),
            &self.medium.psd,
            &self.medium.scatterer,
            &model,
        );
        // A blurred PSD is positive everywhere (the blur is a Gaussian), so a medium that
        // scatters (variance > 0) has σ_s > 0 at the partially coherent level: 0 there means
        // that the blur's quadrature missed the PSD at every node (a band far narrower than the
        // blur, under Gauss–Hermite), not a medium that does not scatter.
        let scatters = coefficient.ln_sigma > neg_inf::<T>();
        if !scatters
            && Coh::LEVEL == CoherenceLevel::Partial
            && self.medium.psd.variance() > T::zero()
        {
            return Err(Error::Unrealizable {
                reason: "the σ_s quadrature found no scattering from a medium that scatters (the \
                         blur's quadrature missed the PSD at every node: a PSD band far narrower \
                         than the coherence's blur)",
            });
        }
        if scatters {
            // F(d̂), the phase matrix's scale forward (where every lobe the model names peaks):
            // beyond the largest a resolved lobe has, σ_s missed the lobe and F would be ~∞.
            let zero = nalgebra::Vector3::zeros();
            let (_, ln_e) = phase_channels.intensity_part(
                self.kernel.coherence(),
                &self.medium.psd,
                &self.medium.scatterer,
                (&zero, T::one()),
                (T::one(), T::zero()),
                model.axial,
            );
            let resolved = matches!(
                (ln_e - coefficient.ln_sigma).partial_cmp(&model.ln_peak),
                Some(core::cmp::Ordering::Less | core::cmp::Ordering::Equal)
            );
            if !resolved {
                return Err(Error::Unrealizable {
                    reason: "the σ_s quadrature did not resolve the phase function's lobe (F \
                             forward beyond what a resolved lobe allows: a PSD whose form names a \
                             lobe far wider than its PSD's)",
                });
            }
        }
        let sampler = DirectionMixture::new(&model, packet.wavenumber(), coefficient.far);
        Ok(VolumeIncident {
            channels,
            phase_channels,
            ln_sigma: coefficient.ln_sigma,
            sampler,
        })
    }

    /// The phase matrix `F(ŝ → r̂)` for the prepared packet and the exit direction `exit` (any
    /// length), per steradian (module docs); 0 for a medium that does not scatter.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::InvalidBasis`] for a non-finite or zero `exit`.
    pub fn eval<T>(
        &self,
        incident: &VolumeIncident<T, Pol, Coh>,
        exit: Vector3<T>,
    ) -> Result<PhaseValue<T, Pol::Throughput<T>>, Error>
    where
        T: Real,
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let g = ScatteringGeometry::new(&incident.channels.frame, incident.channels.k, exit)?;
        Ok(self.eval_geometry(incident, &g))
    }

    fn eval_geometry<T>(
        &self,
        incident: &VolumeIncident<T, Pol, Coh>,
        g: &ScatteringGeometry<T>,
    ) -> PhaseValue<T, Pol::Throughput<T>>
    where
        T: Real,
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let m = if incident.ln_sigma > neg_inf::<T>() {
            incident.phase_channels.phase_matrix(
                self.kernel.coherence(),
                &self.medium.psd,
                &self.medium.scatterer,
                g,
                incident.ln_sigma,
            )
        } else {
            Matrix4::zeros()
        };
        PhaseValue {
            phase: Throughput::from_mueller(&Mueller(m)),
            geometry: *g,
        }
    }

    /// The density per steradian with which [`Self::sample`] draws `direction` (a unit vector).
    ///
    /// # Formula
    /// ```text
    /// p(r̂) = w_u/(4π) + (1 − w_u) k² Σ_j c_j g_j(v)/F_j(2k),     |v| = k|r̂ − d̂|,  Σ_j c_j = 1
    /// Gaussian lobe:  g(v) = exp(−|v|²/2s²)/(2πs²),           F(2k) = 1 − e^{−2k²/s²}
    /// power lobe:     g(v) = (β−1)/(πs²) (1 + |v|²/s²)^{−β},   F(2k) = 1 − (1 + 4k²/s²)^{1−β}
    /// ```
    /// A mixture of the uniform sphere (weight `w_u`: the defensive part, and the whole
    /// proposal when the lobe is as wide as the sphere) and up to four radial lobes on
    /// Lambert's disk about d̂ (`d²v = k² dΩ`), each truncated to `|v| ≤ 2k` with its exact mass
    /// `F`: scales from the PSD's spectral covariance and the inverse coherence, power lobes
    /// of the K-correlation's own exponent. `w_u = min(1, max(0.05, (s_max/2k)², 1.5 f_far))`,
    /// `f_far` the share of `σ_s` beyond three lobe widths.
    #[must_use]
    pub fn pdf<T: Real>(
        &self,
        incident: &VolumeIncident<T, Pol, Coh>,
        direction: &Vector3<T>,
    ) -> T {
        incident
            .sampler
            .pdf(&incident.channels.frame, incident.channels.k, direction)
    }

    /// A direction drawn from three uniforms in `[0, 1)` (`u_part` chooses the sampler's part,
    /// `u` the radius by the truncated radial CDF and the azimuth about d̂), with its pdf
    /// ([`Self::pdf`], exactly) and the weight `F/pdf`. Never empty; uniforms outside `[0, 1)`
    /// (NaN included) are clamped into it.
    #[must_use]
    pub fn sample<T>(
        &self,
        incident: &VolumeIncident<T, Pol, Coh>,
        u_part: T,
        u: [T; 2],
    ) -> PhaseSample<T, Pol::Throughput<T>>
    where
        T: Real,
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let (f, k) = (&incident.channels.frame, incident.channels.k);
        let direction = incident.sampler.sample(f, k, u_part, u);
        let pdf = incident.sampler.pdf(f, k, &direction);
        // The geometry exactly as `eval` builds it, so that `weight` is `eval(direction)/pdf`.
        let unit = crate::numerics::unit_by_largest(&direction).unwrap_or(direction);
        let g = incident.channels.geometry(unit);
        let v = self.eval_geometry(incident, &g);
        PhaseSample {
            direction,
            pdf,
            weight: v.phase.scaled(pdf.recip()),
            geometry: g,
        }
    }

    /// `dI/dV = σ_s F S` for the packet's own Stokes vector `S`, computed without `σ_s`
    /// ([`RandomMedium::differential_scattering`]).
    ///
    /// # Errors
    /// As [`Self::eval`].
    pub fn differential_scattering<T>(
        &self,
        incident: &VolumeIncident<T, Pol, Coh>,
        exit: Vector3<T>,
    ) -> Result<ScatteredLight<T, LevelLight<T, Pol>>, Error>
    where
        T: Real,
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let g = ScatteringGeometry::new(&incident.channels.frame, incident.channels.k, exit)?;
        let v = incident.channels.scattered(
            self.kernel.coherence(),
            &self.medium.psd,
            &self.medium.scatterer,
            &g,
        );
        Ok(ScatteredLight {
            light: <Pol::Throughput<T> as Throughput<T>>::light(&Stokes(v)),
            geometry: g,
        })
    }
}

impl<P, M> RandomMedium<P, M> {
    /// `dI/dV(r̂)`: the Stokes radiant intensity per unit volume that the packet scatters
    /// toward `exit` (any length), in the exit scattering-plane frame, for the packet's own
    /// irradiance `S` — divide by `S0` for the value per unit incident irradiance. The absolute
    /// first-Born constant `k⁴/16π²` is in it ([module docs](super)); it needs no `σ_s` (nothing
    /// is integrated), so it is the cheap form for comparisons with a field sum.
    ///
    /// # Errors
    /// As [`PhaseFunction::prepare`] and [`PhaseFunction::eval`].
    ///
    /// # Examples
    /// A correlation length far below the wavelength: the dipole pattern,
    /// `(k⁴/16π²)(2π)^{3/2} p(h) (1 + cos²Θ)/2` for unpolarized light, fully polarized at 90°.
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Full, Kernel, PlaneWave};
    /// use gmueller::medium::{Dipole, RandomMedium};
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    /// use std::f64::consts::{PI, TAU};
    ///
    /// let (sigma, ell, lambda) = (1e-2_f64, 1e-4, 0.5);
    /// let medium = RandomMedium::new(GaussianPsd::<f64, 3>::isotropic(sigma, ell)?, Dipole);
    /// let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
    /// let light = WavePacket::from_stokes(
    ///     Stokes::unpolarized(1.0)?, CoherenceShape::isotropic(10.0)?, frame, lambda)?;
    /// let kernel = Kernel::<Full, PlaneWave>::default();
    /// let k = TAU / lambda;
    /// // 90°: |h|² = 2k², p(h) = σ² ℓ³ exp(−ℓ² k²) for the Gaussian PSD.
    /// let p = sigma * sigma * ell.powi(3) * (-(ell * k).powi(2)).exp();
    /// let side = medium.differential_scattering(&kernel, &light, Vector3::new(1.0, 0.0, 0.0))?;
    /// let expected = k.powi(4) / (16.0 * PI * PI) * TAU.powf(1.5) * p * 0.5;
    /// assert!((side.light.s0() / expected - 1.0).abs() < 1e-13);
    /// assert!((side.light.degree_of_polarization() - 1.0).abs() < 1e-6); // fully polarized at 90°
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn differential_scattering<T, Pol, Coh>(
        &self,
        kernel: &Kernel<Pol, Coh>,
        packet: &WavePacket<T>,
        exit: Vector3<T>,
    ) -> Result<ScatteredLight<T, LevelLight<T, Pol>>, Error>
    where
        T: Real,
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Pol: PolarizationModel,
        Coh: VolumeCoherence<T, P>,
    {
        let channels = Channels::<T, Pol, Coh>::new(packet, &self.psd, kernel.coherence())?;
        let g = ScatteringGeometry::new(packet.frame(), packet.wavenumber(), exit)?;
        let v = channels.scattered(kernel.coherence(), &self.psd, &self.scatterer, &g);
        Ok(ScatteredLight {
            light: <Pol::Throughput<T> as Throughput<T>>::light(&Stokes(v)),
            geometry: g,
        })
    }
}
