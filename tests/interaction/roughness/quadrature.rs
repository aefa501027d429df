//! Verifies the quadrature roughness level (`KirchhoffQuadrature`, the Kirchhoff phase screen
//! for any PSD with a spatial autocorrelation) against independent computations: on a Gaussian
//! PSD against the series (`KirchhoffSeries`, itself checked against a direct quadrature in
//! `tests/interaction/roughness/series.rs`); on a two-component Gaussian mixture against the
//! multinomial closed form written here (each pair of orders a Gaussian, summed with the closed
//! coherence integral of `verify::oracle`); on the exponential (K-correlation γ = 2) surface
//! against the series of its powers, `F{e^{−nr/ℓ}} = (ℓ/n)² (1 + (ℓ|ζ|/n)²)^{−3/2}`, written here;
//! and at small `g` against the first-order kernel for K-correlations of γ = 2, 3, 4.5 (which
//! checks the Matérn autocorrelation against the closed-form PSD).

use crate::common;

use std::f64::consts::TAU;

use common::{Tol, assert_close};
use gmueller::frame::Frame;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::pbsdf::PhaseScreen;
use gmueller::interaction::roughness::{
    FirstOrder, KirchhoffQuadrature, KirchhoffSeries, RoughnessWeights,
};
use gmueller::interaction::{Geometry, Intensity, Kernel, Partial, PlaneWave, RoughSurface};
use gmueller::packet::{Channel, CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussHermite, GaussianMixturePsd, GaussianPsd, KCorrelation, Psd};
use gmueller::stokes::Stokes;
use gmueller::verify::oracle;
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

const LAMBDA: f64 = 0.5;

fn surface() -> Frame<f64> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}

fn packet(theta: Matrix2<f64>) -> WavePacket<f64> {
    let travel = Vector3::new(0.5, 0.0, -(0.75f64).sqrt());
    WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::new(theta).unwrap(),
        Frame::sp(travel, Vector3::z()).unwrap(),
        LAMBDA,
    )
    .unwrap()
}

/// Exits whose `h_t` is `h` (reflection, 30° incidence).
fn geometry(pk: &WavePacket<f64>, h: [f64; 2]) -> Option<Geometry<f64>> {
    let k = TAU / LAMBDA;
    let rt = Vector2::new(0.5 + h[0] / k, h[1] / k);
    (rt.norm() < 0.95).then(|| {
        let exit = Vector3::new(rt.x, rt.y, (1.0 - rt.norm_squared()).sqrt());
        Geometry::for_packet(pk, &surface(), exit).unwrap()
    })
}

/// The section of the packet by the surface (S2.18 as `verify::oracle` writes it).
fn section(pk: &WavePacket<f64>) -> Matrix2<f64> {
    let f = pk.frame();
    let q = Matrix3::from_columns(&[f.x(), f.y(), f.k()]);
    oracle::section(
        &q,
        &pk.shape(Channel::Half),
        0.0,
        &Vector3::x(),
        &Vector3::y(),
    )
}

/// The kernel's scattered weight per unit `C v²` (the phase screen's radiance over
/// `cos θ_o/λ² · v²`): `K̃` of the roughness level.
fn k_tilde<P, Coh, R>(coh: Coh, rough: R, psd: P, pk: &WavePacket<f64>, g: &Geometry<f64>) -> f64
where
    P: Psd<f64, 2>,
    Coh: CoherenceWeights<f64, P>,
    R: RoughnessWeights<f64, P, Coh>,
{
    let m = RoughSurface {
        psd,
        specular: PhaseScreen::new(1.0).unwrap(),
        scatter: PhaseScreen::new(1.0).unwrap(),
    };
    let l = Kernel::<Intensity, Coh>::new(coh)
        .with_roughness(rough)
        .evaluate(&m, pk, g)
        .scattered;
    let v = g.phase_factor();
    let scale = g.cos_o() / (LAMBDA * LAMBDA) * v * v;
    if R::CARRIES_ATTENUATION {
        l / scale
    } else {
        l / scale / (-(v * v) * m.psd.variance()).exp()
    }
}

