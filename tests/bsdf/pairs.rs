//! Verifies `Bsdf::eval_stokes_pairs` (a wavefront renderer's next-event estimation: every
//! pair its own light direction and exit) against `Bsdf::prepare_surface` + `Bsdf::eval_stokes`
//! one pair at a time: on rough conductors (the kernel's pairs in lanes, then each coherent
//! lobe over its light's mass `E`) with the horizon rule on, within the lane path's bound
//! (`tests/interaction/batch/pairs.rs`) plus the four roundings of applying `1/E` on either
//! side; on a rough dielectric interface (pair by pair) bit for bit. The scenes of
//! `tests/interaction/batch/pairs.rs`; f64 and f32.

use crate::common;
use crate::common::Lcg;
use crate::interaction::batch::pairs::{Scene, local, scene_strategy, uniform_in};

use gmueller::Real;
use gmueller::bsdf::{Bsdf, BsdfKernel, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::batch::{DirectionsSoa, LobesSoa, StokesSoa};
use gmueller::interaction::polarization::KernelOutput;
use gmueller::interaction::{
    Full, Incoherent, Intensity, Kernel, OneShape, Partial, RoughConductor, RoughDielectric,
};
use gmueller::psd::GaussianPsd;
use nalgebra::Vector3;
use num_complex::Complex;
use proptest::prelude::*;

fn check<T, K>(sc: &Scene, kernel: K, dielectric: bool) -> Result<(), TestCaseError>
where
    T: Real,
    K: BsdfKernel<T, GaussianPsd<T, 2>>,
{
    let t = T::lit;
    let corr = Gaussian::new(sc.correlation.map(t)).unwrap();
    let psd = GaussianPsd::<T, 2>::from_autocorrelation(t(sc.sigma * sc.sigma), &corr).unwrap();
    let frame = Frame::from_direction_and_x(sc.frame.k().map(t), sc.frame.x().map(t)).unwrap();
    let lambda = t(sc.wavelength);
    let sky = SurfaceCoherence::new(t(sc.widths.0.sqrt() * sc.widths.1.sqrt())).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(t(sc.eta.re), t(sc.eta.im))).unwrap();
    let glass = RoughDielectric::new(psd, t(1.0 + sc.eta.re)).unwrap();
    let mut rng = Lcg(sc.seed);
    let n = sc.pairs;
    let mut cols: Vec<Vec<T>> = vec![Vec::new(); 6];
    for _ in 0..n {
        let s = local(
            &sc.frame,
            uniform_in(&mut rng, 0.0, 89.9),
            uniform_in(&mut rng, 0.0, 360.0),
        );
        let side = if dielectric && rng.uniform() < 0.4 {
            -1.0
        } else {
            1.0
        };
        let r = local(
            &sc.frame,
            uniform_in(&mut rng, 0.0, 89.0),
            uniform_in(&mut rng, 0.0, 360.0),
        );
        let r = r - sc.frame.k() * ((1.0 - side) * r.dot(&sc.frame.k()));
        for (c, v) in cols.iter_mut().zip([s.x, s.y, s.z, r.x, r.y, r.z]) {
            c.push(t(v));
        }
    }
    let mut buf = vec![vec![T::lit(-7.0); n]; 8];
    let [a, b, c, d, e, f, g, h] = &mut buf[..] else {
        unreachable!()
    };
    let mut out = LobesSoa {
        specular: StokesSoa { s: [a, b, c, d] },
        scattered: StokesSoa { s: [e, f, g, h] },
    };
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
    let eps = T::EPSILON.to_f64();
    let compare = |out: &LobesSoa<'_, T>,
                   one: &dyn Fn(Vector3<T>, Vector3<T>) -> (Vec<T>, Vec<T>),
                   exact: bool| {
        #[expect(
            clippy::needless_range_loop,
            reason = "pair i in six input columns and eight output columns"
        )]
        for i in 0..n {
            let at = |j: usize| Vector3::new(cols[j][i], cols[j + 1][i], cols[j + 2][i]);
            let (sp, scat) = one(at(0), at(3));
            for (lobe, want) in [(&out.specular, sp), (&out.scattered, scat)] {
                let l = want[0].to_f64().abs();
                let bound = if exact {
                    0.0
                } else {
                    4.0 * eps
                        * (4.0 + l.max(f64::MIN_POSITIVE).ln().abs())
                        * (1.0 + 3f64.sqrt())
                        * l
                        + 8.0 * eps * l
                        + T::MIN_POSITIVE.to_f64()
                };
                for (c, w) in want.iter().enumerate() {
                    let got = lobe.s[c][i].to_f64();
                    prop_assert!(
                        (got - w.to_f64()).abs() <= bound,
                        "pair {}, S{}: {:e} vs {:e} (bound {:e})",
                        i,
                        c,
                        got,
                        w.to_f64(),
                        bound
                    );
                }
            }
        }
        Ok(())
    };
    let split = |r: <K::Pol as gmueller::interaction::polarization::PolarizationModel>::Output<
        T,
    >| match r.stokes() {
        Some((sp, sc)) => (
            sp.vector().iter().copied().collect(),
            sc.vector().iter().copied().collect(),
        ),
        None => (vec![r.specular_intensity()], vec![r.scattered_intensity()]),
    };
    if dielectric {
        let bsdf = Bsdf::new(&glass, kernel, frame, lambda).unwrap();
        bsdf.eval_stokes_pairs(&sky, to_source, exits, &mut out, None)
            .unwrap();
        compare(
            &out,
            &|s, r| {
                split(
                    bsdf.eval_stokes(&bsdf.prepare_surface(s, &sky).unwrap(), r)
                        .unwrap(),
                )
            },
            true,
        )
    } else {
        let bsdf = Bsdf::new(&gold, kernel, frame, lambda).unwrap();
        bsdf.eval_stokes_pairs(&sky, to_source, exits, &mut out, None)
            .unwrap();
        compare(
            &out,
            &|s, r| {
                split(
                    bsdf.eval_stokes(&bsdf.prepare_surface(s, &sky).unwrap(), r)
                        .unwrap(),
                )
            },
            false,
        )
    }
}

