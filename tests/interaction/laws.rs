//! Verifies physical laws of the S2.20 kernel (`gmueller::interaction`) against independent
//! computations made in this file: the plane-wave level equals the classical evaluation
//! `(cos θ_o/λ²) α M T S 2π p(h_t)` and Partial coherence tends to it (w → ∞) and to the
//! Incoherent level (w → 0); the model levels agree when `Θ_x = Θ_y`; the diffraction term peaks
//! at `h_t = 0` (the specular direction) and is even in `h_t`; Stokes validity is preserved
//! (proptest, f64 and f32, opaque surfaces and glass interfaces in all four cases); Helmholtz reciprocity of the plane-wave Rayleigh–Rice BRDF; the
//! known bugs of the authors' renderers (frame identity, `R_s` for s light, Malus with 2θ); the
//! documented geometry errors. Energy conservation is in `tests/interaction/energy.rs`.

use crate::common;

use std::f64::consts::{PI, TAU};

use common::oracle::{
    coherence_integral, exit_azimuth, mueller_literal, rayleigh_rice_factors, rotation_literal,
    section, sp_basis,
};
use common::{Tol, assert_all_close, assert_close};
use gmueller::Real;
use gmueller::error::Error;
use gmueller::frame::{Frame, frame_change_mueller};
use gmueller::interaction::coherence::{
    CoherenceModel, surface_coherence_term, surface_inverse_coherence,
};
use gmueller::interaction::pbsdf::{
    ConstantMueller, FresnelReflection, Pbsdf, PhaseScreen, RayleighRice,
};
use gmueller::interaction::polarization::{PolarizationModel, Response};
use gmueller::interaction::{
    Full, Geometry, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave, RoughDielectric,
    RoughSurface, Side,
};
use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::packet::{Channel, CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussianPsd};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector2, Vector3, Vector4};
use num_complex::Complex;
use proptest::prelude::*;

use common::scene::{
    DEG, Glass, dir, eval, fresnel_rs_rp, glass, packet, rel_diff, surface, travel,
};

// ------------------------------------------------------------------ 1. limits and levels

/// The plane-wave level against `(cos θ_o/λ²) α M_scat T S 2π p(h_t)` computed here, without
/// the crate: directions, `h_t`, `α` and the Gaussian PSD in closed form; `M` the literal S1.7
/// `A_mül (J* ⊗ J) A_mül⁻¹` of Germer's Rayleigh–Rice Jones matrix `2k cos θ_i [[ss, ps], [sp,
/// pp]]` (`tests/common/oracle.rs`); `T = A_mül (τ ⊗ τ) A_mül⁻¹` with S2.3's τ from dot products
/// of the packet frame (turned away from s/p) with the incident s/p basis built here.
#[test]
fn plane_wave_level_equals_classical_evaluation() {
    let (lambda, sigma, ell) = (0.5, 0.03, 2.0);
    let k = TAU / lambda;
    let material = glass(sigma, ell);
    let eps = Complex::new(1.5 * 1.5, 0.0);
    let n = Vector3::z();
    let cases = [
        (30.0, 35.0, 10.0, 0.4, [1.0, 0.3, -0.5, 0.2]),
        (0.0, 5.0, 80.0, -1.2, [2.0, 0.0, 0.0, 2.0]),
        (60.0, 58.0, -3.0, 2.0, [1.0, -1.0, 0.0, 0.0]),
        (75.0, 70.0, 175.0, 0.1, [1.0, 0.2, 0.2, 0.2]),
        (45.0, 47.0, 0.0, 0.0, [1.0, 0.0, 0.0, 0.0]),
    ];
    for (ti, to, po, psi, s) in cases {
        let (ti, to, po) = (ti * DEG, to * DEG, po * DEG);
        let pk = packet(s, 7.0, ti, psi, lambda);
        let exit = dir::<f64>(to, po);
        // Independent quantities.
        let s_hat = -travel::<f64>(ti);
        let (ci, co) = (s_hat.z, exit.z);
        let h = (exit + s_hat) * k;
        let ht = Vector2::new(h.x, h.y);
        let alpha = (-(k * sigma * (ci + co)).powi(2)).exp();
        let p = sigma * sigma * ell * ell * (-0.5 * ell * ell * ht.norm_squared()).exp();
        let (sp_in, sp_out) = (sp_basis(&-s_hat, &n), sp_basis(&exit, &n));
        let (cphi, sphi) = exit_azimuth(&sp_in[0], &sp_out[0], &n);
        if ti > 0.0 {
            // Away from normal incidence φ is the plain azimuth difference (here φ_i = 0).
            assert_close("cos φ", cphi, po.cos(), Tol::new(1e-14, 0.0));
            assert_close("sin φ", sphi, po.sin(), Tol::new(1e-14, 0.0));
        }
        let j = rayleigh_rice_factors(eps, ci, co, cphi, sphi) * Complex::new(2.0 * k * ci, 0.0);
        let m = mueller_literal(&j);
        let t = rotation_literal([pk.frame().x(), pk.frame().y()], sp_in);
        let sv = Vector4::from(s);
        let expected = m * t * sv * (co / (lambda * lambda) * alpha * TAU * p);
        let what = format!("θi={ti:.3} θo={to:.3} φo={po:.3}");
        let tol = Tol::new(1e-13 * expected.norm(), 1e-11);
        let full = eval::<Full, PlaneWave, _, _>(&material, &pk, exit);
        assert_all_close(
            &format!("Full scattered {what}"),
            full.scattered.vector().iter().copied(),
            expected.iter().copied(),
            tol,
        );
        assert_eq!(
            full.specular.vector(),
            Vector4::zeros(),
            "no lobe for a plane wave"
        );
        assert_close("attenuation", full.attenuation, alpha, Tol::new(0.0, 1e-13));
        let one = eval::<OneShape, PlaneWave, _, _>(&material, &pk, exit);
        assert_all_close(
            &format!("OneShape scattered {what}"),
            one.scattered.vector().iter().copied(),
            expected.iter().copied(),
            tol,
        );
        // Intensity: M₀₀ S0 only.
        let scalar = eval::<Intensity, PlaneWave, _, _>(&material, &pk, exit);
        assert_close(
            &format!("Intensity scattered {what}"),
            scalar.scattered,
            m[(0, 0)] * s[0] * co / (lambda * lambda) * alpha * TAU * p,
            Tol::new(0.0, 1e-11),
        );
    }
}

