//! The vector exponential against the standard library's over the whole range, and the
//! batch loop against the per-direction kernel, on every back-end: pulp's scalar ones of 1, 2, 4
//! and 8 lanes, and AVX2 + FMA and AVX-512 when present.
use nalgebra::Vector2;
use num_complex::Complex;

use super::*;
use crate::interaction::pbsdf::Pbsdf;
use crate::psd::Psd;
use crate::simd::exp::vexp;

/// Evaluates `vexp` on `xs` with back-end `s`, lane by lane through `load/store_partial`.
struct ExpAll<'a, F> {
    xs: &'a [F],
    out: &'a mut [F],
}

impl<F: Real> WithSimd for ExpAll<'_, F> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) {
        let lanes = F::width::<S>();
        for (x, o) in self.xs.chunks(lanes).zip(self.out.chunks_mut(lanes)) {
            let v = vexp::<S, F>(s, F::load_partial(s, x));
            F::store_partial(s, o, v);
        }
    }
}

/// ulp distance between two non-negative floats of one type, through their bit patterns.
fn ulps_f64(a: f64, b: f64) -> u64 {
    a.to_bits().abs_diff(b.to_bits())
}

fn ulps_f32(a: f32, b: f32) -> u64 {
    u64::from(a.to_bits().abs_diff(b.to_bits()))
}

fn sweep<F: Real>(lo: f64, hi: f64, count: usize, specials: &[f64]) -> Vec<F> {
    let mut xs: Vec<F> = (0..count)
        .map(|i| F::lit(lo + (hi - lo) * (i as f64 + 0.5) / count as f64))
        .collect();
    xs.extend(specials.iter().map(|&v| F::lit(v)));
    xs
}

fn run_all<F: Real>(xs: &[F], mut check: impl FnMut(&str, &[F])) {
    let mut out = vec![F::zero(); xs.len()];
    ExpAll { xs, out: &mut out }.with_simd(pulp::Scalar);
    check("Scalar", &out);
    ExpAll { xs, out: &mut out }.with_simd(pulp::Scalar128b);
    check("Scalar128b", &out);
    ExpAll { xs, out: &mut out }.with_simd(pulp::Scalar256b);
    check("Scalar256b", &out);
    ExpAll { xs, out: &mut out }.with_simd(pulp::Scalar512b);
    check("Scalar512b", &out);
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = pulp::x86::V3::try_new() {
        Simd::vectorize(v3, ExpAll { xs, out: &mut out });
        check("V3", &out);
    }
    #[cfg(target_arch = "x86_64")]
    if let Some(v4) = pulp::x86::V4::try_new() {
        Simd::vectorize(v4, ExpAll { xs, out: &mut out });
        check("V4", &out);
    }
}

/// Seeded unit directions around the specular one and near the normal (every band of
/// `Frame::sp`), `n` of them.
fn exits<F: Real>(theta_i: f64, n: usize) -> Vec<Vector3<F>> {
    stages::fixture::seeded_exits(theta_i, n, 0.2)
        .iter()
        .map(|e| e.map(F::lit))
        .collect()
}

