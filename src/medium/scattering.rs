//! The single-scattering kernel of a random medium, S2.20 with n = 3 and the first-Born
//! constant: per packet, the channel weights' ingredients; per exit direction, the scattered
//! Stokes radiant intensity (per unit volume) and the same as a Mueller matrix.
//!
//! # Formula
//! ```text
//! dI/dV = (k⁴/16π²) · m̄(cos Θ) · T · Σ_α K³_α(h) P_α S
//! P_x = ½[[1,1],[1,1]] ⊕ 0,  P_y = ½[[1,−1],[−1,1]] ⊕ 0,  P_½ = 0 ⊕ I₂       (S2.16: Σ_α P_α S = Σ_α S_α)
//! Intensity:  (k⁴/16π²) m̄₀₀ K³_½ S0;   OneShape: (k⁴/16π²) m̄ T K³_½ S;   Full: as above
//! ```
//! `T` the rotation (S2.4) from the packet frame to the incident scattering-plane frame
//! ([`super::ScatteringGeometry`]); `K³_α` from [`super::VolumeCoherence`]. The Full level
//! caps `K³_½` at the Cauchy–Schwarz bound `√(K³_x K³_y)/|μ|_max` exactly as the surface
//! kernel does (the bound holds in any dimension: the spectral matrix of a realizable packet is
//! positive semidefinite at every frequency, and `K³` averages it against `p ≥ 0`).

use nalgebra::{Matrix3, Matrix4, Vector4};

use super::basis::{ChannelBasis, PacketLobe, PacketXi, packet_inverse_coherence};
use super::coherence::VolumeCoherence;
use super::geometry::ScatteringGeometry;
use super::scatterer::Scatterer;
use super::spectrum::VolumeLobes;
use crate::error::Error;
use crate::frame::{Frame, frame_change_mueller};
use crate::gaussian::Gaussian;
use crate::interaction::coherence::{CoherenceLevel, CoherenceModel};
use crate::interaction::polarization::{PolarizationLevel, PolarizationModel};
use crate::interaction::{Plan, PreparedPacket, onto_cone, unit_scaled};
use crate::numerics::cholesky;
use crate::packet::{Channel, CoherenceShape, WavePacket};
use crate::psd::Psd;
use crate::real::Real;
use crate::stokes::Stokes;

/// `ln(k⁴/16π²)`, the first-Born constant of the differential scattering (module docs of
/// [`crate::medium`]).
#[inline]
pub(crate) fn ln_born<T: Real>(k: T) -> T {
    T::lit(4.0) * k.ln() - T::lit((16.0 * core::f64::consts::PI * core::f64::consts::PI).ln())
}

