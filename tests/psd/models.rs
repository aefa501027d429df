//! Verifies `gmueller::psd`: normalisation `∫p = (2π)^{n/2} R(0)` of every model by independent
//! quadrature, the unitary-transform definition of the Gaussian PSD, SCATMECH's Gaussian and ABC
//! PSDs after the change of variables, the S2.17 constant (numerically, against the direct
//! integral S2.15), Bessel efficiencies against Abramowitz & Stegun, an accuracy sweep of every
//! blur method against the adaptive reference, and the Gaussian PSD's log-free blur path against
//! its log-space form.

use crate::common;

use common::{Tol, assert_close, cube_quad};
use gmueller::gaussian::Gaussian;
use gmueller::psd::{
    Adaptive, BlurMethod, ClosedForm, GaussHermite, GaussianMixturePsd, GaussianPsd, Grating,
    KCorrelation, OrderCutoff, Psd, Smooth, bessel_j,
};
use gmueller::verify::oracle;
use nalgebra::{Matrix2, Matrix3, Rotation2, Rotation3, Vector2, Vector3};
use num_complex::Complex;

const TAU: f64 = std::f64::consts::TAU;
const PI: f64 = std::f64::consts::PI;

/// `∫ f(|ζ|) dⁿζ` for a radial function, by the trapezoid rule in `t = ln r` over `[−30, 60]`
/// (exponentially convergent for the decays used here; independent of the crate).
fn radial_integral(n: usize, f: impl Fn(f64) -> f64) -> f64 {
    let surface = if n == 2 { TAU } else { 2.0 * TAU };
    let (a, b, m) = (-30.0_f64, 60.0_f64, 60_000);
    let dt = (b - a) / m as f64;
    let s: f64 = (0..=m)
        .map(|i| {
            let r = (a + dt * i as f64).exp();
            let w = if i == 0 || i == m { 0.5 } else { 1.0 };
            w * f(r) * r.powi(n as i32)
        })
        .sum();
    surface * s * dt
}

/// `exp(−½ xᵀΣ⁻¹x)` (the kit's oracle).
use gmueller::verify::oracle::gaussian as literal_gauss;

const QUAD: Tol = Tol::new(1e-11, 1e-9);

// ------------------------------------------------------------------ normalisation

#[test]
fn normalisation_gaussian_and_kcorrelation() {
    let (sigma, ell) = (0.3, 1.7);
    let g2 = GaussianPsd::<f64, 2>::isotropic(sigma, ell).unwrap();
    let i2 = radial_integral(2, |r| g2.value(&Vector2::new(r, 0.0)));
    assert_close("∫p Gaussian 2-D", i2, TAU * sigma * sigma, QUAD);
    assert_close("integral() Gaussian 2-D", g2.integral(), i2, QUAD);
    let g3 = GaussianPsd::<f64, 3>::isotropic(sigma, ell).unwrap();
    let i3 = radial_integral(3, |r| g3.value(&Vector3::new(0.0, r, 0.0)));
    assert_close("∫p Gaussian 3-D", i3, TAU.powf(1.5) * sigma * sigma, QUAD);

    for &(t, gamma) in &[(4.0_f64, 1.5_f64), (0.3, 2.0), (25.0, 3.7)] {
        let k = KCorrelation::<f64, 2>::new(0.02, t, gamma).unwrap();
        let i = radial_integral(2, |r| k.value(&Vector2::new(r, 0.0)));
        assert_close("∫p K-correlation 2-D", i, TAU * 0.02, Tol::new(1e-12, 1e-8));
        // The main paper: p per unit variance and unit integral is (γ−1)T/(2π)(1+T|ζ|²)^{−(γ+1)/2}.
        let z = Vector2::<f64>::new(0.37, -0.2);
        let formalism =
            (gamma - 1.0) * t / TAU * (1.0 + t * z.norm_squared()).powf(-(gamma + 1.0) / 2.0);
        assert_close(
            "K-correlation vs the main paper's form",
            k.value(&z) / k.integral(),
            formalism,
            Tol::new(1e-14, 1e-12),
        );
    }
    let k3 = KCorrelation::<f64, 3>::new(0.5, 2.0, 3.5).unwrap();
    let i = radial_integral(3, |r| k3.value(&Vector3::new(r, 0.0, 0.0)));
    assert_close(
        "∫p K-correlation 3-D",
        i,
        TAU.powf(1.5) * 0.5,
        Tol::new(1e-12, 1e-8),
    );
    assert!(
        KCorrelation::<f64, 3>::new(0.5, 2.0, 1.9).is_err(),
        "γ ≤ n − 1 has no finite variance"
    );
    // Gaussian mixture (here the K-correlation fit): ∫p = 2π Σ variances.
    let (mix, _) = KCorrelation::<f64, 2>::new(0.02, 4.0, 2.5)
        .unwrap()
        .mixture_fit(12)
        .unwrap();
    let i = radial_integral(2, |r| mix.value(&Vector2::new(r, 0.0)));
    assert_close("∫p mixture 2-D", i, mix.integral(), QUAD);
    assert_close(
        "mixture integral()",
        mix.integral(),
        TAU * mix.variance(),
        Tol::new(0.0, 1e-15),
    );
}