/// Every back-end of the batch loop (pulp's scalar ones of 1, 2, 4, 8 lanes, which exercise
/// the remainder logic at every width and the unfused arithmetic of machines without FMA,
/// and AVX2 + FMA and AVX-512 when present) against the per-direction kernel, lengths 0–41,
/// normal and oblique
/// incidence, dielectric and metal; tolerance `4 ε (4 + |E|) S0` as in
/// `tests/interaction/batch/plane_wave.rs`.
fn back_ends<F: Real>() {
    let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let psd = GaussianPsd::<F, 2>::isotropic(F::lit(0.02), F::lit(1.5)).unwrap();
    for (theta_i, eta) in [(0.0_f64, (1.5, 0.0)), (0.6, (0.3, 6.0)), (1.2, (2.0, 0.5))] {
        let eta = Complex::new(F::lit(eta.0), F::lit(eta.1));
        let travel = Vector3::new(theta_i.sin(), 0.0, -theta_i.cos()).map(F::lit);
        let frame = Frame::sp(travel, Vector3::z())
            .unwrap()
            .rotated(F::lit(0.7));
        let stokes = crate::stokes::Stokes::new(F::one(), F::lit(0.3), F::lit(-0.5), F::lit(0.6));
        let packet = WavePacket::from_stokes(
            stokes.unwrap(),
            crate::packet::CoherenceShape::isotropic(F::lit(5.0)).unwrap(),
            frame,
            F::lit(0.5),
        )
        .unwrap();
        let prep = PlaneWavePrep::new(&psd, eta * eta, &packet, &surface).unwrap();
        assert!(prep.vectorizable);
        let scatter = RayleighRice::new(eta).unwrap();
        for n in 0..42 {
            let e = exits::<F>(theta_i, n);
            let (x, y, z): (Vec<F>, Vec<F>, Vec<F>) = (
                e.iter().map(|v| v.x).collect(),
                e.iter().map(|v| v.y).collect(),
                e.iter().map(|v| v.z).collect(),
            );
            let dirs = DirectionsSoa {
                x: &x,
                y: &y,
                z: &z,
            };
            let run = |op: &dyn Fn(&mut StokesSoa<'_, F>) -> Result<(), Error>| {
                let mut s = [(); 4].map(|()| vec![F::lit(f64::NAN); n]);
                let [s0, s1, s2, s3] = &mut s;
                op(&mut StokesSoa {
                    s: [s0, s1, s2, s3],
                })
                .unwrap();
                s
            };
            let want = run(&|out| portable(&psd, scatter, &packet, &surface, &dirs, out));
            let check = |what: &str, got: [Vec<F>; 4]| {
                for i in 0..n {
                    let g = Geometry::for_packet(&packet, &surface, e[i]).unwrap();
                    let (k, ci, co) = (g.k.to_f64(), g.cos_i.to_f64(), g.cos_o.to_f64());
                    let big_e = psd.log_value(&g.h_t).to_f64().abs()
                        + prep.log_scale.to_f64().abs()
                        + (k * (ci + co)).powi(2) * psd.variance().to_f64();
                    let s0 = want[0][i].to_f64();
                    // Results the per-direction path rounds through subnormal numbers: the smallest
                    // normal number times the output scale.
                    let lam = core::f64::consts::TAU / k;
                    let amp = psd.log_value(&Vector2::zeros()).to_f64().exp().max(1.0);
                    let scale =
                        core::f64::consts::TAU * co / (lam * lam) * scatter.m00(&g).to_f64() * amp;
                    let min_size = (F::MIN_POSITIVE / F::EPSILON).to_f64();
                    let tiny = min_size * F::EPSILON.to_f64() * scale;
                    let tol = tiny + 4.0 * F::EPSILON.to_f64() * (4.0 + big_e) * s0;
                    for c in 0..4 {
                        let d = (got[c][i].to_f64() - want[c][i].to_f64()).abs();
                        assert!(
                            d <= tol,
                            "{what}: θ_i {theta_i}, n {n}, exit {i}, S{c}: {d:e} > {tol:e}"
                        );
                    }
                }
            };
            let batch =
                |s: &mut StokesSoa<'_, F>,
                 simd: &dyn Fn(Batch<'_, '_, '_, F>) -> Result<(), Error>| {
                    simd(Batch {
                        prep: &prep,
                        exits: &dirs,
                        out: s,
                    })
                };
            check("Scalar", run(&|o| batch(o, &|b| b.with_simd(pulp::Scalar))));
            check(
                "Scalar128b",
                run(&|o| batch(o, &|b| b.with_simd(pulp::Scalar128b))),
            );
            check(
                "Scalar256b",
                run(&|o| batch(o, &|b| b.with_simd(pulp::Scalar256b))),
            );
            check(
                "Scalar512b",
                run(&|o| batch(o, &|b| b.with_simd(pulp::Scalar512b))),
            );
            check("dispatched", run(&|o| kernel_simd(&prep, &dirs, o)));
            #[cfg(target_arch = "x86_64")]
            if let Some(v3) = pulp::x86::V3::try_new() {
                check("V3", run(&|o| batch(o, &|b| Simd::vectorize(v3, b))));
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(v4) = pulp::x86::V4::try_new() {
                check("V4", run(&|o| batch(o, &|b| Simd::vectorize(v4, b))));
            }
        }
    }
}

#[test]
fn every_back_end_matches_the_per_direction_kernel_f64() {
    back_ends::<f64>();
}

#[test]
fn every_back_end_matches_the_per_direction_kernel_f32() {
    back_ends::<f32>();
}

/// `vexp` on 2²⁰ points of `[lo, hi]` plus `specials`, every back-end, against the standard
/// library's `exp`: at most 2 ulp (an infinite result must be infinite); prints the worst.
fn check_vexp<F: Real + core::fmt::LowerExp>(
    lo: f64,
    hi: f64,
    specials: &[f64],
    ulps: fn(F, F) -> u64,
) {
    let xs = sweep::<F>(lo, hi, 1 << 20, specials);
    let mut worst = (0_u64, F::zero());
    run_all(&xs, |what, got| {
        for (&x, &g) in xs.iter().zip(got) {
            let want = x.exp();
            let u = if want.is_finite() {
                ulps(g, want)
            } else {
                u64::from(g.is_finite()) * u64::MAX
            };
            if u > worst.0 {
                worst = (u, x);
            }
            assert!(u <= 2, "{what}: exp({x:e}) = {g:e}, std {want:e}: {u} ulp");
        }
    });
    println!("vexp: max {} ulp (at x = {:e})", worst.0, worst.1);
}

#[test]
fn vexp_f64_within_2_ulp_over_the_whole_range() {
    let specials = [
        f64::NEG_INFINITY,
        -1e300,
        -746.0,
        -745.2,
        -745.1332191019412,
        -745.13,
        -744.0,
        -708.4,
        -708.3,
        -1e-300,
        -0.0,
        0.0,
        1e-300,
        1e-17,
        -1e-17,
        0.34657359027997264,
        -0.34657359027997264,
        709.78,
        709.782712893384,
        709.8,
        1e300,
        f64::INFINITY,
    ];
    check_vexp::<f64>(-746.0, 710.0, &specials, ulps_f64);
}

#[test]
fn vexp_f32_within_2_ulp_over_the_whole_range() {
    let specials = [
        f64::NEG_INFINITY,
        -1e30,
        -104.0,
        -103.98,
        -103.972,
        -103.97,
        -87.4,
        -87.3,
        -1e-30,
        0.0,
        1e-30,
        0.3465736,
        -0.3465736,
        88.72,
        88.7228,
        88.73,
        1e30,
        f64::INFINITY,
    ];
    check_vexp::<f32>(-104.0, 89.0, &specials, ulps_f32);
}