/// The deviation of `Partial` (at the `OneShape` and `Full` levels) from `PlaneWave` as the width
/// grows, and from `Incoherent` as it shrinks, printed and asserted monotone with a final bound.
#[test]
fn partial_coherence_tends_to_plane_wave_and_incoherent_limits() {
    let (lambda, sigma, ell) = (0.5, 0.02, 2.0);
    let material = glass(sigma, ell);
    let (ti, to, po) = (40.0 * DEG, 44.0 * DEG, 6.0 * DEG);
    let exit = dir::<f64>(to, po);
    let frame = Frame::sp(travel::<f64>(ti), Vector3::z())
        .unwrap()
        .rotated(0.3);
    // Θ_y = 1.3² Θ_x; correlation inside the realizability bound.
    let make = |w: f64| {
        let (wx, wy) = (w, 1.3 * w);
        let sx = CoherenceShape::isotropic(wx).unwrap();
        let sy = CoherenceShape::isotropic(wy).unwrap();
        WavePacket::new(
            Stokes::new(1.0, 0.2, 0.3, -0.2).unwrap(),
            sx,
            sy,
            frame,
            lambda,
        )
        .unwrap()
    };
    fn level<Pol: PolarizationModel<Output<f64> = Response<f64>>>(
        material: &Glass,
        make: &dyn Fn(f64) -> WavePacket<f64>,
        exit: Vector3<f64>,
        name: &str,
    ) {
        let mut last = f64::INFINITY;
        let mut dev = f64::NAN;
        for w in [3.0, 30.0, 300.0, 3e3, 3e4] {
            let pk = make(w);
            let part = eval::<Pol, Partial, _, _>(material, &pk, exit);
            let pw = eval::<Pol, PlaneWave, _, _>(material, &pk, exit);
            dev = rel_diff(&part.scattered.vector(), &pw.scattered.vector());
            println!("{name}: w = {w:>7} µm  |Partial − PlaneWave|/|PlaneWave| = {dev:.3e}");
            assert!(
                dev < last,
                "{name}: deviation must shrink ({dev:e} after {last:e})"
            );
            last = dev;
        }
        assert!(dev < 1e-6, "{name}: deviation at w = 3e4 µm is {dev:e}");
        let mut last = f64::INFINITY;
        for w in [0.5, 0.1, 0.02, 0.004] {
            let pk = make(w);
            let part = eval::<Pol, Partial, _, _>(material, &pk, exit);
            let inc = eval::<Pol, Incoherent, _, _>(material, &pk, exit);
            dev = rel_diff(&part.scattered.vector(), &inc.scattered.vector());
            println!("{name}: w = {w:>7} µm  |Partial − Incoherent|/|Incoherent| = {dev:.3e}");
            assert!(
                dev < last,
                "{name}: deviation must shrink ({dev:e} after {last:e})"
            );
            // The specular lobe is the same function at both levels.
            assert_all_close(
                "specular Partial vs Incoherent",
                part.specular.vector().iter().copied(),
                inc.specular.vector().iter().copied(),
                Tol::new(0.0, 1e-13),
            );
            last = dev;
        }
        // Relative deviation ~ (w/ℓ)²: 4e-6 at w = 0.004 µm, ℓ = 2 µm.
        assert!(dev < 1e-4, "{name}: deviation at w = 0.004 µm is {dev:e}");
    }
    level::<OneShape>(&material, &make, exit, "OneShape");
    level::<Full>(&material, &make, exit, "Full");
}

