//! How paraxial the medium's packet is: its first-Born scattering against an exact sum of plane
//! waves, written here from the beam and the medium (no `gmueller::medium` code), for a Gaussian
//! Schell-model beam in a Gaussian-correlated medium; a table over `(w/λ, kℓ, Θ)` and the
//! measured bound.
//!
//! # The exact sum
//! ```text
//! W(ξ) = ∫_{|κ|<k} Ã(κ) e^{i K(κ)·ξ} d²κ,   Ã(κ) = (w²/2π) e^{−w²|κ|²/2},   K(κ) = κ + √(k² − |κ|²) d̂
//! dI/dV(r̂) = (k⁴/16π²) ∫ Ã(κ) (2π)^{3/2} p(k r̂ − K(κ)) m(K̂·r̂) d²κ,   p(q) = σ² ℓ³ e^{−ℓ²|q|²/2}
//! ```
//! A statistically homogeneous beam whose cross-spectral density across `d̂` is the packet's
//! `e^{−|ξ⊥|²/2w²}` is the incoherent superposition of the plane waves of its angular spectrum
//! `Ã` (κ the transverse wave vector; evanescent ones, `|κ| > k`, carry `e^{−(kw)²/2}` and are
//! left out). Each scatters by the exact first-Born formula of a plane wave: the PSD of `δε`
//! at `k r̂ − K`, times `m = 1` (scalar) or `(1 + (K̂·r̂)²)/2` (dipole, unpolarized). `p` is the
//! unitary transform of `R = σ² e^{−r²/2ℓ²}` (`tests/medium/conventions.rs`). The crate's
//! packet puts the same plane waves on the tangent plane, `K = k d̂ + κ`, and the dipole factor
//! at `d̂`; with that one change (`exact = false` below) this sum reproduces the crate to 3e-13,
//! which checks the quadrature and the constants, so what remains is the paraxial error.
//!
//! # The error
//! `K` lies `δ = |κ|²/2k` behind the plane along `d̂`, and `h·d̂ = −k(1 − cos Θ)`, so the PSD's
//! exponent gains `ℓ²kδ(1 − cos Θ) = ℓ²|κ|²(1 − cos Θ)/2`. Averaged over `Ã` (`⟨|κ|²⟩ = 2/w²`) the
//! exact sum exceeds the packet by `e ≈ 2(ℓ/w)²(1 − cos Θ)/2`; exactly backward
//! `e = 2ℓ²/(w² − ℓ²)`. Off axis the PSD pulls the mean plane wave toward the exit by
//! `ℓ²k sin Θ/w²`, adding the factor `1 + (kℓ²/w)² sin²Θ`; the dipole factor at `d̂` instead of at
//! each `K̂` adds `O((ℓ/w)² sin²Θ + 1/(kw)²)`. The bound asserted:
//! ```text
//! |e| ≤ C [a² ((1 − cos Θ)/2 · (1 + b² sin²Θ) + D sin²Θ) + D/(kw)²],   a² = ℓ²/(w² − ℓ²),  b = kℓ²/w
//! ```
//! `D` = 1 for the dipole, 0 for the scalar scatterer, `e = I_exact/I_packet − 1`.

use std::f64::consts::{PI, TAU};

use gmueller::frame::Frame;
use gmueller::interaction::{Full, Kernel, Partial};
use gmueller::medium::{Dipole, RandomMedium, Scalar};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::verify::quadrature::integrate;
use nalgebra::Vector3;