/// The inverse coherence `Ξ_α = Q Θ_α⁻¹ Qᵀ` of a channel in world coordinates (S2.18), as a
/// Gaussian in `h`: formed and factored in `f64` whatever `T` (the factor is then rounded).
///
/// A longitudinal variance `1/σ_zz²` below `64 ε₆₄` times the largest transverse one `1/w²`
/// (the smallest the factorisation keeps: `σ_zz ≳ 1.2e7 w`) is raised to it, and so is that of
/// unbounded longitudinal coherence (`σ_zz = ∞`, monochromatic light) when `unbounded_ok`: the
/// limit, which moves a blur `∫ p 𝒩_Ξ(h − ·)` by a relative `~64 ε₆₄ λ_max(Θ⊥⁻¹)/Λ_zz` (`Λ_zz`
/// the PSD's spectral variance along d̂): `1e-14 (ℓ/w)²`.
///
/// The world form is what a blur method is handed for a PSD that is not known to be isotropic
/// or Gaussian ([`crate::psd::Form::is_exact`]); its rounding to `T` keeps `Ξ_α`'s small
/// variances only to a relative `~ε κ` in sums such as `Λ + Ξ_α` (`κ` the condition of the
/// sum), which is why the medium prefers the channel's own basis ([`super::basis`]).
///
/// # Errors
/// [`Error::Singular`] for unbounded longitudinal coherence unless `unbounded_ok`;
/// [`Error::NotPositiveDefinite`] when the factor is not representable in `T`.
pub(crate) fn inverse_coherence<T: Real>(
    packet: &WavePacket<T>,
    channel: Channel,
    unbounded_ok: bool,
) -> Result<Gaussian<T, 3>, Error> {
    let PacketXi {
        transverse: inv,
        zz: inv_zz,
    } = packet_inverse_coherence(packet, channel, unbounded_ok)?;
    let f = packet.frame();
    let v = |w: nalgebra::Vector3<T>| w.map(|x| x.to_f64());
    let (x, y, k) = (v(f.x), v(f.y), v(f.k));
    let m: Matrix3<f64> = x * x.transpose() * inv[(0, 0)]
        + (x * y.transpose() + y * x.transpose()) * (0.5 * (inv[(0, 1)] + inv[(1, 0)]))
        + y * y.transpose() * inv[(1, 1)]
        + k * k.transpose() * inv_zz;
    let bad = Error::NotPositiveDefinite {
        what: "inverse coherence Ξ = QΘ⁻¹Qᵀ of the packet",
        min_eigenvalue: inv_zz.min(inv[(0, 0)]),
    };
    let l = cholesky(&m).map_err(|_| bad.clone())?;
    Gaussian::from_cholesky(l.map(T::lit)).ok_or(bad)
}

/// How one channel's weight is evaluated ([`super::basis`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Weight<T: Real> {
    /// Unused by the level.
    None,
    /// The level's [`VolumeCoherence::log_volume_weight`] at the world `h` (`PlaneWave`; a
    /// `Partial` blur of a PSD that is neither an exact Gaussian with a closed-form blur nor
    /// isotropic), with the world `Ξ_α` where the level uses it.
    World(Option<Gaussian<T, 3>>),
    /// The level's weight of an isotropic PSD at `B_αᵀ h`, with the diagonal `Ξ_α` of the
    /// channel's basis.
    Basis([nalgebra::Vector3<T>; 3], Gaussian<T, 3>),
    /// A Gaussian lobe in the channel's basis (`Incoherent`; `Partial` with a Gaussian PSD and
    /// a blur exact for Gaussians).
    Lobe(PacketLobe<T>),
}

/// `true` when every lobe is isotropic (`Λ ∝ I` to 64 ε; the K-correlation always).
fn lobes_isotropic<T: Real>(lobes: &VolumeLobes<'_, T>) -> bool {
    let iso = |a: &Matrix3<T>| {
        let mean = a.trace() / T::lit(3.0);
        (a - Matrix3::identity() * mean).amax() <= T::lit(64.0) * T::EPSILON * mean.abs()
    };
    match lobes {
        VolumeLobes::Gaussian(lambda) => iso(lambda),
        VolumeLobes::Mixture(components) => components
            .iter()
            .all(|c| iso(c.spectral_shape().covariance())),
        VolumeLobes::KCorrelation { .. } => true,
    }
}

/// The per-packet part of the medium's kernel: the packet's channel intensities and
/// Bochner bound (the surface kernel's [`PreparedPacket`], without sections or rotation), the
/// weights `K³_α` of the channels the level uses in the form each is evaluated in, the packet
/// frame and the Born constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Channels<T: Real, Pol, Coh> {
    pub(crate) prepared: PreparedPacket<T, Pol, Coh>,
    /// The weights of `x`, `y`, `½`.
    pub(crate) weights: [Weight<T>; 3],
    /// `Ξ_½` in the packet basis, exact (`None` at the plane-wave level): the lobe's shape.
    pub(crate) xi_half: Option<PacketXi>,
    pub(crate) frame: Frame<T>,
    pub(crate) k: T,
    pub(crate) ln_born: T,
    /// The Full level on a packet with two shapes: three weights.
    pub(crate) three: bool,
}