/// With `Θ_x = Θ_y`: `Full` equals `OneShape` to rounding; `Intensity` equals S0 of `OneShape` for
/// unpolarized light (any M), and for any light when M is a multiple of the identity (the scalar
/// level ignores diattenuation by design: it keeps `M₀₀ S0`).
#[test]
fn levels_agree_for_a_single_shape() {
    let lambda = 0.6;
    let material = glass(0.02, 1.5);
    let screen = RoughSurface {
        psd: GaussianPsd::isotropic(0.02, 1.5).unwrap(),
        specular: ConstantMueller(
            Mueller::from_matrix(nalgebra::Matrix4::identity() * 0.8).unwrap(),
        ),
        scatter: PhaseScreen::new(0.9).unwrap(),
    };
    for (ti, to, po, w, psi) in [
        (20.0, 21.0, 1.0, 4.0, 0.7),
        (0.0, 1.0, 90.0, 1.0, -0.3),
        (70.0, 69.5, 0.5, 30.0, 2.5),
    ] {
        let (ti, to, po) = (ti * DEG, to * DEG, po * DEG);
        let exit = dir::<f64>(to, po);
        let pol = packet([1.0, 0.3, 0.4, -0.5], w, ti, psi, lambda);
        let unpol = packet([1.0, 0.0, 0.0, 0.0], w, ti, psi, lambda);
        macro_rules! coh {
            ($coh:ty) => {{
                let full = eval::<Full, $coh, _, _>(&material, &pol, exit);
                let one = eval::<OneShape, $coh, _, _>(&material, &pol, exit);
                for (a, b, what) in [
                    (full.specular, one.specular, "specular"),
                    (full.scattered, one.scattered, "scattered"),
                ] {
                    let scale = b.vector().norm();
                    assert_all_close(
                        &format!("Full vs OneShape {what} {}", stringify!($coh)),
                        a.vector().iter().copied(),
                        b.vector().iter().copied(),
                        Tol::new(1e-14 * scale, 1e-13),
                    );
                }
                let one = eval::<OneShape, $coh, _, _>(&material, &unpol, exit);
                let sc = eval::<Intensity, $coh, _, _>(&material, &unpol, exit);
                assert_close(
                    "Intensity vs OneShape S0 (spec)",
                    sc.specular,
                    one.specular.s0(),
                    Tol::new(1e-300, 1e-13),
                );
                assert_close(
                    "Intensity vs OneShape S0 (scat)",
                    sc.scattered,
                    one.scattered.s0(),
                    Tol::new(1e-300, 1e-13),
                );
                let one = eval::<OneShape, $coh, _, _>(&screen, &pol, exit);
                let sc = eval::<Intensity, $coh, _, _>(&screen, &pol, exit);
                assert_close(
                    "Intensity vs OneShape S0 (screen spec)",
                    sc.specular,
                    one.specular.s0(),
                    Tol::new(1e-300, 1e-13),
                );
                assert_close(
                    "Intensity vs OneShape S0 (screen scat)",
                    sc.scattered,
                    one.scattered.s0(),
                    Tol::new(1e-300, 1e-13),
                );
            }};
        }
        coh!(PlaneWave);
        coh!(Partial);
        coh!(Incoherent);
    }
}

// ------------------------------------------------------------------ 2. the lobe's centre