/// `ln dI/dV(r̂)` per unit `S0` by the sum of plane waves (module docs) for a beam along `+z`,
/// exit at `Θ` in the `xz` plane; `exact = false` puts the plane waves on the tangent plane and
/// the dipole factor at `d̂` (the packet's approximation). 2-D adaptive Gauss–Legendre over `κ`
/// about the integrand's centre, ±16 of its widths.
fn plane_wave_sum(
    k: f64,
    w: f64,
    ell: f64,
    sigma: f64,
    theta: f64,
    dipole: bool,
    exact: bool,
) -> f64 {
    let r = Vector3::new(theta.sin(), 0.0, theta.cos());
    let h = (r - Vector3::z()) * k;
    // The exponent at the paraxial integrand's peak, factored out (it reaches −2(kℓ)²).
    let e0 = 0.5 * ell * ell * (h.z * h.z + w * w * h.x * h.x / (w * w + ell * ell));
    let centre = ell * ell * h.x / (w * w + ell * ell);
    let extent = 16.0 / (w * w - ell * ell).max(0.25 * w * w).sqrt();
    let f = |kx: f64, ky: f64| -> f64 {
        let rho2 = kx * kx + ky * ky;
        if rho2 >= k * k {
            return 0.0;
        }
        let kz = if exact { (k * k - rho2).sqrt() } else { k };
        let kv = Vector3::new(kx, ky, kz);
        let q = r * k - kv;
        let m = if dipole {
            let c = if exact { kv.dot(&r) / k } else { r.z };
            0.5 * (1.0 + c * c)
        } else {
            1.0
        };
        (-0.5 * ell * ell * q.norm_squared() - 0.5 * w * w * rho2 + e0).exp() * m
    };
    let j = integrate(
        &mut |kx| integrate(&mut |ky| f(kx, ky), -extent, extent, 8, 1e-15),
        centre - extent,
        centre + extent,
        8,
        1e-15,
    );
    // (k⁴/16π²) (2π)^{3/2} σ² ℓ³ · w²/2π
    let ln_c = 4.0 * k.ln() - (16.0 * PI * PI).ln()
        + 1.5 * TAU.ln()
        + 2.0 * sigma.ln()
        + 3.0 * ell.ln()
        + 2.0 * w.ln()
        - TAU.ln();
    ln_c - e0 + j.ln()
}

/// The packet's `ln dI/dV` per unit `S0` (`Full · Partial`, unpolarized, one isotropic shape of
/// width `w`, unbounded `σ_zz`: monochromatic light).
fn packet_value(k: f64, w: f64, ell: f64, sigma: f64, theta: f64, dipole: bool) -> f64 {
    let lambda = TAU / k;
    let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let p = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(w).unwrap(),
        frame,
        lambda,
    )
    .unwrap();
    let psd = GaussianPsd::<f64, 3>::isotropic(sigma, ell).unwrap();
    let r = Vector3::new(theta.sin(), 0.0, theta.cos());
    let kernel = Kernel::<Full, Partial>::default();
    let s0 = if dipole {
        RandomMedium::new(psd, Dipole)
            .differential_scattering(&kernel, &p, r)
            .unwrap()
            .light
            .s0()
    } else {
        RandomMedium::new(psd, Scalar)
            .differential_scattering(&kernel, &p, r)
            .unwrap()
            .light
            .s0()
    };
    s0.ln()
}

/// The bound's shape (module docs) without `C`.
fn shape(k: f64, w: f64, ell: f64, theta: f64, dipole: bool) -> f64 {
    let d = if dipole { 1.0 } else { 0.0 };
    let a2 = ell * ell / (w * w - ell * ell);
    let b2 = (k * ell * ell / w).powi(2);
    let s2 = theta.sin().powi(2);
    a2 * ((1.0 - theta.cos()) / 2.0 * (1.0 + b2 * s2) + d * s2) + d / (k * w).powi(2)
}

