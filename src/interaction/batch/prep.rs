//! The per-packet work of the batch plane-wave kernel, done once per call: the incident s/p
//! frame, the rotation `T` and the effective Stokes vector, the per-packet part of the
//! Rayleigh–Rice factors, the PSD's Cholesky factor and the constant part of the exponent.

use nalgebra::{Matrix4, Vector2, Vector3, Vector4};
use num_complex::Complex;

use crate::error::Error;
use crate::frame::{Frame, frame_change_mueller};
use crate::interaction::geometry::{self, Geometry};
use crate::interaction::pbsdf::Scale;
use crate::numerics::unit_direction;
use crate::numerics::{HYPOT_PLAIN, principal_sqrt};
use crate::packet::WavePacket;
use crate::psd::{GaussianPsd, Psd};
use crate::real::Real;

/// The per-packet constants of the incidence shared by the batch kernels: the surface, ŝ, the
/// azimuth axes, and the per-packet part of the Rayleigh–Rice factors for a permittivity `ε`
/// (what the geometry, azimuth, `q_o` and Rayleigh–Rice stages read).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Incidence<T: Real> {
    pub(crate) surface: Frame<T>,
    /// `−k̂` of the packet as given (for the exact error of an ambiguous direction).
    pub(crate) to_source_raw: Vector3<T>,
    /// ŝ (unit).
    pub(crate) s: Vector3<T>,
    pub(crate) n: Vector3<T>,
    pub(crate) t1: Vector3<T>,
    pub(crate) t2: Vector3<T>,
    /// `n̂ × ŝ_in` and `n̂ × (n̂ × ŝ_in)`: the azimuth axes of [`Geometry::exit_azimuth`].
    pub(crate) u_az: Vector3<T>,
    pub(crate) v_az: Vector3<T>,
    pub(crate) k: T,
    pub(crate) cos_i: T,
    pub(crate) si2: T,
    pub(crate) e: Complex<T>,
    pub(crate) qi: Complex<T>,
    /// The Rayleigh–Rice factors' scale `1/t, 1/t², 1/t³` (`RayleighRice`'s `Scale`) and the
    /// per-packet terms scaled by it, with the scalar's operations: `(ε − 1)/t²`, its
    /// negation, `D₁/t`, `D₃/t²` and `−(ε − 1)/t² · q_i/t`.
    pub(crate) scale: Scale<T>,
    pub(crate) em1s: Complex<T>,
    pub(crate) neg_em1s: Complex<T>,
    pub(crate) d1s: Complex<T>,
    pub(crate) d3s: Complex<T>,
    pub(crate) neg_em1s_qis: Complex<T>,
    /// `Im ε = 0`: the modulus in `q_o` is `|Re(ε) − sin²θ_o|`.
    pub(crate) real_eps: bool,
    /// The scalar `hypot` in `q_o` takes its plain branch for every exit (or `Im ε = 0`): the
    /// lanes reproduce it.
    pub(crate) plain_q: bool,
    /// `(Im ε)²` and `(Im ε)/2`.
    pub(crate) eim2: T,
    pub(crate) eim_half: T,
    /// `√ε` of the type: below it `Frame::sp` falls back to a tangent of n̂.
    pub(crate) parallel_tol: T,
    /// The incident s/p frame.
    pub(crate) incident_sp: Frame<T>,
    /// `Some((η, surface))` at a dielectric interface of relative index `η` and the caller's
    /// surface frame (`surface` above is the one facing the source: reversed for light from
    /// below; exits on either side are valid, [`Geometry::at_interface`]); `None` in reflection
    /// ([`Geometry::new`]).
    pub(crate) interface: Option<(T, Frame<T>)>,
}

/// The per-packet constants of [`super::plane_wave_rayleigh_rice`]: the incidence and the
/// plane-wave PSD weight's constants (reached through `Deref`, so the incidence stages take a
/// `&PlaneWavePrep` as an `&Incidence`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PlaneWavePrep<T: Real> {
    pub(crate) inc: Incidence<T>,
    /// Whether the SIMD loop reproduces the per-direction kernel for these parameters.
    pub(crate) vectorizable: bool,
    /// `ln(σ²|Λ|^{1/2}) + ln(2π (2k cos θ_i)² / λ²) + ln S0`.
    pub(crate) log_scale: T,
    pub(crate) variance: T,
    pub(crate) l00: T,
    pub(crate) l10: T,
    pub(crate) l11: T,
    /// `T S/S0` as `(S0 + S1)/2, (S0 − S1)/2, S2, S3` (the Full level's effective vector,
    /// normalised; `S0` is in `log_scale`).
    pub(crate) stokes: [T; 4],
}

impl<T: Real> core::ops::Deref for PlaneWavePrep<T> {
    type Target = Incidence<T>;
    #[inline(always)]
    fn deref(&self) -> &Incidence<T> {
        &self.inc
    }
}

impl<T: Real> Incidence<T> {
    /// The incidence of `packet` on `surface` with the Rayleigh–Rice permittivity `epsilon`.
    #[inline]
    pub(crate) fn new(
        epsilon: Complex<T>,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
    ) -> Result<Self, Error> {
        Self::from_direction(epsilon, -packet.direction(), packet.wavenumber(), surface)
    }

