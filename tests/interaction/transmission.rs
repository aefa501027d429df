//! Verifies the S2.20 kernel in transmission through a rough interface between two dielectrics,
//! from either side: the phase factor against explicitly propagated plane waves, the coherent
//! transmitted lobe against the textbook Fresnel transmittance, Brewster's angle and total
//! internal reflection, the first-order scattering against its Kirchhoff (phase-screen) limit,
//! energy conservation of reflection plus transmission (bounded by the first-order truncation),
//! generalized reciprocity of the plane-wave BTDF, the continuity of the levels into their
//! plane-wave and incoherent limits, the exitant packet in the new medium, and what a small
//! absorption would change. The peer values (SCATMECH for all four cases, Mitsuba's Fresnel
//! transmission) are in `tests/interaction/reference.rs`; the brute-force wave optics in
//! `validation/src/tests/tracer.rs`.
//!
//! Conventions of these tests: the interface is the plane z = 0 with n̂ = +ẑ; the medium above
//! has index 1 and the one below `η` (1.5 unless said); a packet's wavelength is the one in the
//! medium it travels in (`λ₀/n`).

use crate::common;

use std::f64::consts::TAU;

use common::hemisphere::{Hemisphere, hemisphere_integral};
use common::scene::{DEG, fresnel_rs_rp, rel_diff, surface};
use common::{Tol, assert_all_close, assert_close, entries4};
use gmueller::frame::Frame;
use gmueller::interaction::exitant::exitant_packet;
use gmueller::interaction::pbsdf::Pbsdf;
use gmueller::interaction::polarization::{KernelOutput, PolarizationModel, Response};
use gmueller::interaction::{
    Full, Geometry, Incoherent, Intensity, Kernel, Level, OneShape, Partial, PlaneWave,
    RoughDielectric, Side, SmoothDielectric,
};
use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::packet::{Channel, CoherenceShape, WavePacket};
use gmueller::psd::ClosedForm;
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector2, Vector3};
use num_complex::Complex;

type Glass = RoughDielectric<f64, GaussianPsd<f64, 2>>;

const LAMBDA0: f64 = 0.5;

fn glass(eta: f64, sigma: f64, ell: f64) -> Glass {
    RoughDielectric::new(GaussianPsd::isotropic(sigma, ell).unwrap(), eta).unwrap()
}

/// The direction of travel of light arriving at polar angle `theta` in the x–z plane (moving
/// toward +x), from above (downward) or from below (upward).
fn travel(theta: f64, from_below: bool) -> Vector3<f64> {
    let z = if from_below {
        theta.cos()
    } else {
        -theta.cos()
    };
    Vector3::new(theta.sin(), 0.0, z)
}

/// A unit direction at polar angle θ from ±ẑ, azimuth φ.
fn dir(theta: f64, phi: f64, below: bool) -> Vector3<f64> {
    let z = if below { -theta.cos() } else { theta.cos() };
    Vector3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), z)
}

/// A single-shape packet travelling along `d` with Stokes `s` in its s/p frame (w.r.t. ẑ).
fn packet_along(d: Vector3<f64>, s: [f64; 4], width: f64, lambda: f64) -> WavePacket<f64> {
    WavePacket::from_stokes(
        Stokes::new(s[0], s[1], s[2], s[3]).unwrap(),
        CoherenceShape::isotropic(width).unwrap(),
        Frame::sp(d, Vector3::z()).unwrap(),
        lambda,
    )
    .unwrap()
}

/// `(n_i, n_t)` for light from above (index 1) or below (index η).
fn indices(eta: f64, from_below: bool) -> (f64, f64) {
    if from_below { (eta, 1.0) } else { (1.0, eta) }
}

/// Textbook Fresnel amplitude transmissions of a lossless interface below the critical angle
/// (Born & Wolf §1.5.2 with relative index `n`): `(t_s, t_p)`.
fn fresnel_ts_tp(cos_i: f64, n: f64) -> (f64, f64) {
    let q = (n * n - (1.0 - cos_i * cos_i)).sqrt(); // n cos θ_t
    (
        2.0 * cos_i / (cos_i + q),
        2.0 * n * cos_i / (n * n * cos_i + q),
    )
}

/// Fractions `[R_spec, R_scat, T_spec, T_scat]` of light with Stokes `s` arriving at `theta_i`:
/// `∫ L cos θ_o dω / (S0 cos θ_i)` over each hemisphere, at the `OneShape` level.
fn fractions(
    material: &Glass,
    theta_i: f64,
    from_below: bool,
    s: [f64; 4],
    width: f64,
) -> [f64; 4] {
    let (n_i, n_t) = indices(material.relative_index(), from_below);
    let pk = packet_along(travel(theta_i, from_below), s, width, LAMBDA0 / n_i);
    let kernel = Kernel::<OneShape, Partial>::default();
    let r0 = Vector2::new(theta_i.sin(), 0.0);
    // Snell's point (or the rim under total internal reflection, where only scatter remains).
    let t0 = Vector2::new((n_i / n_t * theta_i.sin()).min(0.999), 0.0);
    let (near, far) = if from_below {
        (Hemisphere::Below, Hemisphere::Above)
    } else {
        (Hemisphere::Above, Hemisphere::Below)
    };
    let run = |r0: Vector2<f64>, side: Hemisphere, expect: Side| {
        hemisphere_integral(r0, 96, side, &mut |exit| {
            let g = material.geometry_for_packet(&pk, &surface(), exit).unwrap();
            let r = kernel.evaluate(material, &pk, &g);
            assert_eq!(r.side, expect);
            [r.specular.s0(), r.scattered.s0()]
        })
    };
    let [rs, rd] = run(r0, near, Side::Reflection);
    let [ts, td] = run(t0, far, Side::Transmission);
    let c = theta_i.cos() * s[0];
    [rs / c, rd / c, ts / c, td / c]
}

