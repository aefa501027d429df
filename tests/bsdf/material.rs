//! `bsdf::Material`, the type-erased material, against the static `Bsdf` of the same choice
//! (issue 37): bit-identical answers on random scenes — five surface kinds (rough glass, a
//! Gaussian-mixture conductor, a K-correlation conductor, a metal grating, smooth glass) at
//! all nine levels, and beyond first order, in `f32` and `f64`, for every call (eval of a
//! packet, eval of surface-coherent light, backward and forward sample, both pdfs) — and the
//! two-sided option: the back of a two-sided opaque surface answers as its front turned over,
//! bit for bit, and a one-sided one refuses it.

use gmueller::bsdf::{Bsdf, Interface, Material, ShadingPoint, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::level::{LevelVisitor, RoughLevelVisitor};
use gmueller::interaction::pbsdf::Pbsdf;
use gmueller::interaction::polarization::{PolarizationModel, Throughput};
use gmueller::interaction::roughness::{KirchhoffSeries, RoughnessWeights};
use gmueller::interaction::{
    Kernel, Level, RoughConductor, RoughDielectric, RoughSurface, Roughness,
};
use gmueller::mueller::Mueller;
use gmueller::psd::{
    BlurMethod, ClosedForm, GaussHermite, GaussianMixturePsd, GaussianPsd, Grating, KCorrelation,
    Smooth,
};
use gmueller::real::Real;
use gmueller::stokes::Stokes;
use nalgebra::{Vector2, Vector3};
use num_complex::Complex;

/// A small deterministic generator (`SplitMix64`).
struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One random scene: shading frame, wavelength, directions, coherence, uniforms.
#[derive(Debug, Clone, Copy)]
struct Scene {
    normal: [f64; 3],
    lambda: f64,
    exit: [f64; 3],
    source: [f64; 3],
    width: f64,
    u: [f64; 3],
}

fn scene(rng: &mut Rng, opaque: bool) -> Scene {
    let unit = |z_sign: f64, rng: &mut Rng| {
        let t = rng.unit() * 80f64.to_radians();
        let p = rng.unit() * std::f64::consts::TAU;
        [t.sin() * p.cos(), t.sin() * p.sin(), z_sign * t.cos()]
    };
    let normal = [rng.unit() - 0.5, rng.unit() - 0.5, 2.0];
    let transmit = !opaque && rng.unit() < 0.3;
    let exit = unit(1.0, rng);
    let source = unit(if transmit { -1.0 } else { 1.0 }, rng);
    Scene {
        normal,
        lambda: 0.4 + 0.3 * rng.unit(),
        exit,
        source,
        width: 2.0 + 40.0 * rng.unit(),
        u: [rng.unit(), rng.unit(), rng.unit()],
    }
}

/// The directions of `s` in the frame `f` (given in its local coordinates).
fn local<T: Real>(f: &Frame<T>, d: [f64; 3]) -> Vector3<T> {
    (f.x() * T::lit(d[0]) + f.y() * T::lit(d[1]) + f.k() * T::lit(d[2])).normalize()
}

/// Every number a call answers, in order (for bit comparison): `None` marks an error.
type Answers = Vec<Option<Vec<u64>>>;

fn bits<T: Real>(xs: impl IntoIterator<Item = T>) -> Vec<u64> {
    xs.into_iter().map(|x| x.to_f64().to_bits()).collect()
}

fn mueller_bits<T: Real>(m: &Mueller<T>) -> Vec<u64> {
    bits(m.matrix().iter().copied())
}

/// The static form's answers for `s`.
struct Static<'a, T: Real, P, Sp, Sc> {
    surface: &'a RoughSurface<P, Sp, Sc>,
    s: Scene,
    _t: core::marker::PhantomData<T>,
}