const HS: [[f64; 2]; 6] = [
    [0.0, 0.0],
    [1.5, 0.0],
    [-2.5, 0.0],
    [0.0, 2.0],
    [2.0, -2.5],
    [4.0, 1.0],
];

/// On a Gaussian PSD the quadrature (tolerance 10⁻⁸) equals the series (10⁻¹⁰) to 10⁻⁶ where
/// the weight is at least 10⁻³ of its peak, plane wave and partially coherent, `vσ` 0.3 to 5.
#[test]
fn quadrature_equals_the_series_on_a_gaussian_psd() {
    let pk = packet(Matrix2::new(1.44, 0.2, 0.2, 2.56));
    let quad = KirchhoffQuadrature::new(1e-8).unwrap();
    let series = KirchhoffSeries::new(1e-10).unwrap();
    let k = TAU / LAMBDA;
    for v_sigma in [0.3, 1.0, 3.0, 5.0] {
        let sigma = v_sigma / (2.0 * k * (0.75f64).sqrt());
        let psd = GaussianPsd::<f64, 2>::isotropic(sigma, 1.0).unwrap();
        let g0 = geometry(&pk, [0.0, 0.0]).unwrap();
        let peak = k_tilde(Partial(ClosedForm), series, psd, &pk, &g0);
        let peak_pw = k_tilde(PlaneWave, series, psd, &pk, &g0);
        for h in HS {
            let Some(g) = geometry(&pk, h) else { continue };
            let a = k_tilde(Partial(ClosedForm), quad, psd, &pk, &g);
            let b = k_tilde(Partial(ClosedForm), series, psd, &pk, &g);
            assert_close(
                &format!("partial, vσ {v_sigma}, h {h:?}"),
                a,
                b,
                Tol::new(1e-3 * peak * 1e-6, 1e-6),
            );
            let a = k_tilde(PlaneWave, quad, psd, &pk, &g);
            let b = k_tilde(PlaneWave, series, psd, &pk, &g);
            assert_close(
                &format!("plane wave, vσ {v_sigma}, h {h:?}"),
                a,
                b,
                Tol::new(1e-3 * peak_pw * 1e-6, 1e-6),
            );
        }
    }
}

/// A two-component isotropic Gaussian mixture (σ₁ = 40 nm, ℓ₁ = 0.5 µm; σ₂ = 60 nm, ℓ₂ = 2 µm):
/// `e^{−g}(e^{gρ} − 1)/g` with `ρ = a₁ρ₁ + a₂ρ₂` is `Σ_{(m₁, m₂) ≠ 0} e^{−g} (g a₁)^{m₁} (g a₂)^{m₂}
/// /(m₁! m₂! g) exp(−½ (m₁/ℓ₁² + m₂/ℓ₂²)|ξ|²)`, each term's coherence integral in closed form
/// (`oracle::coherence_integral`); the quadrature (10⁻⁸) agrees to 10⁻⁶, plane wave and
/// partially coherent.
#[test]
fn quadrature_equals_the_multinomial_series_of_a_mixture() {
    let pk = packet(Matrix2::new(1.44, 0.2, 0.2, 2.56));
    let xi = section(&pk);
    let (s1, l1, s2, l2) = (0.04, 0.5, 0.06, 2.0);
    let mixture = GaussianMixturePsd::new(vec![
        GaussianPsd::<f64, 2>::isotropic(s1, l1).unwrap(),
        GaussianPsd::<f64, 2>::isotropic(s2, l2).unwrap(),
    ])
    .unwrap();
    let var = s1 * s1 + s2 * s2;
    let (a1, a2) = (s1 * s1 / var, s2 * s2 / var);
    let quad = KirchhoffQuadrature::new(1e-8).unwrap();
    for h in HS {
        let Some(g) = geometry(&pk, h) else { continue };
        let v = g.phase_factor();
        let gg = v * v * var;
        for plane_wave in [false, true] {
            let x = if plane_wave { Matrix2::zeros() } else { xi };
            let mut want = 0.0;
            let top = |a: f64| (gg * a + 12.0 * (gg * a).sqrt() + 30.0) as i32;
            let ln_fact = |m: i32| (1..=m).map(|i| f64::from(i).ln()).sum::<f64>();
            for m1 in 0..=top(a1) {
                for m2 in 0..=top(a2) {
                    if m1 == 0 && m2 == 0 {
                        continue;
                    }
                    let lw = -gg + f64::from(m1) * (gg * a1).ln() + f64::from(m2) * (gg * a2).ln()
                        - ln_fact(m1)
                        - ln_fact(m2)
                        - gg.ln();
                    let prec = f64::from(m1) / (l1 * l1) + f64::from(m2) / (l2 * l2);
                    want += lw.exp()
                        * oracle::coherence_integral(
                            1.0,
                            &(Matrix2::identity() * prec),
                            &x,
                            &Vector2::new(h[0], h[1]),
                        );
                }
            }
            want *= var;
            let got = if plane_wave {
                k_tilde(PlaneWave, quad, mixture.clone(), &pk, &g)
            } else {
                k_tilde(Partial(ClosedForm), quad, mixture.clone(), &pk, &g)
            };
            assert_close(
                &format!("plane {plane_wave}, h {h:?}, g {gg:.3}"),
                got,
                want,
                Tol::new(0.0, 1e-6),
            );
        }
    }
}

