//! `psd::PowerLaw`, the band-limited power-law (fractal) PSD, end to end — the PSD that was
//! added as its own file (issue 38): its value and normalisation against independent
//! numerics (a lattice sum in 2-D, a radial quadrature in 3-D, the textbook `K f^{−α}` in
//! cycles), its blur by the quadrature methods against a lattice sum, f32 against f64, bad
//! input, the BSDF sampler (through the K-correlation form it names) against uniform sampling,
//! the batch path against the per-exit kernel, and the medium's `σ_s`, phase function and
//! sampler against adaptive quadrature and a χ² test.

use std::f64::consts::{PI, TAU};

use gmueller::bsdf::{Material, ShadingPoint, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::batch::{DirectionsSoa, LobesSoa, StokesSoa};
use gmueller::interaction::{Full, Kernel, Level, Partial, PlaneWave, RoughConductor};
use gmueller::medium::{Dipole, RandomMedium};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{Adaptive, BlurMethod, GaussHermite, PowerLaw, Psd, Shape};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Matrix4, Vector2, Vector3};
use num_complex::Complex;
use proptest::prelude::*;

use crate::common::{self, SplitMix64, Tol, assert_close, proptest_config};

/// `∫ p d²ζ = 2π σ²` by a midpoint lattice sum over `[−ζ_max, ζ_max]²` (no polar
/// coordinates, no use of the closed form of `c`): the band's two circular edges cost the
/// lattice an error of order `d/ζ_min` per edge cell, which averages out far below the
/// `1e-3` asked (printed).
#[test]
fn normalisation_2d_against_a_lattice_sum() {
    let (sigma, alpha, lo, hi) = (0.7, 3.0, 1.0, 6.0);
    let p = PowerLaw::<f64, 2>::new(sigma, alpha, lo, hi).unwrap();
    let n = 3000;
    let d = 2.0 * hi / n as f64;
    let mut sum = 0.0;
    for i in 0..n {
        let x = -hi + (i as f64 + 0.5) * d;
        for j in 0..n {
            let y = -hi + (j as f64 + 0.5) * d;
            sum += p.value(&Vector2::new(x, y));
        }
    }
    let integral = sum * d * d;
    println!(
        "lattice ∫p = {integral:.8}, 2πσ² = {:.8}",
        TAU * sigma * sigma
    );
    assert_close(
        "∫ p d²ζ",
        integral,
        TAU * sigma * sigma,
        Tol::new(0.0, 1e-3),
    );
    assert_close(
        "integral()",
        p.integral(),
        TAU * sigma * sigma,
        Tol::new(0.0, 1e-15),
    );
}

/// In 3-D, `∫ p d³q = (2π)^{3/2} σ²` by adaptive radial quadrature of `p` along random
/// directions (the PSD is isotropic: each direction gives the same integral).
#[test]
fn normalisation_3d_by_radial_quadrature() {
    let (sigma, alpha, lo, hi) = (2e-3, 3.7, 0.5, 40.0);
    let p = PowerLaw::<f64, 3>::new(sigma, alpha, lo, hi).unwrap();
    let want = TAU.powf(1.5) * sigma * sigma;
    let mut rng = SplitMix64(0x9e37);
    for _ in 0..4 {
        let dir = Vector3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize();
        let mut f = |r: f64| 4.0 * PI * r * r * p.value(&(dir * r));
        // Panels on a log scale: the integrand falls as r^{2−α}.
        let mut total = 0.0;
        let mut a = lo;
        while a < hi {
            let b = (2.0 * a).min(hi);
            total += crate::common::quadrature::integrate(&mut f, a, b, 4, 1e-14 * want);
            a = b;
        }
        assert_close("∫ p d³q", total, want, Tol::new(0.0, 1e-10));
    }
}

