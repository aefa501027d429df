//! Issue 36, the renderer layer: every promise of `docs/renderer.md` holds in `f32` too.
//!
//! - **No subnormal throughput** (`docs/renderer.md` §7, "Matrix range"): the weights of the
//!   samplers' delta lobes, forward (`exit_weight`) and backward (`incident_weight`), in `f32`
//!   and `f64`, follow the rule for small entries (`Throughput::flushed`: 0 when every entry is
//!   below `MIN_POSITIVE`, no subnormal entry beside a largest one of `MIN_POSITIVE/ε` or more)
//!   and map valid Stokes vectors to valid ones; their `M₀₀` is the `f64` one where that is a
//!   normal `f32` number, and 0 where it is below. The issue's case — the reflected specular
//!   delta of very rough glass seen from inside, `α ≈ 5·10⁻⁴³` — was a matrix of subnormal
//!   entries in `f32`. (`tests/bsdf/extremes.rs` checks the rule on every lobe and weight.)
//! - **Flags that tell the truth** for the packet at hand (`Bsdf::incident_flags`): where the
//!   section of a very wide coherence is not representable the kernel and the exit sampler
//!   fall back to the plane wave, whose specular lobe and grating orders are deltas; the
//!   static `Bsdf::flags` did not say so.

use gmueller::Real;
use gmueller::bsdf::{Bsdf, DirectionSample, Part, SurfaceCoherence};
use gmueller::frame::Frame;
use gmueller::interaction::RoughSurface;
use gmueller::interaction::roughness::KirchhoffSeries;
use gmueller::interaction::{Kernel, KirchhoffDielectric, OneShape, PlaneWave, Side};
use gmueller::mueller::Mueller;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use nalgebra::{Matrix4, Vector3, Vector4};

/// The rule for small entries (`Throughput::flushed`): `m` is 0 when its entries are all below
/// `MIN_POSITIVE`, and has no subnormal entry when its largest is at least `MIN_POSITIVE/ε`;
/// and `m S` is a valid Stokes vector for the unit probes on the cone (±S1, ±S2, ±S3 fully
/// polarized, and unpolarized): `|S_pol| ≤ S0 (1 + 64 ε)` relative to `max|m|` (the product's
/// rounding).
fn assert_clean<T: Real>(what: &str, m: &Matrix4<T>) {
    let mm = m.map(|x| x.to_f64());
    let (n, min) = (mm.amax(), T::MIN_POSITIVE.to_f64());
    assert!(
        n == 0.0 || n >= min,
        "{what}: every entry subnormal: {mm:e}"
    );
    if n >= min / T::EPSILON.to_f64() {
        for a in mm.iter().map(|x| x.abs()) {
            assert!(
                a == 0.0 || a >= min,
                "{what}: subnormal entry {a:e} in {mm:e}"
            );
        }
    }
    if n == 0.0 {
        return;
    }
    let rel = 64.0 * T::EPSILON.to_f64();
    for k in 0..7 {
        let mut s = Vector4::new(1.0, 0.0, 0.0, 0.0);
        if k > 0 {
            s[1 + (k - 1) / 2] = if k % 2 == 0 { 1.0 } else { -1.0 };
        }
        let out = (mm / n) * s;
        let pol = out[1].hypot(out[2]).hypot(out[3]);
        assert!(
            pol <= out[0] * (1.0 + rel) + rel,
            "{what}: M S invalid for S = {s:?}: {out:?}"
        );
    }
}

