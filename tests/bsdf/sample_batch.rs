//! Verifies `LobeSampler::sample_batch` (`src/bsdf/sampler/batch.rs`): lane for lane against
//! `LobeSampler::sample` (the scalar sampler, an independent code path: `std`'s logarithm,
//! sine and cosine, nalgebra's vector algebra) in `f64` and `f32`, on every lobe kind the lanes
//! draw (rough glass forward and backward from both sides, gold, the plane-wave level's Dirac
//! lobes, two coherence shapes, the incoherent limit) and on samplers that fall back to the
//! scalar draw (grating orders, a Gaussian mixture, a grazing backward lobe, the rough series);
//! Pearson's chi-square of the batch draws against `pdf`; batch lengths around the SIMD width;
//! extreme uniforms and bad slice lengths.

use crate::common;

use common::chi2;
use common::rng::SplitMix64;
use common::shading::{dir, tilted_frame as frame};
use gmueller::bsdf::UniformsSoa;
use gmueller::bsdf::{Bsdf, LobeSampler, NO_LOBE, SampledLobe, SamplesSoa, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::batch::StokesSoa;
use gmueller::interaction::roughness::KirchhoffSeries;
use gmueller::interaction::{
    Full, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave, RoughConductor,
    RoughDielectric,
};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{GaussianMixturePsd, GaussianPsd, Grating};
use gmueller::real::Real;
use gmueller::spectral::Metal;
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Vector2, Vector3, Vector4};

/// The batch outputs, owned.
struct Out<T> {
    x: Vec<T>,
    y: Vec<T>,
    z: Vec<T>,
    pdf: Vec<T>,
    dw: Vec<T>,
    lobe: Vec<u8>,
}

impl<T: Real> Out<T> {
    fn new(n: usize) -> Self {
        Self {
            x: vec![T::zero(); n],
            y: vec![T::zero(); n],
            z: vec![T::zero(); n],
            pdf: vec![T::zero(); n],
            dw: vec![T::zero(); n],
            lobe: vec![0; n],
        }
    }

    fn soa(&mut self) -> SamplesSoa<'_, T> {
        SamplesSoa {
            x: &mut self.x,
            y: &mut self.y,
            z: &mut self.z,
            pdf: &mut self.pdf,
            delta_weight: &mut self.dw,
            lobe: &mut self.lobe,
        }
    }
}

/// `n` seeded triples of uniforms in `[0, 1)`.
fn uniforms<T: Real>(n: usize, seed: u64) -> [Vec<T>; 3] {
    let mut rng = SplitMix64(seed);
    let mut u: [Vec<T>; 3] = Default::default();
    for _ in 0..n {
        for v in &mut u {
            v.push(T::lit(rng.unit()));
        }
    }
    u
}

/// `u` as the sampler's uniforms.
fn soa_of<T>(u: &[Vec<T>; 3]) -> UniformsSoa<'_, T> {
    UniformsSoa {
        lobe: &u[0],
        u0: &u[1],
        u1: &u[2],
    }
}

/// Four weight slices as a `StokesSoa`.
fn stokes_of<T>(w: &mut [Vec<T>; 4]) -> StokesSoa<'_, T> {
    let [w0, w1, w2, w3] = w;
    StokesSoa {
        s: [w0, w1, w2, w3],
    }
}

/// The batch draws of `u`.
fn batch<T: Real>(sampler: &LobeSampler<'_, T>, u: &[Vec<T>; 3]) -> Out<T> {
    let mut out = Out::new(u[0].len());
    sampler.sample_batch(soa_of(u), out.soa()).unwrap();
    out
}

/// Compares the batch with the scalar sampler lane for lane: the largest relative differences
/// of direction and pdf over lanes that drew the same lobe, and the number of lanes where the
/// lobe (or whether there is a direction) differs. Panics on a lane whose output is not a
/// valid sample (pdf > 0 and finite, unit direction, delta weight as its lobe says).
#[expect(
    clippy::needless_range_loop,
    reason = "lane i of six output slices and three inputs"
)]
fn compare<T: Real>(sampler: &LobeSampler<'_, T>, u: &[Vec<T>; 3]) -> (f64, f64, usize, usize) {
    let out = batch(sampler, u);
    let (mut dmax, mut pmax, mut differ, mut some) = (0.0f64, 0.0f64, 0, 0);
    for i in 0..u[0].len() {
        let one = sampler.sample(u[0][i], [u[1][i], u[2][i]]);
        let lobe = SampledLobe::from_code(out.lobe[i]);
        if lobe.is_some() {
            let p = out.pdf[i].to_f64();
            let d = Vector3::new(out.x[i].to_f64(), out.y[i].to_f64(), out.z[i].to_f64());
            assert!(p > 0.0 && p.is_finite(), "lane {i}: pdf {p}");
            assert!(
                (d.norm() - 1.0).abs() < 1e3 * T::EPSILON.to_f64(),
                "lane {i}: {d}"
            );
            let delta = lobe.is_some_and(|l| l.delta);
            assert_eq!(out.dw[i].to_f64() > 0.0, delta, "lane {i}");
            some += 1;
        } else {
            assert_eq!(out.lobe[i], NO_LOBE);
            assert_eq!(out.pdf[i], T::zero());
        }
        match one {
            Some(s) if Some(s.lobe) == lobe => {
                let d = Vector3::new(out.x[i], out.y[i], out.z[i]);
                dmax = dmax.max((d - s.direction).norm().to_f64());
                pmax = pmax.max(((out.pdf[i] - s.pdf) / s.pdf).abs().to_f64());
                assert_eq!(out.dw[i], s.delta_weight, "lane {i}");
            }
            None if lobe.is_none() => {}
            _ => differ += 1,
        }
    }
    (dmax, pmax, differ, some)
}

