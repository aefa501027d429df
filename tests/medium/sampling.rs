//! The medium's direction sampler (`PhaseFunction::sample` / `pdf`): `pdf` integrates to 1 over
//! the sphere (adaptive quadrature in Lambert coordinates about d̂); `sample` draws from `pdf`
//! (Pearson's chi-square on seeded draws, cells in `(|v|, φ)` refined about the lobe's scale,
//! expected counts from 2-D adaptive quadrature of `pdf` over each cell — not from its radial
//! form — 99.9 % Wilson–Hilferty quantile), and the same test rejects a density whose truncation
//! mass is left out; `pdf(sample.direction) == sample.pdf`; `weight = F/pdf`; the Monte Carlo
//! estimate of `∫ [F S]₀ dΩ` from the sampler is `S0` within its standard error; extreme
//! uniforms give finite unit directions.

use crate::common;

use std::f64::consts::TAU;

use common::chi2::{chi_square, chi2_quantile_999};
use common::{SplitMix64, Tol, assert_close};
use gmueller::frame::Frame;
use gmueller::interaction::polarization::{PolarizationModel, Throughput};
use gmueller::interaction::{Full, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave};
use gmueller::medium::{Dipole, PhaseFunction, RandomMedium, VolumeCoherence, VolumeIncident};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{GaussianPsd, KCorrelation};
use gmueller::stokes::Stokes;
use gmueller::verify::quadrature::integrate;
use nalgebra::{Matrix2, Matrix3, Vector3};

const N: usize = 100_000;

fn frame() -> Frame<f64> {
    Frame::from_direction_and_x(Vector3::new(0.3, -0.4, 0.87), Vector3::new(1.0, 0.2, 0.0)).unwrap()
}

fn packet(
    stokes: Stokes<f64>,
    tx: Matrix2<f64>,
    ty: Matrix2<f64>,
    sigma_zz: f64,
) -> WavePacket<f64> {
    WavePacket::new(
        stokes,
        CoherenceShape::new(tx).unwrap(),
        CoherenceShape::new(ty).unwrap(),
        frame(),
        0.6,
    )
    .unwrap()
    .with_longitudinal_coherence(sigma_zz)
    .unwrap()
}

/// `(|v|, φ)` of a direction about the packet's d̂: `|v| = k|r̂ − d̂|`, φ its azimuth in (x̂, ŷ).
fn coords(f: &Frame<f64>, k: f64, r: &Vector3<f64>) -> (f64, f64) {
    let u = k * (r - f.k()).norm();
    let phi = r.dot(&f.y()).atan2(r.dot(&f.x())).rem_euclid(TAU);
    (u.min(2.0 * k), phi)
}

/// The direction of `(|v|, φ)`.
fn direction(f: &Frame<f64>, k: f64, u: f64, phi: f64) -> Vector3<f64> {
    let a2 = (u / (2.0 * k)).powi(2).min(1.0);
    let (cos, sin) = (1.0 - 2.0 * a2, 2.0 * (a2 * (1.0 - a2)).sqrt());
    (f.k() * cos + (f.x() * phi.cos() + f.y() * phi.sin()) * sin).normalize()
}

/// Radial edges on `[0, 2k]`: 12 of equal area (the uniform part), and `s · m` for the lobe
/// scale `s` and multiples `m`.
fn radial_edges(k: f64, s: f64) -> Vec<f64> {
    let mut e: Vec<f64> = (0..=12)
        .map(|i| 2.0 * k * (f64::from(i) / 12.0).sqrt())
        .collect();
    for m in [
        0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.5, 7.0, 12.0, 25.0, 60.0,
    ] {
        if s * m < 2.0 * k {
            e.push(s * m);
        }
    }
    e.sort_by(f64::total_cmp);
    e.dedup_by(|a, b| (*a - *b).abs() < 1e-9 * k);
    e
}

