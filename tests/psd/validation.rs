//! Verifies that every PSD constructor (Gaussian, Gaussian mixture, smooth, K-correlation and its
//! ABC form and mixture fit, sinusoidal, rectangular and crossed gratings), in f32 and f64, either
//! rejects its parameters with an `Error` naming them or returns a PSD whose derived quantities
//! (variance, ∫p, peak p(0), spectral widths, order positions and efficiencies, blurs) are finite
//! — swept over parameters from the smallest subnormal to `T::MAX` — plus the named cases of each
//! check, the grating order cap (`Grating::MAX_ORDERS`, exact at its boundary), and blurs at huge
//! frequencies (0, not NaN).

use crate::common;

use common::{Tol, assert_close};
use gmueller::Error;
use gmueller::Real;
use gmueller::gaussian::Gaussian;
use gmueller::psd::{
    BlurMethod, ClosedForm, GaussHermite, GaussianMixturePsd, GaussianPsd, Grating, KCorrelation,
    OrderCutoff, Psd, Smooth,
};
use nalgebra::{Matrix2, SVector, Vector2};

/// Parameter magnitudes from the smallest subnormal to `T::MAX` (values beyond `T` become ∞ and
/// must be rejected as non-finite).
fn magnitudes<T: Real>() -> Vec<T> {
    let max = T::max_value().unwrap();
    let tiny = T::lit(if T::EPSILON.to_f64() > 1e-10 {
        1.4e-45
    } else {
        5e-324
    });
    let mut v = vec![T::zero(), tiny, max, max * T::lit(0.5)];
    for e in [
        -300, -200, -100, -40, -38, -30, -20, -10, -3, 0, 3, 10, 20, 30, 38, 100, 200, 300,
    ] {
        v.push(T::lit(10f64.powi(e)));
    }
    v.push(T::lit(0.7));
    v
}

/// Asserts the derived quantities of an accepted PSD: finite (and ≥ 0) variance, integral,
/// peak `p(0)`, feature width, values and normalised blurs at a few points.
fn check_psd<T: Real, P, const N: usize>(p: &P, what: &str)
where
    P: Psd<T, N>,
    ClosedForm: BlurMethod<T, N, P>,
{
    check_psd_with(p, &ClosedForm, what);
}

/// [`check_psd`] with the blur method `method`.
fn check_psd_with<T: Real, P, M, const N: usize>(p: &P, method: &M, what: &str)
where
    P: Psd<T, N>,
    M: BlurMethod<T, N, P>,
{
    let finite_nonneg = |x: T, name: &str| {
        assert!(x.is_finite() && x >= T::zero(), "{what}: {name} = {x:?}");
    };
    finite_nonneg(p.variance(), "variance");
    finite_nonneg(p.integral(), "∫p");
    let zero = SVector::<T, N>::zeros();
    finite_nonneg(p.value(&zero), "p(0)");
    if p.variance() > T::zero() && p.value(&zero) == T::zero() {
        // Only Dirac PSDs have no continuous peak.
        assert!(p.integral() > T::zero(), "{what}: ∫p = 0 for σ² > 0");
    }
    finite_nonneg(p.feature_width(), "feature width");
    let cov = Gaussian::<T, N>::isotropic(T::one()).unwrap();
    for s in [0.0, 1e-3, 1.0, 1e3, 1e30] {
        let mut h = zero;
        h[0] = T::lit(s);
        finite_nonneg(p.value(&h), "p(h)");
        finite_nonneg(method.normalized_blur(p, &cov, &h), "normalised blur");
        finite_nonneg(method.blur(p, &cov, &h), "blur");
    }
}

