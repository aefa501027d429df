//! Rough scenes: speed versus accuracy of the roughness levels (first order, the Kirchhoff
//! series at three tolerances, the geometric limit) from smooth to very rough surfaces, so
//! that the roughness guide (`docs/roughness.md`) can say which level to use for which roughness.
//!
//! **Suite.** Rough glass (η = 1.5, Fresnel specular interface) with an isotropic Gaussian PSD,
//! ℓ = 5λ and 20λ, rms height set by `vσ` at the specular direction: 0.1, 0.3, 1, 3, 10 (rms
//! slopes up to 0.32 at ℓ = 5λ). Coherence widths 1λ, 10λ and sunlight (68.4λ); incidence 0°,
//! 45°, 70°; polarized input with two shapes (Stokes (1, .5, .5, .3), `Θ_y = 1.3² Θ_x`). Exit
//! directions: `θ_o` 5°…85° (10° steps) × φ 0°…180° (30° steps), and the in-plane directions
//! `θ_i ± 1°, ± 3°`.
//!
//! **Reference.** f64, `Full`, `Partial`, `KirchhoffSeries` at tolerance 10⁻¹⁰ with the
//! tangent-plane pBSDF (`TangentPlane<FresnelReflection>`) — the series itself is checked
//! against a direct quadrature of the phase-screen integral in
//! `tests/interaction/roughness/series.rs`.
//!
//! **Rows.** `Full·Partial` with the tangent plane at every roughness level (first order, the
//! series at 10⁻², 10⁻⁴, 10⁻⁶, the geometric limit; f64, and the series 10⁻⁴ and the
//! geometric limit in f32), and the first-order kernel with Rayleigh–Rice scattering (the
//! level before the series). Errors as in the main suite: S0 relative over the directions where
//! the reference is at least 10⁻⁶ of the scene's largest (and, separately, in the lobe: at
//! least 1 %), the degree of polarization absolute; times are medians per evaluation of a
//! prepared packet.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::pbsdf::{FresnelReflection, Pbsdf, RayleighRice, TangentPlane};
use gmueller::interaction::roughness::{FirstOrder, Geometric, KirchhoffSeries, RoughnessWeights};
use gmueller::interaction::{Full, Geometry, Kernel, Partial, RoughSurface};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussianPsd};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;

use super::measure::median;
use super::scenes::{LAMBDA, sun_width};

/// The roughness steps (`vσ` at specular).
const V_SIGMA: [f64; 5] = [0.1, 0.3, 1.0, 3.0, 10.0];

/// One scene: the packet and the exit geometries, in one precision.
struct Scene<T: Real> {
    packet: WavePacket<T>,
    geometries: Vec<Geometry<T>>,
}

fn surface<T: Real>() -> Frame<T> {
    Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).expect("frame")
}

fn exits(theta_i: f64, quick: bool) -> Vec<Vector3<f64>> {
    let dir = |t: f64, p: f64| {
        let (t, p) = (t.to_radians(), p.to_radians());
        Vector3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    };
    let (thetas, phis): (Vec<f64>, Vec<f64>) = if quick {
        (vec![15.0, 45.0, 75.0], vec![0.0, 90.0, 180.0])
    } else {
        (
            (0..9).map(|i| 5.0 + 10.0 * f64::from(i)).collect(),
            (0..7).map(|i| 30.0 * f64::from(i)).collect(),
        )
    };
    let mut out: Vec<Vector3<f64>> = thetas
        .iter()
        .flat_map(|&t| phis.iter().map(move |&p| dir(t, p)))
        .collect();
    for d in [-3.0, -1.0, 1.0, 3.0] {
        let t: f64 = theta_i + d;
        out.push(dir(t.abs(), if t < 0.0 { 180.0 } else { 0.0 }));
    }
    out
}

fn scene<T: Real>(theta_i: f64, width_lambda: f64, exits: &[Vector3<f64>]) -> Scene<T> {
    let l = T::lit;
    let w = width_lambda * LAMBDA;
    let t = theta_i.to_radians();
    let travel = Vector3::new(t.sin(), 0.0, -t.cos()).map(l);
    let tx = Matrix2::identity() * (w * w);
    let packet = WavePacket::new(
        Stokes::new(l(1.0), l(0.5), l(0.5), l(0.3)).expect("stokes"),
        CoherenceShape::new(tx.map(l)).expect("shape"),
        CoherenceShape::new((tx * 1.69).map(l)).expect("shape"),
        Frame::sp(travel, Vector3::z()).expect("frame"),
        l(LAMBDA),
    )
    .expect("packet");
    let geometries = exits
        .iter()
        .map(|e| Geometry::for_packet(&packet, &surface(), e.map(l)).expect("geometry"))
        .collect();
    Scene { packet, geometries }
}