    /// [`Incidence::new`] of light of wavenumber `k` arriving from `to_source` (`−k̂`, any
    /// length).
    #[inline]
    pub(crate) fn from_direction(
        epsilon: Complex<T>,
        to_source: Vector3<T>,
        k: T,
        surface: &Frame<T>,
    ) -> Result<Self, Error> {
        let s = unit_direction(&to_source, "direction to the source")?.into_inner();
        let n = surface.k();
        let (cos_i, incident_sp) = geometry::incidence(&s, surface)?;
        let u_az = n.cross(&incident_sp.x());
        let v_az = n.cross(&u_az);
        // RayleighRice::factors' per-packet part, with the same operations.
        let e = epsilon;
        let one = Complex::new(T::one(), T::zero());
        let si2 = (T::one() - cos_i * cos_i).max(T::zero());
        let qi = principal_sqrt(e - one * si2);
        let em1 = e - one;
        let d1 = qi + cos_i;
        let d3 = e * cos_i + qi;
        let scale = Scale::of(e);
        let em1s = em1 * scale.inv2;
        // `hypot(Re ε − sin²θ_o, Im ε)` takes its plain branch for every θ_o when Im ε ≠ 0 lies
        // in [1e-18, 1e18] and |Re ε| + 1 ≤ 1e18; with Im ε = 0 it is |Re ε − sin²θ_o| exactly.
        let (lo, hi) = (T::lit(HYPOT_PLAIN.0), T::lit(HYPOT_PLAIN.1));
        let real_eps = e.im == T::zero();
        let plain = e.im.abs() >= lo && e.im.abs() <= hi && e.re.abs() + T::one() <= hi;
        Ok(Self {
            surface: *surface,
            to_source_raw: to_source,
            s,
            n,
            t1: surface.x(),
            t2: surface.y(),
            u_az,
            v_az,
            k,
            cos_i,
            si2,
            e,
            qi,
            scale,
            em1s,
            neg_em1s: -em1s,
            d1s: d1 * scale.inv,
            d3s: d3 * scale.inv2,
            neg_em1s_qis: -em1s * (qi * scale.inv),
            real_eps,
            plain_q: real_eps || plain,
            eim2: e.im * e.im,
            eim_half: e.im * T::lit(0.5),
            parallel_tol: T::EPSILON.sqrt(),
            incident_sp,
            interface: None,
        })
    }

    /// `Ok` when the per-direction kernel accepts `exit` (the error of [`Geometry::new`], or
    /// at an interface of [`Geometry::at_interface`], otherwise).
    pub(crate) fn check_exact(&self, exit: Vector3<T>) -> Result<(), Error> {
        match self.interface {
            Some((eta, surface)) => {
                Geometry::at_interface(self.k, &surface, eta, self.to_source_raw, exit)
            }
            None => Geometry::new(self.k, &self.surface, self.to_source_raw, exit),
        }
        .map(|_| ())
    }

    /// `(cos φ, sin φ)` of [`Geometry::exit_azimuth`] for the unit exit `r` (the scalar code,
    /// for directions within `√ε` of the normal).
    pub(crate) fn azimuth_scalar(&self, r: Vector3<T>) -> (T, T) {
        let s_out = Frame::sp_unit(r, self.n).x();
        (-s_out.dot(&self.v_az), s_out.dot(&self.u_az))
    }
}

impl<T: Real> PlaneWavePrep<T> {
    /// The per-packet constants. `#[inline]`: out of line, its large `Result` was moved into
    /// the caller with a `memcpy` on every call (+135 instructions per call in `f64`).
    #[inline]
    pub(crate) fn new(
        psd: &GaussianPsd<T, 2>,
        epsilon: Complex<T>,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
    ) -> Result<Self, Error> {
        let inc = Incidence::new(epsilon, packet, surface)?;
        // The incident s/p frame, T and the effective Stokes vector exactly as the Full level.
        let t = frame_change_mueller(packet.frame(), &inc.incident_sp).0;
        // S/S0, with ln S0 folded into the exponent of the weight: the weight alone (K, tiny in
        // a far tail) underflowed before it was scaled by a bright S0 (f32: 0 for S0 = 1e25
        // where the answer is 3e-22).
        let st = packet.stokes().0;
        let (st, ln_s0) = if st[0] > T::zero() {
            (st / st[0], st[0].ln())
        } else {
            (Vector4::zeros(), T::zero())
        };
        let half = T::lit(0.5);
        let (sx, sy) = ((st[0] + st[1]) * half, (st[0] - st[1]) * half);
        let ts = t * Vector4::new(sx + sy, sx - sy, st[2], st[3]);
        let k = inc.k;
        let lambda = T::two_pi() / k;
        let jones_scale = T::lit(2.0) * k * inc.cos_i;
        let log_prefactor = (T::two_pi() * jones_scale * jones_scale / (lambda * lambda)).ln();
        let log_amplitude = psd.log_value(&Vector2::zeros());
        let l = psd.spectral_shape().cholesky_factor();
        let vectorizable = inc.plain_q && log_prefactor.is_finite();
        Ok(Self {
            inc,
            vectorizable,
            log_scale: log_amplitude + log_prefactor + ln_s0,
            variance: psd.variance(),
            l00: l[(0, 0)],
            l10: l[(1, 0)],
            l11: l[(1, 1)],
            stokes: [
                (ts[0] + ts[1]) * T::lit(0.5),
                (ts[0] - ts[1]) * T::lit(0.5),
                ts[2],
                ts[3],
            ],
        })
    }
}

