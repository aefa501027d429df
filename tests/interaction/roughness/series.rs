//! Verifies the roughness levels beyond first order (`KirchhoffSeries`, `Geometric`) against
//! independent computations: the series against a direct 2-D quadrature of the Kirchhoff
//! phase-screen integral `∫ (e^{−g(1−ρ)} − e^{−g}) e^{−½ξᵀΞξ} e^{−ih·ξ} d²ξ` (no series, no
//! powers, no Poisson weights; reflection and transmission, plane wave and partial coherence,
//! isotropic and anisotropic surfaces); its truncation against a plain sum of 20√g terms; the
//! small-g limit against the first-order kernel; the geometric level against the Beckmann slope
//! distribution written here; and the series' convergence to it as `g` grows (the measured
//! `1/g` law). Run with `-- --nocapture` to see the tables.

use crate::common;

use std::f64::consts::TAU;

use common::{Tol, assert_close};
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::pbsdf::PhaseScreen;
use gmueller::interaction::roughness::{Geometric, KirchhoffSeries, RoughnessWeights};
use gmueller::interaction::{Geometry, Intensity, Kernel, Partial, PlaneWave, RoughSurface};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{BlurMethod, ClosedForm, GaussianPsd, Psd};
use gmueller::stokes::Stokes;
use gmueller::verify::{oracle, quadrature};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

const LAMBDA: f64 = 0.5;
const THETA_I: f64 = 30.0;

fn surface() -> Frame<f64> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}

fn travel(theta_i_deg: f64) -> Vector3<f64> {
    let t = theta_i_deg.to_radians();
    Vector3::new(t.sin(), 0.0, -t.cos())
}

/// An unpolarized packet at `θ_i` with the coherence shape `theta` (µm²) in its s/p frame.
fn packet(theta_i_deg: f64, theta: Matrix2<f64>, lambda: f64) -> WavePacket<f64> {
    WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::new(theta).unwrap(),
        Frame::sp(travel(theta_i_deg), Vector3::z()).unwrap(),
        lambda,
    )
    .unwrap()
}

/// A Gaussian phase screen `R = σ² exp(−½ ξᵀ C⁻¹ ξ)` on an ideal reflector (`|r|² = 1`) or,
/// with `eta`, on an interface transmitting with `τ = η` (the brute force's aperture model).
type Screen = RoughSurface<GaussianPsd<f64, 2>, PhaseScreen<f64>, PhaseScreen<f64>>;

fn screen(sigma: f64, c: &Matrix2<f64>, eta: Option<f64>) -> Screen {
    let psd =
        GaussianPsd::from_autocorrelation(sigma * sigma, &Gaussian::new(*c).unwrap()).unwrap();
    let s = match eta {
        None => PhaseScreen::new(1.0).unwrap(),
        Some(eta) => PhaseScreen::interface(1.0, eta).unwrap(),
    };
    RoughSurface {
        psd,
        specular: s,
        scatter: s,
    }
}

/// The screen whose `vσ` at the specular (mirror or Snell) direction of `pk` is `v_sigma`, its
/// σ and the specular geometry.
fn screen_at(
    pk: &WavePacket<f64>,
    eta: Option<f64>,
    c: &Matrix2<f64>,
    v_sigma: f64,
) -> (Screen, f64, Geometry<f64>) {
    let g0 = geometry(
        pk,
        eta,
        exit_for(THETA_I, LAMBDA, eta, Vector2::zeros()).unwrap(),
    );
    let sigma = v_sigma / g0.phase_factor().abs();
    (screen(sigma, c, eta), sigma, g0)
}

/// The exit direction whose `h_t` is `h` (reflection: `k (r̂_t − d_t)`, transmission:
/// `k (η r̂_t − d_t)`), `None` beyond the horizon.
fn exit_for(
    theta_i_deg: f64,
    lambda: f64,
    eta: Option<f64>,
    h: Vector2<f64>,
) -> Option<Vector3<f64>> {
    let d = travel(theta_i_deg);
    let k = TAU / lambda;
    let e = eta.unwrap_or(1.0);
    let rt = Vector2::new(d.x + h.x / k, d.y + h.y / k) / e;
    let s2 = rt.norm_squared();
    (s2 < 0.95 * 0.95).then(|| {
        let z = (1.0 - s2).sqrt();
        Vector3::new(rt.x, rt.y, if eta.is_some() { -z } else { z })
    })
}