/// The diffraction term `𝒟` (`surface_coherence_term`) and the specular weight, scanned over exit
/// directions in the plane of incidence (0.01° steps), peak at the specular direction, and are even
/// in `h_t`. Also prints where the whole lobe (`cos θ_o` and the pBSDF included) peaks.
#[test]
fn diffraction_term_is_centred_on_the_specular_direction() {
    let lambda = 0.5;
    let k = TAU / lambda;
    let step = 0.01;
    for (ti_deg, w, sigma, ell) in [
        (30.0, 2.0, 0.01, 2.0),
        (60.0, 0.7, 0.05, 0.5),
        (10.0, 20.0, 0.02, 5.0),
        (75.0, 5.0, 0.02, 1.0),
    ] {
        let ti = ti_deg * DEG;
        let material = glass(sigma, ell);
        let pk = packet([1.0, 0.0, 0.0, 0.0], w, ti, 0.0, lambda);
        let xi = surface_inverse_coherence(&pk, Channel::Half, &surface()).unwrap();
        let (mut best_term, mut best_spec, mut best_full) =
            ((f64::MIN, 0.0), (f64::MIN, 0.0), (f64::MIN, 0.0));
        let n = (178.0 / step) as i64;
        for i in 0..=n {
            let to_deg = -89.0 + i as f64 * step;
            let exit = Vector3::new((to_deg * DEG).sin(), 0.0, (to_deg * DEG).cos());
            let g = Geometry::for_packet(&pk, &surface(), exit).unwrap();
            let term = surface_coherence_term(
                &material.psd,
                &ClosedForm,
                &pk,
                Channel::Half,
                &surface(),
                &g.h_t(),
            );
            let spec = Partial(ClosedForm).specular_weight(Some(&xi), &g.h_t());
            let full = Kernel::<Full, Partial>::default()
                .evaluate(&material, &pk, &g)
                .total()
                .s0();
            for (best, v) in [
                (&mut best_term, term),
                (&mut best_spec, spec),
                (&mut best_full, full),
            ] {
                if v > best.0 {
                    *best = (v, to_deg);
                }
            }
        }
        for (what, best) in [("𝒟", best_term), ("specular weight", best_spec)] {
            assert!(
                (best.1 - ti_deg).abs() <= step * 0.5 + 1e-9,
                "{what} peaks at θo = {}°, specular is {ti_deg}°",
                best.1
            );
        }
        println!(
            "θi = {ti_deg}°, w = {w} µm, σ = {sigma} µm, ℓ = {ell} µm: 𝒟 peaks at {:.2}°, \
             the full lobe (Full×Partial, Fresnel+RR, unpolarized) at {:.2}°",
            best_term.1, best_full.1
        );
        // Evenness in h_t: exit directions with h_t = ±a x̂ in the plane of incidence, and
        // arbitrary ±h_t vectors off the plane.
        for a in [0.05 * k, 0.2 * k, 0.4 * k] {
            let so = |sign: f64| ti.sin() + sign * a / k;
            if so(1.0).abs() >= 1.0 || so(-1.0).abs() >= 1.0 {
                continue;
            }
            let term_at = |sin_o: f64| {
                let exit = Vector3::new(sin_o, 0.0, (1.0 - sin_o * sin_o).sqrt());
                let g = Geometry::for_packet(&pk, &surface(), exit).unwrap();
                assert_close(
                    "h_t.x",
                    g.h_t().x,
                    (sin_o - ti.sin()) * k,
                    Tol::new(1e-12 * k, 0.0),
                );
                surface_coherence_term(
                    &material.psd,
                    &ClosedForm,
                    &pk,
                    Channel::Half,
                    &surface(),
                    &g.h_t(),
                )
            };
            assert_close(
                "𝒟(+a) vs 𝒟(−a)",
                term_at(so(1.0)),
                term_at(so(-1.0)),
                Tol::new(1e-300, 1e-12),
            );
        }
        for h in [
            Vector2::new(1.0, 2.0),
            Vector2::new(-3.0, 0.5),
            Vector2::new(0.2, -4.0),
        ] {
            let t = |h: Vector2<f64>| {
                surface_coherence_term(
                    &material.psd,
                    &ClosedForm,
                    &pk,
                    Channel::Half,
                    &surface(),
                    &h,
                )
            };
            assert_close("𝒟(h) vs 𝒟(−h)", t(h), t(-h), Tol::new(1e-300, 1e-12));
            assert_close(
                "lobe(h) vs lobe(−h)",
                Partial(ClosedForm).specular_weight(Some(&xi), &h),
                Partial(ClosedForm).specular_weight(Some(&xi), &(-h)),
                Tol::new(1e-300, 1e-12),
            );
        }
    }
}

// ------------------------------------------------------------------ 3. Stokes validity

#[derive(Debug, Clone)]
struct ValidityCase {
    stokes: [f64; 4],
    shape_x: Matrix2<f64>,
    shape_y: Matrix2<f64>,
    theta_i: f64,
    theta_o: f64,
    phi_o: f64,
    psi: f64,
    sigma: f64,
    ell: f64,
    lambda: f64,
    metal: bool,
    /// `None`: an opaque surface lit from above; `Some((from_below, transmit))`: a glass
    /// interface (η = 1.5 below), the source on either side, the exit on either side.
    interface: Option<(bool, bool)>,
}

/// Widths 0.3–50 λ, any orientation.
fn shape() -> impl Strategy<Value = Matrix2<f64>> {
    gmueller::verify::strategy::coherence_shape(0.3, 50.0, PI)
}

fn validity_case() -> impl Strategy<Value = ValidityCase> {
    let theta_i = prop_oneof![Just(0.0), 0.0..1e-6f64, 0.0..(85.0 * DEG)];
    (
        common::stokes_vector(),
        shape(),
        shape(),
        theta_i,
        0.0..(85.0 * DEG),
        -PI..PI,
        -PI..PI,
        (1e-3..0.2f64, 0.3..5.0f64, 0.4..1.0f64, any::<bool>()),
        prop_oneof![Just(None), any::<(bool, bool)>().prop_map(Some)],
    )
        .prop_map(
            |(
                s,
                shape_x,
                shape_y,
                theta_i,
                theta_o,
                phi_o,
                psi,
                (sigma, ell, lambda, metal),
                interface,
            )| {
                // Scale the correlation into the realizability bound |μ|² ≤ √(|Θx||Θy|)/|Θ½|.
                let bound = (shape_x.determinant() * shape_y.determinant()).sqrt()
                    / ((shape_x + shape_y) * 0.5).determinant();
                let four_sxsy = s[0] * s[0] - s[1] * s[1];
                let mu2 = (s[2] * s[2] + s[3] * s[3]) / four_sxsy.max(1e-300);
                let scale = if mu2 > bound * (1.0 - 1e-3) {
                    (bound * (1.0 - 1e-3) / mu2).sqrt()
                } else {
                    1.0
                };
                ValidityCase {
                    stokes: [s[0], s[1], s[2] * scale, s[3] * scale],
                    shape_x,
                    shape_y,
                    theta_i,
                    theta_o,
                    phi_o,
                    psi,
                    sigma,
                    ell,
                    lambda,
                    metal,
                    interface,
                }
            },
        )
}

