//! Verifies energy conservation of the S2.20 kernel by hemispherical quadrature in exit-tangent
//! coordinates: the specular lobe's normalisation (`α R_Fresnel`), the total reflected fraction
//! over roughness and coherence width (≤ 1 where the first-order model is valid, for rough glass
//! and a lossless phase screen up to 45°), and the phase screen's documented excess at grazing
//! incidence against an independent first-order oracle of the model.
//!
//! Measured energy table (printed by `energy_reflected_fraction_table`, run with
//! `cargo test --test integration interaction::energy:: -- --nocapture`): see that test's doc
//! comment.

use crate::common;

use std::f64::consts::{PI, TAU};

use common::hemisphere::{Hemisphere, hemisphere_integral};
use common::scene::{DEG, dir, fresnel_rs_rp, glass, packet, surface};
use common::{Tol, assert_close, gauss_legendre};
use gmueller::interaction::pbsdf::{ConstantMueller, Pbsdf, PhaseScreen};
use gmueller::interaction::{
    Geometry, Intensity, Kernel, OneShape, Partial, PlaneWave, RoughSurface,
};
use gmueller::mueller::Mueller;
use gmueller::psd::GaussianPsd;
use nalgebra::Vector2;

/// Reflected fractions (specular, scattered) of unpolarized light: `∫ L cos θ_o dω / (S0 cos θ_i)`.
fn reflected_fraction<Sp: Pbsdf<f64>, Sc: Pbsdf<f64>>(
    material: &RoughSurface<GaussianPsd<f64, 2>, Sp, Sc>,
    theta_i: f64,
    width: f64,
    lambda: f64,
) -> (f64, f64) {
    let pk = packet([1.0, 0.0, 0.0, 0.0], width, theta_i, 0.0, lambda);
    let r0 = Vector2::new(theta_i.sin(), 0.0);
    let kernel = Kernel::<OneShape, Partial>::default();
    let [spec, scat] = hemisphere_integral(r0, 96, Hemisphere::Above, &mut |exit| {
        let Ok(g) = Geometry::for_packet(&pk, &surface(), exit) else {
            return [0.0, 0.0];
        };
        let r = kernel.evaluate(material, &pk, &g);
        [r.specular.s0(), r.scattered.s0()]
    });
    (spec / theta_i.cos(), scat / theta_i.cos())
}

/// The specular lobe alone integrates to `α(θ_o = θ_i) R_Fresnel` for a nearly smooth surface
/// and a wide packet (w = 100 λ): an independent check of the lobe constant `2π|Σ|^{1/2} g`,
/// with `R = (R_s + R_p)/2` from the textbook Fresnel formulas. Tolerance 1e-4 relative (the
/// lobe's width in exit-tangent space is ~1/(k w) ≈ 1.6e-3, so `cos θ_o` and α vary across it by
/// second-order amounts ~1e-6; the quadrature error is below that).
#[test]
fn specular_lobe_integrates_to_attenuated_fresnel_reflectance() {
    let lambda = 0.5;
    let k = TAU / lambda;
    for ti_deg in [0.0, 30.0, 60.0] {
        let ti = ti_deg * DEG;
        let sigma = 1e-3;
        let material = glass(sigma, 2.0);
        let (spec, _) = reflected_fraction(&material, ti, 100.0 * lambda, lambda);
        let (rs, rp) = fresnel_rs_rp(ti.cos(), 1.5);
        let alpha = (-(2.0 * k * sigma * ti.cos()).powi(2)).exp();
        let expected = alpha * (rs + rp) * 0.5;
        println!("θi = {ti_deg}°: ∫specular = {spec:.8e}, α R = {expected:.8e}");
        assert_close(
            &format!("specular fraction θi = {ti_deg}°"),
            spec,
            expected,
            Tol::new(0.0, 1e-4),
        );
    }
}

/// Prints the table of total reflected fractions at incidence `theta_i` and returns, per
/// (kσ, w/λ), the total and whether the case lies within the first-order validity range
/// `kσ (cos θ_i + 1) < 0.5` (every exit direction).
fn energy_table(ti_deg: f64) -> Vec<(f64, f64, f64, bool)> {
    let lambda = 0.5;
    let k = TAU / lambda;
    let ell = 2.0 * lambda;
    let widths = [0.5, 1.0, 3.0, 10.0, 30.0, 100.0];
    let ksigmas = [0.01, 0.03, 0.1, 0.2, 0.3, 0.5, 1.0];
    let ti = ti_deg * DEG;
    let mut out = Vec::new();
    println!(
        "\nθi = {ti_deg}°: total (specular + scattered) reflected fraction, phase screen |r|² = 1"
    );
    print!("{:>8}", "kσ \\ w/λ");
    for w in widths {
        print!("{w:>22}");
    }
    println!();
    for ks in ksigmas {
        let sigma = ks / k;
        let screen = lossless_screen(sigma, ell);
        let glass = glass(sigma, ell);
        let valid = ks * (ti.cos() + 1.0) < 0.5;
        print!("{ks:>8}");
        for w in widths {
            let (s, d) = reflected_fraction(&screen, ti, w * lambda, lambda);
            let (gs, gd) = reflected_fraction(&glass, ti, w * lambda, lambda);
            print!("  {:.4} ({s:.3}+{d:.3})", s + d);
            assert!(
                gs + gd <= 1.0,
                "glass reflects more than it receives: {}",
                gs + gd
            );
            out.push((ks, w, s + d, valid));
        }
        println!("{}", if valid { "" } else { "   (outside validity)" });
    }
    out
}

