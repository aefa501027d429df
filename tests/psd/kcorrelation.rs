//! Verifies the blur of the K-correlation PSD — `blur` and `normalized_blur` of `Adaptive`,
//! `GaussHermite` and the `mixture_fit` + `ClosedForm` path — against two independent test-side
//! oracles that agree with each other to ≤ 1e-10: a real-space Hankel transform of the
//! Matérn autocorrelation (Bessel K, J₀) and a radial quadrature in spectral space (Bessel I₀).
//! Neither shares an algorithm or an integrand with the crate (its adaptive reference is a nested
//! 2-D Gauss–Kronrod of `p(h − L u)`; its mixture fit a scale mixture of Gaussians in ζ).
//!
//! # The oracles (derivation, n = 2, isotropic blur `Σ = s² I`)
//! Conventions (`src/psd/mod.rs`): unitary `p = F{R}`, `F{f}(ζ) = (2π)^{−1} ∫ f(x) e^{−iζ·x} d²x`,
//! blur `(p * g^Σ)(h) = (2π)^{−1} ∫ p(ζ) g^Σ(h − ζ) d²ζ`, `g^Σ` unnormalised, and
//! `normalized_blur = |Σ|^{−1/2} (p * g^Σ) = ∫ p(ζ) 𝒩_Σ(h − ζ) d²ζ`. The crate's PSD
//! (`src/psd/kcorrelation.rs`) is
//! ```text
//! p(ζ) = σ² (γ − 1) T (1 + T|ζ|²)^{−ν},   ν = (γ + 1)/2      (∫ p d²ζ = 2π σ²)
//! ```
//! **Real space.** With `∫₀^∞ x J₀(bx) (x² + a²)^{−ν} dx = (b/a)^{ν−1} K_{ν−1}(ab) / (2^{ν−1} Γ(ν))`
//! (Gradshteyn–Ryzhik 6.565.4, μ = 0), `R(r) = ∫₀^∞ p(ρ) J₀(ρ r) ρ dρ` is the Matérn function
//! ```text
//! R(r) = σ² 2^{1−α}/Γ(α) · u^α K_α(u),   u = r/√T,   α = ν − 1 = (γ − 1)/2    (R(0) = σ²)
//! ```
//! (α = ½: `σ² e^{−u}`; α = 3/2: `σ² (1 + u) e^{−u}` — both checked). `g^Σ = F{φ}` with
//! `φ(x) = |Σ|^{1/2} exp(−½ xᵀΣx)`, and `F{f}·…` turns products into the crate's convolution,
//! `p * g^Σ = F{R φ}`; for radial functions the 2-D transform is a Hankel transform:
//! ```text
//! normalized_blur(h) = ∫₀^∞ R(r) e^{−s² r²/2} J₀(h r) r dr,     blur = s² · normalized_blur
//! ```
//! evaluated by composite 20-point Gauss–Legendre on panels no wider than `π/h`, `√T/2` and
//! `1/s`, graded geometrically toward r = 0 (where `R` has its non-analytic `r^{2α}` term that
//! makes the tail of p), up to where `R e^{−s²r²/2} < e^{−40} R(0)`; `K_α` by the trapezoid rule on
//! `K_α(u) = ∫₀^∞ e^{−u cosh t} cosh(α t) dt` (A&S 9.6.24), `J₀` by the trapezoid rule on
//! `J₀(x) = (2π)^{−1} ∫₀^{2π} cos(x sin θ) dθ` (exact but for `J_{N}(x)` with N > x + 40
//! points), `Γ(α)` by the trapezoid rule on `∫ exp(α y − e^y) dy` (all exponentially convergent).
//!
//! **Spectral space.** In polar coordinates around h, with `I₀(z) = (2π)^{−1} ∫ e^{z cos θ} dθ`,
//! ```text
//! normalized_blur(h) = s^{−2} ∫₀^∞ p(ρ) ρ e^{−(ρ − |h|)²/(2s²)} I₀e(|h| ρ / s²) dρ,   I₀e(z) = e^{−z} I₀(z)
//! ```
//! by composite Gauss–Legendre on panels no wider than `s/2` and `1/(4√T)` over
//! `[0, |h| + 15 s]`; `I₀e` by its power series (z ≤ 25) and asymptotic series (z > 25, terms
//! below e^{−2z}). `J₀`, `I₀`, `K_α` and `Γ` are checked against reference values
//! (`oracle_special_functions`).
//!
//! # Oracle accuracy and tolerances
//! The two oracles agree within 1e-10 relative in every case (asserted; measured ≤ 1e-12 but
//! for 3.6e-11 at γ = 4, h√T = 10, narrow blur, where the Hankel integral cancels to ~1e-5 of
//! its terms), so the oracle error is taken as `ORACLE = 1e-10` relative. The crate's methods are held to their
//! documented accuracy plus that: `Adaptive(tol)` relative `tol + ORACLE`; the mixture fit
//! `|error| ≤ err · p(0) · |Σ|^{1/2}` (blur; `err · p(0)` for `normalized_blur`, its documented
//! bound with the fit's measured uniform error `err`) plus `ORACLE`; Gauss–Hermite, which has no
//! a-priori bound and is documented as accurate for blurs narrow against the PSD's scale
//! `1/√T`, is asserted within 1e-6 relative for `s√T ≤ 0.05` (order 64) and only printed
//! otherwise.