fn geometry(pk: &WavePacket<f64>, eta: Option<f64>, exit: Vector3<f64>) -> Geometry<f64> {
    match eta {
        None => Geometry::for_packet(pk, &surface(), exit).unwrap(),
        Some(eta) => Geometry::for_packet_at_interface(pk, &surface(), eta, exit).unwrap(),
    }
}

/// The section `Ξ` of the packet's coherence by the surface, from the seed's S2.18 written out
/// (`verify::oracle::section`), or 0 for a plane wave.
fn section(pk: &WavePacket<f64>, plane_wave: bool) -> Matrix2<f64> {
    if plane_wave {
        return Matrix2::zeros();
    }
    let f = pk.frame();
    let q = Matrix3::from_columns(&[f.x(), f.y(), f.k()]);
    oracle::section(
        &q,
        &pk.shape(gmueller::packet::Channel::Half),
        0.0,
        &Vector3::x(),
        &Vector3::y(),
    )
}

/// The Kirchhoff phase-screen integral, by the trapezoid rule on a box (spectrally accurate
/// for this smooth, decaying integrand):
/// ```text
/// I(h) = ∫ (e^{−g(1 − ρ(ξ))} − e^{−g}) e^{−½ ξᵀΞξ} e^{−i h·ξ} d²ξ,   ρ = exp(−½ ξᵀC⁻¹ξ)
/// ```
/// — the scattered part of `⟨|∫ E e^{−ivz} e^{−ih·x}|²⟩` for Gaussian heights, with the
/// specular `e^{−g}` removed, written without any series.
fn phase_screen_integral(g: f64, c: &Matrix2<f64>, xi: &Matrix2<f64>, h: Vector2<f64>) -> f64 {
    let ci = c.try_inverse().unwrap();
    let ev_c = c.symmetric_eigen().eigenvalues;
    let (l_min, l_max) = (ev_c.min().sqrt(), ev_c.max().sqrt());
    let ev_xi = xi.symmetric_eigen().eigenvalues;
    // Box: where the integrand is below e^{−40} of its peak.
    let r_rho = if g > 40.0 {
        l_max * (-2.0 * (1.0 - 40.0 / g).ln()).sqrt() * 1.2
    } else {
        l_max * 80f64.sqrt()
    };
    let r_coh = if ev_xi.min() > 0.0 {
        (80.0 / ev_xi.min()).sqrt()
    } else {
        f64::INFINITY
    };
    let half = r_rho.min(r_coh);
    // Step: a fifth of the narrowest feature (the peak of width ℓ/√g, the coherence width).
    let w_coh = if ev_xi.max() > 0.0 {
        1.0 / ev_xi.max().sqrt()
    } else {
        f64::INFINITY
    };
    let step = (l_min / g.max(1.0).sqrt()).min(w_coh) / 5.0;
    let n = (2.0 * half / step).ceil() as usize + 1;
    let eg = (-g).exp();
    quadrature::cube_quad::<2>(
        |x| {
            let rho = (-0.5 * x.dot(&(ci * x))).exp();
            // e^{−g(1−ρ)} − e^{−g} = e^{−g} (e^{gρ} − 1), without cancellation for small gρ.
            let screen = eg * (g * rho).exp_m1();
            let coh = (-0.5 * x.dot(&(xi * x))).exp();
            num_complex::Complex::from_polar(screen * coh, -h.dot(x))
        },
        half,
        n,
    )
    .re
}

/// The kernel's scattered radiance at levels `Coh`, `R` for the screen, packet and exit.
fn scattered<Coh, R>(
    kernel: &Kernel<Intensity, Coh, R>,
    m: &Screen,
    pk: &WavePacket<f64>,
    g: &Geometry<f64>,
) -> f64
where
    Coh: CoherenceWeights<f64, GaussianPsd<f64, 2>>,
    R: RoughnessWeights<f64, GaussianPsd<f64, 2>, Coh>,
{
    kernel.evaluate(m, pk, g).scattered
}

