//! Verifies the wave-BSDF importance sampler: `pdf` integrates to 1 over the hemisphere (nested
//! adaptive Gauss–Legendre in (φ, θ), `tests/common/quadrature.rs`: nodes computed at run time,
//! independent of the crate's Gauss–Kronrod table, and itself checked against closed forms); `sample` draws from `pdf` (chi-square on 20 000 seeded
//! draws, bins about the specular point with expected counts from quadrature of `pdf`, 99.9 %
//! Wilson–Hilferty quantile), and the same test rejects pdfs that forget the `cos θ_o` Jacobian
//! or the truncation mass; `pdf(sample.direction) == sample.pdf`; weights are value/pdf; the
//! truncated masses agree with an independent Cartesian erf quadrature, a 2-D quadrature and
//! Monte Carlo; the test's own erf/erfc match reference values; importance-sampled estimates of
//! `∫ L_o dω` agree with quadrature of the kernel.

use crate::common;

use common::quadrature::{gauss_legendre, integrate};
use common::{SplitMix64, Tol, assert_close};
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::pbsdf::{FresnelReflection, RayleighRice};
use gmueller::interaction::sampling::{RadialProfile, ScatterSampler, weight};
use gmueller::interaction::{Geometry, Intensity, Kernel, Partial, RoughSurface};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{GaussianPsd, KCorrelation};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector2, Vector3};
use num_complex::Complex;
use proptest::prelude::*;
use std::f64::consts::{PI, TAU};

// ------------------------------------------------------------------ helpers

/// erf by its Maclaurin series (|x| ≤ 2) and erfc by its continued fraction (x > 2)
/// (A&S 7.1.5 and 7.1.14), independent of the crate.
fn erfc(x: f64) -> f64 {
    if x < 0.0 {
        return 2.0 - erfc(-x);
    }
    if x <= 2.0 {
        // Σ (−1)ⁿ x^{2n+1} / (n! (2n+1)).
        let (mut term, mut sum, mut n) = (x, x, 0.0);
        while term.abs() > 1e-17 * sum.abs() {
            n += 1.0;
            term *= -x * x / n;
            sum += term / (2.0 * n + 1.0);
        }
        return 1.0 - 2.0 / PI.sqrt() * sum;
    }
    // erfc x = e^{−x²}/√π · 1/(x + (1/2)/(x + 1/(x + (3/2)/(x + …)))), evaluated backward.
    let mut t = x;
    for n in (1..200).rev() {
        t = x + 0.5 * n as f64 / t;
    }
    (-x * x).exp() / PI.sqrt() / t
}
fn erf(x: f64) -> f64 {
    1.0 - erfc(x)
}
/// The normal CDF.
fn phi_cdf(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

fn surface() -> Frame<f64> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap()
}
/// ŝ at incidence `deg` in the x–z plane (source on the −x side).
fn to_source(deg: f64) -> Vector3<f64> {
    let t = deg.to_radians();
    Vector3::new(-t.sin(), 0.0, t.cos())
}
fn k_of(lambda: f64) -> f64 {
    TAU / lambda
}
fn dir_of(u: Vector2<f64>) -> Vector3<f64> {
    Vector3::new(u.x, u.y, (1.0 - u.norm_squared()).max(0.0).sqrt())
}

/// ∫ pdf dω over the hemisphere in (φ, θ), with sin θ dθ dφ.
fn hemisphere_integral(pdf: &dyn Fn(&Vector3<f64>) -> f64) -> f64 {
    let mut outer = |phi: f64| {
        let (sp, cp) = phi.sin_cos();
        let mut inner = |th: f64| {
            let (st, ct) = th.sin_cos();
            pdf(&Vector3::new(st * cp, st * sp, ct)) * st
        };
        integrate(&mut inner, 0.0, PI / 2.0, 16, 1e-11)
    };
    integrate(&mut outer, 0.0, TAU, 48, 1e-10)
}

