//! [`Kernel::evaluate_pairs`] against two oracles, per pair: the batch over exits of that
//! pair's own prepared packet (its lanes, `PartialLobes` with one packet and one exit: bit for
//! bit), and the per-direction kernel on that packet (within `evaluate_batch`'s documented
//! bound). Random pairs — every lane its own incidence (0–89°), exit (near the mirror direction
//! or anywhere above), coherence width (0.3–300 µm) — in `f64` and `f32`, at the three
//! polarization levels, partially coherent and incoherent, on gold (isotropic and anisotropic
//! PSDs) and on glass in reflection.

use std::cell::Cell;

use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;

use super::super::partial::{PartialLobes, ScalarExit, lane_prep_at, row_maker};
use super::super::per_lane::row_of;
use super::super::prep::LobePrep;
use super::super::{DirectionsSoa, ExitFramesSoa, LobesSoa, StokesSoa};
use super::PairsSoa;
use crate::error::Error;
use crate::frame::Frame;
use crate::gaussian::Gaussian;
use crate::interaction::coherence::{CoherenceModel, CoherenceWeights};
use crate::interaction::polarization::{KernelOutput, PolarizationModel};
use crate::interaction::roughness::{RoughnessLevel, RoughnessModel, RoughnessWeights};
use crate::interaction::{
    Full, Geometry, Incoherent, Intensity, Kernel, OneShape, Partial, RoughConductor,
    RoughDielectric, Surface,
};
use crate::numerics::{same, splitmix64};
use crate::psd::GaussianPsd;
use crate::real::Real;

thread_local! {
    /// The pairs `evaluate_pairs` sent to the per-direction kernel on this thread.
    pub(super) static PER_DIRECTION: Cell<usize> = const { Cell::new(0) };
}

/// One pair: the direction to the source, the exit and `1/w`.
type Pair = (Vector3<f64>, Vector3<f64>, f64);

/// Uniform in `[0, 1)`.
fn uniform(state: &mut u64) -> f64 {
    (splitmix64(state) >> 11) as f64 / (1u64 << 53) as f64
}

/// A unit direction at polar angle `theta` and azimuth `phi` about `+z`.
fn direction(theta: f64, phi: f64) -> Vector3<f64> {
    Vector3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// `n` random pairs `(to_source, exit, 1/w)`, the exits a third near the mirror direction
/// (within 0.05 rad), a third within 0.3 rad, a third anywhere above the surface; some lights
/// at the normal, some widths repeated.
fn pairs(seed: u64, n: usize) -> Vec<Pair> {
    let mut st = seed;
    let mut w = 1.0;
    (0..n)
        .map(|i| {
            // Every 23rd light at (or within √ε of) the normal, where the constants are built
            // pair by pair.
            let theta_i = match i % 23 {
                7 => [0.0, 1e-12, 1e-9, 1e-5][i % 4],
                _ => 89f64.to_radians() * uniform(&mut st).sqrt(),
            };
            let phi_i = std::f64::consts::TAU * uniform(&mut st);
            let s = direction(theta_i, phi_i);
            let spread = [0.05, 0.3, 1.5][i % 3];
            let theta_o = (theta_i + spread * (2.0 * uniform(&mut st) - 1.0)).clamp(0.0, 1.55);
            let phi_o = phi_i + std::f64::consts::PI + spread * (2.0 * uniform(&mut st) - 1.0);
            let r = direction(theta_o.abs(), phi_o) * (0.5 + 2.0 * uniform(&mut st));
            // Every third width repeats the one before (the pass reuses its constants).
            if i % 3 != 2 {
                w = 0.3 * 1000f64.powf(uniform(&mut st));
            }
            (s * (0.2 + 3.0 * uniform(&mut st)), r, 1.0 / w)
        })
        .collect()
}

/// `pairs(seed, n)` as the columns `[sx, sy, sz, rx, ry, rz, 1/w]` in type `T`.
fn columns<T: Real>(seed: u64, n: usize) -> [Vec<T>; 7] {
    let ps = pairs(seed, n);
    let col = |f: &dyn Fn(&Pair) -> f64| -> Vec<T> { ps.iter().map(|p| T::lit(f(p))).collect() };
    [
        col(&|p| p.0.x),
        col(&|p| p.0.y),
        col(&|p| p.0.z),
        col(&|p| p.1.x),
        col(&|p| p.1.y),
        col(&|p| p.1.z),
        col(&|p| p.2),
    ]
}

/// The Stokes columns (specular, scattered) and the exit s vectors of a batch of `n`.
struct Columns<T> {
    lobes: [Vec<T>; 8],
    frames: [Vec<T>; 3],
}

impl<T: Real> Columns<T> {
    fn new(n: usize) -> Self {
        Self {
            lobes: core::array::from_fn(|_| vec![T::lit(-7.0); n]),
            frames: core::array::from_fn(|_| vec![T::lit(-7.0); n]),
        }
    }

    /// `f` with the columns as the batch outputs.
    fn write(&mut self, f: impl FnOnce(&mut LobesSoa<'_, T>, &mut ExitFramesSoa<'_, T>)) {
        let [a, b, c, d, e, g, h, k] = &mut self.lobes;
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, c, d] },
            scattered: StokesSoa { s: [e, g, h, k] },
        };
        let [x, y, z] = &mut self.frames;
        let mut frames = ExitFramesSoa { s: [x, y, z] };
        f(&mut out, &mut frames);
    }
}