/// `c − ½ |L⁻¹ h|²`: the logarithm of a Gaussian channel weight in `h_t`, with `L` lower
/// triangular (`l00`, `l10`, `l11`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LogGaussian<T: Real> {
    pub(crate) c: T,
    pub(crate) l00: T,
    pub(crate) l10: T,
    pub(crate) l11: T,
    /// `1/ℓ₁₁`.
    pub(crate) inv_l11: T,
}

impl<T: Real> LogGaussian<T> {
    /// From the value at `h = 0` and the Cholesky factor `l` of the covariance.
    fn new(c: T, l: &nalgebra::Matrix2<T>) -> Self {
        Self {
            c,
            l00: l[(0, 0)],
            l10: l[(1, 0)],
            l11: l[(1, 1)],
            inv_l11: l[(1, 1)].recip(),
        }
    }

    /// Every constant finite (else the batch takes the per-direction kernel).
    fn is_finite(&self) -> bool {
        self.c.is_finite()
            && self.l10.is_finite()
            && self.l00.is_finite()
            && self.l11.is_finite()
            && self.l00.recip().is_finite()
            && self.l11.recip().is_finite()
    }
}

/// The `½` channel's specular and scattered weight constants ([`LobePrep::channels_of`]).
pub(crate) type HalfChannels<T> = (LogGaussian<T>, LogGaussian<T>);

/// At most this many Gaussian components of a mixture PSD run in lanes (a larger mixture goes
/// exit by exit).
pub(crate) const MAX_COMPONENTS: usize = 8;

/// The per-packet constants of the partially coherent lobe batch
/// ([`super::partial`]): a Gaussian PSD blurred in closed form, Fresnel specular
/// reflection and Rayleigh–Rice scattering, in reflection, at the `Full` or `OneShape` level.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LobePrep<T: Real> {
    pub(crate) inc: Incidence<T>,
    /// The `Full` level with two shapes: three channels mixed per exit (else `Ξ_½` only).
    pub(crate) three: bool,
    /// Built on the caller's frame reversed (light from below an interface): the PSD sees
    /// each section mirrored ([`LobePrep::new`]).
    pub(crate) mirrored: bool,
    /// `ln K^spec_α` and `ln K_α` for `α = x, y, ½` (only `½` when not `three`), `ln 2π` in `c`;
    /// `ln K_α` per PSD component (`scat[α][j]`, `j < components`: `K_α = Σⱼ K_αj`).
    pub(crate) spec: [LogGaussian<T>; 3],
    pub(crate) scat: [[LogGaussian<T>; MAX_COMPONENTS]; 3],
    /// The PSD's Gaussian components (1 for a `GaussianPsd`).
    pub(crate) components: usize,
    /// The channel mix's constants (`PreparedPacket::channel_mix`).
    pub(crate) ln_sx: T,
    pub(crate) ln_sy: T,
    pub(crate) ln_c: T,
    pub(crate) ln_mu_max: T,
    pub(crate) phase: (T, T),
    pub(crate) t: Matrix4<T>,
    /// `T S/S0` (the one-weight effective vector).
    pub(crate) t_stokes: Vector4<T>,
    /// `σ²` of the PSD (Debye–Waller).
    pub(crate) variance: T,
    /// `−2 ln λ + ln S0`, and `ln (2k cos θ_i)²` (the Rayleigh–Rice Jones scale) on top for the
    /// scattered part.
    pub(crate) ln_spec: T,
    pub(crate) ln_scat: T,
    /// `ln` of the smallest subnormal number: a part whose exponent lies below is 0.
    pub(crate) ln_dark: T,
    /// The Fresnel Mueller matrix (incident s/p frame to the specular s/p frame).
    pub(crate) fresnel: Matrix4<T>,
    /// The specular s/p frame: ŝ, p̂ and the specular direction.
    pub(crate) spec_frame: Frame<T>,
    /// `256 ε`: `r̂·r̂_spec` below its negative counts as a flipped frame change.
    pub(crate) flip_tol: T,
    /// The `Intensity` level: only `S0` of each lobe is written.
    pub(crate) intensity: bool,
    /// At a dielectric interface, the constants of the transmission side
    /// ([`LobePrep::at_interface`]); `None` in reflection.
    pub(crate) transmission: Option<TransmissionPrep<T>>,
}

