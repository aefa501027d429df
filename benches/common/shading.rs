//! The shading frame and directions shared by the renderer-layer benches (`bsdf`,
//! `bsdf_rough`); included with `#[path]`, so it is not a bench target of its own.

use gmueller::Real;
use gmueller::frame::Frame;
use nalgebra::Vector3;

/// A tilted shading frame (normal along `(0.1, −0.2, 1)`).
pub fn frame<T: Real>() -> Frame<T> {
    Frame::from_normal(Vector3::new(0.1, -0.2, 1.0).map(T::lit)).unwrap()
}

/// The direction at polar angle `theta` (rad) from `side · n̂`, azimuth `phi`, in frame `f`.
pub fn dir<T: Real>(f: &Frame<T>, theta: f64, phi: f64, side: f64) -> Vector3<T> {
    let v = Vector3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        side * theta.cos(),
    );
    f.x() * T::lit(v.x) + f.y() * T::lit(v.y) + f.k() * T::lit(v.z)
}