/// Calls `f` with every sampler of the cases (name, sampler, whether the lanes draw it).
fn cases_f64(f: &mut dyn FnMut(&str, &LobeSampler<'_, f64>, bool)) {
    let fr = frame();
    let c = SurfaceCoherence::new(3.0).unwrap();
    let unpol = Stokes::unpolarized(1.0).unwrap();
    let glass = RoughDielectric::new(GaussianPsd::isotropic(0.02, 1.0).unwrap(), 1.5).unwrap();
    let b = Bsdf::new(&glass, Kernel::<Full, Partial>::default(), fr, 0.5).unwrap();
    for (deg, side) in [(35.0, 1.0), (25.0, -1.0), (55.0, -1.0)] {
        let packet = b
            .surface_packet(unpol, dir(&fr, deg, 30.0, side), &c)
            .unwrap();
        let inc = b.prepare(&packet).unwrap();
        let name = format!("glass forward {deg}° side {side}");
        f(&name, &b.exit_sampler(&inc).unwrap(), true);
    }
    for (deg, side) in [(40.0, 1.0), (30.0, -1.0), (60.0, -1.0)] {
        let s = b.incident_sampler(dir(&fr, deg, -50.0, side), &c).unwrap();
        f(&format!("glass backward {deg}° side {side}"), &s, true);
    }
    let gold = RoughConductor::new(
        GaussianPsd::isotropic(0.03, 1.2).unwrap(),
        Metal::Au.index(0.5),
    )
    .unwrap();
    let g = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), fr, 0.5).unwrap();
    let s = g.incident_sampler(dir(&fr, 50.0, 10.0, 1.0), &c).unwrap();
    f("gold backward 50°", &s, true);
    let inc = g
        .prepare(
            &g.surface_packet(unpol, dir(&fr, 20.0, 120.0, 1.0), &c)
                .unwrap(),
        )
        .unwrap();
    f("gold forward 20°", &g.exit_sampler(&inc).unwrap(), true);
    // The plane-wave level: Dirac specular lobes.
    let p = Bsdf::new(&glass, Kernel::<OneShape, PlaneWave>::default(), fr, 0.5).unwrap();
    let inc = p
        .prepare(
            &p.surface_packet(unpol, dir(&fr, 30.0, 45.0, 1.0), &c)
                .unwrap(),
        )
        .unwrap();
    f(
        "glass plane wave forward",
        &p.exit_sampler(&inc).unwrap(),
        true,
    );
    let s = p.incident_sampler(dir(&fr, 45.0, 0.0, -1.0), &c).unwrap();
    f("glass plane wave backward", &s, true);
    // The incoherent limit, and two coherence shapes (two specular channels).
    let i = Bsdf::new(&glass, Kernel::<OneShape, Incoherent>::default(), fr, 0.5).unwrap();
    let inc = i
        .prepare(
            &i.surface_packet(unpol, dir(&fr, 40.0, -20.0, 1.0), &c)
                .unwrap(),
        )
        .unwrap();
    f(
        "glass incoherent forward",
        &i.exit_sampler(&inc).unwrap(),
        true,
    );
    let s = dir(&fr, 40.0, -20.0, 1.0);
    let beam = Frame::sp(-s, fr.k()).unwrap();
    let wx = CoherenceShape::new(Matrix2::new(4.0, 0.5, 0.5, 2.0)).unwrap();
    let wy = CoherenceShape::new(Matrix2::new(1.5, 0.0, 0.0, 9.0)).unwrap();
    let packet =
        WavePacket::new(Stokes::new(1.0, 0.4, 0.0, 0.0).unwrap(), wx, wy, beam, 0.5).unwrap();
    let inc = b.prepare(&packet).unwrap();
    f(
        "glass two shapes forward",
        &b.exit_sampler(&inc).unwrap(),
        true,
    );

    // The scalar fallback: a grazing backward specular lobe (the angle chart), grating orders,
    // a Gaussian mixture; then the rough series' order lobes (in lanes).
    let s = b.incident_sampler(
        dir(&fr, 86.0, 20.0, 1.0),
        &SurfaceCoherence::fixed(20.0).unwrap(),
    );
    f("glass backward 86° (angle chart)", &s.unwrap(), false);
    let grating = RoughConductor::new(
        Grating::sinusoidal_height(0.03, 2.0, &Vector2::new(0.9, 0.3)).unwrap(),
        Metal::Au.index(0.5),
    )
    .unwrap();
    let gr = Bsdf::new(&grating, Kernel::<Full, Partial>::default(), fr, 0.5).unwrap();
    let s = gr.incident_sampler(dir(&fr, 20.0, 0.0, 1.0), &c).unwrap();
    f("grating backward", &s, false);
    let mix = RoughConductor::new(
        GaussianMixturePsd::new(vec![
            GaussianPsd::isotropic(0.01, 0.7).unwrap(),
            GaussianPsd::isotropic(0.02, 3.0).unwrap(),
        ])
        .unwrap(),
        Metal::Au.index(0.5),
    )
    .unwrap();
    let mx = Bsdf::new(&mix, Kernel::<Full, Partial>::default(), fr, 0.5).unwrap();
    let s = mx.incident_sampler(dir(&fr, 30.0, 0.0, 1.0), &c).unwrap();
    f("mixture backward", &s, false);
    let rough = RoughConductor::new(
        GaussianPsd::isotropic(0.1, 1.0).unwrap(),
        Metal::Au.index(0.5),
    )
    .unwrap();
    let k = Kernel::<Full, Partial>::default().with_roughness(KirchhoffSeries::default());
    let rs = Bsdf::new(&rough, k, fr, 0.5).unwrap();
    let s = rs.incident_sampler(dir(&fr, 30.0, 0.0, 1.0), &c).unwrap();
    f("rough series backward", &s, true);
    let rough_glass =
        RoughDielectric::new(GaussianPsd::isotropic(0.08, 1.5).unwrap(), 1.5).unwrap();
    let k = Kernel::<Full, Partial>::default().with_roughness(KirchhoffSeries::default());
    let rg = Bsdf::new(&rough_glass, k, fr, 0.5).unwrap();
    for (deg, side) in [(35.0, 1.0), (25.0, -1.0)] {
        let s = rg.incident_sampler(dir(&fr, deg, 10.0, side), &c).unwrap();
        f(
            &format!("rough glass series backward {deg}° side {side}"),
            &s,
            true,
        );
    }
}