/// The per-packet constants of the transmission side of a dielectric interface
/// (`FresnelInterface` specular transmission, Elson's Rayleigh–Rice transmission factors).
#[derive(Debug, Clone, Copy)]
pub(crate) struct TransmissionPrep<T: Real> {
    /// `η = √ε` of the Rayleigh–Rice permittivity and `sin θ_i`.
    pub(crate) consts: TransmissionConsts<T>,
    /// The geometry's relative index `η_t = n_t/n_i` (`η`, or `1/η` from below: of
    /// `h = k (ŝ + η_t r̂)`, `v = k (cos θ_i − η_t cos θ_o)`, `λ_t = λ/η_t` and the `√η_t` of the
    /// Rayleigh–Rice Jones scale).
    pub(crate) eta: T,
    /// `ln_spec + ln η²`, and `ln (2k cos θ_i √η)²` on top for the scattered part.
    pub(crate) ln_spec: T,
    pub(crate) ln_scat: T,
    /// The Fresnel transmission Mueller matrix (incident s/p frame to the s/p frame of Snell's
    /// direction, `√η diag(t_s, t_p)`), zero under total internal reflection.
    pub(crate) fresnel: Matrix4<T>,
    /// The s/p frame of Snell's direction (`Geometry::specular_sp` on the transmission side).
    pub(crate) spec_frame: Frame<T>,
    /// Total internal reflection: no specular transmission.
    pub(crate) tir: bool,
}

/// `ln K^spec` of the section `xi`: `ln 2π − ½ ln|Ξ|` and `Ξ`'s Cholesky factor.
#[inline]
fn spec_channel<T: Real>(xi: &crate::gaussian::Gaussian<T, 2>) -> LogGaussian<T> {
    let ln2pi = crate::interaction::coherence::ln_two_pi::<T>();
    LogGaussian::new(ln2pi - T::lit(0.5) * xi.log_det(), xi.cholesky_factor())
}

/// `ln K` of the PSD component `c` blurred by the section `xi_psd` (mirrored already where
/// `mirrored`, whose `ℓ₁₀` is then negated: [`LobePrep::new`]).
#[inline]
fn scat_channel<T: Real>(
    c: &GaussianPsd<T, 2>,
    xi_psd: &crate::gaussian::Gaussian<T, 2>,
    mirrored: bool,
) -> Option<LogGaussian<T>> {
    let ln2pi = crate::interaction::coherence::ln_two_pi::<T>();
    let l = crate::gaussian::cholesky_of_sum(c.spectral_shape(), xi_psd)?;
    let mut out = LogGaussian::new(ln2pi + c.log_normalized_blur(xi_psd, &Vector2::zeros()), &l);
    if mirrored {
        out.l10 = -out.l10;
    }
    Some(out)
}

/// `ln ∫p − ln 2π`: the incoherent limit's scattered weight over the specular one
/// ([`LobePrep::incoherent`]).
#[inline]
pub(crate) fn incoherent_shift<T: Real>(integral: T) -> T {
    integral.ln() - crate::interaction::coherence::ln_two_pi::<T>()
}

/// `ln_spec + ln (2k cos θ_i)²`: the scattered part's constant exponent in reflection.
#[inline]
fn scat_exponent<T: Real>(ln_spec: T, inc: &Incidence<T>) -> T {
    let jones_scale = T::lit(2.0) * inc.k * inc.cos_i;
    ln_spec + (jones_scale * jones_scale).ln()
}

/// The Fresnel reflection's Mueller matrix at `cos θ_i` for the index `eta`.
#[inline]
fn fresnel_mueller<T: Real>(inc: &Incidence<T>, eta: Complex<T>) -> Matrix4<T> {
    crate::mueller::Mueller::from_jones(&crate::fresnel::reflection(inc.cos_i, eta)).0
}

/// The specular s/p frame of the incidence.
#[inline]
fn specular_frame<T: Real>(inc: &Incidence<T>) -> Frame<T> {
    let r_spec = inc.n * (inc.cos_i + inc.cos_i) - inc.s;
    Frame::sp_unit(r_spec, inc.n)
}

/// The per-lane constants of a pair in lanes (`super::per_lane`), in [`lane_row`]'s order.
pub(crate) const LANE_FIELDS: usize = 53;

/// One lane's per-lane constants (those `super::per_lane::LaneConsts` reads) in order: ŝ,
/// the azimuth axes `u`, `v`, `cos θ_i`, `sin²θ_i`, `q_i`, `D₁/t`, `D₃/t²`,
/// `−(ε − 1)/t² · q_i/t` (complex: re, im), the `½` channel's `LogGaussian` constants `c`,
/// `ℓ₀₀`, `ℓ₁₀`, `1/ℓ₁₁` of the specular and of the scattered weight, the scattered part's
/// exponent, the Fresnel matrix by rows, and the specular frame's ŝ, p̂, r̂.
#[inline]
pub(crate) fn lane_row<T: Real>(
    inc: &Incidence<T>,
    (spec, scat): (&LogGaussian<T>, &LogGaussian<T>),
    ln_scat: T,
    fresnel: &Matrix4<T>,
    spec_frame: &Frame<T>,
) -> [T; LANE_FIELDS] {
    let i = inc;
    let (sp, sc, m) = (spec, scat, fresnel);
    let (fs, fp, fk) = (spec_frame.x(), spec_frame.y(), spec_frame.k());
    [
        i.s.x,
        i.s.y,
        i.s.z,
        i.u_az.x,
        i.u_az.y,
        i.u_az.z,
        i.v_az.x,
        i.v_az.y,
        i.v_az.z,
        i.cos_i,
        i.si2,
        i.qi.re,
        i.qi.im,
        i.d1s.re,
        i.d1s.im,
        i.d3s.re,
        i.d3s.im,
        i.neg_em1s_qis.re,
        i.neg_em1s_qis.im,
        sp.c,
        sp.l00,
        sp.l10,
        sp.inv_l11,
        sc.c,
        sc.l00,
        sc.l10,
        sc.inv_l11,
        ln_scat,
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(0, 3)],
        m[(1, 0)],
        m[(1, 1)],
        m[(1, 2)],
        m[(1, 3)],
        m[(2, 0)],
        m[(2, 1)],
        m[(2, 2)],
        m[(2, 3)],
        m[(3, 0)],
        m[(3, 1)],
        m[(3, 2)],
        m[(3, 3)],
        fs.x,
        fs.y,
        fs.z,
        fp.x,
        fp.y,
        fp.z,
        fk.x,
        fk.y,
        fk.z,
    ]
}