/// Checks `S0 ≥ 0` and `|S| ≤ S0` within `rel` (relative; `abs` for outputs that underflowed),
/// for every part of every level — on an opaque surface, or at a glass interface from either
/// side in reflection and transmission (beyond the critical angle too).
fn check_validity<T: Real>(c: &ValidityCase, rel: f64, abs: f64) -> Result<(), TestCaseError> {
    let lit = |m: Matrix2<f64>| m.map(T::lit);
    let (from_below, transmit) = c.interface.unwrap_or((false, false));
    let mirror = |v: Vector3<T>| Vector3::new(v.x, v.y, -v.z);
    let travel_dir = if from_below {
        mirror(travel::<T>(c.theta_i))
    } else {
        travel::<T>(c.theta_i)
    };
    let frame = Frame::sp(travel_dir, Vector3::z())
        .unwrap()
        .rotated(T::lit(c.psi));
    let s = c.stokes.map(T::lit);
    let stokes = Stokes::new(s[0], s[1], s[2], s[3]).unwrap();
    let pk = WavePacket::new(
        stokes,
        CoherenceShape::new(lit(c.shape_x)).unwrap(),
        CoherenceShape::new(lit(c.shape_y)).unwrap(),
        frame,
        T::lit(c.lambda),
    )
    .unwrap();
    let eta = if c.metal {
        Complex::new(T::lit(0.18), T::lit(3.0))
    } else {
        Complex::new(T::lit(1.5), T::zero())
    };
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(c.sigma), T::lit(c.ell)).unwrap();
    if c.interface.is_some() {
        // Exit on the source's side (reflection) or across (transmission).
        let up = dir::<T>(c.theta_o, c.phi_o);
        let exit = if from_below != transmit {
            mirror(up)
        } else {
            up
        };
        let material = RoughDielectric::new(psd, T::lit(1.5)).unwrap();
        let g = material.geometry_for_packet(&pk, &surface(), exit).unwrap();
        let side = if transmit {
            Side::Transmission
        } else {
            Side::Reflection
        };
        prop_assert_eq!(g.side(), side);
        return check_levels(&material, &pk, &g, rel, abs);
    }
    let material = RoughSurface {
        psd,
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    };
    let g = Geometry::for_packet(&pk, &surface(), dir::<T>(c.theta_o, c.phi_o)).unwrap();
    check_levels(&material, &pk, &g, rel, abs)
}

/// The validity checks of [`check_validity`] for one material and geometry.
fn check_levels<T: Real, Sp: Pbsdf<T>, Sc: Pbsdf<T>>(
    material: &RoughSurface<GaussianPsd<T, 2>, Sp, Sc>,
    pk: &WavePacket<T>,
    g: &Geometry<T>,
    rel: f64,
    abs: f64,
) -> Result<(), TestCaseError> {
    let check = |what: &str, st: Stokes<T>| -> Result<(), TestCaseError> {
        // Scale before squaring: outputs of ~1e-162 would square into subnormals.
        let raw = st.vector().map(|x| x.to_f64());
        let scale = raw.amax();
        let v = if scale > 0.0 { raw / scale } else { raw };
        let pol = (v[1] * v[1] + v[2] * v[2] + v[3] * v[3]).sqrt();
        prop_assert!(
            raw.iter().all(|x| x.is_finite()),
            "{what}: non-finite {raw:?}"
        );
        prop_assert!(raw[0] >= -abs, "{what}: S0 < 0: {raw:?}");
        // In units of the largest component: |S| ≤ S0 (1 + rel), or all below `abs`.
        prop_assert!(
            pol <= v[0] * (1.0 + rel) || scale <= abs,
            "{what}: |S| > S0: {raw:?} (|S|/S0 − 1 = {:e})",
            pol / v[0] - 1.0
        );
        Ok(())
    };
    macro_rules! level {
        ($pol:ty, $coh:ty) => {{
            let r = Kernel::<$pol, $coh>::default().evaluate(material, pk, g);
            let name = concat!(stringify!($pol), "×", stringify!($coh));
            check(&format!("{name} specular"), r.specular)?;
            check(&format!("{name} scattered"), r.scattered)?;
            check(&format!("{name} total"), r.total())?;
        }};
    }
    level!(Full, Partial);
    level!(Full, Incoherent);
    level!(Full, PlaneWave);
    level!(OneShape, Partial);
    // The intensity level: S0 only, finite and non-negative.
    let r = Kernel::<Intensity, Partial>::default().evaluate(material, pk, g);
    for (what, x) in [("specular", r.specular), ("scattered", r.scattered)] {
        let x = x.to_f64();
        prop_assert!(x.is_finite() && x >= 0.0, "Intensity×Partial {what}: {x:e}");
    }
    Ok(())
}