/// Checks every pair of `pairs(seed, n)` at wavelength `lambda`; returns how many pairs the
/// pass sent to the per-direction kernel.
fn check<T, S, Pol, Coh, Rough>(
    kernel: &Kernel<Pol, Coh, Rough>,
    material: &S,
    (seed, n, lambda): (u64, usize, f64),
    what: &str,
) -> usize
where
    T: Real,
    S: Surface<T>,
    Pol: PolarizationModel,
    Coh: CoherenceModel + CoherenceWeights<T, S::Psd>,
    Rough: RoughnessModel + RoughnessWeights<T, S::Psd, Coh>,
{
    let surface = Frame::from_normal(Vector3::new(T::zero(), T::zero(), T::one())).unwrap();
    let k = T::lit(std::f64::consts::TAU / lambda);
    let [sx, sy, sz, rx, ry, rz, inv_w] = columns::<T>(seed, n);
    let mut got = Columns::<T>::new(n);
    let before = PER_DIRECTION.with(Cell::get);
    got.write(|out, frames| {
        let pairs = PairsSoa {
            to_source: DirectionsSoa {
                x: &sx,
                y: &sy,
                z: &sz,
            },
            exit: DirectionsSoa {
                x: &rx,
                y: &ry,
                z: &rz,
            },
            inverse_width: &inv_w,
        };
        kernel
            .evaluate_pairs(material, k, &surface, pairs, out, Some(frames))
            .unwrap();
    });
    let redone = PER_DIRECTION.with(Cell::get) - before;
    let stokes_len = if got.lobes[1][0] == T::lit(-7.0) {
        1
    } else {
        4
    };
    let eps = T::EPSILON.to_f64();
    for i in 0..n {
        let s = Vector3::new(sx[i], sy[i], sz[i]);
        let r = Vector3::new(rx[i], ry[i], rz[i]);
        let prepared = kernel.prepare_unpolarized_isotropic(k, inv_w[i]);
        let g = Geometry::new(k, &surface, s, r).unwrap();
        let one = kernel.evaluate_prepared(material, &prepared, &g);
        let (sp, sc) = match one.stokes() {
            Some((sp, sc)) => (sp.0, sc.0),
            None => {
                let z = T::zero();
                let v = |x: T| nalgebra::Vector4::new(x, z, z, z);
                (v(one.specular_intensity()), v(one.scattered_intensity()))
            }
        };
        if Rough::LEVEL != RoughnessLevel::FirstOrder {
            // Not in lanes: the per-direction kernel itself.
            for c in 0..stokes_len {
                assert!(same(got.lobes[c][i], sp[c]) && same(got.lobes[4 + c][i], sc[c]));
            }
            continue;
        }
        // Oracle 1: the batch over exits of this pair's own packet, bit for bit.
        let prep = lane_prep_at(kernel, material, &prepared, s, &surface, None)
            .expect("a pair the lanes take");
        // The pass's lean per-pair constants are the whole LobePrep's, bit for bit.
        let m = row_maker(kernel, material).expect("a kernel the lanes take");
        let lean = LobePrep::lane_row_of(&prepared, m.psd, m.indices, s, &surface, m.incoherent)
            .expect("the pair's constants");
        for (a, b) in lean.iter().zip(row_of(&prep)) {
            assert!(same(*a, b), "{what}: pair {i}: lane constants");
        }
        let mut want = Columns::<T>::new(1);
        let mut scalar = |_: usize, _: usize| -> Result<ScalarExit<T>, Error> {
            Ok((sp.into(), sc.into(), g.exit_sp().x().into()))
        };
        want.write(|out, frames| {
            crate::simd::dispatch(PartialLobes {
                preps: core::slice::from_ref(&prep),
                series: &[],
                exits: DirectionsSoa {
                    x: &rx[i..=i],
                    y: &ry[i..=i],
                    z: &rz[i..=i],
                },
                outs: core::slice::from_mut(out),
                frames: Some(frames),
                scalar: &mut scalar,
            })
            .unwrap();
        });
        for c in (0..stokes_len).chain(4..4 + stokes_len) {
            let (a, b) = (got.lobes[c][i], want.lobes[c][0]);
            assert!(
                same(a, b),
                "{what}: pair {i}, column {c}: {:e} vs {:e}",
                a.to_f64(),
                b.to_f64()
            );
        }
        for c in 0..3 {
            assert!(
                same(got.frames[c][i], want.frames[c][0]),
                "{what}: pair {i} frame"
            );
        }
        // Oracle 2: the per-direction kernel, within evaluate_batch's bound (S0 = 1 and an
        // unpolarized one-shape packet: L̂ = (1 + √3) L).
        for (lobe, v) in [(0, sp), (4, sc)] {
            let l = v[0].to_f64();
            let bound = 4.0
                * eps
                * (4.0 + l.abs().max(f64::MIN_POSITIVE).ln().abs())
                * (1.0 + 3f64.sqrt())
                * l.abs()
                + T::MIN_POSITIVE.to_f64();
            for c in 0..stokes_len {
                let d = (got.lobes[lobe + c][i].to_f64() - v[c].to_f64()).abs();
                assert!(
                    d <= bound,
                    "{what}: pair {i}, lobe {lobe}, S{c}: {:e} vs {:e} (bound {bound:e})",
                    got.lobes[lobe + c][i].to_f64(),
                    v[c].to_f64()
                );
            }
        }
    }
    redone
}