/// The test's cases: (label, sampler, scale of the lobe in u for binning).
fn gaussian_case(deg: f64, ell: f64, w_min: f64, lambda: f64) -> ScatterSampler<f64> {
    let psd = GaussianPsd::<f64, 2>::isotropic(0.01, ell).unwrap();
    ScatterSampler::gaussian(&psd, &surface(), &to_source(deg), k_of(lambda), w_min).unwrap()
}
fn k_case(deg: f64, t: f64, gamma: f64, w_min: f64, lambda: f64) -> ScatterSampler<f64> {
    let psd = KCorrelation::<f64, 2>::new(1e-4, t, gamma).unwrap();
    ScatterSampler::k_correlation(&psd, &surface(), &to_source(deg), k_of(lambda), w_min).unwrap()
}

// ------------------------------------------------------------------ the quadrature oracle

/// The oracle's rules and its adaptive integrator against closed forms: the 2- and 3-point rules
/// (nodes ±1/√3; 0, ±√(3/5); weights 1; 8/9, 5/9), the exactness of the n-point rule for
/// polynomials of degree ≤ 2n − 1 (∫₋₁¹ xᵏ = 2/(k+1) for even k, 0 for odd), and `integrate` on
/// smooth, peaked and endpoint-singular integrands with known integrals.
#[test]
fn quadrature_oracle_matches_closed_forms() {
    let t = Tol::new(1e-15, 1e-15);
    let g2 = gauss_legendre(2);
    let mut x2 = g2.nodes.clone();
    x2.sort_by(f64::total_cmp);
    assert_close("G2 node", x2[0], -1.0 / 3f64.sqrt(), t);
    assert_close("G2 node", x2[1], 1.0 / 3f64.sqrt(), t);
    for w in &g2.weights {
        assert_close("G2 weight", *w, 1.0, t);
    }
    let g3 = gauss_legendre(3);
    let mut nw: Vec<(f64, f64)> = g3.nodes.iter().copied().zip(g3.weights.clone()).collect();
    nw.sort_by(|a, b| a.0.total_cmp(&b.0));
    let r = (3.0f64 / 5.0).sqrt();
    for ((x, w), (xe, we)) in nw
        .iter()
        .zip([(-r, 5.0 / 9.0), (0.0, 8.0 / 9.0), (r, 5.0 / 9.0)])
    {
        assert_close("G3 node", *x, xe, t);
        assert_close("G3 weight", *w, we, t);
    }
    for n in [8usize, 12] {
        let g = gauss_legendre(n);
        assert_eq!(g.nodes.len(), n);
        for k in 0..2 * n {
            let q: f64 = g
                .nodes
                .iter()
                .zip(&g.weights)
                .map(|(x, w)| w * x.powi(k as i32))
                .sum();
            let exact = if k % 2 == 0 {
                2.0 / (k as f64 + 1.0)
            } else {
                0.0
            };
            assert_close(&format!("G{n} ∫x^{k}"), q, exact, Tol::new(2e-15, 2e-15));
        }
        // Degree 2n is not integrated exactly: the remainder is the classical
        // ∫f − Q = 2^{2n+1} (n!)⁴ / ((2n+1) ((2n)!)³) f^{(2n)}, with f^{(2n)} = (2n)! for x^{2n}.
        let q: f64 = g
            .nodes
            .iter()
            .zip(&g.weights)
            .map(|(x, w)| w * x.powi(2 * n as i32))
            .sum();
        let fact = |m: usize| (1..=m).map(|i| i as f64).product::<f64>();
        let remainder = 2f64.powi(2 * n as i32 + 1) * fact(n).powi(4)
            / ((2 * n + 1) as f64 * fact(2 * n).powi(2));
        assert_close(
            &format!("G{n} remainder at degree 2n"),
            2.0 / (2.0 * n as f64 + 1.0) - q,
            remainder,
            Tol::new(0.0, 1e-8),
        );
    }
    /// (label, integrand, a, b, ∫ₐᵇ f).
    type Case = (&'static str, fn(f64) -> f64, f64, f64, f64);
    let cases: [Case; 8] = [
        ("x^29 on [0, 1]", |x| x.powi(29), 0.0, 1.0, 1.0 / 30.0),
        ("e^x on [0, 3]", f64::exp, 0.0, 3.0, 3f64.exp() - 1.0),
        ("sin on [0, π]", f64::sin, 0.0, PI, 2.0),
        (
            "1/(1+x²) on [0, 1]",
            |x| 1.0 / (1.0 + x * x),
            0.0,
            1.0,
            PI / 4.0,
        ),
        // ∫₋₁₀¹⁰ e^{−x²/2} = √(2π) erf(10/√2), erfc(10/√2) ≈ 1.5e-23: √(2π) to f64.
        (
            "Gaussian on [−10, 10]",
            |x| (-0.5 * x * x).exp(),
            -10.0,
            10.0,
            TAU.sqrt(),
        ),
        // A narrow Gaussian (σ = 0.01) off-centre: adaptivity.
        (
            "narrow Gaussian",
            |x| (-0.5 * ((x - 0.3) / 0.01).powi(2)).exp(),
            0.0,
            1.0,
            0.01 * TAU.sqrt(),
        ),
        ("√x on [0, 1]", f64::sqrt, 0.0, 1.0, 2.0 / 3.0),
        ("x ln x on [0, 1]", |x| x * x.ln(), 0.0, 1.0, -0.25),
    ];
    for (what, f, a, b, exact) in cases {
        let mut g = |x: f64| f(x);
        assert_close(
            what,
            integrate(&mut g, a, b, 4, 1e-14),
            exact,
            Tol::new(1e-13, 1e-13),
        );
    }
}

// ------------------------------------------------------------------ erf reference values

#[test]
fn test_erf_matches_reference_values() {
    // A&S Table 7.1 (10 printed digits); 16-digit values as tabulated by the DLMF §7 software
    // (cross-checked with glibc's erf/erfc, < 1 ulp).
    let tol = Tol::new(1e-15, 2e-14);
    assert_close("erf(0.5)", erf(0.5), 0.5204998778130465, tol);
    assert_close("erf(1)", erf(1.0), 0.8427007929497149, tol);
    assert_close("erf(2)", erf(2.0), 0.9953222650189527, tol);
    assert_close("erfc(0.1)", erfc(0.1), 0.8875370839817152, tol);
    assert_close(
        "erfc(3)",
        erfc(3.0),
        2.209049699858544e-05,
        Tol::new(0.0, 2e-14),
    );
    assert_close(
        "erfc(5)",
        erfc(5.0),
        1.5374597944280351e-12,
        Tol::new(0.0, 2e-14),
    );
}

// ------------------------------------------------------------------ truncated masses

/// m = ∫ φ_{σ₁}(x − c₁) [Φ((√(1−x²) − c₂)/σ₂) − Φ((−√(1−x²) − c₂)/σ₂)] dx in the principal-axes
/// frame, x = sin t (removing the √ endpoint singularity).
fn cartesian_gaussian_mass(cov_u: Matrix2<f64>, c: Vector2<f64>) -> f64 {
    let (a, b, d) = (cov_u[(0, 0)], cov_u[(0, 1)], cov_u[(1, 1)]);
    let th = 0.5 * (2.0 * b).atan2(a - d);
    let (s, co) = th.sin_cos();
    // Eigenvalues along e₁ = (cos θ, sin θ), e₂ = (−sin θ, cos θ).
    let l1 = a * co * co + 2.0 * b * s * co + d * s * s;
    let l2 = a * s * s - 2.0 * b * s * co + d * co * co;
    let (s1, s2) = (l1.sqrt(), l2.sqrt());
    let (c1, c2) = (co * c.x + s * c.y, -s * c.x + co * c.y);
    let mut f = |t: f64| {
        let (x, h) = (t.sin(), t.cos());
        let px = (-0.5 * ((x - c1) / s1).powi(2)).exp() / (s1 * TAU.sqrt());
        h * px * (phi_cdf((h - c2) / s2) - phi_cdf((-h - c2) / s2))
    };
    integrate(&mut f, -PI / 2.0, PI / 2.0, 64, 1e-15)
}

#[test]
fn gaussian_truncated_mass_matches_cartesian_erf_quadrature_and_monte_carlo() {
    let k = k_of(0.5);
    for (deg, spectral, w_min) in [
        (0.0, Matrix2::new(0.25, 0.0, 0.0, 0.25), 1.0),
        (45.0, Matrix2::new(4.0, 1.5, 1.5, 2.0), 0.3),
        (80.0, Matrix2::new(0.25, 0.0, 0.0, 0.25), 0.2),
        (80.0, Matrix2::new(1.0, -0.4, -0.4, 0.5), 2.0),
    ] {
        let psd = GaussianPsd::from_spectral_shape(1e-4, Gaussian::new(spectral).unwrap()).unwrap();
        let sampler =
            ScatterSampler::gaussian(&psd, &surface(), &to_source(deg), k, w_min).unwrap();
        let (_, lobe) = sampler.components().next().unwrap();
        // The lobe, rebuilt here from the module formula: covariance (C_p + I/w²)/k², c = −ŝ_t.
        let cov_u = (spectral + Matrix2::identity() / (w_min * w_min)) / (k * k);
        let c = Vector2::new(-to_source(deg).x, -to_source(deg).y);
        let l = lobe.whitening();
        common::assert_all_close(
            "L Lᵀ",
            (l * l.transpose()).iter().copied(),
            cov_u.iter().copied(),
            Tol::new(1e-15, 1e-12),
        );
        let m_ref = cartesian_gaussian_mass(cov_u, c);
        assert_close(
            &format!("mass θ_i = {deg}"),
            lobe.truncated_mass(),
            m_ref,
            Tol::new(1e-14, 1e-12),
        );
        // Monte Carlo: the fraction of untruncated draws (Box–Muller) inside the disk.
        let mut rng = SplitMix64(7 + deg as u64);
        let n = 400_000;
        let chol = cov_u.cholesky().unwrap().l();
        let mut inside = 0usize;
        for _ in 0..n / 2 {
            let (u1, u2) = (1.0 - rng.unit(), rng.unit());
            let r = (-2.0 * u1.ln()).sqrt();
            let (s, co) = (TAU * u2).sin_cos();
            for z in [Vector2::new(r * co, r * s), Vector2::new(-r * s, r * co)] {
                if (c + chol * z).norm_squared() < 1.0 {
                    inside += 1;
                }
            }
        }
        let est = inside as f64 / n as f64;
        let se = (m_ref * (1.0 - m_ref) / n as f64).sqrt();
        assert!(
            (est - m_ref).abs() <= 5.0 * se + 1e-12,
            "MC mass {est} vs {m_ref} (5σ = {})",
            5.0 * se
        );
    }
}

#[test]
fn k_correlation_truncated_mass_matches_2d_quadrature() {
    for (deg, t, gamma, lambda) in [
        (0.0, 4.0, 2.0, 0.5),
        (45.0, 1.0, 1.5, 0.5),
        (80.0, 0.3, 3.0, 0.6),
    ] {
        let k = k_of(lambda);
        let sampler = k_case(deg, t, gamma, 1.0, lambda);
        let (w, lobe) = sampler.components().next().unwrap();
        assert_eq!(w, 0.5);
        assert!(matches!(lobe.profile(), RadialProfile::Power { .. }));
        // q_K(u) = k²T (γ−1)/(2π) (1 + k²T|u − c|²)^{−(γ+1)/2}, integrated over the disk in polar
        // coordinates about the disk's centre.
        let s = k * k * t;
        let c = Vector2::new(-to_source(deg).x, -to_source(deg).y);
        let q = |u: Vector2<f64>| {
            s * (gamma - 1.0) / TAU * (1.0 + s * (u - c).norm_squared()).powf(-(gamma + 1.0) / 2.0)
        };
        let mut outer = |phi: f64| {
            let (sp, cp) = phi.sin_cos();
            let mut inner = |r: f64| q(Vector2::new(r * cp, r * sp)) * r;
            integrate(&mut inner, 0.0, 1.0, 32, 1e-14)
        };
        let m_ref = integrate(&mut outer, 0.0, TAU, 64, 1e-13);
        assert_close(
            &format!("K mass θ_i = {deg}"),
            lobe.truncated_mass(),
            m_ref,
            Tol::new(1e-12, 1e-10),
        );
    }
}

// ------------------------------------------------------------------ normalisation

#[test]
fn pdf_integrates_to_one_over_the_hemisphere() {
    let mut cases: Vec<(String, ScatterSampler<f64>)> = Vec::new();
    for deg in [0.0, 45.0, 80.0] {
        for w_min in [1.0, 0.2] {
            cases.push((
                format!("gauss θ={deg} w={w_min}"),
                gaussian_case(deg, 2.0, w_min, 0.5),
            ));
        }
        cases.push((format!("K θ={deg}"), k_case(deg, 1.0, 2.0, 0.5, 0.5)));
    }
    for (label, sampler) in &cases {
        let total = hemisphere_integral(&|d| sampler.pdf(d));
        assert_close(label, total, 1.0, Tol::new(1e-7, 1e-7));
    }
}

// ------------------------------------------------------------------ chi-square

/// Pearson's statistic (bins of expected count < 5 pooled) and the 99.9 % quantile of χ²
/// (Wilson & Hilferty): the kit's.
use gmueller::verify::chi2::{chi_square, chi2_quantile_999};

/// Bins: rings at radii `scale·{½, 1, 2, 4}` about c (the last ring extends to the disk edge) ×
/// 8 sectors. Returns the bin of `u`.
const RINGS: [f64; 4] = [0.5, 1.0, 2.0, 4.0];
const SECTORS: usize = 8;
fn bin_of(u: Vector2<f64>, c: Vector2<f64>, scale: f64) -> usize {
    let d = u - c;
    let r = d.norm() / scale;
    let ring = RINGS.iter().filter(|&&e| r >= e).count();
    let a = d.y.atan2(d.x).rem_euclid(TAU);
    let sector = ((a / TAU * SECTORS as f64) as usize).min(SECTORS - 1);
    ring * SECTORS + sector
}

/// Expected probabilities of the bins under a density per *solid angle* `pdf_omega`, integrated
/// over each bin in the disk as ∫ `pdf_ω(r̂(u)) / cos θ_o d²u` (J1), in polar coordinates about c.
fn bin_probabilities(
    pdf_omega: &dyn Fn(&Vector3<f64>) -> f64,
    c: Vector2<f64>,
    scale: f64,
    tol: f64,
) -> Vec<f64> {
    let inside = 1.0 - c.norm_squared();
    let edge = |a: f64| {
        let e = Vector2::new(a.cos(), a.sin());
        let b = c.dot(&e);
        -b + (b * b + inside).sqrt()
    };
    let mut probs = vec![0.0; (RINGS.len() + 1) * SECTORS];
    for ring in 0..=RINGS.len() {
        let r_lo = if ring == 0 {
            0.0
        } else {
            RINGS[ring - 1] * scale
        };
        let r_hi = if ring == RINGS.len() {
            f64::INFINITY
        } else {
            RINGS[ring] * scale
        };
        for sector in 0..SECTORS {
            let a0 = TAU * sector as f64 / SECTORS as f64;
            let mut outer = |a: f64| {
                let hi = r_hi.min(edge(a));
                if hi <= r_lo {
                    return 0.0;
                }
                let e = Vector2::new(a.cos(), a.sin());
                // r = hi − (hi − r_lo) t²: removes the 1/√(hi − r) of 1/cos θ_o at the disk edge
                // (only a wrong pdf lacking the cos θ_o factor has it; harmless otherwise).
                let span = hi - r_lo;
                let mut inner = |t: f64| {
                    let r = hi - span * t * t;
                    let d = dir_of(c + e * r);
                    if d.z <= 0.0 {
                        0.0
                    } else {
                        pdf_omega(&d) / d.z * r * 2.0 * span * t
                    }
                };
                integrate(&mut inner, 0.0, 1.0, 8, 0.1 * tol)
            };
            probs[ring * SECTORS + sector] =
                integrate(&mut outer, a0, a0 + TAU / SECTORS as f64, 8, tol);
        }
    }
    probs
}

fn draw_counts(
    sampler: &ScatterSampler<f64>,
    c: Vector2<f64>,
    scale: f64,
    n: usize,
    seed: u64,
) -> Vec<usize> {
    let mut rng = SplitMix64(seed);
    let mut counts = vec![0usize; (RINGS.len() + 1) * SECTORS];
    for _ in 0..n {
        let s = sampler.sample([rng.unit(), rng.unit()]);
        assert!(s.direction.z > 0.0 && s.pdf > 0.0);
        counts[bin_of(Vector2::new(s.direction.x, s.direction.y), c, scale)] += 1;
    }
    counts
}

struct ChiCase {
    label: &'static str,
    sampler: ScatterSampler<f64>,
    deg: f64,
    scale: f64,
}

fn chi_cases() -> Vec<ChiCase> {
    vec![
        ChiCase {
            label: "gauss 30°",
            sampler: gaussian_case(30.0, 2.0, 1.0, 0.5),
            deg: 30.0,
            scale: 0.09,
        },
        ChiCase {
            label: "K 45°",
            sampler: k_case(45.0, 1.0, 2.0, 1.0, 0.5),
            deg: 45.0,
            scale: 0.05,
        },
        ChiCase {
            label: "gauss grazing 80°",
            sampler: gaussian_case(80.0, 1.0, 0.15, 0.5),
            deg: 80.0,
            scale: 0.3,
        },
        ChiCase {
            label: "K grazing 80°",
            sampler: k_case(80.0, 0.5, 1.5, 0.3, 0.5),
            deg: 80.0,
            scale: 0.1,
        },
    ]
}

#[test]
fn chi_square_sample_draws_from_pdf() {
    let n = 20_000;
    for (i, case) in chi_cases().iter().enumerate() {
        let c = Vector2::new(-to_source(case.deg).x, -to_source(case.deg).y);
        let probs = bin_probabilities(&|d| case.sampler.pdf(d), c, case.scale, 1e-11);
        let total: f64 = probs.iter().sum();
        assert_close(case.label, total, 1.0, Tol::new(1e-7, 1e-7));
        let counts = draw_counts(&case.sampler, c, case.scale, n, 1234 + i as u64);
        let (chi2, dof) = chi_square(&counts, &probs, n);
        let q = chi2_quantile_999(dof);
        eprintln!(
            "{}: χ² = {chi2:.1}, dof {dof}, 99.9 % quantile {q:.1}",
            case.label
        );
        assert!(dof >= 10, "{}: too few populated bins ({dof})", case.label);
        assert!(
            chi2 < q,
            "{}: χ² = {chi2:.1} ≥ {q:.1} (dof {dof})",
            case.label
        );
    }
}

/// The authors' bug class: a pdf that disagrees with its sampler. Forgetting the `cos θ_o` Jacobian
/// (using the disk density as if per solid angle) or the truncation mass must fail the test.
#[test]
fn chi_square_rejects_pdfs_missing_a_jacobian_or_the_truncation_mass() {
    let n = 20_000;
    let case = &chi_cases()[2]; // grazing, wide: cos θ_o varies and m is well below 1
    let c = Vector2::new(-to_source(case.deg).x, -to_source(case.deg).y);
    let counts = draw_counts(&case.sampler, c, case.scale, n, 99);
    let (_, lobe) = case.sampler.components().next().unwrap();
    let m = lobe.truncated_mass();
    assert!(m < 0.9, "case must truncate noticeably (m = {m})");
    let no_cos = |d: &Vector3<f64>| case.sampler.disk_pdf(&Vector2::new(d.x, d.y));
    let no_mass = |d: &Vector3<f64>| case.sampler.pdf(d) * m;
    for (what, wrong) in [
        ("missing cos θ_o", &no_cos as &dyn Fn(&Vector3<f64>) -> f64),
        ("missing truncation mass", &no_mass),
    ] {
        // Loose tolerance: a wrong pdf only has to be told apart, and 1/cos θ_o makes the
        // integrand noisy at the disk edge.
        let probs = bin_probabilities(wrong, c, case.scale, 1e-6);
        let (chi2, dof) = chi_square(&counts, &probs, n);
        let q = chi2_quantile_999(dof);
        eprintln!("{what}: χ² = {chi2:.1}, dof {dof}, 99.9 % quantile {q:.1}");
        assert!(chi2 > 10.0 * q, "{what}: χ² = {chi2:.1} not ≫ {q:.1}");
    }
}

// ------------------------------------------------------------------ pdf agreement, weights

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn prop_sample_pdf_equals_pdf_of_direction(
        deg in 0.0..85.0f64,
        log_ell in -1.0..1.5f64,
        w_min in 0.1..5.0f64,
        u0 in 0.0..1.0f64,
        u1 in 0.0..1.0f64,
        kind in 0usize..2,
    ) {
        let sampler = if kind == 0 {
            gaussian_case(deg, 10f64.powf(log_ell), w_min, 0.5)
        } else {
            k_case(deg, 10f64.powf(log_ell), 1.2 + w_min, w_min, 0.5)
        };
        let s = sampler.sample([u0, u1]);
        prop_assert!((s.direction.norm() - 1.0).abs() < 1e-12);
        prop_assert!(s.direction.z > 0.0 && s.pdf > 0.0 && s.pdf.is_finite());
        let p = sampler.pdf(&s.direction);
        prop_assert!((p - s.pdf).abs() <= 1e-12 * p, "{p} vs {}", s.pdf);
        // J1 by hand: pdf per solid angle = disk density × cos θ_o.
        let pd = sampler.disk_pdf(&Vector2::new(s.direction.x, s.direction.y)) * s.direction.z;
        prop_assert!((pd - p).abs() <= 1e-12 * p);
        // The first uniform moves ψ monotonically within a panel; nothing below the horizon.
        prop_assert_eq!(sampler.pdf(&Vector3::new(0.3, 0.1, -0.2)), 0.0);
    }
}