/// Energy: the total reflected fraction `∫ (L_spec + L_scat) cos θ_o dω / (S0 cos θ_i)` of
/// unpolarized light on a lossless phase screen (`|r|² = 1`, mirror specular part), Gaussian PSD
/// (ℓ = 2λ, λ = 0.5 µm), OneShape×Partial (= Full for unpolarized light), over kσ and the
/// coherence width w, at θi = 0° and 45°; asserted ≤ 1 + 1e-5 where the first-order model is
/// valid (`kσ (cos θ_i + 1) < 0.5`). Glass (Fresnel + Rayleigh–Rice) must stay ≤ 1 everywhere.
/// The 75° table is printed too (for the record below); its check is
/// `energy_at_grazing_incidence`. The quadrature is converged to ~1e-8 (doubling the angles and
/// going from 12 to 20 Gauss–Legendre points per panel changed no printed digit of the 75° case).
///
/// Measured (`cargo test --test integration interaction::energy:: -- --nocapture`),
/// total fraction, rows kσ, columns w/λ = 0.5, 1, 3, 10, 30, 100:
/// ```text
/// θi = 0°   0.01  0.8825 0.9740 0.9972 0.9997 1.0000 1.0000
///           0.1   0.8815 0.9728 0.9959 0.9985 0.9987 0.9987
///           0.2   0.8724 0.9617 0.9842 0.9867 0.9869 0.9869
///           0.3   0.8413 0.9236 0.9438 0.9460 0.9462 0.9462   (outside validity)
///           1     0.1124 0.0979 0.0931 0.0926 0.0925 0.0925   (outside validity)
/// θi = 45°  0.01  0.7751 0.9412 0.9943 0.9995 0.9999 1.0000
///           0.2   0.7720 0.9369 0.9896 0.9948 0.9952 0.9953
///           0.5   0.6982 0.8494 0.8969 0.9015 0.9019 0.9020   (outside validity)
/// θi = 75°  0.01  0.6015 0.7276 0.9500 0.9962 0.9996 1.0000
///           0.03  0.6016 0.7277 0.9501 0.9963 0.9997 1.0001
///           0.1   0.6023 0.7289 0.9514 0.9975 1.0009 1.0013
///           0.2   0.6047 0.7327 0.9554 1.0014 1.0048 1.0052
///           0.3   0.6081 0.7384 0.9615 1.0072 1.0106 1.0110
///           0.5   0.6148 0.7522 0.9759 1.0208 1.0240 1.0244   (outside validity)
///           1     0.5893 0.7485 0.9674 1.0074 1.0103 1.0106   (outside validity)
/// (75°, kσ = 0.1, w = 100λ: specular 0.99729 = α, scattered 0.00403 vs 1 − α = 0.00268)
/// ```
/// Narrow coherence loses energy (the lobe spills past the horizon and is weighted by
/// `cos θ_o/cos θ_i`); at grazing incidence the phase screen EXCEEDS 1 even inside the stated
/// validity range: a property of the model, not of the kernel — see `energy_at_grazing_incidence`.
#[test]
fn energy_reflected_fraction_table() {
    for ti_deg in [0.0, 45.0] {
        for (ks, w, total, valid) in energy_table(ti_deg) {
            if valid {
                assert!(
                    total <= 1.0 + 1e-5,
                    "θi = {ti_deg}°, kσ = {ks}, w = {w}λ: reflected fraction {total} > 1"
                );
            }
        }
    }
    let _printed_for_the_record = energy_table(75.0);
}

/// The lossless phase screen at λ = 0.5 µm, `R = σ² exp(−r²/(2ℓ²))`, mirror specular part.
fn lossless_screen(
    sigma: f64,
    ell: f64,
) -> RoughSurface<GaussianPsd<f64, 2>, ConstantMueller<f64>, PhaseScreen<f64>> {
    RoughSurface {
        psd: GaussianPsd::isotropic(sigma, ell).unwrap(),
        specular: ConstantMueller(Mueller::identity()),
        scatter: PhaseScreen::new(1.0).unwrap(),
    }
}

