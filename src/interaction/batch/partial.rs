//! The partially coherent lobe batch in lanes: `Kernel::evaluate_batch` (and
//! `evaluate_batch_spectral`, several wavelengths per pass over the exits) for a Gaussian PSD,
//! or a mixture of at most 8 Gaussians (`ln Σⱼ Kⱼ` per channel by `channels::mixture_log`),
//! blurred in closed form ([`Partial`]`<`[`ClosedForm`]`>`) or in the incoherent limit
//! ([`Incoherent`]), [`FresnelReflection`] specular
//! reflection and [`RayleighRice`] scattering in reflection (a rough conductor), or
//! [`FresnelInterface`] and [`RayleighRice`] with a real permittivity in reflection and at the
//! interface lit from either side (a rough dielectric: per lane, reflection where `r̂·n̂ > 0`
//! and transmission where `r̂·n̂ < 0`, `n̂` the normal facing the source; from below the
//! constants are those of the reversed frame, the indices seen from the source and the PSD
//! mirrored, as `Geometry::at_interface` has them), at the [`Full`], [`OneShape`] and
//! [`Intensity`] levels — both lobes and the exit frames, 8 (`f64`) or 16 (`f32`) exits per
//! instruction under AVX-512, 4 or 8 under AVX2 + FMA. The `Intensity` level runs the `OneShape` stages on the effective vector
//! `(1, 0, 0, 0)` and writes `S0` only.
//!
//! With the Kirchhoff series' roughness level (a Gaussian PSD, partially coherent), the
//! scattered channels' weights are the series' sums ([`stages::series`]) instead of
//! `ln α + ln K`.
//!
//! Per vector of exits, the stages in order: r̂ and `cos θ_o` ([`stages::geometry`]), the exit
//! s vector and azimuth ([`stages::azimuth`]), `q_o` ([`stages::fresnel`]), the Rayleigh–Rice
//! factors ([`stages::rayleigh_rice`]: Germer's in reflection, Elson's in transmission), `h_t`
//! (`k (ŝ + η r̂)`, `η = 1` in reflection) and the Debye–Waller exponent (`v = k (cos θ_i +
//! cos θ_o)`, or `k (cos θ_i − η cos θ_o)`), the channel
//! weights and their mix ([`stages::channels`]), the scattered Stokes vector
//! ([`stages::stokes`]), the specular one ([`stages::specular`]), the projection onto the cone
//! and the final scale. The lanes the stages cannot reproduce — within `√ε` of the normal
//! (where `Frame::sp_unit` takes a tangent), a lit part whose scale leaves the normal range
//! (where the scalar kernel folds `|u|` into the exponent) — are redone by the per-direction
//! kernel, lane by lane; a part whose `S0` is below `MIN_POSITIVE/2` is written as 0 instead
//! (`stages::channels::scaled`).
//!
//! [`Partial`]: crate::interaction::Partial
//! [`ClosedForm`]: crate::psd::ClosedForm
//! [`Incoherent`]: crate::interaction::Incoherent
//! [`FresnelReflection`]: crate::interaction::pbsdf::FresnelReflection
//! [`FresnelInterface`]: crate::interaction::pbsdf::FresnelInterface
//! [`RayleighRice`]: crate::interaction::pbsdf::RayleighRice
//! [`Full`]: crate::interaction::Full
//! [`OneShape`]: crate::interaction::OneShape
//! [`Intensity`]: crate::interaction::Intensity

use nalgebra::Vector3;
use pulp::{Simd, WithSimd};

use super::DirectionsSoa;
use super::outputs::{ExitFramesSoa, LobesSoa};
use super::per_lane::{LaneConsts, MAX_LANES};
use super::prep::{Incidence, LobePrep, SERIES_MIN_EXITS, SeriesPrep, TransmissionPrep};
use super::stages;
use super::stages::validity::{clearly_valid, clearly_valid_lanes};
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::coherence::{CoherenceLevel, CoherenceWeights};
use crate::interaction::pbsdf::{FresnelInterface, RayleighRice};
use crate::interaction::pbsdf::{Pbsdf, PbsdfForm};
use crate::interaction::polarization::PolarizationModel;
use crate::interaction::polarization::{KernelOutput, PolarizationLevel};
use crate::interaction::roughness::{RoughnessLevel, RoughnessModel, RoughnessWeights};
use crate::interaction::{Geometry, Kernel, PreparedPacket, Surface};
use crate::packet::WavePacket;
use crate::psd::{GaussianPsd, Psd};
use crate::real::Real;
use crate::simd::complex::C;

/// One exit evaluated by the per-direction kernel: the specular and scattered Stokes vectors
/// and the exit s vector.
pub(crate) type ScalarExit<F> = ([F; 4], [F; 4], [F; 3]);

/// The lanes of one vector of exits.
pub(super) struct LobeLanes<S: Simd, F: Real> {
    pub(super) specular: [F::V<S>; 4],
    pub(super) scattered: [F::V<S>; 4],
    /// The lanes the per-direction kernel must redo.
    pub(super) redo: F::M<S>,
}

/// The wavelength-independent part of one vector of exits: r̂, `cos θ_o` and the exit frame.
pub(super) struct ExitLanes<S: Simd, F: Real> {
    r: [F::V<S>; 3],
    cos_o: F::V<S>,
    pub(super) frame: stages::azimuth::ExitFrame<S, F>,
}

/// [`ExitLanes`] of one vector of (validated) exits `(x, y, z)`: the incidence `inc` of any
/// of the wavelengths (their directions and surface are the same).
#[inline(always)]
pub(super) fn exit_lanes<S: Simd, F: Real, Q: LaneConsts<S, F>>(
    s: S,
    (inc, q): (&Incidence<F>, &Q),
    x: F::V<S>,
    y: F::V<S>,
    z: F::V<S>,
) -> ExitLanes<S, F> {
    let (r, cos_o) = stages::geometry::exit_direction::<S, F>(s, inc, x, y, z);
    let frame = stages::azimuth::exit_frame_with::<S, F>(s, inc, q.azimuth_axes(s), r);
    ExitLanes { r, cos_o, frame }
}

/// The kernel of one wavelength (`p`) on one vector of exits: in reflection (`below =
/// None`), or on the transmission side of a dielectric interface (`below = Some(t)`, `t` of
/// `p`: `cos θ_o = |r̂·n̂|`, `h = k (ŝ + η r̂)`, `v = k (cos θ_i − η cos θ_o)`, Elson's factors,
/// the Fresnel transmission and `ln η²` in the scale). Lanes on the other side carry values
/// the caller discards.
#[inline(always)]
pub(super) fn lobe_lanes<S: Simd, F: Real, Q: LaneConsts<S, F>>(
    s: S,
    (p, q): (&LobePrep<F>, &Q),
    series: Option<&SeriesPrep<F>>,
    e: &ExitLanes<S, F>,
    below: Option<&TransmissionPrep<F>>,
) -> LobeLanes<S, F> {
    let parts = lobe_parts::<S, F, Q>(s, (p, q), series, e, below);
    if p.intensity {
        intensity_lanes::<S, F, Q>(s, (p, q), &parts)
    } else {
        stokes_lanes::<S, F, Q>(s, (p, q), e, &parts)
    }
}

