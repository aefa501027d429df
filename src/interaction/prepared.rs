//! The per-packet part of the kernel: everything that depends on the packet and the surface
//! but not on the exit direction.

use core::marker::PhantomData;

use nalgebra::{Matrix4, Vector4};

use super::coherence::{ln_smallest_subnormal, ln_two_pi, neg_infinity};
use super::section::surface_inverse_coherence;
use crate::frame::{Frame, frame_change_mueller};
use crate::gaussian::Gaussian;
use crate::numerics::{det2, det2_of_mean, pow2_scale};
use crate::packet::{Channel, WavePacket};
use crate::real::Real;

/// What the per-packet work computes, chosen by the polarization level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Plan {
    /// Which sections: `Ξ_x`, `Ξ_y`, `Ξ_½`.
    pub(crate) sections: [bool; 3],
    /// The rotation `T` to the incident s/p frame (not needed for intensity only).
    pub(crate) rotation: bool,
    /// The channel logarithms of the Full level's channel mix.
    pub(crate) channel_logs: bool,
    /// The packet has one shape (`Θ_x = Θ_y`).
    pub(crate) single_shape: bool,
}

impl Plan {
    /// The plan of a one-weight level (`Intensity`, `OneShape`, and `Full` on single-shape
    /// packets): the section `Ξ_½` when the coherence model uses shapes, the rotation `T` if
    /// asked, no channel logarithms.
    #[inline]
    pub(crate) fn one_weight<T: Real>(
        packet: &WavePacket<T>,
        uses_shape: bool,
        rotation: bool,
    ) -> Self {
        Self {
            sections: [false, false, uses_shape],
            rotation,
            channel_logs: false,
            single_shape: packet.has_single_shape(),
        }
    }
}

/// The per-packet part of a [`super::Kernel`] at model level (`Pol`, `Coh`), from
/// [`super::Kernel::prepare`].
///
/// Holds the packet's Stokes vector normalised by `S0` with the logarithms of its channel
/// intensities (for the log-space channel mix of [`super::Full`]), the rotation `T` (S2.4) from the
/// packet frame to the incident s/p frame, and the surface sections `Ξ_α` of the channels the
/// level uses (none for [`super::PlaneWave`]; `Ξ_½` only below [`super::Full`] and for
/// single-shape packets), each with its Cholesky
/// factor. No heap allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedPacket<T: Real, Pol, Coh> {
    /// `S0` and `ln S0` (−∞ for a dark packet).
    pub(crate) s0: T,
    pub(crate) ln_s0: T,
    /// `1/λ² = (k/2π)²`.
    pub(crate) inv_lambda_sq: T,
    /// `ln(smallest subnormal) − ln S0`: a part whose `ln_e` lies below is 0.
    pub(crate) dark_below: T,
    /// `2 ln(k/2π) = −2 ln λ`.
    pub(crate) two_ln_k_over_2pi: T,
    /// `ln(S_x/S0)`, `ln(S_y/S0)`, `ln(|S2 + iS3|/(2 S0))` (−∞ where 0).
    pub(crate) ln_sx: T,
    pub(crate) ln_sy: T,
    pub(crate) ln_c: T,
    /// `(S2, S3)/|S2 + iS3|`, the phase of `μ` (0 where `S2 = S3 = 0`).
    pub(crate) phase: (T, T),
    pub(crate) t: Matrix4<T>,
    /// `T S/S0`.
    pub(crate) t_stokes: Vector4<T>,
    /// `Ξ_x`, `Ξ_y`, `Ξ_½` (`None` where unused or not positive definite).
    pub(crate) sections: [Option<Gaussian<T, 2>>; 3],
    /// `Θ_x = Θ_y`: the `Full` level then takes the one-weight path (the three weights agree).
    pub(crate) single_shape: bool,
    /// The packet's wavenumber `k` (in the medium of incidence).
    pub(crate) k: T,
    /// `ln |μ|_max = ¼ ln(|Θ_x||Θ_y|) − ½ ln|Θ_½|` (≤ 0, the Bochner bound of the shapes), for the
    /// Full level's BSDF form only (0 otherwise).
    pub(crate) ln_mu_max: T,
    _levels: PhantomData<(Pol, Coh)>,
}