// ------------------------------------------------------------------ 1. geometry

/// The transmitted phase factor `v = k (cos θ_i − η cos θ_o)` is the optical path difference
/// that raising the interface by `z` imprints, computed here from explicitly matched plane
/// waves: the incident wave `e^{i k_i d_i·x}` and the refracted one `e^{i k_t d_t·x}` (its
/// direction from the tangential matching `k_i d_i,t = k_t d_t,t` alone) agree on the interface
/// plane `z = h`; the refracted wave's phase at a point of the mean plane below, minus its
/// phase for `h = 0`, is `−v h`. From above and below, several angles and azimuths.
#[test]
fn phase_factor_is_the_optical_path_difference() {
    for from_below in [false, true] {
        // From below only up to the critical angle (41.8°).
        let angles = if from_below {
            [(0.0, 0.0), (20.0, 0.0), (35.0, 1.0), (41.0, -2.5)]
        } else {
            [(0.0, 0.0), (20.0, 0.0), (45.0, 1.0), (70.0, -2.5)]
        };
        for (ti, phi) in angles {
            let (n_i, n_t) = indices(1.5, from_below);
            let k0 = TAU / LAMBDA0;
            let (ki, kt) = (n_i * k0, n_t * k0);
            // Incident direction turned by φ about ẑ.
            let d0 = travel(ti * DEG, from_below);
            let (s, c) = f64::sin_cos(phi);
            let di = Vector3::new(c * d0.x - s * d0.y, s * d0.x + c * d0.y, d0.z);
            // Refracted direction: same tangential wavevector, continuing away from the source.
            let tang = Vector2::new(di.x, di.y) * (ki / kt);
            let dz = (1.0 - tang.norm_squared()).sqrt() * di.z.signum();
            let dt = Vector3::new(tang.x, tang.y, dz);
            // Raised by h toward the source (along the normal the geometry orients).
            let h = 0.013;
            let z = if from_below { -h } else { h };
            let x = Vector3::new(0.7, -0.2, 0.0); // a point of the mean plane
            // On the raised plane the two waves agree at x_s = (x, z) (any point of it, by the
            // tangential matching); propagate the refracted wave from there to x.
            let xs = Vector3::new(x.x, x.y, z);
            let phase_raised = ki * di.dot(&xs) + kt * dt.dot(&(x - xs));
            let phase_flat = ki * di.dot(&x);
            let exit = dt;
            let g = Geometry::at_interface(ki, &surface(), 1.5, -di, exit).unwrap();
            assert_eq!(g.side(), Side::Transmission);
            assert_eq!(g.incident_from_below(), from_below);
            assert_close(
                &format!("phase difference (below = {from_below}, θi = {ti}°)"),
                phase_raised - phase_flat,
                -g.phase_factor() * h,
                Tol::new(1e-14, 1e-12),
            );
            // The refracted direction is phase matched (h_t = 0) and is Snell's.
            assert!(g.h_t().norm() < 1e-10 * ki, "h_t = {:?}", g.h_t());
            let spec = g.specular_direction().unwrap();
            assert!((spec - dt).norm() < 1e-14, "Snell: {spec:?} vs {dt:?}");
            assert_close(
                "relative index",
                g.relative_index(),
                n_t / n_i,
                Tol::new(0.0, 1e-15),
            );
        }
    }
}

// ------------------------------------------------------------------ 2. the coherent lobes