/// Very rough glass (Gaussian PSD, σ = `sigma` λ, ℓ = 1376 λ, η = 2.4) at λ = 0.1239 µm, the
/// `KirchhoffSeries` (1e-4) `OneShape · PlaneWave` kernel, light inside the glass arriving at
/// `theta` (degrees) with a 10 λ coherence width: the forward weight of the reflected specular
/// delta and the backward weight of the delta toward the source for the same pair.
fn reflected_delta<T: Real>(sigma: f64, theta: f64) -> [Matrix4<T>; 2] {
    let lambda = 0.1239;
    let psd =
        GaussianPsd::<T, 2>::isotropic(T::lit(sigma * lambda), T::lit(1376.0 * lambda)).unwrap();
    let glass = KirchhoffDielectric::new(psd, T::lit(2.4)).unwrap();
    let kernel = Kernel::<OneShape, PlaneWave>::default()
        .with_roughness(KirchhoffSeries::new(1e-4).unwrap());
    let f = Frame::<T>::from_normal(Vector3::z()).unwrap();
    let b = Bsdf::new(&glass, kernel, f, T::lit(lambda)).unwrap();
    let t = theta.to_radians();
    let to_source = Vector3::new(-t.sin(), 0.0, -t.cos()).map(T::lit);
    let lam_in = b.wavelength(&to_source).unwrap();
    let packet = WavePacket::from_stokes(
        Stokes::unpolarized(T::one()).unwrap(),
        CoherenceShape::isotropic(T::lit(10.0) * lam_in).unwrap(),
        Frame::sp(-to_source, f.k()).unwrap(),
        lam_in,
    )
    .unwrap();
    let inc = b.prepare(&packet).unwrap();
    let only_reflected_specular = [T::one(), T::zero(), T::zero(), T::zero()];
    let sampler = b
        .exit_sampler(&inc)
        .unwrap()
        .with_part_probabilities(only_reflected_specular);
    let s: DirectionSample<T> = sampler.sample(T::lit(0.5), [T::lit(0.5); 2]).unwrap();
    assert!(s.lobe.delta && s.lobe.part == Part::Specular && s.lobe.side == Side::Reflection);
    let forward: Mueller<T> = b.exit_weight(&inc, &s).unwrap().0;
    let coherence = SurfaceCoherence::new(T::lit(10.0 * lambda)).unwrap();
    let back = b
        .incident_sampler(s.direction, &coherence)
        .unwrap()
        .with_part_probabilities(only_reflected_specular);
    let d = back.sample(T::lit(0.5), [T::lit(0.5); 2]).unwrap();
    assert!(d.lobe.delta && (d.direction - to_source).norm() < T::lit(1e-5));
    let backward: Mueller<T> = b.incident_weight(s.direction, &coherence, &d).unwrap().0;
    [forward.matrix(), backward.matrix()]
}

/// Issue 36's case: σ = 0.354 λ, exit inside the glass at 23.3°. In `f64` the delta's weight
/// is 4.8e-43 (α e^{…}: `(2 k_glass σ cos θ)²` ≈ 96.7); below `f32::MIN_POSITIVE` the `f32`
/// weight is exactly 0 (it was a matrix of subnormal entries, `M₀₁ = 0.966 M₀₀` to two digits).
#[test]
fn the_issue_delta_weight_is_flushed() {
    let [f64_fwd, f64_back] = reflected_delta::<f64>(0.354, 23.3);
    println!(
        "f64 M00: forward {:e}, backward {:e}",
        f64_fwd[(0, 0)],
        f64_back[(0, 0)]
    );
    for m in [f64_fwd, f64_back] {
        assert!(m[(0, 0)] > 1e-43 && m[(0, 0)] < 1e-42);
        assert_clean("f64", &m);
    }
    let [fwd, back] = reflected_delta::<f32>(0.354, 23.3);
    assert_eq!(fwd, Matrix4::zeros(), "{fwd:e}");
    assert_eq!(back, Matrix4::zeros(), "{back:e}");
}