impl<T: Real, Pol, Coh> PreparedPacket<T, Pol, Coh> {
    /// The per-packet work of `plan` (chosen by the polarization level, see
    /// `polarization/`): the sections it asks for, the rotation `T` unless intensity only,
    /// the channel logarithms for the Full level's channel mix.
    ///
    /// `inline(always)`: at each level's call site most of `plan` is a constant, and its
    /// branches fold away only when this body is inlined there. Left to the compiler it stayed
    /// out of line (with a plain `#[inline]` too, once `evaluate` also calls it), and
    /// `Kernel::prepare` ran 3–25 % more instructions.
    #[inline(always)]
    pub(crate) fn new(
        packet: &WavePacket<T>,
        surface: &Frame<T>,
        incident_sp: &Frame<T>,
        plan: Plan,
    ) -> Self {
        let section = |wanted: bool, channel| {
            if wanted {
                surface_inverse_coherence(packet, channel, surface)
            } else {
                None
            }
        };
        let sections = [
            section(plan.sections[0], Channel::X),
            section(plan.sections[1], Channel::Y),
            section(plan.sections[2], Channel::Half),
        ];
        let stokes = packet.stokes().0;
        let s0 = stokes[0];
        let hat = if s0 > T::zero() {
            stokes / s0
        } else {
            Vector4::zeros()
        };
        let t = if plan.rotation {
            frame_change_mueller(packet.frame(), incident_sp).0
        } else {
            Matrix4::identity()
        };
        // The channel intensities in log form, for the Full level's channel mix only.
        let (ln_sx, ln_sy, ln_c, phase) = if plan.channel_logs {
            let half = T::lit(0.5);
            let c = hat[2].hypot(hat[3]);
            let phase = if c > T::zero() {
                (hat[2] / c, hat[3] / c)
            } else {
                (T::zero(), T::zero())
            };
            (
                ((hat[0] + hat[1]) * half).ln(),
                ((hat[0] - hat[1]) * half).ln(),
                (c * half).ln(),
                phase,
            )
        } else {
            (T::zero(), T::zero(), T::zero(), (T::zero(), T::zero()))
        };
        let ln_mu_max = if plan.channel_logs {
            ln_bochner_bound(packet)
        } else {
            T::zero()
        };
        let k = packet.wavenumber();
        let ln_s0 = s0.ln();
        let (inv_lambda_sq, two_ln_k_over_2pi) = wavenumber_terms(k);
        Self {
            s0,
            ln_s0,
            inv_lambda_sq,
            dark_below: T::lit(ln_smallest_subnormal::<T>()) - ln_s0,
            two_ln_k_over_2pi,
            ln_sx,
            ln_sy,
            ln_c,
            phase,
            t,
            t_stokes: t * hat,
            sections,
            single_shape: plan.single_shape,
            k,
            ln_mu_max,
            _levels: PhantomData,
        }
    }

    /// The per-packet work of unpolarized light of unit `S0` and wavenumber `k` whose frame is
    /// the incident s/p frame and whose coherence section on the surface is isotropic,
    /// `Ξ = I/w²` (`inverse_width` = `1/w`): what [`Self::new`] computes for the packet
    /// `SurfaceCoherence::packet` builds (shape `diag(w², w² cos²θ_i)` in that frame, unbounded
    /// longitudinal coherence), without the packet. Such a packet has one shape, so every
    /// level's plan is the one-weight plan (the section `Ξ_½` alone, when the coherence model
    /// uses shapes; no channel logarithms); its rotation `T` to the incident s/p frame is the
    /// identity and `T S/S0 = (1, 0, 0, 0)`. The section is `None` where `1/w` is not a
    /// positive finite number, as [`Self::new`] leaves it for a section it cannot represent.
    #[inline]
    pub(crate) fn unpolarized_isotropic(k: T, inverse_width: T, uses_shape: bool) -> Self {
        let section = if uses_shape {
            Gaussian::from_cholesky(nalgebra::Matrix2::new(
                inverse_width,
                T::zero(),
                T::zero(),
                inverse_width,
            ))
        } else {
            None
        };
        let (inv_lambda_sq, two_ln_k_over_2pi) = wavenumber_terms(k);
        Self {
            s0: T::one(),
            ln_s0: T::zero(),
            inv_lambda_sq,
            dark_below: T::lit(ln_smallest_subnormal::<T>()),
            two_ln_k_over_2pi,
            ln_sx: T::zero(),
            ln_sy: T::zero(),
            ln_c: T::zero(),
            phase: (T::zero(), T::zero()),
            t: Matrix4::identity(),
            t_stokes: Vector4::new(T::one(), T::zero(), T::zero(), T::zero()),
            sections: [None, None, section],
            single_shape: true,
            k,
            ln_mu_max: T::zero(),
            _levels: PhantomData,
        }
    }