type Glass<T, Sc> = RoughSurface<GaussianPsd<T, 2>, FresnelReflection<T>, Sc>;

fn glass<T: Real, Sc>(sigma: f64, ell: f64, scatter: Sc) -> Glass<T, Sc> {
    RoughSurface {
        psd: GaussianPsd::isotropic(T::lit(sigma), T::lit(ell)).expect("psd"),
        specular: FresnelReflection::new(Complex::new(T::lit(1.5), T::zero())).expect("η"),
        scatter,
    }
}

/// Every exit's total Stokes vector, and the median time per evaluation (ns).
fn run<T, R, Sc>(rough: R, m: &Glass<T, Sc>, s: &Scene<T>, budget: Duration) -> (Vec<[f64; 4]>, f64)
where
    T: Real,
    Partial: CoherenceWeights<T, GaussianPsd<T, 2>>,
    R: RoughnessWeights<T, GaussianPsd<T, 2>, Partial>,
    Sc: Pbsdf<T>,
{
    let kernel = Kernel::<Full, Partial>::new(Partial(ClosedForm)).with_roughness(rough);
    let pass = || -> Vec<[f64; 4]> {
        let prepared = kernel.prepare(&s.packet, &surface()).expect("prepare");
        s.geometries
            .iter()
            .map(|g| {
                let r = kernel.evaluate_prepared(m, &prepared, std::hint::black_box(g));
                r.total().vector().map(|x| x.to_f64()).into()
            })
            .collect()
    };
    let out = pass();
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < 3 || (start.elapsed() < budget && times.len() < 100) {
        let t = Instant::now();
        std::hint::black_box(pass());
        times.push(t.elapsed().as_secs_f64() * 1e9 / s.geometries.len() as f64);
    }
    (out, median(&mut times))
}

/// The rows of the rough suite.
const ROWS: [&str; 8] = [
    "first order · Rayleigh–Rice",
    "first order · tangent plane",
    "series 1e-2",
    "series 1e-4",
    "series 1e-6",
    "geometric",
    "series 1e-4 · f32",
    "geometric · f32",
];

/// Errors of one row over the scenes of one roughness step.
#[derive(Default, Clone)]
struct Acc {
    s0: Vec<f64>,
    lobe: Vec<f64>,
    dop: Vec<f64>,
    ns: Vec<f64>,
}

fn dop(s: &[f64; 4]) -> f64 {
    if s[0] > 0.0 {
        (s[1] * s[1] + s[2] * s[2] + s[3] * s[3]).sqrt() / s[0]
    } else {
        0.0
    }
}