/// What [`lobe_lanes`] computes before it assembles the Stokes vectors (and
/// [`mueller_lanes`] the Mueller matrices): `cos θ_o`, the Rayleigh–Rice factors, the two
/// parts' log scales and effective vectors, the side's specular lobe and the lanes to redo so
/// far (within `√ε` of the normal, a series lane out of range).
pub(super) struct LobeParts<'t, S: Simd, F: Real> {
    cos_o: F::V<S>,
    factors: [C<F::V<S>>; 4],
    ln_spec: F::V<S>,
    ln_scat: F::V<S>,
    v_spec: [F::V<S>; 4],
    v_scat: [F::V<S>; 4],
    /// `None`: no specular lobe on this side; `Some(None)` in reflection; `Some(Some(t))` in
    /// transmission.
    spec: Option<Option<&'t TransmissionPrep<F>>>,
    redo: F::M<S>,
}

/// [`LobeParts`] of one wavelength on one vector of exits ([`lobe_lanes`]' arguments).
#[inline(always)]
fn lobe_parts<'t, S: Simd, F: Real, Q: LaneConsts<S, F>>(
    s: S,
    (p, q): (&LobePrep<F>, &Q),
    series: Option<&SeriesPrep<F>>,
    e: &ExitLanes<S, F>,
    below: Option<&'t TransmissionPrep<F>>,
) -> LobeParts<'t, S, F> {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let inc = &p.inc;
    let (r, frame) = (e.r, &e.frame);
    let azimuth = (frame.cos_phi, frame.sin_phi);
    let (sv, kk) = (q.to_source(s), c(inc.k));
    // cos θ_o, the Rayleigh–Rice factors, h_t = k (ŝ + η r̂) (Geometry::h_t: η = 1 in
    // reflection), v (the phase factor: ln α = −v² σ²), the constant exponents and the
    // specular pBSDF's per-packet part (None: no specular lobe on this side).
    let (cos_o, factors, h, v, (ln_spec0, ln_scat0), spec) = match below {
        None => {
            let cos_o = e.cos_o;
            let (so2, qo) = stages::fresnel::exit_q::<S, F>(s, inc, cos_o);
            let factors = stages::rayleigh_rice::factors_with::<S, F>(
                s,
                inc,
                &q.terms(s),
                cos_o,
                so2,
                qo,
                azimuth,
            );
            let h = [
                mul(s, add(s, r[0], sv[0]), kk),
                mul(s, add(s, r[1], sv[1]), kk),
                mul(s, add(s, r[2], sv[2]), kk),
            ];
            let v = mul(s, kk, add(s, q.cos_i(s), cos_o));
            (
                cos_o,
                factors,
                h,
                v,
                (c(p.ln_spec), q.ln_scat(s)),
                Some(None),
            )
        }
        Some(t) => {
            let cos_o = F::vabs(s, e.cos_o);
            let factors = stages::rayleigh_rice::transmission_factors::<S, F>(
                s, inc, &t.consts, cos_o, azimuth,
            );
            let eta = c(t.eta);
            let h = [
                mul(s, add(s, sv[0], mul(s, r[0], eta)), kk),
                mul(s, add(s, sv[1], mul(s, r[1], eta)), kk),
                mul(s, add(s, sv[2], mul(s, r[2], eta)), kk),
            ];
            let v = mul(s, kk, sub(s, q.cos_i(s), mul(s, eta, cos_o)));
            let spec = (!t.tir).then_some(Some(t));
            (cos_o, factors, h, v, (c(t.ln_spec), c(t.ln_scat)), spec)
        }
    };
    let h0 = stages::dot3::<S, F>(s, h, stages::splat3::<S, F>(s, inc.t1));
    let h1 = stages::dot3::<S, F>(s, h, stages::splat3::<S, F>(s, inc.t2));
    let ln_alpha = F::vneg_mul_add(s, mul(s, v, v), c(p.variance), c(F::zero()));
    let lg = stages::channels::log_gaussian::<S, F>;
    let lgw = stages::channels::log_gaussian_with::<S, F>;
    let (ml, nc) = (stages::channels::mixture_log::<S, F>, p.components);
    // The scattered channels' log weights: `ln α + ln K_α` at first order (α added below),
    // the series' `ln Σ (w_n/g) K_α[p_n]`, which carries it.
    let (scat_logs, redo_series) = match (series, p.three) {
        (Some(sp), true) => {
            let w = stages::series::log_weights::<S, F, 3>;
            w(s, sp, [0, 1, 2], v, (h0, h1), p.variance)
        }
        (Some(sp), false) => {
            let w = stages::series::log_weights::<S, F, 1>;
            let ([half], redo) = w(s, sp, [2], v, (h0, h1), p.variance);
            ([half; 3], redo)
        }
        (None, true) => (
            [
                ml(s, &p.scat[0][..nc], h0, h1),
                ml(s, &p.scat[1][..nc], h0, h1),
                ml(s, &p.scat[2][..nc], h0, h1),
            ],
            F::vlt(s, c(F::zero()), c(F::zero())),
        ),
        (None, false) => {
            let half = if nc == 1 {
                lgw(s, &q.scat_half(s), h0, h1)
            } else {
                ml(s, &p.scat[2][..nc], h0, h1)
            };
            ([half; 3], F::vlt(s, c(F::zero()), c(F::zero())))
        }
    };
    let ((v_spec, m_spec), (v_scat, m_scat)) = if p.three {
        let (sx, sy, sh) = (
            lg(s, &p.spec[0], h0, h1),
            lg(s, &p.spec[1], h0, h1),
            lg(s, &p.spec[2], h0, h1),
        );
        let [dx, dy, dh] = scat_logs;
        (
            stages::channels::channel_mix::<S, F>(s, p, sx, sy, sh),
            stages::channels::channel_mix::<S, F>(s, p, dx, dy, dh),
        )
    } else {
        let t = p.t_stokes;
        let tv = [c(t[0]), c(t[1]), c(t[2]), c(t[3])];
        ((tv, lgw(s, &q.spec_half(s), h0, h1)), (tv, scat_logs[2]))
    };
    let ln_scat = if series.is_some() {
        add(s, m_scat, ln_scat0)
    } else {
        add(s, add(s, ln_alpha, m_scat), ln_scat0)
    };
    let ln_spec = add(s, add(s, ln_alpha, m_spec), ln_spec0);
    LobeParts {
        cos_o,
        factors,
        ln_spec,
        ln_scat,
        v_spec,
        v_scat,
        spec,
        redo: F::vor(s, e.frame.normal, redo_series),
    }
}