/// Dirac models: ∫ (p * g^Σ)(h) dⁿh = σ² (2π)^{n/2} |Σ|^{1/2} iff ∫p = (2π)^{n/2} σ².
#[test]
fn normalisation_dirac_models_through_the_blur() {
    let cov = Gaussian::new(Matrix2::new(0.5_f64, 0.1, 0.1, 0.3)).unwrap();
    let expected = |var: f64| var * TAU * cov.det().sqrt();
    let cut = OrderCutoff {
        max_frequency: 12.0,
        tail: 1e-14,
    };
    let grating = Grating::sinusoidal(2.0, &Vector2::new(1.0, 0.5), 1.3, cut).unwrap();
    let total = cube_quad(
        |h: &Vector2<f64>| Complex::new(ClosedForm.blur(&grating, &cov, h), 0.0),
        20.0,
        801,
    )
    .re;
    assert_close(
        "∫ blur, sinusoidal grating",
        total,
        expected(grating.variance()),
        QUAD,
    );
    let smooth = Smooth::new(0.8).unwrap();
    let total = cube_quad(
        |h: &Vector2<f64>| Complex::new(ClosedForm.blur(&smooth, &cov, h), 0.0),
        10.0,
        401,
    )
    .re;
    assert_close("∫ blur, smooth", total, expected(0.8), QUAD);
    assert_close(
        "integral() smooth",
        Psd::<f64, 2>::integral(&smooth),
        TAU * 0.8,
        Tol::new(0.0, 1e-15),
    );
}

/// p = F{R} under the unitary transform: direct quadrature of R(x) = σ² g^Λ(x).
#[test]
fn gaussian_psd_is_unitary_transform_of_r() {
    let lambda = Matrix2::new(1.2, 0.3, 0.3, 0.6);
    let var = 0.04;
    let p = GaussianPsd::from_autocorrelation(var, &Gaussian::new(lambda).unwrap()).unwrap();
    for z in [
        Vector2::new(0.0, 0.0),
        Vector2::new(0.8, -0.5),
        Vector2::new(-1.5, 2.0),
    ] {
        let ft = cube_quad(
            |x| Complex::from_polar(var * literal_gauss(&lambda, x), -z.dot(x)),
            10.0,
            301,
        ) / TAU;
        assert_close("p = F{R}", p.value(&z), ft.re, QUAD);
    }
}

// ------------------------------------------------------------------ SCATMECH conversions

/// SCATMECH: S(f) = π σ² L² exp(−(π L f)²), C(r) = σ² exp(−r²/L²), f in cycles/µm;
/// ours: S(f) = 2π p(2πf), ℓ = L/√2.
#[test]
fn gaussian_psd_matches_scatmech() {
    let (sigma, l) = (0.005_f64, 0.8_f64);
    let p = GaussianPsd::<f64, 2>::from_scatmech(sigma, l).unwrap();
    for f in [
        Vector2::<f64>::new(0.0, 0.0),
        Vector2::new(0.3, 0.1),
        Vector2::new(-0.7, 0.9),
    ] {
        let s = PI * sigma * sigma * l * l * (-(PI * l).powi(2) * f.norm_squared()).exp();
        assert_close("SCATMECH S(f)", p.value_cycles(&f), s, Tol::new(0.0, 1e-13));
        assert_close(
            "S(f) = 2π p(2πf)",
            p.value_cycles(&f),
            TAU * p.value(&(f * TAU)),
            Tol::new(0.0, 1e-14),
        );
    }
    // ∫ S d²f = σ² (SCATMECH's normalisation) vs ∫ p d²ζ = 2π σ² (ours).
    let is = radial_integral(2, |r| p.value_cycles(&Vector2::new(r, 0.0)));
    assert_close("∫S d²f = σ²", is, sigma * sigma, QUAD);
}