/// Expected probabilities of the cells `radial × 8 sectors` under `pdf`, `∫∫ pdf u du dφ/k²`.
fn probabilities(
    f: &Frame<f64>,
    k: f64,
    edges: &[f64],
    pdf: &dyn Fn(&Vector3<f64>) -> f64,
) -> Vec<f64> {
    let sectors = 8;
    let mut p = Vec::new();
    for w in edges.windows(2) {
        for j in 0..sectors {
            let (p0, p1) = (TAU * f64::from(j) / 8.0, TAU * f64::from(j + 1) / 8.0);
            let mut outer = |u: f64| {
                let mut inner = |phi: f64| pdf(&direction(f, k, u, phi));
                u / (k * k) * integrate(&mut inner, p0, p1, 1, 1e-12)
            };
            p.push(integrate(&mut outer, w[0], w[1], 2, 1e-11));
        }
    }
    p
}

fn counts(f: &Frame<f64>, k: f64, edges: &[f64], draws: &[Vector3<f64>]) -> Vec<usize> {
    let mut c = vec![0usize; (edges.len() - 1) * 8];
    for r in draws {
        let (u, phi) = coords(f, k, r);
        let i = edges.partition_point(|&e| e <= u).clamp(1, edges.len() - 1) - 1;
        let j = ((phi / TAU * 8.0) as usize).min(7);
        c[i * 8 + j] += 1;
    }
    c
}

/// The sampler of one medium and level: pdf integral, chi-square, exactness, weights, the Monte
/// Carlo furnace. Returns (χ², quantile).
pub(crate) fn check<P, Pol, Coh>(
    name: &str,
    medium: &RandomMedium<P, Dipole>,
    kernel: Kernel<Pol, Coh>,
    light: &WavePacket<f64>,
    scale: f64,
    seed: u64,
) -> (f64, f64)
where
    P: gmueller::psd::Psd<f64, 3>,
    Pol: PolarizationModel,
    Coh: VolumeCoherence<f64, P>,
{
    let phase = PhaseFunction::new(medium, kernel);
    let inc: VolumeIncident<f64, Pol, Coh> = phase.prepare(light).unwrap();
    let (f, k) = (*light.frame(), light.wavenumber());
    let edges = radial_edges(k, scale);
    let pdf = |r: &Vector3<f64>| phase.pdf(&inc, r);
    let probs = probabilities(&f, k, &edges, &pdf);
    let total: f64 = probs.iter().sum();
    assert_close(
        &format!("{name}: ∫ pdf dΩ"),
        total,
        1.0,
        Tol::new(1e-9, 0.0),
    );
    let mut rng = SplitMix64(seed);
    let s = <Pol::Throughput<f64> as Throughput<f64>>::light(&light.stokes());
    let (mut mean, mut sq) = (0.0, 0.0);
    let draws: Vec<Vector3<f64>> = (0..N)
        .map(|_| {
            let d = phase.sample(&inc, rng.unit(), [rng.unit(), rng.unit()]);
            assert!(
                (d.direction.norm() - 1.0).abs() < 1e-14,
                "{name}: not a unit direction"
            );
            assert_eq!(
                phase.pdf(&inc, &d.direction),
                d.pdf,
                "{name}: pdf(sample) ≠ sample.pdf"
            );
            // weight = F/pdf.
            let v = phase.eval(&inc, d.direction).unwrap().phase;
            let w = v.scaled(d.pdf.recip());
            assert_eq!(w, d.weight, "{name}: weight ≠ F/pdf");
            let x = <Pol::Throughput<f64> as Throughput<f64>>::intensity(&d.weight.apply(&s))
                / light.stokes().s0();
            mean += x;
            sq += x * x;
            d.direction
        })
        .collect();
    let n = N as f64;
    let (mean, var) = (mean / n, sq / n - (mean / n).powi(2));
    let se = (var / n).sqrt();
    println!(
        "{name}: MC ∫[F S]₀/S0 = {mean:.5} ± {se:.5}; uniform weight {:.3}",
        inc.uniform_weight()
    );
    assert!(
        (mean - 1.0).abs() <= 4.0 * se + 1e-12,
        "{name}: furnace {mean} ± {se}"
    );
    let c = counts(&f, k, &edges, &draws);
    let (chi2, dof) = chi_square(&c, &probs, N);
    let q = chi2_quantile_999(dof.max(1));
    println!("{name}: χ² = {chi2:.1} on {dof} dof (99.9 % quantile {q:.1})");
    assert!(chi2 <= q, "{name}: χ² = {chi2} > {q} on {dof} dof");
    (chi2, q)
}