/// The coherent transmitted lobe of a nearly smooth interface integrates to `α_t T`, with the
/// textbook power transmittance `T = 1 − (R_s + R_p)/2` and the transmitted Debye–Waller factor
/// `α_t = exp(−(k_i σ (cos θ_i − η cos θ_t))²)`; the reflected lobe to `α_r R`. Wide packet
/// (w = 500 µm), σ = 5 nm, from above and below (below the critical angle), tolerance 1e-4 as
/// for reflection (`tests/interaction/energy.rs`). (At w = 50 µm the lobe's own width shows at
/// 40° from below, 2° from the critical angle, where the transmitted beam is at 74°: the lobe
/// averages `cos θ_t` and `α_t` over its width and integrates to 1.7e-4 less.)
#[test]
fn coherent_lobes_integrate_to_attenuated_fresnel_powers() {
    let sigma = 0.005;
    let material = glass(1.5, sigma, 2.0);
    for from_below in [false, true] {
        for ti_deg in [0.0, 30.0, 40.0] {
            let ti = ti_deg * DEG;
            let (n_i, n_t) = indices(1.5, from_below);
            let f = fractions(&material, ti, from_below, [1.0, 0.0, 0.0, 0.0], 500.0);
            let (rs, rp) = fresnel_rs_rp(ti.cos(), n_t / n_i);
            let r = 0.5 * (rs + rp);
            let ki = TAU / LAMBDA0 * n_i;
            let cos_t = (1.0 - (n_i / n_t * ti.sin()).powi(2)).sqrt();
            let alpha_t = (-(ki * sigma * (ti.cos() - n_t / n_i * cos_t)).powi(2)).exp();
            let alpha_r = (-(2.0 * ki * sigma * ti.cos()).powi(2)).exp();
            println!(
                "below = {from_below}, θi = {ti_deg}°: R_spec {:.8} (α R {:.8}), T_spec {:.8} (α T {:.8})",
                f[0],
                alpha_r * r,
                f[2],
                alpha_t * (1.0 - r)
            );
            let tol = Tol::new(0.0, 1e-4);
            assert_close("R_spec", f[0], alpha_r * r, tol);
            assert_close("T_spec", f[2], alpha_t * (1.0 - r), tol);
        }
    }
}

/// Brewster's angle, from both sides (`tan θ_B = n_t/n_i`): p-polarized light (S1 = −1 in the
/// s/p frame) is not reflected at all — the reflected coherent lobe is 0 at every exit — and the
/// coherent transmitted lobe carries `α_t T_p = α_t` of it.
#[test]
fn brewster_angle_transmits_all_p_light() {
    let sigma = 0.002;
    let material = glass(1.5, sigma, 2.0);
    for from_below in [false, true] {
        let (n_i, n_t) = indices(1.5, from_below);
        let tb = (n_t / n_i).atan();
        let p_light = [1.0, -1.0, 0.0, 0.0];
        let f = fractions(&material, tb, from_below, p_light, 50.0);
        let ki = TAU / LAMBDA0 * n_i;
        let cos_t = (1.0 - (n_i / n_t * tb.sin()).powi(2)).sqrt();
        let alpha_t = (-(ki * sigma * (tb.cos() - n_t / n_i * cos_t)).powi(2)).exp();
        println!(
            "Brewster {:.3}° (below = {from_below}): R_spec {:.3e}, T_spec {:.8} (α_t {alpha_t:.8})",
            tb / DEG,
            f[0],
            f[2]
        );
        assert!(f[0] < 1e-20, "p light reflected at Brewster: {}", f[0]);
        assert_close("T_p at Brewster", f[2], alpha_t, Tol::new(0.0, 1e-4));
        // s light is reflected there (a wrong frame or swapped s/p would show here).
        let fs = fractions(&material, tb, from_below, [1.0, 1.0, 0.0, 0.0], 50.0);
        let (rs, _) = fresnel_rs_rp(tb.cos(), n_t / n_i);
        let alpha_r = (-(2.0 * ki * sigma * tb.cos()).powi(2)).exp();
        assert_close("R_s at Brewster", fs[0], alpha_r * rs, Tol::new(0.0, 1e-4));
    }
}

/// Total internal reflection, from the dense side beyond the critical angle: the coherent
/// transmitted lobe is exactly 0 at every exit, the coherent reflected one carries `α_r` (R = 1),
/// and scattered transmission into the propagating directions of the rare medium remains.
#[test]
fn total_internal_reflection_leaves_only_scattered_transmission() {
    let sigma = 0.01;
    let material = glass(1.5, sigma, 1.0);
    for ti_deg in [45.0, 60.0, 80.0] {
        let ti = ti_deg * DEG;
        let f = fractions(&material, ti, true, [1.0, 0.0, 0.0, 0.0], 50.0);
        let ki = TAU / LAMBDA0 * 1.5;
        let alpha_r = (-(2.0 * ki * sigma * ti.cos()).powi(2)).exp();
        println!(
            "TIR θi = {ti_deg}°: R_spec {:.8} (α {alpha_r:.8}) R_scat {:.3e} T_spec {:e} T_scat {:.3e}",
            f[0], f[1], f[2], f[3]
        );
        assert_eq!(f[2], 0.0, "coherent transmission under TIR");
        assert_close("R_spec under TIR", f[0], alpha_r, Tol::new(0.0, 1e-4));
        assert!(f[3] > 0.0, "scattered transmission under TIR: {}", f[3]);
    }
}

// ------------------------------------------------------------------ 3. first-order scattering