use crate::common;

use common::gauss_legendre;
use gmueller::gaussian::Gaussian;
use gmueller::psd::{Adaptive, BlurMethod, ClosedForm, GaussHermite, KCorrelation};
use nalgebra::Vector2;

const TAU: f64 = std::f64::consts::TAU;
const PI: f64 = std::f64::consts::PI;

/// The oracles' relative accuracy (their mutual agreement is asserted below this).
const ORACLE: f64 = 1e-10;

// ------------------------------------------------------------------ special functions (test-side)

/// `Γ(α)`, α > 0, by the trapezoid rule on `∫ exp(α y − e^y) dy` (substitution t = e^y).
fn gamma(alpha: f64) -> f64 {
    let (a, b, h) = (-45.0 / alpha, 4.5, 0.02);
    let n = ((b - a) / h).ceil() as usize;
    let h = (b - a) / n as f64;
    (0..=n)
        .map(|i| {
            let y = a + h * i as f64;
            (alpha * y - y.exp()).exp()
        })
        .sum::<f64>()
        * h
}

/// `K_α(u)`, u > 0, by the trapezoid rule on `∫₀^∞ e^{−u cosh t} cosh(α t) dt` (even integrand:
/// the rule on `[0, t_max]` with half weight at 0), truncated past the integrand's maximum
/// (`u sinh t > α`) once a term falls below 1e-20 of the sum.
fn bessel_k(alpha: f64, u: f64) -> f64 {
    let h = 0.05_f64;
    let mut sum = 0.5 * (-u).exp();
    let mut t = h;
    loop {
        let term = (-u * t.cosh()).exp() * (alpha * t).cosh();
        sum += term;
        if u * t.sinh() > alpha && term < 1e-20 * sum {
            break;
        }
        t += h;
    }
    sum * h
}

/// `J₀(x)` by the trapezoid rule on `(2π)^{−1} ∫₀^{2π} cos(x sin θ) dθ` with N > |x| + 40 points
/// (the rule is exact but for the aliased `2 J_N(x)`, N even).
fn bessel_j0(x: f64) -> f64 {
    let n = 2 * ((x.abs() as usize) / 2 + 24);
    (0..n)
        .map(|j| (x * (TAU * j as f64 / n as f64).sin()).cos())
        .sum::<f64>()
        / n as f64
}

/// `e^{−z} I₀(z)`, z ≥ 0: power series for z ≤ 25, asymptotic series beyond.
fn bessel_i0e(z: f64) -> f64 {
    if z <= 25.0 {
        let q = z * z / 4.0;
        let (mut term, mut sum) = (1.0, 1.0);
        for k in 1..200 {
            term *= q / (k * k) as f64;
            sum += term;
            if term < 1e-18 * sum {
                break;
            }
        }
        sum * (-z).exp()
    } else {
        // I₀(z) ~ e^z/√(2πz) Σ ((2k−1)!!)² / (k! (8z)^k).
        let (mut term, mut sum) = (1.0, 1.0);
        for k in 1..60 {
            let next = term * ((2 * k - 1) as f64).powi(2) / (k as f64 * 8.0 * z);
            if next > term {
                break;
            }
            term = next;
            sum += term;
        }
        sum / (TAU * z).sqrt()
    }
}

// ------------------------------------------------------------------ the oracles

/// The K-correlation parameters, as plain numbers.
#[derive(Debug, Clone, Copy)]
struct Kc {
    sigma2: f64,
    t: f64,
    gamma: f64,
}