impl<T: Real> core::ops::Deref for LobePrep<T> {
    type Target = Incidence<T>;
    #[inline(always)]
    fn deref(&self) -> &Incidence<T> {
        &self.inc
    }
}

impl<T: Real> LobePrep<T> {
    /// The constants from the scalar kernel's prepared packet, for a PSD of Gaussian components
    /// `psd` (one for a `GaussianPsd`, those of a `GaussianMixturePsd`) and total variance
    /// `variance`; `None` where the lanes would not reproduce the scalar kernel (no component or
    /// more than [`MAX_COMPONENTS`], a section that is not positive definite, a Cholesky factor
    /// of a sum that fails, an index outside the plain `hypot` range, a non-finite constant).
    ///
    /// `surface` is the frame facing the source (`fresnel_eta` and `epsilon` the indices seen
    /// from it); `mirrored` when it is the caller's reversed (light from below an interface,
    /// t̂₂ negated): the PSD is given in the caller's frame, so each scattered channel is the
    /// PSD blurred with the mirrored section `D Ξ D` at `(h₁, −h₂)`, as the per-direction
    /// kernel has it (`psd_xi`, `Geometry::psd_h`) — the Cholesky factor of `Λ⁻¹ + D Ξ D` with
    /// `ℓ₁₀` negated, which gives the same `|L⁻¹ D h|²` at `h` exactly.
    #[cfg(test)]
    pub(crate) fn new<Pol, Coh>(
        prepared: &crate::interaction::PreparedPacket<T, Pol, Coh>,
        psd: &[GaussianPsd<T, 2>],
        variance: T,
        indices: (Complex<T>, Complex<T>),
        packet: &WavePacket<T>,
        surface: (&Frame<T>, bool),
        full: bool,
    ) -> Option<Self> {
        let to_source = -packet.direction();
        Self::from_direction(prepared, (psd, variance), indices, to_source, surface, full)
    }

    /// [`LobePrep::new`] for light arriving from `to_source` (`−k̂`, any length) at the
    /// prepared packet's wavenumber.
    pub(crate) fn from_direction<Pol, Coh>(
        prepared: &crate::interaction::PreparedPacket<T, Pol, Coh>,
        (psd, variance): (&[GaussianPsd<T, 2>], T),
        (fresnel_eta, epsilon): (Complex<T>, Complex<T>),
        to_source: Vector3<T>,
        (surface, mirrored): (&Frame<T>, bool),
        full: bool,
    ) -> Option<Self> {
        if psd.is_empty() || psd.len() > MAX_COMPONENTS {
            return None;
        }
        let inc = Incidence::from_direction(epsilon, to_source, prepared.k, surface).ok()?;
        let three = full && !prepared.single_shape;
        let channel = |xi: &crate::gaussian::Gaussian<T, 2>| -> Option<_> {
            let spec = spec_channel(xi);
            let mut scat = [spec; MAX_COMPONENTS];
            let xi_psd = if mirrored { xi.mirrored_y() } else { *xi };
            for (out, c) in scat.iter_mut().zip(psd) {
                *out = scat_channel(c, &xi_psd, mirrored)?;
            }
            Some((spec, scat))
        };
        let half = channel(prepared.sections[2].as_ref()?)?;
        let (x, y) = if three {
            (
                channel(prepared.sections[0].as_ref()?)?,
                channel(prepared.sections[1].as_ref()?)?,
            )
        } else {
            (half, half)
        };
        let ln_s0 = prepared.ln_s0;
        let ln_spec = prepared.two_ln_k_over_2pi + ln_s0;
        let ln_scat = scat_exponent(ln_spec, &inc);
        let out = Self {
            three,
            mirrored,
            spec: [x.0, y.0, half.0],
            scat: [x.1, y.1, half.1],
            components: psd.len(),
            ln_sx: prepared.ln_sx,
            ln_sy: prepared.ln_sy,
            ln_c: prepared.ln_c,
            ln_mu_max: prepared.ln_mu_max,
            phase: prepared.phase,
            t: prepared.t,
            t_stokes: prepared.t_stokes,
            variance,
            ln_spec,
            ln_scat,
            ln_dark: T::lit(crate::interaction::coherence::ln_smallest_subnormal::<T>()),
            fresnel: fresnel_mueller(&inc, fresnel_eta),
            spec_frame: specular_frame(&inc),
            flip_tol: T::lit(Frame::<T>::TOLERANCE_ULPS) * T::EPSILON,
            intensity: false,
            transmission: None,
            inc,
        };
        let finite = out.spec.iter().all(LogGaussian::is_finite)
            && out
                .scat
                .iter()
                .all(|ch| ch[..out.components].iter().all(LogGaussian::is_finite))
            && ln_spec.is_finite()
            && ln_scat.is_finite()
            && out.fresnel.iter().all(|v| v.is_finite());
        (out.inc.plain_q && finite && ln_s0.is_finite()).then_some(out)
    }

