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
//!
//! Then `Kernel::evaluate_pairs_mueller` against the seed's formulas written out, never calling
//! the crate (`mueller_pairs_equal_the_literal_seed_formulas`): S1.7's `A_mül (J* ⊗ J) A_mül⁻¹`
//! of Germer's Rayleigh–Rice factors and of the Fresnel matrix, S2.4's frame change and S2.10's
//! coherence integral in closed form ([`literal_pair`]). A transposed Rayleigh–Rice matrix, the
//! other sign of `sin φ` or of `r_p`, and the specular lobe's frame change taken as a rotation
//! beyond 90° each failed it (mutations of the oracle, run once, not committed).

use crate::common;
use crate::common::Lcg;

use common::oracle::{
    coherence_integral, exit_azimuth, mueller_literal, rayleigh_rice_factors, rotation_literal,
    sp_basis, tau,
};
use gmueller::Real;
use gmueller::bsdf::{Bsdf, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::batch::{
    DirectionsSoa, ExitFramesSoa, LobesSoa, MuellerLobesSoa, MuellerSoa, PairsSoa, StokesSoa,
};
use gmueller::interaction::coherence::{CoherenceModel, CoherenceWeights};
use gmueller::interaction::polarization::{KernelOutput, PolarizationModel};
use gmueller::interaction::roughness::RoughnessWeights;
use gmueller::interaction::{
    Full, Incoherent, Intensity, Kernel, OneShape, Partial, RoughConductor, Side,
};
use gmueller::psd::GaussianPsd;
use nalgebra::{Matrix2, Matrix4, Vector2, Vector3};
use num_complex::Complex;
use std::f64::consts::TAU;

type C64 = Complex<f64>;
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

/// The pairs of a test's columns: `to_source` in 0–2, `exit` in 3–5, `1/w` in 6.
fn pairs_of<T>(cols: &[Vec<T>]) -> PairsSoa<'_, T> {
    PairsSoa {
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
    }
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
    let pairs = pairs_of(&cols);
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

// ------------------------------------------------- the Mueller pairs against the literal S1.7

/// The Mueller matrices of one pair by the seed's formulas, never calling the crate (the
/// oracle of `tests/interaction/polarization/channels.rs`, module docs, for one shape): the
/// pair's light is unpolarized, of one shape, with the section `Ξ = I/w²` on the surface, so
/// every channel has the same weight and a lobe's Mueller matrix is
/// ```text
/// M = (cos θ_o / λ²) α f(h_t) · M_lit,   α = exp(−(kσ(cos θ_i + cos θ_o))²)
/// f(h_t) = σ² 2π |G|^{−1/2} exp(−½ h_tᵀ G⁻¹ h_t),   G = C_R⁻¹ + Ξ,   h = k(ŝ + r̂)   (S2.10)
/// ```
/// with `C_R⁻¹ = 0`, `σ² = 1` for the specular lobe and `C_R⁻¹ = 0` for the scattered one at the
/// `Incoherent` level. `M_lit` is S1.7 literally (`A_mül (J* ⊗ J) A_mül⁻¹`): of Germer's
/// Rayleigh–Rice factors `J = 2k cos θ_i [[ss, ps], [sp, pp]]` (SCATMECH's form) between the
/// incident and exit s/p bases for the scattered lobe; for the specular lobe, of the Fresnel
/// matrix `diag(r_s, r_p)` (Born & Wolf, `r_p = (η² c − q)/(η² c + q)`) into the s/p basis of
/// the mirror direction, carried to the exit's by the minimal rotation `r_spec → r̂` (Rodrigues)
/// and S2.4's `T` of the two bases; beyond 90° from `r_spec`, by S2.3's reflection (the minimal
/// rotation to `−r̂`, the exit basis with `p̂` reversed, then `diag(1, −1)`).
///
/// Returns the two matrices and, per lobe: the exponent `½ h_tᵀ G⁻¹ h_t + (kσ(cos θ_i +
/// cos θ_o))²`, whose rounding the result inherits; its gradient `|G⁻¹ h_t|` in `h_t`, which
/// scales the rounding of `h_t` itself; and `M′₀₀ = ½ Σ |J′ᵢⱼ|²` of the lobe's unscaled Jones
/// matrix (`J′` the Rayleigh–Rice factors without `2k cos θ_i`, or the Fresnel matrix).
fn literal_pair(
    sc: &Scene,
    s: Vector3<f64>,
    r: Vector3<f64>,
    w: f64,
    incoherent: bool,
) -> ([Matrix4<f64>; 2], [[f64; 3]; 2]) {
    let (t1, t2, n) = (sc.frame.x(), sc.frame.y(), sc.frame.k());
    let (s, r) = (s.normalize(), r.normalize());
    let k = TAU / sc.wavelength;
    let (ci, co) = (s.dot(&n), r.dot(&n));
    let h = (s + r) * k;
    let ht = Vector2::new(h.dot(&t1), h.dot(&t2));
    let xi = Matrix2::identity() / (w * w);
    let sigma2 = sc.sigma * sc.sigma;
    let c_inv = if incoherent {
        Matrix2::zeros()
    } else {
        sc.correlation.try_inverse().unwrap()
    };
    let f = [
        coherence_integral(1.0, &Matrix2::zeros(), &xi, &ht),
        coherence_integral(sigma2, &c_inv, &xi, &ht),
    ];
    let debye_waller = (k * sc.sigma * (ci + co)).powi(2);
    let exponent = [Matrix2::zeros(), c_inv].map(|c| {
        let g: Matrix2<f64> = c + xi;
        let gradient = g.try_inverse().unwrap() * ht;
        (0.5 * ht.dot(&gradient) + debye_waller, gradient.norm())
    });
    let front = co / (sc.wavelength * sc.wavelength) * (-debye_waller).exp();
    // The scattered lobe: Rayleigh–Rice between the incident and exit s/p bases.
    let eps = sc.eta * sc.eta;
    let (sp_in, sp_out) = (sp_basis(&-s, &n), sp_basis(&r, &n));
    let (cphi, sphi) = exit_azimuth(&sp_in[0], &sp_out[0], &n);
    let factors = rayleigh_rice_factors(eps, ci, co, cphi, sphi);
    let j_scat = factors * C64::new(2.0 * k * ci, 0.0);
    // The specular lobe: Fresnel into the mirror direction's basis, then the minimal rotation.
    let q = (eps - (1.0 - ci * ci)).sqrt();
    let (rs, rp) = ((ci - q) / (ci + q), (eps * ci - q) / (eps * ci + q));
    let j_spec = Matrix2::new(rs, C64::new(0.0, 0.0), C64::new(0.0, 0.0), rp);
    let mirror = -s + n * (2.0 * ci);
    // Beyond 90° from the mirror direction S2.3's frame change is a reflection: the minimal
    // rotation to −r̂, onto the exit basis with p̂ reversed, then diag(1, −1) (`frame` docs).
    let backward = mirror.dot(&r) < 0.0;
    let target = if backward { -r } else { r };
    let axis = mirror.cross(&target);
    let angle = axis.norm().atan2(mirror.dot(&target));
    let turn = |v: Vector3<f64>| {
        if axis.norm() == 0.0 {
            return v;
        }
        let a = axis.normalize();
        v * angle.cos() + a.cross(&v) * angle.sin() + a * (a.dot(&v) * (1.0 - angle.cos()))
    };
    let sp_mirror = sp_basis(&mirror, &n).map(turn);
    let transport = if backward {
        let flip = Matrix2::new(1.0, 0.0, 0.0, -1.0);
        let turned = flip * tau(sp_mirror, [sp_out[0], -sp_out[1]]);
        mueller_literal(&turned.map(|x| C64::new(x, 0.0)))
    } else {
        rotation_literal(sp_mirror, sp_out)
    };
    let m_spec = transport * mueller_literal(&j_spec);
    let m_scat = mueller_literal(&j_scat);
    let unscaled = [j_spec, factors].map(|j| 0.5 * j.iter().map(|z| z.norm_sqr()).sum::<f64>());
    let terms = [0, 1].map(|l| [exponent[l].0, exponent[l].1, unscaled[l]]);
    ([m_spec * (front * f[0]), m_scat * (front * f[1])], terms)
}

/// `Kernel::evaluate_pairs_mueller` (f64) against [`literal_pair`] for the scene's pairs: every
/// entry of each lobe within `8 ε (16 + e + |ln M₀₀| + k |G⁻¹ h_t|) M₀₀ + MIN_POSITIVE
/// max(1, M′₀₀)` of the literal matrix (`M₀₀` the literal one). `128 ε` covers the two routes'
/// matrix algebra (both a few dozen operations on entries at most `M₀₀`). `e` is the lobe's
/// exponent: `exp` turns its rounding into a relative error `ε e`. The last term is the exponent's conditioning: both
/// sides form `h_t = k(ŝ + r̂)_t` from unit vectors each rounded by up to `2 ε`, so `h_t` may
/// differ by `4 ε k` on either side, and the exponent by `|G⁻¹ h_t|` times that (found needed:
/// without it the specular lobe of a wide coherence, `e ≈ 130`, differed by 1.6·10⁻¹¹
/// relative, 30× the other terms). The absolute term is `MIN_POSITIVE max(1, M′₀₀)`, not
/// `MIN_POSITIVE`: the crate writes a lobe as 0 where its scale (everything but the Mueller
/// matrix `M′` of the unscaled Jones matrix) is below the smallest normal number, the scalar
/// BSDF form's rule (`scaled_matrix`), so `M₀₀ = M′₀₀ × scale` may be up to `M′₀₀ MIN_POSITIVE`
/// (found needed: 0 against 2.5·10⁻³⁰⁸ on a conductor with `|ε| ≈ 38`). Entries of a Mueller
/// matrix are at most `M₀₀`, so a wrong sign, a transposed Jones matrix, a swapped basis or a
/// wrong weight is off by `O(M₀₀)`.
fn check_literal<Pol, Coh>(sc: &Scene, kernel: Kernel<Pol, Coh>, incoherent: bool)
where
    Pol: PolarizationModel,
    Coh: CoherenceModel + CoherenceWeights<f64, GaussianPsd<f64, 2>>,
    gmueller::interaction::roughness::FirstOrder: RoughnessWeights<f64, GaussianPsd<f64, 2>, Coh>,
{
    let corr = Gaussian::new(sc.correlation).unwrap();
    let psd = GaussianPsd::<f64, 2>::from_autocorrelation(sc.sigma * sc.sigma, &corr).unwrap();
    let gold = RoughConductor::new(psd, sc.eta).unwrap();
    let mut rng = Lcg(sc.seed);
    let k = TAU / sc.wavelength;
    let n = sc.pairs;
    // Columns: to_source (3), exit (3), 1/w, w.
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 8];
    for _ in 0..n {
        let s = local(
            &sc.frame,
            uniform_in(&mut rng, 1.0, 85.0),
            uniform_in(&mut rng, 0.0, 360.0),
        );
        let w = (sc.widths.0.ln() + rng.uniform() * (sc.widths.1 / sc.widths.0).ln()).exp();
        let r = if rng.uniform() < 0.5 {
            // Near the mirror direction, out to a few widths of either lobe.
            let mirror = sc.frame.k() * (2.0 * s.dot(&sc.frame.k())) - s;
            let off = 10f64.powf(uniform_in(&mut rng, -6.0, -0.5));
            let axis = mirror.cross(&local(&sc.frame, 45.0, uniform_in(&mut rng, 0.0, 360.0)));
            (mirror + axis.normalize() * off).normalize()
        } else {
            local(
                &sc.frame,
                uniform_in(&mut rng, 1.0, 89.0),
                uniform_in(&mut rng, 0.0, 360.0),
            )
        };
        let r = if r.dot(&sc.frame.k()) < 0.02 {
            local(&sc.frame, 60.0, 0.0)
        } else {
            r
        };
        for (c, v) in cols
            .iter_mut()
            .zip([s.x, s.y, s.z, r.x, r.y, r.z, 1.0 / w, w])
        {
            c.push(v);
        }
    }
    let mut buf = vec![vec![-7.0; n]; 32];
    let (a, b) = buf.split_at_mut(16);
    let mut out = MuellerLobesSoa {
        specular: MuellerSoa {
            m: a.iter_mut()
                .map(Vec::as_mut_slice)
                .collect::<Vec<_>>()
                .try_into()
                .unwrap(),
        },
        scattered: MuellerSoa {
            m: b.iter_mut()
                .map(Vec::as_mut_slice)
                .collect::<Vec<_>>()
                .try_into()
                .unwrap(),
        },
    };
    let pairs = pairs_of(&cols);
    kernel
        .evaluate_pairs_mueller(&gold, k, &sc.frame, pairs, &mut out, None)
        .unwrap();
    let intensity = out.specular.m[1][0] == -7.0;
    let entries = if intensity { 1 } else { 16 };
    #[expect(
        clippy::needless_range_loop,
        reason = "pair i in eight input columns and thirty-two output columns"
    )]
    for i in 0..n {
        let at = |j: usize| Vector3::new(cols[j][i], cols[j + 1][i], cols[j + 2][i]);
        let (want, terms) = literal_pair(sc, at(0), at(3), cols[7][i], incoherent);
        for (lobe, got) in [&out.specular, &out.scattered].into_iter().enumerate() {
            let m00 = want[lobe][(0, 0)];
            let [e, gradient, unscaled] = terms[lobe];
            let ln = if m00 > 0.0 { m00.ln().abs() } else { 0.0 };
            let bound = (8.0 * f64::EPSILON * (16.0 + e + ln + k * gradient)) * m00
                + f64::MIN_POSITIVE * unscaled.max(1.0);
            for e in 0..entries {
                let (g, w) = (got.m[e][i], want[lobe][(e / 4, e % 4)]);
                assert!(
                    (g - w).abs() <= bound,
                    "pair {i} of {n}, lobe {lobe}, M{}{}: lanes {g:e}, literal {w:e} (bound {bound:e}; \
                     {sc:?})",
                    e / 4,
                    e % 4
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(common::proptest_config(32))]

    /// The Mueller pairs (f64; `Full · Partial`, `Intensity · Partial`, `Full · Incoherent`)
    /// against S1.7, S2.10 and the Rayleigh–Rice and
    /// Fresnel Jones matrices written out ([`literal_pair`]): light 1–85° from the normal, exits
    /// near the mirror direction (10⁻⁶–0.3 rad) and anywhere above, widths 0.3–3000 µm.
    #[test]
    fn mueller_pairs_equal_the_literal_seed_formulas(sc in scene_strategy(false)) {
        // Three of the five lane levels: with one shape `OneShape` is `Full`, and each lane
        // level is checked against the per-direction kernel in `interaction::batch::pairs`'s
        // unit tests; the other two would add two instantiations of the lane path to the build.
        match sc.level {
            0 | 1 => check_literal(&sc, Kernel::<Full, Partial>::default(), false),
            2 | 4 => check_literal(&sc, Kernel::<Intensity, Partial>::default(), false),
            _ => check_literal(&sc, Kernel::<Full, Incoherent>::default(), true),
        }
    }
}