/// SCATMECH ABC: S(f) = A/(1 + (Bf)²)^{C/2}; T = B²/4π², γ = C − 1, σ² = 2πA/((C−2)B²).
#[test]
fn kcorrelation_matches_scatmech_abc() {
    let (a, b, c) = (3e-5_f64, 120.0_f64, 2.6_f64);
    let k = KCorrelation::<f64, 2>::from_abc(a, b, c).unwrap();
    for f in [
        Vector2::<f64>::new(0.0, 0.0),
        Vector2::new(0.01, 0.02),
        Vector2::new(1.0, -0.5),
    ] {
        let s = a / (1.0 + (b * b) * f.norm_squared()).powf(c / 2.0);
        assert_close("ABC S(f)", k.value_cycles(&f), s, Tol::new(0.0, 1e-13));
    }
    let is = radial_integral(2, |r| k.value_cycles(&Vector2::new(r, 0.0)));
    assert_close("σ² = ∫S d²f", k.variance(), is, Tol::new(1e-16, 1e-8));
    let (a2, b2, c2) = k.abc();
    assert_close("A round trip", a2, a, Tol::new(0.0, 1e-14));
    assert_close("B round trip", b2, b, Tol::new(0.0, 1e-14));
    assert_close("C round trip", c2, c, Tol::new(0.0, 1e-14));
}

// ------------------------------------------------------------------ S2.17 constant

/// S2.15 directly: f = ∫ e^{−ik r̂·ξ} R(ξ) e^{−ikŝ·ξ} g^Θ(Qᵀξ) dⁿξ, by quadrature; S2.17 says
/// `f = C_n |Θ|^{1/2} (p * g^Ξ)(h)`, `h = k(r̂ + ŝ)`, `Ξ = QΘ⁻¹Qᵀ`. Decides `C_n = (2π)^{n/2}`, not `8π³`.
#[test]
fn s2_17_constant_2d() {
    let var = 0.01;
    let lambda = Matrix2::new(0.9, 0.2, 0.2, 0.5);
    let psd = GaussianPsd::from_autocorrelation(var, &Gaussian::new(lambda).unwrap()).unwrap();
    let theta = Matrix2::new(2.0, 0.5, 0.5, 0.7);
    let rot = Rotation2::new(0.6);
    let gt = Gaussian::new(theta).unwrap();
    let xi = gt.inverse().unwrap().rotated(&rot).unwrap(); // Ξ = QΘ⁻¹Qᵀ
    let (k_r, k_s) = (Vector2::new(0.3, 0.4), Vector2::new(-0.8, 0.1));
    let q = rot.matrix().transpose();
    let h = k_r + k_s;
    let direct = oracle::coherence_integral_by_quadrature(
        &|x| var * literal_gauss(&lambda, x),
        &theta,
        &q.transpose(),
        &h,
        12.0,
        401,
    );
    let blur = gt.det().sqrt() * ClosedForm.blur(&psd, &xi, &h);
    assert_close("S2.17 with (2π)^{n/2}", direct.re, TAU * blur, QUAD);
    assert_close("S2.15 is real", direct.im, 0.0, QUAD);
    assert!(
        (direct.re - 8.0 * PI.powi(3) * blur).abs() > 0.5 * direct.re,
        "printed 8π³ must fail"
    );
}

#[test]
fn s2_17_constant_3d() {
    let var = 0.02;
    let lambda = Matrix3::new(0.8, 0.1, 0.0, 0.1, 0.6, 0.1, 0.0, 0.1, 0.9);
    let psd = GaussianPsd::from_autocorrelation(var, &Gaussian::new(lambda).unwrap()).unwrap();
    let theta = Matrix3::new(1.5, 0.3, 0.0, 0.3, 0.8, 0.0, 0.0, 0.0, 1.1);
    let rot = Rotation3::from_euler_angles(0.2, 0.7, -0.4);
    let gt = Gaussian::new(theta).unwrap();
    let xi = gt.inverse().unwrap().rotated(&rot).unwrap();
    let (k_r, k_s) = (Vector3::new(0.3, -0.2, 0.5), Vector3::new(-0.1, 0.4, -0.9));
    let q = rot.matrix().transpose();
    let direct = oracle::coherence_integral_by_quadrature(
        &|x| var * literal_gauss(&lambda, x),
        &theta,
        &q.transpose(),
        &(k_r + k_s),
        8.0,
        81,
    );
    let blur = gt.det().sqrt() * ClosedForm.blur(&psd, &xi, &(k_r + k_s));
    assert_close(
        "S2.17 (3-D) with (2π)^{3/2}",
        direct.re,
        TAU.powf(1.5) * blur,
        QUAD,
    );
    assert!(
        (direct.re - 8.0 * PI.powi(3) * blur).abs() > 0.5 * direct.re,
        "printed 8π³ must fail"
    );
}