    /// This prepared packet's per-lane constants ([`lane_row`]) arriving from `to_source` in
    /// reflection, without the rest of the `LobePrep`: the same operations as
    /// [`LobePrep::from_direction`] (one shape, one PSD component `psd`, not mirrored; then
    /// [`LobePrep::incoherent`] for the PSD's integral `incoherent`) for those fields, so the
    /// same values; `None` where they return `None`.
    pub(crate) fn lane_row_of<Pol, Coh>(
        prepared: &crate::interaction::PreparedPacket<T, Pol, Coh>,
        psd: &GaussianPsd<T, 2>,
        (fresnel_eta, epsilon): (Complex<T>, Complex<T>),
        to_source: Vector3<T>,
        surface: &Frame<T>,
        incoherent: Option<T>,
    ) -> Option<[T; LANE_FIELDS]> {
        let inc = Incidence::from_direction(epsilon, to_source, prepared.k, surface).ok()?;
        let (spec, scat) = Self::channels_of(prepared, psd, incoherent)?;
        let ln_spec = prepared.two_ln_k_over_2pi + prepared.ln_s0;
        let ln_scat = scat_exponent(ln_spec, &inc);
        let fresnel = fresnel_mueller(&inc, fresnel_eta);
        let finite = ln_spec.is_finite()
            && ln_scat.is_finite()
            && fresnel.iter().all(|v| v.is_finite())
            && inc.plain_q
            && prepared.ln_s0.is_finite();
        finite.then(|| {
            lane_row(
                &inc,
                (&spec, &scat),
                ln_scat,
                &fresnel,
                &specular_frame(&inc),
            )
        })
    }

    /// The per-lane constants of [`LobePrep::lane_row_of`] that depend on the prepared packet
    /// alone, not on the direction: the `½` channel's specular and scattered `LogGaussian`
    /// (the scattered one at the incoherent level for the PSD's integral `incoherent`); `None`
    /// where one is not finite.
    pub(crate) fn channels_of<Pol, Coh>(
        prepared: &crate::interaction::PreparedPacket<T, Pol, Coh>,
        psd: &GaussianPsd<T, 2>,
        incoherent: Option<T>,
    ) -> Option<HalfChannels<T>> {
        let xi = prepared.sections[2].as_ref()?;
        let (spec, scat) = (spec_channel(xi), scat_channel(psd, xi, false)?);
        let scat = match incoherent {
            // LobePrep::incoherent's scattered weight.
            Some(integral) => LogGaussian {
                c: spec.c + incoherent_shift(integral),
                ..spec
            },
            None => scat,
        };
        let shift_finite = incoherent.is_none_or(|i| incoherent_shift(i).is_finite());
        (spec.is_finite() && scat.is_finite() && shift_finite).then_some((spec, scat))
    }

    /// The constants at a dielectric interface of relative index `eta` (the geometry's, as
    /// `interface = Some(η)` of `Kernel::evaluate_batch`) in the caller's frame `surface`, with
    /// the specular pBSDF `specular`, from constants built on the frame facing the source: the
    /// transmission side's from a probe geometry on that side (`FresnelInterface::jones`,
    /// `Geometry::specular_sp`, `η_t` and `ln η_t²` there, as the per-direction kernel has them
    /// for every transmitted exit). `None` unless the Rayleigh–Rice permittivity is real
    /// ([`TransmissionConsts::new`]), or where the probe geometry is rejected (`η` outside
    /// [`Geometry::at_interface`]'s range) or a constant is not finite.
    pub(crate) fn at_interface(
        mut self,
        eta: T,
        surface: &Frame<T>,
        specular: &crate::interaction::pbsdf::FresnelInterface<T>,
    ) -> Option<Self> {
        let consts = TransmissionConsts::new(&self.inc)?;
        let inc = &self.inc;
        let probe = Geometry::at_interface(inc.k, surface, eta, inc.to_source_raw, -inc.n).ok()?;
        let jones = specular.jones(&probe);
        let tir = jones.is_none();
        let eta_t = probe.relative_index();
        let ln_spec = self.ln_spec + probe.ln_eta_sq;
        let jones_scale = T::lit(2.0) * inc.k * inc.cos_i * eta_t.sqrt();
        let ln_scat = ln_spec + (jones_scale * jones_scale).ln();
        let t = TransmissionPrep {
            consts,
            eta: eta_t,
            ln_spec,
            ln_scat,
            fresnel: jones.map_or_else(Matrix4::zeros, |j| {
                crate::mueller::Mueller::from_jones(&j).0
            }),
            spec_frame: probe.specular_sp(),
            tir,
        };
        let finite = ln_spec.is_finite()
            && ln_scat.is_finite()
            && consts.index.re.is_finite()
            && t.fresnel.iter().all(|v| v.is_finite());
        self.inc.interface = Some((eta, *surface));
        self.transmission = Some(t);
        finite.then_some(self)
    }

