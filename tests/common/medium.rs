//! Scenes shared by the random medium's tests (`tests/medium/extremes.rs`,
//! `tests/medium/limits.rs`, `tests/medium/f32.rs`).
#![allow(
    dead_code,
    reason = "each test file uses a different subset of the helpers"
)]

use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::medium::{Dipole, RandomMedium};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector3};

/// A packet on the standard frame turned about y by `tilt`, unpolarized or not, with isotropic
/// or anisotropic transverse shapes (length units of `lambda`).
pub fn simple<T: Real>(
    stokes: [f64; 4],
    shape: Matrix2<f64>,
    zz: Option<f64>,
    lambda: f64,
) -> WavePacket<T> {
    let f = Frame::from_direction_and_x(
        Vector3::new(0.2, -0.3, 0.93).map(T::lit),
        Vector3::new(1.0, 0.1, 0.0).map(T::lit),
    )
    .unwrap();
    let p = WavePacket::from_stokes(
        Stokes::new(
            T::lit(stokes[0]),
            T::lit(stokes[1]),
            T::lit(stokes[2]),
            T::lit(stokes[3]),
        )
        .unwrap(),
        CoherenceShape::new(shape.map(T::lit)).unwrap(),
        f,
        T::lit(lambda),
    )
    .unwrap();
    match zz {
        Some(z) => p.with_longitudinal_coherence(T::lit(z)).unwrap(),
        None => p,
    }
}

pub fn gaussian<T: Real>(ell: f64) -> RandomMedium<GaussianPsd<T, 3>, Dipole> {
    RandomMedium::new(
        GaussianPsd::<T, 3>::isotropic(T::lit(2e-3), T::lit(ell)).unwrap(),
        Dipole,
    )
}

/// The `f64` packet with the numbers of an `f32` one (the frame renormalised: `f32` unit
/// vectors are not unit to `f64`'s 256 ε, a ~1e-7 change).
pub fn widened(p: &WavePacket<f32>) -> WavePacket<f64> {
    let f = p.frame();
    let fr = Frame::from_direction_and_x(f.k().map(f64::from), f.x().map(f64::from)).unwrap();
    let s = p.stokes().vector().map(f64::from);
    let c = |ch| CoherenceShape::new(p.shape(ch).map(f64::from)).unwrap();
    let out = WavePacket::new(
        Stokes::new(s[0], s[1], s[2], s[3]).unwrap(),
        c(gmueller::packet::Channel::X),
        c(gmueller::packet::Channel::Y),
        fr,
        f64::from(p.wavelength()),
    )
    .unwrap();
    let inv = f64::from(p.inverse_longitudinal_variance());
    if inv > 0.0 {
        out.with_longitudinal_coherence(inv.sqrt().recip()).unwrap()
    } else {
        out
    }
}

pub fn turned(d: &Vector3<f64>, t: f64, phi: f64) -> Vector3<f64> {
    let x = if d.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (x - d * d.dot(&x)).normalize();
    let e2 = d.cross(&e1);
    (d * t.cos() + (e1 * phi.cos() + e2 * phi.sin()) * t.sin()).normalize()
}