/// [`lobe_lanes`] at the `Intensity` level.
#[inline(always)]
fn intensity_lanes<S: Simd, F: Real, Q: LaneConsts<S, F>>(
    s: S,
    (p, q): (&LobePrep<F>, &Q),
    parts: &LobeParts<'_, S, F>,
) -> LobeLanes<S, F> {
    let c = |v: F| F::vsplat(s, v);
    let mul = F::vmul::<S>;
    let zero = c(F::zero());
    let &LobeParts {
        cos_o,
        factors,
        ln_spec,
        ln_scat,
        spec,
        redo,
        ..
    } = parts;
    // S0 only, of the effective vector (1, 0, 0, 0): the scattered M₀₀ cos θ_o (the S0 of
    // `assemble_vector`, bit for bit), the specular M₀₀ cos θ_o (the frame change keeps
    // row 0 of the Fresnel matrix: the S0 of `fresnel_stokes`, bit for bit), and of
    // `onto_cone` the S0 alone (u₀ where u₀ > 0, else 0; it never changes u₀).
    let s0 = |u: F::V<S>| [F::vselect(s, F::vlt(s, zero, u), u, zero), zero, zero, zero];
    let u_scat = s0(stages::stokes::assemble_s0::<S, F>(s, factors, cos_o));
    let (scattered, redo_scat) = stages::channels::scaled::<S, F>(s, p, u_scat, ln_scat);
    let (specular, redo_spec) = match spec {
        Some(side) if F::vany(s, F::vle(s, c(p.ln_dark), ln_spec)) => {
            let m00 = side.map_or_else(|| q.fresnel_m00(s), |t| c(t.fresnel[(0, 0)]));
            let u = s0(mul(s, m00, cos_o));
            stages::channels::scaled::<S, F>(s, p, u, ln_spec)
        }
        _ => ([zero; 4], F::vlt(s, zero, zero)),
    };
    LobeLanes {
        specular,
        scattered,
        redo: F::vor(s, redo, F::vor(s, redo_scat, redo_spec)),
    }
}

/// The lanes of one vector of pairs as Mueller matrices (`[j]` column `j`, in each exit's
/// s/p frame, acting on Stokes vectors in the incident s/p frame), for
/// `Kernel::evaluate_pairs_mueller`.
pub(super) struct MuellerLanes<S: Simd, F: Real> {
    pub(super) specular: stages::channels::MatrixLanes<S, F>,
    pub(super) scattered: stages::channels::MatrixLanes<S, F>,
    /// The lanes the per-direction kernel must redo.
    pub(super) redo: F::M<S>,
}

/// [`lobe_lanes`] in reflection at first order as Mueller matrices, for a packet whose
/// effective vector is the unpolarized `(1, 0, 0, 0)` with one channel (`T = I`: the closed
/// form of `PreparedPacket::unpolarized_isotropic` the pairs use). Column `j` is what the
/// Stokes assembly gives for the effective vector `e_j` before the projection onto the cone,
/// so column 0 is [`lobe_lanes`]' vector before that projection, bit for bit; the scale, the
/// dark and negligible parts and the lanes to redo follow `M₀₀`
/// ([`stages::channels::scaled_matrix`]). At the `Intensity` level `M₀₀` alone (the other
/// entries 0): [`lobe_lanes`]' `S0`.
#[inline(always)]
pub(super) fn mueller_lanes<S: Simd, F: Real, Q: LaneConsts<S, F>>(
    s: S,
    (p, q): (&LobePrep<F>, &Q),
    e: &ExitLanes<S, F>,
) -> MuellerLanes<S, F> {
    debug_assert!(
        !p.three && p.t_stokes == nalgebra::Vector4::new(F::one(), F::zero(), F::zero(), F::zero()),
        "mueller_lanes: an unpolarized packet with one channel"
    );
    let c = |v: F| F::vsplat(s, v);
    let zero = c(F::zero());
    let parts = lobe_parts::<S, F, Q>(s, (p, q), None, e, None);
    if p.intensity {
        let l = intensity_lanes::<S, F, Q>(s, (p, q), &parts);
        let m00 = |v: F::V<S>| [[v, zero, zero, zero], [zero; 4], [zero; 4], [zero; 4]];
        return MuellerLanes {
            specular: m00(l.specular[0]),
            scattered: m00(l.scattered[0]),
            redo: l.redo,
        };
    }
    let LobeParts {
        cos_o,
        factors,
        ln_spec,
        ln_scat,
        spec,
        redo,
        ..
    } = parts;
    // The effective vectors e_j as [P, Q, S2, S3] (`channels::halves` of e_j).
    let (half, one) = (c(F::lit(0.5)), c(F::one()));
    let assemble = stages::stokes::assemble_vector::<S, F>;
    let scat = [
        assemble(s, [half, half, zero, zero], factors, cos_o),
        assemble(s, [half, c(F::lit(-0.5)), zero, zero], factors, cos_o),
        assemble(s, [zero, zero, one, zero], factors, cos_o),
        assemble(s, [zero, zero, zero, one], factors, cos_o),
    ];
    let (scattered, redo_scat) = stages::channels::scaled_matrix::<S, F>(s, p, scat, ln_scat);
    let (specular, redo_spec) = match spec {
        Some(None) if F::vany(s, F::vle(s, c(p.ln_dark), ln_spec)) => {
            let (r, s_out) = (e.r, e.frame.s_out);
            let m = [
                q.fresnel_stokes(s, r, s_out, [cos_o, zero, zero, zero]),
                q.fresnel_stokes(s, r, s_out, [zero, cos_o, zero, zero]),
                q.fresnel_stokes(s, r, s_out, [zero, zero, cos_o, zero]),
                q.fresnel_stokes(s, r, s_out, [zero, zero, zero, cos_o]),
            ];
            stages::channels::scaled_matrix::<S, F>(s, p, m, ln_spec)
        }
        _ => ([[zero; 4]; 4], F::vlt(s, zero, zero)),
    };
    MuellerLanes {
        specular,
        scattered,
        redo: F::vor(s, redo, F::vor(s, redo_scat, redo_spec)),
    }
}

/// [`lobe_lanes`] at the Stokes levels.
#[inline(always)]
fn stokes_lanes<S: Simd, F: Real, Q: LaneConsts<S, F>>(
    s: S,
    (p, q): (&LobePrep<F>, &Q),
    e: &ExitLanes<S, F>,
    parts: &LobeParts<'_, S, F>,
) -> LobeLanes<S, F> {
    let c = |v: F| F::vsplat(s, v);
    let mul = F::vmul::<S>;
    let zero = c(F::zero());
    let (r, frame) = (e.r, &e.frame);
    let &LobeParts {
        cos_o,
        factors,
        ln_spec,
        ln_scat,
        v_spec,
        v_scat,
        spec,
        redo,
    } = parts;
    let raw_scat = stages::stokes::assemble_vector::<S, F>(
        s,
        stages::channels::halves::<S, F>(s, v_scat),
        factors,
        cos_o,
    );
    let u_scat = stages::channels::onto_cone::<S, F>(s, raw_scat);
    let (scattered, redo_scat) = stages::channels::scaled::<S, F>(s, p, u_scat, ln_scat);
    let (specular, redo_spec) = match spec {
        Some(side) if F::vany(s, F::vle(s, c(p.ln_dark), ln_spec)) => {
            let v = [
                mul(s, v_spec[0], cos_o),
                mul(s, v_spec[1], cos_o),
                mul(s, v_spec[2], cos_o),
                mul(s, v_spec[3], cos_o),
            ];
            let u = match side {
                None => q.fresnel_stokes(s, r, frame.s_out, v),
                Some(t) => stages::specular::fresnel_stokes::<S, F>(
                    s,
                    (&t.fresnel, &t.spec_frame, p.flip_tol),
                    r,
                    frame.s_out,
                    v,
                ),
            };
            let u = stages::channels::onto_cone::<S, F>(s, u);
            stages::channels::scaled::<S, F>(s, p, u, ln_spec)
        }
        _ => ([zero; 4], F::vlt(s, zero, zero)),
    };
    LobeLanes {
        specular,
        scattered,
        redo: F::vor(s, redo, F::vor(s, redo_scat, redo_spec)),
    }
}

