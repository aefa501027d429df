//! Verifies the Kirchhoff tangent-plane pBSDF (`TangentPlane`) and the polarized roughness
//! levels built on it: at the specular (mirror or Snell) direction it is the Fresnel matrix
//! times `v²`, as the phase screen; at the geometric level (`Geometric`, large `vσ`) the kernel
//! equals the microfacet BSDF (Beckmann slopes, Fresnel matrix at the half vector, no
//! shadowing) written here from the textbook Fresnel coefficients, the seed's S2.3–S2.4 frame
//! rotations (`verify::oracle`) and Walter et al.'s BSDF, in reflection (full Mueller matrix)
//! and transmission (`M₀₀`); and at first order it agrees with the Rayleigh–Rice level near the
//! specular direction of a long-correlated surface (measured, printed).

use crate::common;

use std::f64::consts::TAU;

use common::{Tol, assert_close};
use gmueller::frame::Frame;
use gmueller::interaction::pbsdf::{
    FresnelInterface, FresnelReflection, Pbsdf, RayleighRice, TangentPlane,
};
use gmueller::interaction::roughness::Geometric;
use gmueller::interaction::{Full, Geometry, Intensity, Kernel, Partial, PlaneWave, RoughSurface};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::verify::check::assert_mueller_close;
use gmueller::verify::oracle;
use nalgebra::{Complex, Matrix2, Matrix4, Vector2, Vector3, Vector4};

type C64 = Complex<f64>;

fn surface() -> Frame<f64> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}

fn to_source(theta_i_deg: f64, phi_deg: f64) -> Vector3<f64> {
    let (t, p) = (theta_i_deg.to_radians(), phi_deg.to_radians());
    Vector3::new(-t.sin() * p.cos(), -t.sin() * p.sin(), t.cos())
}

fn dir(theta_deg: f64, phi_deg: f64, up: bool) -> Vector3<f64> {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    let z = if up { t.cos() } else { -t.cos() };
    Vector3::new(t.sin() * p.cos(), t.sin() * p.sin(), z)
}

/// Textbook Fresnel amplitudes (Born & Wolf §1.5.2, the crate's documented convention:
/// x̂ = ŝ common to both beams, ŷ = k̂ × ŝ), relative index `eta`, `c = cos θ_i`.
fn fresnel_r(c: f64, eta: C64) -> (C64, C64) {
    let q = (eta * eta - C64::new(1.0 - c * c, 0.0)).sqrt();
    let rs = (c - q) / (c + q);
    let rp = (eta * eta * c - q) / (eta * eta * c + q);
    (rs, rp)
}

/// At the mirror direction (`h_t = 0`, the facet is the mean surface) the tangent plane is the
/// flat Fresnel reflector times `v² = (2k cos θ_i)²`, and at Snell's direction the Fresnel
/// interface times `v² = k² (cos θ_i − η cos θ_t)²`: both the phase screen's factor with the
/// Fresnel polarization. Glass and a metal, from above and (glass) from below, to 10⁻¹²
/// on the matrix's scale.
#[test]
fn tangent_plane_at_the_specular_direction_is_fresnel_times_v_squared() {
    let k = TAU / 0.5;
    for eta in [C64::new(1.5, 0.0), C64::new(0.2, 3.4)] {
        let flat = FresnelReflection::new(eta).unwrap();
        let tp = TangentPlane::new(flat);
        for (ti, phi) in [(0.0, 0.0), (30.0, 20.0), (70.0, -100.0)] {
            let s = to_source(ti, phi);
            let mirror = Vector3::new(-s.x, -s.y, s.z);
            let g = Geometry::new(k, &surface(), s, mirror).unwrap();
            let v2 = g.phase_factor().powi(2);
            assert_mueller_close(
                &format!("η {eta}, θ_i {ti}"),
                &tp.mueller(&g).matrix(),
                &(flat.mueller(&g).matrix() * v2),
                Tol::new(0.0, 1e-12),
            );
        }
    }
    let glass = FresnelInterface::new(1.5).unwrap();
    let tp = TangentPlane::new(glass);
    for (frame, ti) in [(surface(), 35.0), (surface().reversed(), 25.0)] {
        let s = to_source(ti, 40.0);
        let s = if frame.k().z < 0.0 {
            Vector3::new(s.x, s.y, -s.z)
        } else {
            s
        };
        for exit_sign in [1.0, -1.0] {
            // Any exit on the wanted side, then the geometry's own specular direction.
            let probe = Vector3::new(0.1, 0.0, exit_sign * s.z.signum());
            let g0 = Geometry::at_interface(k, &frame, 1.5, s, probe).unwrap();
            let Some(spec) = g0.specular_direction() else {
                continue;
            };
            let g = Geometry::at_interface(k, &frame, 1.5, s, spec).unwrap();
            assert!(g.h_t().norm() < 1e-9 * k);
            let v2 = g.phase_factor().powi(2);
            assert_mueller_close(
                &format!("interface, θ_i {ti}, side {:?}", g.side()),
                &tp.mueller(&g).matrix(),
                &(glass.mueller(&g).matrix() * v2),
                Tol::new(0.0, 1e-12),
            );
        }
    }
}

