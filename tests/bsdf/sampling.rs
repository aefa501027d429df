//! Verifies the renderer layer's samplers (`gmueller::bsdf`) against their own densities, in
//! both hemispheres and both tracing directions: Pearson's chi-square on 100 000 seeded draws
//! per case (Cartesian bins in the projected disk of each hemisphere, edges at the quantiles
//! of a separate pilot draw so that narrow lobes are bracketed, expected counts from adaptive
//! Gauss–Legendre quadrature of `pdf`, `tests/common/chi2.rs`), for every lobe kind: rough glass
//! from above and below (Snell lobes, total internal reflection), a conductor, K-correlation,
//! Gaussian-mixture and grating PSDs, the smooth limit, the plane-wave level's Dirac lobes
//! (drawn with their probability) and the two-shape Full level. The same test rejects a
//! density with the `cos θ` Jacobian applied twice. Also: `sample.pdf == pdf(sample.direction)`
//! bit for bit, and the fraction of delta draws against the part probabilities — including a
//! Dirac order of the scattered part beyond first order, where the projected disk takes a
//! share of that part's draws (a downstream PSD with an origin order and an autocorrelation:
//! the reported probability was the part's whole, 0.0288 against 0.0211 drawn).

use crate::common;

use common::chi2::{self, Disk, Grid};
use common::rng::SplitMix64;
use gmueller::bsdf::{Bsdf, LobeSampler, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::{
    Full, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave, RoughConductor,
    RoughDielectric, SmoothDielectric,
};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{GaussHermite, GaussianMixturePsd, GaussianPsd, Grating, KCorrelation};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector2, Vector3};
use num_complex::Complex;

const N: usize = 100_000;
const LAMBDA: f64 = 0.5;

use crate::common::shading::{dir, tilted_frame as frame};

fn disk(f: &Frame<f64>) -> Disk {
    Disk {
        t1: f.x(),
        t2: f.y(),
        n: f.k(),
    }
}

/// Quantile edges of a pilot draw (seed distinct from the test's) merged with a coarse grid,
/// per hemisphere that the pilot reaches.
pub(crate) fn grids(disk: &Disk, draw: &mut dyn FnMut(usize) -> Option<Vector3<f64>>) -> Vec<Grid> {
    let mut per_side: [(Vec<f64>, Vec<f64>); 2] = Default::default();
    for i in 0..4000 {
        if let Some(d) = draw(i) {
            let (side, u) = disk.coords(&d);
            let s = usize::from(side < 0.0);
            per_side[s].0.push(u.x);
            per_side[s].1.push(u.y);
        }
    }
    let qs = [
        0.005, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.98, 0.995,
    ];
    let mut out = Vec::new();
    for (s, (xs, ys)) in per_side.iter_mut().enumerate() {
        let side = if s == 0 { 1.0 } else { -1.0 };
        let edges_of = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            let mut e = chi2::edges(8, &[], &[]);
            if v.len() > 50 {
                for q in qs {
                    e.push(v[((v.len() - 1) as f64 * q) as usize]);
                }
            }
            e.sort_by(f64::total_cmp);
            e.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
            e
        };
        out.push(Grid {
            side,
            ex: edges_of(xs),
            ey: edges_of(ys),
        });
    }
    out
}

/// Draws from `sampler` with the uniforms of `seed`: non-delta directions, checking
/// `pdf(direction) == pdf` on the way; delta draws are counted.
struct Draws<'s, 'a> {
    sampler: &'s LobeSampler<'a, f64>,
    rng: SplitMix64,
    deltas: usize,
}

impl Draws<'_, '_> {
    fn next(&mut self) -> Option<Vector3<f64>> {
        let (a, b, c) = (self.rng.unit(), self.rng.unit(), self.rng.unit());
        let s = self.sampler.sample(a, [b, c])?;
        if s.lobe.delta {
            self.deltas += 1;
            return None;
        }
        assert_eq!(self.sampler.pdf(&s.direction), s.pdf, "pdf of the sample");
        assert!(s.pdf > 0.0 && s.pdf.is_finite());
        assert!((s.direction.norm() - 1.0).abs() < 1e-12);
        Some(s.direction)
    }
}

