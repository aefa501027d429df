//! `bsdf::PathThroughput` and `bsdf::ShadingPoint` (issue 37):
//! - **Long `f32` chains stay valid.** Backward paths of up to 24 vertices drawn by
//!   `Material::sample_incident` on rough glass (both sides) and rough gold at `Full · Partial`,
//!   `f32`: at every vertex the camera's reading of random valid Stokes light through an
//!   `eval` (`contribution`) and arriving directly (`arriving`) is a valid Stokes vector
//!   (finite, `|S_pol| ≤ S0`), and agrees with the same product formed in `f64` from the
//!   chain's own matrices and frames (`T C M S`, `docs/renderer.md` §3) within
//!   `64 ε S0 + 10⁻³⁰` (ε of `f32`; worst seen 3.9·10⁻⁷ S0 in 7 200 vertices) — so the
//!   projection onto the cone moves it by no more than the chain's rounding. Counted: how often the raw `f32` product left the cone (the projection's
//!   work).
//! - **`ShadingPoint::new`** refuses a wavelength that is zero, negative, NaN or infinite; a
//!   positive wavelength whose wavenumber overflows (a subnormal `f32`) is refused by the
//!   material's calls with an error, not a panic.

use crate::common;
use gmueller::bsdf::{Material, PathThroughput, ShadingPoint, SurfaceCoherence};
use gmueller::frame::{Frame, frame_change_mueller};
use gmueller::interaction::{Level, RoughConductor, RoughDielectric};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::verify::rng::SplitMix64;
use nalgebra::{Matrix4, Vector3, Vector4};
use num_complex::Complex;

fn f64s(m: &Matrix4<f32>) -> Matrix4<f64> {
    m.map(f64::from)
}

/// The `f32` frame in `f64`, orthonormalised there (Gram–Schmidt; it moves by ~ε of `f32`).
fn frame64(f: &Frame<f32>) -> Frame<f64> {
    let v = |x: Vector3<f32>| x.map(f64::from);
    let x = v(f.x()).normalize();
    let y = v(f.y()) - x * x.dot(&v(f.y()));
    let y = y.normalize();
    Frame::new(x, y, x.cross(&y)).expect("an orthonormal frame")
}

/// A random valid Stokes vector of unit `S0` (degree of polarization up to 1).
fn stokes(rng: &mut SplitMix64) -> Stokes<f32> {
    let p = rng.unit();
    let z = 2.0 * rng.unit() - 1.0;
    let a = std::f64::consts::TAU * rng.unit();
    let r = (1.0 - z * z).sqrt();
    Stokes::new(
        1.0,
        (p * r * a.cos()) as f32,
        (p * r * a.sin()) as f32,
        (p * z) as f32,
    )
    .or_else(|_| Stokes::unpolarized(1.0))
    .unwrap()
}

fn check(got: &Stokes<f32>, want: &Vector4<f64>, what: &str) -> f64 {
    let v = got.vector().map(f64::from);
    assert!(v.iter().all(|x| x.is_finite()), "{what}: {v}");
    let pol = (v[1] * v[1] + v[2] * v[2] + v[3] * v[3]).sqrt();
    assert!(pol <= v[0], "{what}: |S_pol| {pol} > S0 {}", v[0]);
    // Three products of 4×4 matrices whose entries are bounded by their M₀₀ (Mueller
    // matrices; the chain is rescaled to M₀₀ = 1 at each vertex), each rounding by ≤ 4ε per
    // entry, and f64 frames that differ from the f32 ones by ~ε: 64 ε of f32 covers them.
    let tol = 64.0 * f64::from(f32::EPSILON) * want[0].abs() + 1e-30;
    assert!((v - want).amax() <= tol, "{what}: {v} vs f64 {want}");
    if want[0] > 0.0 {
        (v - want).amax() / want[0]
    } else {
        0.0
    }
}