/// f64: lanes equal the scalar sampler to 1e-12 relative; a lobe chosen differently (a uniform
/// within rounding of a part's boundary) in at most 1 lane in 10⁴; the fallback bit for bit.
#[test]
fn lanes_equal_the_scalar_sampler_f64() {
    let n = 20_011; // not a multiple of any SIMD width: the overlapping last vector
    let mut seed = 0;
    cases_f64(&mut |name, sampler, lanes| {
        seed += 1;
        let u = uniforms::<f64>(n, 0xba7c + seed);
        let (dmax, pmax, differ, some) = compare(sampler, &u);
        println!(
            "{name}: {some} drawn, max |Δd| {dmax:.2e}, max |Δp|/p {pmax:.2e}, {differ} differ"
        );
        assert!(some > n / 3, "{name}: {some} of {n} drawn");
        if lanes {
            assert!(dmax <= 1e-12 && pmax <= 1e-12, "{name}: {dmax:e} {pmax:e}");
            assert!(differ <= n / 10_000, "{name}: {differ} lanes differ");
        } else {
            assert!(
                dmax == 0.0 && pmax == 0.0 && differ == 0,
                "{name}: fallback differs"
            );
        }
    });
}

/// The f32 cases: rough glass (both sides, both directions) and gold, Full and Intensity; rough
/// glass with the Kirchhoff series' order lobes.
fn cases_f32(f: &mut dyn FnMut(&str, &LobeSampler<'_, f32>)) {
    let fr = Frame::<f32>::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let d = |deg: f32, phi: f32, side: f32| {
        let (t, p) = (deg.to_radians(), phi.to_radians());
        fr.x() * (t.sin() * p.cos()) + fr.y() * (t.sin() * p.sin()) + fr.k() * (side * t.cos())
    };
    let c = SurfaceCoherence::new(3.0f32).unwrap();
    let glass =
        RoughDielectric::new(GaussianPsd::<f32, 2>::isotropic(0.02, 1.0).unwrap(), 1.5).unwrap();
    let b = Bsdf::new(&glass, Kernel::<Full, Partial>::default(), fr, 0.5).unwrap();
    for (deg, side) in [(40.0, 1.0), (30.0, -1.0), (60.0, -1.0)] {
        let s = b.incident_sampler(d(deg, -50.0, side), &c).unwrap();
        f(&format!("f32 glass backward {deg}° side {side}"), &s);
    }
    let packet = b
        .surface_packet(Stokes::unpolarized(1.0).unwrap(), d(35.0, 30.0, 1.0), &c)
        .unwrap();
    let inc = b.prepare(&packet).unwrap();
    f("f32 glass forward 35°", &b.exit_sampler(&inc).unwrap());
    let gold = RoughConductor::new(
        GaussianPsd::<f32, 2>::isotropic(0.03, 1.2).unwrap(),
        Metal::Au.index(0.5f32),
    )
    .unwrap();
    let g = Bsdf::new(&gold, Kernel::<Intensity, Partial>::default(), fr, 0.5).unwrap();
    let s = g.incident_sampler(d(70.0, 10.0, 1.0), &c).unwrap();
    f("f32 gold backward 70° (Intensity)", &s);
    let rough =
        RoughDielectric::new(GaussianPsd::<f32, 2>::isotropic(0.08, 1.5).unwrap(), 1.5).unwrap();
    let k = Kernel::<Full, Partial>::default().with_roughness(KirchhoffSeries::default());
    let r = Bsdf::new(&rough, k, fr, 0.5).unwrap();
    let s = r.incident_sampler(d(35.0, 10.0, -1.0), &c).unwrap();
    f("f32 rough glass series backward 35° side -1", &s);
}

/// f32: the direction within 64 ε and the pdf within 2⁻¹² relative of the scalar sampler's, on
/// lanes that drew the same lobe; a different lobe in at most 1 lane in 10⁴. The density is
/// recomputed from each path's own direction, so their difference (a few ε) enters the
/// Gaussian's exponent multiplied by `k |z| / σ_h` (tens, for the narrow lobes here): the
/// largest measured was 5.5·10⁻⁵ (gold at 70°), 1.6·10⁻⁶ on the direction.
#[test]
fn lanes_equal_the_scalar_sampler_f32() {
    let n = 20_011;
    let mut seed = 0;
    cases_f32(&mut |name, sampler| {
        seed += 1;
        let u = uniforms::<f32>(n, 0xf32 + seed);
        let (dmax, pmax, differ, some) = compare(sampler, &u);
        println!(
            "{name}: {some} drawn, max |Δd| {dmax:.2e}, max |Δp|/p {pmax:.2e}, {differ} differ"
        );
        assert!(some > n / 3, "{name}: {some} of {n} drawn");
        let eps = f64::from(f32::EPSILON);
        assert!(
            dmax <= 64.0 * eps && pmax <= 2f64.powi(-12),
            "{name}: {dmax:e} {pmax:e}"
        );
        assert!(differ <= n / 10_000, "{name}: {differ} lanes differ");
    });
}

/// Pearson's chi-square of the batch draws against the sampler's `pdf` (the scalar test of
/// `bsdf::sampling::check`, its draws taken from one batch).
#[test]
fn batch_draws_pass_chi_square_against_the_pdf() {
    let mut seed = 0;
    cases_f64(&mut |name, sampler, lanes| {
        seed += 1;
        if !lanes {
            return;
        }
        let fr = frame();
        let disk = chi2::Disk {
            t1: fr.x(),
            t2: fr.y(),
            n: fr.k(),
        };
        let n = 100_000;
        let pilot = batch(sampler, &uniforms::<f64>(4000, 0x9170 + seed));
        let grids = crate::bsdf::sampling::grids(&disk, &mut |i| direction(&pilot, i));
        let out = batch(sampler, &uniforms::<f64>(n, 0xc412 + seed));
        let pdf = |d: &Vector3<f64>| sampler.pdf(d);
        let res = chi2::test(&disk, &grids, &pdf, n, &mut |i| direction(&out, i));
        println!(
            "{name}: chi2 {:.1} dof {} (99.9% {:.1})",
            res.chi2, res.dof, res.quantile
        );
        assert!(res.passes() && res.dof >= 20, "{name}: {res:?}");
    });
}

/// Draw `i` of a batch, `None` for a delta or no direction (the rest bin).
fn direction(out: &Out<f64>, i: usize) -> Option<Vector3<f64>> {
    SampledLobe::from_code(out.lobe[i])
        .filter(|l| !l.delta)
        .map(|_| Vector3::new(out.x[i], out.y[i], out.z[i]))
}

/// Batches shorter than, equal to and just above the SIMD widths (1..=40): the masked and
/// overlapping vectors give the same lanes as one long batch, bit for bit.
#[test]
fn every_batch_length_gives_the_same_lanes() {
    fn check<T: Real>(s: &LobeSampler<'_, T>) {
        let u = uniforms::<T>(40, 3);
        let all = batch(s, &u);
        for n in 1..=40 {
            let head: [Vec<T>; 3] = core::array::from_fn(|k| u[k][..n].to_vec());
            let part = batch(s, &head);
            for i in 0..n {
                assert_eq!(
                    (part.x[i], part.y[i], part.z[i], part.pdf[i], part.lobe[i]),
                    (all.x[i], all.y[i], all.z[i], all.pdf[i], all.lobe[i]),
                    "n {n}, lane {i}"
                );
            }
        }
    }
    let mut done = false;
    cases_f64(&mut |_, s, lanes| {
        if lanes && !done {
            check(s);
            done = true;
        }
    });
    let mut done = false;
    cases_f32(&mut |_, s| {
        if !done {
            check(s);
            done = true;
        }
    });
}

/// Uniforms outside `[0, 1)`, NaN and infinities: no panic, and each lane is a valid sample or
/// none (as `sample`, which clamps them); slices of different lengths are refused.
#[test]
fn extreme_uniforms_and_bad_lengths() {
    let odd = [
        0.0,
        1.0,
        -1.0,
        2.0,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1.0 - f64::EPSILON,
    ];
    let mut lobe = Vec::new();
    let (mut u0, mut u1) = (Vec::new(), Vec::new());
    for a in odd {
        for b in odd {
            for c in odd {
                lobe.push(a);
                u0.push(b);
                u1.push(c);
            }
        }
    }
    let u = [lobe, u0, u1];
    cases_f64(&mut |name, sampler, _| {
        let out = batch(sampler, &u);
        for i in 0..u[0].len() {
            let p = out.pdf[i];
            assert!(p.is_finite() && p >= 0.0, "{name} lane {i}: pdf {p}");
            if p > 0.0 {
                let d = Vector3::new(out.x[i], out.y[i], out.z[i]);
                assert!((d.norm() - 1.0).abs() < 1e-12, "{name} lane {i}: {d}");
            }
        }
        let mut o = Out::<f64>::new(3);
        let short = UniformsSoa {
            lobe: &u[0][..3],
            u0: &u[1][..3],
            u1: &u[2][..2],
        };
        assert!(sampler.sample_batch(short, o.soa()).is_err());
        let mut o = Out::<f64>::new(2);
        let long = UniformsSoa {
            lobe: &u[0][..3],
            u0: &u[1][..3],
            u1: &u[2][..3],
        };
        assert!(sampler.sample_batch(long, o.soa()).is_err());
    });
}

/// Compares `sample_exit_batch` with `sample_exit` lane for lane for `packet`: the largest
/// `|W_batch − W_scalar| / W_scalar,0` over lanes that drew the same lobe, and the number of
/// lanes whose lobe differs. At the intensity levels the batch's S1..S3 must be 0.
fn compare_weights<T: Real, S, Pol, Coh>(
    b: &Bsdf<'_, T, S, Kernel<Pol, Coh>>,
    packet: &WavePacket<T>,
    n: usize,
    seed: u64,
) -> (f64, usize)
where
    S: gmueller::bsdf::BsdfSurface<T>,
    Pol: gmueller::interaction::polarization::PolarizationModel,
    Coh: gmueller::interaction::coherence::CoherenceWeights<T, S::Psd>,
    Kernel<Pol, Coh>: gmueller::bsdf::BsdfKernel<T, S::Psd, Pol = Pol, Coh = Coh>,
{
    use gmueller::interaction::polarization::{PolarizationLevel, Throughput};
    let u = uniforms::<T>(n, seed);
    let mut out = Out::<T>::new(n);
    let mut w: [Vec<T>; 4] = core::array::from_fn(|_| vec![T::lit(7.0); n]);
    b.sample_exit_batch(packet, soa_of(&u), out.soa(), stokes_of(&mut w))
        .unwrap();
    let inc = b.prepare(packet).unwrap();
    let intensity = Pol::LEVEL == PolarizationLevel::Intensity;
    let (mut worst, mut differ) = (0.0f64, 0);
    for i in 0..n {
        let one = b.sample_exit(&inc, u[0][i], [u[1][i], u[2][i]]).unwrap();
        let lobe = SampledLobe::from_code(out.lobe[i]);
        match one {
            Some(s) if Some(s.sample.lobe) == lobe => {
                let v = s.weight.to_mueller().apply(&packet.stokes());
                let want = [v.s0(), v.s1(), v.s2(), v.s3()];
                let d = (0..4)
                    .map(|c| (w[c][i] - want[c]).to_f64().powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(want[0] > T::zero(), "lane {i}: scalar weight {want:?}");
                worst = worst.max(d / want[0].to_f64());
                if intensity {
                    assert!((1..4).all(|c| w[c][i] == T::zero()), "lane {i}");
                }
            }
            None if lobe.is_none() => {
                assert!(
                    (0..4).all(|c| w[c][i] == T::zero()),
                    "lane {i}: no draw, weight"
                );
            }
            _ => differ += 1,
        }
    }
    (worst, differ)
}

/// The forward bounce in batch against `sample_exit` one draw at a time: rough glass from
/// above and from below (reflection and transmission), gold, a polarized two-shape packet, the
/// plane-wave level (Dirac lobes, weighed per draw) and the intensity level, in f64 (weights
/// within 10⁻¹⁰ of `W₀`) and f32 (within 2⁻¹⁰: the lanes' pdf is within 2⁻¹² and the batch
/// evaluation within its own bound, `interaction::batch`).
#[test]
fn forward_batch_weights_equal_the_scalar_bounce() {
    let fr = frame();
    let c = SurfaceCoherence::new(3.0).unwrap();
    let unpol = Stokes::unpolarized(1.0).unwrap();
    let n = 4_099;
    let glass = RoughDielectric::new(GaussianPsd::isotropic(0.02, 1.0).unwrap(), 1.5).unwrap();
    let b = Bsdf::new(&glass, Kernel::<Full, Partial>::default(), fr, 0.5).unwrap();
    let report = |name: &str, (worst, differ): (f64, usize), tol: f64| {
        println!("{name}: max |ΔW|/W₀ {worst:.2e}, {differ} lanes differ");
        assert!(
            worst <= tol && differ <= n / 1000,
            "{name}: {worst:e}, {differ}"
        );
    };
    for (deg, side) in [(35.0, 1.0), (25.0, -1.0), (55.0, -1.0)] {
        let packet = b
            .surface_packet(unpol, dir(&fr, deg, 30.0, side), &c)
            .unwrap();
        let name = format!("glass {deg}° side {side}");
        report(&name, compare_weights(&b, &packet, n, 1), 1e-10);
    }
    let s = dir(&fr, 40.0, -20.0, 1.0);
    let beam = Frame::sp(-s, fr.k()).unwrap();
    let wx = CoherenceShape::new(Matrix2::new(4.0, 0.5, 0.5, 2.0)).unwrap();
    let wy = CoherenceShape::new(Matrix2::new(1.5, 0.0, 0.0, 9.0)).unwrap();
    let polarized =
        WavePacket::new(Stokes::new(1.0, 0.4, 0.3, -0.5).unwrap(), wx, wy, beam, 0.5).unwrap();
    report(
        "glass two shapes, polarized",
        compare_weights(&b, &polarized, n, 2),
        1e-10,
    );
    let gold = RoughConductor::new(
        GaussianPsd::isotropic(0.03, 1.2).unwrap(),
        Metal::Au.index(0.5),
    )
    .unwrap();
    let g = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), fr, 0.5).unwrap();
    let packet = g
        .surface_packet(unpol, dir(&fr, 20.0, 120.0, 1.0), &c)
        .unwrap();
    report("gold 20°", compare_weights(&g, &packet, n, 3), 1e-10);
    let gi = Bsdf::new(&gold, Kernel::<Intensity, Partial>::default(), fr, 0.5).unwrap();
    report(
        "gold 20° Intensity",
        compare_weights(&gi, &packet, n, 4),
        1e-10,
    );
    let p = Bsdf::new(&glass, Kernel::<OneShape, PlaneWave>::default(), fr, 0.5).unwrap();
    let packet = p
        .surface_packet(unpol, dir(&fr, 30.0, 45.0, 1.0), &c)
        .unwrap();
    report(
        "glass plane wave",
        compare_weights(&p, &packet, n, 5),
        1e-10,
    );

    let fr32 = Frame::<f32>::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let d32 = |deg: f32, side: f32| {
        let t = deg.to_radians();
        fr32.x() * t.sin() + fr32.k() * (side * t.cos())
    };
    let c32 = SurfaceCoherence::new(3.0f32).unwrap();
    let glass32 =
        RoughDielectric::new(GaussianPsd::<f32, 2>::isotropic(0.02, 1.0).unwrap(), 1.5).unwrap();
    let b32 = Bsdf::new(&glass32, Kernel::<Full, Partial>::default(), fr32, 0.5).unwrap();
    for (deg, side) in [(35.0, 1.0), (25.0, -1.0)] {
        let packet = b32
            .surface_packet(Stokes::unpolarized(1.0).unwrap(), d32(deg, side), &c32)
            .unwrap();
        let name = format!("f32 glass {deg}° side {side}");
        report(&name, compare_weights(&b32, &packet, n, 6), 2f64.powi(-10));
    }
}

