//! One physical interface described from either side must give the same answer.
//!
//! Rough glass (η = 1.5) with an anisotropic Gaussian PSD (correlation lengths 1 and 3 µm),
//! lit from inside the glass: once with the frame `(x̂, ŷ, ẑ)` (the normal out of the glass,
//! light from below) and once with `(x̂, −ŷ, −ẑ)`, η = 1/1.5 and the wavelength of the glass
//! (light from above). In the second frame the same surface has its correlation ellipse
//! mirrored (`Λ' = D Λ D`, `D = diag(1, −1)`). The intensities of both lobes, in reflection
//! inside the glass and in transmission, must agree.
//!
//! With the ellipse along the axes (mirror-symmetric) they agree to rounding. With a rotated
//! ellipse they do not: the kernel, for light from below, evaluates the PSD at `h_t` in its
//! source-facing frame `(t̂₁, −t̂₂, −n̂)` without mirroring the PSD, so it answers for the
//! mirror-image surface (the test marked `ignore`; found 2026-12-02, open). Isotropic PSDs and
//! gratings along an axis are not affected.

use gmueller::bsdf::Bsdf;
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::{Full, Kernel, Partial, RoughDielectric, Throughput};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector3};

const LAMBDA: f64 = 0.5;
const ETA: f64 = 1.5;

/// σ² = 1e-4 µm², correlation ellipse of axes 1 and 3 µm rotated by `angle`.
fn psd(angle: f64) -> GaussianPsd<f64, 2> {
    let (s, c) = angle.sin_cos();
    let r = Matrix2::new(c, -s, s, c);
    let lam = r * Matrix2::new(1.0, 0.0, 0.0, 9.0) * r.transpose();
    GaussianPsd::from_autocorrelation(1e-4, &Gaussian::new(lam).unwrap()).unwrap()
}

/// The largest relative difference of the two descriptions over four exits near the lobes.
fn worst_difference(angle: f64) -> f64 {
    let up = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let down = Frame::new(Vector3::x(), -Vector3::y(), -Vector3::z()).unwrap();
    let m_up = RoughDielectric::new(psd(angle), ETA).unwrap();
    let m_down = RoughDielectric::new(psd(-angle), 1.0 / ETA).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let a = Bsdf::new(&m_up, kernel, up, LAMBDA).unwrap();
    let b = Bsdf::new(&m_down, kernel, down, LAMBDA / ETA).unwrap();
    let s = Vector3::new(0.3, 0.2, -0.93).normalize(); // toward the source, inside the glass
    let packet = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(3.0).unwrap(),
        Frame::sp(-s, Vector3::z()).unwrap(),
        LAMBDA / ETA,
    )
    .unwrap();
    let exits = [
        Vector3::new(-0.26, -0.23, -0.93), // reflection inside, near the mirror direction
        Vector3::new(-0.34, -0.23, -0.93),
        Vector3::new(-0.40, -0.34, 0.84), // transmission, near the Snell direction
        Vector3::new(-0.50, -0.34, 0.84),
    ];
    let mut worst = 0.0f64;
    for r in exits.map(|r| r.normalize()) {
        let va = a.eval(&a.prepare(&packet).unwrap(), r).unwrap().response;
        let vb = b.eval(&b.prepare(&packet).unwrap(), r).unwrap().response;
        for (x, y) in [
            (va.scattered.m00(), vb.scattered.m00()),
            (va.specular.m00(), vb.specular.m00()),
        ] {
            assert!(x > 0.0 && y > 0.0, "both lit: {x} {y}");
            worst = worst.max((x - y).abs() / x.max(y));
        }
    }
    worst
}

#[test]
fn an_interface_seen_from_either_side_agrees_for_an_axis_aligned_psd() {
    let d = worst_difference(0.0);
    println!("axis-aligned ellipse: worst relative difference {d:.2e}");
    assert!(d < 1e-10, "{d}");
}

#[test]
#[ignore = "open bug (2026-12-02): the kernel mirrors a rotated anisotropic PSD for light from below; measured worst relative difference 0.73"]
fn an_interface_seen_from_either_side_agrees_for_a_rotated_psd() {
    let d = worst_difference(0.5);
    println!("ellipse rotated by 0.5 rad: worst relative difference {d:.2e}");
    assert!(d < 1e-10, "{d}");
}