impl<T: Real, P, Sp, Sc> Static<'_, T, P, Sp, Sc>
where
    P: gmueller::psd::Psd<T, 2>,
    Sp: Interface<T>,
    Sc: Pbsdf<T>,
{
    fn run<Pol, Coh, Rough>(&self, kernel: Kernel<Pol, Coh, Rough>) -> Answers
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P>,
        Rough: RoughnessWeights<T, P, Coh>,
    {
        let s = self.s;
        let f = Frame::from_normal(Vector3::from(s.normal).map(T::lit)).unwrap();
        let (exit, source) = (local(&f, s.exit), local(&f, s.source));
        let c = SurfaceCoherence::new(T::lit(s.width)).unwrap();
        let b = Bsdf::new(self.surface, kernel, f, T::lit(s.lambda)).unwrap();
        let mut out = Answers::new();
        let value = |v: gmueller::bsdf::BsdfValue<T, Pol::Throughput<T>>| {
            let mut x = mueller_bits(&v.response.specular.to_mueller());
            x.extend(mueller_bits(&v.response.scattered.to_mueller()));
            x
        };
        let sample = |v: gmueller::bsdf::BsdfSample<T, Pol::Throughput<T>>| {
            let mut x = bits(v.sample.direction.iter().copied());
            x.push(v.sample.pdf.to_f64().to_bits());
            x.extend(mueller_bits(&v.weight.to_mueller()));
            x
        };
        let (u0, u) = (T::lit(s.u[0]), [T::lit(s.u[1]), T::lit(s.u[2])]);
        // Backward.
        let drawn = b.sample_incident(exit, &c, u0, u);
        out.push(
            drawn
                .as_ref()
                .ok()
                .map(|x| x.map(sample).unwrap_or_default()),
        );
        out.push(
            b.incident_sampler(exit, &c)
                .ok()
                .map(|m| bits([m.pdf(&source)])),
        );
        out.push(
            b.prepare_surface(source, &c)
                .and_then(|l| b.eval(&l, exit))
                .ok()
                .map(value),
        );
        // Forward, with a polarized surface packet from `source`.
        let stokes = Stokes::new(T::one(), T::lit(0.3), T::lit(-0.2), T::lit(0.1)).unwrap();
        let packet = b.surface_packet(stokes, source, &c).unwrap();
        let inc = b.prepare(&packet).unwrap();
        out.push(b.eval(&inc, exit).ok().map(value));
        out.push(
            b.sample_exit(&inc, u0, u)
                .ok()
                .map(|x| x.map(sample).unwrap_or_default()),
        );
        out.push(b.exit_sampler(&inc).ok().map(|m| bits([m.pdf(&exit)])));
        out
    }
}

impl<T: Real, P, Sp, Sc> LevelVisitor<T, P> for Static<'_, T, P, Sp, Sc>
where
    P: gmueller::psd::Psd<T, 2>,
    Sp: Interface<T>,
    Sc: Pbsdf<T>,
{
    type Output = Answers;
    fn visit<Pol, Coh>(self, _level: Level, kernel: Kernel<Pol, Coh>) -> Answers
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P>,
    {
        self.run(kernel)
    }
}

impl<T: Real, P, Sp, Sc> RoughLevelVisitor<T, P> for Static<'_, T, P, Sp, Sc>
where
    P: gmueller::psd::Psd<T, 2>,
    Sp: Interface<T>,
    Sc: Pbsdf<T>,
{
    type Output = Answers;
    fn visit<Pol, Coh, Rough>(self, _level: Level, kernel: Kernel<Pol, Coh, Rough>) -> Answers
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P>,
        Rough: RoughnessWeights<T, P, Coh>,
    {
        self.run(kernel)
    }
}