impl Kc {
    fn alpha(&self) -> f64 {
        0.5 * (self.gamma - 1.0)
    }
    /// `p(ρ)`, written from the formula (not the crate's).
    fn psd(&self, rho: f64) -> f64 {
        self.sigma2
            * (self.gamma - 1.0)
            * self.t
            * (1.0 + self.t * rho * rho).powf(-0.5 * (self.gamma + 1.0))
    }
    /// `R(r)` (Matérn), with `2^{1−α}/Γ(α)` precomputed by the caller.
    fn autocorrelation(&self, r: f64, norm: f64) -> f64 {
        if r == 0.0 {
            return self.sigma2;
        }
        let (a, u) = (self.alpha(), r / self.t.sqrt());
        self.sigma2 * norm * u.powf(a) * bessel_k(a, u)
    }
}

/// Composite Gauss–Legendre of `f` over the panels `breaks[i]..breaks[i+1]`.
fn panels(breaks: &[f64], f: &mut dyn FnMut(f64) -> f64) -> f64 {
    let (x, w) = gauss_legendre(20);
    breaks
        .windows(2)
        .map(|p| {
            let (mid, half) = (0.5 * (p[0] + p[1]), 0.5 * (p[1] - p[0]));
            x.iter()
                .zip(&w)
                .map(|(xi, wi)| wi * f(mid + half * xi))
                .sum::<f64>()
                * half
        })
        .sum()
}

/// Breakpoints of `[0, end]`: uniform panels of width ≤ `width`, the first one graded
/// geometrically toward 0 (40 halvings).
fn graded(end: f64, width: f64) -> Vec<f64> {
    let n = (end / width).ceil().max(1.0) as usize;
    let step = end / n as f64;
    let mut b: Vec<f64> = (0..40).rev().map(|j| step * 0.5f64.powi(j + 1)).collect();
    b.insert(0, 0.0);
    b.extend((1..=n).map(|i| step * i as f64));
    b
}

/// Real-space oracle: `∫₀^∞ R(r) e^{−s²r²/2} J₀(h r) r dr` (the normalised blur).
fn hankel_oracle(kc: &Kc, s: f64, h: f64) -> f64 {
    let a = kc.alpha();
    let norm = 2f64.powf(1.0 - a) / gamma(a);
    let rt = kc.t.sqrt();
    // R ≲ u^{α−½} e^{−u}: e^{−40} R(0) by u ≈ 45 + α ln u; the Gaussian by s r = √80.
    let end = (48.0 + 2.0 * a) * rt;
    let end = end.min(80f64.sqrt() / s);
    let mut width = (0.5 * rt).min(1.0 / s);
    if h > 0.0 {
        width = width.min(PI / h);
    }
    panels(&graded(end, width), &mut |r| {
        kc.autocorrelation(r, norm) * (-0.5 * s * s * r * r).exp() * bessel_j0(h * r) * r
    })
}

/// Spectral-space oracle: `s^{−2} ∫₀^∞ p(ρ) ρ e^{−(ρ−h)²/(2s²)} I₀e(hρ/s²) dρ`.
fn radial_oracle(kc: &Kc, s: f64, h: f64) -> f64 {
    let end = h + 15.0 * s;
    let width = (0.5 * s).min(0.25 / kc.t.sqrt());
    panels(&graded(end, width), &mut |rho| {
        let d = rho - h;
        kc.psd(rho) * rho * (-0.5 * d * d / (s * s)).exp() * bessel_i0e(h * rho / (s * s))
    }) / (s * s)
}

// ------------------------------------------------------------------ tests