fn sweep<T: Real>() {
    let ty = std::any::type_name::<T>();
    let mags = magnitudes::<T>();
    let gh = GaussHermite::<T>::new(4).unwrap();
    let mut accepted = 0usize;
    for &a in &mags {
        for &b in &mags {
            let w = format!("{ty} ({:e}, {:e})", a.to_f64(), b.to_f64());
            if let Ok(p) = GaussianPsd::<T, 2>::isotropic(a, b) {
                check_psd(&p, &format!("isotropic {w}"));
                let sp = p.spectral_shape().covariance();
                assert!(
                    sp.iter().all(|x| x.is_finite()) && sp[(0, 0)] > T::zero(),
                    "{w}: {sp:?}"
                );
                accepted += 1;
            }
            if let Ok(p) = GaussianPsd::<T, 3>::from_scatmech(a, b) {
                check_psd(&p, &format!("scatmech {w}"));
            }
            if let Ok(g) = Gaussian::<T, 2>::isotropic(b) {
                if let Ok(p) = GaussianPsd::from_autocorrelation(a, &g) {
                    check_psd(&p, &format!("autocorrelation {w}"));
                }
                if let Ok(p) = GaussianPsd::from_spectral_shape(a, g) {
                    check_psd(&p, &format!("spectral shape {w}"));
                    if let Ok(m) = GaussianMixturePsd::new(vec![p, p, p]) {
                        check_psd(&m, &format!("mixture {w}"));
                    }
                }
            }
            if let Ok(s) = Smooth::new(a) {
                check_psd::<T, _, 2>(&s, &format!("smooth {w}"));
                check_psd::<T, _, 3>(&s, &format!("smooth 3-D {w}"));
            }
            for gamma in [1.5, 2.0, 3.5, 1e3, 1e30] {
                let wg = format!("K-correlation {w} γ = {gamma}");
                if let Ok(k) = KCorrelation::<T, 2>::new(a, b, T::lit(gamma)) {
                    check_psd_with(&k, &gh, &wg);
                    assert_eq!(k.peak_value(), k.value(&Vector2::zeros()), "{wg}");
                    if let Ok((mix, err)) = k.mixture_fit(8) {
                        check_psd(&mix, &format!("{wg} mixture fit"));
                        assert!(err.is_finite(), "{wg}: fit error {err}");
                    }
                    accepted += 1;
                }
                if let Ok(k) = KCorrelation::<T, 3>::new(a, b, T::lit(gamma)) {
                    check_psd_with(&k, &gh, &format!("{wg} (3-D)"));
                }
                if let Ok(k) = KCorrelation::<T, 2>::from_abc(a, b, T::lit(gamma)) {
                    check_psd_with(&k, &gh, &format!("ABC {w} C = {gamma}"));
                }
            }
            for max_frequency in [T::lit(10.0), T::lit(1e6), T::lit(f64::INFINITY)] {
                let cut = OrderCutoff {
                    max_frequency,
                    tail: T::lit(1e-6),
                };
                let dir = Vector2::new(b, T::one());
                let gratings = [
                    Grating::<T, 2>::sinusoidal(a, &dir, T::lit(1.3), cut),
                    Grating::<T, 2>::rectangular(a, &dir, T::lit(2.0), T::lit(0.3), cut),
                ];
                for g in gratings.into_iter().flatten() {
                    let wg = format!("grating {w} max_frequency {:e}", max_frequency.to_f64());
                    check_psd(&g, &wg);
                    assert!(g.orders().len() <= Grating::<T, 2>::MAX_ORDERS, "{wg}");
                    for (z, e) in g.orders() {
                        assert!(z.iter().all(|x| x.is_finite()), "{wg}: ζ = {z:?}");
                        assert!(e.is_finite() && *e > T::zero(), "{wg}: η = {e:?}");
                    }
                    let d = g.dropped_efficiency();
                    assert!(
                        d.is_finite() && d >= T::zero() && d <= T::one(),
                        "{wg}: {d:?}"
                    );
                    if let Ok(x) = Grating::crossed(&g, &g, T::zero()) {
                        check_psd(&x, &format!("crossed {wg}"));
                        assert!(
                            x.orders()
                                .iter()
                                .all(|(z, _)| z.iter().all(|v| v.is_finite()))
                        );
                    }
                }
            }
        }
    }
    assert!(
        accepted > 100,
        "{ty}: the sweep accepted only {accepted} PSDs"
    );
}

#[test]
fn accepted_psds_have_finite_derived_quantities() {
    sweep::<f32>();
    sweep::<f64>();
}

/// Asserts `r` is `Err(OutOfRange)` or `Err(NonFinite)` whose `what` contains `name`.
#[track_caller]
fn rejects_naming<P: std::fmt::Debug>(r: Result<P, Error>, name: &str) {
    match r {
        Err(Error::OutOfRange { what, .. } | Error::NonFinite { what }) => {
            assert!(
                what.contains(name),
                "error names {what:?}, expected {name:?}"
            );
        }
        other => {
            let got: String = format!("{other:?}").chars().take(300).collect();
            panic!("expected an error naming {name:?}, got {got}…")
        }
    }
}