/// What [`every_case`] runs for one kernel and material: [`check`] or [`check_mueller`].
trait Check {
    fn run<T, S, Pol, Coh, Rough>(
        kernel: &Kernel<Pol, Coh, Rough>,
        material: &S,
        case: (u64, usize, f64),
        what: &str,
    ) -> usize
    where
        T: Real,
        S: Surface<T>,
        Pol: PolarizationModel,
        Coh: CoherenceModel + CoherenceWeights<T, S::Psd>,
        Rough: RoughnessModel + RoughnessWeights<T, S::Psd, Coh>;
}

/// [`check`]: `evaluate_pairs`.
struct StokesPairs;
/// [`check_mueller`]: `evaluate_pairs_mueller`.
struct MuellerPairs;

impl Check for StokesPairs {
    fn run<T, S, Pol, Coh, Rough>(
        kernel: &Kernel<Pol, Coh, Rough>,
        material: &S,
        case: (u64, usize, f64),
        what: &str,
    ) -> usize
    where
        T: Real,
        S: Surface<T>,
        Pol: PolarizationModel,
        Coh: CoherenceModel + CoherenceWeights<T, S::Psd>,
        Rough: RoughnessModel + RoughnessWeights<T, S::Psd, Coh>,
    {
        check(kernel, material, case, what)
    }
}

