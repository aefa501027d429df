//! The medium's conventions, each against an independent computation: `GaussianPsd::isotropic(σ,
//! ℓ)` in 3-D is the unitary Fourier transform of `σ² e^{−r²/2ℓ²}` (radial quadrature of the
//! transform); `h = k(r̂ + ŝ)` with ŝ pointing toward the source (the lobe of a long correlation
//! peaks forward, away from the source, by exactly `p(0)/p(2k)`); the PSD is that of the
//! relative permittivity `δε ≈ 2δn`: against the classical cross-section of refractive-index
//! fluctuations, a δε PSD built from δn is exact and a δn PSD passed in unchanged is 4 times low.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use crate::common;

use common::quadrature::integrate;
use common::{Tol, assert_close};
use gmueller::frame::Frame;
use gmueller::interaction::{Full, Kernel, PlaneWave};
use gmueller::medium::{Dipole, PhaseFunction, RandomMedium, ScatteringGeometry};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{GaussianPsd, Psd};
use gmueller::stokes::Stokes;
use nalgebra::Vector3;

/// `(2π)^{−3/2} ∫ R(|x|) e^{−iq·x} d³x = (2π)^{−3/2} 4π ∫₀^∞ R(r) r² sinc(qr) dr` (an isotropic
/// function's 3-D transform), by adaptive quadrature on `[0, 14 ℓ]`.
fn radial_transform(r_of: &dyn Fn(f64) -> f64, q: f64, ell: f64) -> f64 {
    let mut f = |r: f64| {
        let x = q * r;
        let sinc = if x.abs() < 1e-8 { 1.0 } else { x.sin() / x };
        r_of(r) * r * r * sinc
    };
    4.0 * PI * integrate(&mut f, 0.0, 14.0 * ell, 28, 1e-16) / TAU.powf(1.5)
}

/// `GaussianPsd::<_, 3>::isotropic(σ, ℓ)` is `F{σ² e^{−r²/2ℓ²}}` under the crate's unitary
/// transform, at any direction of `q` (to 1e-12), and is not the transform of the other common
/// reading `σ² e^{−r²/ℓ²}` (SCATMECH's, off by a factor ≥ 2.8 at `q = 0`).
#[test]
fn gaussian_psd_is_the_transform_of_its_correlation() {
    let (sigma, ell) = (0.03, 0.7);
    let psd = GaussianPsd::<f64, 3>::isotropic(sigma, ell).unwrap();
    let ours = |r: f64| sigma * sigma * (-r * r / (2.0 * ell * ell)).exp();
    let other = |r: f64| sigma * sigma * (-r * r / (ell * ell)).exp();
    let dirs = [
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(0.6, -0.48, 0.64),
        Vector3::new(-0.36, 0.8, 0.48),
    ];
    for (i, q) in [0.0, 0.3, 1.0, 2.2, 4.0].into_iter().enumerate() {
        let reference = radial_transform(&ours, q, ell);
        let value = psd.value(&(dirs[i % 3] * q));
        assert_close(
            &format!("p(|q| = {q})"),
            value,
            reference,
            Tol::new(1e-16 * reference.abs(), 1e-12),
        );
        if q == 0.0 {
            let wrong = radial_transform(&other, q, ell);
            assert!(
                (value / wrong - 2.0f64.powf(1.5)).abs() < 1e-10,
                "σ² e^{{−r²/ℓ²}} would give {wrong:e}, not {value:e}"
            );
        }
    }
    assert_close(
        "∫p d³q = (2π)^{3/2} σ²",
        Psd::<f64, 3>::integral(&psd),
        TAU.powf(1.5) * sigma * sigma,
        Tol::new(0.0, 1e-14),
    );
}

/// `h = k(r̂ + ŝ)` with ŝ = −d̂ pointing toward the source: the scattering vector is 0 forward
/// (r̂ = d̂, away from the source) and `2kŝ` back toward the source, and a medium of long
/// correlation (kℓ = 3) scatters forward more than backward by exactly
/// `p(0)/p(2k) = e^{2(kℓ)²}` (the dipole factor is 1 both ways); with `h = k(r̂ − ŝ)` the two
/// would swap.
#[test]
fn scattering_vector_points_toward_the_source_side() {
    let lambda = 0.5;
    let k = TAU / lambda;
    let d = Vector3::new(0.3, -0.4, 0.5).normalize();
    let frame = Frame::from_direction_and_x(d, Vector3::x()).unwrap();
    let s_hat = -d;
    let generic = Vector3::new(-0.2, 0.9, 0.1).normalize();
    for r in [d, s_hat, generic] {
        let g = ScatteringGeometry::new(&frame, k, r).unwrap();
        let expected = (r + s_hat) * k;
        assert!(
            (g.scattering_vector() - expected).amax() <= 1e-13 * k,
            "h at r̂ = {r:?}: {:?} vs k(r̂ + ŝ) = {expected:?}",
            g.scattering_vector()
        );
    }
    let ell = 3.0 / k;
    let medium = RandomMedium::new(GaussianPsd::<f64, 3>::isotropic(1e-3, ell).unwrap(), Dipole);
    let light = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(20.0).unwrap(),
        frame,
        lambda,
    )
    .unwrap();
    let kernel = Kernel::<Full, PlaneWave>::default();
    let at = |r: Vector3<f64>| {
        medium
            .differential_scattering(&kernel, &light, r)
            .unwrap()
            .light
            .s0()
    };
    let ratio = at(d) / at(s_hat);
    assert_close(
        "forward / backward",
        ratio,
        (2.0 * (k * ell).powi(2)).exp(),
        Tol::new(0.0, 1e-12),
    );
}

