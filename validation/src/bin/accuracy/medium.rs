//! The random medium's speed versus accuracy (`-- --medium`): every model level and blur method
//! of `gmueller::medium` against the reference level, in f32 and f64.
//!
//! **Suite.** λ = 0.5 µm, rms δε 1e-3. Media: isotropic Gaussian with ℓ = 0.1, 1, 10 λ; an
//! anisotropic Gaussian (correlation lengths 1 λ × 5 λ × 2 λ, turned); K-correlation with
//! √T = 1 λ and γ = 3 (the Debye–Bueche medium) and γ = 2.5. All with the dipole scatterer.
//! Packets along a tilted direction with transverse coherence widths 1, 10, 100 λ and `σ_zz` = 10 λ
//! or unbounded; unpolarized with one shape, or polarized (Stokes (1, 0.5, 0.5, 0.3)) with two
//! isotropic shapes `Θ_y = 1.3² Θ_x` (every packet is symmetric about its direction, so the
//! scattering coefficient of the K-correlation's adaptive reference stays affordable). Exit
//! directions: scattering angles 1e-3 … π (12, geometric then linear) × 6 azimuths.
//!
//! **Reference.** f64, `Full`, `Partial`: the closed-form blur (Gaussian media); for the
//! K-correlation, the closed-form blur of its Gaussian-mixture fit to a uniform error of 1e-12
//! of `p(0)` (`KCorrelation::mixture_fit_to`: the blur then errs by at most 1e-12 of the peak
//! blur, below 1e-6 relative above the harness's floor), cross-checked against adaptive
//! quadrature at 1e-9 on three directions of every K-correlation scene (the largest relative
//! difference is reported; adaptive quadrature in 3-D is too slow to be the reference of every
//! direction and of `σ_s`, and Gauss–Hermite of order 24 was 2.2e-3 off it at 1 λ coherence). The `Incoherent` level needs a bounded `σ_zz`: its rows
//! skip the unbounded scenes.
//!
//! **Errors.** `dI/dV`: `|S0 − S0_ref|/S0_ref` over directions with `S0_ref ≥ 1e-6` of the
//! scene's maximum; degree of polarization: `|DoP − DoP_ref|` (n/a at the intensity level); `σ_s`: relative. Max
//! over all scenes a row applies to.
//!
//! **Timing.** Per scene: `PhaseFunction::prepare` timed once per repetition; `differential_scattering`
//! per direction, in batches over every direction; medians per scene, then over scenes
//! (`std::time::Instant`, `black_box`). The criterion bench `benches/medium.rs` gives precise
//! numbers.

use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;

use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::polarization::{PolarizationModel, Throughput};
use gmueller::interaction::{Full, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave};
use gmueller::medium::{Dipole, PhaseFunction, RandomMedium, VolumeCoherence};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{
    Adaptive, BlurMethod, ClosedForm, GaussHermite, GaussianPsd, KCorrelation, Psd,
};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix3, Rotation3, Unit, Vector3, Vector4};

const LAMBDA: f64 = 0.5;
const SIGMA: f64 = 1e-3;
const FLOOR: f64 = 1e-6;

/// A medium of the suite.
#[derive(Debug, Clone, Copy)]
enum Spec {
    Gaussian(f64),
    Anisotropic,
    KCorr(f64),
}

impl Spec {
    fn name(&self) -> String {
        match self {
            Spec::Gaussian(l) => format!("Gaussian ℓ = {l} λ"),
            Spec::Anisotropic => "anisotropic Gaussian".into(),
            Spec::KCorr(g) => format!("K-correlation γ = {g}"),
        }
    }
    fn is_k(&self) -> bool {
        matches!(self, Spec::KCorr(_))
    }
}

/// One scene: a medium, a packet, exit directions.
struct Scene {
    medium: usize,
    width: f64,
    zz: Option<f64>,
    polarized: bool,
}

fn gaussian<T: Real>(spec: Spec) -> GaussianPsd<T, 3> {
    match spec {
        Spec::Gaussian(l) => GaussianPsd::isotropic(T::lit(SIGMA), T::lit(l * LAMBDA)).unwrap(),
        _ => {
            let r =
                Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, 2.0, 0.5)), 0.7);
            let d = Matrix3::from_diagonal(&Vector3::new(1.0, 25.0, 4.0)) * (LAMBDA * LAMBDA);
            let c = r.matrix() * d * r.matrix().transpose();
            let g = gmueller::gaussian::Gaussian::new(c.map(T::lit)).unwrap();
            GaussianPsd::from_autocorrelation(T::lit(SIGMA * SIGMA), &g).unwrap()
        }
    }
}