/// The scattered radiance at roughness level `rough`, partially coherent or (`plane_wave`) in
/// the plane-wave limit.
fn scattered_at<R>(
    rough: R,
    plane_wave: bool,
    m: &Screen,
    pk: &WavePacket<f64>,
    g: &Geometry<f64>,
) -> f64
where
    R: RoughnessWeights<f64, GaussianPsd<f64, 2>, Partial>
        + RoughnessWeights<f64, GaussianPsd<f64, 2>, PlaneWave>,
{
    if plane_wave {
        scattered(
            &Kernel::<Intensity, PlaneWave>::default().with_roughness(rough),
            m,
            pk,
            g,
        )
    } else {
        scattered(
            &Kernel::<Intensity, Partial>::default().with_roughness(rough),
            m,
            pk,
            g,
        )
    }
}

const THETA: [[f64; 2]; 2] = [[1.44, 0.2], [0.2, 2.56]];

fn hs() -> Vec<Vector2<f64>> {
    [
        [0.0, 0.0],
        [2.6, 0.0],
        [-2.6, 0.0],
        [2.0, -3.2],
        [0.0, 4.2],
        [5.0, 1.0],
        [-5.5, -2.0],
    ]
    .iter()
    .map(|h| Vector2::new(h[0], h[1]))
    .collect()
}

/// The series kernel (tolerance 10⁻¹⁰) equals the phase-screen integral to 10⁻⁷ relative, in
/// reflection and in transmission into glass, for `vσ` at specular from 0.3 to 5.5 (g from 0.09
/// to 30), partially coherent (anisotropic Θ) and plane-wave light, isotropic (ℓ = 1 µm) and
/// anisotropic surfaces; the first-order kernel is off by up to tens of percent there (printed).
/// Expected `L = (η³ cos θ_o/λ²) I(h)` (`η = 1` in reflection: `cos θ_o/λ_t² · τ v² · I/v²`).
#[test]
fn series_equals_the_phase_screen_integral() {
    let series = KirchhoffSeries::new(1e-10).unwrap();
    let iso = Matrix2::identity();
    let aniso = Matrix2::new(1.0, 0.3, 0.3, 0.6);
    let mut worst_first: f64 = 0.0;
    for eta in [None, Some(1.5)] {
        for (c, plane_wave) in [(iso, false), (aniso, false), (iso, true)] {
            for v_sigma in [0.3, 1.0, 3.0, 5.5] {
                let theta = Matrix2::new(THETA[0][0], THETA[0][1], THETA[1][0], THETA[1][1]);
                let pk = packet(THETA_I, theta, LAMBDA);
                let (m, sigma, g0) = screen_at(&pk, eta, &c, v_sigma);
                let xi = section(&pk, plane_wave);
                let e = eta.unwrap_or(1.0);
                let peak = (e.powi(3) * g0.cos_o() / (LAMBDA * LAMBDA))
                    * phase_screen_integral(v_sigma * v_sigma, &c, &xi, Vector2::zeros());
                for h in hs() {
                    let Some(exit) = exit_for(THETA_I, LAMBDA, eta, h) else {
                        continue;
                    };
                    let g = geometry(&pk, eta, exit);
                    assert!((g.h_t() - h).norm() < 1e-9);
                    let gg = (g.phase_factor() * sigma).powi(2);
                    let want = e.powi(3) * g.cos_o() / (LAMBDA * LAMBDA)
                        * phase_screen_integral(gg, &c, &xi, h);
                    let got = scattered_at(series, plane_wave, &m, &pk, &g);
                    let fo = scattered_at(
                        gmueller::interaction::roughness::FirstOrder,
                        plane_wave,
                        &m,
                        &pk,
                        &g,
                    );
                    worst_first = worst_first.max((fo / want - 1.0).abs());
                    assert_close(
                        &format!(
                            "η {eta:?}, C {c:?}, plane {plane_wave}, vσ₀ {v_sigma}, h {h:?} (g = {gg:.3})"
                        ),
                        got,
                        want,
                        Tol::new(1e-12 * peak, 1e-7),
                    );
                }
            }
        }
    }
    println!("first-order kernel: largest relative error against the integral {worst_first:.3}");
    assert!(
        worst_first > 0.3,
        "the cases do not reach beyond first order"
    );
}