fn iso(w: f64) -> Matrix2<f64> {
    Matrix2::identity() * (w * w)
}

#[test]
fn gaussian_media_every_coherence_level() {
    let un = Stokes::unpolarized(1.0).unwrap();
    let light = packet(un, iso(5.0), iso(5.0), 3.0);
    for (ell, seed) in [(0.02, 1), (0.3, 2), (3.0, 3)] {
        let m = RandomMedium::new(GaussianPsd::<f64, 3>::isotropic(1e-3, ell).unwrap(), Dipole);
        let s = 1.0 / ell;
        check(
            &format!("ℓ = {ell} PlaneWave"),
            &m,
            Kernel::<Full, PlaneWave>::default(),
            &light,
            s,
            seed,
        );
        check(
            &format!("ℓ = {ell} Partial"),
            &m,
            Kernel::<Full, Partial>::default(),
            &light,
            s,
            seed + 10,
        );
        check(
            &format!("ℓ = {ell} Incoherent"),
            &m,
            Kernel::<Intensity, Incoherent>::default(),
            &light,
            0.2,
            seed + 20,
        );
    }
}

#[test]
fn anisotropic_polarized_kcorrelation_and_mixture() {
    let polarized = Stokes::new(1.0, 0.4, -0.3, 0.5).unwrap();
    let tx = Matrix2::new(30.0, 12.0, 12.0, 9.0);
    let light = packet(polarized, tx, tx, 1.0);
    let corr = gmueller::gaussian::Gaussian::new(Matrix3::new(
        4.0, 0.5, -0.3, 0.5, 0.3, 0.1, -0.3, 0.1, 1.2,
    ))
    .unwrap();
    let aniso = RandomMedium::new(
        GaussianPsd::from_autocorrelation(1e-6, &corr).unwrap(),
        Dipole,
    );
    check(
        "anisotropic Full·Partial",
        &aniso,
        Kernel::<Full, Partial>::default(),
        &light,
        0.5,
        7,
    );
    check(
        "anisotropic OneShape·PlaneWave",
        &aniso,
        Kernel::<OneShape, PlaneWave>::default(),
        &light,
        0.5,
        8,
    );
    let kc = RandomMedium::new(KCorrelation::<f64, 3>::new(1e-6, 1.0, 2.4).unwrap(), Dipole);
    check(
        "K-correlation PlaneWave",
        &kc,
        Kernel::<Full, PlaneWave>::default(),
        &light,
        1.0,
        9,
    );
    check(
        "K-correlation Incoherent",
        &kc,
        Kernel::<Full, Incoherent>::default(),
        &light,
        0.3,
        10,
    );
    let (mix, _) = KCorrelation::<f64, 3>::new(1e-6, 1.0, 3.0)
        .unwrap()
        .mixture_fit(12)
        .unwrap();
    let mix = RandomMedium::new(mix, Dipole);
    check(
        "mixture Full·Partial",
        &mix,
        Kernel::<Full, Partial>::default(),
        &light,
        1.0,
        11,
    );
}