/// The test-side special functions against reference values: `J₀` at 1, 5, 10 (A&S Table 9.1)
/// and 30, `e^{−x}I₀` at 1, 10 (Table 9.8), 25, 30 and 100, `K_{0.1}` at 0.5 and 3, `Γ(0.1)` (A&S
/// Table 6.1: `Γ(1.1) = 0.9513507699`) — the digits from mpmath 1.3.0 at 30 digits —, `Γ(½) = √π`,
/// `Γ(3/2) = √π/2`, and the Matérn `R` at α = ½, 3/2 against `e^{−u}`, `(1 + u) e^{−u}`.
#[test]
fn oracle_special_functions() {
    let close = |what: &str, a: f64, b: f64, tol: f64| {
        assert!((a - b).abs() <= tol * b.abs(), "{what}: {a:e} vs {b:e}");
    };
    for (x, j0) in [
        (1.0, 0.765197686557966551),
        (5.0, -0.177596771314338304),
        (10.0, -0.245935764451348335),
        (30.0, -0.0863679835810402113),
    ] {
        close("J₀", bessel_j0(x), j0, 1e-13);
    }
    for (x, i0e) in [
        (1.0, 0.465759607593640437),
        (10.0, 0.127833337163428607),
        (25.0, 0.0801967735474367084), // the last power-series point
        (30.0, 0.0731459464822372939),
        (100.0, 0.0399443792990966826),
    ] {
        close("I₀e", bessel_i0e(x), i0e, 1e-14);
    }
    close(
        "K_0.1(0.5)",
        bessel_k(0.1, 0.5),
        0.930086529131478535,
        1e-14,
    );
    close("K_0.1(3)", bessel_k(0.1, 3.0), 0.0347901322378918028, 1e-14);
    close("Γ(0.1)", gamma(0.1), 9.51350769866873129, 1e-13);
    close("Γ(½)", gamma(0.5), PI.sqrt(), 1e-13);
    close("Γ(3/2)", gamma(1.5), 0.5 * PI.sqrt(), 1e-13);
    for (gamma_k, closed) in [
        (2.0, (|u: f64| (-u).exp()) as fn(f64) -> f64),
        (4.0, |u: f64| (1.0 + u) * (-u).exp()),
    ] {
        let kc = Kc {
            sigma2: 1.0,
            t: 4.0,
            gamma: gamma_k,
        };
        let norm = 2f64.powf(1.0 - kc.alpha()) / gamma(kc.alpha());
        for u in [1e-6, 0.1, 1.0, 5.0, 30.0] {
            close(
                "Matérn R",
                kc.autocorrelation(u * 2.0, norm),
                closed(u),
                1e-12,
            );
        }
    }
}

/// The cases: γ ∈ {1.2, 2, 4}, T ∈ {0.25, 4}, blur width `s√T` ∈ {0.05, 0.5, 3} (narrow,
/// comparable, wide: high to low coherence), `h√T` ∈ {0, 1, 3, 10} (peak to tail).
fn cases() -> Vec<(Kc, f64, f64)> {
    let mut v = Vec::new();
    for gamma in [1.2, 2.0, 4.0] {
        for t in [0.25, 4.0] {
            for s_rel in [0.05, 0.5, 3.0] {
                for h_rel in [0.0, 1.0, 3.0, 10.0] {
                    let kc = Kc {
                        sigma2: 1e-4,
                        t,
                        gamma,
                    };
                    v.push((kc, s_rel / t.sqrt(), h_rel / t.sqrt()));
                }
            }
        }
    }
    v
}

/// The two oracles agree within `ORACLE` relative (the accuracy every tolerance below adds).
#[test]
fn oracles_agree() {
    let mut worst = 0.0_f64;
    for (kc, s, h) in cases() {
        let a = hankel_oracle(&kc, s, h);
        let b = radial_oracle(&kc, s, h);
        let d = (a - b).abs() / b;
        if d > 1e-12 {
            println!(
                "γ {} T {} s√T {:.2} h√T {:.1}: {d:.2e}",
                kc.gamma,
                kc.t,
                s * kc.t.sqrt(),
                h * kc.t.sqrt()
            );
        }
        worst = worst.max(d);
        assert!(
            d <= ORACLE,
            "γ {} T {} s {s} h {h}: Hankel {a:e} vs radial {b:e} (rel {d:e})",
            kc.gamma,
            kc.t
        );
    }
    println!("Hankel vs radial oracle: worst relative difference {worst:.2e}");
}