/// In cycles per length, `S(f) = K f^{−α}` with `∫ S dⁿf = σ²`: the textbook constant
/// `K = σ² (α − n) / (S_{n−1} (f_min^{n−α} − f_max^{n−α}))`, `S_1 = 2π`, `S_2 = 4π`, derived
/// here in polar/spherical coordinates from `S` alone (the crate derives `c` of the unitary
/// `p` instead).
#[test]
fn cycles_form_is_the_textbook_fractal_psd() {
    let (sigma, alpha, f_min, f_max) = (1.3e-3_f64, 2.6_f64, 0.02_f64, 3.0_f64);
    let k2 =
        sigma * sigma * (alpha - 2.0) / (TAU * (f_min.powf(2.0 - alpha) - f_max.powf(2.0 - alpha)));
    let p2 = PowerLaw::<f64, 2>::from_cycles(sigma, alpha, f_min, f_max).unwrap();
    let alpha3 = 3.4;
    let k3 = sigma * sigma * (alpha3 - 3.0)
        / (4.0 * PI * (f_min.powf(3.0 - alpha3) - f_max.powf(3.0 - alpha3)));
    let p3 = PowerLaw::<f64, 3>::from_cycles(sigma, alpha3, f_min, f_max).unwrap();
    for f in [0.021, 0.1, 0.77, 2.99] {
        let s2 = p2.value_cycles(&Vector2::new(0.6 * f, 0.8 * f));
        assert_close("S(f), n = 2", s2, k2 * f.powf(-alpha), Tol::new(0.0, 1e-12));
        let s3 = p3.value_cycles(&Vector3::new(0.0, 0.6 * f, -0.8 * f));
        assert_close(
            "S(f), n = 3",
            s3,
            k3 * f.powf(-alpha3),
            Tol::new(0.0, 1e-12),
        );
    }
    // Outside the band, 0.
    for f in [0.0, 0.019, 3.01, 1e300] {
        assert_eq!(p2.value_cycles(&Vector2::new(f, 0.0)), 0.0);
        assert_eq!(p3.value_cycles(&Vector3::new(0.0, 0.0, f)), 0.0);
    }
}

/// The quadrature blurs of the crate (`Adaptive`, the reference, and `GaussHermite`) against a
/// lattice sum of `∫ p(ζ) 𝒩_Σ(h − ζ) d²ζ`, at points inside the band, across its inner edge
/// and outside it, with an anisotropic Σ.
#[test]
fn quadrature_blurs_against_a_lattice_sum() {
    let p = PowerLaw::<f64, 2>::new(0.05, 3.0, 2.0, 30.0).unwrap();
    let cov = Gaussian::<f64, 2>::new(Matrix2::new(0.5, 0.2, 0.2, 0.8)).unwrap();
    let c = Matrix2::<f64>::new(0.5, 0.2, 0.2, 0.8);
    let inv = c.try_inverse().unwrap();
    let norm = 1.0 / (TAU * c.determinant().sqrt());
    let adaptive = Adaptive::new(1e-9).unwrap();
    let hermite = GaussHermite::new(24).unwrap();
    for h in [
        Vector2::new(5.0, 1.0),
        Vector2::new(2.0, 0.3),
        Vector2::new(0.3, 0.0),
    ] {
        // Lattice over h ± 9 standard deviations (the Gaussian's tail beyond is < 1e-17).
        let n = 2000;
        let half = 9.0 * 0.8f64.sqrt();
        let d = 2.0 * half / n as f64;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let z =
                    h + Vector2::new(-half + (i as f64 + 0.5) * d, -half + (j as f64 + 0.5) * d);
                let e = h - z;
                sum += p.value(&z) * norm * (-0.5 * (e.transpose() * inv * e)[(0, 0)]).exp();
            }
        }
        let lattice = sum * d * d;
        let a = adaptive.normalized_blur(&p, &cov, &h);
        let g = hermite.normalized_blur(&p, &cov, &h);
        println!("h = {h:?}: lattice {lattice:.6e}, adaptive {a:.6e}, Gauss–Hermite(24) {g:.6e}");
        assert_close(
            "Adaptive blur",
            a,
            lattice,
            Tol::new(1e-9 * lattice.abs(), 2e-3),
        );
        // Gauss–Hermite is exact for smooth integrands only: at 4 blur widths from both edges
        // (h = (5, 1)) it agrees; at the inner edge and inside the hole its fixed nodes see the
        // step (3 % and 17 % off: the type docs' warning), so it is asserted only away from them.
        if (h.norm() - 2.0).abs() > 3.0 {
            assert_close("Gauss–Hermite blur", g, lattice, Tol::new(0.0, 1e-4));
        }
    }
}

/// The form: the K-correlation of `T = 1/ζ_min²`, `γ = α − 1`, as the closest (not exact)
/// form; a PSD of zero rms names `Zero`.
#[test]
fn form_is_the_closest_k_correlation() {
    let p = PowerLaw::<f64, 2>::new(1e-3, 3.2, 0.5, 10.0).unwrap();
    let f = p.form();
    assert!(!f.is_exact());
    match f.shape() {
        Shape::KCorrelation { t, gamma } => {
            assert_close("T", t, 4.0, Tol::new(0.0, 1e-15));
            assert_close("γ", gamma, 2.2, Tol::new(0.0, 1e-15));
        }
        s => panic!("form {s:?}"),
    }
    let zero = PowerLaw::<f64, 2>::new(0.0, 3.2, 0.5, 10.0).unwrap();
    assert!(matches!(zero.form().shape(), Shape::Zero));
    assert_eq!(zero.value(&Vector2::new(1.0, 0.0)), 0.0);
}

