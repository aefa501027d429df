//! Shading-frame helpers shared by the renderer-layer tests (`bsdf::sampling`,
//! `bsdf::reciprocity`, `bsdf::furnace`, `bsdf::rough`).

use gmueller::frame::Frame;
use nalgebra::Vector3;

/// A tilted shading frame (normal along `(0.2, −0.1, 1)`), so that nothing lines up with the
/// world axes.
pub fn tilted_frame() -> Frame<f64> {
    Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap()
}

/// A direction at polar angle `deg` from `side · n̂`, azimuth `phi_deg`, in frame `f`.
pub fn dir(f: &Frame<f64>, deg: f64, phi_deg: f64, side: f64) -> Vector3<f64> {
    let (t, p) = (deg.to_radians(), phi_deg.to_radians());
    f.x() * (t.sin() * p.cos()) + f.y() * (t.sin() * p.sin()) + f.k() * (side * t.cos())
}