impl Check for MuellerPairs {
    fn run<T, S, Pol, Coh, Rough>(
        kernel: &Kernel<Pol, Coh, Rough>,
        material: &S,
        case: (u64, usize, f64),
        what: &str,
    ) -> usize
    where
        T: Real,
        S: Surface<T>,
        Pol: PolarizationModel,
        Coh: CoherenceModel + CoherenceWeights<T, S::Psd>,
        Rough: RoughnessModel + RoughnessWeights<T, S::Psd, Coh>,
    {
        check_mueller(kernel, material, case, what)
    }
}

/// Every combination, `n` pairs each, in type `T`, through `C`; the pairs redone one at a time
/// stay few.
fn every_case<T: Real, C: Check>(seed: u64, n: usize) {
    let t = |x: f64| T::lit(x);
    let iso = GaussianPsd::<T, 2>::isotropic(t(0.02), t(1.0)).unwrap();
    let aniso = GaussianPsd::<T, 2>::from_autocorrelation(
        t(4e-4),
        &Gaussian::new(Matrix2::new(t(2.0), t(0.6), t(0.6), t(0.5))).unwrap(),
    )
    .unwrap();
    let gold = Complex::new(t(0.47), t(2.4));
    let gold_iso = RoughConductor::new(iso, gold).unwrap();
    let gold_aniso = RoughConductor::new(aniso, gold).unwrap();
    let glass = RoughDielectric::new(iso, t(1.5)).unwrap();
    let mut redone = 0;
    let mut total = 0;
    let mut run = |r: usize| {
        redone += r;
        total += n;
    };
    for (m, name) in [(&gold_iso, "gold"), (&gold_aniso, "gold, anisotropic")] {
        let case = |i: u64| (seed ^ (i << 32), n, 0.38 + 0.4 * (i as f64 / 6.0));
        run(C::run(
            &Kernel::<Full, Partial>::default(),
            m,
            case(0),
            name,
        ));
        run(C::run(
            &Kernel::<OneShape, Partial>::default(),
            m,
            case(1),
            name,
        ));
        run(C::run(
            &Kernel::<Intensity, Partial>::default(),
            m,
            case(2),
            name,
        ));
        run(C::run(
            &Kernel::<Full, Incoherent>::default(),
            m,
            case(3),
            name,
        ));
        run(C::run(
            &Kernel::<Intensity, Incoherent>::default(),
            m,
            case(4),
            name,
        ));
    }
    let case = (seed ^ (9 << 32), n, 0.55);
    run(C::run(
        &Kernel::<Full, Partial>::default(),
        &glass,
        case,
        "glass",
    ));
    run(C::run(
        &Kernel::<Intensity, Partial>::default(),
        &glass,
        case,
        "glass",
    ));
    // The lanes ran: most pairs were not sent to the per-direction kernel.
    assert!(
        redone * 10 < total,
        "{redone} of {total} pairs redone one at a time"
    );
}

#[test]
fn pairs_equal_the_batch_lanes_bit_for_bit() {
    every_case::<f64, StokesPairs>(0x5eed_0001, 203);
    every_case::<f32, StokesPairs>(0x5eed_0002, 203);
}

