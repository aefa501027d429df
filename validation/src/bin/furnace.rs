//! The white furnace of lossless interfaces at grazing incidence (issue 36 exploration).
use gmueller::bsdf::{Bsdf, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::{Full, Kernel, Partial, SmoothConductor, SmoothDielectric, Throughput};
use gmueller::stokes::Stokes;
use gmueller::verify::rng::SplitMix64;
use nalgebra::Vector3;
use num_complex::Complex;

const LAMBDA: f32 = 0.55;
const SUN: f32 = 6.8e-5;

fn dir(f: &Frame<f32>, deg: f64, side: f32) -> Vector3<f32> {
    let t = deg.to_radians();
    f.x() * (t.sin() as f32) + f.k() * (side * t.cos() as f32)
}

fn stats(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(200_000, |s| s.parse().unwrap());
    let f = Frame::from_normal(Vector3::new(0.0f32, 0.0, 1.0)).unwrap();
    let glass: SmoothDielectric<f32> = SmoothDielectric::smooth(1.5).unwrap();
    let metal: SmoothConductor<f32> = SmoothConductor::smooth(Complex::new(0.01, 100.0)).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let bg = Bsdf::new(&glass, kernel, f, LAMBDA).unwrap();
    let bm = Bsdf::new(&metal, kernel, f, LAMBDA).unwrap();
    let un = Stokes::unpolarized(1.0f32).unwrap();
    println!("dir      mat    w       θ=0      30      60      75      80      85      88      89");
    for w in [2.0f32, 5.0, 20.0, 100.0, 0.0] {
        for (name, is_glass) in [("glass", true), ("metal", false)] {
            let mut row = format!(
                "forward  {name:<6} {:<6}",
                if w == 0.0 {
                    "sun".into()
                } else {
                    format!("{w}")
                }
            );
            for deg in [0.0, 30.0, 60.0, 75.0, 80.0, 85.0, 88.0, 89.0] {
                let s = dir(&f, deg, 1.0);
                let mut rng = SplitMix64(7);
                let mut v = Vec::with_capacity(n);
                macro_rules! run {
                    ($b:expr) => {{
                        let b = $b;
                        let p = if w == 0.0 {
                            b.distant_packet(un, SUN, s).unwrap()
                        } else {
                            b.surface_packet(un, s, &SurfaceCoherence::new(w).unwrap())
                                .unwrap()
                        };
                        let inc = b.prepare(&p).unwrap();
                        for _ in 0..n {
                            let x = b
                                .sample_exit(
                                    &inc,
                                    rng.unit() as f32,
                                    [rng.unit() as f32, rng.unit() as f32],
                                )
                                .unwrap();
                            v.push(x.map_or(0.0, |x| x.weight.m00() as f64));
                        }
                    }};
                }
                if is_glass {
                    run!(&bg)
                } else {
                    run!(&bm)
                }
                let (m, se) = stats(&v);
                row += &format!(" {m:.4}({:.0})", se * 1e4);
            }
            println!("{row}");
        }
    }
    for w in [2.0f32, 5.0, 20.0, 100.0] {
        for (name, is_glass) in [("glass", true), ("metal", false)] {
            let mut row = format!("backward {name:<6} {w:<6}");
            for deg in [0.0, 30.0, 60.0, 75.0, 80.0, 85.0, 88.0, 89.0] {
                let r = dir(&f, deg, 1.0);
                let c = SurfaceCoherence::new(w).unwrap();
                let mut rng = SplitMix64(9);
                let mut v = Vec::with_capacity(n);
                macro_rules! run {
                    ($b:expr) => {{
                        let b = $b;
                        for _ in 0..n {
                            let x = b
                                .sample_incident(
                                    r,
                                    &c,
                                    rng.unit() as f32,
                                    [rng.unit() as f32, rng.unit() as f32],
                                )
                                .unwrap();
                            v.push(x.map_or(0.0, |x| {
                                let l = if x.sample.direction.z > 0.0 {
                                    1.0
                                } else {
                                    1.5f64 * 1.5
                                };
                                x.weight.m00() as f64 * l
                            }));
                        }
                    }};
                }
                if is_glass {
                    run!(&bg)
                } else {
                    run!(&bm)
                }
                let (m, se) = stats(&v);
                row += &format!(" {m:.4}({:.0})", se * 1e4);
            }
            println!("{row}");
        }
    }
}
