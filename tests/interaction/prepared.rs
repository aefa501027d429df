//! Verifies the kernel's fast paths against the plain ones they replace: `Kernel::prepare` +
//! `Kernel::evaluate_prepared` return exactly (bit for bit) what `Kernel::evaluate` returns, at
//! all nine model levels, f32 and f64, with two PSD/blur pairs, over exit grids that include
//! normal incidence; `prepare` refuses a packet travelling away from the surface; the
//! Rayleigh–Rice `m00` shortcut equals `M₀₀` of its full Mueller matrix; and the Fresnel
//! pBSDF's direct construction of the specular s/p frame equals its documented formula
//! `T(Frame::sp(r_spec, n̂) → exit) · M_Fresnel`, evaluated here literally, at incidences from
//! exactly normal (the tangent fallback) through the re-orthogonalized band to grazing.

use crate::common;

use common::{Tol, assert_all_close, assert_close};
use gmueller::Real;
use gmueller::error::Error;
use gmueller::frame::{Frame, frame_change_mueller};
use gmueller::fresnel;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::level::LevelVisitor;
use gmueller::interaction::pbsdf::{FresnelReflection, Pbsdf, RayleighRice};
use gmueller::interaction::polarization::{KernelOutput, PolarizationModel};
use gmueller::interaction::{Full, Geometry, Kernel, Level, Partial, RoughSurface};
use gmueller::mueller::Mueller;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussHermite, GaussianPsd, KCorrelation, Psd};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;
use proptest::prelude::*;

fn surface<T: Real>() -> Frame<T> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}

/// A polarized packet with `Θ_x ≠ Θ_y` (anisotropic, correlated) at incidence `theta_i`, its
/// frame turned by 0.4 rad from s/p.
fn packet<T: Real>(theta_i: f64) -> WavePacket<T> {
    let travel = Vector3::new(theta_i.sin(), 0.0, -theta_i.cos()).map(T::lit);
    let frame = Frame::sp(travel, Vector3::z())
        .unwrap()
        .rotated(T::lit(0.4));
    let sx = CoherenceShape::new(Matrix2::new(9.0, 1.0, 1.0, 4.0).map(T::lit)).unwrap();
    let sy = CoherenceShape::new(Matrix2::new(12.0, 0.0, 0.0, 6.0).map(T::lit)).unwrap();
    let stokes = Stokes::new(T::lit(1.0), T::lit(0.2), T::lit(0.1), T::lit(-0.2)).unwrap();
    WavePacket::new(stokes, sx, sy, frame, T::lit(0.5)).unwrap()
}

/// Exit directions around the specular one (and the exact specular direction).
fn exits<T: Real>(theta_i: f64) -> Vec<Vector3<T>> {
    let mut v: Vec<Vector3<T>> = (0..36)
        .map(|i| {
            let to = (theta_i + 0.04 * (i % 6) as f64 - 0.1).abs() + 1e-3;
            let po = -0.3 + 0.1 * (i / 6) as f64;
            Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos()).map(T::lit)
        })
        .collect();
    v.push(Vector3::new(theta_i.sin(), 0.0, theta_i.cos()).map(T::lit));
    v
}

fn same_as_evaluate<T, Pol, Coh, P>(
    name: &str,
    kernel: &Kernel<Pol, Coh>,
    material: &RoughSurface<P, FresnelReflection<T>, RayleighRice<T>>,
) where
    T: Real,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, P>,
    P: Psd<T, 2>,
{
    for theta_i in [0.0, 1e-9, 0.05, 0.6, 1.3] {
        let p = packet::<T>(theta_i);
        let prepared = kernel.prepare(&p, &surface()).unwrap();
        for e in exits::<T>(theta_i) {
            let g = Geometry::for_packet(&p, &surface(), e).unwrap();
            let once = kernel.evaluate(material, &p, &g);
            let many = kernel.evaluate_prepared(material, &prepared, &g);
            assert_eq!(once, many, "{name}, θ_i = {theta_i}, exit {e:?}");
            assert!(once.total_intensity().is_finite(), "{name}: finite");
        }
    }
}

/// [`same_as_evaluate`] for the kernel of a level chosen at run time.
struct SameAsEvaluate<'a, T: Real, P> {
    name: &'a str,
    material: &'a RoughSurface<P, FresnelReflection<T>, RayleighRice<T>>,
}

impl<T: Real, P: Psd<T, 2>> LevelVisitor<T, P> for SameAsEvaluate<'_, T, P> {
    type Output = ();
    fn visit<Pol, Coh>(self, level: Level, kernel: Kernel<Pol, Coh>)
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P>,
    {
        same_as_evaluate(
            &format!("{} {}", level.name(), self.name),
            &kernel,
            self.material,
        );
    }
}