/// The named cases: each derived quantity over- or underflowing at each end, in f32 and f64.
#[test]
fn overflowing_derived_quantities_are_rejected() {
    // σ² = 10⁴⁰ and 10⁻⁶⁰ are outside f32; p(0) = σ²ℓ² = 10⁶⁰ too.
    rejects_naming(GaussianPsd::<f32, 2>::isotropic(1e20, 1.0), "rms height");
    rejects_naming(GaussianPsd::<f32, 2>::isotropic(1e-30, 1.0), "rms height");
    rejects_naming(
        GaussianPsd::<f32, 2>::isotropic(1e15, 1e15),
        "rms height σ and correlation length ℓ",
    );
    rejects_naming(GaussianPsd::<f64, 2>::isotropic(1e200, 1.0), "rms height");
    // A peak below the range is accepted (the amplitude is a logarithm): f32 σ = 10⁻²⁰,
    // ℓ = 10⁻³ has p(0) = σ²ℓ² = 10⁻⁴⁶ < the smallest f32, ln p(0) = −46 ln 10 by hand.
    let faint = GaussianPsd::<f32, 2>::isotropic(1e-20, 1e-3).unwrap();
    assert_eq!(faint.value(&Vector2::zeros()), 0.0);
    let lv = f64::from(faint.log_value(&Vector2::zeros()));
    assert_close("ln p(0)", lv, -46.0 * 10f64.ln(), Tol::new(0.0, 1e-6));
    // 1/ℓ² outside f32: ℓ = 10⁻²⁰ (1e40) and 10²³ (1e-46 → 0).
    rejects_naming(
        GaussianPsd::<f32, 2>::isotropic(1.0, 1e-20),
        "correlation length",
    );
    rejects_naming(
        GaussianPsd::<f32, 2>::isotropic(1.0, 1e23),
        "correlation length",
    );
    rejects_naming(
        GaussianPsd::<f64, 2>::from_scatmech(1.0, 1e-200),
        "1/e correlation length",
    );
    // ∫p = 2π σ² overflows although σ² = 0.9·MAX does not.
    rejects_naming(
        GaussianPsd::<f64, 2>::from_spectral_shape(
            0.9 * f64::MAX,
            Gaussian::isotropic(1.0).unwrap(),
        ),
        "variance σ² and spectral shape P",
    );
    // Λ⁻¹ of Λ = 10⁻⁴⁰ I is not an f32.
    let lam = Gaussian::<f32, 2>::new(Matrix2::new(1e-40, 0.0, 0.0, 1e-40)).unwrap();
    rejects_naming(
        GaussianPsd::from_autocorrelation(1.0, &lam),
        "correlation shape Λ",
    );
    // Mixture: Σ σⱼ² = 2 · 2e38 overflows f32.
    let big = GaussianPsd::<f32, 2>::from_spectral_shape(2e38, Gaussian::isotropic(1.0).unwrap())
        .unwrap_err();
    assert!(
        matches!(big, Error::OutOfRange { .. }),
        "2e38·2π overflows ∫p: {big:?}"
    );
    let half = GaussianPsd::<f32, 2>::from_spectral_shape(2e37, Gaussian::isotropic(1.0).unwrap())
        .unwrap();
    rejects_naming(GaussianMixturePsd::new(vec![half; 4]), "mixture components");
    rejects_naming(Smooth::new(f32::MAX), "specular weight");
    rejects_naming(Smooth::new(f64::MAX / 10.0), "specular weight");
    // K-correlation, n = 2: p(0) = σ²(γ − 1)T by hand.
    let k = KCorrelation::<f64, 2>::new(1.0, 1e308, 2.0).unwrap();
    assert!(k.peak_value().is_finite());
    assert_close(
        "p(0) = σ²(γ−1)T",
        k.peak_value(),
        1e308,
        Tol::new(0.0, 1e-13),
    );
    rejects_naming(
        KCorrelation::<f64, 2>::new(1.0, 1e308, 3.0),
        "K-correlation σ², T, γ",
    );
    rejects_naming(
        KCorrelation::<f32, 2>::new(1e-30, 1e-30, 2.0),
        "K-correlation σ², T, γ",
    );
    rejects_naming(
        KCorrelation::<f64, 2>::new(1.0, 1e10, 1e300),
        "K-correlation σ², T, γ",
    );
    let huge_gamma = KCorrelation::<f64, 2>::new(1.0, 1e-300, 1e290).unwrap();
    assert!(huge_gamma.peak_value().is_finite());
    assert_close(
        "p(0), γ = 1e290",
        huge_gamma.peak_value(),
        1e-10,
        Tol::new(0.0, 1e-12),
    );
    // ABC: A is validated by name; B² and σ² = 2πA/((C − 2)B²) outside the type.
    rejects_naming(
        KCorrelation::<f64, 2>::from_abc(f64::NAN, 1.0, 3.0),
        "ABC amplitude A",
    );
    rejects_naming(
        KCorrelation::<f64, 2>::from_abc(-1.0, 1.0, 3.0),
        "ABC amplitude A",
    );
    rejects_naming(
        KCorrelation::<f32, 2>::from_abc(1.0, 1e30, 3.0),
        "ABC length B",
    );
    rejects_naming(
        KCorrelation::<f32, 2>::from_abc(1.0, 1e-30, 3.0),
        "ABC length B",
    );
    rejects_naming(
        KCorrelation::<f32, 2>::from_abc(1.0, 1e-19, 3.0),
        "ABC parameters A, B, C",
    );
    // Mixture fit: squared component widths 1/(2 s T) above f32::MAX for T = 1e-40 (s ≪ 1).
    let kt = KCorrelation::<f32, 2>::new(1e10, 1e-40, 2.5).unwrap();
    rejects_naming(kt.mixture_fit(12), "K-correlation T, γ");
    // Gratings: 2π/Λ = ∞ for Λ = 1e-308 (f64) and 1e-38 (f32); ζ_m = m 2π/Λ overflows for
    // m ≥ 2 at Λ = 4e-308.
    let cut = OrderCutoff {
        max_frequency: f64::INFINITY,
        tail: 1e-12,
    };
    let x = Vector2::x();
    rejects_naming(
        Grating::<f64, 2>::sinusoidal(1e-308, &x, 1.0, cut),
        "grating period",
    );
    rejects_naming(
        Grating::<f64, 2>::sinusoidal(4e-308, &x, 1.0, cut),
        "grating period",
    );
    let cut32 = OrderCutoff {
        max_frequency: f32::INFINITY,
        tail: 1e-6,
    };
    rejects_naming(
        Grating::<f32, 2>::rectangular(1e-38, &Vector2::x(), 1.0, 0.3, cut32),
        "grating period",
    );
    rejects_naming(
        Grating::<f64, 2>::rectangular(1.0, &x, f64::NAN, 0.3, cut),
        "phase depth",
    );
    // A direction of 1e-200 is not zero.
    let small = Grating::<f64, 2>::sinusoidal(1.0, &Vector2::new(1e-200, 0.0), 1.0, cut).unwrap();
    assert_close(
        "ζ₁ along x",
        small.orders()[1].0.x.abs(),
        std::f64::consts::TAU,
        Tol::new(0.0, 1e-15),
    );
    // Crossed: positions ζ_a + ζ_b overflow (orders 0, ±1 at ±0.6·MAX, summed).
    let p = std::f64::consts::TAU / (0.6 * f64::MAX);
    let narrow = OrderCutoff {
        max_frequency: 0.7 * f64::MAX,
        tail: 0.0,
    };
    let g = Grating::<f64, 2>::sinusoidal(p, &x, 1.0, narrow).unwrap();
    assert_eq!(g.orders().len(), 3, "orders 0, ±1: {:?}", g.orders());
    rejects_naming(
        Grating::crossed(&g, &g, 0.0),
        "crossed grating order positions",
    );
    rejects_naming(Grating::crossed(&g, &g, f64::NAN), "minimum efficiency");
}