/// A pair the lanes cannot take (the Kirchhoff series) goes to the per-direction kernel, and
/// bad input is an error before anything is written.
#[test]
fn other_levels_and_bad_input() {
    use crate::interaction::roughness::KirchhoffSeries;
    let psd = GaussianPsd::<f64, 2>::isotropic(0.05, 1.0).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(0.47, 2.4)).unwrap();
    let series = Kernel::<Full, Partial, KirchhoffSeries>::default();
    let before = PER_DIRECTION.with(Cell::get);
    let redone = check(&series, &gold, (7, 17, 0.55), "series");
    assert_eq!(redone, 17);
    assert_eq!(PER_DIRECTION.with(Cell::get) - before, 17);
    let surface = Frame::from_normal(Vector3::z()).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let one = [0.5, 0.5];
    let (x, z) = ([0.1, 0.2], [1.0, 0.9]);
    let d = DirectionsSoa {
        x: &x,
        y: &x,
        z: &z,
    };
    let below_z = [1.0, -0.9];
    let below = DirectionsSoa {
        x: &x,
        y: &x,
        z: &below_z,
    };
    let cols = std::cell::RefCell::new(Columns::<f64>::new(2));
    let run = |pairs: PairsSoa<'_, f64>, k: f64| {
        let mut r = Ok(());
        cols.borrow_mut()
            .write(|out, _| r = kernel.evaluate_pairs(&gold, k, &surface, pairs, out, None));
        r
    };
    let pairs = |to_source, exit, inverse_width| PairsSoa {
        to_source,
        exit,
        inverse_width,
    };
    assert!(run(pairs(d, d, &one), 11.4).is_ok());
    assert!(run(pairs(d, d, &one), f64::NAN).is_err());
    assert!(run(pairs(d, d, &one), -1.0).is_err());
    assert!(run(pairs(d, d, &[0.5, f64::NAN]), 11.4).is_err());
    assert!(run(pairs(d, d, &[0.5, 0.0]), 11.4).is_err());
    assert!(run(pairs(d, d, &[0.5]), 11.4).is_err());
    assert!(run(pairs(d, below, &one), 11.4).is_err());
    assert!(run(pairs(below, d, &one), 11.4).is_err());
    // A failed call writes nothing.
    let first = cols.borrow().lobes.clone();
    assert!(run(pairs(d, below, &one), 11.4).is_err());
    assert_eq!(first, cols.borrow().lobes);
}

/// The error for the first bad pair of 37 (widths first, then directions, as documented), where
/// the vector validation sees it (a whole vector, the tail, every position), in both types;
/// against the scalar checks: the width test and `Geometry::new` of each pair in order.
fn first_error_is_the_scalar_one<T: Real>() {
    let t = |x: f64| T::lit(x);
    let psd = GaussianPsd::<T, 2>::isotropic(t(0.05), t(1.0)).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(t(0.47), t(2.4))).unwrap();
    let surface = Frame::from_normal(Vector3::new(t(0.0), t(0.0), t(1.0))).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let k = t(11.4);
    let n = 37;
    let ps = pairs(0xbad, n);
    let col = |f: &dyn Fn(&Pair) -> f64| -> Vec<T> { ps.iter().map(|p| t(f(p))).collect() };
    let good: [Vec<T>; 7] = [
        col(&|p| p.0.x),
        col(&|p| p.0.y),
        col(&|p| p.0.z),
        col(&|p| p.1.x),
        col(&|p| p.1.y),
        col(&|p| p.1.z),
        col(&|p| p.2),
    ];
    // (column, value): a bad width, a bad direction component, a direction below.
    let bad: [(usize, f64); 9] = [
        (6, f64::NAN),
        (6, 0.0),
        (6, -1.0),
        (6, f64::INFINITY),
        (0, f64::NAN),
        (4, f64::INFINITY),
        (2, -2.0),
        (5, -2.0),
        (5, 0.0),
    ];
    // The pairs as generated are all good.
    let mut got = Columns::<T>::new(n);
    got.write(|out, _| {
        let pairs = PairsSoa {
            to_source: DirectionsSoa {
                x: &good[0],
                y: &good[1],
                z: &good[2],
            },
            exit: DirectionsSoa {
                x: &good[3],
                y: &good[4],
                z: &good[5],
            },
            inverse_width: &good[6],
        };
        kernel
            .evaluate_pairs(&gold, k, &surface, pairs, out, None)
            .unwrap();
    });
    let mut cases = 0;
    for (a, &(ca, va)) in bad.iter().enumerate() {
        for &(cb, vb) in &bad[a..] {
            for (ia, ib) in [(0, 36), (5, 3), (17, 30), (36, 36), (33, 8)] {
                let mut c = good.clone();
                c[ca][ia] = t(va);
                c[cb][ib] = t(vb);
                // The scalar order: every width, then each pair's geometry.
                let width_ok = |w: T| w > T::zero() && w.is_finite();
                let want = match c[6].iter().find(|w| !width_ok(**w)) {
                    Some(w) => Err(Error::OutOfRange {
                        what: "inverse coherence width 1/w (1/µm)",
                        value: w.to_f64(),
                        expected: "positive and finite",
                    }),
                    None => (0..n).try_for_each(|i| {
                        let v = |j: usize| Vector3::new(c[j][i], c[j + 1][i], c[j + 2][i]);
                        Geometry::new(k, &surface, v(0), v(3)).map(|_| ())
                    }),
                };
                let mut got = Columns::<T>::new(n);
                let mut r = Ok(());
                got.write(|out, _| {
                    let pairs = PairsSoa {
                        to_source: DirectionsSoa {
                            x: &c[0],
                            y: &c[1],
                            z: &c[2],
                        },
                        exit: DirectionsSoa {
                            x: &c[3],
                            y: &c[4],
                            z: &c[5],
                        },
                        inverse_width: &c[6],
                    };
                    r = kernel.evaluate_pairs(&gold, k, &surface, pairs, out, None);
                });
                assert!(want.is_err(), "{ca} {cb} at {ia} {ib}: a bad pair");
                assert_eq!(
                    format!("{r:?}"),
                    format!("{want:?}"),
                    "{ca} {cb} at {ia} {ib}"
                );
                // Nothing written.
                assert!(got.lobes.iter().flatten().all(|v| *v == t(-7.0)));
                cases += 1;
            }
        }
    }
    assert_eq!(cases, 45 * 5);
}