fn all_levels<T: Real>() {
    let eta = Complex::new(T::lit(1.5), T::lit(0.01));
    let gaussian = RoughSurface {
        psd: GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap(),
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    };
    let kc = RoughSurface {
        psd: KCorrelation::<T, 2>::new(T::lit(4e-4), T::lit(4.0), T::lit(2.5)).unwrap(),
        specular: FresnelReflection::new(eta).unwrap(),
        scatter: RayleighRice::new(eta).unwrap(),
    };
    for level in Level::ALL {
        let material = &gaussian;
        level.dispatch(
            ClosedForm,
            SameAsEvaluate {
                name: "Gaussian",
                material,
            },
        );
        let material = &kc;
        let gh = GaussHermite::<T>::new(4).unwrap();
        level.dispatch(
            gh,
            SameAsEvaluate {
                name: "KCorrelation/GaussHermite",
                material,
            },
        );
    }
}

#[test]
fn prepared_equals_evaluate_f64() {
    all_levels::<f64>();
}

#[test]
fn prepared_equals_evaluate_f32() {
    all_levels::<f32>();
}

#[test]
fn prepare_refuses_a_packet_leaving_the_surface() {
    let up = Frame::<f64>::sp(Vector3::new(0.3, 0.0, 0.9), Vector3::z()).unwrap();
    let p = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(2.0).unwrap(),
        up,
        0.5,
    )
    .unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let err = kernel.prepare(&p, &surface()).unwrap_err();
    assert!(
        matches!(err, Error::OutOfRange { .. }),
        "expected OutOfRange, got {err:?}"
    );
}

fn geometry(theta_i: f64, theta_o: f64, phi_o: f64) -> Geometry<f64> {
    let to_source = Vector3::new(-theta_i.sin(), 0.0, theta_i.cos());
    let exit = Vector3::new(
        theta_o.sin() * phi_o.cos(),
        theta_o.sin() * phi_o.sin(),
        theta_o.cos(),
    );
    Geometry::new(
        2.0 * std::f64::consts::PI / 0.5,
        &surface(),
        to_source,
        exit,
    )
    .unwrap()
}

proptest! {
    #![proptest_config(common::proptest_config(256))]
    /// `RayleighRice::m00` (½ Σ|J_ij|²) against `M₀₀` of `Mueller::from_jones(J)`.
    #[test]
    fn rayleigh_rice_m00_is_m00_of_its_mueller(
        ti in 0.0f64..1.5, to in 0.0f64..1.5, po in -3.1f64..3.1,
        n in 0.2f64..4.0, kappa in 0.0f64..8.0,
    ) {
        let g = geometry(ti, to, po);
        let rr = RayleighRice::new(Complex::new(n, kappa)).unwrap();
        let full = Mueller::from_jones(&rr.jones(&g)).matrix()[(0, 0)];
        assert_close("RR m00", rr.m00(&g), full, Tol { abs: 1e-300, rel: 1e-13 });
    }

    /// The Fresnel pBSDF against its documented formula, with the specular s/p frame built by
    /// the public `Frame::sp` from `r_spec = −ŝ + 2 cos θ_i n̂`.
    #[test]
    fn fresnel_pbsdf_matches_its_formula(
        ti_exp in -12.0f64..0.17, to in 0.0f64..1.5, po in -3.1f64..3.1,
        n in 0.2f64..4.0, kappa in 0.0f64..8.0, turn in -3.1f64..3.1,
    ) {
        // θ_i from 1e-12 rad (inside the √ε normal-incidence band) to ≈ 1.48 rad.
        let ti = 10f64.powf(ti_exp);
        // Incidence from an arbitrary azimuth `turn`.
        let (c, s) = (turn.cos(), turn.sin());
        let to_source = Vector3::new(-ti.sin() * c, -ti.sin() * s, ti.cos());
        let exit = Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos());
        let g = Geometry::new(4.0 * std::f64::consts::PI, &surface(), to_source, exit).unwrap();
        let eta = Complex::new(n, kappa);
        let m = FresnelReflection::new(eta).unwrap().mueller(&g).matrix();
        let nrm = Vector3::z();
        let r_spec = nrm * (2.0 * g.cos_i()) - g.to_source();
        let spec = Frame::sp(r_spec, nrm).unwrap();
        let literal = (frame_change_mueller(&spec, g.exit_sp())
            * Mueller::from_jones(&fresnel::reflection(g.cos_i(), eta)))
        .matrix();
        let tol = Tol { abs: 1e-13, rel: 1e-13 };
        assert_all_close(&format!("Fresnel pBSDF, θ_i = {ti:e}"), m.iter().copied(), literal.iter().copied(), tol);
    }
}

#[test]
fn fresnel_pbsdf_at_exact_normal_incidence() {
    // ŝ = n̂ exactly: both constructions use the tangent of n̂.
    let g = geometry(0.0, 0.4, 0.7);
    let eta = Complex::new(1.5, 0.0);
    let m = FresnelReflection::new(eta).unwrap().mueller(&g).matrix();
    let spec = Frame::sp(Vector3::z(), Vector3::z()).unwrap();
    let literal = (frame_change_mueller(&spec, g.exit_sp())
        * Mueller::from_jones(&fresnel::reflection(1.0, eta)))
    .matrix();
    assert_all_close(
        "Fresnel pBSDF, normal incidence",
        m.iter().copied(),
        literal.iter().copied(),
        Tol {
            abs: 1e-15,
            rel: 1e-15,
        },
    );
}