/// [`lobe_lanes`] on each lane's side: reflection everywhere without an interface; at one,
/// the transmission side where `r̂·n̂ < 0` (both computed, and selected lane by lane, only for a
/// vector with exits on both sides).
#[inline(always)]
fn lobe_lanes_either_side<S: Simd, F: Real>(
    s: S,
    p: &LobePrep<F>,
    series: Option<&SeriesPrep<F>>,
    e: &ExitLanes<S, F>,
) -> LobeLanes<S, F> {
    let lobe_lanes = |below| lobe_lanes::<S, F, LobePrep<F>>(s, (p, p), series, e, below);
    let Some(t) = p.transmission.as_ref() else {
        return lobe_lanes(None);
    };
    let below = F::vlt(s, e.cos_o, F::vsplat(s, F::zero()));
    if !F::vany(s, below) {
        return lobe_lanes(None);
    }
    if !F::vany(s, F::vnot(s, below)) {
        return lobe_lanes(Some(t));
    }
    let (up, down) = (lobe_lanes(None), lobe_lanes(Some(t)));
    let and = F::vand::<S>;
    LobeLanes {
        specular: pick::<S, F>(s, below, down.specular, up.specular),
        scattered: pick::<S, F>(s, below, down.scattered, up.scattered),
        redo: F::vor(
            s,
            and(s, below, down.redo),
            and(s, F::vnot(s, below), up.redo),
        ),
    }
}

/// `b` where `m`, else `a`, per component.
#[inline(always)]
fn pick<S: Simd, F: Real>(s: S, m: F::M<S>, b: [F::V<S>; 4], a: [F::V<S>; 4]) -> [F::V<S>; 4] {
    [
        F::vselect(s, m, b[0], a[0]),
        F::vselect(s, m, b[1], a[1]),
        F::vselect(s, m, b[2], a[2]),
        F::vselect(s, m, b[3], a[3]),
    ]
}

/// The SIMD loop over a batch of exits and one or more wavelengths, instantiated by
/// [`pulp::Arch::dispatch`] once per instruction set: `preps[w]` and `outs[w]` are wavelength
/// `w`'s constants and lobes (the exit geometry is computed once per vector for all of them);
/// `scalar(w, i)` evaluates exit `i` at wavelength `w` with the per-direction kernel.
///
/// `scalar` is a trait object so that the loop is one type per float type, whatever the
/// material and kernel: each crate that calls it then compiles it once per instruction set and
/// float type instead of once per material and level as well (with AVX-512 in the dispatch,
/// the integration tests' build needed over 14 GiB with a generic closure). It is called only
/// for the lanes the loop cannot do.
pub(crate) struct PartialLobes<'r, 'e, 'o, 'f, F: Real> {
    pub(crate) preps: &'r [LobePrep<F>],
    /// The Kirchhoff series' constants of each wavelength (`series[w]` of `preps[w]`); empty
    /// or `None` at first order.
    pub(crate) series: &'r [Option<SeriesPrep<F>>],
    pub(crate) exits: DirectionsSoa<'e, F>,
    pub(crate) outs: &'r mut [LobesSoa<'o, F>],
    pub(crate) frames: Option<&'r mut ExitFramesSoa<'f, F>>,
    pub(crate) scalar: ScalarRedo<'r, F>,
}

/// The per-direction kernel at exit `i` and wavelength `w`, for the lanes redone one at a time.
pub(crate) type ScalarRedo<'r, F> = &'r mut dyn FnMut(usize, usize) -> Result<ScalarExit<F>, Error>;

/// The exits `start..start + count` of `v` as one vector: a whole vector when `count` is the
/// width, else padded with `v[0]` (through `b`).
#[inline(always)]
pub(super) fn load<S: Simd, F: Real>(
    v: &[F],
    b: &mut [F; MAX_LANES],
    start: usize,
    count: usize,
) -> F::V<S> {
    let lanes = F::width::<S>();
    if count == lanes {
        F::vsplit::<S>(&v[start..start + lanes]).0[0]
    } else {
        b[..lanes].fill(v[0]);
        b[..count].copy_from_slice(&v[..count]);
        F::vsplit::<S>(&b[..lanes]).0[0]
    }
}

/// The first `count` lanes of `v` into `o[start..start + count]`.
#[inline(always)]
pub(super) fn store<S: Simd, F: Real>(s: S, o: &mut [F], v: F::V<S>, start: usize, count: usize) {
    let t = &mut o[start..start + count];
    if count == F::width::<S>() {
        F::vsplit_mut::<S>(t).0[0] = v;
    } else {
        F::store_partial(s, t, v);
    }
}

impl<F: Real> WithSimd for PartialLobes<'_, '_, '_, '_, F> {
    type Output = Result<(), Error>;

    // `inline(always)`: the body must be compiled inside pulp's `#[target_feature]` function.
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> Result<(), Error> {
        let Self {
            preps,
            series,
            exits,
            outs,
            frames,
            scalar,
        } = self;
        let Some(prep) = preps.first() else {
            return Ok(());
        };
        let n = exits.len();
        let (xs, ys, zs) = (&exits.x[..n], &exits.y[..n], &exits.z[..n]);
        let lanes = F::width::<S>();
        let exit = |i: usize| Vector3::new(xs[i], ys[i], zs[i]);
        // Validate everything before writing anything (the exits' validity does not depend on
        // the wavelength: the same direction and surface).
        let nv = n / lanes;
        {
            let (hx, hy, hz) = (
                F::vsplit::<S>(xs).0,
                F::vsplit::<S>(ys).0,
                F::vsplit::<S>(zs).0,
            );
            for i in 0..nv {
                let ok = clearly_valid_lanes::<S, F>(s, prep, hx[i], hy[i], hz[i]);
                if F::vany(s, F::vnot(s, ok)) {
                    for j in i * lanes..(i + 1) * lanes {
                        prep.check_exact(exit(j))?;
                    }
                }
            }
            for j in nv * lanes..n {
                if !clearly_valid(prep, xs[j], ys[j], zs[j]) {
                    prep.check_exact(exit(j))?;
                }
            }
        }
        if n == 0 {
            return Ok(());
        }
        // One instantiation of the loop, the series chosen at run time: first order costs the
        // same (callgrind: 187/398 instructions per f32/f64 direction, 186/396 with a second
        // instantiation without the series), and the crate builds in 52 s instead of 68.
        lobe_loop::<S, F>(s, preps, series, [xs, ys, zs], outs, frames, scalar)
    }
}