/// At the specular (Snell) direction the first-order (Rayleigh–Rice) Mueller matrix equals the
/// phase screen's with the Fresnel coefficients, `M_RR = v² M_F` — the Kirchhoff limit that
/// ties the transmission factors (Elson's, with `2k cos θ_i √η`) to the coherent part
/// independently of SCATMECH. `M_F` from the textbook amplitudes: `diag(r_s, r_p)` in reflection,
/// `√η diag(t_s, t_p)` in transmission (`η = n_t/n_i`). All four cases, several angles; for
/// reflection from the dense side also beyond the critical angle (complex `r`).
#[test]
fn rayleigh_rice_tends_to_the_phase_screen_at_the_specular_direction() {
    let material = glass(1.5, 0.01, 2.0);
    for from_below in [false, true] {
        let (n_i, n_t) = indices(1.5, from_below);
        let eta = n_t / n_i;
        let ki = TAU / LAMBDA0 * n_i;
        for ti_deg in [0.0, 10.0, 35.0, 41.0, 55.0, 75.0] {
            let ti = ti_deg * DEG;
            let s = travel(ti, from_below);
            let below_critical = ti.sin() < eta;
            // Reflection: the mirror direction.
            let mirror = Vector3::new(s.x, s.y, -s.z);
            let g = material.geometry(ki, &surface(), -s, mirror).unwrap();
            let v = g.phase_factor();
            let q = Complex::new(eta * eta - ti.sin().powi(2), 0.0).sqrt();
            let c = Complex::new(ti.cos(), 0.0);
            let e = Complex::new(eta * eta, 0.0);
            let (rs, rp) = ((c - q) / (c + q), (e * c - q) / (e * c + q));
            let jf = JonesMatrix::from_matrix(Matrix2::new(
                rs,
                Complex::new(0.0, 0.0),
                Complex::new(0.0, 0.0),
                rp,
            ))
            .unwrap();
            let expected = Mueller::from_jones(&jf).matrix() * (v * v);
            let got = material.scatter.mueller(&g).matrix();
            assert_all_close(
                &format!("reflection below = {from_below}, θi = {ti_deg}°"),
                entries4(&got),
                entries4(&expected),
                Tol::new(1e-12 * expected[(0, 0)], 1e-10),
            );
            if !below_critical {
                continue;
            }
            // Transmission: Snell's direction.
            let sin_t = ti.sin() / eta;
            let snell = Vector3::new(sin_t, 0.0, s.z.signum() * (1.0 - sin_t * sin_t).sqrt());
            let g = material.geometry(ki, &surface(), -s, snell).unwrap();
            assert_eq!(g.side(), Side::Transmission);
            assert!(g.h_t().norm() < 1e-9 * ki);
            let v = g.phase_factor();
            let (ts, tp) = fresnel_ts_tp(ti.cos(), eta);
            let root = eta.sqrt();
            let jf = JonesMatrix::from_matrix(Matrix2::new(
                Complex::new(root * ts, 0.0),
                Complex::new(0.0, 0.0),
                Complex::new(0.0, 0.0),
                Complex::new(root * tp, 0.0),
            ))
            .unwrap();
            let expected = Mueller::from_jones(&jf).matrix() * (v * v);
            let got = material.scatter.mueller(&g).matrix();
            println!(
                "below = {from_below}, θi = {ti_deg}°: M00 RR {:.10e} vs v² η|t|² {:.10e}",
                got[(0, 0)],
                expected[(0, 0)]
            );
            assert_all_close(
                &format!("transmission below = {from_below}, θi = {ti_deg}°"),
                entries4(&got),
                entries4(&expected),
                Tol::new(1e-12 * expected[(0, 0)], 1e-10),
            );
            // The coherent pBSDF there is the Fresnel transmission itself.
            let spec = material.specular.mueller(&g).matrix();
            let fresnel = Mueller::from_jones(&jf).matrix();
            assert_all_close(
                "specular pBSDF at Snell",
                entries4(&spec),
                entries4(&fresnel),
                Tol::new(1e-14, 1e-12),
            );
        }
    }
}

