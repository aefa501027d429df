//! Verifies `Kernel::evaluate_pairs` (every lane its own light direction, exit and coherence
//! width) against the renderer layer one pair at a time: `Bsdf::prepare_surface` (the same
//! closed-form light, `SurfaceCoherence::fixed(w)`) and `Bsdf::eval_stokes`, the per-direction
//! kernel, on rough conductors. Proptest over tilted surface frames (any orientation), light
//! directions 0–89.9° at any azimuth, exits near the mirror direction and anywhere above
//! (0–89.9°, not unit length), widths 0.3–3000 µm, wavelengths 0.3–1 µm (and, in the extreme
//! variant, 0.01–100 µm with widths 0.01–10⁵ µm), absorbing indices, isotropic and
//! anisotropic PSDs, the three polarization levels at `Partial` and `Incoherent` coherence,
//! f64 and f32, 1–40 pairs per call.
//!
//! Tolerance: the lane path's documented bound (`Kernel::evaluate_batch`) for an unpolarized
//! packet of `S0 = 1` and one shape, per Stokes parameter of a lobe of one-at-a-time `S0 = L`,
//! `|Δ| ≤ 4 ε (4 + |ln L|) (1 + √3) L + MIN_POSITIVE`, plus, for the specular lobe, the two
//! roundings of undoing the renderer layer's division by the lobe's mass `E`
//! (`Incident::specular_mass`): `4 ε L`. Every lobe is a valid Stokes vector
//! (`S1² + S2² + S3² ≤ S0² (1 + 8 ε)`, `S0 ≥ 0`) and every exit s vector a unit vector
//! orthogonal to the exit direction.

use crate::common;
use crate::common::Lcg;