/// `Adaptive`, the mixture fit and Gauss–Hermite against the oracle, `blur` and
/// `normalized_blur`, f64 (tolerances in the module docs).
#[test]
fn kcorrelation_blur_against_oracle() {
    let adaptive = Adaptive::new(1e-9).unwrap();
    let gh = GaussHermite::new(64).unwrap();
    let mut table = Vec::new();
    for (kc, s, h) in cases() {
        let oracle = radial_oracle(&kc, s, h);
        let psd = KCorrelation::<f64, 2>::new(kc.sigma2, kc.t, kc.gamma).unwrap();
        let (mix, _, err) = psd.mixture_fit_to(1e-8).unwrap();
        let cov = Gaussian::isotropic(s).unwrap();
        let hv = Vector2::new(h * 0.6, -h * 0.8); // |h| = h, off the axes
        let det_half = s * s; // |Σ|^{1/2}
        let p0 = kc.psd(0.0);
        let what = format!(
            "γ {} T {} s√T {:.2} h√T {:.1}",
            kc.gamma,
            kc.t,
            s * kc.t.sqrt(),
            h * kc.t.sqrt()
        );
        // Adaptive: relative tol + ORACLE, both forms.
        let an = adaptive.normalized_blur(&psd, &cov, &hv);
        let ab = adaptive.blur(&psd, &cov, &hv);
        let rel_n = (an - oracle).abs() / oracle;
        let rel_b = (ab - oracle * det_half).abs() / (oracle * det_half);
        assert!(
            rel_n <= 1e-9 + ORACLE,
            "{what}: Adaptive normalized rel {rel_n:e}"
        );
        assert!(
            rel_b <= 1e-9 + ORACLE,
            "{what}: Adaptive blur rel {rel_b:e}"
        );
        // Mixture fit: absolute bound err·p(0)(·|Σ|^{1/2}) plus the oracle's error.
        let mn = ClosedForm.normalized_blur(&mix, &cov, &hv);
        let mb = ClosedForm.blur(&mix, &cov, &hv);
        let bound_n = err * p0 * (1.0 + 1e-6) + ORACLE * oracle;
        assert!(
            (mn - oracle).abs() <= bound_n,
            "{what}: mixture normalized |err| {:e} > {bound_n:e}",
            (mn - oracle).abs()
        );
        let bound_b = (err * p0 * (1.0 + 1e-6) + ORACLE * oracle) * det_half;
        assert!(
            (mb - oracle * det_half).abs() <= bound_b,
            "{what}: mixture blur |err| {:e} > {bound_b:e}",
            (mb - oracle * det_half).abs()
        );
        // Gauss–Hermite: asserted where documented accurate (narrow blur).
        let gn = gh.normalized_blur(&psd, &cov, &hv);
        let gb = gh.blur(&psd, &cov, &hv);
        let rel_g = (gn - oracle).abs() / oracle;
        let rel_gb = (gb - oracle * det_half).abs() / (oracle * det_half);
        if s * kc.t.sqrt() <= 0.05 {
            assert!(
                rel_g <= 1e-6 && rel_gb <= 1e-6,
                "{what}: Gauss–Hermite rel {rel_g:e} {rel_gb:e}"
            );
        }
        table.push((what, oracle, rel_n, (mn - oracle).abs() / oracle, rel_g));
    }
    println!(
        "case                              oracle        Adaptive   mixture    GH64   (relative errors)"
    );
    for (what, o, a, m, g) in table {
        println!("{what:<34} {o:.6e}  {a:.1e}  {m:.1e}  {g:.1e}");
    }
}

/// f32: `Adaptive` and the mixture fit against the f64 oracle within 1e-4 relative (narrow to
/// wide blurs, peak and tail; the mixture's own bound is far below that here).
#[test]
fn kcorrelation_blur_f32() {
    let adaptive = Adaptive::<f32>::new(1e-5).unwrap();
    for (kc, s, h) in cases().into_iter().step_by(5) {
        let oracle = radial_oracle(&kc, s, h);
        let psd =
            KCorrelation::<f32, 2>::new(kc.sigma2 as f32, kc.t as f32, kc.gamma as f32).unwrap();
        let (mix, _, err) = psd.mixture_fit_to(1e-6).unwrap();
        let cov = Gaussian::<f32, 2>::isotropic(s as f32).unwrap();
        let hv = Vector2::new((h * 0.6) as f32, (-h * 0.8) as f32);
        let what = format!("f32 γ {} T {} s {s:.3} h {h:.3}", kc.gamma, kc.t);
        let a = f64::from(adaptive.normalized_blur(&psd, &cov, &hv));
        assert!(
            (a - oracle).abs() <= 1e-4 * oracle,
            "{what}: Adaptive {a:e} vs {oracle:e}"
        );
        let m = f64::from(ClosedForm.normalized_blur(&mix, &cov, &hv));
        let bound = err * kc.psd(0.0) + 1e-4 * oracle;
        assert!(
            (m - oracle).abs() <= bound,
            "{what}: mixture {m:e} vs {oracle:e}"
        );
    }
}
