//! Verifies `Kernel::evaluate_batch` at the Kirchhoff series' roughness level
//! (`interaction::batch::stages::series`: the lanes for a Gaussian PSD blurred in closed form)
//! against the per-direction series kernel `Kernel::evaluate` with the same tolerance:
//! proptest over the scenes of `lobes.rs` (incidence 0–83°, tilted surfaces, turned packet
//! frames, polarized input, two coherence shapes of widths 0.3–300 λ, conductors with
//! dielectric and absorbing indices, glass interfaces lit from either side, exits near the
//! specular direction and over the hemisphere, not unit length), with the scene's first PSD
//! component as a `GaussianPsd` whose rms height is scaled so that `vσ` at normal incidence,
//! `4πσ/λ`, is 0.05–8 (the series' orders from one to ~90), at `Full`, `OneShape` and
//! `Intensity` with `Partial` (the lanes, f64 to 10⁻¹⁰ and f32 to 10⁻⁶) and `Incoherent` (one
//! exit at a time: bit for bit); and `Kernel::evaluate_batch_spectral` of three wavelengths of
//! each scene (the PSD's heights fixed, the index dispersed) against one `evaluate_batch` per
//! wavelength, bit for bit, at every scale the extreme-scale tests draw.
//!
//! Tolerance: the first-order lanes' documented bound (`lobes.rs`) plus `tol L`: each of the
//! two sums is within `tol/2` of the whole series (the lanes stop where a falling term is below
//! `tol/2` of the largest; the per-direction kernel by the geometric bound on the rest), `L`
//! the lobe's one-at-a-time `S0` (`lobes.rs`'s `compare`, which also asks for valid Stokes
//! vectors).

use crate::common;

use super::lobes::{Scene, check_kernel, interface_strategy, scene_strategy};
use gmueller::Real;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::coherence::{CoherenceModel, CoherenceWeights};
use gmueller::interaction::pbsdf::{FresnelInterface, FresnelReflection, Pbsdf, RayleighRice};
use gmueller::interaction::polarization::PolarizationModel;
use gmueller::interaction::roughness::KirchhoffSeries;
use gmueller::interaction::{Full, Incoherent, Intensity, Kernel, OneShape, Partial, RoughSurface};
use gmueller::psd::GaussianPsd;
use num_complex::Complex;
use proptest::prelude::*;

/// The scene's first component as a Gaussian PSD, its rms height set to `vs λ/4π`.
fn psd<T: Real>(sc: &Scene, vs: f64) -> GaussianPsd<T, 2> {
    let (_, cov) = &sc.components[0];
    let sigma = vs * sc.wavelength / (4.0 * std::f64::consts::PI);
    let corr = Gaussian::new(cov.map(T::lit)).unwrap();
    GaussianPsd::from_autocorrelation(T::lit(sigma * sigma), &corr).unwrap()
}

/// `lobes.rs`'s [`check_kernel`] with the series of tolerance `tol`: the lanes (`Partial`)
/// within the bound plus `tol L`, one exit at a time (`Incoherent`) bit for bit; the spectral
/// batch bit for bit. `make(stretch)` is the material at `wavelength × stretch` and its
/// interface.
fn check<T, Pol, Coh, Sp, Sc>(
    sc: &Scene,
    what: &str,
    tol: f64,
    make: impl Fn(f64) -> (RoughSurface<GaussianPsd<T, 2>, Sp, Sc>, Option<T>),
) where
    T: Real,
    Pol: PolarizationModel,
    Coh: CoherenceModel + CoherenceWeights<T, GaussianPsd<T, 2>> + Default + 'static,
    Sp: Pbsdf<T> + Copy + 'static,
    Sc: Pbsdf<T> + Copy + 'static,
{
    let kernel = Kernel::<Pol, Coh>::default().with_roughness(KirchhoffSeries::new(tol).unwrap());
    let lanes = matches!(
        Coh::LEVEL,
        gmueller::interaction::coherence::CoherenceLevel::Partial
    );
    check_kernel(sc, what, &kernel, make, (tol, !lanes));
}