#[test]
fn long_f32_chains_give_valid_stokes() {
    let psd = GaussianPsd::<f32, 2>::isotropic(0.01, 2.0).unwrap();
    let full_partial = Level::ALL[7];
    let materials = [
        Material::new(RoughDielectric::new(psd, 1.5).unwrap(), full_partial),
        Material::new(
            RoughConductor::new(psd, Complex::new(0.2, 3.5)).unwrap(),
            full_partial,
        )
        .two_sided(true),
    ];
    let sky = SurfaceCoherence::new(5.0_f32).unwrap();
    let mut rng = SplitMix64(0x7a7_4c4a);
    let (mut vertices, mut raw_outside, mut worst) = (0, 0, 0.0_f64);
    for path_index in 0..300 {
        let m = &materials[path_index % 2];
        let frame = Frame::from_normal(Vector3::new(0.1, -0.2, 1.0)).unwrap();
        let at = ShadingPoint::new(frame, 0.4 + 0.3 * rng.unit() as f32).unwrap();
        let t = rng.unit() * 1.4;
        let mut r = (frame.x() * t.sin() as f32 + frame.k() * t.cos() as f32).normalize();
        let mut path = PathThroughput::new(Frame::sp(r, frame.k()).unwrap());
        for _ in 0..24 {
            // Light sampling: a random direction on r̂'s side, random polarized light.
            let s_dir = {
                let (a, b) = (rng.unit() * 1.4, rng.unit() * std::f64::consts::TAU);
                let side = if r.dot(&frame.k()) > 0.0 { 1.0 } else { -1.0 };
                (frame.x() * (a.sin() * b.cos()) as f32
                    + frame.y() * (a.sin() * b.sin()) as f32
                    + frame.k() * (side * a.cos()) as f32)
                    .normalize()
            };
            let light = stokes(&mut rng);
            if let Ok(packet) = m.surface_packet(&at, light, s_dir, &sky) {
                let v = m.eval(&at, &packet, r).unwrap();
                let total = v.response.total();
                let got = path.contribution(&total, &v.geometry, &light);
                let c =
                    frame_change_mueller(&frame64(v.geometry.exit_sp()), &frame64(path.frame()));
                let want = f64s(&path.matrix().matrix())
                    * c.matrix()
                    * f64s(&total.matrix())
                    * light.vector().map(f64::from);
                let raw = (path.matrix().matrix()
                    * frame_change_mueller(v.geometry.exit_sp(), path.frame()).matrix()
                    * total.matrix())
                    * light.vector();
                raw_outside += usize::from(raw[1].hypot(raw[2]).hypot(raw[3]) > raw[0]);
                worst = worst.max(check(&got, &want, "contribution"));
                // Light arriving directly in the frame of the packet.
                let got = path.arriving(packet.frame(), &light);
                let c = frame_change_mueller(&frame64(packet.frame()), &frame64(path.frame()));
                let want =
                    f64s(&path.matrix().matrix()) * c.matrix() * light.vector().map(f64::from);
                worst = worst.max(check(&got, &want, "arriving"));
                vertices += 1;
            }
            let u = [rng.unit(), rng.unit(), rng.unit()].map(|x| x as f32);
            match m.sample_incident(&at, r, &sky, u[0], [u[1], u[2]]).unwrap() {
                Some(s) if path.is_alive() => {
                    path.advance(&s.weight, &s.geometry);
                    // The next vertex sees the light leaving toward this one.
                    r = -s.sample.direction;
                    // Keep the chain's scale near 1 (as Russian roulette's rescaling would).
                    let m00 = path.matrix().matrix()[(0, 0)];
                    if m00 > 0.0 && m00.is_finite() {
                        path.scale(1.0 / m00);
                    }
                }
                _ => break,
            }
        }
    }
    println!(
        "{vertices} vertices checked (worst |f32 − f64|/S0 {worst:e}); the raw f32 product left \
         the cone at {raw_outside}"
    );
    assert!(vertices > 3000, "{vertices}");
}