/// The sweep across the edge of the `f32` normal range: σ from 0.30 to 0.40 λ (`α` from ~1e-31
/// to ~1e-54 in `f32`'s terms), exits 0–70° inside the glass, forward and backward: no
/// subnormal entry, valid, and `M₀₀` the `f64` one (to 1e-4 relative plus the `16
/// MIN_POSITIVE` that flushing may add) where that is at least `MIN_POSITIVE`, 0 where it is
/// below `MIN_POSITIVE/(1 + 10⁻⁴)`.
#[test]
fn delta_weights_across_the_normal_range_are_flushed_consistently() {
    let min = f64::from(f32::MIN_POSITIVE);
    let (mut kept, mut zero) = (0, 0);
    for i in 0..=40 {
        let sigma = 0.30 + 0.0025 * f64::from(i);
        for theta in [0.0, 10.0, 23.3, 40.0, 55.0, 70.0] {
            let want = reflected_delta::<f64>(sigma, theta);
            let got = reflected_delta::<f32>(sigma, theta);
            for (w, g) in want.iter().zip(&got) {
                let what = format!("σ {sigma} λ, θ {theta}°");
                assert_clean(&what, g);
                assert_clean(&what, w);
                let (a, b) = (f64::from(g[(0, 0)]), w[(0, 0)]);
                if b >= min * (1.0 + 1e-4) {
                    assert!(
                        (a - b).abs() <= 1e-4 * b + 16.0 * min,
                        "{what}: {a:e} vs {b:e}"
                    );
                    kept += 1;
                } else if b < min / (1.0 + 1e-4) {
                    assert_eq!(a, 0.0, "{what}: f64 {b:e}");
                    zero += 1;
                }
            }
        }
    }
    println!("f32 weights kept {kept}, flushed to 0 {zero}");
    assert!(kept > 50 && zero > 50, "{kept} {zero}");
}

/// What the exit sampler draws and `eval` returns for one prepared packet agrees with
/// `Bsdf::incident_flags`: a delta draw only with `DELTA`, a non-delta specular draw only with
/// `COHERENT_SPECULAR`, and with `DELTA` (no `COHERENT_SPECULAR`) `eval`'s specular lobe is 0
/// at the specular direction. Returns whether the packet's section was representable, or
/// `None` where the packet or the sampler could not be built.
fn flags_case<T: Real>(width_over_lambda: f64, theta: f64, grating: bool) -> Option<bool> {
    use gmueller::bsdf::LobeFlags;
    use gmueller::interaction::{Full, Partial, RoughConductor, RoughDielectric};
    use gmueller::psd::Grating;
    use num_complex::Complex;
    let lambda = 0.5;
    let f = Frame::<T>::from_normal(Vector3::new(0.1, -0.2, 1.0).map(T::lit)).unwrap();
    let t = theta.to_radians();
    let to_source = (f.x() * T::lit(-t.sin()) + f.k() * T::lit(t.cos())).normalize();
    let mirror = (f.x() * T::lit(t.sin()) + f.k() * T::lit(t.cos())).normalize();
    let kernel = Kernel::<Full, Partial>::default();
    let run = |b: &dyn Fn(&WavePacket<T>) -> Option<ProbeAnswer<T>>| -> Option<bool> {
        let c = SurfaceCoherence::new(T::lit(width_over_lambda * lambda)).ok()?;
        let packet = c
            .packet(
                Stokes::unpolarized(T::one()).unwrap(),
                to_source,
                &f,
                T::lit(lambda),
            )
            .ok()?;
        let (flags, draws, specular, section) = b(&packet)?;
        let what = format!("w {width_over_lambda:e} λ, θ {theta}°, grating {grating}: {flags:?}");
        for (delta, part) in draws {
            if delta {
                assert!(flags.contains(LobeFlags::DELTA), "{what}: a delta drawn");
            } else if part == Part::Specular {
                assert!(
                    flags.contains(LobeFlags::COHERENT_SPECULAR),
                    "{what}: a specular lobe drawn"
                );
            }
        }
        if !flags.contains(LobeFlags::COHERENT_SPECULAR) {
            assert!(
                specular == T::zero(),
                "{what}: eval's specular lobe {specular:?}"
            );
        }
        Some(section)
    };
    let probe = |b: &dyn Probe<T>, p: &WavePacket<T>| b.probe(p, mirror);
    if grating {
        let g = Grating::<T, 2>::sinusoidal_height(
            T::lit(0.02),
            T::lit(3.0),
            &nalgebra::Vector2::new(T::one(), T::lit(0.3)),
        )
        .unwrap();
        let m = RoughConductor::new(g, Complex::new(T::lit(0.2), T::lit(3.5))).unwrap();
        let b = Bsdf::new(&m, kernel, f, T::lit(lambda)).unwrap();
        run(&|p| probe(&b, p))
    } else {
        let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.01), T::lit(2.0)).unwrap();
        let m = RoughDielectric::new(psd, T::lit(1.5)).unwrap();
        let b = Bsdf::new(&m, kernel, f, T::lit(lambda)).unwrap();
        run(&|p| probe(&b, p))
    }
}