/// Energy: the reflected plus transmitted, coherent plus scattered fraction of unpolarized light
/// on lossless rough glass (η = 1.5, Gaussian PSD with ℓ = 2λ and 10λ), from above (0°–80°) and
/// below (beyond the critical angle too), as a function of kσ (`k = 2π/λ₀`, the vacuum
/// wavenumber). First-order theory with the Debye–Waller coherent part conserves energy only up
/// to second order in the roughness: the Debye–Waller factors take `(vσ)²` out of the coherent
/// beams, the first-order scattering puts back an amount that agrees with it only for long
/// correlation lengths (the Kirchhoff limit), and the remainder is `O((kσ)²)`. Measured for a
/// wide packet (w = 100 λ): `|1 − R − T| ≤ 0.35 (kσ)²` in every case, largest at grazing
/// incidence and beyond the critical angle with ℓ = 2λ (there the imbalance is 15–18 % of the
/// scattered power; near normal incidence ≤ 1 %); asserted as `≤ 0.4 (kσ)² + 1e-5` (1e-5 covers
/// the quadrature and the lobes' own `⟨cos θ_o⟩` deficit `≈ 1/(k w)²`). A wrong η², √η or side
/// would break it at first order with a larger constant: a factor η² on the scattered
/// transmission alone changes the total by 3e-3 at kσ = 0.1, i.e. 0.3 (kσ)² on top. The
/// narrower packet (w = 10 λ) is printed, not asserted: there the coherent lobes themselves
/// integrate to `⟨cos θ_o⟩/cos θ_i` of the Fresnel powers, 1.2e-4 short at normal incidence —
/// the finite-coherence property of S2.20 that `tests/interaction/energy.rs` tabulates for
/// reflection.
///
/// Measured (`cargo test --release --test integration -- --nocapture
/// interaction::transmission::energy`), `|1 − R − T|` at w = 100 λ, worst over ℓ, per kσ = 0.02,
/// 0.05, 0.1, 0.2:
/// ```text
/// above  0°   1.2e-6  3.4e-6  3.5e-5  5.1e-4
/// above 30°   1.3e-6  2.6e-6  2.3e-5  3.4e-4
/// above 60°   8.7e-6  6.4e-5  2.5e-4  7.9e-4
/// above 80°   4.2e-5  9.2e-5  2.9e-4  1.3e-3
/// below  0°   2.7e-6  1.3e-5  1.6e-4  2.1e-3
/// below 30°   7.6e-6  1.5e-5  1.3e-4  1.8e-3
/// below 50°   5.2e-5  3.5e-4  1.8e-3  1.4e-2     (total internal reflection)
/// below 70°   5.7e-5  3.1e-4  1.2e-3  5.6e-3     (total internal reflection)
/// ```
#[test]
fn energy_of_reflection_plus_transmission() {
    let k0 = TAU / LAMBDA0;
    let mut worst: f64 = 0.0;
    println!(
        "side   θi   kσ    ℓ/µm  w/λ  R_spec    R_scat    T_spec    T_scat    1−total   /(kσ)²"
    );
    for (from_below, ti_deg) in [
        (false, 0.0),
        (false, 30.0),
        (false, 60.0),
        (false, 80.0),
        (true, 0.0),
        (true, 30.0),
        (true, 50.0),
        (true, 70.0),
    ] {
        for ks in [0.02, 0.05, 0.1, 0.2] {
            for ell in [1.0, 5.0] {
                for w in [10.0, 100.0] {
                    let m = glass(1.5, ks / k0, ell);
                    let ti = ti_deg * DEG;
                    let f = fractions(&m, ti, from_below, [1.0, 0.0, 0.0, 0.0], w * LAMBDA0);
                    let dev = 1.0 - f.iter().sum::<f64>();
                    let ks2 = ks * ks;
                    if w == 100.0 {
                        worst = worst.max(dev.abs() / ks2);
                    }
                    println!(
                        "{} {ti_deg:>4} {ks:>5} {ell:>5} {w:>5} {:.7} {:.7} {:.7} {:.7} {dev:>9.2e} {:.3}",
                        if from_below { "below" } else { "above" },
                        f[0],
                        f[1],
                        f[2],
                        f[3],
                        dev.abs() / ks2
                    );
                    if w == 100.0 {
                        assert!(
                            dev.abs() <= 0.4 * ks2 + 1e-5,
                            "energy: 1 − R − T = {dev:e} > 0.4 (kσ)² + 1e-5 = {:e}",
                            0.4 * ks2 + 1e-5
                        );
                    }
                }
            }
        }
    }
    println!("largest |1 − R − T|/(kσ)² at w = 100 λ = {worst:.3}");
}

/// Generalized reciprocity of the plane-wave BTDF, `f_t(i→o)/n_o² = f_t(o→i)/n_i²`
/// (`f = L/(S0 cos θ_i)`, unpolarized): light from the air into the glass along `a → b` and
/// back along `b → a`, for several direction pairs, to 1e-12. The reflections from either side
/// are reciprocal themselves (`f_r(a→b) = f_r(b→a)`).
#[test]
fn generalized_reciprocity_of_the_plane_wave_btdf() {
    let eta = 1.5;
    let material = glass(eta, 0.01, 1.0);
    let kernel = Kernel::<Intensity, PlaneWave>::default();
    let f = |src: Vector3<f64>, out: Vector3<f64>, n_i: f64| {
        let pk = packet_along(-src, [1.0, 0.0, 0.0, 0.0], 10.0, LAMBDA0 / n_i);
        let g = material.geometry_for_packet(&pk, &surface(), out).unwrap();
        kernel.evaluate(&material, &pk, &g).scattered / src.z.abs()
    };
    for (ta, pa, tb, pb) in [
        (30.0, 180.0, 20.0, 10.0),
        (10.0, 170.0, 40.0, -30.0),
        (60.0, 200.0, 5.0, 90.0),
        (80.0, 135.0, 35.0, 0.0),
    ] {
        let a = dir(ta * DEG, pa * DEG, false); // in the air (above)
        let b = dir(tb * DEG, pb * DEG, true); // in the glass (below)
        let air_to_glass = f(a, b, 1.0);
        let glass_to_air = f(b, a, eta);
        assert!(air_to_glass > 0.0 && glass_to_air > 0.0);
        assert_close(
            &format!("f_t(a→b)/η² vs f_t(b→a) ({ta},{pa} ↔ {tb},{pb})"),
            air_to_glass / (eta * eta),
            glass_to_air,
            Tol::new(0.0, 1e-12),
        );
        // Reflection on either side.
        let a2 = dir(tb * DEG, pb * DEG, false);
        assert_close(
            "f_r above",
            f(a, a2, 1.0),
            f(a2, a, 1.0),
            Tol::new(0.0, 1e-12),
        );
        let b2 = dir(ta * DEG, pa * DEG, true);
        assert_close(
            "f_r below",
            f(b, b2, eta),
            f(b2, b, eta),
            Tol::new(0.0, 1e-12),
        );
    }
}