    /// The `Full` level's effective Stokes vector `T v̂` (normalised) and the logarithm of
    /// its scale, from the channel weights `ln K_x`, `ln K_y`, `ln K_½`:
    /// ```text
    /// a_x = ln(K_x S_x/S0),  a_y = ln(K_y S_y/S0)
    /// a_½ = min(min(ln K_½, ½(ln K_x + ln K_y) − ln|μ|_max) + ln(|S2+iS3|/(2S0)), ½(a_x + a_y))
    /// m = max(a_x, a_y),     r_α = e^{a_α − m}
    /// v̂ = (r_x + r_y, r_x − r_y, 2 r_½ cos arg μ, 2 r_½ sin arg μ),     v = S0 e^{m} v̂
    /// ```
    /// The `min`s are the Cauchy–Schwarz inequality of the weights, `K_½² |μ|² ≤ K_x K_y`, which
    /// the exact S2.20 satisfies for every realizable packet, and so for the largest `|μ|` the
    /// shapes admit, `K_½ |μ|_max ≤ √(K_x K_y)` (module docs of
    /// [`crate::packet`]: at every spatial frequency the spectral matrix is positive
    /// semidefinite, and K is its average against `p ≥ 0`); it makes `v̂` a valid Stokes vector
    /// by construction, `(r_x − r_y)² + 4 r_½² ≤ (r_x + r_y)²`. Where the computed weights
    /// break the inequality — rounding of nearly proportional shapes in `f32`, or per-channel
    /// quadrature errors of [`crate::psd::GaussHermite`] — it lowers `K_½` by no more than their
    /// own error: the exact weights satisfy it. The `|μ|_max` form is the one the BSDF form
    /// ([`Self::channel_matrix`]) must use (a matrix does not know `|μ|`), so both forms agree
    /// where a quadrature blur breaks the inequality (`tests/bsdf/eval.rs`); the second `min`
    /// keeps validity for a packet at the realizability slack.
    #[inline]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN maximum must take the dark branch too"
    )]
    pub(crate) fn channel_mix(&self, lx: T, ly: T, lh: T) -> (Vector4<T>, T) {
        let ax = lx + self.ln_sx;
        let ay = ly + self.ln_sy;
        let half = T::lit(0.5);
        let ah = (lh.min((lx + ly) * half - self.ln_mu_max) + self.ln_c).min((ax + ay) * half);
        let m = ax.max(ay);
        if !(m > neg_infinity()) {
            return (Vector4::zeros(), neg_infinity());
        }
        let rel = |a: T| if a == m { T::one() } else { (a - m).exp() };
        let (rx, ry, rh) = (rel(ax), rel(ay), rel(ah));
        let two_rh = rh * T::lit(2.0);
        let v = Vector4::new(
            rx + ry,
            rx - ry,
            two_rh * self.phase.0,
            two_rh * self.phase.1,
        );
        (self.t * v, m)
    }

    /// The Full level's BSDF form of the channel mix, from the channel weights `ln K_x`,
    /// `ln K_y`, `ln K_½`: `T D̂` and the logarithm `m` of its scale, with
    /// ```text
    /// a_½ = min(ln K_½, ½(ln K_x + ln K_y) − ln|μ|_max),   m = max(ln K_x, ln K_y),  r_α = e^{a_α − m}
    /// D̂ = [[r_x+r_y, r_x−r_y],[r_x−r_y, r_x+r_y]]/2 ⊕ r_½ I₂
    /// ```
    /// so that `D̂ S/S0 · e^m` is the [`Self::channel_mix`] vector for every Stokes vector the
    /// shapes admit; the cap is the same Cauchy–Schwarz bound, for the largest admitted `|μ|`.
    #[inline]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN maximum must take the dark branch too"
    )]
    pub(crate) fn channel_matrix(&self, lx: T, ly: T, lh: T) -> (Matrix4<T>, T) {
        let half = T::lit(0.5);
        let ah = lh.min((lx + ly) * half - self.ln_mu_max);
        let m = lx.max(ly);
        if !(m > neg_infinity()) {
            return (Matrix4::zeros(), neg_infinity());
        }
        let rel = |a: T| if a == m { T::one() } else { (a - m).exp() };
        let (rx, ry, rh) = (rel(lx), rel(ly), rel(ah));
        let (a, b) = ((rx + ry) * half, (rx - ry) * half);
        let z = T::zero();
        #[rustfmt::skip]
        let d = Matrix4::new(
            a, b, z, z,
            b, a, z, z,
            z, z, rh, z,
            z, z, z, rh,
        );
        (self.t * d, m)
    }

    /// `S0 α K η²/λ²` (`η` the relative index of the exit medium, 1 in reflection) when the
    /// weight `K` lies in [1e-30, 1e30] (so it has not lost digits to underflow) and the product
    /// is a normal number: the linear form of the scale of a one-weight part. `None` otherwise
    /// (the caller then takes the log form).
    #[inline]
    pub(crate) fn linear_scale(&self, weight: T, attenuation: T, eta: T) -> Option<T> {
        if !crate::numerics::in_normal_range(weight) {
            return None;
        }
        // Every partial product normal too: a subnormal one would keep only a few digits.
        let normal = |x: T| x >= T::MIN_POSITIVE && x <= T::MAX;
        let p = weight * attenuation * (self.inv_lambda_sq * (eta * eta));
        let e = p * self.s0;
        (normal(p) && normal(e)).then_some(e)
    }

    /// `true` when `S0 e^{ln_e}` is below the smallest subnormal number, so that the part is 0
    /// (the pBSDF need not be evaluated).
    #[inline]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN exponent must count as dark too"
    )]
    pub(crate) fn is_dark(&self, ln_e: T) -> bool {
        !(ln_e >= self.dark_below)
    }

    /// `u · S0 e^{ln_e}`, the scalar applied once at the end.
    ///
    /// When `S0 e^{ln_e}` is not a normal number, the magnitude of `u` is folded into the
    /// exponent first: `(u/u₀) · exp(ln_e + ln S0 + ln u₀)`. Every entry then rounds once, so a
    /// result that underflows into the subnormal range keeps its degree of polarization
    /// (`|u_pol|/u₀`), and one whose factors are below the smallest number of the type (a far
    /// tail of a bright packet) is not lost.
    #[inline]
    pub(crate) fn scaled(&self, u: Vector4<T>, ln_e: T) -> Vector4<T> {
        // exp(ln_e) · S0 would round exp(ln_e) first, with a subnormal's few digits when the
        // weight is tiny and S0 bright: one exponential of the sum instead.
        let e = (ln_e + self.ln_s0).exp();
        subnormal_onto_cone(if e >= T::MIN_POSITIVE && e <= T::MAX {
            u * e
        } else if u[0] <= T::zero() {
            // No magnitude to fold; a 0 entry stays 0 rather than 0 · ∞ = NaN.
            u.map(|x| if x == T::zero() { x } else { x * e })
        } else {
            let e = (ln_e + self.ln_s0 + u[0].ln()).exp();
            if e <= T::MAX {
                // An entry that is exactly 0 stays 0 rather than becoming 0 · ∞ = NaN.
                (u / u[0]).map(|x| if x == T::zero() { x } else { x * e })
            } else {
                // S0 itself overflows (±∞: brighter than the type), but a polarized entry
                // may not: each from its own logarithm, so an entry ≤ MAX stays finite.
                u.map(|x| beyond_scale(x, ln_e + self.ln_s0))
            }
        })
    }
}

