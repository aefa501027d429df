//! A fixed workload for counting the instructions of the SIMD batch path with callgrind:
//! `Kernel::<Full, Partial>::evaluate_batch` (both lobes and the exit frames) on 65,536 exits
//! around the mirror direction — the scene of the `kernel_batch_partial` bench (30° incidence,
//! `Θ_y = 1.44 Θ_x`, Gaussian PSD, Fresnel + Rayleigh–Rice on glass) — `reps` times, in `f32`
//! or `f64`. The cost of one pass per direction is the difference of two runs over 65,536:
//!
//! ```text
//! cargo build --release --example batch_count
//! valgrind --tool=callgrind target/release/examples/batch_count f32 1
//! valgrind --tool=callgrind target/release/examples/batch_count f32 2
//! ```
//!
//! (valgrind has no AVX-512, so the dispatch takes AVX2 + FMA under it). It prints a checksum
//! so that the work is not optimised away. A third argument picks another workload: `exits`
//! (the default, above), `exits-intensity` (the same at the `Intensity` level, `S0` only and no
//! exit frames), `pairs` (`Kernel::evaluate_pairs` on 65,536 pairs of one surface
//! width), `pairs-horizon` (each pair its own width, the horizon rule), `pairs-scalar` or
//! `pairs-horizon-scalar` (the same pairs one at a time through the renderer layer),
//! `pairs-material` or `pairs-horizon-material` (`Material::eval_incident_pairs`), and
//! `pairs-mueller` or `pairs-horizon-mueller` (`Kernel::evaluate_pairs_mueller`; its checksum
//! is the sum of the scattered `M₀₀`).

use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::batch::{DirectionsSoa, ExitFramesSoa, LobesSoa, StokesSoa};
use gmueller::interaction::{Full, Intensity, Kernel, Partial, RoughSurface};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::verify::rng::Lcg;
use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;

/// The number of exits of one pass.
const M: usize = 65_536;

/// `reps` passes of `evaluate_batch` over the `M` exits at the `Full` level (with the exit
/// frames) or, with `intensity`, at the `Intensity` level (`S0` only, no frames: what a
/// renderer that ignores polarization asks for); the sum of the last pass's scattered `S0`.
fn run<T: Real>(reps: usize, intensity: bool) -> f64 {
    let eta = Complex::new(T::lit(1.5), T::zero());
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.02), T::lit(2.0)).unwrap();
    let material = RoughSurface {
        psd,
        specular: gmueller::interaction::pbsdf::FresnelReflection::new(eta).unwrap(),
        scatter: gmueller::interaction::pbsdf::RayleighRice::new(eta).unwrap(),
    };
    let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let theta_i = 30f64.to_radians();
    let travel = Vector3::new(theta_i.sin(), 0.0, -theta_i.cos()).map(T::lit);
    let frame = Frame::sp(travel, Vector3::z())
        .unwrap()
        .rotated(T::lit(0.7));
    let shape = |w: f64| CoherenceShape::new(Matrix2::new(w * w, 0.0, 0.0, w * w).map(T::lit));
    let stokes = Stokes::new(T::lit(1.0), T::lit(0.3), T::lit(0.2), T::lit(-0.3)).unwrap();
    let packet = WavePacket::new(
        stokes,
        shape(5.0).unwrap(),
        shape(6.0).unwrap(),
        frame,
        T::lit(0.5),
    )
    .unwrap();
    let mut rng = Lcg(0xba7c);
    let (mut x, mut y, mut z) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..M {
        let to = (theta_i + (rng.uniform() - 0.5) * 0.26).abs();
        let po = (rng.uniform() - 0.5) * 0.52;
        x.push(T::lit(to.sin() * po.cos()));
        y.push(T::lit(to.sin() * po.sin()));
        z.push(T::lit(to.cos()));
    }
    let mut buf = vec![vec![T::zero(); M]; 11];
    let [a, b, c, d, e, f, g, h, sx, sy, sz] = &mut buf[..] else {
        unreachable!()
    };
    let mut out = LobesSoa {
        specular: StokesSoa { s: [a, b, c, d] },
        scattered: StokesSoa { s: [e, f, g, h] },
    };
    let mut frames = ExitFramesSoa { s: [sx, sy, sz] };
    for _ in 0..reps {
        let dirs = DirectionsSoa {
            x: &x,
            y: &y,
            z: &z,
        };
        if intensity {
            Kernel::<Intensity, Partial>::default()
                .evaluate_batch(&material, &packet, &surface, None, dirs, &mut out, None)
                .unwrap();
        } else {
            Kernel::<Full, Partial>::default()
                .evaluate_batch(
                    &material,
                    &packet,
                    &surface,
                    None,
                    dirs,
                    &mut out,
                    Some(&mut frames),
                )
                .unwrap();
        }
    }
    out.scattered.s[0].iter().map(|v| v.to_f64()).sum::<f64>()
}