/// The kernel's plane-wave (w → ∞) reflected fractions (specular, scattered) of unpolarized
/// light: the specular lobe is then a Dirac delta of weight `α M₀₀` (`M₀₀ = 1`, α the kernel's
/// `attenuation` at the specular direction); the scattered part is `∫ L cos θ_o dω / cos θ_i` of
/// `Kernel::<Intensity, PlaneWave>` by the hemisphere quadrature above.
fn plane_wave_fraction(sigma: f64, ell: f64, theta_i: f64, lambda: f64) -> (f64, f64) {
    // 4× the angles of `reflected_fraction`: at 85° the lobe hugs the horizon (96 angles were
    // 2.1e-7 off the oracle at ℓ = 2λ, 192 angles 3e-10 at ℓ = 10λ).
    const N_ANGLE: usize = 384;
    let material = lossless_screen(sigma, ell);
    let pk = packet([1.0, 0.0, 0.0, 0.0], 10.0, theta_i, 0.0, lambda);
    let kernel = Kernel::<Intensity, PlaneWave>::default();
    let g = Geometry::for_packet(&pk, &surface(), dir(theta_i, 0.0)).unwrap();
    let specular = kernel.evaluate(&material, &pk, &g).attenuation;
    let r0 = Vector2::new(theta_i.sin(), 0.0);
    let [scat, _] = hemisphere_integral(r0, N_ANGLE, Hemisphere::Above, &mut |exit| {
        let Ok(g) = Geometry::for_packet(&pk, &surface(), exit) else {
            return [0.0, 0.0];
        };
        [kernel.evaluate(&material, &pk, &g).scattered, 0.0]
    });
    (specular, scat / theta_i.cos())
}

/// The phase-screen model's own first-order reflected fractions, from its definition and not
/// from the kernel: a plane wave on `z = h(x)`, `E(r̂) = ∫ e^{−i v h(x)} e^{−i h_t·x} d²x`,
/// `dP/dΩ = cos²θ_o/λ² ⟨|E|²⟩`, `⟨e^{−i v (h(x) − h(x'))}⟩ = e^{−v²σ²} e^{v² R(x − x')}` for
/// Gaussian heights; the first order of `e^{v² R}` gives, per unit area and with
/// `d²h_t = k² cos θ_o dω`, `2π p(h) = 2π σ² ℓ² exp(−|h|² ℓ²/2)` (unitary transform of `R`):
/// ```text
/// specular  = α_s = exp(−(2kσ cos θ_i)²)
/// scattered = 1/cos θ_i ∫ cos²θ_o/λ² · e^{−v²σ²} v² 2π p(h_t) dω,   v = k (cos θ_i + cos θ_o)
/// ```
/// integrated in `(θ_o, φ_o)` with Gauss–Legendre panels (24 × 12 in `θ_o`, 48 × 12 in `φ_o`
/// over the half-space `φ_o ∈ [0, π]`, doubled): going to 90 × 16 and 180 × 16 changed the
/// scattered part by < 3e-12 relative at `θ_i` = 0°, 45°, 75°, 85° (ℓ = 2λ), and 96 or 192
/// azimuth panels by < 6e-13 for ℓ = 10λ.
fn phase_screen_first_order(sigma: f64, ell: f64, theta_i: f64, lambda: f64) -> (f64, f64) {
    let k = TAU / lambda;
    let (si, ci) = theta_i.sin_cos();
    let (x, w) = gauss_legendre(12);
    // Nodes and weights of `n` equal Gauss–Legendre panels on [lo, hi].
    let panels = |lo: f64, hi: f64, n: usize| -> Vec<(f64, f64)> {
        let step = (hi - lo) / n as f64;
        (0..n)
            .flat_map(|p| {
                let mid = lo + (p as f64 + 0.5) * step;
                x.iter()
                    .zip(&w)
                    .map(move |(x, w)| (mid + 0.5 * step * x, 0.5 * step * w))
            })
            .collect()
    };
    let azimuths = panels(0.0, PI, 48);
    let mut total = 0.0;
    for (t, wt) in panels(0.0, PI / 2.0, 24) {
        let (st, co) = t.sin_cos();
        let v = k * (ci + co);
        let radial = co * co * (-(v * sigma).powi(2)).exp() * v * v * st * wt;
        for &(p, wp) in &azimuths {
            let h2 = k * k * ((st * p.cos() - si).powi(2) + (st * p.sin()).powi(2));
            total += 2.0 * wp * radial * (-0.5 * h2 * ell * ell).exp();
        }
    }
    let psd_scale = TAU * sigma * sigma * ell * ell;
    let specular = (-(2.0 * k * sigma * ci).powi(2)).exp();
    (specular, total * psd_scale / (lambda * lambda * ci))
}