// ------------------------------------------------------------------ 4. levels and limits

/// In transmission, as in reflection (`tests/interaction/laws.rs`), `Partial` tends to
/// `PlaneWave` as the coherence width grows and to `Incoherent` as it shrinks, monotonically,
/// at the `OneShape` and `Full` levels, from above and from below; and `Full` equals `OneShape`
/// on a single-shape packet while two shapes differ.
#[test]
fn transmitted_levels_tend_to_their_limits() {
    let material = glass(1.5, 0.02, 2.0);
    for from_below in [false, true] {
        let (n_i, _) = indices(1.5, from_below);
        let d = travel(35.0 * DEG, from_below);
        let exit = dir(20.0 * DEG, 8.0 * DEG, !from_below);
        let frame = Frame::sp(d, Vector3::z()).unwrap().rotated(0.3);
        let make = |w: f64| {
            WavePacket::new(
                Stokes::new(1.0, 0.2, 0.3, -0.2).unwrap(),
                CoherenceShape::isotropic(w).unwrap(),
                CoherenceShape::isotropic(1.3 * w).unwrap(),
                frame,
                LAMBDA0 / n_i,
            )
            .unwrap()
        };
        fn eval<Pol: PolarizationModel<Output<f64> = Response<f64>>, Coh>(
            material: &Glass,
            pk: &WavePacket<f64>,
            exit: Vector3<f64>,
        ) -> Response<f64>
        where
            Coh: gmueller::interaction::coherence::CoherenceWeights<f64, GaussianPsd<f64, 2>>
                + Default,
        {
            let g = material.geometry_for_packet(pk, &surface(), exit).unwrap();
            assert_eq!(g.side(), Side::Transmission);
            Kernel::<Pol, Coh>::default().evaluate(material, pk, &g)
        }
        fn limits<Pol: PolarizationModel<Output<f64> = Response<f64>>>(
            material: &Glass,
            make: &dyn Fn(f64) -> WavePacket<f64>,
            exit: Vector3<f64>,
        ) {
            let mut last = f64::INFINITY;
            let mut dev = f64::NAN;
            for w in [3.0, 30.0, 300.0, 3e3, 3e4] {
                let pk = make(w);
                let part = eval::<Pol, Partial>(material, &pk, exit);
                let pw = eval::<Pol, PlaneWave>(material, &pk, exit);
                dev = rel_diff(&part.scattered.vector(), &pw.scattered.vector());
                assert!(dev < last, "deviation from PlaneWave must shrink");
                last = dev;
            }
            assert!(dev < 1e-6, "deviation at w = 3e4 µm: {dev:e}");
            let mut last = f64::INFINITY;
            for w in [0.5, 0.1, 0.02, 0.004] {
                let pk = make(w);
                let part = eval::<Pol, Partial>(material, &pk, exit);
                let inc = eval::<Pol, Incoherent>(material, &pk, exit);
                dev = rel_diff(&part.scattered.vector(), &inc.scattered.vector());
                assert!(dev < last, "deviation from Incoherent must shrink");
                last = dev;
            }
            assert!(dev < 1e-4, "deviation at w = 0.004 µm: {dev:e}");
        }
        limits::<OneShape>(&material, &make, exit);
        limits::<Full>(&material, &make, exit);
        // Single shape: Full = OneShape exactly; two shapes: they differ.
        let one = packet_along(d, [1.0, 0.3, 0.2, 0.1], 2.0, LAMBDA0 / n_i);
        let (full, os) = (
            eval::<Full, Partial>(&material, &one, exit),
            eval::<OneShape, Partial>(&material, &one, exit),
        );
        assert_eq!(full, os);
        let two = make(2.0);
        let (full, os) = (
            eval::<Full, Partial>(&material, &two, exit),
            eval::<OneShape, Partial>(&material, &two, exit),
        );
        assert!(rel_diff(&full.scattered.vector(), &os.scattered.vector()) > 1e-3);
    }
}

// ------------------------------------------------------------------ 5. the exitant packet