proptest! {
    #![proptest_config(common::proptest_config(256))]

    /// f64: `S0 ≥ |S|` within 1e-9 relative (abs 1e-300 for underflowed outputs).
    #[test]
    fn stokes_validity_is_preserved_f64(c in validity_case()) {
        check_validity::<f64>(&c, 1e-9, 1e-300)?;
    }

    /// f32: within 1e-4 relative (abs 1e-30).
    #[test]
    fn stokes_validity_is_preserved_f32(c in validity_case()) {
        check_validity::<f32>(&c, 1e-4, 1e-30)?;
    }
}

// ------------------------------------------------------------------ 4. reciprocity

/// The plane-wave scalar BRDF `f = L/(S0 cos θ_i)` for light from `src` (toward the source)
/// leaving along `out`.
fn scalar_brdf<Sc: Pbsdf<f64>>(scatter: Sc, src: Vector3<f64>, out: Vector3<f64>) -> f64 {
    let lambda = 0.5;
    let material = RoughSurface {
        psd: GaussianPsd::isotropic(0.01, 1.0).unwrap(),
        specular: FresnelReflection::new(Complex::new(1.5, 0.0)).unwrap(),
        scatter,
    };
    let frame = Frame::sp(-src, Vector3::z()).unwrap();
    let pk = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(10.0).unwrap(),
        frame,
        lambda,
    )
    .unwrap();
    let r = eval::<Intensity, PlaneWave, _, _>(&material, &pk, out);
    r.scattered / src.z
}

/// Helmholtz reciprocity `f(ŝ → r̂) = f(r̂ → ŝ)` of the plane-wave Rayleigh–Rice BRDF holds to
/// 1e-12. The phase screen is *not* reciprocal as a BRDF: its `M = |r|² v² I` lacks the
/// `cos θ_i` obliquity factor that the Rayleigh–Rice Jones matrix carries (`2k cos θ_i`), so
/// `f(ŝ → r̂)/f(r̂ → ŝ) = (cos θ_o/cos θ_i)²` exactly — asserted here as the model's property
/// (the Kirchhoff phase-screen, like the original Harvey–Shack model, is not reciprocal).
#[test]
fn helmholtz_reciprocity_of_the_plane_wave_brdf() {
    let rr = RayleighRice::new(Complex::new(1.5, 0.0)).unwrap();
    let metal = RayleighRice::new(Complex::new(0.18, 3.0)).unwrap();
    let screen = PhaseScreen::new(1.0).unwrap();
    for (ta, pa, tb, pb) in [
        (30.0, 180.0, 40.0, 10.0),
        (10.0, 170.0, 70.0, -30.0),
        (60.0, 200.0, 5.0, 90.0),
        (80.0, 135.0, 20.0, 0.0),
    ] {
        let (a, b) = (
            dir::<f64>(ta * DEG, pa * DEG),
            dir::<f64>(tb * DEG, pb * DEG),
        );
        for (name, f_ab, f_ba) in [
            ("RR glass", scalar_brdf(rr, a, b), scalar_brdf(rr, b, a)),
            (
                "RR metal",
                scalar_brdf(metal, a, b),
                scalar_brdf(metal, b, a),
            ),
        ] {
            assert!(f_ab > 0.0, "{name}: positive BRDF");
            assert_close(
                &format!("{name} reciprocity {ta},{pa} ↔ {tb},{pb}"),
                f_ab,
                f_ba,
                Tol::new(0.0, 1e-12),
            );
        }
        let (f_ab, f_ba) = (scalar_brdf(screen, a, b), scalar_brdf(screen, b, a));
        let expected = (b.z / a.z).powi(2);
        println!(
            "phase screen: f(a→b)/f(b→a) = {:.6} (θa = {ta}°, θb = {tb}°)",
            f_ab / f_ba
        );
        assert_close(
            "phase-screen reciprocity ratio",
            f_ab / f_ba,
            expected,
            Tol::new(0.0, 1e-12),
        );
    }
}

// ------------------------------------------------------------------ 6. the authors' known bugs

