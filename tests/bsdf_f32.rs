//! Issue 36 (the renderer layer): every promise of `docs/renderer.md` and `docs/numerical.md`
//! holds in `f32` too.

use gmueller::bsdf::{Bsdf, Part};
use gmueller::frame::Frame;
use gmueller::interaction::{
    Kernel, KirchhoffDielectric, KirchhoffSeries, OneShape, PlaneWave, Side, Throughput,
};
use gmueller::mueller::Mueller;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::Real;
use nalgebra::Vector3;

/// The reflected specular delta of very rough glass seen from inside (issue 36's case).
#[test]
fn repro_delta_weight_subnormal() {
    let lambda = 0.1239_f32;
    let psd = GaussianPsd::<f32, 2>::isotropic(0.354 * lambda, 1376.0 * lambda).unwrap();
    let glass = KirchhoffDielectric::new(psd, 2.4f32).unwrap();
    let kernel = Kernel::<OneShape, PlaneWave>::default()
        .with_roughness(KirchhoffSeries::new(1e-4).unwrap());
    let f = Frame::<f32>::from_normal(Vector3::z()).unwrap();
    let b = Bsdf::new(&glass, kernel, f, lambda).unwrap();
    let t = 23.3_f32.to_radians();
    let to_source = Vector3::new(-t.sin(), 0.0, -t.cos());
    let lam_in = b.wavelength(&to_source).unwrap();
    let packet = WavePacket::from_stokes(
        Stokes::unpolarized(1.0f32).unwrap(),
        CoherenceShape::isotropic(10.0 * lam_in).unwrap(),
        Frame::sp(-to_source, -f.k()).unwrap(),
        lam_in,
    )
    .unwrap();
    let inc = b.prepare(&packet).unwrap();
    let sampler = b.exit_sampler(&inc).unwrap().with_part_probabilities([1.0, 0.0, 0.0, 0.0]);
    let s = sampler.sample(0.5, [0.5, 0.5]).unwrap();
    println!("{:?}", s);
    assert!(s.lobe.delta && s.lobe.part == Part::Specular && s.lobe.side == Side::Reflection);
    let (w, _) = b.exit_weight(&inc, &s).unwrap();
    let m: Mueller<f32> = w;
    println!("{:e}", m.matrix());
    let _ = m.m00();
    let _ = f32::MIN_POSITIVE;
    let _ = <f32 as Real>::EPSILON;
}

fn item2_case<T: Real>(theta_deg: f64, w_over_lambda: f64, s0: f64, off: f64) -> f64 {
    use gmueller::interaction::{FresnelReflection, Geometry, Intensity, Partial, RayleighRice, RoughSurface};
    use num_complex::Complex;
    let lambda = 0.5;
    let eta = Complex::new(T::lit(1.5), T::zero());
    let m = RoughSurface {
        psd: GaussianPsd::<T, 2>::isotropic(T::lit(0.01 * lambda), T::lit(3.0 * lambda)).unwrap(),
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    };
    let surface = Frame::<T>::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let t = theta_deg.to_radians();
    let travel = Vector3::new(t.sin(), 0.0, -t.cos()).map(T::lit);
    let packet = WavePacket::from_stokes(
        Stokes::new(T::lit(s0), T::zero(), T::zero(), T::zero()).unwrap(),
        CoherenceShape::isotropic(T::lit(w_over_lambda * lambda)).unwrap(),
        Frame::sp(travel, Vector3::z()).unwrap(),
        T::lit(lambda),
    )
    .unwrap();
    let to = t + off;
    let exit = Vector3::new(to.sin(), 0.0, to.cos()).map(T::lit);
    let g = Geometry::for_packet(&packet, &surface, exit).unwrap();
    let r = Kernel::<Intensity, Partial>::default().evaluate(&m, &packet, &g);
    r.specular.to_f64()
}

#[test]
fn repro_item2() {
    for theta in [0.0, 0.01, 0.1, 0.3, 1.0, 3.0] {
        for w in [4.1e5, 1e5, 1e6] {
            for s0 in [6.2e29, 1e30, 1e33] {
                for off in [0.0, 1e-7, 1e-6] {
                    let a = item2_case::<f64>(theta, w, s0, off);
                    let b = item2_case::<f32>(theta, w, s0, off);
                    if !b.is_finite() || (a - b).abs() > 1e-2 * a.abs() {
                        println!("θ {theta} w {w:e} S0 {s0:e} off {off:e}: f64 {a:e} f32 {b:e}");
                    }
                }
            }
        }
    }
}