/// `1/λ² = (k/2π)²` and `2 ln(k/2π)` of the wavenumber `k`.
#[inline]
fn wavenumber_terms<T: Real>(k: T) -> (T, T) {
    let k_over_2pi = k / T::two_pi();
    (
        k_over_2pi * k_over_2pi,
        T::lit(2.0) * (k.ln() - ln_two_pi::<T>()),
    )
}

/// `ln |μ|_max`, the logarithm of the largest degree of correlation the packet's shapes admit:
/// `¼ (ln|Θ_x| + ln|Θ_y|) − ½ ln|Θ_½|`, capped at 0 (Bochner, [`crate::packet`]). The
/// determinants are taken after a common power-of-two scaling (the bound is scale-invariant).
fn ln_bochner_bound<T: Real>(packet: &WavePacket<T>) -> T {
    let (x, y) = (packet.shape(Channel::X), packet.shape(Channel::Y));
    let s = pow2_scale(x.amax().max(y.amax()));
    let (nx, ny) = (x / s, y / s);
    let (dx, dy, dh) = (det2(&nx), det2(&ny), det2_of_mean(&nx, &ny));
    let b = T::lit(0.25) * (dx.ln() + dy.ln()) - T::lit(0.5) * dh.ln();
    if b.is_finite() {
        b.min(T::zero())
    } else {
        T::zero()
    }
}