/// Frame identity: the kernel with the packet in the incident s/p frame applies no rotation
/// (`T = I` exactly; its output equals `(cos θ_o/λ²) α K M S` computed here without the crate),
/// and the same light described in a turned frame gives the same output.
#[test]
fn frame_rotation_is_identity_for_identical_frames() {
    let lambda = 0.5;
    let material = glass(0.02, 1.5);
    let ti = 35.0 * DEG;
    let exit = dir::<f64>(38.0 * DEG, 12.0 * DEG);
    let pk = packet([1.0, 0.4, -0.3, 0.5], 5.0, ti, 0.0, lambda);
    let g = Geometry::for_packet(&pk, &surface(), exit).unwrap();
    assert_eq!(
        frame_change_mueller(pk.frame(), g.incident_sp()).matrix(),
        nalgebra::Matrix4::identity(),
        "T between the packet's s/p frame and the geometry's incident s/p frame"
    );
    let base = eval::<Full, Partial, _, _>(&material, &pk, exit);
    // Independent (tests/common/oracle.rs): without T, L = (cos θ_o/λ²) α K M S, with the
    // section Ξ = Bᵀ Q Θ⁻¹ Qᵀ B, the Gaussian-PSD blur K = σ² 2π |G|^{−1/2} exp(−½ h_tᵀ G⁻¹ h_t),
    // G = I/ℓ² + Ξ, and M the literal S1.7 Mueller matrix of Germer's Jones matrix.
    let (sigma, ell, w) = (0.02, 1.5, 5.0);
    let k = TAU / lambda;
    let n = Vector3::z();
    let s_hat = -travel::<f64>(ti);
    let (ci, co) = (s_hat.z, exit.z);
    let h = (exit + s_hat) * k;
    let ht = Vector2::new(h.x, h.y);
    let f = pk.frame();
    let q = nalgebra::Matrix3::from_columns(&[f.x(), f.y(), f.k()]);
    let xi = section(
        &q,
        &(Matrix2::identity() * (w * w)),
        0.0,
        &Vector3::x(),
        &Vector3::y(),
    );
    let kd = coherence_integral(
        sigma * sigma,
        &(Matrix2::identity() / (ell * ell)),
        &xi,
        &ht,
    );
    let alpha = (-(k * sigma * (ci + co)).powi(2)).exp();
    assert_close("attenuation", base.attenuation, alpha, Tol::new(0.0, 1e-13));
    let (sp_in, sp_out) = (sp_basis(&-s_hat, &n), sp_basis(&exit, &n));
    let (cphi, sphi) = exit_azimuth(&sp_in[0], &sp_out[0], &n);
    let eps = Complex::new(1.5 * 1.5, 0.0);
    let m = mueller_literal(
        &(rayleigh_rice_factors(eps, ci, co, cphi, sphi) * Complex::new(2.0 * k * ci, 0.0)),
    );
    let stokes = Vector4::new(1.0, 0.4, -0.3, 0.5);
    let expected = m * stokes * (co / (lambda * lambda) * alpha * kd);
    assert_all_close(
        "no rotation in the s/p frame",
        base.scattered.vector().iter().copied(),
        expected.iter().copied(),
        Tol::new(1e-14 * expected.norm(), 1e-12),
    );
    for psi in [0.3, 1.0, -2.2, PI] {
        let turned = pk.rotated(psi);
        let r = eval::<Full, Partial, _, _>(&material, &turned, exit);
        for (a, b, what) in [
            (r.specular, base.specular, "specular"),
            (r.scattered, base.scattered, "scattered"),
        ] {
            assert_all_close(
                &format!("{what}: packet frame turned by {psi}"),
                a.vector().iter().copied(),
                b.vector().iter().copied(),
                Tol::new(1e-13 * b.vector().norm(), 1e-12),
            );
        }
    }
}

/// s-polarized light on a smooth Fresnel surface: the specular output is `∝ R_s` (and p light
/// `∝ R_p`), with `R_s`, `R_p` from the textbook formulas — relative to the unpolarized output and
/// in absolute terms, the lobe constant computed here; s stays s (S1 = S0) in the exit frame.
/// Near Brewster's angle the p output vanishes.
#[test]
fn fresnel_uses_rs_for_s_polarized_light() {
    let lambda = 0.5;
    let material = glass(1e-4, 2.0);
    for ti_deg in [20.0, 45.0, 56.309932474020215, 70.0] {
        let ti = ti_deg * DEG;
        let exit = dir::<f64>(ti, 0.0);
        let s_light = packet([1.0, 1.0, 0.0, 0.0], 10.0, ti, 0.0, lambda);
        let p_light = packet([1.0, -1.0, 0.0, 0.0], 10.0, ti, 0.0, lambda);
        let unpol = packet([1.0, 0.0, 0.0, 0.0], 10.0, ti, 0.0, lambda);
        let rs_out = eval::<Full, Partial, _, _>(&material, &s_light, exit).specular;
        let rp_out = eval::<Full, Partial, _, _>(&material, &p_light, exit).specular;
        let un = eval::<Full, Partial, _, _>(&material, &unpol, exit).specular;
        let (rs, rp) = fresnel_rs_rp(ti.cos(), 1.5);
        // Unpolarized output S0 ∝ (R_s + R_p)/2: the common factor, also computed here —
        // (cos θ_o/λ²) α K_spec with the lobe K_spec = 2π |Ξ|^{−1/2} at h_t = 0 (the S2.10
        // integral with R ≡ 1, tests/common/oracle.rs) and α = exp(−(2kσ cos θ_i)²).
        let scale = un.s0() / ((rs + rp) * 0.5);
        let f = s_light.frame();
        let q = nalgebra::Matrix3::from_columns(&[f.x(), f.y(), f.k()]);
        let xi = section(
            &q,
            &(Matrix2::identity() * 100.0),
            0.0,
            &Vector3::x(),
            &Vector3::y(),
        );
        let lobe = coherence_integral(1.0, &Matrix2::zeros(), &xi, &Vector2::zeros());
        let k = TAU / lambda;
        let alpha = (-(2.0 * k * 1e-4 * ti.cos()).powi(2)).exp();
        let front = ti.cos() / (lambda * lambda) * alpha * lobe;
        assert_close(
            "s light, absolute",
            rs_out.s0(),
            front * rs,
            Tol::new(0.0, 1e-12),
        );
        assert_close(
            "p light, absolute",
            rp_out.s0(),
            front * rp,
            Tol::new(1e-14 * front, 1e-12),
        );
        assert_close(
            &format!("s light at {ti_deg}°"),
            rs_out.s0() / scale,
            rs,
            Tol::new(1e-14, 1e-12),
        );
        assert_close(
            &format!("p light at {ti_deg}°"),
            rp_out.s0() / scale,
            rp,
            Tol::new(1e-14, 1e-12),
        );
        assert_close(
            "s stays s",
            rs_out.s1(),
            rs_out.s0(),
            Tol::new(1e-300, 1e-12),
        );
    }
}