/// The microfacet Mueller BSDF times `cos θ_i`, reflection, written independently: facet
/// normal `m = (ŝ + r̂)/|ŝ + r̂|`, Jones `τ(F'_o → F_o) diag(r_s, r_p)(ŝ·m) τ(F_i → F'_i)` with
/// the s/p bases of the facet and of the mean surface (`oracle::sp_basis`, `oracle::tau`, S2.3),
/// Mueller by S1.7 (`oracle::mueller_literal`), times `(1 − e^{−g}) D(m)/(4 cos θ_o)` with the
/// Beckmann `D = P(ζ)/cos⁴θ_m`, `P` the isotropic Gaussian slope density of variance `s²` per
/// axis.
fn microfacet_reflection(
    s: Vector3<f64>,
    r: Vector3<f64>,
    eta: C64,
    slope_var: f64,
    g: f64,
) -> Matrix4<f64> {
    let n = Vector3::z();
    let m = (s + r).normalize();
    let d_in = -s;
    let s_loc = d_in.cross(&m).normalize();
    let local_in = [s_loc, d_in.cross(&s_loc)];
    let local_out = [s_loc, r.cross(&s_loc)];
    let (rs, rp) = fresnel_r(s.dot(&m), eta);
    let j_loc = Matrix2::new(rs, C64::new(0.0, 0.0), C64::new(0.0, 0.0), rp);
    let t_in = oracle::tau(oracle::sp_basis(&d_in, &n), local_in).map(|x| C64::new(x, 0.0));
    let t_out = oracle::tau(local_out, oracle::sp_basis(&r, &n)).map(|x| C64::new(x, 0.0));
    let mueller = oracle::mueller_literal(&(t_out * j_loc * t_in));
    let zeta = Vector2::new(m.x / m.z, m.y / m.z);
    let p = (-0.5 * zeta.norm_squared() / slope_var).exp() / (TAU * slope_var);
    let d = p / m.z.powi(4);
    mueller * ((1.0 - (-g).exp()) * d / (4.0 * r.z))
}

/// The geometric level with the tangent-plane pBSDF is the microfacet BSDF: `Full`, plane wave,
/// a Gaussian surface of slope variance `σ²/ℓ² = 0.01` and `vσ = 30` at specular, glass and a
/// metal, 3 incidences, exits across the lobe in and out of the plane (φ ≠ 0), 10⁻¹⁰ on the
/// matrix's scale (the output's Mueller matrix, `Kernel::evaluate_mueller`).
#[test]
fn geometric_tangent_plane_is_the_microfacet_bsdf_in_reflection() {
    let lambda = 0.5;
    let k = TAU / lambda;
    let kernel = Kernel::<Full, PlaneWave>::default().with_roughness(Geometric);
    for eta in [C64::new(1.5, 0.0), C64::new(0.2, 3.4)] {
        for (ti, phi) in [(0.0, 0.0), (30.0, 0.0), (60.0, 35.0)] {
            let s = to_source(ti, phi);
            let sigma = 30.0 / (2.0 * k * s.z);
            let ell = sigma / 0.1;
            let material = RoughSurface {
                psd: GaussianPsd::<f64, 2>::isotropic(sigma, ell).unwrap(),
                specular: FresnelReflection::new(eta).unwrap(),
                scatter: TangentPlane::new(FresnelReflection::new(eta).unwrap()),
            };
            let travel = -s;
            let pk = WavePacket::from_stokes(
                Stokes::unpolarized(1.0).unwrap(),
                CoherenceShape::isotropic(5.0).unwrap(),
                Frame::sp(travel, Vector3::z()).unwrap(),
                lambda,
            )
            .unwrap();
            let mirror = Vector3::new(-s.x, -s.y, s.z);
            for (dt, dp) in [
                (0.0, 0.0),
                (8.0, 0.0),
                (-10.0, 0.0),
                (5.0, 25.0),
                (15.0, -40.0),
            ] {
                let r = rotate_about_normal(tilt(mirror, dt), dp);
                // Back-scatter (the facet normal along ŝ) has no plane of incidence at the facet.
                if r.z < 0.05 || (r - s).norm() < 1e-6 {
                    continue;
                }
                let g = Geometry::for_packet(&pk, &surface(), r).unwrap();
                let gg = (g.phase_factor() * sigma).powi(2);
                let got = kernel
                    .evaluate_mueller(&material, &pk, &g)
                    .scattered
                    .matrix();
                let want = microfacet_reflection(s, r, eta, 0.01, gg);
                assert_mueller_close(
                    &format!("η {eta}, θ_i {ti}, exit {r:?}"),
                    &got,
                    &want,
                    Tol::new(0.0, 1e-10),
                );
            }
        }
    }
}