// ------------------------------------------------------------------ closed-form blurs

/// Closed-form Gaussian and mixture blurs against direct quadrature of (2π)^{−1}∫p(ζ)g(h−ζ)dζ.
#[test]
fn closed_form_blur_matches_quadrature() {
    let psd = GaussianPsd::<f64, 2>::isotropic(0.1, 0.8).unwrap();
    let aniso = GaussianPsd::from_autocorrelation(
        0.05,
        &Gaussian::new(Matrix2::new(3.0, 1.0, 1.0, 0.7)).unwrap(),
    )
    .unwrap();
    let mix = GaussianMixturePsd::new(vec![psd, aniso]).unwrap();
    let covm = Matrix2::new(0.3, -0.1, -0.1, 0.5);
    let cov = Gaussian::new(covm).unwrap();
    for h in [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.0, -0.5),
        Vector2::new(3.0, 2.0),
    ] {
        let quad =
            |p: &dyn Fn(&Vector2<f64>) -> f64| oracle::blur_by_quadrature(p, &covm, &h, 14.0, 401);
        assert_close(
            "Gaussian blur",
            ClosedForm.blur(&psd, &cov, &h),
            quad(&|z| psd.value(z)),
            QUAD,
        );
        assert_close(
            "mixture blur",
            ClosedForm.blur(&mix, &cov, &h),
            quad(&|z| mix.value(z)),
            QUAD,
        );
        let r = Adaptive::new(1e-12).unwrap().blur(&mix, &cov, &h);
        assert_close(
            "adaptive vs closed form",
            r,
            ClosedForm.blur(&mix, &cov, &h),
            Tol::new(1e-16, 1e-11),
        );
    }
}

#[test]
fn adaptive_3d_matches_closed_form() {
    let psd = GaussianPsd::from_autocorrelation(
        0.02,
        &Gaussian::new(Matrix3::new(1.0, 0.2, 0.0, 0.2, 0.5, 0.1, 0.0, 0.1, 2.0)).unwrap(),
    )
    .unwrap();
    let cov = Gaussian::new(Matrix3::new(0.4, 0.1, 0.0, 0.1, 0.3, 0.0, 0.0, 0.0, 0.6)).unwrap();
    let h = Vector3::new(0.5, -0.3, 0.8);
    let r = Adaptive::new(1e-8).unwrap().blur(&psd, &cov, &h);
    assert_close(
        "adaptive 3-D",
        r,
        ClosedForm.blur(&psd, &cov, &h),
        Tol::new(1e-16, 1e-8),
    );
}

// ------------------------------------------------------------------ gratings

/// Abramowitz & Stegun, Table 9.1 (J0, J1, J2 at x = 1; J0, J1 at x = 10) and Table 9.5 (zeros).
#[test]
fn bessel_against_tables() {
    let j1 = bessel_j(2, 1.0);
    assert_close("J0(1)", j1[0], 0.7651976865579666, Tol::new(1e-15, 0.0));
    assert_close("J1(1)", j1[1], 0.4400505857449335, Tol::new(1e-15, 0.0));
    assert_close("J2(1)", j1[2], 0.1149034849319005, Tol::new(1e-15, 0.0));
    let j10 = bessel_j(1, 10.0);
    assert_close("J0(10)", j10[0], -0.2459357644513483, Tol::new(1e-14, 0.0));
    assert_close("J1(10)", j10[1], 0.04347274616886144, Tol::new(1e-14, 0.0));
    assert_close(
        "J0(j01)",
        bessel_j(0, 2.404825557695773)[0],
        0.0,
        Tol::new(1e-15, 0.0),
    );
    assert_close(
        "J1(j11)",
        bessel_j(1, 3.831705970207512)[1],
        0.0,
        Tol::new(1e-15, 0.0),
    );
    // Power series J_m(x) = Σ_k (−1)^k (x/2)^{2k+m} / (k! (k+m)!) as an independent oracle.
    for &x in &[0.3, 2.4, 7.0] {
        let j = bessel_j(6, x);
        for (m, &jm) in j.iter().enumerate() {
            let mut term = (0.5 * x).powi(m as i32) / (1..=m).map(|v| v as f64).product::<f64>();
            let mut s = 0.0;
            for k in 0..60 {
                s += term;
                term *= -(0.25 * x * x) / ((k + 1) as f64 * (k + 1 + m) as f64);
            }
            assert_close("J_m series", jm, s, Tol::new(1e-14, 1e-12));
        }
        // Σ_m J_m² = J0² + 2 Σ_{m≥1} J_m² = 1.
        let all = bessel_j(80, x);
        let sum = all[0] * all[0] + 2.0 * all[1..].iter().map(|v| v * v).sum::<f64>();
        assert_close("Σ J_m² = 1", sum, 1.0, Tol::new(1e-14, 0.0));
    }
    assert_close(
        "J1(−1) = −J1(1)",
        bessel_j(1, -1.0)[1],
        -0.4400505857449335,
        Tol::new(1e-15, 0.0),
    );
}