/// The exponential correlation `R = σ² e^{−r/ℓ}` (K-correlation γ = 2, `T = ℓ²`), plane wave:
/// its powers `e^{−nr/ℓ}` have the unitary spectra `(ℓ/n)² (1 + (ℓ|ζ|/n)²)^{−3/2}`, so the
/// phase screen is `K̃ = Σ_n (w_n/g) 2π σ² (ℓ/n)² (1 + (ℓ|h_t|/n)²)^{−3/2}` (summed here to
/// `n = g + 20√g + 60`); the quadrature (10⁻⁸) agrees to 10⁻⁵ for `vσ` from 0.3 to 30 (the
/// cusp at ξ = 0 is smooth in the polar radius; at large `g` the integrand's core is `ℓ/g`
/// wide there, not `ℓ/√g`, which the radial panels must and do resolve); and in `f32` to
/// 10⁻⁴.
#[test]
fn quadrature_equals_the_exponential_power_series() {
    let pk = packet(Matrix2::identity());
    let quad = KirchhoffQuadrature::new(1e-8).unwrap();
    let k = TAU / LAMBDA;
    let ell = 1.0;
    for v_sigma in [0.3, 1.0, 3.0, 10.0, 30.0] {
        let sigma = v_sigma / (2.0 * k * (0.75f64).sqrt());
        let psd = KCorrelation::<f64, 2>::new(sigma * sigma, ell * ell, 2.0).unwrap();
        for h in HS {
            let Some(g) = geometry(&pk, h) else { continue };
            let v = g.phase_factor();
            let gg = v * v * sigma * sigma;
            let hn = (h[0] * h[0] + h[1] * h[1]).sqrt();
            let n_max = (gg + 20.0 * gg.sqrt() + 60.0) as i32;
            let mut ln_fact = 0.0;
            let mut want = 0.0;
            for n in 1..=n_max {
                let nf = f64::from(n);
                ln_fact += nf.ln();
                let lw = -gg + (nf - 1.0) * gg.ln() - ln_fact;
                let p = (ell / nf).powi(2) * (1.0 + (ell * hn / nf).powi(2)).powf(-1.5);
                want += lw.exp() * TAU * sigma * sigma * p;
            }
            let got = k_tilde(PlaneWave, quad, psd, &pk, &g);
            assert_close(
                &format!("vσ {v_sigma}, h {h:?}"),
                got,
                want,
                Tol::new(0.0, 1e-5),
            );
        }
    }
}