/// The small-g limit: the series is the first-order kernel plus its second order, then terms
/// of relative size `O(g²)`: `series/first − 1 = (g/2) K[p₂]/K[p₁] (1 + O(g))`, `K[p_n]` the
/// partially coherent weight of the Gaussian PSD of length `ℓ/√n`, computed here with
/// `ClosedForm` and the section of `verify::oracle`. For `g = 10⁻⁸ … 10⁻⁴` at every direction of
/// `hs()` (out to the far tail, where `K[p₂]/K[p₁]` reaches 175) the measured `series/first − 1`
/// is non-negative and within 10⁻³ (relative) of that prediction; the largest ratio
/// `(series/first − 1)/g` is printed.
#[test]
fn series_small_g_limit_is_the_first_order_kernel() {
    let series = Kernel::<Intensity, Partial>::default().with_roughness(KirchhoffSeries::default());
    let first = Kernel::<Intensity, Partial>::default();
    let pk = packet(THETA_I, Matrix2::new(1.44, 0.2, 0.2, 2.56), LAMBDA);
    let xi = Gaussian::new(section(&pk, false)).unwrap();
    let ell = 1.0;
    let g0 = geometry(
        &pk,
        None,
        exit_for(THETA_I, LAMBDA, None, Vector2::zeros()).unwrap(),
    );
    for g_spec in [1e-8_f64, 1e-6, 1e-4] {
        let sigma = g_spec.sqrt() / g0.phase_factor();
        let m = screen(sigma, &(Matrix2::identity() * (ell * ell)), None);
        let mut worst: f64 = 0.0;
        for h in hs() {
            let Some(exit) = exit_for(THETA_I, LAMBDA, None, h) else {
                continue;
            };
            let g = geometry(&pk, None, exit);
            let gg = (g.phase_factor() * sigma).powi(2);
            let (s, f) = (
                scattered(&series, &m, &pk, &g),
                scattered(&first, &m, &pk, &g),
            );
            let rel = s / f - 1.0;
            let k = |n: f64| {
                let p = GaussianPsd::<f64, 2>::isotropic(sigma, ell / n.sqrt()).unwrap();
                ClosedForm.normalized_blur(&p, &xi, &h)
            };
            let predicted = 0.5 * gg * k(2.0) / k(1.0);
            assert!(rel >= 0.0, "g {gg:e}, h {h:?}: series/first − 1 = {rel:e}");
            assert_close(
                &format!("g {gg:e}, h {h:?}: series/first − 1"),
                rel,
                predicted,
                Tol::new(1e-14, 1e-3),
            );
            worst = worst.max(rel / gg);
        }
        println!("g = {g_spec:e}: max (series/first − 1)/g = {worst:.3}");
    }
}

/// The plain sum `Σ_{n=1}^{N} (w_n/g) K[p_n]`, `N = g + 20√g + 60`, each term from a
/// `GaussianPsd` of correlation length `ℓ/√n` built here and `ClosedForm`'s normalised blur
/// (no mode search, no tail bounds), with `ln(w_n/g) = −g + (n−1) ln g − ln n!` by summing logs.
fn plain_sum(sigma: f64, ell: f64, xi: &Gaussian<f64, 2>, h: Vector2<f64>, g: f64) -> f64 {
    let n_max = (g + 20.0 * g.sqrt() + 60.0) as usize;
    let mut ln_fact = 0.0;
    let mut terms = Vec::new();
    for n in 1..=n_max {
        ln_fact += (n as f64).ln();
        let psd = GaussianPsd::<f64, 2>::isotropic(sigma, ell / (n as f64).sqrt()).unwrap();
        let k = TAU * ClosedForm.normalized_blur(&psd, xi, &h);
        let lw = -g + (n as f64 - 1.0) * g.ln() - ln_fact;
        terms.push(lw + k.ln());
    }
    let m = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    m.exp() * terms.iter().map(|t| (t - m).exp()).sum::<f64>()
}