impl<T: Real, Pol: PolarizationModel, Coh: CoherenceModel> Channels<T, Pol, Coh> {
    /// The per-packet part for `packet` at the levels `(Pol, Coh)` in the medium of PSD `psd`.
    ///
    /// # Errors
    /// As [`inverse_coherence`], for the levels that use the shapes (`Partial`, `Incoherent`).
    pub(crate) fn new<P>(packet: &WavePacket<T>, psd: &P, coherence: &Coh) -> Result<Self, Error>
    where
        P: Psd<T, 3>,
        Coh: VolumeCoherence<T, P>,
    {
        let single = packet.has_single_shape();
        let three = Pol::LEVEL == PolarizationLevel::Full && Coh::USES_SHAPE && !single;
        let plan = Plan {
            sections: [false; 3],
            rotation: false,
            channel_logs: three,
            single_shape: single,
        };
        let prepared = PreparedPacket::new(packet, packet.frame(), packet.frame(), plan);
        let partial = Coh::LEVEL == CoherenceLevel::Partial;
        let lobes = VolumeLobes::of(psd.form())?;
        let exact = psd.form().is_exact();
        let isotropic = exact && lobes_isotropic(&lobes);
        // A closed-form blur in the channel's basis (a quadrature blur keeps the world axes its
        // nodes were placed in: its error depends on their orientation).
        let closed = coherence.closed_form_for_gaussians();
        // ln((2π)^{3/2} σ²) = ln ∫p.
        let ln_amplitude = psd.integral().to_f64().ln();
        let bad = |x: &PacketXi| Error::NotPositiveDefinite {
            what: "inverse coherence Ξ = QΘ⁻¹Qᵀ of the packet",
            min_eigenvalue: x.zz.min(x.transverse[(0, 0)]),
        };
        let weight = |used: bool, c: Channel| -> Result<Weight<T>, Error> {
            if !used {
                return Ok(Weight::None);
            }
            if !Coh::USES_SHAPE {
                return Ok(Weight::World(None));
            }
            let x = packet_inverse_coherence(packet, c, partial)?;
            let basis = ChannelBasis::new(&x, packet.frame());
            if !partial {
                // Incoherent: the lobe of Ξ_α alone.
                return PacketLobe::new(&basis.diagonal(), &basis, ln_amplitude)
                    .map(Weight::Lobe)
                    .ok_or_else(|| bad(&x));
            }
            match lobes {
                VolumeLobes::Gaussian(lambda) if exact && closed => {
                    let cov = basis.project(&lambda) + basis.diagonal();
                    PacketLobe::new(&cov, &basis, ln_amplitude)
                        .map(Weight::Lobe)
                        .ok_or_else(|| bad(&x))
                }
                _ if isotropic && closed => basis
                    .gaussian()
                    .map(|g| Weight::Basis(basis.rows(), g))
                    .ok_or_else(|| bad(&x)),
                _ => inverse_coherence(packet, c, true).map(|g| Weight::World(Some(g))),
            }
        };
        Ok(Self {
            prepared,
            weights: [
                weight(three, Channel::X)?,
                weight(three, Channel::Y)?,
                weight(true, Channel::Half)?,
            ],
            xi_half: if Coh::USES_SHAPE {
                Some(packet_inverse_coherence(packet, Channel::Half, partial)?)
            } else {
                None
            },
            frame: *packet.frame(),
            k: packet.wavenumber(),
            ln_born: ln_born(packet.wavenumber()),
            three,
        })
    }