/// The erased form's answers for `s`, in the order of [`Static::run`].
fn erased<T: Real>(m: &Material<T>, s: Scene) -> Answers {
    let f = Frame::from_normal(Vector3::from(s.normal).map(T::lit)).unwrap();
    let (exit, source) = (local(&f, s.exit), local(&f, s.source));
    let c = SurfaceCoherence::new(T::lit(s.width)).unwrap();
    let at = ShadingPoint::new(f, T::lit(s.lambda)).unwrap();
    let value = |v: gmueller::bsdf::BsdfValue<T, Mueller<T>>| {
        let mut x = mueller_bits(&v.response.specular);
        x.extend(mueller_bits(&v.response.scattered));
        x
    };
    let sample = |v: gmueller::bsdf::BsdfSample<T, Mueller<T>>| {
        let mut x = bits(v.sample.direction.iter().copied());
        x.push(v.sample.pdf.to_f64().to_bits());
        x.extend(mueller_bits(&v.weight));
        x
    };
    let (u0, u) = (T::lit(s.u[0]), [T::lit(s.u[1]), T::lit(s.u[2])]);
    let mut out = Answers::new();
    out.push(
        m.sample_incident(&at, exit, &c, u0, u)
            .ok()
            .map(|x| x.map(sample).unwrap_or_default()),
    );
    out.push(
        m.pdf_incident(&at, exit, &c, source)
            .ok()
            .map(|p| bits([p])),
    );
    out.push(m.eval_incident(&at, exit, &c, source).ok().map(value));
    // The same three from one build of the sampler: bit for bit the calls above.
    match m.incident_vertex(&at, exit, &c, Some(source), u0, u) {
        Ok(v) => {
            assert_eq!(Some(v.sample.map(sample).unwrap_or_default()), out[0]);
            match v.light.expect("a light direction was given") {
                Ok(light) => {
                    assert_eq!(Some(bits([light.pdf])), out[1]);
                    assert_eq!(Some(value(light.value)), out[2]);
                }
                Err(_) => assert_eq!(out[2], None),
            }
        }
        Err(_) => assert_eq!(out[0], None),
    }
    // Forward, with a polarized surface packet from `source`.
    let stokes = Stokes::new(T::one(), T::lit(0.3), T::lit(-0.2), T::lit(0.1)).unwrap();
    let packet = m.surface_packet(&at, stokes, source, &c).unwrap();
    out.push(m.eval(&at, &packet, exit).ok().map(value));
    out.push(
        m.sample_exit(&at, &packet, u0, u)
            .ok()
            .map(|x| x.map(sample).unwrap_or_default()),
    );
    out.push(m.pdf_exit(&at, &packet, exit).ok().map(|p| bits([p])));
    out
}

/// Compares both forms of `surface` at every level over `n` scenes; returns the calls compared.
fn compare<T, P, Sp, Sc, B>(
    surface: &RoughSurface<P, Sp, Sc>,
    blur: B,
    n: usize,
    seed: u64,
) -> usize
where
    T: Real,
    P: gmueller::psd::Psd<T, 2> + Clone + std::fmt::Debug + Send + Sync + 'static,
    Sp: Interface<T> + Clone + std::fmt::Debug + Send + Sync + 'static,
    Sc: Pbsdf<T> + Clone + std::fmt::Debug + Send + Sync + 'static,
    B: BlurMethod<T, 2, P> + Clone + std::fmt::Debug + Send + Sync + 'static,
{
    let opaque = surface.specular.transmission_index().is_none();
    let mut rng = Rng(seed);
    let mut compared = 0;
    for level in Level::ALL {
        let m = Material::with_blur(surface.clone(), level, blur.clone());
        assert_eq!(m.level(), level);
        for _ in 0..n {
            let s = scene(&mut rng, opaque);
            let want = level.dispatch(
                blur.clone(),
                Static {
                    surface,
                    s,
                    _t: core::marker::PhantomData::<T>,
                },
            );
            let got = erased(&m, s);
            assert_eq!(want.len(), got.len());
            for (i, (a, b)) in want.iter().zip(&got).enumerate() {
                assert_eq!(a, b, "{} call {i}, scene {s:?}", level.name());
                compared += 1;
            }
        }
    }
    compared
}

fn all_surfaces<T: Real>(n: usize) -> usize
where
    ClosedForm: BlurMethod<T, 2, GaussianPsd<T, 2>>
        + BlurMethod<T, 2, GaussianMixturePsd<T, 2>>
        + BlurMethod<T, 2, Grating<T, 2>>
        + BlurMethod<T, 2, Smooth<T>>,
{
    let l = T::lit;
    let gauss = GaussianPsd::<T, 2>::isotropic(l(0.01), l(2.0)).unwrap();
    let gold = Complex::new(l(0.2), l(3.5));
    let mut c = compare(
        &RoughDielectric::new(gauss, l(1.5)).unwrap(),
        ClosedForm,
        n,
        1,
    );
    let mixture = GaussianMixturePsd::new(vec![
        GaussianPsd::isotropic(l(0.01), l(1.0)).unwrap(),
        GaussianPsd::isotropic(l(0.02), l(4.0)).unwrap(),
    ])
    .unwrap();
    c += compare(
        &RoughConductor::new(mixture, gold).unwrap(),
        ClosedForm,
        n,
        2,
    );
    let k = KCorrelation::<T, 2>::new(l(1e-4), l(4.0), l(2.5)).unwrap();
    let hermite = GaussHermite::<T>::new(8).unwrap();
    c += compare(&RoughConductor::new(k, gold).unwrap(), hermite, n, 3);
    let grating =
        Grating::<T, 2>::sinusoidal_height(l(0.02), l(3.0), &Vector2::new(T::one(), l(0.3)))
            .unwrap();
    c += compare(
        &RoughConductor::new(grating, gold).unwrap(),
        ClosedForm,
        n,
        4,
    );
    c += compare(
        &RoughDielectric::new(Smooth::new(T::one()).unwrap(), l(1.5)).unwrap(),
        ClosedForm,
        n,
        5,
    );
    c
}