/// `v` tilted by `deg` toward (positive) or away from the normal, in its own vertical plane.
fn tilt(v: Vector3<f64>, deg: f64) -> Vector3<f64> {
    let theta = v.z.acos() - deg.to_radians();
    let phi = v.y.atan2(v.x);
    Vector3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// `v` turned by `deg` about the surface normal.
fn rotate_about_normal(v: Vector3<f64>, deg: f64) -> Vector3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Vector3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

/// In transmission, the geometric level's `M₀₀` with `TangentPlane<FresnelInterface>` is Walter
/// et al.'s BTDF (EGSR 2007, eq. 21 with G = 1) times `cos θ_i`, for radiance in the exit
/// medium: `(1 − e^{−g}) η² |ŝ·m||r̂·m| (1 − F) D/(cos θ_o (ŝ·m + η r̂·m)²)`, `m` the facet
/// normal `∝ ±(ŝ + η r̂)` toward the source, `F` the textbook unpolarized reflectance at `ŝ·m`
/// — into glass and out of it, exits around Snell's direction, 10⁻¹⁰ relative.
#[test]
fn geometric_tangent_plane_is_the_microfacet_btdf_in_transmission() {
    let lambda = 0.5;
    let kernel = Kernel::<Intensity, PlaneWave>::default().with_roughness(Geometric);
    for (eta, ti) in [(1.5, 30.0), (1.0 / 1.5, 20.0)] {
        let s = to_source(ti, 10.0);
        let sin_t = (ti.to_radians().sin() / eta).min(0.99);
        let theta_t = sin_t.asin().to_degrees();
        let material = |sigma: f64| RoughSurface {
            psd: GaussianPsd::<f64, 2>::isotropic(sigma, sigma / 0.1).unwrap(),
            specular: FresnelInterface::new(eta).unwrap(),
            scatter: TangentPlane::new(FresnelInterface::new(eta).unwrap()),
        };
        let pk = WavePacket::from_stokes(
            Stokes::unpolarized(1.0).unwrap(),
            CoherenceShape::isotropic(5.0).unwrap(),
            Frame::sp(-s, Vector3::z()).unwrap(),
            lambda,
        )
        .unwrap();
        for (dt, dp) in [
            (0.0, 10.0),
            (6.0, 10.0),
            (-6.0, 10.0),
            (3.0, 30.0),
            (4.0, -20.0),
        ] {
            let r = dir(theta_t + dt, dp, false);
            let g = Geometry::for_packet_at_interface(&pk, &surface(), eta, r).unwrap();
            let sigma = 30.0 / g.phase_factor().abs();
            let m_vec = s + r * eta;
            let m = if m_vec.z > 0.0 {
                m_vec.normalize()
            } else {
                -m_vec.normalize()
            };
            let (sm, rm) = (s.dot(&m), r.dot(&m));
            if sm <= 0.0 || rm >= 0.0 {
                continue;
            }
            let (rs, rp) = fresnel_r(sm, C64::new(eta, 0.0));
            let f = 0.5 * (rs.norm_sqr() + rp.norm_sqr());
            let slope_var = 0.01;
            let zeta = Vector2::new(m.x / m.z, m.y / m.z);
            let d =
                (-0.5 * zeta.norm_squared() / slope_var).exp() / (TAU * slope_var) / m.z.powi(4);
            let gg = (g.phase_factor() * sigma).powi(2);
            let want = (1.0 - (-gg).exp()) * eta * eta * sm * rm.abs() * (1.0 - f) * d
                / (r.z.abs() * (sm + eta * rm).powi(2));
            let got = kernel.evaluate(&material(sigma), &pk, &g).scattered;
            assert_close(
                &format!("η {eta}, exit {r:?}"),
                got,
                want,
                Tol::new(0.0, 1e-10),
            );
        }
    }
}

/// First order: near the specular direction of a long-correlated surface the tangent plane and
/// Rayleigh–Rice agree — both tend to the Fresnel matrix times `v²` there — and their difference
/// across the lobe shrinks as `ℓ` grows (it is of the order of the lobe's angular width
/// `~2/(kℓ)`). `Full`, partially coherent (w = 3ℓ), polarized light (linear 45° and circular),
/// glass and a metal, at 30° incidence: the largest relative difference of `S0` and of the
/// normalized Stokes vector over exits within two lobe widths is printed; at ℓ = 40λ it is
/// below 5 % and 5·10⁻², and at ℓ = 160λ below a third of that at ℓ = 10λ.
#[test]
fn first_order_tangent_plane_agrees_with_rayleigh_rice_near_specular() {
    let lambda = 0.5;
    let k = TAU / lambda;
    let s = to_source(30.0, 0.0);
    let mut by_ell = Vec::new();
    for ell_l in [10.0, 40.0, 160.0] {
        let ell = ell_l * lambda;
        let sigma = 0.01 / (2.0 * k * s.z);
        let mut worst = (0.0f64, 0.0f64);
        for eta in [C64::new(1.5, 0.0), C64::new(0.2, 3.4)] {
            let psd = GaussianPsd::<f64, 2>::isotropic(sigma, ell).unwrap();
            let tp = RoughSurface {
                psd,
                specular: FresnelReflection::new(eta).unwrap(),
                scatter: TangentPlane::new(FresnelReflection::new(eta).unwrap()),
            };
            let rr = RoughSurface {
                psd,
                specular: FresnelReflection::new(eta).unwrap(),
                scatter: RayleighRice::new(eta).unwrap(),
            };
            for stokes in [
                Vector4::new(1.0, 0.0, 1.0, 0.0),
                Vector4::new(1.0, 0.0, 0.0, 1.0),
            ] {
                let pk = WavePacket::from_stokes(
                    Stokes::new(stokes[0], stokes[1], stokes[2], stokes[3]).unwrap(),
                    CoherenceShape::isotropic(3.0 * ell).unwrap(),
                    Frame::sp(-s, Vector3::z()).unwrap(),
                    lambda,
                )
                .unwrap();
                let kernel = Kernel::<Full, Partial>::default();
                let lobe = 2.0 / ell;
                for (hx, hy) in [(0.3, 0.0), (1.0, 0.0), (-1.0, 0.5), (0.0, 1.0), (1.4, -1.4)] {
                    let rt = Vector2::new(-s.x + hx * lobe / k, -s.y + hy * lobe / k);
                    let r = Vector3::new(rt.x, rt.y, (1.0 - rt.norm_squared()).sqrt());
                    let g = Geometry::for_packet(&pk, &surface(), r).unwrap();
                    let a = kernel.evaluate(&tp, &pk, &g).scattered.vector();
                    let b = kernel.evaluate(&rr, &pk, &g).scattered.vector();
                    worst.0 = worst.0.max((a[0] / b[0] - 1.0).abs());
                    worst.1 = worst.1.max((a / a[0] - b / b[0]).amax());
                }
            }
        }
        println!(
            "ℓ = {ell_l}λ: tangent plane vs Rayleigh–Rice within 2 lobe widths: S0 {:.2e}, normalized Stokes {:.2e}",
            worst.0, worst.1
        );
        by_ell.push(worst);
    }
    assert!(by_ell[1].0 < 0.05 && by_ell[1].1 < 0.05, "{by_ell:?}");
    assert!(
        by_ell[2].0 < by_ell[0].0 / 3.0 && by_ell[2].1 < by_ell[0].1 / 3.0,
        "{by_ell:?}"
    );
}