#[test]
fn grating_orders_and_cutoff() {
    let cut = OrderCutoff {
        max_frequency: 100.0,
        tail: 1e-12,
    };
    let g = Grating::<f64, 2>::sinusoidal(1.0, &Vector2::new(1.0, 0.0), 2.0, cut).unwrap();
    assert!(g.dropped_efficiency() <= 1e-12);
    for (z, e) in g.orders() {
        let m = (z.x / TAU).round() as i64;
        let jm = bessel_j(m.unsigned_abs() as usize, 2.0)[m.unsigned_abs() as usize];
        assert_close("η_m = J_m(a)²", *e, jm * jm, Tol::new(1e-15, 1e-12));
    }
    // Frequency cut: only |m| 2π/Λ ≤ max_frequency.
    let narrow = Grating::<f64, 2>::sinusoidal(
        1.0,
        &Vector2::new(0.0, 1.0),
        2.0,
        OrderCutoff {
            max_frequency: 13.0,
            tail: 0.0,
        },
    )
    .unwrap();
    assert_eq!(narrow.orders().len(), 5, "orders 0, ±1, ±2");
    assert!(narrow.orders().iter().all(|(z, _)| z.norm() <= 13.0));
    // Binary grating: π depth, duty ½ suppresses the zeroth order; Σ η = 1.
    let bin = Grating::<f64, 2>::rectangular(
        2.0,
        &Vector2::new(1.0, 0.0),
        PI,
        0.5,
        OrderCutoff {
            max_frequency: 1e4,
            tail: 0.0,
        },
    )
    .unwrap();
    assert!(
        bin.orders().iter().all(|(z, _)| z.norm() > 0.0),
        "zeroth order vanishes"
    );
    assert_close(
        "binary ±1 = 4/π²",
        bin.orders()[0].1,
        4.0 / (PI * PI),
        Tol::new(1e-15, 1e-12),
    );
    assert!(1.0 - bin.variance() < 1e-3 && bin.variance() <= 1.0 + 1e-12);
    // Crossed: product efficiencies, total 1.
    let gx = Grating::<f64, 2>::sinusoidal(1.0, &Vector2::new(1.0, 0.0), 1.0, cut).unwrap();
    let gy = Grating::<f64, 2>::sinusoidal(1.5, &Vector2::new(0.0, 1.0), 0.5, cut).unwrap();
    let xg = Grating::crossed(&gx, &gy, 0.0).unwrap();
    assert_close("crossed Σ η", xg.variance(), 1.0, Tol::new(1e-12, 0.0));
    // Blur = Σ η_m g(h − ζ_m).
    let cov = Gaussian::new(Matrix2::new(0.2, 0.0, 0.0, 0.2)).unwrap();
    let h = Vector2::new(TAU, 0.1);
    let direct: f64 = gx
        .orders()
        .iter()
        .map(|(z, e)| e * literal_gauss(&Matrix2::new(0.2, 0.0, 0.0, 0.2), &(h - z)))
        .sum();
    assert_close(
        "grating blur",
        ClosedForm.blur(&gx, &cov, &h),
        direct,
        Tol::new(1e-15, 1e-13),
    );
}

// ------------------------------------------------------------------ accuracy sweep

struct Case {
    cov: Gaussian<f64, 2>,
    h: Vector2<f64>,
}