#[test]
fn shading_point_refuses_bad_wavelengths() {
    let frame = Frame::from_normal(Vector3::new(0.0_f32, 0.0, 1.0)).unwrap();
    for bad in [0.0_f32, -0.5, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert!(ShadingPoint::new(frame, bad).is_err(), "λ = {bad}");
    }
    // Positive but with an overflowing wavenumber: accepted here, refused by the material.
    let at = ShadingPoint::new(frame, 1e-40).unwrap();
    let psd = GaussianPsd::<f32, 2>::isotropic(0.01, 2.0).unwrap();
    let glass = Material::new(RoughDielectric::new(psd, 1.5).unwrap(), Level::ALL[7]);
    let sky = SurfaceCoherence::new(5.0_f32).unwrap();
    let up = Vector3::new(0.2_f32, 0.0, 1.0).normalize();
    assert!(
        glass
            .sample_incident(&at, up, &sky, 0.5, [0.5, 0.5])
            .is_err()
    );
    assert!(glass.pdf_incident(&at, up, &sky, up).is_err());
    assert!(glass.eval_incident(&at, up, &sky, up).is_err());
}

/// `PathThroughput::roulette`: a path at or above the threshold survives unscaled; below it,
/// with probability `M₀₀/threshold` (a draw `u` below it) and rescaled by the inverse, so the
/// expected throughput is unchanged; a dead path (0 or NaN) ends.
#[test]
fn roulette_keeps_the_expected_throughput() {
    let camera = Frame::from_normal(Vector3::new(0.0_f32, 0.0, 1.0)).unwrap();
    let path = |m00: f32| {
        let mut p = PathThroughput::new(camera);
        p.scale(m00);
        p
    };
    // At the threshold and above: survives for every u < 1, unscaled.
    for (m00, u) in [(0.05_f32, 0.999_f32), (0.8, 0.999), (1.0, 0.0)] {
        let mut p = path(m00);
        assert!(p.roulette(u, 0.05), "M00 {m00}, u {u}");
        assert_eq!(p.matrix().m00(), m00);
    }
    // Below: survival probability 0.01/0.05 = 0.2; the survivor carries M00 = 0.05.
    let mut p = path(0.01);
    assert!(p.roulette(0.199, 0.05));
    assert!(
        (p.matrix().m00() - 0.05).abs() < 1e-7,
        "{}",
        p.matrix().m00()
    );
    assert!(!path(0.01).roulette(0.2, 0.05));
    // The expectation over u on a fine grid: 0.2 · 0.05 = 0.01.
    let n = 10_000;
    let mean: f64 = (0..n)
        .map(|i| {
            let mut p = path(0.01);
            let u = (i as f32 + 0.5) / n as f32;
            if p.roulette(u, 0.05) {
                f64::from(p.matrix().m00())
            } else {
                0.0
            }
        })
        .sum::<f64>()
        / f64::from(n);
    assert!((mean - 0.01).abs() < 1e-6, "{mean}");
    // Dead paths end whatever u is.
    for m00 in [0.0_f32, -0.1, f32::NAN, f32::INFINITY] {
        assert!(!path(m00).roulette(0.0, 0.05), "M00 {m00}");
    }
    // No roulette without a positive threshold: a live path survives, unscaled.
    for threshold in [0.0_f32, -1.0, f32::NAN] {
        let mut p = path(0.01);
        assert!(p.roulette(0.999, threshold), "threshold {threshold}");
        assert_eq!(p.matrix().m00(), 0.01);
    }
}