#[test]
fn the_first_bad_pair_gives_the_error() {
    first_error_is_the_scalar_one::<f64>();
    first_error_is_the_scalar_one::<f32>();
}

/// Checks every pair of `pairs(seed, n)` through [`Kernel::evaluate_pairs_mueller`] against the
/// per-direction kernel's [`Kernel::evaluate_mueller_prepared`] of the pair's packet: every
/// entry within `evaluate_batch`'s bound for a vector of `S0 = M₀₀` (at the `Intensity`
/// level `M₀₀` alone, the other slices untouched), the exit frames bit for bit those of
/// [`Kernel::evaluate_pairs`]; returns how many pairs went to the per-direction kernel.
fn check_mueller<T, S, Pol, Coh, Rough>(
    kernel: &Kernel<Pol, Coh, Rough>,
    material: &S,
    (seed, n, lambda): (u64, usize, f64),
    what: &str,
) -> usize
where
    T: Real,
    S: Surface<T>,
    Pol: PolarizationModel,
    Coh: CoherenceModel + CoherenceWeights<T, S::Psd>,
    Rough: RoughnessModel + RoughnessWeights<T, S::Psd, Coh>,
{
    use crate::interaction::batch::{MuellerLobesSoa, MuellerSoa};
    use crate::interaction::polarization::{PolarizationLevel, Throughput};
    let surface = Frame::from_normal(Vector3::new(T::zero(), T::zero(), T::one())).unwrap();
    let k = T::lit(std::f64::consts::TAU / lambda);
    let [sx, sy, sz, rx, ry, rz, inv_w] = columns::<T>(seed, n);
    let pairs = PairsSoa {
        to_source: DirectionsSoa {
            x: &sx,
            y: &sy,
            z: &sz,
        },
        exit: DirectionsSoa {
            x: &rx,
            y: &ry,
            z: &rz,
        },
        inverse_width: &inv_w,
    };
    let mut m: [Vec<T>; 32] = core::array::from_fn(|_| vec![T::lit(-7.0); n]);
    let mut frames: [Vec<T>; 3] = core::array::from_fn(|_| vec![T::lit(-7.0); n]);
    let before = PER_DIRECTION.with(Cell::get);
    {
        let (a, b) = m.split_at_mut(16);
        let mut it_a = a.iter_mut().map(Vec::as_mut_slice);
        let mut it_b = b.iter_mut().map(Vec::as_mut_slice);
        let mut out = MuellerLobesSoa {
            specular: MuellerSoa {
                m: core::array::from_fn(|_| it_a.next().unwrap()),
            },
            scattered: MuellerSoa {
                m: core::array::from_fn(|_| it_b.next().unwrap()),
            },
        };
        let [fx, fy, fz] = &mut frames;
        let mut f = ExitFramesSoa { s: [fx, fy, fz] };
        kernel
            .evaluate_pairs_mueller(material, k, &surface, pairs, &mut out, Some(&mut f))
            .unwrap();
    }
    let redone = PER_DIRECTION.with(Cell::get) - before;
    // The Stokes pass's frames.
    let mut stokes = Columns::<T>::new(n);
    stokes.write(|out, f| {
        kernel
            .evaluate_pairs(material, k, &surface, pairs, out, Some(f))
            .unwrap();
    });
    let intensity = Pol::LEVEL == PolarizationLevel::Intensity;
    let eps = T::EPSILON.to_f64();
    for i in 0..n {
        let s = Vector3::new(sx[i], sy[i], sz[i]);
        let r = Vector3::new(rx[i], ry[i], rz[i]);
        let prepared = kernel.prepare_unpolarized_isotropic(k, inv_w[i]);
        let g = Geometry::new(k, &surface, s, r).unwrap();
        let one = kernel.evaluate_mueller_prepared(material, &prepared, &g);
        for (got, want) in frames.iter().zip(&stokes.frames) {
            assert!(same(got[i], want[i]), "{what}: pair {i} frame");
        }
        // Where the BSDF form writes a part as 0 because its scale alone is subnormal (its
        // unscaled matrix, some 10³ in these units, would have made it normal), the lanes keep
        // the product: there the oracle of M₀₀ (and of the first column) is the Stokes kernel,
        // which folds the matrix into the exponent, and every other entry is at most M₀₀.
        let stokes_one = kernel.evaluate_prepared(material, &prepared, &g);
        let (sp, sc) = match stokes_one.stokes() {
            Some((sp, sc)) => (sp.0, sc.0),
            None => {
                let z = T::zero();
                let v = |x: T| nalgebra::Vector4::new(x, z, z, z);
                (
                    v(stokes_one.specular_intensity()),
                    v(stokes_one.scattered_intensity()),
                )
            }
        };
        for (lobe, mut want, vector) in [
            (0, one.specular.entries(), sp),
            (16, one.scattered.entries(), sc),
        ] {
            let zeroed = want.iter().all(|x| *x == T::zero());
            if zeroed {
                let m00 = m[lobe][i];
                for e in 1..16 {
                    assert!(
                        intensity || m[lobe + e][i].abs() <= m00,
                        "{what}: pair {i}, lobe {lobe}: |M{e}| > M00"
                    );
                }
                if intensity {
                    want[0] = vector[0];
                } else {
                    for r in 0..4 {
                        want[4 * r] = vector[r];
                    }
                    for e in (0..16).filter(|e| e % 4 != 0) {
                        want[e] = m[lobe + e][i];
                    }
                }
            }
            let l = want[0].to_f64();
            let bound = 4.0
                * eps
                * (4.0 + l.abs().max(f64::MIN_POSITIVE).ln().abs())
                * (1.0 + 3f64.sqrt())
                * l.abs()
                + T::MIN_POSITIVE.to_f64();
            for e in 0..16 {
                let got = m[lobe + e][i];
                if intensity && e > 0 {
                    assert!(got == T::lit(-7.0), "{what}: pair {i}: M{e} written");
                    continue;
                }
                let d = (got.to_f64() - want[e].to_f64()).abs();
                assert!(
                    d <= bound,
                    "{what}: pair {i}, lobe {lobe}, M{}{}: {:e} vs {:e} (bound {bound:e})",
                    e / 4,
                    e % 4,
                    got.to_f64(),
                    want[e].to_f64()
                );
            }
        }
    }
    redone
}

#[test]
fn mueller_pairs_equal_the_per_direction_kernel() {
    every_case::<f64, MuellerPairs>(0x5eed_0003, 203);
    every_case::<f32, MuellerPairs>(0x5eed_0004, 203);
}