/// The chi-square test of one sampler (module docs); returns the delta fraction drawn.
pub(crate) fn check(name: &str, f: &Frame<f64>, sampler: &LobeSampler<'_, f64>, seed: u64) -> f64 {
    let disk = disk(f);
    let mut pilot = Draws {
        sampler,
        rng: SplitMix64(seed ^ 0x5eed),
        deltas: 0,
    };
    let grids = grids(&disk, &mut |_| pilot.next());
    let mut draws = Draws {
        sampler,
        rng: SplitMix64(seed),
        deltas: 0,
    };
    let pdf = |d: &Vector3<f64>| sampler.pdf(d);
    let out = chi2::test(&disk, &grids, &pdf, N, &mut |_| draws.next());
    println!(
        "{name}: chi2 {:.1} dof {} (99.9% {:.1}), parts {:?}",
        out.chi2,
        out.dof,
        out.quantile,
        sampler.part_probabilities()
    );
    assert!(
        out.passes(),
        "{name}: chi2 {} > {} (dof {})",
        out.chi2,
        out.quantile,
        out.dof
    );
    assert!(out.dof >= 20, "{name}: too few bins ({})", out.dof);
    draws.deltas as f64 / N as f64
}

/// The fraction of delta draws agrees with the probability of the delta parts.
fn check_delta_fraction(name: &str, fraction: f64, expected: f64) {
    let se = (expected * (1.0 - expected) / N as f64).sqrt();
    assert!(
        (fraction - expected).abs() <= 4.5 * se + 1e-12,
        "{name}: delta fraction {fraction} vs {expected} (s.e. {se})"
    );
}

fn glass() -> RoughDielectric<f64, GaussianPsd<f64, 2>> {
    RoughDielectric::new(GaussianPsd::isotropic(0.02, 1.0).unwrap(), 1.5).unwrap()
}

fn unpolarized() -> Stokes<f64> {
    Stokes::unpolarized(1.0).unwrap()
}