/// `gather_*` add finite contributions (the same vectors as `contribution` / `arriving`) and
/// count, without adding, those that are not finite.
#[test]
fn gather_adds_finite_light_and_counts_the_rest() {
    let psd = GaussianPsd::<f32, 2>::isotropic(0.01, 2.0).unwrap();
    let gold = Material::new(
        RoughConductor::new(psd, Complex::new(0.2, 3.5)).unwrap(),
        Level::ALL[7],
    );
    let frame = Frame::from_normal(Vector3::new(0.1_f32, -0.2, 1.0)).unwrap();
    let at = ShadingPoint::new(frame, 0.55).unwrap();
    let r = (frame.k() + frame.x() * 0.3).normalize();
    let mut path = PathThroughput::new(Frame::sp(r, frame.k()).unwrap());
    let light = Stokes::new(1.0, 0.3, -0.2, 0.1).unwrap();
    let sun = (frame.k() - frame.x() * 0.3).normalize();
    let packet = gold.distant_packet(&at, light, 6.8e-5, sun).unwrap();
    let v = gold.eval(&at, &packet, r).unwrap();
    let seen = path.contribution(&v.response.total(), &v.geometry, &packet.stokes());
    let sky = path.arriving(packet.frame(), &light);
    path.gather_light(&v, &packet);
    path.gather_arriving(packet.frame(), &light);
    let want = seen.vector() + sky.vector();
    assert!(
        (path.radiance().vector() - want).norm() <= 1e-6 * want[0],
        "{want}"
    );
    assert_eq!(path.rejected(), 0);
    // A poisoned throughput: its contributions are refused and counted.
    let before = path.radiance();
    path.scale(f32::NAN);
    path.gather_light(&v, &packet);
    path.gather_arriving(packet.frame(), &light);
    assert_eq!(path.rejected(), 2);
    assert_eq!(path.radiance(), before);
}

/// `Material::sample_incident_uniform`: its weight is `eval_incident / p` with `p` the uniform
/// density of the exit's hemisphere (opaque, also the back of a two-sided one) or of the
/// sphere (an interface), its directions stay in that domain, and its mean weight agrees with
/// the importance sampler's (`sample_incident`) — two estimators of the same integral, one
/// without the sampler's proposals — within 4.5 standard errors in every Mueller entry.
#[test]
fn uniform_incident_sampling_is_the_unweighted_twin_of_sample_incident() {
    let psd = GaussianPsd::<f64, 2>::isotropic(0.05, 0.5).unwrap();
    let full_partial = Level::ALL[7];
    let gold = Material::new(
        RoughConductor::new(psd, Complex::new(0.2, 3.5)).unwrap(),
        full_partial,
    )
    .two_sided(true);
    let glass = Material::new(RoughDielectric::new(psd, 1.5).unwrap(), full_partial);
    let frame = Frame::from_normal(Vector3::new(0.1, -0.2, 1.0)).unwrap();
    let at = ShadingPoint::new(frame, 0.55).unwrap();
    // A fixed width (no horizon rule, which would raise it to 16/(k cos²θ) ≈ 5.6 µm at 60°):
    // wide specular lobes that uniform sampling resolves.
    let coherence = SurfaceCoherence::fixed(0.5).unwrap();
    let mut rng = SplitMix64(0x0b5e_55ed);
    for (name, m, exit, domain) in [
        ("gold, front", &gold, 0.6, 1.0),
        ("gold, back (two-sided)", &gold, -0.9, 1.0),
        ("glass, outside", &glass, 0.5, 2.0),
        ("glass, inside", &glass, -0.7, 2.0),
    ] {
        let up = if exit > 0.0 { 1.0 } else { -1.0 };
        let r = (frame.x() * (1.0_f64 - exit * exit).sqrt() + frame.k() * exit).normalize();
        let pdf = 1.0 / (domain * std::f64::consts::TAU);
        // 20 batches, each a jittered 50 × 50 grid of u (stratified: the transmitted
        // specular lobe, ~10⁻⁴ of the sphere, is what dominates the variance); the standard
        // error from the spread of the batch means.
        let (batches, side) = (20, 50);
        let (mut sum_u, mut sq_u) = (Matrix4::<f64>::zeros(), Matrix4::<f64>::zeros());
        for _ in 0..batches {
            let mut batch = Matrix4::<f64>::zeros();
            for i in 0..side * side {
                let u = [
                    ((i % side) as f64 + rng.unit()) / side as f64,
                    ((i / side) as f64 + rng.unit()) / side as f64,
                ];
                let Some(s) = m.sample_incident_uniform(&at, r, &coherence, u).unwrap() else {
                    continue;
                };
                let d = s.sample.direction;
                assert_eq!(s.sample.pdf, pdf, "{name}");
                assert!(!s.sample.lobe.delta);
                if domain == 1.0 {
                    assert!(d.dot(&frame.k()) * up > 0.0, "{name}: {d}");
                }
                let v = m.eval_incident(&at, r, &coherence, d).unwrap();
                assert_eq!(s.weight, v.response.total().scaled(1.0 / pdf), "{name}");
                batch += s.weight.matrix();
            }
            let mean = batch / (side * side) as f64;
            sum_u += mean;
            sq_u += mean.component_mul(&mean);
        }
        let n = batches;
        let (mut sum_i, mut sq_i) = (Matrix4::<f64>::zeros(), Matrix4::<f64>::zeros());
        let ni = 10_000;
        for _ in 0..ni {
            let u = [rng.unit(), rng.unit(), rng.unit()];
            if let Some(s) = m
                .sample_incident(&at, r, &coherence, u[0], [u[1], u[2]])
                .unwrap()
            {
                let w = s.weight.matrix();
                sum_i += w;
                sq_i += w.component_mul(&w);
            }
        }
        let [(mu, su), (mi, si)] =
            common::assert_same_mean(name, (sum_u, sq_u, n), (sum_i, sq_i, ni), 4.5);
        println!(
            "{name}: albedo (M00) uniform {:.4} ± {:.4}, sampler {:.4} ± {:.4}",
            mu[0], su[0], mi[0], si[0]
        );
    }
}

