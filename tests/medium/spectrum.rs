//! The medium's spectra: the 3-D K-correlation against the transform of its autocorrelation
//! (the Debye–Bueche medium), and what S2.20's longitudinal coherence `σ_zz` does against what
//! bandwidth does.

use crate::common;

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use common::{Tol, assert_close};
use gmueller::frame::Frame;
use gmueller::interaction::{Intensity, Kernel, Partial};
use gmueller::medium::{Dipole, RandomMedium, Scatterer};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{GaussianPsd, KCorrelation, Psd};
use gmueller::stokes::Stokes;
use gmueller::verify::quadrature::integrate;
use nalgebra::Vector3;

fn dir(theta: f64, phi: f64) -> Vector3<f64> {
    Vector3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// The 3-D K-correlation with γ = 3 is the transform of the exponential autocorrelation
/// `R = σ² e^{−r/√T}` (the Debye–Bueche medium): `p(q) = (2π)^{−3/2} (4π/q) ∫₀^∞ R(r) r sin(qr) dr`
/// by quadrature, against `KCorrelation::<_, 3>::value`; and its integral is `(2π)^{3/2} σ²`.
#[test]
fn kcorrelation_3d_is_the_debye_bueche_transform() {
    let (sigma2, t) = (0.3_f64, 0.49_f64);
    let a = t.sqrt();
    let k = KCorrelation::<f64, 3>::new(sigma2, t, 3.0).unwrap();
    for q in [1e-3, 0.3, 1.0, 2.5, 10.0, 40.0] {
        // ∫₀^∞ e^{−r/a} r sin(qr) dr on [0, 60a], panels resolving the oscillation.
        let panels = ((60.0 * a * q) as usize).max(4) * 4;
        let mut f = |r: f64| sigma2 * (-r / a).exp() * r * (q * r).sin();
        let radial = integrate(&mut f, 0.0, 60.0 * a, panels, 1e-15);
        let p = TAU.powf(-1.5) * 4.0 * PI / q * radial;
        let v = k.value(&Vector3::new(q, 0.0, 0.0));
        assert_close(
            &format!("p({q})"),
            v,
            p,
            Tol::new(1e-14 * k.peak_value(), 1e-9),
        );
    }
    assert_close(
        "∫p",
        k.integral(),
        TAU.powf(1.5) * sigma2,
        Tol::new(0.0, 1e-15),
    );
}

/// What the longitudinal coherence `σ_zz` does, against what bandwidth does. S2.20 enters
/// `σ_zz` as a blur of the PSD along d̂ (`Ξ_zz = 1/σ_zz²`); light whose equal-time coherence
/// has that length has a spectrum of width `Δk = 1/σ_zz`, and its frequencies scatter
/// independently, each with its own `h = k'(r̂ − d̂)`:
/// `K_poly = ∫ 𝒩(k'; k, 1/σ_zz²) (k'/k)⁴ (2π)^{3/2} p(k'(r̂ − d̂)) dk'` (no blur forward, a
/// blur of `2/σ_zz` backward). With transverse coherence far wider than ℓ, the packet gives
/// `(1 + ℓ²/σ_zz²)^{−1/2}` of the plane wave forward, bandwidth `E[(k'/k)⁴]`. Measured at
/// `ℓ = σ_zz = 0.3` µm, λ = 0.5 µm (a 26 % bandwidth), relative to the monochromatic plane wave:
/// ```text
///   Θ       packet    bandwidth
///   0       0.7071    1.437
///   0.3     0.7121    1.059
///   π/2     24.69     222.9
///   π       1.05e6    1.87e7
/// ```
/// The test asserts both forward values and prints the table: the medium follows the seed
/// (finite `σ_zz` is S2.20's), and its docs advise `σ_zz = ∞` for per-wavelength packets.
#[test]
fn longitudinal_coherence_against_bandwidth() {
    let (ell, zz, lambda) = (0.3_f64, 0.3_f64, 0.5_f64);
    let k = TAU / lambda;
    let sigma = 1e-3;
    let medium = RandomMedium::new(
        GaussianPsd::<f64, 3>::isotropic(sigma, ell).unwrap(),
        Dipole,
    );
    let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let light = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(1e5).unwrap(),
        frame,
        lambda,
    )
    .unwrap()
    .with_longitudinal_coherence(zz)
    .unwrap();
    let p = |q: f64| sigma * sigma * ell.powi(3) * (-0.5 * (ell * q).powi(2)).exp();
    let poly = |t: f64| {
        let dk = 1.0 / zz;
        let mut f = |kk: f64| {
            let g = (-0.5 * ((kk - k) / dk).powi(2)).exp() / (dk * TAU.sqrt());
            let h = 2.0 * kk * (0.5 * t).sin();
            g * (kk / k).powi(4) * TAU.powf(1.5) * p(h)
        };
        integrate(&mut f, k - 12.0 * dk, k + 12.0 * dk, 24, 1e-18)
    };
    println!("  Θ      packet K³/(2π)^{{3/2}}p(h)   bandwidth K/(2π)^{{3/2}}p(h)");
    for t in [0.0, 0.05, 0.3, FRAC_PI_2, PI] {
        let r = dir(t, 0.0);
        let s = medium
            .differential_scattering(&Kernel::<Intensity, Partial>::default(), &light, r)
            .unwrap()
            .light;
        // K³ from dI/dV = (k⁴/16π²) m̄₀₀ K³ S0.
        let k3 = s / (k.powi(4) / (16.0 * PI * PI) * Dipole.m00(t.cos()));
        let plane = TAU.powf(1.5) * p(2.0 * k * (0.5 * t).sin());
        println!("{t:6.3}   {:.6}   {:.6}", k3 / plane, poly(t) / plane);
        if t == 0.0 {
            assert_close(
                "packet forward",
                k3 / plane,
                (1.0 + (ell / zz).powi(2)).powf(-0.5),
                Tol::new(0.0, 1e-6),
            );
            let m4 = 1.0 + 6.0 / (k * zz).powi(2) + 3.0 / (k * zz).powi(4); // E[(k'/k)⁴]
            assert_close(
                "bandwidth forward",
                poly(t) / plane,
                m4,
                Tol::new(0.0, 1e-9),
            );
        }
    }
}