#[test]
fn f32_sampler_agrees_with_f64() {
    let psd64 = GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap();
    let psd32 = GaussianPsd::<f32, 2>::isotropic(0.01, 2.0).unwrap();
    let s32 = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let src = to_source(40.0);
    let a = ScatterSampler::gaussian(&psd64, &surface(), &src, k_of(0.5), 0.7).unwrap();
    let b = ScatterSampler::gaussian(&psd32, &s32, &src.map(|x| x as f32), k_of(0.5) as f32, 0.7)
        .unwrap();
    let mut rng = SplitMix64(5);
    for _ in 0..500 {
        let u = [rng.unit(), rng.unit()];
        let x = a.sample(u);
        let y = b.sample([u[0] as f32, u[1] as f32]);
        assert!(y.pdf > 0.0 && y.direction.z > 0.0);
        for i in 0..3 {
            assert_close(
                "direction",
                f64::from(y.direction[i]),
                x.direction[i],
                Tol::new(2e-4, 1e-4),
            );
        }
        assert_close(
            "pdf",
            f64::from(b.pdf(&y.direction)),
            f64::from(y.pdf),
            Tol::new(0.0, 1e-6),
        );
        let p64 = a.pdf(&y.direction.map(f64::from));
        assert_close(
            "pdf f32 vs f64",
            f64::from(y.pdf),
            p64,
            Tol::new(1e-6, 2e-4),
        );
    }
}

