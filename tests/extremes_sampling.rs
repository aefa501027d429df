//! Verifies importance sampling at the extremes of DESIGN §7: for Gaussian and K-correlation
//! lobes with correlation lengths 10⁻³…10⁴ λ, minimum coherence widths 10⁻³…10⁶ λ, wavelengths
//! 0.1…100 µm and incidence up to 89.99° (plus exact normal incidence), construction succeeds
//! below 80° (beyond, a sampler may refuse a very narrow lobe with an error, see the test), and
//! every sample is a finite unit direction above the
//! horizon whose `pdf(direction)` equals `sample.pdf`, finite and positive.

mod common;

use gmueller::frame::Frame;
use gmueller::interaction::sampling::LobeSampler;
use gmueller::psd::{GaussianPsd, KCorrelation};
use nalgebra::Vector3;
use proptest::prelude::*;

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..=hi.ln()).prop_map(f64::exp)
}

fn incidence() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        Just(89.99f64.to_radians()),
        0.0..89.99f64.to_radians()
    ]
}

fn check(sampler: &LobeSampler<f64>, us: &[(f64, f64)]) -> Result<(), TestCaseError> {
    for &(a, b) in us {
        let s = sampler.sample([a, b]);
        let d = s.direction;
        prop_assert!(d.iter().all(|x| x.is_finite()), "finite direction {d:?}");
        prop_assert!((d.norm() - 1.0).abs() < 1e-9, "unit direction {d:?}");
        prop_assert!(d.z > 0.0, "above the horizon {d:?}");
        prop_assert!(s.pdf.is_finite() && s.pdf > 0.0, "pdf {}", s.pdf);
        let again = sampler.pdf(&d);
        prop_assert!(
            (again - s.pdf).abs() <= 1e-12 * s.pdf,
            "pdf(direction) {again} vs sample.pdf {}",
            s.pdf
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(common::proptest_config(96))]
    #[test]
    fn samplers_at_the_extremes(
        lambda in log_uniform(0.1, 100.0),
        ell in log_uniform(1e-3, 1e4),
        width in log_uniform(1e-3, 1e6),
        rms in log_uniform(1e-4, 0.05),
        theta in incidence(),
        azimuth in -3.1..3.1f64,
        gamma in 1.5..4.0f64,
        us in proptest::collection::vec((0.0..1.0f64, 0.0..1.0f64), 8),
    ) {
        // Known limitation (both samplers): at grazing incidence with a very narrow lobe (long
        // correlation length and wide coherence) the angular table may not converge within its
        // panel budget; construction then returns `Error::Unrealizable` — never a wrong pdf.
        // Away from grazing incidence construction must succeed; where built, it must be exact.
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let to_source = Vector3::new(theta.sin() * azimuth.cos(), theta.sin() * azimuth.sin(), theta.cos());
        let k = std::f64::consts::TAU / lambda;
        let gauss = GaussianPsd::isotropic(rms * lambda, ell * lambda).unwrap();
        match LobeSampler::gaussian(&gauss, &surface, &to_source, k, width * lambda) {
            Ok(s) => check(&s, &us)?,
            Err(e) => prop_assert!(
                theta > 80f64.to_radians(),
                "Gaussian sampler construction failed away from grazing: {e:?}"
            ),
        }
        let kc = KCorrelation::new((rms * lambda).powi(2), (ell * lambda).powi(2), gamma).unwrap();
        match LobeSampler::k_correlation(&kc, &surface, &to_source, k, width * lambda) {
            Ok(s) => check(&s, &us)?,
            Err(e) => prop_assert!(
                theta > 80f64.to_radians(),
                "K-correlation sampler construction failed away from grazing: {e:?}"
            ),
        }
    }
}