    /// The same for unpolarized light of the packet's coherence (for a dark packet, whose
    /// phase matrix and scattering coefficient are those of unpolarized light).
    pub(crate) fn unpolarized<P>(
        packet: &WavePacket<T>,
        psd: &P,
        coherence: &Coh,
    ) -> Result<Self, Error>
    where
        P: Psd<T, 3>,
        Coh: VolumeCoherence<T, P>,
    {
        let mut p = WavePacket::new(
            Stokes::unpolarized(T::one())?,
            CoherenceShape::new(packet.shape(Channel::X))?,
            CoherenceShape::new(packet.shape(Channel::Y))?,
            *packet.frame(),
            packet.wavelength(),
        )?;
        let inv = packet.inverse_longitudinal_variance();
        if inv > T::zero() {
            p = p.with_longitudinal_coherence(inv.sqrt().recip())?;
        }
        Self::new(&p, psd, coherence)
    }

    /// The geometry of the exit direction `r` (finite unit vector).
    #[inline]
    pub(crate) fn geometry(&self, r: nalgebra::Vector3<T>) -> ScatteringGeometry<T> {
        ScatteringGeometry::from_unit(&self.frame, self.k, r)
    }

    /// `ln K³` of channel `i` (`x`, `y`, `½`) at `h` (world), in the channel's form
    /// ([`Weight`]).
    #[inline]
    fn log_weight<P>(&self, coherence: &Coh, psd: &P, i: usize, h: &nalgebra::Vector3<T>) -> T
    where
        P: Psd<T, 3>,
        Coh: VolumeCoherence<T, P>,
    {
        match &self.weights[i] {
            Weight::Lobe(l) => l.log_weight(h),
            Weight::Basis(rows, xi) => {
                let hb = nalgebra::Vector3::new(rows[0].dot(h), rows[1].dot(h), rows[2].dot(h));
                coherence.log_volume_weight(psd, Some(xi), &hb)
            }
            Weight::World(xi) => coherence.log_volume_weight(psd, xi.as_ref(), h),
            Weight::None => coherence.log_volume_weight(psd, None, h),
        }
    }

    /// The channel weights `ln K³_x, ln K³_y, ln K³_½` (only `K³_½` unless three).
    #[inline]
    fn log_weights<P>(&self, coherence: &Coh, psd: &P, g: &ScatteringGeometry<T>) -> [T; 3]
    where
        P: Psd<T, 3>,
        Coh: VolumeCoherence<T, P>,
    {
        let w = |i: usize| self.log_weight(coherence, psd, i, &g.h);
        if self.three {
            [w(0), w(1), w(2)]
        } else {
            let h = w(2);
            [h, h, h]
        }
    }