/// One BSDF's answers for [`flags_case`]: its flags for the packet, the lobes of 200 draws,
/// `eval`'s specular `M₀₀` at the mirror direction, and whether the section exists.
trait Probe<T: Real> {
    fn probe(&self, packet: &WavePacket<T>, mirror: Vector3<T>) -> Option<ProbeAnswer<T>>;
}

/// What [`Probe::probe`] answers: the flags, the (delta, part) of each draw, the specular
/// `M₀₀` and whether the section exists.
type ProbeAnswer<T> = (gmueller::bsdf::LobeFlags, Vec<(bool, Part)>, T, bool);

impl<T, P, Sp, Sc, Pol, Coh, Rough> Probe<T>
    for Bsdf<'_, T, RoughSurface<P, Sp, Sc>, Kernel<Pol, Coh, Rough>>
where
    T: Real,
    P: gmueller::psd::Psd<T, 2>,
    Sp: gmueller::bsdf::Interface<T>,
    Sc: gmueller::interaction::pbsdf::Pbsdf<T>,
    Pol: gmueller::interaction::polarization::PolarizationModel,
    Coh: gmueller::interaction::coherence::CoherenceWeights<T, P>,
    Rough: gmueller::interaction::roughness::RoughnessWeights<T, P, Coh>,
{
    fn probe(
        &self,
        packet: &WavePacket<T>,
        mirror: Vector3<T>,
    ) -> Option<(gmueller::bsdf::LobeFlags, Vec<(bool, Part)>, T, bool)> {
        use gmueller::interaction::polarization::Throughput;
        let inc = self.prepare(packet).ok()?;
        let flags = self.incident_flags(&inc);
        let sampler = self.exit_sampler(&inc).ok()?;
        let mut draws = Vec::new();
        for i in 0..200 {
            let u = T::lit((f64::from(i) + 0.5) / 200.0);
            if let Some(s) = sampler.sample(u, [T::lit(0.3), T::lit(0.6)]) {
                draws.push((s.lobe.delta, s.lobe.part));
            }
        }
        let specular = self.eval(&inc, mirror).ok()?.response.specular.m00();
        Some((flags, draws, specular, inc.prepared().section().is_some()))
    }
}

/// Issue 36 (3): coherence widths 10³…10¹⁵ λ (half decades), incidence 0°, 30°, 70°, rough
/// glass and a metal height grating, `Full · Partial`, f32 and f64: the flags of every
/// prepared packet are truthful ([`flags_case`]). In `f32` the section stops being
/// representable at 10¹¹ λ (its entries `1/w²` are then ~10⁻²³ µm⁻² and their products
/// underflow): there the sampler draws the plane wave's deltas, and `Bsdf::flags` (static)
/// said `COHERENT_SPECULAR` without `DELTA`.
#[test]
fn incident_flags_tell_the_truth_past_the_section() {
    for (name, run) in [
        (
            "f32",
            flags_case::<f32> as fn(f64, f64, bool) -> Option<bool>,
        ),
        ("f64", flags_case::<f64>),
    ] {
        let mut fallback_from = f64::INFINITY;
        let mut built = 0;
        for k in 6..=30 {
            let w = 10f64.powf(f64::from(k) / 2.0);
            for theta in [0.0, 30.0, 70.0] {
                for grating in [false, true] {
                    if let Some(section) = run(w, theta, grating) {
                        built += 1;
                        if !section {
                            fallback_from = fallback_from.min(w);
                        }
                    }
                }
            }
        }
        println!(
            "{name}: {built} packets sampled; plane-wave fallback from w = {fallback_from:e} λ"
        );
        if name == "f32" {
            assert!(fallback_from <= 1e12, "{fallback_from:e}");
        }
        assert!(built > 20);
    }
}