fn sweep_cases() -> Vec<Case> {
    // Narrow (coherent), comparable and wide (incoherent) blurs relative to the K-correlation scale
    // 1/√T = 0.5, anisotropic, at the peak and in the tail.
    let mk = |a: f64, b: f64, c: f64| Gaussian::new(Matrix2::new(a, b, b, c)).unwrap();
    vec![
        Case {
            cov: mk(0.01, 0.002, 0.004),
            h: Vector2::new(0.3, -0.2),
        },
        Case {
            cov: mk(0.2, 0.05, 0.1),
            h: Vector2::new(0.0, 0.0),
        },
        Case {
            cov: mk(0.2, 0.05, 0.1),
            h: Vector2::new(2.0, 1.0),
        },
        Case {
            cov: mk(4.0, 1.0, 1.5),
            h: Vector2::new(1.0, -3.0),
        },
    ]
}

/// Every blur method against the adaptive reference at tol 1e-13, over tolerances 1e-2 … 1e-10.
#[test]
fn accuracy_sweep_kcorrelation() {
    let k = KCorrelation::<f64, 2>::new(0.01, 4.0, 2.2).unwrap();
    let cases = sweep_cases();
    let reference: Vec<f64> = cases
        .iter()
        .map(|c| Adaptive::new(1e-13).unwrap().blur(&k, &c.cov, &c.h))
        .collect();
    for tol in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10] {
        // Adaptive: relative error ≤ tol.
        let ad = Adaptive::new(tol).unwrap();
        for (c, r) in cases.iter().zip(&reference) {
            let v = ad.blur(&k, &c.cov, &c.h);
            assert!(
                ((v - r) / r).abs() <= tol,
                "adaptive tol {tol}: rel err {:e}",
                ((v - r) / r).abs()
            );
        }
        // Mixture fit: |error| ≤ sup|p − p_m| |Σ|^{1/2} with the measured sup error ≤ tol·p(0).
        let (mix, m, err) = k.mixture_fit_to(tol).unwrap();
        assert!(err <= tol);
        for (c, r) in cases.iter().zip(&reference) {
            let v = ClosedForm.blur(&mix, &c.cov, &c.h);
            let bound = err * k.peak_value() * c.cov.det().sqrt();
            eprintln!(
                "mixture m={m} tol {tol:e}: rel err {:e}, abs err {:e} ≤ bound {bound:e}",
                ((v - r) / r).abs(),
                (v - r).abs()
            );
            assert!(
                (v - r).abs() <= bound * (1.0 + 1e-6) + 1e-16,
                "mixture bound violated"
            );
        }
    }
    // Gauss–Hermite: measured (no a-priori tolerance); converges for the narrow blur.
    let mut prev = f64::INFINITY;
    for order in [2, 4, 8, 16, 32, 64] {
        let gh = GaussHermite::new(order).unwrap();
        let errs: Vec<f64> = cases
            .iter()
            .zip(&reference)
            .map(|(c, r)| ((gh.blur(&k, &c.cov, &c.h) - r) / r).abs())
            .collect();
        eprintln!("Gauss–Hermite order {order}: rel errs {errs:?}");
        assert!(
            errs[0] <= prev.max(1e-14),
            "GH must converge on the narrow case"
        );
        prev = errs[0];
    }
    assert!(prev < 1e-10, "GH order 64, narrow blur: {prev:e}");
}

#[test]
fn gauss_hermite_integrates_polynomials_exactly() {
    let gh = GaussHermite::<f64>::new(5).unwrap();
    let (x, w) = gh.nodes_weights();
    // E[u^{2k}] = (2k − 1)!! for the standard normal.
    for (k, expect) in [(0, 1.0), (1, 1.0), (2, 3.0), (3, 15.0), (4, 105.0)] {
        let s: f64 = x.iter().zip(w).map(|(u, w)| w * u.powi(2 * k)).sum();
        assert_close("GH moment", s, expect, Tol::new(1e-12, 1e-12));
    }
}

/// Extremes: blur of Gaussian PSD with eigenvalues 1e-12…1e12 is finite, ≥ 0, 0 on underflow.
#[test]
fn blur_stability() {
    for &s in &[1e-12_f64, 1e-6, 1.0, 1e6, 1e12] {
        for &a in &[1.0_f64, 1e6] {
            let cov = Gaussian::new(Matrix2::new(s, 0.0, 0.0, s / a)).unwrap();
            let psd = GaussianPsd::<f64, 2>::isotropic(0.01, 1.0 / s.sqrt()).unwrap();
            for &hs in &[0.0, 1.0, 1e3, 1e9] {
                let h = Vector2::new(hs, -hs);
                let v = ClosedForm.blur(&psd, &cov, &h);
                assert!(v.is_finite() && v >= 0.0, "blur {v} at s {s} a {a} h {hs}");
                let l = psd.log_blur(&cov, &h);
                assert!(l.is_finite() || l == f64::NEG_INFINITY);
                let v32 = ClosedForm.blur(
                    &GaussianPsd::<f32, 2>::isotropic(0.01, (1.0 / s.sqrt()) as f32).unwrap(),
                    &Gaussian::new(Matrix2::new(s as f32, 0.0, 0.0, (s / a) as f32)).unwrap(),
                    &h.cast::<f32>(),
                );
                assert!(v32.is_finite() && v32 >= 0.0);
            }
        }
    }
}