/// `Material::sample_exit_batch` against `Material::sample_exit` one draw at a time: gold at
/// first order (lanes), the same gold rougher (`vσ ≈ 2.2`) with the Kirchhoff series (its
/// weights in the series lanes; tolerance 10⁻¹², so that the two sums' truncations stay below
/// the assertion) and a tangent-plane Kirchhoff-series conductor (the batch evaluation one
/// exit at a time), Full · Partial; the same tolerance as the `Bsdf` test (10⁻¹⁰ of `W₀`).
#[test]
fn material_forward_batch_equals_its_scalar_bounce() {
    use gmueller::bsdf::{Material, ShadingPoint};
    use gmueller::interaction::{KirchhoffConductor, Level, Roughness};
    let fr = frame();
    let at = ShadingPoint::new(fr, 0.5).unwrap();
    let c = SurfaceCoherence::new(3.0).unwrap();
    let gold = RoughConductor::new(
        GaussianPsd::isotropic(0.03, 1.2).unwrap(),
        Metal::Au.index(0.5),
    )
    .unwrap();
    let series = KirchhoffConductor::new(
        GaussianPsd::isotropic(0.2, 2.0).unwrap(),
        Metal::Au.index(0.5),
    )
    .unwrap();
    let rough_gold = RoughConductor::new(
        GaussianPsd::isotropic(0.1, 1.2).unwrap(),
        Metal::Au.index(0.5),
    )
    .unwrap();
    let materials = [
        ("gold, first order", Material::new(gold, Level::ALL[7])),
        (
            "gold, Kirchhoff series in lanes",
            Material::with_roughness(
                rough_gold,
                Level::ALL[7],
                Roughness::Series(KirchhoffSeries::new(1e-12).unwrap()),
            ),
        ),
        (
            "Kirchhoff series",
            Material::with_roughness(
                series,
                Level::ALL[7],
                Roughness::Series(KirchhoffSeries::new(1e-3).unwrap()),
            ),
        ),
    ];
    let n = 2_053;
    for (k, (name, m)) in materials.iter().enumerate() {
        let packet = m
            .surface_packet(
                &at,
                Stokes::unpolarized(1.0).unwrap(),
                dir(&fr, 30.0, 40.0, 1.0),
                &c,
            )
            .unwrap();
        let u = uniforms::<f64>(n, 0x3a7 + k as u64);
        let mut out = Out::<f64>::new(n);
        let mut w: [Vec<f64>; 4] = core::array::from_fn(|_| vec![0.0; n]);
        m.sample_exit_batch(&at, &packet, soa_of(&u), out.soa(), stokes_of(&mut w))
            .unwrap();
        let (mut worst, mut some, mut differ) = (0.0f64, 0, 0);
        for i in 0..n {
            let one = m
                .sample_exit(&at, &packet, u[0][i], [u[1][i], u[2][i]])
                .unwrap();
            match one {
                Some(s) if Some(s.sample.lobe) == SampledLobe::from_code(out.lobe[i]) => {
                    let v = s.weight.apply(&packet.stokes());
                    let d = (0..4)
                        .map(|c| (w[c][i] - v.vector()[c]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    worst = worst.max(d / v.s0());
                    some += 1;
                }
                None if out.lobe[i] == NO_LOBE => {}
                _ => differ += 1,
            }
        }
        println!("{name}: {some} draws, max |ΔW|/W₀ {worst:.2e}, {differ} differ");
        assert!(
            some > n / 2 && worst <= 1e-10 && differ <= n / 1000,
            "{name}"
        );
    }
}

// ---------------------------------------------------------------- properties

/// One random shading configuration of the property below.
#[derive(Debug, Clone)]
struct Case {
    lambda: f64,
    sigma: f64,
    ell: f64,
    width: f64,
    theta: f64,
    phi: f64,
    below: bool,
    material: usize,
    level: usize,
    seed: u64,
}

fn case() -> impl proptest::strategy::Strategy<Value = Case> {
    use common::log_uniform;
    use proptest::prelude::*;
    (
        (
            log_uniform(0.3, 2.0),
            log_uniform(1e-3, 0.04),
            log_uniform(0.1, 100.0),
            log_uniform(0.1, 1e4),
        ),
        (
            gmueller::verify::strategy::polar_angle().prop_map(f64::to_degrees),
            -180.0..180.0f64,
            any::<bool>(),
        ),
        (0..2usize, 0..4usize, any::<u64>()),
    )
        .prop_map(
            |((lambda, s, l, w), (theta, phi, below), (material, level, seed))| Case {
                lambda,
                sigma: s * lambda,
                ell: l * lambda,
                width: w * lambda,
                theta,
                phi,
                below,
                material,
                level,
                seed,
            },
        )
}

/// The batched forward bounce of `Material` against its scalar bounce for case `c` in `T`: an
/// error in the batch only where the scalar bounce errs; every lane a valid draw or none, with
/// a finite weight that is a valid Stokes vector; on lanes that drew the same lobe, the weight
/// within `tol` of `W₀`; at most 1 lane in 16 (and 2 per case) with a different lobe. Returns
/// the number of lanes compared.
fn check_case<T: Real>(c: &Case, tol: f64) -> usize
where
    gmueller::psd::ClosedForm: gmueller::psd::BlurMethod<T, 2, GaussianPsd<T, 2>>,
{
    use gmueller::bsdf::{Material, ShadingPoint};
    use gmueller::interaction::Level;
    let fr = Frame::<T>::from_normal(Vector3::new(0.2, -0.1, 1.0).map(T::lit)).unwrap();
    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(c.sigma), T::lit(c.ell)).unwrap();
    let level = [Level::ALL[7], Level::ALL[1], Level::ALL[6], Level::ALL[8]][c.level];
    let m = if c.material == 0 {
        Material::new(RoughDielectric::new(psd, T::lit(1.5)).unwrap(), level)
    } else {
        let gold = Metal::Au.index(T::lit(c.lambda.clamp(0.3, 2.0)));
        Material::new(RoughConductor::new(psd, gold).unwrap(), level)
    };
    let below = c.below && c.material == 0;
    let (t, p) = (c.theta.to_radians(), c.phi.to_radians());
    let z = if below { -t.cos() } else { t.cos() };
    let s = fr.x() * T::lit(t.sin() * p.cos())
        + fr.y() * T::lit(t.sin() * p.sin())
        + fr.k() * T::lit(z);
    let at = ShadingPoint::new(fr, T::lit(c.lambda)).unwrap();
    let Ok(sky) = SurfaceCoherence::new(T::lit(c.width)) else {
        return 0;
    };
    let Ok(packet) = m.surface_packet(&at, Stokes::unpolarized(T::one()).unwrap(), s, &sky) else {
        return 0;
    };
    let n = 67;
    let u = uniforms::<T>(n, c.seed);
    let mut out = Out::<T>::new(n);
    let mut w: [Vec<T>; 4] = core::array::from_fn(|_| vec![T::zero(); n]);
    let batch = m.sample_exit_batch(&at, &packet, soa_of(&u), out.soa(), stokes_of(&mut w));
    let scalar: Vec<_> = (0..n)
        .map(|i| m.sample_exit(&at, &packet, u[0][i], [u[1][i], u[2][i]]))
        .collect();
    if let Err(e) = batch {
        assert!(
            scalar.iter().any(Result::is_err),
            "{c:?}: batch refused ({e}), scalar did not"
        );
        return 0;
    }
    let (mut compared, mut differ) = (0, 0);
    for (i, one) in scalar.into_iter().enumerate() {
        let lobe = SampledLobe::from_code(out.lobe[i]);
        let wi = Vector4::new(w[0][i], w[1][i], w[2][i], w[3][i]).map(|x| x.to_f64());
        if lobe.is_some() {
            let p = out.pdf[i].to_f64();
            assert!(p > 0.0 && p.is_finite(), "{c:?} lane {i}: pdf {p}");
            let pol = wi[1].hypot(wi[2]).hypot(wi[3]);
            let slack = 64.0 * T::EPSILON.to_f64();
            assert!(
                wi.iter().all(|x| x.is_finite())
                    && wi[0] >= 0.0
                    && pol <= wi[0] * (1.0 + slack) + 1e-30,
                "{c:?} lane {i}: weight {wi:?} is not a valid Stokes vector"
            );
        } else {
            assert!(
                wi.iter().all(|&x| x == 0.0),
                "{c:?} lane {i}: no draw, weight {wi:?}"
            );
        }
        match one {
            Ok(Some(s)) if Some(s.sample.lobe) == lobe => {
                let v = s
                    .weight
                    .apply(&packet.stokes())
                    .vector()
                    .map(|x| x.to_f64());
                let d = (wi - v).norm();
                assert!(d <= tol * v[0] + 1e-30, "{c:?} lane {i}: {wi:?} vs {v:?}");
                compared += 1;
            }
            Ok(None) if lobe.is_none() => {}
            _ => differ += 1,
        }
    }
    assert!(
        differ <= 2 && differ * 16 <= n,
        "{c:?}: {differ} lanes differ"
    );
    compared
}

proptest::proptest! {
    #![proptest_config(common::proptest_config(48))]

    /// `check_case` in f64 (10⁻⁹ of `W₀`) and f32 (2⁻⁹), over random wavelengths, roughness,
    /// coherence widths (0.1–10⁴ λ), incidence (0° and 89.99° each in 1/8 of the cases, from
    /// either side of glass), glass and gold, Full and Intensity at Partial, Full at PlaneWave
    /// and Incoherent.
    #[test]
    fn batched_forward_bounce_matches_the_scalar_one(c in case()) {
        // In f64 every case builds and draws (1,968 cases, fresh seeds, 2026-12-06); in f32 a
        // sampler whose lobe is narrower than 8 ε is refused by both paths.
        proptest::prop_assert!(check_case::<f64>(&c, 1e-9) > 0, "{c:?}: nothing compared");
        check_case::<f32>(&c, 2f64.powi(-9));
    }
}

/// `pdf_batch` against `pdf` on directions over the whole sphere (not unit: scaled by 0.5–2),
/// plus a zero, a NaN and an infinite direction, and on the batch draws' own directions: f64
/// within 10⁻¹² relative, f32 within 2⁻¹² (the draws' bound), each plus `16 ε |ln(p/p_max)|`
/// — far from the lobes the pdf is `exp(−q/2)` of a large quadratic form `q ≈ 2 |ln(p/p_max)|`,
/// whose few-ulp rounding moves `p` by `q` times as much (measured 3.2·10⁻⁴ in f32 before this
/// term, at `q` in the thousands); the fallback bit for bit.
#[test]
fn pdf_batch_equals_pdf() {
    fn check<T: Real>(name: &str, s: &LobeSampler<'_, T>, tol: f64, exact: bool) {
        use gmueller::interaction::batch::DirectionsSoa;
        let mut rng = SplitMix64(0x9df);
        let n = 3001;
        let mut d: [Vec<T>; 3] = Default::default();
        for i in 0..n {
            let v = match i {
                0 => Vector3::zeros(),
                1 => Vector3::new(f64::NAN, 0.0, 1.0),
                2 => Vector3::new(0.0, f64::INFINITY, 1.0),
                _ => {
                    let z = 2.0 * rng.unit() - 1.0;
                    let p = std::f64::consts::TAU * rng.unit();
                    let r = (1.0 - z * z).sqrt();
                    Vector3::new(r * p.cos(), r * p.sin(), z) * (0.5 + 1.5 * rng.unit())
                }
            };
            for k in 0..3 {
                d[k].push(T::lit(v[k]));
            }
        }
        // Half of them near the draws: the batch's own directions.
        let u = uniforms::<T>(n / 2, 0xd1a);
        let out = batch(s, &u);
        for i in 0..n / 2 {
            if out.pdf[i] > T::zero() && out.dw[i] == T::zero() {
                (d[0][3 + i], d[1][3 + i], d[2][3 + i]) = (out.x[i], out.y[i], out.z[i]);
            }
        }
        let mut pdf = vec![T::zero(); n];
        s.pdf_batch(
            DirectionsSoa {
                x: &d[0],
                y: &d[1],
                z: &d[2],
            },
            &mut pdf,
        )
        .unwrap();
        let (mut worst, mut positive) = (0.0f64, 0);
        let p_max = (0..n)
            .map(|i| s.pdf(&Vector3::new(d[0][i], d[1][i], d[2][i])).to_f64())
            .fold(0.0, f64::max);
        let eps = T::EPSILON.to_f64();
        for i in 0..n {
            let one = s.pdf(&Vector3::new(d[0][i], d[1][i], d[2][i])).to_f64();
            let got = pdf[i].to_f64();
            assert!(got.is_finite() && got >= 0.0, "{name} {i}: {got}");
            if exact {
                assert_eq!(got, one, "{name} {i}");
            } else if one == 0.0 {
                assert_eq!(got, 0.0, "{name} {i}");
            } else {
                // The relative error in units of the bound at this depth below the peak.
                let bound = tol + 16.0 * eps * (one / p_max).ln().abs();
                worst = worst.max((got - one).abs() / one / bound);
                positive += 1;
            }
        }
        println!("{name}: {positive} positive, max |Δp|/p {worst:.3} of the bound");
        assert!(worst <= 1.0, "{name}: {worst} of the bound");
        assert!(exact || positive > n / 4, "{name}: {positive}");
        assert!(
            s.pdf_batch(
                DirectionsSoa {
                    x: &d[0],
                    y: &d[1],
                    z: &d[2][..2]
                },
                &mut pdf
            )
            .is_err()
        );
    }
    cases_f64(&mut |name, s, lanes| check(name, s, 1e-12, !lanes));
    cases_f32(&mut |name, s| check(name, s, 2f64.powi(-12), false));
}