/// The measured `C` (max over the grid of `|e|/shape`) and the largest deviation of the
/// tangent-plane sum from the crate, over `w/λ × kℓ × Θ` (`ℓ ≤ w/2`), printing the table.
fn sweep(widths: &[f64], kls: &[f64], degrees: &[f64]) -> ([f64; 2], f64) {
    let (lambda, sigma) = (1.0, 1e-3);
    let k = TAU / lambda;
    let mut c = [0.0f64; 2];
    let mut flat = 0.0f64;
    let header: String = degrees.iter().map(|d| format!(" {d:>14}°")).collect();
    for dipole in [false, true] {
        println!(
            "{}: e = I_exact/I_packet − 1 (ratio to the bound's shape) at Θ =\n  w/λ     kℓ   ℓ/w{header}",
            if dipole { "Dipole" } else { "Scalar" }
        );
        for &wl in widths {
            for &kl in kls {
                let (w, ell) = (wl * lambda, kl / k);
                if ell > 0.5 * w {
                    continue;
                }
                let mut line = format!("{wl:>5} {kl:>6.2} {:.3}", ell / w);
                for &deg in degrees {
                    let t = f64::to_radians(deg);
                    let ours = packet_value(k, w, ell, sigma, t, dipole);
                    let exact = plane_wave_sum(k, w, ell, sigma, t, dipole, true);
                    let tangent = plane_wave_sum(k, w, ell, sigma, t, dipole, false);
                    flat = flat.max((tangent - ours).abs());
                    let e = (exact - ours).exp_m1();
                    let ratio = e.abs() / shape(k, w, ell, t, dipole);
                    c[usize::from(dipole)] = c[usize::from(dipole)].max(ratio);
                    line += &format!(" {e:+.2e} ({ratio:.2})");
                }
                println!("{line}");
            }
        }
    }
    println!(
        "C measured: scalar {:.4}, dipole {:.4}; tangent-plane sum vs the crate: {flat:.1e} in ln",
        c[0], c[1]
    );
    (c, flat)
}

/// The asserted constant (module docs): the measured maximum of `|e|/shape` over the default
/// grid is 2.0106 (scalar, w = 2 λ, kℓ = 0.5, 150°–180°: the next order in `(ℓ/w)²`) and 1.971
/// (dipole, w = 5 λ, kℓ = 10, backward); the leading-order derivation gives 2 for the scalar
/// scatterer, exactly so backward.
const C: f64 = 2.02;

/// The packet against the exact plane-wave sum over w = 2–50 λ, kℓ = 0.5–10 (ℓ ≤ w/2), Θ =
/// 10°–180°, scalar and dipole: the tangent-plane sum reproduces the crate to 1e-11 (measured
/// 3.1e-13: the oracle's own check), and `|e| ≤ C · shape` with `C` = 2.02 (module docs). The issue's
/// numbers: backward, w = 2 λ, kℓ = 3.54 (its correlation `σ²e^{−r²/ℓ'²}` with kℓ' = 5):
/// `e` = 16.5 % (dipole); w = 20 λ: 1.52e-3.
#[test]
fn the_packet_against_an_exact_plane_wave_sum() {
    let (c, flat) = sweep(
        &[2.0, 5.0, 20.0, 50.0],
        &[0.5, 2.0, 5.0 / 2f64.sqrt(), 5.0, 10.0],
        &[10.0, 30.0, 60.0, 90.0, 120.0, 150.0, 180.0],
    );
    assert!(
        flat <= 1e-11,
        "the tangent-plane sum is not the crate: {flat:e}"
    );
    assert!(c[0] <= C && c[1] <= C, "C = {c:?} > {C}");
    // The issue's two numbers, to the printed digits.
    let k = TAU;
    for (wl, expected) in [(2.0, 0.165), (20.0, 1.52e-3)] {
        let ell = 5.0 / 2f64.sqrt() / k;
        let e = (plane_wave_sum(k, wl, ell, 1e-3, PI, true, true)
            - packet_value(k, wl, ell, 1e-3, PI, true))
        .exp_m1();
        assert!(
            (e / expected - 1.0).abs() < 0.01,
            "backward at w = {wl} λ: {e:e}"
        );
    }
}

/// The same over a finer and wider grid (w = 1.5–200 λ, kℓ = 0.1–10, every 10°):
/// `cargo test --release --test integration medium::paraxial:: -- --ignored --nocapture`.
#[test]
#[ignore = "a larger sweep, several minutes in release"]
fn the_packet_against_an_exact_plane_wave_sum_wide() {
    let degrees: Vec<f64> = (1..=18).map(|i| 10.0 * f64::from(i)).collect();
    let (c, flat) = sweep(
        &[1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0],
        &[0.1, 0.3, 1.0, 2.0, 5.0 / 2f64.sqrt(), 5.0, 10.0],
        &degrees,
    );
    assert!(
        flat <= 1e-11,
        "the tangent-plane sum is not the crate: {flat:e}"
    );
    assert!(c[0] <= C && c[1] <= C, "C = {c:?} > {C}");
}