fn run<T: Real>(sc: &Scene, dielectric: bool) -> Result<(), TestCaseError> {
    match sc.level {
        0 => check::<T, _>(sc, Kernel::<Full, Partial>::default(), dielectric),
        1 => check::<T, _>(sc, Kernel::<OneShape, Partial>::default(), dielectric),
        2 => check::<T, _>(sc, Kernel::<Intensity, Partial>::default(), dielectric),
        3 => check::<T, _>(sc, Kernel::<Full, Incoherent>::default(), dielectric),
        _ => check::<T, _>(sc, Kernel::<Intensity, Incoherent>::default(), dielectric),
    }
}

proptest! {
    #![proptest_config(common::proptest_config(32))]

    #[test]
    fn eval_stokes_pairs_matches_one_pair_at_a_time_f64(
        sc in scene_strategy(false), dielectric in any::<bool>()
    ) {
        run::<f64>(&sc, dielectric)?;
    }

    #[test]
    fn eval_stokes_pairs_matches_one_pair_at_a_time_f32(
        sc in scene_strategy(false), dielectric in any::<bool>()
    ) {
        run::<f32>(&sc, dielectric)?;
    }
}

/// `Material::eval_incident_pairs` against `Material::eval_incident` one pair at a time (its
/// Mueller matrices applied to unpolarized light of unit irradiance), on gold one-sided and
/// two-sided (exits on both sides of the frame, the lower ones on the flipped side), at the
/// Full and Intensity levels, f64: within the lane bound plus `8 ε L` (the Mueller form's
/// products against the Stokes form's) and `MIN_POSITIVE`.
#[test]
fn material_pairs_match_eval_incident_one_sided_and_two_sided() {
    use gmueller::bsdf::{Material, ShadingPoint};
    use gmueller::interaction::Level;
    let psd = GaussianPsd::<f64, 2>::isotropic(0.03, 0.8).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(0.47, 2.4)).unwrap();
    let frame = Frame::from_direction_and_x(
        Vector3::new(0.2, -0.1, 1.0).normalize(),
        Vector3::new(1.0, 0.3, 0.0),
    )
    .unwrap();
    let at = ShadingPoint::new(frame, 0.6).unwrap();
    let sky = SurfaceCoherence::new(15.0).unwrap();
    let mut rng = Lcg(0x7a1e);
    let n = 150;
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 6];
    for i in 0..n {
        let (s, r) = rng.light_and_exit(i);
        // Light and exit about the frame's normal, on the upper side or both below.
        let down = if i % 3 == 2 { -1.0 } else { 1.0 };
        let world = |v: [f64; 3]| (frame.x() * v[0] + frame.y() * v[1] + frame.k() * v[2]) * down;
        let (s, r) = (world(s), world(r));
        for (c, v) in cols.iter_mut().zip([s.x, s.y, s.z, r.x, r.y, r.z]) {
            c.push(v);
        }
    }
    let eps = f64::EPSILON;
    for (two_sided, level) in [(false, 7), (true, 7), (true, 1)] {
        let m = Material::new(gold.clone(), Level::ALL[level]).two_sided(two_sided);
        let mut buf = vec![vec![-7.0; n]; 11];
        let [a, b, c, d, e, f, g, h, fx, fy, fz] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, c, d] },
            scattered: StokesSoa { s: [e, f, g, h] },
        };
        let mut frames = gmueller::interaction::batch::ExitFramesSoa { s: [fx, fy, fz] };
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
        let done = m.eval_incident_pairs(&at, &sky, to_source, exits, &mut out, Some(&mut frames));
        if !two_sided {
            // The lower pairs are below a one-sided conductor: an error, as eval_incident's.
            assert!(done.is_err());
            continue;
        }
        done.unwrap();
        let len = if level == 1 { 1 } else { 4 };
        #[expect(
            clippy::needless_range_loop,
            reason = "pair i in six input columns and eleven output columns"
        )]
        for i in 0..n {
            let s = Vector3::new(cols[0][i], cols[1][i], cols[2][i]);
            let r = Vector3::new(cols[3][i], cols[4][i], cols[5][i]);
            let v = m.eval_incident(&at, r, &sky, s).unwrap();
            let unpolarized = nalgebra::Vector4::new(1.0, 0.0, 0.0, 0.0);
            let lobes = [
                (v.response.specular.matrix() * unpolarized, &out.specular),
                (v.response.scattered.matrix() * unpolarized, &out.scattered),
            ];
            for (want, got) in lobes {
                let l = want[0].abs();
                let bound = 4.0
                    * eps
                    * (4.0 + l.max(f64::MIN_POSITIVE).ln().abs())
                    * (1.0 + 3f64.sqrt())
                    * l
                    + 8.0 * eps * l
                    + f64::MIN_POSITIVE;
                for c in 0..len {
                    assert!(
                        (got.s[c][i] - want[c]).abs() <= bound,
                        "level {level}, pair {i}, S{c}: {:e} vs {:e}",
                        got.s[c][i],
                        want[c]
                    );
                }
            }
            let so = Vector3::new(frames.s[0][i], frames.s[1][i], frames.s[2][i]);
            assert!(
                (so - v.geometry.exit_sp().x()).norm() <= 8.0 * eps,
                "pair {i} frame"
            );
        }
    }
}