impl<T: Real, Pol, Coh> PreparedPacket<T, Pol, Coh> {
    /// The packet's wavenumber `k`.
    #[inline]
    #[must_use]
    pub fn wavenumber(&self) -> T {
        self.k
    }

    /// The section `Ξ_½` of the packet's coherence by the surface (a covariance in `h_t`,
    /// rad²/length², [`crate::interaction::coherence::surface_inverse_coherence`]), when this level
    /// computed it (every level but the plane wave) and it is positive definite.
    #[inline]
    #[must_use]
    pub fn section(&self) -> Option<&Gaussian<T, 2>> {
        self.sections[2].as_ref()
    }

    /// The sections `Ξ_x`, `Ξ_y` where the level computed them (the Full level on a packet
    /// with two shapes), with the channel intensities `S_x/S0`, `S_y/S0`.
    #[inline]
    #[must_use]
    pub(crate) fn channel_sections(&self) -> Option<[(&Gaussian<T, 2>, T); 2]> {
        match (&self.sections[0], &self.sections[1]) {
            (Some(x), Some(y)) if !self.single_shape => {
                Some([(x, self.ln_sx.exp()), (y, self.ln_sy.exp())])
            }
            _ => None,
        }
    }

    /// The BSDF form's `S0`-free scale `α K η²/λ²` of a one-weight part when the weight `K` lies
    /// in [1e-30, 1e30] and the product is a normal number (as [`Self::linear_scale`], per unit
    /// `S0`).
    #[inline]
    pub(crate) fn unit_linear_scale(&self, weight: T, attenuation: T, eta: T) -> Option<T> {
        if !crate::numerics::in_normal_range(weight) {
            return None;
        }
        let p = weight * attenuation * (self.inv_lambda_sq * (eta * eta));
        (p >= T::MIN_POSITIVE && p <= T::MAX).then_some(p)
    }
}

/// A Stokes vector whose `S0` is subnormal, back inside the cone of valid vectors.
///
/// Each entry rounds to the subnormal grid on its own (steps of the smallest subnormal number
/// `δ = MIN_POSITIVE · ε`), which can leave `S1² + S2² + S3² > S0²` by up to half a step per
/// entry (f32, measured by `tests/interaction/batch/lobes.rs`: `(9, 9, 1, 0) δ`). The entries in
/// steps are whole numbers (exact), so the test is done on them, and the polarized entries are
/// shrunk toward 0 by one step at a time until the vector is valid (after four steps, to 0). The
/// change is below `4 δ` per entry, within the `MIN_POSITIVE` of every documented bound. Unchanged
/// when `S0` is normal, zero or negative.
#[inline]
pub(crate) fn subnormal_onto_cone<T: Real>(v: Vector4<T>) -> Vector4<T> {
    if !(v[0] > T::zero() && v[0] < T::MIN_POSITIVE) {
        return v;
    }
    let step = T::MIN_POSITIVE * T::EPSILON;
    let mut n = v / step;
    for _ in 0..4 {
        if n[1] * n[1] + n[2] * n[2] + n[3] * n[3] <= n[0] * n[0] {
            return n * step;
        }
        for k in 1..4 {
            n[k] = if n[k] >= T::one() {
                n[k] - T::one()
            } else if n[k] <= -T::one() {
                n[k] + T::one()
            } else {
                T::zero()
            };
        }
    }
    if n[1] * n[1] + n[2] * n[2] + n[3] * n[3] <= n[0] * n[0] {
        n * step
    } else {
        Vector4::new(v[0], T::zero(), T::zero(), T::zero())
    }
}