    /// The Stokes form per unit `S0`: `(u, ln e)` with `dI/dV = S0 e^{ln e} u`, `u` a valid
    /// Stokes vector of order one in the exit frame (`u = (m̄₀₀, 0, 0, 0)` at the intensity
    /// level).
    #[inline]
    pub(crate) fn stokes_part<P, M>(
        &self,
        coherence: &Coh,
        psd: &P,
        scatterer: &M,
        g: &ScatteringGeometry<T>,
    ) -> (Vector4<T>, T)
    where
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let [lx, ly, lh] = self.log_weights(coherence, psd, g);
        let z = T::zero();
        match Pol::LEVEL {
            PolarizationLevel::Intensity => (
                Vector4::new(scatterer.m00(g.cos_theta), z, z, z),
                self.ln_born + lh,
            ),
            _ => {
                let (v, ln_w) = if self.three {
                    self.prepared.channel_mix(lx, ly, lh)
                } else {
                    (self.prepared.t_stokes, lh)
                };
                let t = frame_change_mueller(&self.frame, &g.incident).0;
                let m = scatterer.mueller(g.cos_theta).0;
                (onto_cone(m * (t * v)), self.ln_born + ln_w)
            }
        }
    }

    /// `[dI/dV]₀/S0 = e^{ln e} · value` for the exit of scattering vector `h` and `cos Θ`
    /// whose transverse direction in the packet basis is `(c, s) = (cos φ, sin φ)`, without
    /// the frames: the first
    /// row of `m̄ T`, with `T` the rotation to the scattering plane, whose normal `d̂ × r̂` lies at
    /// `φ + π/2` (S2.4: `(T v)₁ = −cos 2φ v₁ − sin 2φ v₂`, `(T v)₂ = sin 2φ v₁ − cos 2φ v₂`).
    /// `axial`: the terms in `cos 2φ`, `sin 2φ` left out (they integrate to 0 over φ when the
    /// weights are symmetric about d̂). The `σ_s` quadrature's integrand.
    #[inline]
    pub(crate) fn intensity_part<P, M>(
        &self,
        coherence: &Coh,
        psd: &P,
        scatterer: &M,
        (h, cos_theta): (&nalgebra::Vector3<T>, T),
        (c, s): (T, T),
        axial: bool,
    ) -> (T, T)
    where
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let w = |i: usize| self.log_weight(coherence, psd, i, h);
        if Pol::LEVEL == PolarizationLevel::Intensity {
            return (scatterer.m00(cos_theta), self.ln_born + w(2));
        }
        let (v, ln_w) = if self.three {
            self.prepared.channel_mix(w(0), w(1), w(2))
        } else {
            (self.prepared.t_stokes, w(2))
        };
        let m = scatterer.mueller(cos_theta).0;
        let mut value = m[(0, 0)] * v[0] + m[(0, 3)] * v[3];
        if !axial {
            let (c2, s2) = (c * c - s * s, (c + c) * s);
            value += m[(0, 1)] * (-c2 * v[1] - s2 * v[2]) + m[(0, 2)] * (s2 * v[1] - c2 * v[2]);
        }
        (value.max(T::zero()), self.ln_born + ln_w)
    }

    /// The Mueller form: `(A, ln e)` with `dI/dV = e^{ln e} A S` for every Stokes vector `S`
    /// the packet's shapes admit (`A = m̄ T D̂`, `D̂` the channel matrix; `m̄₀₀` alone in the
    /// `(0, 0)` entry at the intensity level).
    #[inline]
    pub(crate) fn mueller_part<P, M>(
        &self,
        coherence: &Coh,
        psd: &P,
        scatterer: &M,
        g: &ScatteringGeometry<T>,
    ) -> (Matrix4<T>, T)
    where
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let [lx, ly, lh] = self.log_weights(coherence, psd, g);
        match Pol::LEVEL {
            PolarizationLevel::Intensity => {
                let mut a = Matrix4::zeros();
                a[(0, 0)] = scatterer.m00(g.cos_theta);
                (a, self.ln_born + lh)
            }
            _ => {
                let (d, ln_w) = if self.three {
                    self.prepared.channel_matrix(lx, ly, lh)
                } else {
                    (Matrix4::identity(), lh)
                };
                let t = frame_change_mueller(&self.frame, &g.incident).0;
                let m = scatterer.mueller(g.cos_theta).0;
                (m * (t * d), self.ln_born + ln_w)
            }
        }
    }

    /// The absolute Stokes radiant intensity per unit volume (`S0 e^{ln e} u`, log-space safe).
    #[inline]
    pub(crate) fn scattered<P, M>(
        &self,
        coherence: &Coh,
        psd: &P,
        scatterer: &M,
        g: &ScatteringGeometry<T>,
    ) -> Vector4<T>
    where
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let (u, ln_e) = self.stokes_part(coherence, psd, scatterer, g);
        if self.prepared.is_dark(ln_e) {
            return Vector4::zeros();
        }
        self.prepared.scaled(u, ln_e)
    }

    /// `e^{ln e − ln σ} A`: the phase matrix, 0 where its scale is below the smallest normal
    /// number.
    #[inline]
    pub(crate) fn phase_matrix<P, M>(
        &self,
        coherence: &Coh,
        psd: &P,
        scatterer: &M,
        g: &ScatteringGeometry<T>,
        ln_sigma: T,
    ) -> Matrix4<T>
    where
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let (a, ln_e) = self.mueller_part(coherence, psd, scatterer, g);
        unit_scaled(a, ln_e - ln_sigma)
    }
}