/// 3-D: the K-correlation mixture fit and Gauss–Hermite against the adaptive reference.
#[test]
fn kcorrelation_3d_methods() {
    let k = KCorrelation::<f64, 3>::new(0.02, 1.0, 3.5).unwrap();
    let cov = Gaussian::new(Matrix3::new(
        0.05, 0.01, 0.0, 0.01, 0.04, 0.0, 0.0, 0.0, 0.03,
    ))
    .unwrap();
    let h = Vector3::new(0.4, -0.2, 0.3);
    let reference = Adaptive::new(1e-9).unwrap().blur(&k, &cov, &h);
    let (mix, _, err) = k.mixture_fit_to(1e-6).unwrap();
    let v = ClosedForm.blur(&mix, &cov, &h);
    assert!(
        (v - reference).abs()
            <= err * k.peak_value() * cov.det().sqrt() * 1.001 + 1e-15 * reference
    );
    let gh = GaussHermite::new(16).unwrap().blur(&k, &cov, &h);
    assert_close("GH 3-D, narrow blur", gh, reference, Tol::new(1e-16, 1e-8));
}

/// f32 evaluation agrees with f64 (well-conditioned inputs), for every method.
#[test]
fn f32_agrees_with_f64() {
    let k64 = KCorrelation::<f64, 2>::new(0.01, 4.0, 2.2).unwrap();
    let k32 = KCorrelation::<f32, 2>::new(0.01, 4.0, 2.2).unwrap();
    let c64 = Gaussian::new(Matrix2::new(0.2, 0.05, 0.05, 0.1)).unwrap();
    let c32 = Gaussian::new(Matrix2::new(0.2_f32, 0.05, 0.05, 0.1)).unwrap();
    let tol = Tol::new(1e-9, 2e-5);
    for h in [Vector2::new(0.0, 0.0), Vector2::new(0.7, -1.1)] {
        let h32 = h.cast::<f32>();
        let (m64, _) = k64.mixture_fit(24).unwrap();
        let (m32, _) = k32.mixture_fit(24).unwrap();
        assert_close(
            "mixture f32",
            f64::from(ClosedForm.blur(&m32, &c32, &h32)),
            ClosedForm.blur(&m64, &c64, &h),
            tol,
        );
        let (g64, g32) = (
            GaussHermite::<f64>::new(16).unwrap(),
            GaussHermite::<f32>::new(16).unwrap(),
        );
        assert_close(
            "GH f32",
            f64::from(g32.blur(&k32, &c32, &h32)),
            g64.blur(&k64, &c64, &h),
            tol,
        );
        let a32 = Adaptive::new(1e-5_f32).unwrap().blur(&k32, &c32, &h32);
        assert_close(
            "adaptive f32",
            f64::from(a32),
            Adaptive::new(1e-10).unwrap().blur(&k64, &c64, &h),
            Tol::new(1e-9, 5e-5),
        );
        let p64 = GaussianPsd::<f64, 2>::isotropic(0.1, 0.7).unwrap();
        let p32 = GaussianPsd::<f32, 2>::isotropic(0.1, 0.7).unwrap();
        assert_close(
            "Gaussian PSD f32",
            f64::from(ClosedForm.blur(&p32, &c32, &h32)),
            ClosedForm.blur(&p64, &c64, &h),
            tol,
        );
    }
}

/// Every method stays finite and non-negative for blur eigenvalues 1e-12…1e12, anisotropy 1e6.
#[test]
fn all_methods_finite_at_extremes() {
    let k = KCorrelation::<f64, 2>::new(0.01, 4.0, 2.2).unwrap();
    let (mix, _) = k.mixture_fit(16).unwrap();
    let gh = GaussHermite::<f64>::new(8).unwrap();
    let ad = Adaptive::new(1e-4).unwrap();
    for &s in &[1e-12_f64, 1.0, 1e12] {
        for &a in &[1.0_f64, 1e6] {
            let cov = Gaussian::new(Matrix2::new(s, 0.0, 0.0, s / a)).unwrap();
            for &hs in &[0.0_f64, 1.0, 1e6] {
                let h = Vector2::new(hs, 0.5 * hs);
                for v in [
                    ClosedForm.blur(&mix, &cov, &h),
                    gh.blur(&k, &cov, &h),
                    ad.blur(&k, &cov, &h),
                ] {
                    assert!(v.is_finite() && v >= 0.0, "blur {v} at s {s} a {a} h {hs}");
                }
            }
        }
    }
}