/// The loop of [`PartialLobes`] over the vectors of (validated) exits `xyz`.
#[inline(always)]
fn lobe_loop<S: Simd, F: Real>(
    s: S,
    preps: &[LobePrep<F>],
    series: &[Option<SeriesPrep<F>>],
    [xs, ys, zs]: [&[F]; 3],
    outs: &mut [LobesSoa<'_, F>],
    mut frames: Option<&mut ExitFramesSoa<'_, F>>,
    scalar: ScalarRedo<'_, F>,
) -> Result<(), Error> {
    let prep = &preps[0];
    let n = xs.len();
    let lanes = F::width::<S>();
    // Whole vectors at 0, lanes, 2 lanes, …; the tail as the last `lanes` exits (overlapping
    // the vector before it), or, for a batch shorter than one vector, padded with exit 0.
    let chunks = n.div_ceil(lanes);
    // The Intensity level writes S0 only.
    let stokes_len = if prep.intensity { 1 } else { 4 };
    let mut buf = [[F::zero(); MAX_LANES]; 3];
    for chunk in 0..chunks {
        let (start, count) = if n >= lanes {
            ((chunk * lanes).min(n - lanes), lanes)
        } else {
            (0, n)
        };
        let [bx, by, bz] = &mut buf;
        let x = load::<S, F>(xs, bx, start, count);
        let y = load::<S, F>(ys, by, start, count);
        let z = load::<S, F>(zs, bz, start, count);
        let e = exit_lanes::<S, F, LobePrep<F>>(s, (prep, prep), x, y, z);
        if let Some(f) = frames.as_deref_mut() {
            for k in 0..3 {
                store::<S, F>(s, f.s[k], e.frame.s_out[k], start, count);
            }
        }
        for (w, (p, out)) in preps.iter().zip(outs.iter_mut()).enumerate() {
            let sp = series.get(w).and_then(Option::as_ref);
            let l = lobe_lanes_either_side::<S, F>(s, p, sp, &e);
            for k in 0..stokes_len {
                store::<S, F>(s, out.specular.s[k], l.specular[k], start, count);
                store::<S, F>(s, out.scattered.s[k], l.scattered[k], start, count);
            }
            if F::vany(s, l.redo) {
                for j in redo_lanes::<S, F>(s, l.redo, count) {
                    let i = start + j;
                    let f = if w == 0 { frames.as_deref_mut() } else { None };
                    write_scalar(i, scalar(w, i)?, (out, f), stokes_len);
                }
            }
        }
    }
    Ok(())
}

/// The lanes of the mask `redo` among the first `count`.
#[inline(always)]
pub(super) fn redo_lanes<S: Simd, F: Real>(
    s: S,
    redo: F::M<S>,
    count: usize,
) -> impl Iterator<Item = usize> {
    let mut flags = [F::zero(); MAX_LANES];
    let ones = F::vselect(s, redo, F::vsplat(s, F::one()), F::vsplat(s, F::zero()));
    F::store_partial(s, &mut flags[..F::width::<S>()], ones);
    (0..count).filter(move |&j| flags[j] != F::zero())
}

/// Exit `i` as the per-direction kernel gave it (`S0` alone when `stokes_len` is 1), with its
/// exit s vector where `frames` is given.
#[inline]
pub(super) fn write_scalar<F: Real>(
    i: usize,
    (sp, sc, so): ScalarExit<F>,
    (out, frames): (&mut LobesSoa<'_, F>, Option<&mut ExitFramesSoa<'_, F>>),
    stokes_len: usize,
) {
    for k in 0..stokes_len {
        out.specular.s[k][i] = sp[k];
        out.scattered.s[k][i] = sc[k];
    }
    if let Some(f) = frames {
        for (col, v) in f.s.iter_mut().zip(so) {
            col[i] = v;
        }
    }
}

/// The lane constants of one wavelength: `Some` when the kernel and the material are those of
/// the module docs and the per-packet constants are inside what the lanes reproduce (see
/// [`LobePrep::new`], and [`LobePrep::at_interface`] with `interface = Some(η)`); `None`
/// otherwise, and the caller goes exit by exit.
pub(crate) fn lane_prep<T, S, Pol, Coh, Rough>(
    kernel: &Kernel<Pol, Coh, Rough>,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    packet: &WavePacket<T>,
    surface: &Frame<T>,
    interface: Option<T>,
) -> Option<LobePrep<T>>
where
    T: Real,
    S: Surface<T>,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessModel,
{
    let to_source = -packet.direction();
    lane_prep_at(kernel, material, prepared, to_source, surface, interface)
}

/// [`lane_prep`] for the prepared packet arriving from `to_source` (`−k̂`, any length).
pub(crate) fn lane_prep_at<T, S, Pol, Coh, Rough>(
    kernel: &Kernel<Pol, Coh, Rough>,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    to_source: Vector3<T>,
    surface: &Frame<T>,
    interface: Option<T>,
) -> Option<LobePrep<T>>
where
    T: Real,
    S: Surface<T>,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessModel,
{
    // First order, or the Kirchhoff series (its weights from `series_prep`, partially coherent
    // only: the incoherent series is a closed form the lanes do not have).
    let series = match (Rough::LEVEL, kernel.roughness().lane_series()) {
        (RoughnessLevel::FirstOrder, _) => false,
        (RoughnessLevel::KirchhoffSeries, Some(_)) => true,
        _ => return None,
    };
    let (full, intensity) = match Pol::LEVEL {
        PolarizationLevel::Full => (true, false),
        PolarizationLevel::OneShape => (false, false),
        PolarizationLevel::Intensity => (false, true),
    };
    // The lanes' weights are the closed forms: the incoherent level's, and the partially
    // coherent level's where its blur of a Gaussian is exact (`Partial<ClosedForm>`).
    let incoherent = match Coh::LEVEL {
        CoherenceLevel::Incoherent if !series => true,
        CoherenceLevel::Partial if kernel.coherence().closed_form_gaussian() => false,
        _ => return None,
    };
    let parts: LaneMaterial<'_, T> = LaneMaterial::of(material)?;
    // A conductor's Fresnel reflection has no transmitted lobe: its interface goes exit by exit.
    if interface.is_some() && parts.dielectric.is_none() {
        return None;
    }
    // At an interface lit from below, the frame facing the source (t̂₂ and n̂ negated) and the
    // indices seen from the source, as `Geometry::at_interface` and the pBSDFs have them.
    let below = interface.is_some() && (-to_source).dot(&surface.k()) > T::zero();
    let facing = if below { surface.reversed() } else { *surface };
    let (index, permittivity) = match (below, parts.dielectric) {
        (true, Some(d)) => (
            num_complex::Complex::new(d.relative_index().recip(), T::zero()),
            parts.scatter.permittivity_seen(true),
        ),
        _ => (parts.index, parts.scatter.permittivity()),
    };
    let prep = LobePrep::from_direction(
        prepared,
        (parts.components, parts.variance),
        (index, permittivity),
        to_source,
        (&facing, below),
        full,
    )?;
    let prep = match (interface, parts.dielectric) {
        (Some(eta), Some(d)) => prep.at_interface(eta, surface, d)?,
        _ => prep,
    };
    let prep = if incoherent {
        prep.incoherent(parts.integral)?
    } else {
        prep
    };
    Some(if intensity {
        prep.intensity_only()
    } else {
        prep
    })
}

/// What the per-pair constants of [`super::pairs`] need besides each pair's prepared packet
/// and direction ([`LobePrep::lane_row_of`]): the PSD's one Gaussian component, the Fresnel
/// index and the Rayleigh–Rice permittivity, and the PSD's integral at the incoherent level.
pub(crate) struct RowMaker<'a, T: Real> {
    pub(crate) psd: &'a GaussianPsd<T, 2>,
    pub(crate) indices: (num_complex::Complex<T>, num_complex::Complex<T>),
    pub(crate) incoherent: Option<T>,
}