/// 0 when every entry of `m` is below the smallest normal number (a matrix whose entries are
/// all subnormal has lost the digits that keep it valid, and 0 is a valid Mueller matrix);
/// `m` otherwise.
#[inline]
pub(crate) fn flush_subnormal<T: Real, const R: usize, const C: usize>(
    m: nalgebra::SMatrix<T, R, C>,
) -> nalgebra::SMatrix<T, R, C> {
    if crate::numerics::amax(&m) >= T::MIN_POSITIVE {
        m
    } else {
        nalgebra::SMatrix::zeros()
    }
}

/// `x · e^{ln_e}` for a scale `e^{ln_e}` beyond the largest number of `T`, from the entry's
/// own logarithm, `sign(x) e^{ln_e + ln|x|}`: finite where the product is representable, `±∞`
/// where it is not, and 0 (not `0 · ∞ = NaN`) for `x = 0`.
#[inline]
pub(crate) fn beyond_scale<T: Real>(x: T, ln_e: T) -> T {
    if x == T::zero() {
        x
    } else {
        (ln_e + x.abs().ln()).exp().copysign(x)
    }
}

/// The rule for small entries of every throughput of the BSDF form (and of the renderer
/// layer's weights):
/// - 0 when every entry is below the smallest normal number (as [`flush_subnormal`]: such a
///   matrix has lost the digits that keep it valid, and 0 is a valid Mueller matrix);
/// - when the largest entry is at least `MIN_POSITIVE/ε` (f32: 9.9e-32, f64: 1.0e-292), every
///   entry below `MIN_POSITIVE` set to 0: that moves `M S` by at most `11 MIN_POSITIVE S0 ≤
///   11 ε max|M| S0`, inside the validity slack `64 ε M₀₀ S0` of the product's rounding;
/// - in between, unchanged: a subnormal entry there carries up to all of the polarization of
///   its row (zeroing it could leave `M S` invalid by a sizeable fraction of `M₀₀`), and it is
///   exact to half a subnormal step, `ε MIN_POSITIVE/2`, within the same slack.
#[inline]
pub(crate) fn flush_to_normal<T: Real, const R: usize, const C: usize>(
    m: nalgebra::SMatrix<T, R, C>,
) -> nalgebra::SMatrix<T, R, C> {
    let largest = crate::numerics::amax(&m);
    if largest >= T::MIN_POSITIVE / T::EPSILON {
        m.map(|x| {
            if x.abs() < T::MIN_POSITIVE {
                T::zero()
            } else {
                x
            }
        })
    } else if largest >= T::MIN_POSITIVE {
        m
    } else {
        nalgebra::SMatrix::zeros()
    }
}

/// `m · e^{ln_e}` (the medium's phase matrices): 0 when the scale, or every entry of the
/// result, is below the smallest normal number (a matrix cannot keep the digits of a subnormal
/// scale entry by entry, and 0 is a valid Mueller matrix); for a scale beyond the largest
/// number each entry from its own logarithm ([`beyond_scale`]: `±∞` only where the entry
/// itself is beyond it, zeros stay 0).
#[inline]
pub(crate) fn unit_scaled<T: Real, const R: usize, const C: usize>(
    m: nalgebra::SMatrix<T, R, C>,
    ln_e: T,
) -> nalgebra::SMatrix<T, R, C> {
    scaled_then(m, ln_e, flush_subnormal)
}

/// `m · e^{ln_e}` for the kernel's BSDF form and the renderer layer's weights: as
/// [`unit_scaled`], with no subnormal entry left ([`flush_to_normal`]).
#[inline]
pub(crate) fn throughput_scaled<T: Real, const R: usize, const C: usize>(
    m: nalgebra::SMatrix<T, R, C>,
    ln_e: T,
) -> nalgebra::SMatrix<T, R, C> {
    scaled_then(m, ln_e, flush_to_normal)
}

