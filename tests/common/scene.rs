//! Scene helpers shared by `tests/interaction/laws.rs` and `tests/interaction/energy.rs`: the
//! surface z = 0, directions by polar angles, isotropic packets, rough glass, one kernel call,
//! and textbook Fresnel reflectances (the tests' own, independent of the crate's `fresnel`).

use std::f64::consts::PI;

use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::pbsdf::{FresnelReflection, Pbsdf, RayleighRice};
use gmueller::interaction::polarization::PolarizationModel;
use gmueller::interaction::{Geometry, Kernel, RoughSurface};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use nalgebra::{Vector3, Vector4};
use num_complex::Complex;

/// One degree in radians.
pub const DEG: f64 = PI / 180.0;

/// The surface z = 0, normal +ẑ, tangents (x̂, ŷ).
pub fn surface<T: Real>() -> Frame<T> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}

/// Propagation direction of light arriving at polar angle `theta_i` in the x–z plane (from −x).
pub fn travel<T: Real>(theta_i: f64) -> Vector3<T> {
    Vector3::new(theta_i.sin(), 0.0, -theta_i.cos()).map(T::lit)
}

/// A unit direction above the surface: polar angle θ, azimuth φ (φ = 0 is the specular side).
pub fn dir<T: Real>(theta: f64, phi: f64) -> Vector3<T> {
    Vector3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
    .map(T::lit)
}

/// An isotropic packet travelling along `travel(theta_i)` in its s/p frame turned by `psi`.
pub fn packet(
    stokes: [f64; 4],
    width: f64,
    theta_i: f64,
    psi: f64,
    lambda: f64,
) -> WavePacket<f64> {
    let frame = Frame::sp(travel::<f64>(theta_i), Vector3::z())
        .unwrap()
        .rotated(psi);
    WavePacket::from_stokes(
        Stokes::new(stokes[0], stokes[1], stokes[2], stokes[3]).unwrap(),
        CoherenceShape::isotropic(width).unwrap(),
        frame,
        lambda,
    )
    .unwrap()
}

pub type Glass = RoughSurface<GaussianPsd<f64, 2>, FresnelReflection<f64>, RayleighRice<f64>>;

pub fn glass(sigma: f64, ell: f64) -> Glass {
    let eta = Complex::new(1.5, 0.0);
    RoughSurface {
        psd: GaussianPsd::isotropic(sigma, ell).unwrap(),
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    }
}

pub fn eval<Pol, Coh, Sp, Sc>(
    material: &RoughSurface<GaussianPsd<f64, 2>, Sp, Sc>,
    packet: &WavePacket<f64>,
    exit: Vector3<f64>,
) -> Pol::Output<f64>
where
    Pol: PolarizationModel,
    Coh: CoherenceWeights<f64, GaussianPsd<f64, 2>> + Default,
    Sp: Pbsdf<f64>,
    Sc: Pbsdf<f64>,
{
    let g = Geometry::for_packet(packet, &surface(), exit).unwrap();
    Kernel::<Pol, Coh>::default().evaluate(material, packet, &g)
}

pub fn rel_diff(a: &Vector4<f64>, b: &Vector4<f64>) -> f64 {
    (a - b).norm() / b.norm()
}

/// Textbook Fresnel power reflectances of a dielectric (Hecht, Optics, eq. 4.42–4.43).
pub fn fresnel_rs_rp(cos_i: f64, n: f64) -> (f64, f64) {
    let sin2 = 1.0 - cos_i * cos_i;
    let q = (n * n - sin2).sqrt(); // n cos θ_t
    let rs = (cos_i - q) / (cos_i + q);
    let rp = (n * n * cos_i - q) / (n * n * cos_i + q);
    (rs * rs, rp * rp)
}
