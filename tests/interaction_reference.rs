//! Verifies the S2.20 kernel against a published model: in the fully coherent (plane-wave) limit,
//! with the Rayleigh–Rice pBSDF and a Gaussian PSD, the scattered part divided by the roughness
//! attenuation (which first-order theory does not have) and by `cos θ_i` (the kernel is per unit
//! irradiance across the beam, a BRDF per unit irradiance on the surface) must equal
//! SCATMECH's `Microroughness_BRDF_Model` Mueller BRDF (pySCATMECH 0.1.10, Germer, Appl. Opt. 36,
//! 8798, 1997), cases `rayleigh_rice_gaussian` of `tests/data/peer_values.json`, to 1e-9 relative.
//! The same comparison through the partially coherent kernel with a huge coherence width shows
//! continuity into that limit.

mod common;

use common::{Tol, assert_close, matrix4_from_rows};
use gmueller::frame::Frame;
use gmueller::interaction::{
    CoherenceModel, FresnelReflection, Full, Geometry, Kernel, Partial, PlaneWave,
    PolarizationModel, RayleighRice, RoughSurface,
};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussianPsd};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix4, Vector3};
use num_complex::Complex;
use serde_json::Value;

fn cases() -> Vec<Value> {
    common::peer_cases("rayleigh_rice_gaussian")
}

fn f(c: &Value, key: &str) -> f64 {
    c[key].as_f64().unwrap_or_else(|| panic!("missing {key}"))
}

/// The kernel's Mueller BRDF for one SCATMECH case: columns from the responses to the Stokes
/// basis (1,0,0,0), (1,1,0,0), (1,0,1,0), (1,0,0,1), with the packet frame equal to the incident
/// s/p frame (so that T = I), divided by the attenuation and by `cos θ_i`.
fn kernel_mueller_brdf<Pol: PolarizationModel, Coh: CoherenceModel>(
    c: &Value,
    width: f64,
) -> Matrix4<f64> {
    let (lambda, n) = (f(c, "lambda_um"), f(c, "n"));
    let (ti, ts, ps) = (f(c, "theta_i"), f(c, "theta_s"), f(c, "phi_s"));
    // SCATMECH's geometry: incidence in the x–z plane, specular at φ_s = 0, z the normal.
    let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let travel = Vector3::new(ti.sin(), 0.0, -ti.cos());
    let exit = Vector3::new(ts.sin() * ps.cos(), ts.sin() * ps.sin(), ts.cos());
    let frame = Frame::sp(travel, Vector3::z()).unwrap();
    let eta = Complex::new(n, 0.0);
    let material = RoughSurface {
        psd: GaussianPsd::<f64, 2>::from_scatmech(f(c, "sigma_um"), f(c, "length_um")).unwrap(),
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    };
    let kernel = Kernel::<Pol, Coh, ClosedForm>::new(ClosedForm);
    let shape = CoherenceShape::isotropic(width).unwrap();
    let column = |s: [f64; 4]| {
        let stokes = Stokes::new(s[0], s[1], s[2], s[3]).unwrap();
        let packet = WavePacket::from_stokes(stokes, shape, frame, lambda).unwrap();
        let g = Geometry::for_packet(&packet, &surface, exit).unwrap();
        let r = kernel.evaluate(&material, &packet, &g);
        r.scattered.vector() / (r.attenuation * ti.cos())
    };
    let c0 = column([1.0, 0.0, 0.0, 0.0]);
    let mut m = Matrix4::zeros();
    m.set_column(0, &c0);
    for j in 1..4 {
        let mut s = [1.0, 0.0, 0.0, 0.0];
        s[j] = 1.0;
        m.set_column(j, &(column(s) - c0));
    }
    m
}

fn compare(c: &Value, m: &Matrix4<f64>, rel: f64) {
    let reference = matrix4_from_rows(
        &c["mueller_brdf"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| {
                r.as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect()
            })
            .collect::<Vec<Vec<f64>>>(),
    );
    let scale = reference[(0, 0)];
    assert_close(
        "unpolarized BRDF",
        m[(0, 0)],
        f(c, "brdf_unpolarized"),
        Tol::new(0.0, rel),
    );
    for r in 0..4 {
        for col in 0..4 {
            // Entries that vanish in the reference are compared relative to M00.
            assert_close(
                &format!(
                    "Mueller BRDF [{r}][{col}] (θi={}, θs={}, φs={})",
                    f(c, "theta_i"),
                    f(c, "theta_s"),
                    f(c, "phi_s")
                ),
                m[(r, col)],
                reference[(r, col)],
                Tol::new(rel * scale, rel),
            );
        }
    }
}

#[test]
fn plane_wave_limit_reproduces_scatmech_rayleigh_rice() {
    let cases = cases();
    assert_eq!(cases.len(), 6, "expected the six SCATMECH cases");
    for c in &cases {
        // The width is ignored at the plane-wave level.
        let m = kernel_mueller_brdf::<Full, PlaneWave>(c, 1.0);
        compare(c, &m, 1e-9);
    }
}

#[test]
fn partial_coherence_tends_to_scatmech_as_coherence_grows() {
    // Relative deviation of the partially coherent kernel from the plane-wave reference shrinks
    // as the coherence width w grows (the Gaussian blur has width ~1/w in h).
    for c in &cases() {
        let reference = f(c, "brdf_unpolarized");
        let mut last = f64::INFINITY;
        for width in [1e2, 1e3, 1e4] {
            let m = kernel_mueller_brdf::<Full, Partial>(c, width);
            let dev = ((m[(0, 0)] - reference) / reference).abs();
            assert!(dev.is_finite(), "finite deviation at w = {width}");
            assert!(
                dev < last || dev < 1e-12,
                "deviation must shrink: {dev} after {last} at w = {width}"
            );
            last = dev;
        }
        assert!(last < 1e-3, "within 0.1 % at w = 1e4 µm, got {last}");
    }
}