/// The truncation meets its tolerance: against the plain sum, `|series/plain − 1| ≤ tolerance`
/// for tolerances 10⁻², 10⁻⁴, 10⁻⁸, `g` from 0.1 to 1000, at the lobe's centre and out to its
/// far tail. The orders summed grow like `√g` (printed; at most `12 √(g + 1) + 6` here).
#[test]
fn series_meets_its_tolerance() {
    let (sigma, ell) = (0.05, 1.0);
    let xi = Gaussian::new(Matrix2::new(0.8, 0.1, 0.1, 0.4)).unwrap();
    for tol in [1e-2, 1e-4, 1e-8] {
        let series = KirchhoffSeries::new(tol).unwrap();
        for g in [0.1_f64, 1.0, 10.0, 100.0, 1000.0] {
            let v = g.sqrt() / sigma;
            let psd = GaussianPsd::<f64, 2>::isotropic(sigma, ell).unwrap();
            let width = (g / (ell * ell) + 0.8).sqrt();
            let mut most = 0;
            for reach in [0.0, 1.0, 3.0, 6.0] {
                let h = Vector2::new(reach * width, 0.3 * reach * width);
                let s = series.sum(&Partial(ClosedForm), &psd, Some(&xi), &h, v);
                let want = plain_sum(sigma, ell, &xi, h, g);
                let rel = s.log_weight.exp() / want - 1.0;
                assert!(
                    rel.abs() <= tol,
                    "tol {tol:e}, g {g}, h {h:?}: rel {rel:e} ({} terms)",
                    s.terms()
                );
                assert!(
                    (s.terms() as f64) <= 12.0 * (g + 1.0).sqrt() + 6.0,
                    "tol {tol:e}, g {g}: {} terms",
                    s.terms()
                );
                most = most.max(s.terms());
            }
            println!("tolerance {tol:e}, g = {g:6}: at most {most} orders");
        }
    }
}

/// The geometric level is the Beckmann slope distribution blurred by the coherence: with the
/// phase screen, `L = (cos θ_o/λ²) v² ∫ Q(ξ) e^{−½ξᵀΞξ} e^{−ih·ξ} d²ξ` for
/// `Q = ((1 − e^{−g})/v²) exp(−½ g ξᵀC⁻¹ξ)` (the slope covariance `σ²C⁻¹` seen in `h_t/v`),
/// which `verify::oracle::coherence_integral` evaluates in closed form; to 10⁻¹² relative, plane
/// wave and partially coherent, isotropic and anisotropic surfaces, both sides.
#[test]
fn geometric_level_is_the_slope_distribution() {
    for eta in [None, Some(1.5)] {
        for c in [Matrix2::identity(), Matrix2::new(1.0, 0.3, 0.3, 0.6)] {
            for plane_wave in [false, true] {
                let pk = packet(THETA_I, Matrix2::new(1.44, 0.2, 0.2, 2.56), LAMBDA);
                let xi = section(&pk, plane_wave);
                for v_sigma in [2.0, 10.0] {
                    let (m, sigma, _) = screen_at(&pk, eta, &c, v_sigma);
                    let e = eta.unwrap_or(1.0);
                    for h in hs() {
                        let Some(exit) = exit_for(THETA_I, LAMBDA, eta, h) else {
                            continue;
                        };
                        let g = geometry(&pk, eta, exit);
                        let v = g.phase_factor();
                        let gg = (v * sigma).powi(2);
                        let q = (1.0 - (-gg).exp()) / (v * v);
                        let want = e.powi(3) * g.cos_o() / (LAMBDA * LAMBDA)
                            * v
                            * v
                            * oracle::coherence_integral(
                                q,
                                &(c.try_inverse().unwrap() * gg),
                                &xi,
                                &h,
                            );
                        let got = scattered_at(Geometric, plane_wave, &m, &pk, &g);
                        assert_close(
                            &format!(
                                "η {eta:?}, C {c:?}, plane {plane_wave}, vσ₀ {v_sigma}, h {h:?}"
                            ),
                            got,
                            want,
                            Tol::new(0.0, 1e-11),
                        );
                    }
                }
            }
        }
    }
}