/// [`check`] at the scene's level (`level` 0–5 as in `lobes.rs`) on its conductor or glass.
fn check_scene<T: Real>(sc: &Scene, vs: f64, what: &str) {
    let tol = if T::EPSILON.to_f64() < 1e-10 {
        1e-10
    } else {
        1e-6
    };
    macro_rules! level {
        ($m:expr) => {
            match sc.level {
                0 => check::<T, Full, Partial, _, _>(sc, what, tol, $m),
                1 => check::<T, Full, Incoherent, _, _>(sc, what, tol, $m),
                2 => check::<T, OneShape, Partial, _, _>(sc, what, tol, $m),
                3 => check::<T, OneShape, Incoherent, _, _>(sc, what, tol, $m),
                4 => check::<T, Intensity, Partial, _, _>(sc, what, tol, $m),
                _ => check::<T, Intensity, Incoherent, _, _>(sc, what, tol, $m),
            }
        };
    }
    // At `wavelength × stretch`: the same heights, the index's real part scaled by `√stretch`
    // (a dispersion, as in `lobes.rs`).
    let p = psd::<T>(sc, vs);
    if sc.interface {
        level!(|stretch: f64| {
            let eta = T::lit(sc.eta.re * stretch.sqrt());
            let glass = RoughSurface {
                psd: p,
                specular: FresnelInterface::new(eta).unwrap(),
                scatter: RayleighRice::new(Complex::new(eta, T::zero())).unwrap(),
            };
            (glass, Some(eta))
        });
    } else {
        level!(|stretch: f64| {
            let eta = Complex::new(T::lit(sc.eta.re * stretch.sqrt()), T::lit(sc.eta.im));
            let metal = RoughSurface {
                psd: p,
                specular: FresnelReflection::new(eta).unwrap(),
                scatter: RayleighRice::new(eta).unwrap(),
            };
            (metal, None)
        });
    }
}

/// The scene at `lambda` times its wavelength and coherence widths (the same scene in units of
/// the wavelength) with correlation lengths `lambda × ell` times its own (`ℓ/λ` scaled by `ell`).
fn scaled(mut sc: Scene, lambda: f64, ell: f64) -> Scene {
    sc.wavelength *= lambda;
    sc.width *= lambda;
    for (_, cov) in &mut sc.components {
        *cov *= (lambda * ell) * (lambda * ell);
    }
    sc
}

proptest! {
    #![proptest_config(common::proptest_config(24))]

    /// At the edges: wavelengths 10⁻²–10² µm, correlation lengths 10⁻²–10² times the scenes'
    /// (ℓ/λ from ~10⁻³ to ~10³: lobes from the whole hemisphere to far below a degree, where
    /// far exits may need more orders than the call builds and are then redone one at a time;
    /// how many are redone is not measured here), and `vσ` at the lanes' `g` limit (f64: 64,
    /// `vσ` 7.5–8.5 at normal incidence, more at oblique exits).
    #[test]
    fn series_batch_at_extreme_scales_f64(
        sc in prop_oneof![scene_strategy(), interface_strategy()],
        log_lambda in -2.0..2.0f64, log_ell in -2.0..2.0f64,
        vs in prop_oneof![0.05..8.0f64, 7.5..8.5f64],
    ) {
        let sc = scaled(sc, 10f64.powf(log_lambda), 10f64.powf(log_ell));
        check_scene::<f64>(&sc, vs, "f64 extreme");
    }

    /// [`series_batch_at_extreme_scales_f64`] in f32, `vσ` near its lanes' limit `g = 16`
    /// (`vσ` 3.7–4.3: lanes on both sides of it in one call, the far side redone).
    #[test]
    fn series_batch_at_extreme_scales_f32(
        sc in prop_oneof![scene_strategy(), interface_strategy()],
        log_lambda in -2.0..2.0f64, log_ell in -2.0..2.0f64,
        vs in prop_oneof![0.05..8.0f64, 3.7..4.3f64],
    ) {
        let sc = scaled(sc, 10f64.powf(log_lambda), 10f64.powf(log_ell));
        check_scene::<f32>(&sc, vs, "f32 extreme");
    }

    #[test]
    fn series_batch_matches_the_per_direction_series_f64(
        sc in scene_strategy(), vs in 0.05..8.0f64
    ) {
        check_scene::<f64>(&sc, vs, "f64");
    }

    #[test]
    fn series_batch_matches_the_per_direction_series_f32(
        sc in scene_strategy(), vs in 0.05..8.0f64
    ) {
        check_scene::<f32>(&sc, vs, "f32");
    }

    #[test]
    fn series_batch_at_an_interface_matches_the_per_direction_series_f64(
        sc in interface_strategy(), vs in 0.05..8.0f64
    ) {
        check_scene::<f64>(&sc, vs, "f64");
    }

    #[test]
    fn series_batch_at_an_interface_matches_the_per_direction_series_f32(
        sc in interface_strategy(), vs in 0.05..8.0f64
    ) {
        check_scene::<f32>(&sc, vs, "f32");
    }
}