/// The order cap: a rectangular grating with no frequency limit and `tail = 1e-12` needs
/// ~10¹¹ orders (`η_m ∝ 1/m²`): an error naming the cutoff (it silently built 200 001 orders
/// before). At the cap's boundary, `|m| ≤ 5000` (10 001 orders) is accepted and `|m| ≤ 5001`
/// (10 003) is not; a frequency limit keeps it within the cap, with the dropped efficiency
/// reported; crossed gratings are counted before allocation.
#[test]
fn grating_order_count_is_capped() {
    assert_eq!(Grating::<f64, 2>::MAX_ORDERS, 10_001);
    let x = Vector2::x();
    let loose = OrderCutoff {
        max_frequency: f64::INFINITY,
        tail: 1e-12,
    };
    rejects_naming(
        Grating::<f64, 2>::rectangular(1.0, &x, 1.0, 0.3, loose),
        "number of grating orders",
    );
    rejects_naming(
        Grating::<f32, 2>::rectangular(
            1.0,
            &Vector2::x(),
            1.0,
            0.3,
            OrderCutoff {
                max_frequency: f32::INFINITY,
                tail: 1e-7,
            },
        ),
        "number of grating orders",
    );
    let tau = std::f64::consts::TAU;
    let at = |m: f64| OrderCutoff {
        max_frequency: (m + 0.5) * tau,
        tail: 0.0,
    };
    let ok = Grating::<f64, 2>::rectangular(1.0, &x, 1.0, 0.37, at(5000.0)).unwrap();
    assert_eq!(ok.orders().len(), 10_001);
    rejects_naming(
        Grating::<f64, 2>::rectangular(1.0, &x, 1.0, 0.37, at(5001.0)),
        "number of grating orders",
    );
    // Dropped efficiency, by hand: Σ_{|m|>M} 2c sin²(πmD)/(πm)², c = 1 − cos φ₀ (summed here
    // to m = 10⁶, the rest below 2c/(π²·10⁶)).
    let (c, d) = (1.0 - 1f64.cos(), 0.37);
    let tail: f64 = (5001..1_000_000)
        .map(|m| {
            let xm = std::f64::consts::PI * m as f64;
            2.0 * 2.0 * c * (xm * d).sin().powi(2) / (xm * xm)
        })
        .sum();
    assert_close(
        "dropped efficiency",
        ok.dropped_efficiency(),
        tail,
        Tol::new(2.0 * c / (9.8e6) + 1e-13, 1e-6),
    );
    // Crossed: 101 × 101 orders exceed the cap; with a threshold only the strong ones remain.
    let s = Grating::<f64, 2>::sinusoidal(
        1.0,
        &x,
        40.0,
        OrderCutoff {
            max_frequency: 50.5 * tau,
            tail: 0.0,
        },
    )
    .unwrap();
    assert_eq!(s.orders().len(), 101);
    let sy = Grating::<f64, 2>::sinusoidal(
        1.0,
        &Vector2::y(),
        40.0,
        OrderCutoff {
            max_frequency: 50.5 * tau,
            tail: 0.0,
        },
    )
    .unwrap();
    rejects_naming(Grating::crossed(&s, &sy, 0.0), "number of grating orders");
    let strong = Grating::crossed(&s, &sy, 1e-4).unwrap();
    assert!(strong.orders().len() <= Grating::<f64, 2>::MAX_ORDERS && !strong.orders().is_empty());
    assert!(strong.dropped_efficiency() > 0.0);
}