/// Bad input is refused with an error, never a panic or a PSD of non-finite values.
#[test]
fn bad_input_is_refused() {
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    for (s, a, lo, hi) in [
        (-1e-3, 3.0, 0.1, 10.0),
        (nan, 3.0, 0.1, 10.0),
        (inf, 3.0, 0.1, 10.0),
        (1e-3, 2.0, 0.1, 10.0),
        (1e-3, 1.0, 0.1, 10.0),
        (1e-3, nan, 0.1, 10.0),
        (1e-3, inf, 0.1, 10.0),
        (1e-3, 3.0, 0.0, 10.0),
        (1e-3, 3.0, -0.1, 10.0),
        (1e-3, 3.0, 0.1, 0.1),
        (1e-3, 3.0, 0.1, 0.05),
        (1e-3, 3.0, 0.1, inf),
        (1e-3, 3.0, nan, 10.0),
        (1e200, 3.0, 0.1, 10.0),
        (1e-3, 3.0, 1e-200, 10.0),
    ] {
        assert!(
            PowerLaw::<f64, 2>::new(s, a, lo, hi).is_err(),
            "accepted σ {s}, α {a}, band [{lo}, {hi}]"
        );
    }
    // In f32: ζ_max² overflows, 1/ζ_min² overflows, c (σ² = 1e36 in a narrow band) overflows.
    assert!(PowerLaw::<f32, 2>::new(1e-3, 3.0, 0.1, 1e20).is_err());
    assert!(PowerLaw::<f32, 2>::new(1e-3, 3.0, 1e-20, 1.0).is_err());
    assert!(PowerLaw::<f32, 2>::new(1e18, 3.0, 1.0, 1.0001).is_err());
    // A steep law (α = 300) is not bad input: c = e^{−2050} underflows, but p is formed in
    // logs, and its mass — all but e^{−28} of it within 10 % of ζ_min — is 2πσ² (radial
    // quadrature).
    let steep = PowerLaw::<f64, 2>::new(1e-3, 300.0, 1e-3, 10.0).unwrap();
    let peak = steep.value(&Vector2::new(1e-3, 0.0));
    assert!(peak.is_finite() && peak > 0.0);
    let mut f = |r: f64| TAU * r * steep.value(&Vector2::new(0.0, r));
    let mass = crate::common::quadrature::integrate(&mut f, 1e-3, 1.1e-3, 32, 1e-16);
    assert_close("steep ∫p", mass, TAU * 1e-6, Tol::new(0.0, 1e-9));
    // 3-D needs α > 3.
    assert!(PowerLaw::<f64, 3>::new(1e-3, 3.0, 0.1, 10.0).is_err());
    assert!(PowerLaw::<f64, 3>::new(1e-3, 3.01, 0.1, 10.0).is_ok());
}

proptest! {
    #![proptest_config(proptest_config(256))]

    /// `f32` against `f64` over the band (log-uniform ζ and band, α ∈ (2, 5)): finite,
    /// non-negative, and within `8 ε₃₂ (|ln c| + α|ln|ζ||)` relative (the rounding of the
    /// two logarithms that make `p`); 0 outside the band in both; never NaN, at 0 and at 10³⁰.
    #[test]
    fn f32_agrees_with_f64(
        (sigma, alpha, lo, ratio) in (1e-4f64..1.0, 2.05f64..5.0, 1e-2f64..10.0, 1.5f64..1e3),
        (t, phi) in (0.0f64..1.0, 0.0f64..TAU),
    ) {
        let hi = lo * ratio;
        let p64 = PowerLaw::<f64, 2>::new(sigma, alpha, lo, hi).unwrap();
        let p32 = PowerLaw::<f32, 2>::new(sigma as f32, alpha as f32, lo as f32, hi as f32).unwrap();
        // ζ log-uniform over [lo/2, 2 hi].
        let r = (lo / 2.0) * (4.0 * ratio).powf(t);
        let z = Vector2::new(r * phi.cos(), r * phi.sin());
        let z32 = z.map(|x| x as f32);
        let (a, b) = (f64::from(p32.value(&z32)), p64.value(&z.map(|x| f64::from(x as f32))));
        prop_assert!(a.is_finite() && a >= 0.0);
        let ln_c = (b.ln() + alpha * r.ln()).abs();
        let margin = (r / lo - 1.0).abs().min((r / hi - 1.0).abs());
        if b > 0.0 && margin > 1e-5 {
            let tol = 8.0 * f64::from(f32::EPSILON) * (ln_c + alpha * r.ln().abs() + 1.0);
            prop_assert!((a / b - 1.0).abs() <= tol, "f32 {a} vs f64 {b} (tol {tol})");
        } else if margin > 1e-5 {
            prop_assert_eq!(a, 0.0);
        }
        for far in [0.0f32, 1e-30, 1e30, f32::MAX] {
            let v = p32.value(&Vector2::new(far, 0.0));
            prop_assert!(v.is_finite() && v >= 0.0);
        }
    }
}