/// The exitant packet of transmitted light lives in the new medium: its wavelength is `λ/η`, its
/// frame the exit s/p frame, and its shape the projection of the shared footprint. At Snell's
/// direction that shape is exactly what the kernel's coherent lobe says: the lobe's covariance
/// in the exit beam's transverse direction cosines, measured by finite differences of
/// `ln K^spec`, equals `Θ′⁻¹/k_t²` — the far-field spread of a beam of coherence `Θ′` in a
/// medium of wavenumber `k_t = η k`. Widths in the plane of incidence scale by
/// `cos θ_t/cos θ_i`, the others are unchanged.
#[test]
fn exitant_packet_in_the_new_medium() {
    let material = SmoothDielectric::<f64>::smooth(1.5).unwrap();
    for from_below in [false, true] {
        let (n_i, n_t) = indices(1.5, from_below);
        let ti = 30.0 * DEG;
        let w = 3.0;
        let pk = packet_along(
            travel(ti, from_below),
            [1.0, 0.0, 0.0, 0.0],
            w,
            LAMBDA0 / n_i,
        );
        let sin_t = n_i / n_t * ti.sin();
        let (cos_i, cos_t) = (ti.cos(), (1.0 - sin_t * sin_t).sqrt());
        let snell = Vector3::new(sin_t, 0.0, if from_below { cos_t } else { -cos_t });
        let g = material
            .geometry_for_packet(&pk, &surface(), snell)
            .unwrap();
        let out = exitant_packet(&pk, &g, Stokes::unpolarized(1.0).unwrap()).unwrap();
        assert_close(
            "wavelength in the new medium",
            out.wavelength(),
            LAMBDA0 / n_t,
            Tol::new(0.0, 1e-15),
        );
        assert_eq!(out.frame(), g.exit_sp());
        // Projection: the s width (⟂ plane of incidence) unchanged, the p width × cos θ_t/cos θ_i.
        let th = out.shape(Channel::Half);
        let expected = Matrix2::new(w * w, 0.0, 0.0, (w * cos_t / cos_i).powi(2));
        assert_all_close(
            "exitant shape",
            th.iter().copied(),
            expected.iter().copied(),
            Tol::new(1e-12, 1e-12),
        );
        // The kernel's coherent lobe around Snell's direction, in the exit beam's transverse
        // direction cosines u (r̂ = normalize(r̂_s + u₁ x̂ + u₂ ŷ)).
        let kernel = Kernel::<Intensity, Partial>::default();
        let kt = TAU / (LAMBDA0 / n_t);
        let ex = g.exit_sp();
        let lnk = |u: Vector2<f64>| {
            let r = (snell + ex.x() * u.x + ex.y() * u.y).normalize();
            let g = material.geometry_for_packet(&pk, &surface(), r).unwrap();
            // Divide out cos θ_o (the lobe is g^Ξ; the kernel multiplies by cos θ_o).
            (kernel.evaluate(&material, &pk, &g).specular / g.cos_o()).ln()
        };
        let step = 0.3 / (kt * w);
        let e = |i: usize| if i == 0 { Vector2::x() } else { Vector2::y() } * step;
        let mut hess = Matrix2::zeros();
        for i in 0..2 {
            for j in 0..2 {
                let (a, b) = (e(i), e(j));
                hess[(i, j)] =
                    (lnk(a + b) - lnk(a - b) - lnk(b - a) + lnk(-a - b)) / (4.0 * step * step);
            }
        }
        // ln g = −½ uᵀ C⁻¹ u: the Hessian is −C⁻¹ = −k_t² Θ′.
        let predicted = th * (kt * kt);
        assert_all_close(
            "lobe curvature vs exitant coherence",
            (-hess).iter().copied(),
            predicted.iter().copied(),
            Tol::new(1e-4 * predicted.norm(), 1e-4),
        );
    }
}

// ------------------------------------------------------------------ 6. absorption

/// The claim of the `RoughDielectric` docs: a small absorption κ changes the Fresnel reflectance
/// only at second order — `|R(n + iκ) − R(n)|/κ²` is the same at κ = 1e-3 and 1e-2 (to 1 %) —
/// and by at most `3κ²` for n ≥ 1.2 (`0.4κ²` for n ≥ 1.5) at every incidence, κ ≤ 0.05 (textbook
/// complex Fresnel, independent of the crate). Measured maximum: 2.72 κ² (n = 1.2, 80°).
#[test]
fn small_absorption_changes_reflectance_at_second_order() {
    let r = |c: f64, n: Complex<f64>| {
        let one = Complex::new(1.0, 0.0);
        let cc = Complex::new(c, 0.0);
        let q = (n * n - one * (1.0 - c * c)).sqrt();
        let rs = (cc - q) / (cc + q);
        let rp = (n * n * cc - q) / (n * n * cc + q);
        0.5 * (rs.norm_sqr() + rp.norm_sqr())
    };
    let mut worst: f64 = 0.0;
    for n in [1.2, 1.5, 2.0, 2.4] {
        let bound = if n >= 1.5 { 0.4 } else { 3.0 };
        for ti in [0.0, 20.0, 40.0, 60.0, 70.0, 80.0, 85.0, 89.0] {
            let c = (ti * DEG).cos();
            let ratio = |kappa: f64| {
                (r(c, Complex::new(n, kappa)) - r(c, Complex::new(n, 0.0))).abs() / (kappa * kappa)
            };
            assert_close(
                "second order",
                ratio(1e-3),
                ratio(1e-2),
                Tol::new(0.0, 1e-2),
            );
            for kappa in [1e-3, 1e-2, 0.05] {
                worst = worst.max(ratio(kappa));
                assert!(
                    ratio(kappa) <= bound,
                    "n {n}, θ {ti}°, κ {kappa}: ΔR/κ² = {}",
                    ratio(kappa)
                );
            }
        }
    }
    println!("largest |ΔR|/κ² = {worst:.3}");
}

// ------------------------------------------------------------------ 7. lobes and sides