/// Grazing incidence: the lossless phase screen reflects MORE than it receives, and that is the
/// model's own first-order total, not a kernel error. For ℓ = 2λ and 10λ, θi = 0°…85° and
/// kσ = 0.1, 0.2, 0.3 inside the stated validity range `kσ (cos θ_i + 1) < 0.5`, the kernel's
/// plane-wave total (`plane_wave_fraction`) equals the model's first-order total computed from
/// its definition (`phase_screen_first_order`, an independent quadrature) to 1e-10 relative in
/// the scattered part (measured ≤ 2e-12; with 96 instead of 384 angles the kernel-side
/// quadrature was 2.1e-7 off at 85°). The total is ≤ 1 + 1e-5 at θi ≤ 45° (as in the table
/// above) and, for ℓ = 2λ, above 1 at 75° and 85° — by `(ρ − 1)(1 − α_s)`, with
/// `ρ = scattered/(1 − α_s)` printed per case (the `PhaseScreen` docs list it and say why).
/// The Partial level at w = 100λ (the table above: 1.00519 at 75°, kσ = 0.2) approaches the
/// plane-wave total as `1/w²` (30λ → 100λ: the gap shrinks from 4.2e-4 to 3.8e-5): within 1e-4.
///
/// The model itself is checked against brute force by the `wave_tracer` program of `validation/`
/// (`cargo run --release -p gmueller-validation --bin wave_tracer -- --energy`): the brute-force hemispherical
/// total of a coherent Gaussian beam (W = 40 µm at 75°, 100 µm at 85°; 128 realizations)
/// agrees with the model's analytic all-order total for that beam within 1 s.e. and is above 1
/// by as much: normalised by what a mirror reflects of the same beam, 75°, kσ = 0.2:
/// 1.005480 ± 0.000017 (analytic 1.005474); 85°, kσ = 0.2: 1.015817 ± 0.000013 (analytic
/// 1.015827). The first-order totals of the same beam are 2.4e-4 and 1.8e-4 lower (the higher
/// orders of `e^{v²R}`); this test's plane-wave first-order totals are 1.005230 and 1.015601.
#[test]
fn energy_at_grazing_incidence() {
    let lambda = 0.5;
    let k = TAU / lambda;
    for ell_per_lambda in [2.0, 10.0] {
        let ell = ell_per_lambda * lambda;
        for ti_deg in [0.0, 45.0, 60.0, 70.0, 75.0, 80.0, 85.0] {
            let ti = ti_deg * DEG;
            // Only inside the stated first-order validity range.
            for ks in [0.1, 0.2, 0.3]
                .into_iter()
                .filter(|ks| ks * (ti.cos() + 1.0) < 0.5)
            {
                let sigma = ks / k;
                let (spec, scat) = plane_wave_fraction(sigma, ell, ti, lambda);
                let (m_spec, m_scat) = phase_screen_first_order(sigma, ell, ti, lambda);
                let rho = m_scat / (1.0 - m_spec);
                let what = format!("ℓ = {ell_per_lambda}λ, θi = {ti_deg}°, kσ = {ks}");
                println!(
                    "{what}: kernel {:.9} = {spec:.9} + {scat:.9e}, model {:.9} (scattered differ \
                     by {:.1e}); scattered/(1 − α) = {rho:.4}",
                    spec + scat,
                    m_spec + m_scat,
                    scat / m_scat - 1.0
                );
                assert_close(
                    &format!("{what}: specular α"),
                    spec,
                    m_spec,
                    Tol::new(0.0, 1e-13),
                );
                assert_close(
                    &format!("{what}: scattered fraction"),
                    scat,
                    m_scat,
                    Tol::new(0.0, 1e-10),
                );
                if ti_deg <= 45.0 {
                    assert!(spec + scat <= 1.0 + 1e-5, "{what}: {} > 1", spec + scat);
                }
                if ell_per_lambda == 2.0 && ti_deg >= 75.0 {
                    // The documented limit, pinned: the model itself reflects more than 1.
                    assert!(spec + scat > 1.0, "{what}: {}", spec + scat);
                }
            }
        }
    }
    // The finite-coherence level of the table approaches the plane-wave total.
    let (ti, sigma, ell) = (75.0 * DEG, 0.2 / k, 2.0 * lambda);
    let (s, d) = reflected_fraction(&lossless_screen(sigma, ell), ti, 100.0 * lambda, lambda);
    let (m_spec, m_scat) = phase_screen_first_order(sigma, ell, ti, lambda);
    assert_close(
        "75°, kσ = 0.2: Partial at w = 100λ vs the plane-wave model",
        s + d,
        m_spec + m_scat,
        Tol::new(1e-4, 0.0),
    );
}