    /// The constants for the [`crate::interaction::Intensity`] level (from those of the
    /// `OneShape` level, `full = false`): the effective vector becomes `(1, 0, 0, 0)`, so that
    /// `S0` of each lobe is `M₀₀` times the one-weight scale, as
    /// `Intensity::evaluate` (`onto_cone` keeps `S0`), and only `S0` is written.
    pub(crate) fn intensity_only(mut self) -> Self {
        self.t_stokes = Vector4::new(T::one(), T::zero(), T::zero(), T::zero());
        self.intensity = true;
        self
    }

    /// The constants for the incoherent limit ([`crate::interaction::Incoherent`]) instead of
    /// the partially coherent one, for a PSD of integral `integral` (`∫p`, every component's
    /// together): one scattered weight per channel,
    /// `ln K_α = ln K^spec_α + ln ∫p − ln 2π` (`|Σ|^{1/2} g^Ξ(h_t) ∫p`), the covariance of the
    /// smooth-surface lobe; `None` where `ln ∫p` is not finite.
    pub(crate) fn incoherent(mut self, integral: T) -> Option<Self> {
        let shift = incoherent_shift(integral);
        for (scat, spec) in self.scat.iter_mut().zip(&self.spec) {
            scat[0] = LogGaussian {
                c: spec.c + shift,
                ..*spec
            };
        }
        self.components = 1;
        shift.is_finite().then_some(self)
    }
}

/// The per-packet constants of the transmission factors (`stages::rayleigh_rice::
/// transmission_factors`) besides the [`Incidence`]: `η = √ε`
/// (principal branch) scaled by `1/t` ([`Incidence::scale`]) and `sin θ_i`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TransmissionConsts<F: Real> {
    pub(crate) index: Complex<F>,
    pub(crate) index_s: Complex<F>,
    pub(crate) sin_i: F,
}

impl<F: Real> TransmissionConsts<F> {
    /// The constants of the incidence `p` (built with the permittivity seen from the source),
    /// or `None` unless `ε` is real (a dielectric interface): the lanes take `a_o`'s square
    /// root on the real axis only.
    pub(crate) fn new(p: &Incidence<F>) -> Option<Self> {
        (p.e.im == F::zero()).then(|| {
            let index = principal_sqrt(p.e);
            Self {
                index,
                index_s: index * p.scale.inv,
                sin_i: p.si2.sqrt(),
            }
        })
    }
}

/// The fewest exits for which a call runs the series in lanes: below, one exit at a time is
/// cheaper than building [`SeriesPrep`] (`kernel_batch_series`, 2026-12-07, AVX2, `vσ ≈ 1`:
/// about 2 µs per exit one at a time against 4–6 µs for a call of 1–4 exits in lanes).
pub(crate) const SERIES_MIN_EXITS: usize = 3;

/// The most orders the series lanes sum ([`SeriesPrep`]); a lane whose sum has not met its
/// bound by then is redone by the per-direction kernel.
pub(crate) const SERIES_ORDERS: usize = 160;

/// One channel's constants of the series lanes: the section's quadratic form and, per order
/// `n = 1 ..= SERIES_ORDERS`, the closed form's constants.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SeriesChannel<T: Real> {
    /// `(a, b, c)` with `h_tᵀ adj(Ξ) h_t = (a h₀ + b h₁)² + (c h₀)²` at the lanes' `h_t` (the
    /// PSD's `h_t` mirrored where the section is, [`SeriesPrep::new`]). The orders past
    /// [`SeriesPrep::orders`] are not set.
    pub(crate) quad: [T; 3],
    /// `ln 2πσ² − ½ ln|nA + Ξ| − ln n!` at index `n − 1`.
    pub(crate) k: [T; SERIES_ORDERS],
    /// `½ / |nA + Ξ|` at index `n − 1`.
    pub(crate) half_inv_det: [T; SERIES_ORDERS],
}