#[test]
fn rough_glass_forward_from_both_sides() {
    let f = frame();
    let m = glass();
    let b = Bsdf::new(&m, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let c = SurfaceCoherence::new(3.0).unwrap();
    // From the air at 35°; from inside at 25° and beyond the critical angle (41.8°) at 55°.
    for (i, (deg, side)) in [(35.0, 1.0), (25.0, -1.0), (55.0, -1.0)].iter().enumerate() {
        let s = dir(&f, *deg, 30.0, *side);
        let packet = b.surface_packet(unpolarized(), s, &c).unwrap();
        let inc = b.prepare(&packet).unwrap();
        let sampler = b.exit_sampler(&inc).unwrap();
        check(
            &format!("glass forward {deg}° side {side}"),
            &f,
            &sampler,
            11 + i as u64,
        );
    }
}

#[test]
fn rough_glass_backward_from_both_sides() {
    let f = frame();
    let m = glass();
    let b = Bsdf::new(&m, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let c = SurfaceCoherence::new(3.0).unwrap();
    for (i, (deg, side)) in [(40.0, 1.0), (30.0, -1.0), (60.0, -1.0)].iter().enumerate() {
        let r = dir(&f, *deg, -50.0, *side);
        let sampler = b.incident_sampler(r, &c).unwrap();
        check(
            &format!("glass backward {deg}° side {side}"),
            &f,
            &sampler,
            21 + i as u64,
        );
    }
}

/// Backward, the kernel's specular lobe goes as `cos θ_o` in ŝ while a projected-disk density
/// goes as `cos θ_i`: without the angle chart the weights `M/p` of a lobe reaching the horizon
/// have a log-divergent variance (at 85° and 20 µm the largest of 200 000 was 320× the mean).
/// With it they stay within a small multiple of the mean. The same under the horizon rule
/// (`SurfaceCoherence::new`), where the light's width varies across the lobe and a quarter of
/// the draws come from a lobe twice as wide (without it: 43× the mean at 80°, 2 µm).
#[test]
fn grazing_backward_specular_weights_stay_bounded() {
    let f = frame();
    let m = RoughDielectric::new(GaussianPsd::isotropic(0.008, 3.0).unwrap(), 1.5).unwrap();
    let b = Bsdf::new(&m, Kernel::<Full, Partial>::default(), f, 0.55).unwrap();
    for (w, deg, rule) in [
        (20.0, 85.0, false),
        (20.0, 88.0, false),
        (2.0, 80.0, false),
        (2.0, 85.0, false),
        (20.0, 85.0, true),
        (20.0, 88.0, true),
        (2.0, 80.0, true),
        (2.0, 85.0, true),
    ] {
        let c = if rule {
            SurfaceCoherence::new(w).unwrap()
        } else {
            SurfaceCoherence::fixed(w).unwrap()
        };
        let r = dir(&f, deg, 20.0, 1.0);
        let sampler = b.incident_sampler(r, &c).unwrap();
        let p = sampler.part_probabilities();
        let sampler = sampler.with_part_probabilities([p[0], p[1], 0.0, 0.0]);
        let mut rng = SplitMix64(7);
        let (mut sum, mut max) = (0.0, 0.0f64);
        let n = 20_000;
        for _ in 0..n {
            if let Some(s) = sampler.sample(rng.unit(), [rng.unit(), rng.unit()]) {
                let (weight, _) = b.incident_weight(r, &c, &s).unwrap();
                sum += weight.m00();
                max = max.max(weight.m00());
            }
        }
        let mean = sum / f64::from(n);
        println!("w {w} µm (rule {rule}), θ_o {deg}°: mean weight {mean:.4}, max {max:.3}");
        assert!(
            mean > 0.0 && max <= 20.0 * mean,
            "w {w}, {deg}°: max {max} vs mean {mean}"
        );
    }
}

/// Pearson's chi-square of a sampler against its density on a grid in the **angles** `(θ, φ)`
/// of the hemisphere `side` about the surface frame (where `pdf sin θ` stays bounded at the
/// horizon, unlike `pdf/cos θ` in the projected disk): 24 × 24 cells at the quantiles of a
/// pilot draw, expected probabilities by 12 × 12-point Gauss–Legendre per cell, one more bin
/// for everything else (the other hemisphere, evanescent draws).
fn check_angles(name: &str, f: &Frame<f64>, sampler: &LobeSampler<'_, f64>, side: f64, seed: u64) {
    use common::quadrature::gauss_legendre;
    let angles = |d: &Vector3<f64>| {
        let c = side * d.dot(&f.k());
        let (x, y) = (d.dot(&f.x()), d.dot(&f.y()));
        (c > 0.0).then(|| (x.hypot(y).atan2(c), y.atan2(x)))
    };
    let mut rng = SplitMix64(seed ^ 0x5eed);
    let mut pilot: Vec<(f64, f64)> = (0..20_000)
        .filter_map(|_| sampler.sample(rng.unit(), [rng.unit(), rng.unit()]))
        .filter_map(|s| angles(&s.direction))
        .collect();
    let quantiles = |v: &mut Vec<f64>, lo: f64, hi: f64| {
        v.sort_by(f64::total_cmp);
        let mut e: Vec<f64> = (1..24).map(|i| v[i * v.len() / 24]).collect();
        e.insert(0, lo);
        e.push(hi);
        e.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
        e
    };
    let mut th: Vec<f64> = pilot.iter().map(|p| p.0).collect();
    let theta_lo = th.iter().copied().fold(f64::MAX, f64::min) * 0.9;
    let et = quantiles(&mut th, theta_lo, std::f64::consts::FRAC_PI_2);
    let mut ph: Vec<f64> = pilot.drain(..).map(|p| p.1).collect();
    let phi_lo = ph.iter().copied().fold(f64::MAX, f64::min) - 0.05;
    let phi_hi = ph.iter().copied().fold(f64::MIN, f64::max) + 0.05;
    let ep = quantiles(&mut ph, phi_lo, phi_hi);
    let rule = gauss_legendre(12);
    let dir =
        |t: f64, p: f64| (f.x() * p.cos() + f.y() * p.sin()) * t.sin() + f.k() * (side * t.cos());
    let mut probs = Vec::new();
    for ti in 0..et.len() - 1 {
        for pi in 0..ep.len() - 1 {
            let (t0, t1, p0, p1) = (et[ti], et[ti + 1], ep[pi], ep[pi + 1]);
            let mut sum = 0.0;
            for (xt, wt) in rule.nodes.iter().zip(&rule.weights) {
                let t = 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * xt;
                for (xp, wp) in rule.nodes.iter().zip(&rule.weights) {
                    let p = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * xp;
                    sum += wt * wp * sampler.pdf(&dir(t, p)) * t.sin();
                }
            }
            probs.push(sum * 0.25 * (t1 - t0) * (p1 - p0));
        }
    }
    let inside: f64 = probs.iter().sum();
    probs.push((1.0 - inside).max(0.0));
    let mut counts = vec![0usize; probs.len()];
    let mut rng = SplitMix64(seed);
    let cells = (ep.len() - 1) * (et.len() - 1);
    for _ in 0..N {
        let cell = sampler
            .sample(rng.unit(), [rng.unit(), rng.unit()])
            .and_then(|s| angles(&s.direction))
            .and_then(|(t, p)| {
                let ti = et.partition_point(|e| *e <= t).checked_sub(1)?;
                let pi = ep.partition_point(|e| *e <= p).checked_sub(1)?;
                (ti < et.len() - 1 && pi < ep.len() - 1).then_some(ti * (ep.len() - 1) + pi)
            });
        counts[cell.unwrap_or(cells)] += 1;
    }
    let (chi2, dof) = chi2::chi_square(&counts, &probs, N);
    let q = chi2::chi2_quantile_999(dof);
    println!("{name}: chi2 {chi2:.1} dof {dof} (99.9% {q:.1}), inside {inside:.5}");
    assert!(chi2 <= q, "{name}: chi2 {chi2} > {q} (dof {dof})");
    assert!(dof >= 100, "{name}: too few bins ({dof})");
}

/// The grazing backward lobes (module docs of the sampler, "Grazing specular lobes"): 85° and
/// 88° from the air, and from inside the glass at 41° (its Snell partner near 80°), at fixed
/// widths (`SurfaceCoherence::fixed`: the horizon rule would keep these lobes off the horizon;
/// its own sampler is checked in `tests/bsdf/horizon.rs`).
#[test]
fn grazing_backward_lobes_draw_from_their_pdf() {
    let f = frame();
    let m = glass();
    let b = Bsdf::new(&m, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    for (i, (w, deg, side, sample_side)) in [
        (20.0, 85.0, 1.0, 1.0),
        (3.0, 88.0, 1.0, 1.0),
        (3.0, 41.0, -1.0, 1.0),
    ]
    .iter()
    .enumerate()
    {
        let c = SurfaceCoherence::fixed(*w).unwrap();
        let r = dir(&f, *deg, -50.0, *side);
        let sampler = b.incident_sampler(r, &c).unwrap();
        check_angles(
            &format!("glass backward {deg}° side {side}, w {w} µm"),
            &f,
            &sampler,
            *sample_side,
            41 + i as u64,
        );
    }
}

#[test]
fn conductor_k_correlation_and_mixture() {
    let f = frame();
    let c = SurfaceCoherence::new(2.0).unwrap();
    let gold = RoughConductor::new(
        GaussianPsd::isotropic(0.015, 1.5).unwrap(),
        Complex::new(0.47, 2.4),
    )
    .unwrap();
    let b = Bsdf::new(&gold, Kernel::<OneShape, Partial>::default(), f, LAMBDA).unwrap();
    let s = dir(&f, 50.0, 10.0, 1.0);
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    check("gold forward", &f, &b.exit_sampler(&inc).unwrap(), 31);
    check(
        "gold backward",
        &f,
        &b.incident_sampler(dir(&f, 20.0, 100.0, 1.0), &c).unwrap(),
        32,
    );

    let kc = RoughDielectric::new(KCorrelation::new(4e-4, 4.0, 2.5).unwrap(), 1.5).unwrap();
    let blur = Partial(GaussHermite::new(8).unwrap());
    let b = Bsdf::new(&kc, Kernel::<Full, _>::new(blur), f, LAMBDA).unwrap();
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    check(
        "K-correlation forward",
        &f,
        &b.exit_sampler(&inc).unwrap(),
        33,
    );
    check(
        "K-correlation backward (exit below)",
        &f,
        &b.incident_sampler(dir(&f, 30.0, 200.0, -1.0), &c).unwrap(),
        34,
    );

    let mix = GaussianMixturePsd::new(vec![
        GaussianPsd::isotropic(0.01, 0.7).unwrap(),
        GaussianPsd::isotropic(0.02, 3.0).unwrap(),
    ])
    .unwrap();
    let mixed = RoughDielectric::new(mix, 1.5).unwrap();
    let b = Bsdf::new(&mixed, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    check("mixture forward", &f, &b.exit_sampler(&inc).unwrap(), 35);
}

#[test]
fn grating_orders_blurred_and_as_deltas() {
    let f = frame();
    let grating = Grating::sinusoidal_height(0.03, 2.0, &Vector2::new(0.9, 0.3)).unwrap();
    let metal = RoughConductor::new(grating, Complex::new(0.2, 3.4)).unwrap();
    let c = SurfaceCoherence::new(6.0).unwrap();
    let s = dir(&f, 20.0, 0.0, 1.0);
    let b = Bsdf::new(&metal, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    check(
        "grating forward, blurred",
        &f,
        &b.exit_sampler(&inc).unwrap(),
        41,
    );
    check(
        "grating backward, blurred",
        &f,
        &b.incident_sampler(dir(&f, 35.0, 160.0, 1.0), &c).unwrap(),
        42,
    );
    // Plane waves: specular and orders are deltas; only the delta fraction can be drawn.
    let b = Bsdf::new(&metal, Kernel::<Intensity, PlaneWave>::default(), f, LAMBDA).unwrap();
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    let sampler = b.exit_sampler(&inc).unwrap();
    let p = sampler.part_probabilities();
    let mut rng = SplitMix64(43);
    let mut deltas = 0;
    for _ in 0..N {
        let s = sampler.sample(rng.unit(), [rng.unit(), rng.unit()]);
        if let Some(s) = s {
            assert!(s.lobe.delta && s.delta_weight > 0.0 && s.pdf > 0.0);
            deltas += 1;
        }
    }
    // Every order kept is visible at 20°: all draws are deltas.
    check_delta_fraction("grating plane wave", deltas as f64 / N as f64, p[0] + p[1]);
}

#[test]
fn plane_wave_level_specular_delta_and_scattered_lobe() {
    let f = frame();
    let m = glass();
    let b = Bsdf::new(&m, Kernel::<OneShape, PlaneWave>::default(), f, LAMBDA).unwrap();
    let c = SurfaceCoherence::new(3.0).unwrap();
    let s = dir(&f, 30.0, 45.0, 1.0);
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    let sampler = b.exit_sampler(&inc).unwrap();
    let frac = check("glass plane wave forward", &f, &sampler, 51);
    let p = sampler.part_probabilities();
    check_delta_fraction("glass plane wave forward", frac, p[0] + p[2]);
    let sampler = b.incident_sampler(dir(&f, 45.0, 0.0, -1.0), &c).unwrap();
    let frac = check("glass plane wave backward (exit below)", &f, &sampler, 52);
    let p = sampler.part_probabilities();
    check_delta_fraction("glass plane wave backward", frac, p[0] + p[2]);
}

#[test]
fn smooth_incoherent_and_two_shape_levels() {
    let f = frame();
    let c = SurfaceCoherence::new(3.0).unwrap();
    let s = dir(&f, 40.0, -20.0, 1.0);
    let smooth: SmoothDielectric<f64> = SmoothDielectric::smooth(1.5).unwrap();
    let b = Bsdf::new(&smooth, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    let sampler = b.exit_sampler(&inc).unwrap();
    assert_eq!(sampler.part_probabilities()[1], 0.0);
    check("smooth glass forward", &f, &sampler, 61);

    let m = glass();
    let b = Bsdf::new(&m, Kernel::<OneShape, Incoherent>::default(), f, LAMBDA).unwrap();
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    check(
        "glass incoherent forward",
        &f,
        &b.exit_sampler(&inc).unwrap(),
        62,
    );

    // Two shapes: x and y channels with different coherence (|μ| = 0 is realizable).
    let b = Bsdf::new(&m, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let beam = Frame::sp(-s, f.k()).unwrap();
    let wx = CoherenceShape::new(Matrix2::new(4.0, 0.5, 0.5, 2.0)).unwrap();
    let wy = CoherenceShape::new(Matrix2::new(1.5, 0.0, 0.0, 9.0)).unwrap();
    let packet = WavePacket::new(
        Stokes::new(1.0, 0.4, 0.0, 0.0).unwrap(),
        wx,
        wy,
        beam,
        LAMBDA,
    )
    .unwrap();
    let inc = b.prepare(&packet).unwrap();
    check(
        "glass two shapes forward",
        &f,
        &b.exit_sampler(&inc).unwrap(),
        63,
    );
}

#[test]
fn chi_square_rejects_a_density_with_a_wrong_jacobian() {
    let f = frame();
    let m = glass();
    let b = Bsdf::new(&m, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let c = SurfaceCoherence::new(3.0).unwrap();
    let s = dir(&f, 60.0, 0.0, 1.0);
    let inc = b
        .prepare(&b.surface_packet(unpolarized(), s, &c).unwrap())
        .unwrap();
    let sampler = b.exit_sampler(&inc).unwrap();
    let disk = disk(&f);
    let mut pilot = Draws {
        sampler: &sampler,
        rng: SplitMix64(71),
        deltas: 0,
    };
    let grids = grids(&disk, &mut |_| pilot.next());
    // The Jacobian d²u = |cos θ| dω applied twice (a pdf in u taken for one in ω and
    // converted again); forgetting it instead makes the expected counts diverge at the horizon.
    let wrong = |d: &Vector3<f64>| sampler.pdf(d) * d.dot(&f.k()).abs();
    let mut draws = Draws {
        sampler: &sampler,
        rng: SplitMix64(72),
        deltas: 0,
    };
    let out = chi2::test(&disk, &grids, &wrong, N, &mut |_| draws.next());
    assert!(!out.passes(), "a density with cos θ twice passed: {out:?}");
}

#[test]
fn f32_sampler_draws_from_its_pdf() {
    let f = Frame::<f32>::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let m =
        RoughDielectric::new(GaussianPsd::<f32, 2>::isotropic(0.02, 1.0).unwrap(), 1.5).unwrap();
    let b = Bsdf::new(&m, Kernel::<Full, Partial>::default(), f, 0.5).unwrap();
    let c = SurfaceCoherence::new(3.0f32).unwrap();
    let r = f.x() * 0.5 + f.k() * (0.75f32).sqrt();
    let sampler = b.incident_sampler(r, &c).unwrap();
    let mut rng = SplitMix64(81);
    let mut some = 0;
    for _ in 0..N {
        let u = [rng.unit() as f32, rng.unit() as f32, rng.unit() as f32];
        if let Some(s) = sampler.sample(u[0], [u[1], u[2]]) {
            assert_eq!(sampler.pdf(&s.direction), s.pdf);
            assert!(s.pdf > 0.0 && s.pdf.is_finite(), "{s:?}");
            assert!((s.direction.norm() - 1.0).abs() < 1e-6);
            some += 1;
        }
    }
    assert!(some > N / 2);
    // Extreme uniforms: never a panic, never a NaN.
    for u in [
        0.0f32,
        1.0,
        -1.0,
        2.0,
        f32::NAN,
        f32::INFINITY,
        1.0 - f32::EPSILON,
    ] {
        if let Some(s) = sampler.sample(u, [u, u]) {
            assert!(s.pdf.is_finite() && s.pdf > 0.0 && s.direction.iter().all(|x| x.is_finite()));
        }
    }
}

/// A downstream PSD (a Gaussian) whose sampler lobe is the origin order (`Shape::Origin`,
/// as `Smooth` names it) and which has an autocorrelation, so the roughness levels beyond
/// first order accept it — the one way to reach a Dirac order in the scattered part together
/// with the projected-disk share of those levels.
#[derive(Debug, Clone, Copy)]
struct OriginPsd(GaussianPsd<f64, 2>);

impl gmueller::psd::Psd<f64, 2> for OriginPsd {
    fn value(&self, zeta: &Vector2<f64>) -> f64 {
        self.0.value(zeta)
    }
    fn variance(&self) -> f64 {
        gmueller::psd::Psd::<f64, 2>::variance(&self.0)
    }
    fn form(&self) -> gmueller::psd::Form<'_, f64, 2> {
        gmueller::psd::Form::closest(gmueller::psd::Shape::Origin)
    }
}

impl gmueller::psd::Autocorrelation<f64> for OriginPsd {
    fn normalized_autocorrelation(&self, xi: &Vector2<f64>) -> f64 {
        self.0.normalized_autocorrelation(xi)
    }
    fn decay_radius(&self, level: f64) -> f64 {
        self.0.decay_radius(level)
    }
}

/// Beyond first order the scattered part gives a share of its draws to the projected disk: a
/// Dirac order drawn from that part (here the origin order of a plane wave) is reached with
/// its probability times the rest, and its reported probability must say so (it said the
/// part's whole probability: weights 25 % low). The frequency of those draws against the
/// probability each reports.
#[test]
fn a_scattered_delta_beyond_first_order_reports_its_probability() {
    use gmueller::bsdf::Part;
    use gmueller::interaction::roughness::KirchhoffQuadrature;
    let f = frame();
    let psd = OriginPsd(GaussianPsd::isotropic(0.05, 2.0).unwrap());
    let m = RoughDielectric::new(psd, 1.5).unwrap();
    let kernel = Kernel::<Full, PlaneWave>::default()
        .with_roughness(KirchhoffQuadrature::new(1e-3).unwrap());
    let b = Bsdf::new(&m, kernel, f, LAMBDA).unwrap();
    let c = SurfaceCoherence::new(3.0).unwrap();
    for (name, sampler) in [
        (
            "forward",
            b.exit_sampler(
                &b.prepare(
                    &b.surface_packet(unpolarized(), dir(&f, 30.0, 0.0, 1.0), &c)
                        .unwrap(),
                )
                .unwrap(),
            )
            .unwrap(),
        ),
        (
            "backward",
            b.incident_sampler(dir(&f, 40.0, 0.0, 1.0), &c).unwrap(),
        ),
    ] {
        let mut rng = SplitMix64(0x0d1);
        let (mut count, mut reported) = (0usize, None);
        for _ in 0..N {
            if let Some(s) = sampler.sample(rng.unit(), [rng.unit(), rng.unit()])
                && s.lobe.delta
                && s.lobe.part == Part::Scattered
                && s.lobe.side == gmueller::interaction::Side::Reflection
            {
                count += 1;
                reported = Some(s.pdf);
            }
        }
        let p = reported.expect("scattered delta draws");
        println!("{name}: scattered delta drawn {count} of {N}, reported probability {p}");
        check_delta_fraction(name, count as f64 / N as f64, p);
    }
}