/// The large-g limit: the series tends to the geometric level, with a relative difference in
/// the lobe (where the series is ≥ 1 % of its peak) that falls like `1/g`: measured
/// `max |series/geometric − 1| · g` is printed and must stay below 3 for g from 10 to 1000
/// (plane wave and partial coherence), while the difference itself falls 30-fold.
#[test]
fn series_large_g_limit_is_the_geometric_level() {
    let (sigma, ell) = (0.05, 1.0);
    let psd = GaussianPsd::<f64, 2>::isotropic(sigma, ell).unwrap();
    let xi = Gaussian::new(Matrix2::new(0.8, 0.1, 0.1, 0.4)).unwrap();
    let series = KirchhoffSeries::new(1e-9).unwrap();
    let mut errs = Vec::new();
    for g in [10.0_f64, 30.0, 100.0, 300.0, 1000.0] {
        let v = g.sqrt() / sigma;
        let width = (g / (ell * ell)).sqrt();
        let mut worst: f64 = 0.0;
        for coh in [Some(&xi), None] {
            let center = series
                .sum(&Partial(ClosedForm), &psd, coh, &Vector2::zeros(), v)
                .log_weight;
            for i in -12..=12 {
                for j in [-1.0, 0.0, 0.7] {
                    let h = Vector2::new(f64::from(i) * 0.25 * width, j * width);
                    let s = series
                        .sum(&Partial(ClosedForm), &psd, coh, &h, v)
                        .log_weight;
                    if s < center + 0.01f64.ln() {
                        continue;
                    }
                    // The geometric level: ((1 − e^{−g})/g) K[p_g], p_g of length ℓ/√g.
                    let pg = GaussianPsd::<f64, 2>::isotropic(sigma, ell / g.sqrt()).unwrap();
                    let k = match coh {
                        Some(x) => TAU * ClosedForm.normalized_blur(&pg, x, &h),
                        None => TAU * pg.value(&h),
                    };
                    let geo = (1.0 - (-g).exp()) / g * k;
                    worst = worst.max((s.exp() / geo - 1.0).abs());
                }
            }
        }
        println!(
            "g = {g:6}: max |series/geometric − 1| in the lobe = {worst:.3e} (× g = {:.3})",
            worst * g
        );
        assert!(worst * g < 3.0, "g {g}: {worst:e}");
        errs.push(worst);
    }
    assert!(errs[0] > 30.0 * errs[4], "{errs:?}");
}

/// The closed form of the Gaussian series (every order's weight from one set of Cholesky
/// products, used with `ClosedForm` and the plane wave) against the generic path (a power per
/// order and its own blur, forced by a blur method that delegates to `ClosedForm` but does not
/// claim to be exact): to 10⁻¹¹ relative, `g` from 10⁻³ to 10³, in and far out of the lobe,
/// anisotropic surface and section, f64; and in f32, where the closed form runs in f64 and the
/// generic path in f32, to 2·10⁻⁵.
#[test]
fn gaussian_closed_form_series_equals_the_generic_sum() {
    #[derive(Debug, Clone, Copy)]
    struct Delegate;
    impl<T: gmueller::Real> BlurMethod<T, 2, GaussianPsd<T, 2>> for Delegate {
        fn blur(&self, p: &GaussianPsd<T, 2>, c: &Gaussian<T, 2>, h: &Vector2<T>) -> T {
            ClosedForm.blur(p, c, h)
        }
        fn normalized_blur(&self, p: &GaussianPsd<T, 2>, c: &Gaussian<T, 2>, h: &Vector2<T>) -> T {
            ClosedForm.normalized_blur(p, c, h)
        }
        fn log_normalized_blur(
            &self,
            p: &GaussianPsd<T, 2>,
            c: &Gaussian<T, 2>,
            h: &Vector2<T>,
        ) -> T {
            ClosedForm.log_normalized_blur(p, c, h)
        }
    }
    fn run<T: gmueller::Real>(tol: f64) {
        let l = T::lit;
        let c = Gaussian::new(Matrix2::new(l(1.0), l(0.3), l(0.3), l(0.6))).unwrap();
        let xi = Gaussian::new(Matrix2::new(l(0.8), l(-0.19), l(-0.19), l(0.05))).unwrap();
        let series = KirchhoffSeries::new(1e-10).unwrap();
        for g in [1e-3_f64, 0.5, 10.0, 1000.0] {
            let sigma = 0.05;
            let psd = GaussianPsd::<T, 2>::from_autocorrelation(l(sigma * sigma), &c).unwrap();
            let v = l(g.sqrt() / sigma);
            for (hx, hy) in [(0.0, 0.0), (1.5, -0.5), (6.0, 4.0), (-20.0, 3.0)] {
                let h = Vector2::new(l(hx), l(hy));
                for xi in [Some(&xi), None] {
                    let fast = series.sum(&Partial(ClosedForm), &psd, xi, &h, v);
                    let slow = series.sum(&Partial(Delegate), &psd, xi, &h, v);
                    let (a, b) = (fast.log_weight.to_f64(), slow.log_weight.to_f64());
                    assert!(
                        (a - b).abs() <= tol * (1.0 + a.abs()),
                        "g {g}, h ({hx}, {hy}), section {}: ln K {a} vs {b}",
                        xi.is_some()
                    );
                }
            }
        }
    }
    run::<f64>(1e-11);
    run::<f32>(2e-5);
}