/// Erased and static answers are bit-identical, every surface kind and level, both precisions;
/// and `Material::incident_vertex` gives what `sample_incident`, `pdf_incident` and
/// `eval_incident` give (`erased`).
#[test]
fn erased_material_is_the_static_bsdf_bit_for_bit() {
    let (a, b) = (all_surfaces::<f64>(12), all_surfaces::<f32>(12));
    println!("calls compared: f64 {a}, f32 {b}");
    assert!(a > 2_500 && b > 2_500, "{a} {b}");
}

/// The same beyond first order: the Kirchhoff series through `Material::with_roughness`.
#[test]
fn erased_material_beyond_first_order_is_bit_identical() {
    fn run<T: Real>() -> usize
    where
        ClosedForm: BlurMethod<T, 2, GaussianPsd<T, 2>>,
    {
        let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.2), T::lit(2.0)).unwrap();
        let surface = gmueller::interaction::KirchhoffConductor::new(
            psd,
            Complex::new(T::lit(0.2), T::lit(3.5)),
        )
        .unwrap();
        let rough = Roughness::Series(KirchhoffSeries::new(1e-3).unwrap());
        let mut rng = Rng(9);
        let mut compared = 0;
        for level in [Level::ALL[1], Level::ALL[7], Level::ALL[8]] {
            let m = Material::with_roughness(surface.clone(), level, rough);
            for _ in 0..8 {
                let s = scene(&mut rng, true);
                let want = level.dispatch_rough(
                    ClosedForm,
                    rough,
                    Static {
                        surface: &surface,
                        s,
                        _t: core::marker::PhantomData::<T>,
                    },
                );
                let got = erased(&m, s);
                assert_eq!(want, got, "{} {s:?}", level.name());
                compared += want.len();
            }
        }
        compared
    }
    let (a, b) = (run::<f64>(), run::<f32>());
    assert!(a == 144 && b == 144, "{a} {b}");
}