/// The [`RowMaker`] of a first-order kernel on a material whose lanes [`lane_prep_at`] builds
/// in reflection, with a PSD of one Gaussian component; `None` otherwise.
pub(crate) fn row_maker<'a, T, S, Pol, Coh, Rough>(
    kernel: &Kernel<Pol, Coh, Rough>,
    material: &'a S,
) -> Option<RowMaker<'a, T>>
where
    T: Real,
    S: Surface<T>,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessModel,
{
    if Rough::LEVEL != RoughnessLevel::FirstOrder {
        return None;
    }
    let incoherent = match Coh::LEVEL {
        CoherenceLevel::Incoherent => true,
        CoherenceLevel::Partial if kernel.coherence().closed_form_gaussian() => false,
        _ => return None,
    };
    let parts: LaneMaterial<'a, T> = LaneMaterial::of(material)?;
    let [psd] = parts.components else {
        return None;
    };
    Some(RowMaker {
        psd,
        indices: (parts.index, parts.scatter.permittivity()),
        incoherent: incoherent.then_some(parts.integral),
    })
}

/// The Kirchhoff series' lane constants for the lane constants `prep` of the same call
/// ([`lane_prep`]): `None` at first order, `Some(None)` where the series cannot run in lanes
/// (a PSD that is not one exact Gaussian, a constant [`SeriesPrep::new`] refuses).
pub(crate) fn series_prep<T, S, Pol, Coh, Rough>(
    kernel: &Kernel<Pol, Coh, Rough>,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    prep: &LobePrep<T>,
) -> Option<Option<SeriesPrep<T>>>
where
    T: Real,
    S: Surface<T>,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessModel,
{
    let params = kernel.roughness().lane_series()?;
    let parts = material.parts();
    let crate::psd::Shape::Gaussian(psd) = parts.psd.form().shape() else {
        return Some(None);
    };
    if !parts.psd.form().is_exact() {
        return Some(None);
    }
    let [x, y, h] = &prepared.sections;
    // |v| ≤ k (cos θ_i + 1) in reflection, k (1 + η_t) in transmission.
    let eta = prep.transmission.map_or(T::one(), |t| t.eta.max(T::one()));
    let v_max = prep.inc.k * (T::one() + eta);
    Some(SeriesPrep::new(
        [x.as_ref(), y.as_ref(), h.as_ref()],
        prep.three,
        psd,
        (prep.mirrored, v_max),
        params,
    ))
}

/// What the lanes read of a material: a [`crate::interaction::RoughConductor`] or a
/// [`crate::interaction::RoughDielectric`] with a
/// Gaussian PSD, or a mixture of at most [`super::prep::MAX_COMPONENTS`] Gaussians
/// ([`LobePrep::new`]).
struct LaneMaterial<'a, T: Real> {
    components: &'a [GaussianPsd<T, 2>],
    variance: T,
    integral: T,
    /// The specular reflection's index (`Complex(η, 0)` for a dielectric).
    index: num_complex::Complex<T>,
    scatter: &'a RayleighRice<T>,
    /// The dielectric's specular pBSDF (`None` for a conductor).
    dielectric: Option<&'a FresnelInterface<T>>,
}

impl<'a, T: Real> LaneMaterial<'a, T> {
    /// The parts, each read from its form (`None` for any other PSD or pBSDF).
    fn of<S: Surface<T>>(material: &'a S) -> Option<Self> {
        let material = material.parts();
        let components = material.psd.form().exact_gaussians()?;
        let (index, dielectric) = match material.specular.form() {
            PbsdfForm::FresnelReflection(f) => (f.index(), None),
            PbsdfForm::FresnelInterface(d) => (
                num_complex::Complex::new(d.relative_index(), T::zero()),
                Some(d),
            ),
            _ => return None,
        };
        let PbsdfForm::RayleighRice(scatter) = material.scatter.form() else {
            return None;
        };
        Some(Self {
            components,
            variance: material.psd.variance(),
            integral: material.psd.integral(),
            index,
            scatter,
            dielectric,
        })
    }
}

/// Exit `exit` of `packet` by the per-direction kernel (in reflection, or at the interface
/// `Some(η)`), as the lanes write it.
pub(crate) fn scalar_exit<T, S, Pol, Coh, Rough>(
    kernel: &Kernel<Pol, Coh, Rough>,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    packet: &WavePacket<T>,
    (surface, interface): (&Frame<T>, Option<T>),
    exit: Vector3<T>,
) -> Result<ScalarExit<T>, Error>
where
    T: Real,
    S: Surface<T>,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessWeights<T, S::Psd, Coh>,
{
    let g = match interface {
        Some(eta) => Geometry::for_packet_at_interface(packet, surface, eta, exit)?,
        None => Geometry::for_packet(packet, surface, exit)?,
    };
    Ok(as_written(
        &kernel.evaluate_prepared(material, prepared, &g),
        &g,
    ))
}

/// The per-direction kernel's output `r` at geometry `g` as the lanes write it: both lobes'
/// Stokes vectors (`S0` alone at the intensity levels, the rest 0) and the exit s vector.
pub(crate) fn as_written<T: Real, O: KernelOutput<T>>(r: &O, g: &Geometry<T>) -> ScalarExit<T> {
    let z = T::zero();
    let (sp, sc) = match r.stokes() {
        Some((sp, sc)) => (sp.0.into(), sc.0.into()),
        None => (
            [r.specular_intensity(), z, z, z],
            [r.scattered_intensity(), z, z, z],
        ),
    };
    (sp, sc, g.exit_sp().x().into())
}