/// The chi-square test can fail: a density that leaves out the truncation mass of the lobe
/// (`F(2k) < 1` for a lobe as wide as the sphere) is rejected by the same cells and draws.
#[test]
fn chi_square_rejects_a_density_without_the_truncation_mass() {
    let light = packet(Stokes::unpolarized(1.0).unwrap(), iso(5.0), iso(5.0), 3.0);
    let m = RandomMedium::new(
        GaussianPsd::<f64, 3>::isotropic(1e-3, 0.12).unwrap(),
        Dipole,
    );
    let phase = PhaseFunction::new(&m, Kernel::<Full, PlaneWave>::default());
    let inc = phase.prepare(&light).unwrap();
    let (f, k) = (*light.frame(), light.wavenumber());
    let edges = radial_edges(k, 1.0 / 0.12);
    // The lobe: the density minus the uniform part; its truncation mass F = 1 − e^{−2k²/s²}.
    let w_u = inc.uniform_weight();
    let s2 = 1.0 / (0.12 * 0.12);
    let mass = -(-2.0 * k * k / s2).exp_m1();
    assert!(
        mass < 0.99 && w_u < 0.9,
        "a case where the mass matters: F = {mass}, w_u = {w_u}"
    );
    let wrong = |r: &Vector3<f64>| {
        let p = phase.pdf(&inc, r);
        w_u / (2.0 * TAU) + (p - w_u / (2.0 * TAU)) * mass
    };
    let mut rng = SplitMix64(5);
    let draws: Vec<Vector3<f64>> = (0..N)
        .map(|_| {
            phase
                .sample(&inc, rng.unit(), [rng.unit(), rng.unit()])
                .direction
        })
        .collect();
    let c = counts(&f, k, &edges, &draws);
    let good = probabilities(&f, k, &edges, &|r| phase.pdf(&inc, r));
    let bad = probabilities(&f, k, &edges, &wrong);
    let (x_good, dof) = chi_square(&c, &good, N);
    let (x_bad, dof_bad) = chi_square(&c, &bad, N);
    println!(
        "right pdf: χ² = {x_good:.1} ({dof} dof); without the mass: χ² = {x_bad:.1} ({dof_bad} dof)"
    );
    assert!(x_good <= chi2_quantile_999(dof));
    assert!(x_bad > chi2_quantile_999(dof_bad));
}

/// Uniforms at and beyond the ends of `[0, 1)` (and NaN) give finite unit directions with a
/// finite positive pdf, in both precisions.
#[test]
fn extreme_uniforms() {
    fn run<T: gmueller::Real>() {
        let f = Frame::<T>::from_direction_and_x(
            Vector3::new(0.3, -0.4, 0.87).map(T::lit),
            Vector3::x(),
        )
        .unwrap();
        let light = WavePacket::from_stokes(
            Stokes::unpolarized(T::one()).unwrap(),
            CoherenceShape::isotropic(T::lit(5.0)).unwrap(),
            f,
            T::lit(0.6),
        )
        .unwrap()
        .with_longitudinal_coherence(T::lit(2.0))
        .unwrap();
        let m = RandomMedium::new(
            GaussianPsd::<T, 3>::isotropic(T::lit(1e-3), T::lit(2.0)).unwrap(),
            Dipole,
        );
        let phase = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
        let inc = phase.prepare(&light).unwrap();
        let specials = [
            T::zero(),
            T::one() - T::EPSILON,
            T::one(),
            T::lit(2.0),
            -T::one(),
            T::lit(f64::NAN),
            T::lit(0.5),
        ];
        for &a in &specials {
            for &b in &specials {
                for &c in &specials {
                    let s = phase.sample(&inc, a, [b, c]);
                    assert!(
                        (s.direction.norm() - T::one()).abs() < T::lit(1e-5),
                        "{:?}",
                        s.direction
                    );
                    assert!(s.pdf.is_finite() && s.pdf > T::zero(), "pdf {:?}", s.pdf);
                    assert!(s.weight.matrix().iter().all(|x| x.is_finite()));
                }
            }
        }
    }
    run::<f64>();
    run::<f32>();
}