/// `reps` passes over `M` (incident, exit) pairs of the renderer's light (unpolarized, the
/// surface coherence of sunlight, 37.6 µm, the same for every pair, or with `horizon` widened
/// by the horizon rule, `SurfaceCoherence::new`: a width of its own per pair) on rough gold at 0.55 µm (the wavefront example's
/// material), Full · Partial: `Kernel::evaluate_pairs` (`scalar = false`) or, pair by pair,
/// what the renderer layer does for one such light (`Bsdf::prepare_surface`, then
/// `Bsdf::eval_stokes`); the pairs of `Lcg::light_and_exit`. The sum of the last pass's
/// scattered `S0`.
fn run_pairs<T: Real>(
    reps: usize,
    scalar: bool,
    horizon: bool,
    (material, mueller): (bool, bool),
) -> f64 {
    use gmueller::bsdf::{Bsdf, SurfaceCoherence};
    use gmueller::interaction::RoughConductor;
    use gmueller::interaction::batch::{MuellerLobesSoa, MuellerSoa, PairsSoa};
    use gmueller::spectral::Metal;
    let lambda = T::lit(0.55);
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.0438), T::lit(0.619)).unwrap();
    let gold = RoughConductor::new(psd, Metal::Au.index(lambda)).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let sun = if horizon {
        SurfaceCoherence::new(T::lit(37.6)).unwrap()
    } else {
        SurfaceCoherence::fixed(T::lit(37.6)).unwrap()
    };
    let bsdf = Bsdf::new(&gold, kernel, surface, lambda).unwrap();
    let mut rng = Lcg(0x9a1e);
    let mut cols = vec![Vec::new(); 7];
    for i in 0..M {
        let (s, r) = rng.light_and_exit(i);
        for (c, x) in cols.iter_mut().zip(s.into_iter().chain(r)) {
            c.push(T::lit(x));
        }
        let s = Vector3::from(s).map(T::lit);
        cols[6].push(bsdf.surface_width(&s, &sun).unwrap().recip());
    }
    let k = T::two_pi() / lambda;
    let mut buf = vec![vec![T::zero(); M]; 8];
    let mut mbuf = vec![vec![T::zero(); if mueller { M } else { 0 }]; 32];
    let [a, b, c, d, e, f, g, h] = &mut buf[..] else {
        unreachable!()
    };
    let mut out = LobesSoa {
        specular: StokesSoa { s: [a, b, c, d] },
        scattered: StokesSoa { s: [e, f, g, h] },
    };
    let mat = gmueller::bsdf::Material::new(gold.clone(), gmueller::interaction::Level::ALL[7]);
    let at = gmueller::bsdf::ShadingPoint::new(surface, lambda).unwrap();
    for _ in 0..reps {
        if material {
            let to_source = DirectionsSoa {
                x: &cols[0],
                y: &cols[1],
                z: &cols[2],
            };
            let exits = DirectionsSoa {
                x: &cols[3],
                y: &cols[4],
                z: &cols[5],
            };
            mat.eval_incident_pairs(&at, &sun, to_source, exits, &mut out, None)
                .unwrap();
        } else if scalar {
            for (i, o) in out.scattered.s[0].iter_mut().enumerate() {
                let s = Vector3::new(cols[0][i], cols[1][i], cols[2][i]);
                let light = bsdf.prepare_surface(s, &sun).unwrap();
                let r = Vector3::new(cols[3][i], cols[4][i], cols[5][i]);
                *o = bsdf.eval_stokes(&light, r).unwrap().scattered.s0();
            }
        } else {
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
            if mueller {
                let (sp, sc) = mbuf.split_at_mut(16);
                let mut sp = sp.iter_mut().map(Vec::as_mut_slice);
                let mut sc = sc.iter_mut().map(Vec::as_mut_slice);
                let mut m = MuellerLobesSoa {
                    specular: MuellerSoa {
                        m: core::array::from_fn(|_| sp.next().unwrap()),
                    },
                    scattered: MuellerSoa {
                        m: core::array::from_fn(|_| sc.next().unwrap()),
                    },
                };
                kernel
                    .evaluate_pairs_mueller(&gold, k, &surface, pairs, &mut m, None)
                    .unwrap();
            } else {
                kernel
                    .evaluate_pairs(&gold, k, &surface, pairs, &mut out, None)
                    .unwrap();
            }
        }
    }
    if mueller {
        return mbuf[16].iter().map(|v| v.to_f64()).sum::<f64>();
    }
    out.scattered.s[0].iter().map(|v| v.to_f64()).sum::<f64>()
}

fn main() {
    let mut args = std::env::args().skip(1);
    let precision = args.next().unwrap_or_else(|| "f32".into());
    let reps = args.next().and_then(|r| r.parse().ok()).unwrap_or(1);
    let what = args.next().unwrap_or_else(|| "exits".into());
    let sum = match (precision.as_str(), what.as_str()) {
        ("f64", "exits") => run::<f64>(reps, false),
        (_, "exits") => run::<f32>(reps, false),
        ("f64", "exits-intensity") => run::<f64>(reps, true),
        (_, "exits-intensity") => run::<f32>(reps, true),
        ("f64", w) => run_pairs::<f64>(
            reps,
            w.ends_with("scalar"),
            w.contains("horizon"),
            (w.contains("material"), w.contains("mueller")),
        ),
        (_, w) => run_pairs::<f32>(
            reps,
            w.ends_with("scalar"),
            w.contains("horizon"),
            (w.contains("material"), w.contains("mueller")),
        ),
    };
    println!("{precision} {what}, {reps} passes of {M}: sum of scattered S0 = {sum:e}");
}