fn kcorr<T: Real>(gamma: f64) -> KCorrelation<T, 3> {
    KCorrelation::new(
        T::lit(SIGMA * SIGMA),
        T::lit(LAMBDA * LAMBDA),
        T::lit(gamma),
    )
    .unwrap()
}

fn packet<T: Real>(s: &Scene) -> WavePacket<T> {
    let f = Frame::from_direction_and_x(
        Vector3::new(0.3, -0.2, 0.93).map(T::lit),
        Vector3::new(1.0, 0.4, 0.0).map(T::lit),
    )
    .unwrap();
    let w2 = (s.width * LAMBDA).powi(2);
    let (stokes, ratio) = if s.polarized {
        (Stokes::new(1.0, 0.5, 0.5, 0.3).unwrap(), 1.69)
    } else {
        (Stokes::unpolarized(1.0).unwrap(), 1.0)
    };
    let st = stokes.vector().map(T::lit);
    let p = WavePacket::new(
        Stokes::new(st[0], st[1], st[2], st[3]).unwrap(),
        CoherenceShape::isotropic(T::lit(w2.sqrt())).unwrap(),
        CoherenceShape::isotropic(T::lit((w2 * ratio).sqrt())).unwrap(),
        f,
        T::lit(LAMBDA),
    )
    .unwrap();
    match s.zz {
        Some(z) => p.with_longitudinal_coherence(T::lit(z * LAMBDA)).unwrap(),
        None => p,
    }
}

fn exits(d: &Vector3<f64>) -> Vec<Vector3<f64>> {
    let x = if d.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (x - d * d.dot(&x)).normalize();
    let e2 = d.cross(&e1);
    let mut thetas: Vec<f64> = (0..6)
        .map(|i| 1e-3 * 10f64.powf(f64::from(i) * 0.5))
        .collect();
    thetas.extend((1..=6).map(|i| std::f64::consts::PI * f64::from(i) / 6.0));
    let mut out = vec![];
    for t in thetas {
        for j in 0..6 {
            let p = std::f64::consts::TAU * f64::from(j) / 6.0 + 0.3;
            out.push((d * t.cos() + (e1 * p.cos() + e2 * p.sin()) * t.sin()).normalize());
        }
    }
    out
}