/// The classical cross-section per unit volume of refractive-index fluctuations (first Born,
/// background index 1): `σ(Θ) = 2π k⁴ Φ_n(K) sin²χ`, `K = 2k sin(Θ/2)`, `Φ_n` the 3-D spectrum of
/// `δn` with `(2π)^{−3}` in the transform, `χ` the angle between the incident field and the
/// exit (V. I. Tatarskii, *The Effects of the Turbulent Atmosphere on Wave Propagation*, 1971;
/// A. Ishimaru, *Wave Propagation and Scattering in Random Media*, vol. 2, 1978, ch. 16;
/// J. D. Rogers, İ. R. Çapoğlu & V. Backman, Opt. Lett. 34, 1891, 2009). For
/// `B_n = σ_n² e^{−r²/2ℓ²}`: `Φ_n = σ_n² ℓ³ (2π)^{−3/2} e^{−K²ℓ²/2}`; unpolarized light averages
/// `sin²χ` to `(1 + cos²Θ)/2`.
fn index_cross_section(k: f64, sigma_n: f64, ell: f64, cos_theta: f64) -> f64 {
    let kk2 = 2.0 * k * k * (1.0 - cos_theta);
    let phi_n = sigma_n * sigma_n * ell.powi(3) * TAU.powf(-1.5) * (-kk2 * ell * ell / 2.0).exp();
    2.0 * PI * k.powi(4) * phi_n * 0.5 * (1.0 + cos_theta * cos_theta)
}

/// The PSD is of the relative permittivity: with `ε = (1 + δn)²`, `δε = 2δn + δn²`, so the
/// PSD of `δε` is 4 times that of `δn` (to `O(δn)`). A medium built from
/// `GaussianPsd::isotropic(2σ_n, ℓ)` scatters the classical `2πk⁴Φ_n sin²χ` of index
/// fluctuations (`dI/dV` at five angles to 1e-12, `σ_s` against the angular integral to 1e-10),
/// and the same `δn` spectrum passed in unchanged (`isotropic(σ_n, ℓ)`) scatters a quarter of it.
#[test]
fn the_psd_is_of_the_permittivity_not_the_index() {
    let lambda = 0.6;
    let k = TAU / lambda;
    let (sigma_n, ell) = (1e-3, 0.15);
    let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let light = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(30.0).unwrap(),
        frame,
        lambda,
    )
    .unwrap();
    let kernel = Kernel::<Full, PlaneWave>::default();
    let from_epsilon = RandomMedium::new(
        GaussianPsd::<f64, 3>::isotropic(2.0 * sigma_n, ell).unwrap(),
        Dipole,
    );
    let from_index = RandomMedium::new(
        GaussianPsd::<f64, 3>::isotropic(sigma_n, ell).unwrap(),
        Dipole,
    );
    for theta in [0.1f64, 0.7, FRAC_PI_2, 2.4, PI] {
        let r = Vector3::new(theta.sin(), 0.0, theta.cos());
        let classical = index_cross_section(k, sigma_n, ell, theta.cos());
        let right = from_epsilon
            .differential_scattering(&kernel, &light, r)
            .unwrap()
            .light
            .s0();
        let wrong = from_index
            .differential_scattering(&kernel, &light, r)
            .unwrap()
            .light
            .s0();
        assert_close(
            &format!("δε PSD at Θ = {theta}"),
            right,
            classical,
            Tol::new(0.0, 1e-12),
        );
        assert_close(
            &format!("δn PSD as δε at Θ = {theta}: a quarter"),
            wrong / classical,
            0.25,
            Tol::new(0.0, 1e-12),
        );
    }
    let total = TAU
        * integrate(
            &mut |mu| index_cross_section(k, sigma_n, ell, mu),
            -1.0,
            1.0,
            16,
            1e-20,
        );
    let sigma_s = |m: &RandomMedium<GaussianPsd<f64, 3>, Dipole>| {
        PhaseFunction::new(m, kernel)
            .prepare(&light)
            .unwrap()
            .scattering_coefficient()
    };
    let (right, wrong) = (sigma_s(&from_epsilon), sigma_s(&from_index));
    println!(
        "σ_s: classical {total:.10e}, δε PSD {right:.10e}, δn PSD {wrong:.10e} (ratio {:.6})",
        total / wrong
    );
    assert_close("σ_s", right, total, Tol::new(0.0, 1e-10));
    assert_close("σ_s ratio", total / wrong, 4.0, Tol::new(0.0, 1e-10));
}