#[inline(always)]
fn scaled_then<T: Real, const R: usize, const C: usize>(
    m: nalgebra::SMatrix<T, R, C>,
    ln_e: T,
    flush: fn(nalgebra::SMatrix<T, R, C>) -> nalgebra::SMatrix<T, R, C>,
) -> nalgebra::SMatrix<T, R, C> {
    let e = ln_e.exp();
    if e >= T::MIN_POSITIVE && e <= T::MAX {
        flush(m * e)
    } else if e > T::MAX {
        flush(m.map(|x| beyond_scale(x, ln_e)))
    } else {
        nalgebra::SMatrix::zeros()
    }
}

#[cfg(test)]
mod tests {
    /// A subnormal vector that rounding left outside the cone (the f32 case
    /// `tests/interaction/batch/lobes.rs` found, `(9, 9, 1, 0) δ`: 81 + 1 > 81) comes back inside
    /// by one step of its polarized entries; a valid one, a normal one and a negative `S0` are
    /// unchanged.
    #[test]
    fn a_subnormal_vector_outside_the_cone_comes_back_inside() {
        fn run<T: Real>() {
            let d = T::MIN_POSITIVE * T::EPSILON;
            let v = Vector4::new(T::lit(9.0), T::lit(9.0), T::lit(1.0), T::zero()) * d;
            let w = subnormal_onto_cone(v);
            assert_eq!(
                w,
                Vector4::new(T::lit(9.0), T::lit(8.0), T::zero(), T::zero()) * d
            );
            let inside = Vector4::new(T::lit(9.0), T::lit(8.0), -T::lit(4.0), T::zero()) * d;
            assert_eq!(subnormal_onto_cone(inside), inside);
            let normal = Vector4::new(T::one(), T::one(), T::lit(0.1), T::zero());
            assert_eq!(subnormal_onto_cone(normal), normal);
            let neg = Vector4::new(-d, d, d, d);
            assert_eq!(subnormal_onto_cone(neg), neg);
            // A polarized part far outside (not from rounding): to 0 after four steps.
            let far = Vector4::new(T::lit(2.0), T::lit(100.0), T::zero(), T::zero()) * d;
            assert_eq!(
                subnormal_onto_cone(far),
                Vector4::new(T::lit(2.0) * d, T::zero(), T::zero(), T::zero())
            );
        }
        run::<f64>();
        run::<f32>();
    }

    use nalgebra::{Vector3, Vector4};

    use super::subnormal_onto_cone;
    use crate::real::Real;

    use crate::frame::Frame;
    use crate::interaction::{Full, Kernel, Partial};
    use crate::packet::{CoherenceShape, WavePacket};
    use crate::stokes::Stokes;

    /// A zero vector (what `onto_cone` returns for `u₀ ≤ 0`) stays 0 under a scale that
    /// overflows, instead of becoming `0 · ∞ = NaN` (found by the batch stage tests).
    #[test]
    fn a_zero_vector_stays_zero_under_an_overflowing_scale() {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let travel = Vector3::new(0.4, 0.1, -0.91).normalize();
        let packet = WavePacket::from_stokes(
            Stokes::new(1e-150, 0.0, 0.0, 0.0).unwrap(),
            CoherenceShape::isotropic(6.0).unwrap(),
            Frame::sp(travel, Vector3::z()).unwrap(),
            0.55,
        )
        .unwrap();
        let prepared = Kernel::<Full, Partial>::default()
            .prepare(&packet, &surface)
            .unwrap();
        for ln_e in [1000.0, 1100.0, 1e5] {
            let z = prepared.scaled(Vector4::zeros(), ln_e);
            assert_eq!(z, Vector4::zeros(), "ln_e {ln_e}");
            let neg = prepared.scaled(Vector4::new(-1.0, 0.0, 0.5, 0.0), ln_e);
            assert!(neg[1] == 0.0 && neg[3] == 0.0 && neg[0] < 0.0, "{neg:?}");
        }
    }
}