/// Regression: a PSD peak 10⁷ times narrower than the blur, off-centre, must not be missed by the
/// adaptive reference (its first estimate samples only the peak's tails).
#[test]
fn adaptive_finds_sharp_off_centre_peak() {
    let psd = GaussianPsd::<f64, 2>::isotropic(0.1, 1e3).unwrap(); // spectral width 1e-3
    let cov = Gaussian::new(Matrix2::new(1e8, 2e7, 2e7, 5e7)).unwrap(); // width ~1e4
    for h in [
        Vector2::new(1e4, 5e3),
        Vector2::new(-3e3, 2e3),
        Vector2::new(0.0, 0.0),
    ] {
        let exact = ClosedForm.blur(&psd, &cov, &h);
        for tol in [1e-4, 1e-8] {
            let v = Adaptive::new(tol).unwrap().blur(&psd, &cov, &h);
            assert_close("adaptive, sharp peak", v, exact, Tol::new(1e-300, tol));
        }
    }
}

/// `GaussianPsd::normalized_blur_value` (the log-free fast path of the closed-form blur)
/// against the exponential of `log_normalized_blur` over scales that cross its switches
/// (`∏Lᵢᵢ`, `σ²` outside `[1e-30, 1e30]`, `|L⁻¹h|² > 100`), in f64 and f32.
#[test]
fn normalized_blur_value_is_exp_of_log_form() {
    let mut worst = [0.0f64; 2];
    for &rms in &[0.0, 1e-20, 1e-3, 0.02, 1e10] {
        for &len in &[1e-12, 1e-3, 0.5, 2.0, 50.0, 1e12] {
            for &w in &[1e-9, 0.1, 3.0, 1e4, 1e9] {
                for &hs in &[0.0, 0.3, 3.0, 30.0] {
                    let p = GaussianPsd::<f64, 2>::isotropic(rms, len).unwrap();
                    let cov = Matrix2::new(1.0, 0.3, 0.3, 2.0) / (w * w);
                    let cov = Gaussian::new(cov).unwrap();
                    // h in units of the combined spectral width.
                    let h =
                        Vector2::new(0.7, -0.4) * (hs * (1.0 / (len * len) + 1.0 / (w * w)).sqrt());
                    let (fast, log) = (
                        p.normalized_blur_value(&cov, &h),
                        p.log_normalized_blur(&cov, &h).exp(),
                    );
                    assert_close("normalized blur f64", fast, log, Tol::new(0.0, 1e-13));
                    worst[0] = worst[0].max(if log > 0.0 {
                        (fast / log - 1.0).abs()
                    } else {
                        0.0
                    });
                    // f32 where the parameters and the peak p(0) = σ²ℓ² are representable
                    // (a larger peak is rejected at construction).
                    let peak = rms * rms * len * len;
                    if rms < 1e15
                        && (1e-15..1e15).contains(&len)
                        && (1e-15..1e15).contains(&w)
                        && peak < 1e38
                    {
                        let p = GaussianPsd::<f32, 2>::isotropic(rms as f32, len as f32).unwrap();
                        let cov =
                            Gaussian::new(Matrix2::new(1.0f32, 0.3, 0.3, 2.0) / (w * w) as f32);
                        let Ok(cov) = cov else { continue };
                        let h = h.map(|v| v as f32);
                        let (fast, log) = (
                            p.normalized_blur_value(&cov, &h),
                            p.log_normalized_blur(&cov, &h).exp(),
                        );
                        assert_close(
                            "normalized blur f32",
                            fast.into(),
                            log.into(),
                            Tol::new(0.0, 2e-5),
                        );
                        worst[1] = worst[1].max(if log > 0.0 {
                            f64::from((fast / log - 1.0).abs())
                        } else {
                            0.0
                        });
                    }
                }
            }
        }
    }
    println!(
        "normalized_blur_value vs exp(log form): worst relative difference f64 {:.1e}, f32 {:.1e}",
        worst[0], worst[1]
    );
}