/// The lane path of [`Kernel::evaluate_batch`] (see [`lane_prep`]); `None` when it does not
/// apply.
#[expect(
    clippy::too_many_arguments,
    reason = "evaluate_batch's arguments and its prepared packet"
)]
pub(crate) fn try_evaluate<T, S, Pol, Coh, Rough>(
    kernel: &Kernel<Pol, Coh, Rough>,
    material: &S,
    prepared: &PreparedPacket<T, Pol, Coh>,
    packet: &WavePacket<T>,
    (surface, interface): (&Frame<T>, Option<T>),
    exits: DirectionsSoa<'_, T>,
    out: &mut LobesSoa<'_, T>,
    frames: Option<&mut ExitFramesSoa<'_, T>>,
) -> Option<Result<(), Error>>
where
    T: Real,
    S: Surface<T>,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, S::Psd>,
    Rough: RoughnessWeights<T, S::Psd, Coh>,
{
    if kernel.roughness().lane_series().is_some() && exits.len() < SERIES_MIN_EXITS {
        return None;
    }
    let prep = lane_prep(kernel, material, prepared, packet, surface, interface)?;
    let series = match series_prep(kernel, material, prepared, &prep) {
        None => None,
        Some(Some(sp)) => Some(sp),
        Some(None) => return None,
    };
    let mut scalar = |_: usize, i: usize| {
        let exit = Vector3::new(exits.x[i], exits.y[i], exits.z[i]);
        scalar_exit(
            kernel,
            material,
            prepared,
            packet,
            (surface, interface),
            exit,
        )
    };
    Some(crate::simd::dispatch(PartialLobes {
        preps: core::slice::from_ref(&prep),
        series: core::slice::from_ref(&series),
        exits,
        outs: core::slice::from_mut(out),
        frames,
        scalar: &mut scalar,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interaction::{Full, Incoherent, Partial, RoughConductor, RoughSurface};
    use crate::packet::CoherenceShape;
    use crate::psd::GaussianMixturePsd;
    use crate::stokes::Stokes;
    use num_complex::Complex;

    /// The two lobes' Stokes columns (specular S0..S3, then scattered S0..S3) of one lane
    /// pass over the exits `[x, y, z]`, asserting that no lane was redone by the per-direction
    /// kernel (whose stand-in here only counts its calls).
    fn lanes_alone<T: Real>(prep: &LobePrep<T>, [x, y, z]: [&[T]; 3]) -> Vec<Vec<T>> {
        let n = x.len();
        let mut buf = vec![vec![T::zero(); n]; 8];
        let [a, b, c, d, e, f, g, h] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: super::super::StokesSoa { s: [a, b, c, d] },
            scattered: super::super::StokesSoa { s: [e, f, g, h] },
        };
        let mut calls = 0;
        crate::simd::dispatch(PartialLobes {
            preps: core::slice::from_ref(prep),
            series: &[],
            exits: DirectionsSoa { x, y, z },
            outs: core::slice::from_mut(&mut out),
            frames: None,
            scalar: &mut |_, _| {
                calls += 1;
                Ok(([T::zero(); 4], [T::zero(); 4], [T::zero(); 3]))
            },
        })
        .unwrap();
        assert_eq!(calls, 0, "lanes redone by the per-direction kernel");
        buf
    }

    /// The scene of the `kernel_batch_partial` bench (30° incidence, two shapes, exits within
    /// ±7.5° of the mirror direction) takes the lane path with every constant prepared, and no
    /// lane needs the per-direction kernel.
    fn in_lanes<T: Real>() {
        let theta_i = 30f64.to_radians();
        let travel = Vector3::new(theta_i.sin(), 0.0, -theta_i.cos()).map(T::lit);
        let frame = Frame::sp(travel, Vector3::z())
            .unwrap()
            .rotated(T::lit(0.7));
        let packet = WavePacket::new(
            Stokes::new(T::one(), T::lit(0.3), T::lit(0.2), -T::lit(0.3)).unwrap(),
            CoherenceShape::isotropic(T::lit(5.0)).unwrap(),
            CoherenceShape::isotropic(T::lit(6.0)).unwrap(),
            frame,
            T::lit(0.5),
        )
        .unwrap();
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let eta = Complex::new(T::lit(1.5), T::zero());
        let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
        let kernel = Kernel::<Full, Partial>::default();
        let prepared = kernel.prepare(&packet, &surface).unwrap();
        let prep = LobePrep::new(
            &prepared,
            core::slice::from_ref(&psd),
            psd.variance(),
            (eta, eta * eta),
            &packet,
            (&surface, false),
            true,
        )
        .expect("the lane constants");
        assert!(prep.three);
        let n = 64;
        let (mut x, mut y, mut z) = (vec![], vec![], vec![]);
        for i in 0..n {
            let to = theta_i + (i as f64 / n as f64 - 0.5) * 0.26;
            let po = ((i * 7 % n) as f64 / n as f64 - 0.5) * 0.52;
            x.push(T::lit(to.sin() * po.cos()));
            y.push(T::lit(to.sin() * po.sin()));
            z.push(T::lit(to.cos()));
        }
        let out = lanes_alone(&prep, [&x, &y, &z]);
        assert!(out[4].iter().all(|v| *v > T::zero()));
        assert!(out[0].iter().filter(|v| **v > T::zero()).count() > n / 2);
    }

    /// `try_evaluate` takes the lane path for exactly the documented kernels and materials.
    #[test]
    fn the_lane_path_is_taken_where_documented() {
        use crate::interaction::pbsdf::{FresnelInterface, RayleighRice};
        use crate::interaction::{Intensity, OneShape, PlaneWave, RoughDielectric};
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let travel = Vector3::new(0.4, 0.1, -0.91).normalize();
        let packet = WavePacket::new(
            Stokes::new(1.0, 0.3, -0.2, 0.5).unwrap(),
            CoherenceShape::isotropic(6.0).unwrap(),
            CoherenceShape::isotropic(7.2).unwrap(),
            Frame::sp(travel, Vector3::z()).unwrap(),
            0.55,
        )
        .unwrap();
        let psd = GaussianPsd::<f64, 2>::isotropic(0.02, 1.5).unwrap();
        let gold = RoughConductor::new(psd, Complex::new(0.2, 3.4)).unwrap();
        let glass: RoughDielectric<f64, _> = RoughSurface {
            psd,
            specular: FresnelInterface::new(1.5).unwrap(),
            scatter: RayleighRice::new(Complex::new(1.5, 0.0)).unwrap(),
        };
        let (x, y, z) = ([0.3], [0.1], [0.9]);
        let mut buf = [[0.0; 1]; 8];
        let [a, b, c, d, e, f, g, h] = &mut buf;
        let mut out = LobesSoa {
            specular: super::super::StokesSoa { s: [a, b, c, d] },
            scattered: super::super::StokesSoa { s: [e, f, g, h] },
        };
        macro_rules! taken {
            ($pol:ty, $coh:ty, $m:expr) => {
                taken!($pol, $coh, $m, None)
            };
            ($pol:ty, $coh:ty, $m:expr, $interface:expr) => {{
                let kernel = Kernel::<$pol, $coh>::default();
                let prepared = kernel.prepare(&packet, &surface).unwrap();
                let exits = DirectionsSoa {
                    x: &x,
                    y: &y,
                    z: &z,
                };
                try_evaluate(
                    &kernel,
                    $m,
                    &prepared,
                    &packet,
                    (&surface, $interface),
                    exits,
                    &mut out,
                    None,
                )
                .map(|r| r.unwrap())
                .is_some()
            }};
        }
        assert!(taken!(Full, Partial, &gold));
        assert!(taken!(OneShape, Partial, &gold));
        assert!(taken!(Full, Incoherent, &gold));
        assert!(taken!(OneShape, Incoherent, &gold));
        assert!(taken!(Intensity, Partial, &gold));
        assert!(taken!(Intensity, Incoherent, &gold));
        assert!(!taken!(Intensity, PlaneWave, &gold));
        assert!(!taken!(Full, PlaneWave, &gold));
        // A dielectric in reflection and at its interface; a conductor's interface one at a
        // time (its Fresnel reflection transmits nothing); a complex Rayleigh–Rice permittivity
        // at an interface one at a time (the transmission lanes take a real one).
        assert!(taken!(Full, Partial, &glass));
        assert!(taken!(Full, Partial, &glass, Some(1.5)));
        assert!(taken!(Intensity, Incoherent, &glass, Some(1.5)));
        assert!(!taken!(Full, Partial, &gold, Some(1.5)));
        {
            // From inside the glass.
            let up = WavePacket::from_stokes(
                Stokes::new(1.0, 0.3, -0.2, 0.5).unwrap(),
                CoherenceShape::isotropic(6.0).unwrap(),
                Frame::sp(Vector3::new(0.4, 0.1, 0.91).normalize(), Vector3::z()).unwrap(),
                0.55,
            )
            .unwrap();
            let kernel = Kernel::<Full, Partial>::default();
            let facing = surface.facing(&-up.direction());
            let prepared = kernel.prepare(&up, &facing).unwrap();
            let exits = DirectionsSoa {
                x: &x,
                y: &y,
                z: &z,
            };
            let lanes = try_evaluate(
                &kernel,
                &glass,
                &prepared,
                &up,
                (&surface, Some(1.5)),
                exits,
                &mut out,
                None,
            );
            assert!(lanes.is_some_and(|r| r.is_ok()), "from below");
        }
        let lossy: RoughDielectric<f64, _> = RoughSurface {
            psd,
            specular: FresnelInterface::new(1.5).unwrap(),
            scatter: RayleighRice::new(Complex::new(1.5, 0.01)).unwrap(),
        };
        assert!(taken!(Full, Partial, &lossy));
        assert!(!taken!(Full, Partial, &lossy, Some(1.5)));
        let mixture = |m: usize| {
            let c = (0..m)
                .map(|j| GaussianPsd::<f64, 2>::isotropic(0.01, 1.0 + j as f64).unwrap())
                .collect();
            RoughConductor::new(GaussianMixturePsd::new(c).unwrap(), Complex::new(0.2, 3.4))
                .unwrap()
        };
        assert!(taken!(Full, Partial, &mixture(1)));
        assert!(taken!(OneShape, Incoherent, &mixture(8)));
        assert!(!taken!(Full, Partial, &mixture(9)));
    }

    #[test]
    fn the_bench_scene_runs_in_lanes() {
        in_lanes::<f64>();
        in_lanes::<f32>();
    }

    /// Glass (η = 1.5) lit at 30° from the air, or from inside: exits around the mirror and
    /// Snell's directions, alternating sides in every vector, all in lanes (none redone one at a
    /// time), both lobes lit on the transmission side; the constants from `lane_prep`.
    fn transmission_in_lanes<T: Real>(from_below: bool) {
        let theta_i = 30f64.to_radians();
        let up = if from_below { -1.0 } else { 1.0 };
        let travel = Vector3::new(theta_i.sin(), 0.0, -up * theta_i.cos()).map(T::lit);
        let packet = WavePacket::new(
            Stokes::new(T::one(), T::lit(0.3), T::lit(0.2), -T::lit(0.3)).unwrap(),
            CoherenceShape::isotropic(T::lit(5.0)).unwrap(),
            CoherenceShape::isotropic(T::lit(6.0)).unwrap(),
            Frame::sp(travel, Vector3::z()).unwrap(),
            T::lit(0.5),
        )
        .unwrap();
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let eta = T::lit(1.5);
        let corr =
            crate::gaussian::Gaussian::new(nalgebra::Matrix2::new(4.0, 1.2, 1.2, 2.0).map(T::lit))
                .unwrap();
        let psd = GaussianPsd::<T, 2>::from_autocorrelation(T::lit(4e-4), &corr).unwrap();
        let glass = crate::interaction::RoughDielectric::new(psd, eta).unwrap();
        let kernel = Kernel::<Full, Partial>::default();
        let facing = surface.facing(&-packet.direction());
        let prepared = kernel.prepare(&packet, &facing).unwrap();
        let prep = lane_prep(&kernel, &glass, &prepared, &packet, &surface, Some(eta))
            .expect("the lane constants");
        assert!(prep.three && prep.transmission.is_some());
        let eta_t = if from_below { 1.0 / 1.5 } else { 1.5 };
        let theta_t = (theta_i.sin() / eta_t).asin();
        let n = 64;
        let (mut x, mut y, mut z) = (vec![], vec![], vec![]);
        for i in 0..n {
            let (centre, side) = if i % 2 == 0 {
                (theta_i, up)
            } else {
                (theta_t, -up)
            };
            let to = centre + ((i / 2) as f64 / (n / 2) as f64 - 0.5) * 0.1;
            let po = ((i * 7 % n) as f64 / n as f64 - 0.5) * 0.2;
            x.push(T::lit(to.sin() * po.cos()));
            y.push(T::lit(to.sin() * po.sin()));
            z.push(T::lit(side * to.cos()));
        }
        let out = lanes_alone(&prep, [&x, &y, &z]);
        let far = |col: &[T]| {
            col.iter()
                .skip(1)
                .step_by(2)
                .filter(|v| **v > T::zero())
                .count()
        };
        assert_eq!(far(&out[4]), n / 2, "transmitted scattered lobe");
        assert!(far(&out[0]) > n / 4, "transmitted specular lobe");
        // And the lanes' values against the per-direction kernel, coarsely (10³ ε of the lobe's
        // S0: a wrong side, a missing factor or, with this anisotropic PSD, a PSD left
        // unmirrored from below would show; tests/interaction/batch/lobes.rs checks the documented
        // bound).
        for i in 0..n {
            let exit = Vector3::new(x[i], y[i], z[i]);
            let g = Geometry::for_packet_at_interface(&packet, &surface, eta, exit).unwrap();
            let r = kernel.evaluate(&glass, &packet, &g);
            let (sp, sc) = r.stokes().unwrap();
            for (lobe, want) in [(0, sp), (4, sc)] {
                for k in 0..4 {
                    let (a, b) = (out[lobe + k][i].to_f64(), want.0[k].to_f64());
                    let tol = 1e3 * T::EPSILON.to_f64() * want.s0().to_f64() + 1e-30;
                    assert!(
                        (a - b).abs() <= tol,
                        "exit {i} S{k}: lanes {a:e}, one at a time {b:e}"
                    );
                }
            }
        }
    }

    #[test]
    fn transmission_runs_in_lanes() {
        for below in [false, true] {
            transmission_in_lanes::<f64>(below);
            transmission_in_lanes::<f32>(below);
        }
    }
}