/// A rough conductor with the power-law PSD: the importance sampler (which draws from the
/// K-correlation lobes the PSD names) and uniform sampling of the sphere estimate the same
/// scattered reflectance, within 4.5 standard errors in every Mueller entry — at the
/// plane-wave level (`K = 2π p(h_t)`, no blur) and partially coherent (Gauss–Hermite blur of
/// order 12).
/// The plane wave's specular delta is left out of both (uniform sampling cannot reach it).
#[test]
fn bsdf_sampler_is_unbiased_through_the_named_form() {
    let psd = PowerLaw::<f64, 2>::new(0.02, 3.0, 2.0, 40.0).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(0.2, 3.5)).unwrap();
    let frame = Frame::from_normal(Vector3::new(0.1, -0.2, 1.0)).unwrap();
    let at = ShadingPoint::new(frame, 0.55).unwrap();
    let coherence = SurfaceCoherence::fixed(2.0).unwrap();
    let blur = GaussHermite::new(12).unwrap();
    let mut rng = SplitMix64(0x00fa_57a1);
    for (name, level) in [
        ("Full·PlaneWave", Level::ALL[6]),
        ("Full·Partial (Gauss–Hermite 12)", Level::ALL[7]),
    ] {
        let m = Material::with_blur(gold.clone(), level, blur.clone());
        let r = (frame.x() * 0.6 + frame.k() * 0.8).normalize();
        let pdf = 1.0 / TAU;
        let (batches, side) = (20, 40);
        let (mut sum_u, mut sq_u) = (Matrix4::<f64>::zeros(), Matrix4::<f64>::zeros());
        for _ in 0..batches {
            let mut batch = Matrix4::<f64>::zeros();
            for i in 0..side * side {
                let u = [
                    ((i % side) as f64 + rng.unit()) / side as f64,
                    ((i / side) as f64 + rng.unit()) / side as f64,
                ];
                if let Some(s) = m.sample_incident_uniform(&at, r, &coherence, u).unwrap() {
                    assert_eq!(s.sample.pdf, pdf);
                    batch += s.weight.matrix();
                }
            }
            let mean = batch / (side * side) as f64;
            sum_u += mean;
            sq_u += mean.component_mul(&mean);
        }
        let (mut sum_i, mut sq_i) = (Matrix4::<f64>::zeros(), Matrix4::<f64>::zeros());
        let ni = 20_000;
        let (mut scattered, mut outside) = (0usize, 0usize);
        for _ in 0..ni {
            let u = [rng.unit(), rng.unit(), rng.unit()];
            if let Some(s) = m
                .sample_incident(&at, r, &coherence, u[0], [u[1], u[2]])
                .unwrap()
            {
                assert!(s.sample.pdf > 0.0 && s.sample.pdf.is_finite(), "{name}");
                if s.sample.lobe.delta {
                    continue;
                }
                scattered += 1;
                let w = s.weight.matrix();
                outside += usize::from(w[(0, 0)] == 0.0);
                sum_i += w;
                sq_i += w.component_mul(&w);
            }
        }
        let [(mu, su), (mi, si)] =
            common::assert_same_mean(name, (sum_u, sq_u, batches), (sum_i, sq_i, ni), 4.5);
        assert!(mu[0] > 10.0 * su[0], "{name}: nothing scattered");
        println!(
            "{name}: scattered M00 uniform {:.4} ± {:.4}, sampler {:.4} ± {:.4} \
             ({scattered} scattered draws, {outside} of them outside the band)",
            mu[0], su[0], mi[0], si[0]
        );
    }
}