/// The per-packet constants of the Kirchhoff series in lanes
/// (`stages::series`): the closed form of every order's weight of a Gaussian PSD blurred by
/// each channel's section (`roughness::GaussianTerms`, with `A = Λ⁻¹`):
/// ```text
/// ln t_n = −g + (n − 1) ln g − ln n! + ln 2πσ² − ½ ln|nA + Ξ| − ½ (n h_tᵀadj(A)h_t + h_tᵀadj(Ξ)h_t)/|nA + Ξ|
/// ```
/// `g = (vσ)²` per lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SeriesPrep<T: Real> {
    /// `(a, b, c)` of `h_tᵀ adj(A) h_t`, as [`SeriesChannel::quad`].
    pub(crate) psd_quad: [T; 3],
    /// The channels `x, y, ½` (only `½` is set without three channels).
    pub(crate) channels: [SeriesChannel<T>; 3],
    /// `ln(tolerance/2)`: a lane's sum stops where a falling term (ratio at most ½ to the one
    /// before) is below `tolerance/2` of the largest.
    pub(crate) ln_half_tol: T,
    /// Lanes with `g ≥ g_max` are redone (the geometric switch, or the lanes' range).
    pub(crate) g_max: T,
    /// The orders built (at most [`SERIES_ORDERS`]): `ĝ + 12√ĝ + 24` for the largest `g` a lane
    /// can have, `ĝ = min(g_max, (v_max σ)²)`; a lane whose sum needs more is redone.
    pub(crate) orders: usize,
}

/// The largest `g` the series lanes sum in `f64` and in `f32`: the terms' parts `g`,
/// `(n − 1) ln g` and `ln n!` reach `~g ln g` before they cancel, and each is rounded to the
/// lanes' type (module docs of `stages::series`).
const SERIES_LANE_G: (f64, f64) = (64.0, 16.0);

impl<T: Real> SeriesPrep<T> {
    /// The constants for the sections `sections` (`x, y, ½`; only `½` read unless `three`) of
    /// the prepared packet, the Gaussian PSD `psd` (variance `σ²`, spectral Cholesky factor
    /// `L_A`), mirrored as [`LobePrep::new`] (`mirrored`: light from below an interface, the
    /// PSD's `h_t = (h₀, −h₁)` of the lanes' and each section `D Ξ D`, as `psd_xi` and
    /// `Geometry::psd_h` have them), `v_max` a bound on the lanes' phase factors `|v|`, the
    /// series' `tolerance` and its switch to the geometric limit `geometric_from`. `None` where a constant is not finite or `|nA + Ξ|` not positive.
    pub(crate) fn new(
        sections: [Option<&crate::gaussian::Gaussian<T, 2>>; 3],
        three: bool,
        psd: &GaussianPsd<T, 2>,
        (mirrored, v_max): (bool, T),
        (tolerance, geometric_from): (f64, f64),
    ) -> Option<Self> {
        use crate::interaction::roughness::{GaussianTerms, SERIES_MAX_G, ln_factorial};
        use crate::psd::CorrelationPowers;
        let (sigma2, la) = psd.gaussian_spectrum()?;
        let lane_g = if T::EPSILON.to_f64() < 1e-10 {
            SERIES_LANE_G.0
        } else {
            SERIES_LANE_G.1
        };
        let g_max = geometric_from.min(SERIES_MAX_G).min(lane_g);
        let g_hi = (v_max * v_max * sigma2).to_f64().min(g_max);
        if g_hi.is_nan() || g_hi < 0.0 {
            return None;
        }
        let orders = ((g_hi + 12.0 * g_hi.sqrt() + 24.0).ceil() as usize).min(SERIES_ORDERS);
        let ln_fact: [f64; SERIES_ORDERS] = core::array::from_fn(|i| {
            if i < orders {
                ln_factorial(i as u64 + 1)
            } else {
                0.0
            }
        });
        let sign = if mirrored { T::one() } else { -T::one() };
        let quad = |l: &nalgebra::Matrix2<T>| [l[(1, 0)], sign * l[(0, 0)], l[(1, 1)]];
        let zero = Vector2::zeros();
        let channel = |xi: &crate::gaussian::Gaussian<T, 2>| -> Option<SeriesChannel<T>> {
            let xi = if mirrored { xi.mirrored_y() } else { *xi };
            let gt = GaussianTerms::new(sigma2, &la, Some(&xi), &zero)?;
            let mut out = SeriesChannel {
                quad: quad(xi.cholesky_factor()),
                k: [T::zero(); SERIES_ORDERS],
                half_inv_det: [T::zero(); SERIES_ORDERS],
            };
            let orders_of = out.k.iter_mut().zip(&mut out.half_inv_det).zip(&ln_fact);
            for (i, ((k, e), lf)) in orders_of.take(orders).enumerate() {
                let n = (i + 1) as f64;
                let det = (n * gt.d2 + gt.d1) * n + gt.d0;
                if det.is_nan() || det <= 0.0 || det.is_infinite() {
                    return None;
                }
                *k = T::lit(gt.ln_front - 0.5 * det.ln() - lf);
                *e = T::lit(0.5 / det);
            }
            let finite = out.quad.iter().chain(&out.k).chain(&out.half_inv_det);
            finite.into_iter().all(|v| v.is_finite()).then_some(out)
        };
        let half = channel(sections[2]?)?;
        let (x, y) = if three {
            (channel(sections[0]?)?, channel(sections[1]?)?)
        } else {
            (half, half)
        };
        let out = Self {
            psd_quad: quad(&la),
            channels: [x, y, half],
            ln_half_tol: T::lit((0.5 * tolerance).ln()),
            g_max: T::lit(g_max),
            orders,
        };
        let finite = out.psd_quad.iter().all(|v| v.is_finite()) && out.ln_half_tol.is_finite();
        finite.then_some(out)
    }
}