fn glass_material<P>(psd: P) -> RoughSurface<P, FresnelReflection<f64>, RayleighRice<f64>> {
    let glass = Complex::new(1.5, 0.0);
    RoughSurface {
        psd,
        specular: FresnelReflection::new(glass).unwrap(),
        scatter: RayleighRice::new(glass).unwrap(),
    }
}

fn packet(deg: f64, width: f64, lambda: f64) -> WavePacket<f64> {
    let travel = -to_source(deg);
    let frame = Frame::sp(travel, Vector3::z()).unwrap();
    WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(width).unwrap(),
        frame,
        lambda,
    )
    .unwrap()
}

#[test]
fn weights_equal_value_over_pdf() {
    let psd = GaussianPsd::<f64, 2>::isotropic(0.02, 1.0).unwrap();
    let material = glass_material(psd);
    let kernel = Kernel::<Intensity, Partial>::default();
    let sampler =
        ScatterSampler::gaussian(&psd, &surface(), &to_source(35.0), k_of(0.5), 0.5).unwrap();
    let pk = packet(35.0, 1.5, 0.5);
    let mut rng = SplitMix64(11);
    for _ in 0..200 {
        let w = sampler
            .sample_weighted(&kernel, &material, &pk, [rng.unit(), rng.unit()])
            .unwrap();
        let g = Geometry::for_packet(&pk, &surface(), w.sample.direction).unwrap();
        let value = kernel.evaluate(&material, &pk, &g).total();
        let pdf = sampler.pdf(&w.sample.direction);
        assert_close(
            "weight",
            w.weight.total(),
            value / pdf,
            Tol::new(1e-300, 1e-12),
        );
        assert_close(
            "weight()",
            weight(value, pdf),
            value / pdf,
            Tol::new(1e-300, 1e-14),
        );
    }
}

