//! Verifies the exitant-packet shape update (`interaction::exitant::exitant_shape`): the coherence
//! area is conserved (det U = 1) in every direction, and in the specular direction the result
//! equals the incident shape carried by the geometric map "project along the incident direction
//! onto the surface, then onto the exit transverse plane", computed here independently from dot
//! products.

use crate::common;

use common::{Tol, assert_all_close, assert_close};
use gmueller::frame::Frame;
use gmueller::interaction::Geometry;
use gmueller::interaction::exitant::{exitant_packet, exitant_shape};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector3};
use proptest::prelude::*;

fn det(m: &Matrix2<f64>) -> f64 {
    m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)]
}

fn setup(theta_i: f64, azimuth: f64, shape: Matrix2<f64>) -> (Frame<f64>, WavePacket<f64>) {
    let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let travel = Vector3::new(
        theta_i.sin() * azimuth.cos(),
        theta_i.sin() * azimuth.sin(),
        -theta_i.cos(),
    );
    let frame = Frame::sp(travel, Vector3::z()).unwrap();
    let packet = WavePacket::from_stokes(
        Stokes::new(1.0, 0.2, -0.3, 0.1).unwrap(),
        CoherenceShape::new(shape).unwrap(),
        frame,
        0.55,
    )
    .unwrap();
    (surface, packet)
}

/// Widths 1–100 λ, turned by up to ±1.5 rad.
fn shape() -> impl Strategy<Value = Matrix2<f64>> {
    gmueller::verify::strategy::coherence_shape(1.0, 100.0, 1.5)
}

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn coherence_area_is_conserved(
        theta_i in 0.0..1.4f64, az in -3.0..3.0f64, theta_o in 0.0..1.4f64, phi_o in -3.1..3.1f64,
        m in shape(),
    ) {
        let (surface, packet) = setup(theta_i, az, m);
        let exit = Vector3::new(theta_o.sin() * phi_o.cos(), theta_o.sin() * phi_o.sin(), theta_o.cos());
        let g = Geometry::for_packet(&packet, &surface, exit).unwrap();
        let out = exitant_shape(&packet, &g).unwrap().matrix();
        assert_close("det Θ′ = det Θ", det(&out), det(&m), Tol::new(0.0, 1e-9));
        // Symmetric positive definite.
        prop_assert!(out[(0, 0)] > 0.0 && det(&out) > 0.0);
        assert_close("symmetric", out[(0, 1)], out[(1, 0)], Tol::new(1e-12 * out.amax(), 0.0));
    }

    #[test]
    fn specular_shape_is_the_geometric_image(
        theta_i in 0.0..1.4f64, az in -3.0..3.0f64, m in shape(),
    ) {
        let (surface, packet) = setup(theta_i, az, m);
        let d = packet.direction();
        let n = Vector3::z();
        let exit = d - n * (2.0 * d.dot(&n));
        let g = Geometry::for_packet(&packet, &surface, exit).unwrap();
        let out = exitant_shape(&packet, &g).unwrap().matrix();
        // Independent map: incident transverse (a, b) → world ξ = a x̂ + b ŷ → along d onto the
        // surface → components on the exit s/p frame.
        let (x, y) = (packet.frame().x(), packet.frame().y());
        let exit_frame = Frame::sp(exit, n).unwrap();
        let map = |v: Vector3<f64>| {
            let on_surface = v - d * (n.dot(&v) / n.dot(&d));
            (exit_frame.x().dot(&on_surface), exit_frame.y().dot(&on_surface))
        };
        let (c1, c2) = (map(x), map(y));
        let l = Matrix2::new(c1.0, c2.0, c1.1, c2.1);
        let expected = l * m * l.transpose();
        assert_all_close("Θ′ at specular", out.iter().copied(), expected.iter().copied(),
            Tol::new(1e-9 * m.amax(), 1e-9));
    }
}

#[test]
fn exitant_packet_carries_the_stokes_vector_in_the_exit_frame() {
    let (surface, packet) = setup(0.6, 0.3, Matrix2::new(400.0, 50.0, 50.0, 100.0));
    let exit = Vector3::new(0.3, -0.2, 0.93);
    let g = Geometry::for_packet(&packet, &surface, exit).unwrap();
    let s = Stokes::new(0.5, 0.1, 0.2, -0.1).unwrap();
    let out = exitant_packet(&packet, &g, s).unwrap();
    assert_eq!(out.stokes(), s);
    assert_eq!(out.frame(), g.exit_sp());
    assert!(out.has_single_shape());
    assert_close("wavelength", out.wavelength(), 0.55, Tol::new(0.0, 1e-14));
}

/// The exitant packet of a dim or bright response (the kernel's output at a far tail of a
/// renderer's path can be 1e-22 or less), in f32 and f64, at grazing angles and φ ≠ 0: the
/// realizability test on S/S0 accepts every valid Stokes vector at every scale (it squared S
/// itself and rejected such packets), and the area-conserving shape stays finite.
#[test]
fn exitant_packet_of_dim_and_bright_responses() {
    fn check<T: gmueller::Real>(scales: &[f64]) {
        let l = |x: f64| T::lit(x);
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        for (ti, az, to, po) in [
            (0.6f64, 0.3f64, 0.4f64, 2.0f64),
            (1.55, -1.2, 1.5, 0.7),
            (0.0, 0.0, 1.2, -2.5),
        ] {
            let travel = Vector3::new(ti.sin() * az.cos(), ti.sin() * az.sin(), -ti.cos());
            let packet = WavePacket::from_stokes(
                Stokes::new(l(1.0), l(0.2), l(-0.3), l(0.1)).unwrap(),
                CoherenceShape::new(Matrix2::new(l(400.0), l(50.0), l(50.0), l(100.0))).unwrap(),
                Frame::sp(travel.map(l), Vector3::z()).unwrap(),
                l(0.55),
            )
            .unwrap();
            let exit = Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos()).map(l);
            let g = Geometry::for_packet(&packet, &surface, exit).unwrap();
            for &sc in scales {
                // Fully polarized (on the edge of the Poincaré sphere) and partially polarized.
                for v in [[1.0, 0.6, 0.0, -0.8], [1.0, 0.1, 0.2, 0.3]] {
                    let s = Stokes::new(l(v[0] * sc), l(v[1] * sc), l(v[2] * sc), l(v[3] * sc))
                        .unwrap();
                    let out = exitant_packet(&packet, &g, s)
                        .unwrap_or_else(|e| panic!("θi = {ti}, scale {sc:e}: {e}"));
                    assert!(
                        out.shape(gmueller::packet::Channel::X)
                            .iter()
                            .all(|x| x.is_finite())
                    );
                }
            }
        }
    }
    check::<f64>(&[1e-300, 1e-200, 1e-22, 1.0, 1e22, 1e200, 1e300]);
    check::<f32>(&[1e-37, 1e-30, 1e-22, 1.0, 1e22, 1e30, 1e37]);
}