/// Every exit direction has one side, and the response says which: above the surface for light
/// from above is reflection, below is transmission (and the converse from below); the coherent
/// reflected lobe of a flat interface is at the mirror direction and the transmitted one at
/// Snell's; an opaque reflector (`FresnelReflection`) gives nothing in transmission.
#[test]
fn the_four_lobes_are_reported_by_side() {
    let material = SmoothDielectric::<f64>::smooth(1.5).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    for from_below in [false, true] {
        let (n_i, n_t) = indices(1.5, from_below);
        let ti = 25.0 * DEG;
        let d = travel(ti, from_below);
        let pk = packet_along(d, [1.0, 0.0, 0.0, 0.0], 5.0, LAMBDA0 / n_i);
        let mirror = Vector3::new(d.x, d.y, -d.z);
        let sin_t = n_i / n_t * ti.sin();
        let snell = Vector3::new(sin_t, 0.0, d.z.signum() * (1.0 - sin_t * sin_t).sqrt());
        for (exit, side) in [(mirror, Side::Reflection), (snell, Side::Transmission)] {
            let g = material.geometry_for_packet(&pk, &surface(), exit).unwrap();
            assert_eq!(g.side(), side);
            let r = kernel.evaluate(&material, &pk, &g);
            assert_eq!(r.side, side);
            // Every level reports it, the run-time ones included.
            for level in Level::ALL {
                let out = level.evaluate(ClosedForm, &material, &pk, &g);
                assert_eq!(out.side(), side, "{}", level.name());
            }
            // A smooth interface: no scattered part, a coherent lobe at its centre.
            assert_eq!(r.scattered.s0(), 0.0);
            assert!(r.specular.s0() > 0.0);
            assert!((g.specular_direction().unwrap() - exit).norm() < 1e-14);
        }
        let opaque =
            gmueller::interaction::SmoothConductor::<f64>::smooth(Complex::new(1.5, 0.0)).unwrap();
        let g = material
            .geometry_for_packet(&pk, &surface(), snell)
            .unwrap();
        assert_eq!(Pbsdf::m00(&opaque.specular, &g), 0.0);
        assert_eq!(Pbsdf::mueller(&opaque.specular, &g).matrix().norm(), 0.0);
        // The conductor's own geometry is reflection only.
        let k = pk.wavenumber();
        let facing = surface().facing(&-d);
        assert!(opaque.geometry(k, &facing, -d, mirror).is_ok());
        assert!(opaque.geometry(k, &facing, -d, snell).is_err());
    }
}

// ------------------------------------------------------------------ 8. smooth to rough

/// The smooth-to-rough progression of a glass interface (η = 1.5, Gaussian PSD, ℓ = 2 µm,
/// λ₀ = 0.5 µm, θi = 30° from the air and 20° from inside, unpolarized, w = 100 λ): the four
/// lobes' fractions as σ grows from 0 past the edge of the first-order range (the largest phase,
/// the reflected `v σ = 2 k_i σ cos θ_i`, at most 0.3; rows beyond it are marked). Within the
/// range, power moves monotonically from the coherent lobes to the scattered ones, and the sum
/// stays within the energy bound of `energy_of_reflection_plus_transmission`. The kernel guide's table (`docs/kernel.md`)
/// is this test's output (`cargo test --release --test integration -- --nocapture
/// smooth_to_rough`).
#[test]
fn smooth_to_rough_progression() {
    let k0 = TAU / LAMBDA0;
    for (from_below, ti_deg) in [(false, 30.0), (true, 20.0)] {
        let (n_i, _) = indices(1.5, from_below);
        println!(
            "\nglass, light from {} at {ti_deg}°:\n σ/nm   kσ    v_rσ   R_spec   R_scat   T_spec   T_scat   total",
            if from_below { "inside" } else { "the air" }
        );
        let mut last: Option<[f64; 4]> = None;
        for sigma_nm in [0.0_f64, 2.0, 5.0, 10.0, 15.0, 20.0, 40.0] {
            let sigma = sigma_nm * 1e-3;
            // σ = 0: the smooth limit (nothing scattered, α = 1).
            let m = glass(1.5, sigma.max(1e-12), 2.0);
            let f = fractions(
                &m,
                ti_deg * DEG,
                from_below,
                [1.0, 0.0, 0.0, 0.0],
                100.0 * LAMBDA0,
            );
            let total: f64 = f.iter().sum();
            let v_sigma = 2.0 * n_i * k0 * sigma * (ti_deg * DEG).cos();
            let valid = v_sigma <= 0.3;
            println!(
                "{sigma_nm:>5} {:.3}  {v_sigma:.3}  {:.5}  {:.5}  {:.5}  {:.5}  {:.5}{}",
                k0 * sigma,
                f[0],
                f[1],
                f[2],
                f[3],
                total,
                if valid { "" } else { "  (beyond first order)" }
            );
            if !valid {
                continue;
            }
            assert!((total - 1.0).abs() <= 0.4 * (k0 * sigma).powi(2) + 1e-5);
            if let Some(p) = last {
                assert!(f[0] < p[0] && f[2] < p[2], "coherent lobes must lose power");
                assert!(
                    f[1] > p[1] && f[3] > p[3],
                    "scattered lobes must gain power"
                );
            }
            last = Some(f);
        }
    }
}