/// Runs the rough suite; returns its markdown section (also written to `rough.md` by the caller).
pub fn run_suite(quick: bool) -> Result<String, Box<dyn std::error::Error>> {
    let wall = Instant::now();
    let ells: Vec<f64> = if quick { vec![5.0] } else { vec![5.0, 20.0] };
    let widths: Vec<f64> = if quick {
        vec![1.0]
    } else {
        vec![1.0, 10.0, sun_width()]
    };
    let incidences: Vec<f64> = if quick {
        vec![45.0]
    } else {
        vec![0.0, 45.0, 70.0]
    };
    let budget = Duration::from_micros(if quick { 100 } else { 400 });
    let k = std::f64::consts::TAU / LAMBDA;
    let mut table: Vec<Vec<Acc>> = vec![vec![Acc::default(); ROWS.len()]; V_SIGMA.len()];
    let mut scenes = 0usize;
    for (vi, &v_sigma) in V_SIGMA.iter().enumerate() {
        for &ell_l in &ells {
            for &theta_i in &incidences {
                let sigma = v_sigma / (2.0 * k * f64::to_radians(theta_i).cos());
                let ell = ell_l * LAMBDA;
                let exits = exits(theta_i, quick);
                for &w in &widths {
                    scenes += 1;
                    let s64 = scene::<f64>(theta_i, w, &exits);
                    let s32 = scene::<f32>(theta_i, w, &exits);
                    let fr64 = FresnelReflection::new(Complex::new(1.5, 0.0)).expect("η");
                    let fr32 = FresnelReflection::new(Complex::new(1.5f32, 0.0)).expect("η");
                    let tp64 = glass::<f64, _>(sigma, ell, TangentPlane::new(fr64));
                    let tp32 = glass::<f32, _>(sigma, ell, TangentPlane::new(fr32));
                    let rr64 = glass::<f64, _>(
                        sigma,
                        ell,
                        RayleighRice::new(Complex::new(1.5, 0.0)).expect("η"),
                    );
                    let series = |tol: f64| KirchhoffSeries::new(tol).expect("tolerance");
                    let (reference, _) = run(series(1e-10), &tp64, &s64, Duration::ZERO);
                    let rows = [
                        run(FirstOrder, &rr64, &s64, budget),
                        run(FirstOrder, &tp64, &s64, budget),
                        run(series(1e-2), &tp64, &s64, budget),
                        run(series(1e-4), &tp64, &s64, budget),
                        run(series(1e-6), &tp64, &s64, budget),
                        run(Geometric, &tp64, &s64, budget),
                        run(series(1e-4), &tp32, &s32, budget),
                        run(Geometric, &tp32, &s32, budget),
                    ];
                    let max_ref = reference.iter().map(|r| r[0]).fold(0.0, f64::max);
                    for (ri, (out, ns)) in rows.iter().enumerate() {
                        let acc = &mut table[vi][ri];
                        acc.ns.push(*ns);
                        for (o, r) in out.iter().zip(&reference) {
                            if r[0] < 1e-6 * max_ref || r[0] <= 0.0 {
                                continue;
                            }
                            let e = ((o[0] - r[0]) / r[0]).abs();
                            acc.s0.push(e);
                            if r[0] >= 1e-2 * max_ref {
                                acc.lobe.push(e);
                            }
                            acc.dop.push((dop(o) - dop(r)).abs());
                        }
                    }
                }
            }
        }
        eprintln!(
            "  rough suite: vσ = {v_sigma} done, {:.0} s",
            wall.elapsed().as_secs_f64()
        );
    }
    let mut md = String::new();
    writeln!(
        md,
        "## Rough surfaces\n\n{scenes} scenes: rough glass (Gaussian PSD, ℓ = {}λ), θ_i = {:?}°, \
         coherence widths {}, polarized two-shape input; reference `Full·Partial·KirchhoffSeries` \
         10⁻¹⁰ with `TangentPlane`. S0 error: max over directions ≥ 10⁻⁶ of the scene's peak \
         (lobe: ≥ 10⁻²), RMS over the same; DoP: max absolute; time: median ns per evaluation.\n",
        ells.iter()
            .map(|e| e.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        incidences,
        widths
            .iter()
            .map(|w| format!("{w:.1}λ"))
            .collect::<Vec<_>>()
            .join(", ")
    )?;
    writeln!(
        md,
        "| vσ | level | S0 max | S0 max (lobe) | S0 RMS | DoP max | ns |"
    )?;
    writeln!(md, "|---|---|---|---|---|---|---|")?;
    let mut advice = String::new();
    let mut best_10: Vec<Option<(f64, &str)>> = vec![None; V_SIGMA.len()];
    for (vi, &v_sigma) in V_SIGMA.iter().enumerate() {
        let mut best: Option<(f64, &str)> = None;
        for (ri, name) in ROWS.iter().enumerate() {
            let a = &table[vi][ri];
            let max = a.s0.iter().copied().fold(0.0, f64::max);
            let lobe = a.lobe.iter().copied().fold(0.0, f64::max);
            let rms = (a.s0.iter().map(|e| e * e).sum::<f64>() / a.s0.len().max(1) as f64).sqrt();
            let dmax = a.dop.iter().copied().fold(0.0, f64::max);
            let ns = median(&mut a.ns.clone());
            writeln!(
                md,
                "| {v_sigma} | {name} | {max:.1e} | {lobe:.1e} | {rms:.1e} | {dmax:.1e} | {ns:.0} |"
            )?;
            if lobe <= 0.01 && best.is_none_or(|(t, _)| ns < t) {
                best = Some((ns, name));
            }
            if lobe <= 0.1 && best_10[vi].is_none_or(|(t, _)| ns < t) {
                best_10[vi] = Some((ns, name));
            }
        }
        let say = |b: Option<(f64, &str)>| {
            b.map_or("none".to_string(), |(ns, name)| {
                format!("{name} ({ns:.0} ns)")
            })
        };
        writeln!(
            advice,
            "- vσ = {v_sigma}: cheapest within 1 % in the lobe: {}; within 10 %: {}",
            say(best),
            say(best_10[vi])
        )?;
    }
    writeln!(md, "\n{advice}")?;
    writeln!(md, "Rough suite: {:.0} s.", wall.elapsed().as_secs_f64())?;
    Ok(md)
}