/// ∫ L₀ dω by importance sampling (N = 20 000) against nested quadrature of the kernel, for a
/// packet wider than `w_min` and one narrower (still unbiased, only noisier): within 5 standard
/// errors of the Monte Carlo estimate.
#[test]
fn importance_sampled_estimate_matches_quadrature() {
    let psd = GaussianPsd::<f64, 2>::isotropic(0.02, 1.0).unwrap();
    let material = glass_material(psd);
    let kernel = Kernel::<Intensity, Partial>::default();
    let (deg, lambda) = (40.0, 0.5);
    let sampler =
        ScatterSampler::gaussian(&psd, &surface(), &to_source(deg), k_of(lambda), 0.6).unwrap();
    for width in [2.0, 0.4] {
        let pk = packet(deg, width, lambda);
        let value = |d: &Vector3<f64>| {
            Geometry::for_packet(&pk, &surface(), *d)
                .map_or(0.0, |g| kernel.evaluate(&material, &pk, &g).total())
        };
        let reference = hemisphere_integral(&value);
        let mut rng = SplitMix64(2024);
        let n = 20_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let w = sampler
                .sample_weighted(&kernel, &material, &pk, [rng.unit(), rng.unit()])
                .unwrap()
                .weight
                .total();
            sum += w;
            sum2 += w * w;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        assert!(
            (mean - reference).abs() <= 5.0 * se,
            "w = {width}: MC {mean:e} ± {se:e} vs quadrature {reference:e}"
        );
        assert!(
            se < 0.05 * reference,
            "w = {width}: relative error {:.3}",
            se / reference
        );
    }
}

#[test]
fn constructors_validate_their_inputs() {
    let psd = GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap();
    let s = surface();
    assert!(ScatterSampler::gaussian(&psd, &s, &Vector3::new(0.0, 0.3, -1.0), 10.0, 1.0).is_err());
    assert!(ScatterSampler::gaussian(&psd, &s, &to_source(10.0), 0.0, 1.0).is_err());
    assert!(ScatterSampler::gaussian(&psd, &s, &to_source(10.0), 10.0, 0.0).is_err());
    assert!(ScatterSampler::gaussian(&psd, &s, &Vector3::zeros(), 10.0, 1.0).is_err());
    // w_min = ∞: the plane-wave lobe C_p/k² only.
    let pw = ScatterSampler::gaussian(&psd, &s, &to_source(10.0), 10.0, f64::INFINITY).unwrap();
    let (_, lobe) = pw.components().next().unwrap();
    let l = lobe.whitening();
    assert_close(
        "plane-wave lobe",
        (l * l.transpose())[(0, 0)],
        0.25 / 100.0,
        Tol::new(1e-16, 1e-12),
    );
}