/// One variant's outcome on one scene: the Stokes vectors (f64), `σ_s`, timings.
struct Outcome {
    stokes: Vec<Vector4<f64>>,
    sigma: f64,
    ns_eval: f64,
    us_prepare: f64,
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs one level on one scene (`None` where the level refuses the packet).
fn run<T, P, Pol, Coh>(
    m: &RandomMedium<P, Dipole>,
    kernel: Kernel<Pol, Coh>,
    s: &Scene,
    reps: usize,
) -> Option<Outcome>
where
    T: Real,
    P: Psd<T, 3>,
    Pol: PolarizationModel,
    Coh: VolumeCoherence<T, P>,
{
    let phase = PhaseFunction::new(m, kernel);
    let pk = packet::<T>(s);
    let inc = phase.prepare(&pk).ok()?;
    let d = pk.frame().k().map(|x| x.to_f64());
    let dirs: Vec<Vector3<T>> = exits(&d).iter().map(|r| r.map(T::lit)).collect();
    let to_vec = |l: &<Pol::Throughput<T> as Throughput<T>>::Light| -> Vector4<f64> {
        <Pol::Throughput<T> as Throughput<T>>::light_stokes(l).map_or_else(
            || {
                Vector4::new(
                    <Pol::Throughput<T> as Throughput<T>>::intensity(l).to_f64(),
                    0.0,
                    0.0,
                    0.0,
                )
            },
            |st| st.vector().map(|x| x.to_f64()),
        )
    };
    let stokes: Vec<Vector4<f64>> = dirs
        .iter()
        .map(|r| to_vec(&phase.differential_scattering(&inc, *r).unwrap().light))
        .collect();
    let (mut te, mut tp) = (vec![], vec![]);
    for _ in 0..reps {
        let t0 = Instant::now();
        black_box(phase.prepare(black_box(&pk)).unwrap());
        tp.push(t0.elapsed().as_secs_f64() * 1e6);
        let t0 = Instant::now();
        for r in &dirs {
            black_box(
                phase
                    .differential_scattering(black_box(&inc), black_box(*r))
                    .unwrap(),
            );
        }
        te.push(t0.elapsed().as_secs_f64() * 1e9 / dirs.len() as f64);
    }
    Some(Outcome {
        stokes,
        sigma: inc.scattering_coefficient().to_f64(),
        ns_eval: median(&mut te),
        us_prepare: median(&mut tp),
    })
}

/// A row of the table: a level, a blur and a precision.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Variant {
    pol: &'static str,
    coh: &'static str,
    blur: Blur,
    f32: bool,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Blur {
    None,
    Exact,
    Mixture(usize),
    GaussHermite(usize),
}

impl Variant {
    fn label(&self) -> String {
        let b = match self.blur {
            Blur::None => "—".to_string(),
            Blur::Exact => "exact".into(),
            Blur::Mixture(m) => format!("mix{m}"),
            Blur::GaussHermite(n) => format!("GH{n}"),
        };
        format!(
            "{}·{}·{} {}",
            self.pol,
            self.coh,
            b,
            if self.f32 { "f32" } else { "f64" }
        )
    }
    fn applies(&self, spec: Spec) -> bool {
        match self.blur {
            Blur::Exact => !spec.is_k(),
            Blur::Mixture(_) | Blur::GaussHermite(_) => spec.is_k(),
            Blur::None => true,
        }
    }
}

fn variants(quick: bool) -> Vec<Variant> {
    let mut v = vec![];
    for f32 in [false, true] {
        for pol in ["Full", "OneShape", "Intensity"] {
            for coh in ["PlaneWave", "Incoherent"] {
                v.push(Variant {
                    pol,
                    coh,
                    blur: Blur::None,
                    f32,
                });
            }
            v.push(Variant {
                pol,
                coh: "Partial",
                blur: Blur::Exact,
                f32,
            });
        }
        let blurs: &[Blur] = if quick {
            &[Blur::Mixture(8), Blur::GaussHermite(6)]
        } else {
            &[
                Blur::Mixture(4),
                Blur::Mixture(8),
                Blur::Mixture(16),
                Blur::Mixture(32),
                Blur::GaussHermite(4),
                Blur::GaussHermite(8),
                Blur::GaussHermite(12),
            ]
        };
        for &b in blurs {
            v.push(Variant {
                pol: "Full",
                coh: "Partial",
                blur: b,
                f32,
            });
        }
    }
    v
}

/// Runs a variant on a scene, dispatching to the monomorphised level.
fn dispatch(v: &Variant, spec: Spec, s: &Scene, reps: usize) -> Option<Outcome> {
    if v.f32 {
        dispatch_t::<f32>(v, spec, s, reps)
    } else {
        dispatch_t::<f64>(v, spec, s, reps)
    }
}

fn with_blur<T: Real, P: Psd<T, 3>, B>(
    pol: &str,
    m: &RandomMedium<P, Dipole>,
    b: B,
    s: &Scene,
    reps: usize,
) -> Option<Outcome>
where
    B: BlurMethod<T, 3, P> + Clone + core::fmt::Debug,
{
    match pol {
        "Full" => run::<T, _, _, _>(m, Kernel::<Full, _>::new(Partial(b)), s, reps),
        "OneShape" => run::<T, _, _, _>(m, Kernel::<OneShape, _>::new(Partial(b)), s, reps),
        _ => run::<T, _, _, _>(m, Kernel::<Intensity, _>::new(Partial(b)), s, reps),
    }
}

fn limits<T: Real, P: Psd<T, 3>>(
    v: &Variant,
    m: &RandomMedium<P, Dipole>,
    s: &Scene,
    reps: usize,
) -> Option<Outcome> {
    match (v.pol, v.coh) {
        ("Full", "PlaneWave") => {
            run::<T, _, _, _>(m, Kernel::<Full, PlaneWave>::default(), s, reps)
        }
        ("OneShape", "PlaneWave") => {
            run::<T, _, _, _>(m, Kernel::<OneShape, PlaneWave>::default(), s, reps)
        }
        ("Intensity", "PlaneWave") => {
            run::<T, _, _, _>(m, Kernel::<Intensity, PlaneWave>::default(), s, reps)
        }
        ("Full", _) => run::<T, _, _, _>(m, Kernel::<Full, Incoherent>::default(), s, reps),
        ("OneShape", _) => run::<T, _, _, _>(m, Kernel::<OneShape, Incoherent>::default(), s, reps),
        _ => run::<T, _, _, _>(m, Kernel::<Intensity, Incoherent>::default(), s, reps),
    }
}

fn dispatch_t<T: Real>(v: &Variant, spec: Spec, s: &Scene, reps: usize) -> Option<Outcome> {
    match spec {
        Spec::KCorr(g) => {
            let m = RandomMedium::new(kcorr::<T>(g), Dipole);
            match v.blur {
                Blur::None => limits(v, &m, s, reps),
                Blur::Mixture(n) => {
                    let (fit, _) = kcorr::<T>(g).mixture_fit(n).unwrap();
                    with_blur(v.pol, &RandomMedium::new(fit, Dipole), ClosedForm, s, reps)
                }
                Blur::GaussHermite(n) => {
                    with_blur(v.pol, &m, GaussHermite::<T>::new(n).unwrap(), s, reps)
                }
                Blur::Exact => None,
            }
        }
        _ => {
            let m = RandomMedium::new(gaussian::<T>(spec), Dipole);
            match v.blur {
                Blur::None => limits(v, &m, s, reps),
                Blur::Exact => with_blur(v.pol, &m, ClosedForm, s, reps),
                _ => None,
            }
        }
    }
}

/// The reference of a scene: f64, Full·Partial, closed form (of the 1e-12 mixture fit for the
/// K-correlation).
fn reference(spec: Spec, s: &Scene) -> Outcome {
    let kernel = Kernel::<Full, _>::new(Partial(ClosedForm));
    let out = if let Spec::KCorr(g) = spec {
        let (fit, _, _) = kcorr::<f64>(g).mixture_fit_to(1e-12).unwrap();
        run::<f64, _, _, _>(&RandomMedium::new(fit, Dipole), kernel, s, 1)
    } else {
        run::<f64, _, _, _>(
            &RandomMedium::new(gaussian::<f64>(spec), Dipole),
            kernel,
            s,
            1,
        )
    };
    out.expect("the reference level takes every packet")
}

/// The K-correlation reference against adaptive quadrature at 1e-9 on three directions
/// (forward, 30°, backward): the largest relative difference of `S0`.
fn crosscheck(spec: Spec, s: &Scene, reference: &Outcome) -> f64 {
    let Spec::KCorr(g) = spec else { return 0.0 };
    let m = RandomMedium::new(kcorr::<f64>(g), Dipole);
    let kernel = Kernel::<Full, _>::new(Partial(Adaptive::<f64>::new(1e-9).unwrap()));
    let pk = packet::<f64>(s);
    let dirs = exits(&pk.frame().k());
    let mut worst = 0.0f64;
    for i in [0, 6 * 7, dirs.len() - 1] {
        let a = m
            .differential_scattering(&kernel, &pk, dirs[i])
            .unwrap()
            .light
            .s0();
        worst = worst.max((a / reference.stokes[i][0] - 1.0).abs());
    }
    worst
}

fn dop(s: &Vector4<f64>) -> f64 {
    (s[1] * s[1] + s[2] * s[2] + s[3] * s[3]).sqrt() / s[0]
}

/// Runs the suite and writes `medium.md` and `medium.csv` into `out_dir`.
pub fn run_suite(quick: bool, out_dir: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    let wall = Instant::now();
    let specs: Vec<Spec> = if quick {
        vec![Spec::Gaussian(1.0), Spec::KCorr(3.0)]
    } else {
        vec![
            Spec::Gaussian(0.1),
            Spec::Gaussian(1.0),
            Spec::Gaussian(10.0),
            Spec::Anisotropic,
            Spec::KCorr(3.0),
            Spec::KCorr(2.5),
        ]
    };
    let widths: &[f64] = if quick { &[10.0] } else { &[1.0, 10.0, 100.0] };
    let mut scenes = vec![];
    for (mi, _) in specs.iter().enumerate() {
        for &w in widths {
            for zz in [Some(10.0), None] {
                for polarized in [false, true] {
                    scenes.push(Scene {
                        medium: mi,
                        width: w,
                        zz,
                        polarized,
                    });
                }
            }
        }
    }
    let reps = if quick { 2 } else { 5 };
    let refs: Vec<Outcome> = scenes
        .iter()
        .map(|s| reference(specs[s.medium], s))
        .collect();
    let cross = scenes
        .iter()
        .zip(&refs)
        .map(|(s, r)| crosscheck(specs[s.medium], s, r))
        .fold(0.0f64, f64::max);
    let mut md = String::from(
        "| variant | scenes | max S0 rel | RMS S0 rel | max DoP abs | max σ_s rel | ns/eval | µs/prepare |\n|---|---|---|---|---|---|---|---|\n",
    );
    let mut csv = String::from(
        "variant,scenes,s0_max_rel,s0_rms_rel,dop_max_abs,sigma_max_rel,ns_eval,us_prepare\n",
    );
    for v in variants(quick) {
        let (mut n, mut s0_max, mut sq, mut cnt, mut dop_max, mut sig_max) =
            (0, 0.0f64, 0.0, 0usize, 0.0f64, 0.0f64);
        let (mut te, mut tp) = (vec![], vec![]);
        for (si, s) in scenes.iter().enumerate() {
            let spec = specs[s.medium];
            if !v.applies(spec) {
                continue;
            }
            let Some(out) = dispatch(&v, spec, s, reps) else {
                continue;
            };
            n += 1;
            let r = &refs[si];
            let peak = r.stokes.iter().fold(0.0f64, |m, x| m.max(x[0]));
            for (a, b) in out.stokes.iter().zip(&r.stokes) {
                if b[0] < FLOOR * peak {
                    continue;
                }
                let e = (a[0] - b[0]).abs() / b[0];
                s0_max = s0_max.max(e);
                sq += e * e;
                cnt += 1;
                if v.pol != "Intensity" {
                    dop_max = dop_max.max((dop(a) - dop(b)).abs());
                }
            }
            sig_max = sig_max.max((out.sigma / r.sigma - 1.0).abs());
            te.push(out.ns_eval);
            tp.push(out.us_prepare);
        }
        if n == 0 {
            continue;
        }
        let rms = (sq / cnt.max(1) as f64).sqrt();
        let dop_s = if v.pol == "Intensity" {
            "n/a".to_string()
        } else {
            format!("{dop_max:.1e}")
        };
        let (ne, np) = (median(&mut te), median(&mut tp));
        writeln!(
            md,
            "| {} | {n} | {s0_max:.1e} | {rms:.1e} | {dop_s} | {sig_max:.1e} | {ne:.0} | {np:.1} |",
            v.label()
        )?;
        writeln!(
            csv,
            "{},{n},{s0_max:.6e},{rms:.6e},{},{sig_max:.6e},{ne:.3},{np:.3}",
            v.label(),
            if v.pol == "Intensity" {
                String::new()
            } else {
                format!("{dop_max:.6e}")
            }
        )?;
    }
    let media: Vec<String> = specs.iter().map(Spec::name).collect();
    let report = format!(
        "# gmueller random medium: speed vs accuracy{}\n\n{} scenes ({}; widths {:?} λ; σ_zz 10 λ or unbounded; unpolarized or polarized two-shape), {} exit directions each. Run time {:.0} s. K-correlation reference (mixture fit to 1e-12) vs adaptive quadrature at 1e-9: max S0 relative difference {cross:.1e}.\n\n{md}",
        if quick { " (--quick)" } else { "" },
        scenes.len(),
        media.join(", "),
        widths,
        exits(&Vector3::z()).len(),
        wall.elapsed().as_secs_f64()
    );
    println!("{report}");
    std::fs::write(out_dir.join("medium.md"), &report)?;
    std::fs::write(out_dir.join("medium.csv"), &csv)?;
    println!(
        "Wrote {} and {}",
        out_dir.join("medium.md").display(),
        out_dir.join("medium.csv").display()
    );
    Ok(())
}