/// A two-sided opaque material answers on its back as on its front turned over: the scene
/// rotated by π about the frame's x̂ (directions `(x, y, z) → (x, −y, −z)` in the frame) gives
/// the same numbers to 1e-12 relative (the turned directions are rebuilt from their
/// coordinates, which rounds them by ~1e-16); a one-sided material refuses the back; an
/// interface ignores the option.
#[test]
fn two_sided_back_is_the_front_turned_over() {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
    let same = |a: &Mueller<f64>, b: &Mueller<f64>| {
        (a.matrix() - b.matrix()).norm() <= 1e-12 * a.matrix().norm().max(b.matrix().norm())
    };
    let psd = GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(0.2, 3.5)).unwrap();
    let one = Material::new(gold.clone(), Level::ALL[7]);
    let two = Material::new(gold, Level::ALL[7]).two_sided(true);
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let at = ShadingPoint::new(f, 0.5).unwrap();
    let c = SurfaceCoherence::new(10.0).unwrap();
    let turn = |d: Vector3<f64>| {
        let (x, y, z) = (d.dot(&f.x()), d.dot(&f.y()), d.dot(&f.k()));
        f.x() * x - f.y() * y - f.k() * z
    };
    let mut rng = Rng(17);
    let mut checked = 0;
    for _ in 0..200 {
        let s = scene(&mut rng, true);
        let (exit, source) = (local(&f, s.exit), local(&f, s.source));
        let (u0, u) = (s.u[0], [s.u[1], s.u[2]]);
        let front = two.sample_incident(&at, exit, &c, u0, u).unwrap();
        let back = two.sample_incident(&at, turn(exit), &c, u0, u).unwrap();
        assert!(one.sample_incident(&at, turn(exit), &c, u0, u).is_err());
        match (front, back) {
            (Some(a), Some(b)) => {
                assert!((turn(a.sample.direction) - b.sample.direction).norm() < 1e-14);
                assert!(close(a.sample.pdf, b.sample.pdf));
                assert!(same(&a.weight, &b.weight), "{:?} {:?}", a.weight, b.weight);
                checked += 1;
            }
            (None, None) => {}
            other => panic!("{other:?}"),
        }
        let a = two.eval_incident(&at, exit, &c, source).unwrap();
        let b = two
            .eval_incident(&at, turn(exit), &c, turn(source))
            .unwrap();
        assert!(same(&a.response.specular, &b.response.specular));
        assert!(same(&a.response.scattered, &b.response.scattered));
        assert!(close(
            two.pdf_incident(&at, exit, &c, source).unwrap(),
            two.pdf_incident(&at, turn(exit), &c, turn(source)).unwrap()
        ));
    }
    assert!(checked > 150, "{checked}");
    // An interface has two sides of its own: the option changes nothing.
    let glass = RoughDielectric::new(psd, 1.5).unwrap();
    let (g1, g2) = (
        Material::new(glass.clone(), Level::ALL[7]),
        Material::new(glass, Level::ALL[7]).two_sided(true),
    );
    let exit = local(&f, [0.3, 0.1, -0.9]);
    let a = g1.sample_incident(&at, exit, &c, 0.3, [0.4, 0.5]).unwrap();
    let b = g2.sample_incident(&at, exit, &c, 0.3, [0.4, 0.5]).unwrap();
    assert_eq!(a, b);
}

/// An `Incident` prepared by one `Bsdf` serves another of the same material value, kernel,
/// frame and wavelength bit for bit (the rule of `Incident`'s docs, "Reuse"): eval, the exit
/// sampler and the forward weight, for rough glass from both sides and a conductor.
#[test]
fn an_incident_serves_every_bsdf_of_the_same_shading_point() {
    use gmueller::interaction::{Full, Partial};
    let psd = GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap();
    let glass = RoughDielectric::new(psd, 1.5).unwrap();
    let gold = RoughConductor::new(psd, Complex::new(0.2, 3.5)).unwrap();
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let c = SurfaceCoherence::new(10.0).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let mut rng = Rng(23);
    let mut checked = 0;
    for _ in 0..50 {
        let s = scene(&mut rng, false);
        let (exit, source) = (local(&f, s.exit), local(&f, s.source));
        let copy = glass.clone();
        let (b1, b2) = (
            Bsdf::new(&glass, kernel, f, 0.5).unwrap(),
            Bsdf::new(&copy, kernel, f, 0.5).unwrap(),
        );
        let stokes = Stokes::new(1.0, 0.3, -0.2, 0.1).unwrap();
        let inc = b1
            .prepare(&b1.surface_packet(stokes, source, &c).unwrap())
            .unwrap();
        assert_eq!(b1.eval(&inc, exit).unwrap(), b2.eval(&inc, exit).unwrap());
        let (u0, u) = (s.u[0], [s.u[1], s.u[2]]);
        assert_eq!(
            b1.sample_exit(&inc, u0, u).unwrap(),
            b2.sample_exit(&inc, u0, u).unwrap()
        );
        let g = Bsdf::new(&gold, kernel, f, 0.5).unwrap();
        let source_up = local(&f, [s.source[0], s.source[1], s.source[2].abs()]);
        let inc = g
            .prepare(&g.surface_packet(stokes, source_up, &c).unwrap())
            .unwrap();
        let copy = gold.clone();
        let g2 = Bsdf::new(&copy, kernel, f, 0.5).unwrap();
        assert_eq!(g.eval(&inc, exit).unwrap(), g2.eval(&inc, exit).unwrap());
        checked += 1;
    }
    assert_eq!(checked, 50);
}