use gmueller::Real;
use gmueller::bsdf::{Bsdf, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::batch::{DirectionsSoa, ExitFramesSoa, LobesSoa, PairsSoa, StokesSoa};
use gmueller::interaction::coherence::{CoherenceModel, CoherenceWeights};
use gmueller::interaction::polarization::{KernelOutput, PolarizationModel};
use gmueller::interaction::roughness::RoughnessWeights;
use gmueller::interaction::{
    Full, Incoherent, Intensity, Kernel, OneShape, Partial, RoughConductor, Side,
};
use gmueller::psd::GaussianPsd;
use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;
use proptest::prelude::*;

/// One call's scene, in f64.
#[derive(Debug, Clone)]
pub(crate) struct Scene {
    pub(crate) frame: Frame<f64>,
    pub(crate) wavelength: f64,
    /// The coherence widths' range (µm).
    pub(crate) widths: (f64, f64),
    pub(crate) eta: Complex<f64>,
    pub(crate) sigma: f64,
    /// The correlation covariance (µm²).
    pub(crate) correlation: Matrix2<f64>,
    pub(crate) level: usize,
    pub(crate) pairs: usize,
    pub(crate) seed: u64,
}

/// Uniform in `[lo, hi)`.
pub(crate) fn uniform_in(rng: &mut Lcg, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.uniform()
}

/// A direction `theta` from the normal of `f` at azimuth `phi` (degrees).
pub(crate) fn local(f: &Frame<f64>, theta: f64, phi: f64) -> Vector3<f64> {
    let (t, p) = (theta.to_radians(), phi.to_radians());
    f.x() * (t.sin() * p.cos()) + f.y() * (t.sin() * p.sin()) + f.k() * t.cos()
}

fn check<T, Pol, Coh>(sc: &Scene, kernel: Kernel<Pol, Coh>) -> Result<(), TestCaseError>
where
    T: Real,
    Pol: PolarizationModel,
    Coh: CoherenceModel + Clone + CoherenceWeights<T, GaussianPsd<T, 2>>,
    gmueller::interaction::roughness::FirstOrder: RoughnessWeights<T, GaussianPsd<T, 2>, Coh>,
    Kernel<Pol, Coh>: gmueller::bsdf::BsdfKernel<T, GaussianPsd<T, 2>>,
{
    let t = T::lit;
    let corr = Gaussian::new(sc.correlation.map(t)).unwrap();
    let psd = GaussianPsd::<T, 2>::from_autocorrelation(t(sc.sigma * sc.sigma), &corr).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(t(sc.eta.re), t(sc.eta.im))).unwrap();
    let frame = Frame::from_direction_and_x(sc.frame.k().map(t), sc.frame.x().map(t)).unwrap();
    let lambda = t(sc.wavelength);
    let bsdf = Bsdf::new(&gold, kernel.clone(), frame, lambda).unwrap();
    let mut rng = Lcg(sc.seed);
    let n = sc.pairs;
    let mut cols: Vec<Vec<T>> = vec![Vec::new(); 8];
    for _ in 0..n {
        let s = local(
            &sc.frame,
            uniform_in(&mut rng, 0.0, 89.9),
            uniform_in(&mut rng, 0.0, 360.0),
        );
        let r = if rng.uniform() < 0.5 {
            let mirror = sc.frame.k() * (2.0 * s.dot(&sc.frame.k())) - s;
            let jitter = local(
                &sc.frame,
                uniform_in(&mut rng, 0.0, 3.0),
                uniform_in(&mut rng, 0.0, 360.0),
            );
            (mirror + (jitter - sc.frame.k()) * 0.5).normalize()
        } else {
            local(
                &sc.frame,
                uniform_in(&mut rng, 0.0, 89.9),
                uniform_in(&mut rng, 0.0, 360.0),
            )
        };
        let r = if r.dot(&sc.frame.k()) < 1e-4 {
            sc.frame.k()
        } else {
            r
        };
        let length = uniform_in(&mut rng, 0.3, 3.0);
        let w = (sc.widths.0.ln() + rng.uniform() * (sc.widths.1 / sc.widths.0).ln()).exp();
        for (c, v) in cols
            .iter_mut()
            .zip([s.x, s.y, s.z, r.x * length, r.y * length, r.z * length])
        {
            c.push(t(v));
        }
        cols[6].push(t(w).recip());
        cols[7].push(t(w));
    }
    let mut buf = vec![vec![T::lit(-7.0); n]; 11];
    let [a, b, c, d, e, f, g, h, fx, fy, fz] = &mut buf[..] else {
        unreachable!()
    };
    let mut out = LobesSoa {
        specular: StokesSoa { s: [a, b, c, d] },
        scattered: StokesSoa { s: [e, f, g, h] },
    };
    let mut frames = ExitFramesSoa { s: [fx, fy, fz] };
    let pairs = PairsSoa {
        to_source: DirectionsSoa {
            x: &cols[0],
            y: &cols[1],
            z: &cols[2],
        },
        exit: DirectionsSoa {
            x: &cols[3],
            y: &cols[4],
            z: &cols[5],
        },
        inverse_width: &cols[6],
    };
    let k = T::two_pi() / lambda;
    kernel
        .evaluate_pairs(&gold, k, &frame, pairs, &mut out, Some(&mut frames))
        .unwrap();
    let intensity = out.specular.s[1][0] == T::lit(-7.0);
    let eps = T::EPSILON.to_f64();
    #[expect(
        clippy::needless_range_loop,
        reason = "pair i in eight input columns and eleven output columns"
    )]
    for i in 0..n {
        let at = |j: usize| Vector3::new(cols[j][i], cols[j + 1][i], cols[j + 2][i]);
        let (s, r) = (at(0), at(3));
        let w = cols[7][i];
        let light = bsdf
            .prepare_surface(s, &SurfaceCoherence::fixed(w).unwrap())
            .unwrap();
        let one = bsdf.eval_stokes(&light, r).unwrap();
        let mass = light.specular_mass(Side::Reflection).to_f64();
        let z = T::zero();
        let (sp, sc_) = match one.stokes() {
            Some((sp, sc)) => (sp.vector(), sc.vector()),
            None => {
                let v = |x: T| nalgebra::Vector4::new(x, z, z, z);
                (v(one.specular_intensity()), v(one.scattered_intensity()))
            }
        };
        let stokes_len = if intensity { 1 } else { 4 };
        for (lobe, want, scale) in [(&out.specular, sp, mass), (&out.scattered, sc_, 1.0f64)] {
            let want: Vec<f64> = want.iter().map(|v| v.to_f64() * scale).collect();
            let l = want[0].abs();
            let bound =
                4.0 * eps * (4.0 + l.max(f64::MIN_POSITIVE).ln().abs()) * (1.0 + 3f64.sqrt()) * l
                    + 4.0 * eps * l
                    + T::MIN_POSITIVE.to_f64();
            let got: Vec<f64> = (0..stokes_len).map(|c| lobe.s[c][i].to_f64()).collect();
            for c in 0..stokes_len {
                prop_assert!(
                    (got[c] - want[c]).abs() <= bound,
                    "pair {}, S{}: {:e} vs {:e} (bound {:e})",
                    i,
                    c,
                    got[c],
                    want[c],
                    bound
                );
            }
            prop_assert!(got[0] >= 0.0);
            if !intensity {
                let p2 = got[1] * got[1] + got[2] * got[2] + got[3] * got[3];
                prop_assert!(
                    p2 <= got[0] * got[0] * (1.0 + 8.0 * eps),
                    "pair {}: not valid",
                    i
                );
            }
        }
        let so = Vector3::new(frames.s[0][i], frames.s[1][i], frames.s[2][i]).map(|v| v.to_f64());
        let rn = r.map(|v| v.to_f64()).normalize();
        prop_assert!((so.norm() - 1.0).abs() <= 8.0 * eps && so.dot(&rn).abs() <= 8.0 * eps);
    }
    Ok(())
}