/// At `g ≈ 10⁻⁶` the quadrature is the first-order kernel (to the second order's `~g`) for
/// K-correlations of γ = 2 (exponential), 3 (Matérn ν = 1, through the numerical `K_ν`) and
/// 4.5: the spatial Matérn autocorrelation and the closed-form PSD describe the same surface
/// (plane wave, within 10⁻⁵).
#[test]
fn quadrature_small_g_is_first_order_for_k_correlations() {
    let pk = packet(Matrix2::identity());
    let quad = KirchhoffQuadrature::new(1e-9).unwrap();
    let k = TAU / LAMBDA;
    for gamma in [2.0, 3.0, 4.5] {
        let sigma = 1e-3 / (2.0 * k * (0.75f64).sqrt());
        let psd = KCorrelation::<f64, 2>::new(sigma * sigma, 0.8, gamma).unwrap();
        for h in HS {
            let Some(g) = geometry(&pk, h) else { continue };
            let a = k_tilde(PlaneWave, quad, psd, &pk, &g);
            let b = k_tilde(PlaneWave, FirstOrder, psd, &pk, &g);
            assert_close(&format!("γ {gamma}, h {h:?}"), a, b, Tol::new(0.0, 1e-5));
        }
    }
}

/// A K-correlation of γ = 3 (Matérn ν = 1, the autocorrelation by `psd::matern`'s integral),
/// where `1 − ρ ~ s² ln(1/s)` is neither smooth nor a cusp: the polar quadrature (10⁻⁸) against
/// a Cartesian trapezoid of the same integrand `σ² e^{−g}(e^{gρ} − 1)/g · c · cos(h·ξ)` (a box
/// and a step of its own: where `g(1 − ρ)` reaches 45 along x, a twelfth of where it reaches
/// 1), partially coherent, `g` = 30 and 10⁴, to 10⁻⁶ relative (measured 2.7·10⁻⁷ and
/// 2.4·10⁻⁷; with twice the step the trapezoid was 4.3·10⁻⁶ off at g = 30 and moved toward the
/// polar value as the step halved: the `s² ln s` at the origin limits the Cartesian rule).
#[test]
fn quadrature_equals_a_cartesian_trapezoid_for_matern_one() {
    let pk = packet(Matrix2::new(1.44, 0.2, 0.2, 2.56));
    let xi = section(&pk);
    let quad = KirchhoffQuadrature::new(1e-8).unwrap();
    let t_len: f64 = 0.8;
    for g_target in [30.0_f64, 1e4] {
        let g = geometry(&pk, [1.0, 0.5]).unwrap();
        let v = g.phase_factor();
        let sigma = g_target.sqrt() / v;
        let psd = KCorrelation::<f64, 2>::new(sigma * sigma, t_len * t_len, 3.0).unwrap();
        let rho = |r: f64| gmueller::psd::matern(1.0, r / t_len);
        // r where g (1 − ρ(r)) = target, by bisection here.
        let reach = |target: f64| {
            let (mut lo, mut hi) = (0.0, 100.0 * t_len);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if g_target * (1.0 - rho(mid)) < target {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            hi
        };
        let coherence_edge = (80.0 / xi.symmetric_eigen().eigenvalues.min()).sqrt();
        let half = reach(45.0).min(coherence_edge);
        let step = reach(1.0) / 12.0;
        let n = (2.0 * half / step).ceil() as usize + 1;
        let h = g.h_t(); // from above: the PSD frame is the surface frame
        let want = sigma
            * sigma
            * gmueller::verify::quadrature::cube_quad::<2>(
                |x| {
                    let r = rho(x.norm());
                    let psi = ((-g_target * (1.0 - r)).exp() - (-g_target).exp()) / g_target;
                    let c = (-0.5 * x.dot(&(xi * x))).exp();
                    num_complex::Complex::new(psi * c * h.dot(x).cos(), 0.0)
                },
                half,
                n,
            )
            .re;
        // The quadrature ignores the blur method (it integrates the coherence itself).
        let got = k_tilde(Partial(GaussHermite::new(1).unwrap()), quad, psd, &pk, &g);
        println!("g = {g_target}: quadrature {got:e}, Cartesian trapezoid {want:e} ({n}² points)");
        assert_close(&format!("g {g_target}"), got, want, Tol::new(0.0, 1e-6));
    }
}