/// The batch path takes any PSD: with the power law (no lanes: its form is not an exact
/// Gaussian) `evaluate_batch` is the per-exit kernel, bit for bit.
#[test]
fn batch_is_the_per_exit_kernel() {
    let psd = PowerLaw::<f64, 2>::new(0.02, 3.0, 2.0, 40.0).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(0.2, 3.5)).unwrap();
    let surface = Frame::from_normal(Vector3::z()).unwrap();
    let travel = Vector3::new(0.3, 0.1, -1.0).normalize();
    let packet = WavePacket::from_stokes(
        Stokes::new(1.0, 0.3, -0.2, 0.1).unwrap(),
        CoherenceShape::isotropic(3.0).unwrap(),
        Frame::sp(travel, Vector3::z()).unwrap(),
        0.5,
    )
    .unwrap();
    let kernel = Kernel::<Full, _>::new(Partial(GaussHermite::<f64>::new(6).unwrap()));
    let exits: Vec<Vector3<f64>> = (0..13)
        .map(|i| {
            let t = 0.1 * i as f64;
            Vector3::new(0.9 * t.cos(), 0.5 * t.sin(), 0.4 + 0.04 * i as f64).normalize()
        })
        .collect();
    let (x, y, z): (Vec<f64>, Vec<f64>, Vec<f64>) = (
        exits.iter().map(|e| e.x).collect(),
        exits.iter().map(|e| e.y).collect(),
        exits.iter().map(|e| e.z).collect(),
    );
    let mut buf = vec![vec![0.0; exits.len()]; 8];
    let [a, b, c, d, e, f, g, h] = &mut buf[..] else {
        unreachable!()
    };
    let mut out = LobesSoa {
        specular: StokesSoa { s: [a, b, c, d] },
        scattered: StokesSoa { s: [e, f, g, h] },
    };
    let soa = DirectionsSoa {
        x: &x,
        y: &y,
        z: &z,
    };
    kernel
        .evaluate_batch(&gold, &packet, &surface, None, soa, &mut out, None)
        .unwrap();
    let mut lit = 0;
    for (i, exit) in exits.iter().enumerate() {
        let g = gmueller::interaction::Geometry::for_packet(&packet, &surface, *exit).unwrap();
        let one = kernel.evaluate(&gold, &packet, &g);
        let (sp, sc) = (one.specular.vector(), one.scattered.vector());
        for k in 0..4 {
            assert_eq!(out.specular.s[k][i], sp[k]);
            assert_eq!(out.scattered.s[k][i], sc[k]);
        }
        lit += usize::from(sc[0] > 0.0);
    }
    assert!(lit > 6, "only {lit} exits scatter");
}

/// A random medium with the 3-D power law: `σ_s` (whose quadrature nodes follow the named
/// K-correlation lobe) against adaptive quadrature of `dI/dV` over the sphere, the phase
/// matrix's normalisation, and the medium's sampler (furnace and χ²), at the plane-wave and
/// partially coherent levels.
#[test]
fn medium_through_the_named_form() {
    let light = WavePacket::from_stokes(
        Stokes::new(1.0, 0.2, -0.1, 0.3).unwrap(),
        CoherenceShape::isotropic(4.0).unwrap(),
        Frame::sp(Vector3::new(0.2, -0.1, 1.0).normalize(), Vector3::x()).unwrap(),
        0.6,
    )
    .unwrap();
    let k = light.wavenumber();
    // The band from 1 rad/µm to beyond 2k (≈ 21 rad/µm): the whole sphere of exits sees it.
    let medium = RandomMedium::new(
        PowerLaw::<f64, 3>::new(1e-3, 3.6, 1.0, 30.0).unwrap(),
        Dipole,
    );
    let rel = crate::medium::born::check_coefficient(
        "power law PlaneWave",
        &medium,
        Kernel::<Full, PlaneWave>::default(),
        &light,
        1.0,
        POWER_LAW_SIGMA_TOL,
    );
    println!("power law: σ_s relative error {rel:.1e} at k = {k:.3}");
    crate::medium::sampling::check(
        "power law PlaneWave",
        &medium,
        Kernel::<Full, PlaneWave>::default(),
        &light,
        1.0,
        0x5eed_0001,
    );
    // Gauss–Hermite of order 12: order 6 left the furnace at 1.058 ± 0.003 here (a 4 µm
    // coherence blurs by ζ_min/4, and 6 nodes a side miss the band's edge; the type docs).
    let partial = Kernel::<Full, _>::new(Partial(GaussHermite::new(12).unwrap()));
    crate::medium::sampling::check(
        "power law Partial (Gauss–Hermite 12)",
        &medium,
        partial,
        &light,
        1.0,
        0x5eed_0002,
    );
}

/// The medium's `σ_s` against adaptive quadrature, as for the crate's own PSDs
/// (`medium::born::scattering_coefficient_against_adaptive_quadrature`; measured here 3.9e-11).
const POWER_LAW_SIGMA_TOL: f64 = 1e-9;
