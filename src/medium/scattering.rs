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

use nalgebra::{Matrix2, Matrix3, Matrix4, Vector4};

use super::coherence::VolumeCoherence;
use super::geometry::ScatteringGeometry;
use super::scatterer::Scatterer;
use crate::error::Error;
use crate::frame::{Frame, frame_change_mueller};
use crate::gaussian::Gaussian;
use crate::interaction::{
    CoherenceLevel, CoherenceModel, Plan, PolarizationLevel, PolarizationModel, PreparedPacket,
    onto_cone, unit_scaled,
};
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
/// Gaussian in `h`: formed and factored in `f64` whatever `T` (the factor is then rounded),
/// so that the longitudinal variance `1/σ_zz²` survives beside a transverse `1/w²` up to a
/// ratio of ~1e14 in both precisions.
///
/// A longitudinal variance `1/σ_zz²` below `64 ε₆₄` times the largest transverse one `1/w²`
/// (the smallest the factorisation keeps: `σ_zz ≳ 1.2e7 w`) is raised to it, and so is that of
/// unbounded longitudinal coherence (`σ_zz = ∞`, monochromatic light) when `unbounded_ok`: the
/// limit, which moves a blur `∫ p 𝒩_Ξ(h − ·)` by a relative `~64 ε₆₄ λ_max(Θ⊥⁻¹)/Λ_zz` (`Λ_zz`
/// the PSD's spectral variance along d̂): `1e-14 (ℓ/w)²`.
///
/// # Errors
/// [`Error::Singular`] for unbounded longitudinal coherence unless `unbounded_ok`;
/// [`Error::NotPositiveDefinite`] when the factor is not representable in `T`.
pub(crate) fn inverse_coherence<T: Real>(
    packet: &WavePacket<T>,
    channel: Channel,
    unbounded_ok: bool,
) -> Result<Gaussian<T, 3>, Error> {
    let mut inv_zz = packet.inverse_longitudinal_variance().to_f64();
    if inv_zz == 0.0 && !unbounded_ok {
        return Err(Error::Singular {
            what: "3-D shape matrix with unbounded longitudinal coherence (set σ_zz with \
                   WavePacket::with_longitudinal_coherence)",
        });
    }
    let s = packet.shape(channel).map(|x| x.to_f64());
    let det = s[(0, 0)] * s[(1, 1)] - s[(0, 1)] * s[(1, 0)];
    let inv = Matrix2::new(s[(1, 1)], -s[(0, 1)], -s[(1, 0)], s[(0, 0)]) / det;
    // The smallest longitudinal variance the factorisation keeps beside the transverse ones:
    // a longer σ_zz (or an unbounded one) is taken as that limit.
    let half = 0.5 * (inv[(0, 0)] + inv[(1, 1)]);
    let r = (0.5 * (inv[(0, 0)] - inv[(1, 1)])).hypot(0.5 * (inv[(0, 1)] + inv[(1, 0)]));
    inv_zz = inv_zz.max(64.0 * f64::EPSILON * (half + r));
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

/// The per-packet part of the medium's kernel: the packet's channel intensities and
/// Bochner bound (the surface kernel's [`PreparedPacket`], without sections or rotation), the
/// inverse coherences `Ξ_α` of the channels the level uses, the packet frame and the Born
/// constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Channels<T: Real, Pol, Coh> {
    pub(crate) prepared: PreparedPacket<T, Pol, Coh>,
    /// `Ξ_x`, `Ξ_y`, `Ξ_½` (`None` where unused).
    pub(crate) xi: [Option<Gaussian<T, 3>>; 3],
    pub(crate) frame: Frame<T>,
    pub(crate) k: T,
    pub(crate) ln_born: T,
    /// The Full level on a packet with two shapes: three weights.
    pub(crate) three: bool,
}

impl<T: Real, Pol: PolarizationModel, Coh: CoherenceModel> Channels<T, Pol, Coh> {
    /// The per-packet part for `packet` at the levels `(Pol, Coh)`.
    ///
    /// # Errors
    /// As [`inverse_coherence`], for the levels that use the shapes (`Partial`, `Incoherent`).
    pub(crate) fn new(packet: &WavePacket<T>) -> Result<Self, Error> {
        let single = packet.has_single_shape();
        let three = Pol::LEVEL == PolarizationLevel::Full && Coh::USES_SHAPE && !single;
        let plan = Plan {
            sections: [false; 3],
            rotation: false,
            channel_logs: three,
            single_shape: single,
        };
        let prepared = PreparedPacket::new(packet, packet.frame(), packet.frame(), plan);
        let xi = |used: bool, c: Channel| -> Result<Option<Gaussian<T, 3>>, Error> {
            if used {
                inverse_coherence(packet, c, Coh::LEVEL == CoherenceLevel::Partial).map(Some)
            } else {
                Ok(None)
            }
        };
        Ok(Self {
            prepared,
            xi: [
                xi(three, Channel::X)?,
                xi(three, Channel::Y)?,
                xi(Coh::USES_SHAPE, Channel::Half)?,
            ],
            frame: *packet.frame(),
            k: packet.wavenumber(),
            ln_born: ln_born(packet.wavenumber()),
            three,
        })
    }

    /// The same for unpolarized light of the packet's coherence (for a dark packet, whose
    /// phase matrix and scattering coefficient are those of unpolarized light).
    pub(crate) fn unpolarized(packet: &WavePacket<T>) -> Result<Self, Error> {
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
        Self::new(&p)
    }

    /// The geometry of the exit direction `r` (finite unit vector).
    #[inline]
    pub(crate) fn geometry(&self, r: nalgebra::Vector3<T>) -> ScatteringGeometry<T> {
        ScatteringGeometry::from_unit(&self.frame, self.k, r)
    }

    /// The channel weights `ln K³_x, ln K³_y, ln K³_½` (only `K³_½` unless three).
    #[inline]
    fn log_weights<P>(&self, coherence: &Coh, psd: &P, g: &ScatteringGeometry<T>) -> [T; 3]
    where
        P: Psd<T, 3>,
        Coh: VolumeCoherence<T, P>,
    {
        let w = |i: usize| coherence.log_volume_weight(psd, self.xi[i].as_ref(), &g.h);
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

    /// `[dI/dV]₀/S0 = e^{ln e} · value` for the exit `r` (finite unit vector) whose transverse
    /// direction in the packet basis is `(c, s) = (cos φ, sin φ)`, without the frames: the first
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
        r: &nalgebra::Vector3<T>,
        (c, s): (T, T),
        axial: bool,
    ) -> (T, T)
    where
        P: Psd<T, 3>,
        M: Scatterer<T>,
        Coh: VolumeCoherence<T, P>,
    {
        let h = (r - self.frame.k) * self.k;
        let cos_theta = r.dot(&self.frame.k).clamp(-T::one(), T::one());
        let w = |i: usize| coherence.log_volume_weight(psd, self.xi[i].as_ref(), &h);
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