/// `sample_incident_uniform` in `f32`, at grazing exits and φ ≠ 0 and over the whole
/// square of uniforms (its edges included): every draw is `None` only within `√ε` of the
/// plane, otherwise a finite weight, the exact density and a direction in the domain; and
/// the weight is `eval_incident / p` bit for bit.
#[test]
fn uniform_incident_sampling_in_f32() {
    let psd = GaussianPsd::<f32, 2>::isotropic(0.01, 2.0).unwrap();
    let full_partial = Level::ALL[7];
    let gold = Material::new(
        RoughConductor::new(psd, Complex::new(0.2, 3.5)).unwrap(),
        full_partial,
    );
    let glass = Material::new(RoughDielectric::new(psd, 1.5).unwrap(), full_partial);
    let frame = Frame::from_normal(Vector3::new(0.3_f32, -0.2, 1.0)).unwrap();
    let at = ShadingPoint::new(frame, 0.55).unwrap();
    let sky = SurfaceCoherence::new(20.0_f32).unwrap();
    let (mut drawn, mut refused) = (0, 0);
    for (m, domain) in [(&gold, 1.0_f32), (&glass, 2.0)] {
        for (theta, phi) in [
            (0.0_f32, 0.0_f32),
            (1.2, 0.7),
            (1.55, -2.0),
            (std::f32::consts::FRAC_PI_2 - 1e-4, 2.9),
        ] {
            let r = (frame.x() * (theta.sin() * phi.cos())
                + frame.y() * (theta.sin() * phi.sin())
                + frame.k() * theta.cos())
            .normalize();
            for i in 0..=20 {
                for j in 0..=8 {
                    let u = [i as f32 / 20.0, j as f32 / 8.0];
                    let Some(s) = m.sample_incident_uniform(&at, r, &sky, u).unwrap() else {
                        refused += 1;
                        continue;
                    };
                    let d = s.sample.direction;
                    let cos = d.dot(&frame.k());
                    assert!(cos.abs() > f32::EPSILON.sqrt(), "{d}");
                    assert!(domain == 2.0 || cos > 0.0, "{d} below an opaque surface");
                    assert_eq!(s.sample.pdf, 1.0 / (domain * std::f32::consts::TAU));
                    assert!(
                        s.weight.matrix().iter().all(|x| x.is_finite()),
                        "{:?}",
                        s.weight
                    );
                    let v = m.eval_incident(&at, r, &sky, d).unwrap();
                    assert_eq!(s.weight, v.response.total().scaled(1.0 / s.sample.pdf));
                    drawn += 1;
                }
            }
        }
    }
    // u₀ = 0 on the hemisphere (z = 0) and u₀ = 0.5 on the sphere are refused, nothing else.
    assert_eq!(
        refused,
        4 * 9 * 2,
        "{refused} refused of {}",
        drawn + refused
    );
}