fn run<T: Real>(sc: &Scene) -> Result<(), TestCaseError> {
    match sc.level {
        0 => check::<T, _, _>(sc, Kernel::<Full, Partial>::default()),
        1 => check::<T, _, _>(sc, Kernel::<OneShape, Partial>::default()),
        2 => check::<T, _, _>(sc, Kernel::<Intensity, Partial>::default()),
        3 => check::<T, _, _>(sc, Kernel::<Full, Incoherent>::default()),
        _ => check::<T, _, _>(sc, Kernel::<Intensity, Incoherent>::default()),
    }
}

prop_compose! {
    pub(crate) fn scene_strategy(extreme: bool)(
        frame in common::frame(),
        wavelength in if extreme { common::log_uniform(0.01, 100.0) } else { common::log_uniform(0.3, 1.0) },
        wide in any::<bool>(),
        eta_re in 0.05..3.0f64,
        eta_im in 0.0..8.0f64,
        sigma_rel in common::log_uniform(0.003, 0.15),
        ell in common::log_uniform(0.3, 5.0),
        ratio in common::log_uniform(0.3, 3.0),
        corr in -0.8..0.8f64,
        level in 0..5usize,
        pairs in prop_oneof![Just(1usize), Just(7), Just(17), Just(40)],
        seed in any::<u64>(),
    ) -> Scene {
        let (a, b) = (ell * ell, ell * ell * ratio * ratio);
        let widths = match (extreme, wide) {
            (false, _) => (0.3, 3000.0),
            (true, false) => (0.01, 1.0),
            (true, true) => (100.0, 1e5),
        };
        Scene {
            frame,
            wavelength,
            widths: (widths.0 * wavelength / 0.55, widths.1 * wavelength / 0.55),
            eta: Complex::new(eta_re, eta_im),
            sigma: sigma_rel * wavelength,
            correlation: Matrix2::new(a, corr * (a * b).sqrt(), corr * (a * b).sqrt(), b)
                * (wavelength / 0.55) * (wavelength / 0.55),
            level,
            pairs,
            seed,
        }
    }
}

proptest! {
    #![proptest_config(common::proptest_config(48))]

    #[test]
    fn pairs_match_the_renderer_layer_one_at_a_time_f64(sc in scene_strategy(false)) {
        run::<f64>(&sc)?;
    }

    #[test]
    fn pairs_match_the_renderer_layer_one_at_a_time_f32(sc in scene_strategy(false)) {
        run::<f32>(&sc)?;
    }

    #[test]
    fn pairs_at_extreme_scales_f64(sc in scene_strategy(true)) {
        run::<f64>(&sc)?;
    }

    #[test]
    fn pairs_at_extreme_scales_f32(sc in scene_strategy(true)) {
        run::<f32>(&sc)?;
    }
}