/// A pair rejected beyond the first chunk of 128 — an exit or a light below the surface, a
/// direction with a NaN, a zero direction to the light: the error of that pair one at a time
/// (`prepare_surface`, then `eval_stokes`), and nothing written.
#[test]
fn a_bad_pair_anywhere_writes_nothing() {
    let psd = GaussianPsd::<f64, 2>::isotropic(0.03, 0.8).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(0.47, 2.4)).unwrap();
    let frame = Frame::from_normal(Vector3::z()).unwrap();
    let bsdf = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), frame, 0.6).unwrap();
    let sky = SurfaceCoherence::new(15.0).unwrap();
    let n = 300;
    type Spoil = fn(&mut [f64; 3], &mut [f64; 3]);
    let spoil: [Spoil; 5] = [
        |_, r| r[2] = -r[2],
        |s, _| s[2] = -s[2],
        |s, _| s[0] = f64::NAN,
        |_, r| r[1] = f64::NAN,
        |s, _| *s = [0.0; 3],
    ];
    for (kind, spoil) in spoil.iter().enumerate() {
        let mut rng = Lcg(0xbad);
        let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 6];
        let mut bad = None;
        for i in 0..n {
            let (mut s, mut r) = rng.light_and_exit(i);
            if i == 250 {
                spoil(&mut s, &mut r);
                let light = bsdf.prepare_surface(Vector3::from(s), &sky);
                bad = Some(light.and_then(|l| bsdf.eval_stokes(&l, Vector3::from(r)).map(|_| ())));
            }
            for (c, v) in cols.iter_mut().zip(s.into_iter().chain(r)) {
                c.push(v);
            }
        }
        let want = bad.unwrap();
        assert!(want.is_err(), "kind {kind}: one at a time, an error");
        let mut buf = vec![vec![-7.0; n]; 8];
        let [a, b, c, d, e, f, g, h] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, c, d] },
            scattered: StokesSoa { s: [e, f, g, h] },
        };
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
        let got = bsdf.eval_stokes_pairs(&sky, to_source, exits, &mut out, None);
        assert_eq!(format!("{got:?}"), format!("{want:?}"), "kind {kind}");
        assert!(buf.iter().flatten().all(|v| *v == -7.0), "kind {kind}");
    }
}