/// Blurs at frequencies near `T::MAX` are 0, not NaN (the Cholesky substitution met 0·∞ for a
/// diagonal `Λ⁻¹ + Σ` with a tiny entry).
fn huge_frequency_blurs<T: Real>(huge: f64) {
    let shape = Gaussian::<T, 2>::new(Matrix2::new(1e-20, 0.0, 0.0, 1.0).map(T::lit)).unwrap();
    let p = GaussianPsd::from_spectral_shape(T::lit(1e-4), shape).unwrap();
    let cov = Gaussian::<T, 2>::isotropic(T::lit(1e-10)).unwrap();
    for h in [Vector2::new(huge, 1.0), Vector2::new(huge, -huge)] {
        let h = h.map(T::lit);
        assert_eq!(
            ClosedForm.normalized_blur(&p, &cov, &h).to_f64(),
            0.0,
            "{h:?}"
        );
        assert_eq!(ClosedForm.blur(&p, &cov, &h).to_f64(), 0.0, "{h:?}");
        assert_eq!(
            p.log_normalized_blur(&cov, &h).to_f64(),
            f64::NEG_INFINITY,
            "{h:?}"
        );
        assert_eq!(p.value(&h).to_f64(), 0.0);
    }
}

#[test]
fn blurs_at_huge_frequencies_are_zero() {
    huge_frequency_blurs::<f32>(3e38);
    huge_frequency_blurs::<f64>(1e300);
}