/// A linear polarizer at θ (`ConstantMueller` of `JonesMatrix::linear_polarizer(θ)`) as the
/// specular pBSDF, on x̂-polarized light in the s/p frame: the output follows Malus `cos²θ`
/// (a θ-instead-of-2θ bug would give `(1 + cos θ)/2`), and its Mueller matrix is the textbook
/// `½[[1, c, s, 0], [c, c², cs, 0], [s, cs, s², 0], [0, 0, 0, 0]]`, `c = cos 2θ`, `s = sin 2θ`.
#[test]
fn polarizer_through_the_kernel_follows_malus() {
    let lambda = 0.5;
    let ti = 25.0 * DEG;
    let exit = dir::<f64>(ti, 0.0);
    let light = packet([1.0, 1.0, 0.0, 0.0], 10.0, ti, 0.0, lambda);
    let out = |theta: f64| {
        let m = Mueller::from_jones(&JonesMatrix::linear_polarizer(theta));
        let material = RoughSurface {
            psd: GaussianPsd::isotropic(1e-4, 2.0).unwrap(),
            specular: ConstantMueller(m),
            scatter: ConstantMueller(m),
        };
        eval::<Full, Partial, _, _>(&material, &light, exit).specular
    };
    let i0 = out(0.0).s0();
    for theta_deg in [10.0, 30.0, 45.0, 60.0, 90.0, 135.0] {
        let theta = theta_deg * DEG;
        assert_close(
            &format!("Malus at {theta_deg}°"),
            out(theta).s0() / i0,
            theta.cos().powi(2),
            Tol::new(1e-14, 1e-12),
        );
        let m = Mueller::from_jones(&JonesMatrix::linear_polarizer(theta)).matrix();
        let (s, c) = (2.0 * theta).sin_cos();
        let textbook = [
            [1.0, c, s, 0.0],
            [c, c * c, c * s, 0.0],
            [s, c * s, s * s, 0.0],
            [0.0, 0.0, 0.0, 0.0],
        ];
        for r in 0..4 {
            for col in 0..4 {
                assert_close(
                    "polarizer Mueller",
                    m[(r, col)],
                    0.5 * textbook[r][col],
                    Tol::new(1e-15, 1e-14),
                );
            }
        }
    }
}

// ------------------------------------------------------------------ 7. geometry errors

/// Source or exit direction on or below the surface, zero and non-finite directions: the
/// documented errors of `Geometry::new`.
#[test]
fn geometry_rejects_directions_below_the_horizon() {
    let k = TAU / 0.5;
    let up = Vector3::new(0.3, 0.1, 0.9);
    let s = surface::<f64>();
    for (src, exit, which) in [
        (Vector3::new(0.3, 0.0, -0.1), up, "cos θ_i"),
        (Vector3::new(1.0, 0.0, 0.0), up, "cos θ_i"),
        (up, Vector3::new(0.2, 0.2, -0.5), "cos θ_o"),
        (up, Vector3::new(0.0, 1.0, 0.0), "cos θ_o"),
    ] {
        match Geometry::new(k, &s, src, exit) {
            Err(Error::OutOfRange {
                what,
                value,
                expected,
            }) => {
                assert!(what.starts_with(which), "{what} should name {which}");
                assert!(value <= 0.0 && expected == "> 0");
            }
            other => panic!("expected OutOfRange for {which}, got {other:?}"),
        }
    }
    assert!(matches!(
        Geometry::new(k, &s, Vector3::zeros(), up),
        Err(Error::InvalidBasis { .. })
    ));
    assert!(matches!(
        Geometry::new(k, &s, up, Vector3::new(f64::NAN, 0.0, 1.0)),
        Err(Error::NonFinite { .. })
    ));
    // The packet form: a packet travelling upward has its source below.
    let pk = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(1.0).unwrap(),
        Frame::sp(Vector3::new(0.1, 0.0, 1.0), Vector3::z()).unwrap(),
        0.5,
    )
    .unwrap();
    assert!(matches!(
        Geometry::for_packet(&pk, &s, up),
        Err(Error::OutOfRange { .. })
    ));
}
