//! The medium's promises at the extremes, in f32 and f64: valid Stokes outputs, no NaN, finite
//! positive pdf and `σ_s` (property tests over random packets — two shapes up to the Bochner
//! bound, any frame, `σ_zz` and wavelength over decades — random media and exit directions with
//! exact forward and backward among them, at every coherence level); f32 within a stated
//! bound of f64; invariance under the scale of `S0` (1e±300 f64, 1e±30 f32) and of the length
//! unit; continuity across the forward/backward frame switch seen in a fixed frame; the limits
//! of the coherence levels; unbounded `σ_zz`; bad input.

use crate::common;

use common::{Tol, assert_close, log_uniform, proptest_config};
use gmueller::Real;
use gmueller::frame::{Frame, stokes_to_frame};
use gmueller::interaction::{
    Full, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave, PolarizationModel,
    Throughput,
};
use gmueller::medium::{Dipole, PhaseFunction, RandomMedium, Scalar, VolumeCoherence, VolumePsd};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{GaussianPsd, KCorrelation};
use gmueller::stokes::Stokes;
use gmueller::verify::check::assert_valid_stokes;
use gmueller::verify::strategy::{frame, packet_parts, unit_vector3};
use nalgebra::{Matrix2, Matrix3, Vector3, Vector4};
use proptest::prelude::*;

/// A medium of the property tests: isotropic or anisotropic Gaussian, or K-correlation.
#[derive(Debug, Clone, Copy)]
enum MediumSpec {
    Iso(f64),
    Aniso(f64, f64, f64),
    K(f64, f64),
}

fn medium_spec() -> impl Strategy<Value = MediumSpec> {
    prop_oneof![
        log_uniform(1e-3, 1e2).prop_map(MediumSpec::Iso),
        (log_uniform(1e-2, 1e1), log_uniform(1e-2, 1e1), -0.9..0.9f64)
            .prop_map(|(a, b, c)| MediumSpec::Aniso(a, b, c)),
        (log_uniform(1e-2, 1e2), 2.1..6.0f64).prop_map(|(t, g)| MediumSpec::K(t, g)),
    ]
}

/// An exit direction: random, or forward, backward, or within 1e-12…1e-3 rad of either.
fn exit_direction() -> impl Strategy<Value = (Vector3<f64>, u8, f64)> {
    (unit_vector3(), 0u8..6, log_uniform(1e-12, 1e-3))
}

fn exit_of<T: Real>(f: &Frame<T>, (r, kind, eps): (Vector3<f64>, u8, f64)) -> Vector3<T> {
    let (d, x) = (f.k().map(|v| v.to_f64()), f.x().map(|v| v.to_f64()));
    let r = match kind {
        0 => d,
        1 => -d,
        2 => (d + x * eps).normalize(),
        3 => (-d + x * eps).normalize(),
        _ => r,
    };
    r.map(T::lit)
}

struct Case<T: Real> {
    packet: WavePacket<T>,
    spec: MediumSpec,
}

fn case<T: Real>(
    (s, tx, ty): (Vector4<f64>, Matrix2<f64>, Matrix2<f64>),
    f: Frame<f64>,
    lambda: f64,
    zz: f64,
    spec: MediumSpec,
) -> Option<Case<T>> {
    let l2 = lambda * lambda;
    let fr = Frame::new(f.x().map(T::lit), f.y().map(T::lit), f.k().map(T::lit)).ok()?;
    let packet = WavePacket::new(
        Stokes::new(T::lit(s[0]), T::lit(s[1]), T::lit(s[2]), T::lit(s[3])).ok()?,
        CoherenceShape::new((tx * l2).map(T::lit)).ok()?,
        CoherenceShape::new((ty * l2).map(T::lit)).ok()?,
        fr,
        T::lit(lambda),
    )
    .ok()?
    .with_longitudinal_coherence(T::lit(zz * lambda))
    .ok()?;
    Some(Case { packet, spec })
}

/// Runs `check` for the case's medium at the level `(Pol, Coh)`.
fn with_medium<T: Real>(spec: MediumSpec, lambda: f64, mut check: impl FnMut(&dyn Checker<T>)) {
    match spec {
        MediumSpec::Iso(l) => {
            let m = RandomMedium::new(
                GaussianPsd::<T, 3>::isotropic(T::lit(1e-3), T::lit(l * lambda)).unwrap(),
                Dipole,
            );
            check(&m);
        }
        MediumSpec::Aniso(a, b, c) => {
            let l = lambda;
            let cov = Matrix3::new(
                a * a,
                c * a * b,
                0.0,
                c * a * b,
                b * b,
                0.0,
                0.0,
                0.0,
                a * b,
            ) * (l * l);
            let corr = gmueller::gaussian::Gaussian::new(cov.map(T::lit)).unwrap();
            let m = RandomMedium::new(
                GaussianPsd::from_autocorrelation(T::lit(1e-6), &corr).unwrap(),
                Dipole,
            );
            check(&m);
        }
        MediumSpec::K(t, g) => {
            let m = ByQuadrature(RandomMedium::new(
                KCorrelation::<T, 3>::new(T::lit(1e-6), T::lit(t * lambda * lambda), T::lit(g))
                    .unwrap(),
                Scalar,
            ));
            check(&m);
        }
    }
}

/// The checks of one medium, object-safe over its PSD and scatterer.
trait Checker<T: Real> {
    fn all_levels(&self, packet: &WavePacket<T>, exit: Vector3<T>, tol: f64);
}

impl<T: Real, P, M: gmueller::medium::Scatterer<T>> Checker<T> for RandomMedium<P, M>
where
    P: VolumePsd<T> + gmueller::psd::ClosedFormBlur<T, 3>,
{
    fn all_levels(&self, packet: &WavePacket<T>, exit: Vector3<T>, tol: f64) {
        let partial = Partial(gmueller::psd::ClosedForm);
        levels(self, partial, packet, exit, tol);
    }
}

/// A medium whose PSD has no closed-form blur: `Partial` by Gauss–Hermite quadrature.
struct ByQuadrature<P, M>(RandomMedium<P, M>);

impl<T: Real, P: VolumePsd<T>, M: gmueller::medium::Scatterer<T>> Checker<T>
    for ByQuadrature<P, M>
{
    fn all_levels(&self, packet: &WavePacket<T>, exit: Vector3<T>, tol: f64) {
        let partial = Partial(gmueller::psd::GaussHermite::<T>::new(6).unwrap());
        levels(&self.0, partial, packet, exit, tol);
    }
}

fn levels<T, P, M, B>(
    m: &RandomMedium<P, M>,
    partial: Partial<B>,
    packet: &WavePacket<T>,
    exit: Vector3<T>,
    tol: f64,
) where
    T: Real,
    P: VolumePsd<T>,
    M: gmueller::medium::Scatterer<T>,
    B: gmueller::psd::BlurMethod<T, 3, P> + Clone + core::fmt::Debug,
{
    level(
        m,
        Kernel::<Full, _>::new(partial.clone()),
        packet,
        exit,
        tol,
        "Full·Partial",
    );
    level(
        m,
        Kernel::<OneShape, _>::new(partial.clone()),
        packet,
        exit,
        tol,
        "OneShape·Partial",
    );
    level(
        m,
        Kernel::<Intensity, _>::new(partial),
        packet,
        exit,
        tol,
        "Intensity·Partial",
    );
    level(
        m,
        Kernel::<Full, PlaneWave>::default(),
        packet,
        exit,
        tol,
        "Full·PlaneWave",
    );
    level(
        m,
        Kernel::<Full, Incoherent>::default(),
        packet,
        exit,
        tol,
        "Full·Incoherent",
    );
}

fn stokes64<T: Real>(v: Vector4<T>) -> Vector4<f64> {
    v.map(|x| x.to_f64())
}

/// Every promise at one level: finite valid `dI/dV`, `σ_s`, `F S`, sample and pdf.
fn level<T, P, M, Pol, Coh>(
    medium: &RandomMedium<P, M>,
    kernel: Kernel<Pol, Coh>,
    packet: &WavePacket<T>,
    exit: Vector3<T>,
    tol: f64,
    name: &str,
) where
    T: Real,
    P: VolumePsd<T>,
    M: gmueller::medium::Scatterer<T>,
    Pol: PolarizationModel,
    Coh: VolumeCoherence<T, P>,
{
    let phase = PhaseFunction::new(medium, kernel);
    let inc = phase.prepare(packet).unwrap();
    let sigma = inc.scattering_coefficient();
    assert!(
        sigma.is_finite() && sigma > T::zero(),
        "{name}: σ_s = {sigma:?}"
    );
    let s = packet.stokes();
    let as_stokes = |l: &<Pol::Throughput<T> as Throughput<T>>::Light| {
        <Pol::Throughput<T> as Throughput<T>>::light_stokes(l).map_or_else(
            || {
                let i = <Pol::Throughput<T> as Throughput<T>>::intensity(l);
                Vector4::new(i, T::zero(), T::zero(), T::zero())
            },
            |st| st.vector(),
        )
    };
    let d = phase.differential_scattering(&inc, exit).unwrap();
    assert_valid_stokes(
        &format!("{name}: dI/dV"),
        stokes64(as_stokes(&d.light)),
        Tol::new(0.0, tol),
    );
    let f = phase.eval(&inc, exit).unwrap().phase;
    assert!(f.is_finite(), "{name}: F not finite");
    let light = <Pol::Throughput<T> as Throughput<T>>::light(&s);
    assert_valid_stokes(
        &format!("{name}: F S"),
        stokes64(as_stokes(&f.apply(&light))),
        Tol::new(0.0, tol),
    );
    let p = phase.pdf(&inc, &exit);
    assert!(p.is_finite() && p > T::zero(), "{name}: pdf {p:?}");
    let smp = phase.sample(&inc, T::lit(0.37), [T::lit(0.81), T::lit(0.13)]);
    assert!(smp.pdf.is_finite() && smp.pdf > T::zero() && smp.weight.is_finite());
    assert!(phase.pdf(&inc, &smp.direction) == smp.pdf);
}

proptest! {
    #![proptest_config(proptest_config(48))]

    /// f64: every level's outputs are finite and valid, forward and backward included, for
    /// packets up to the Bochner bound.
    #[test]
    fn valid_outputs_f64(
        parts in packet_parts(1.0),
        f in frame(),
        lambda in log_uniform(0.1, 10.0),
        zz in log_uniform(0.1, 1e4),
        spec in medium_spec(),
        exit in exit_direction(),
    ) {
        let c = case::<f64>(parts, f, lambda, zz, spec).unwrap();
        let r = exit_of(c.packet.frame(), exit);
        with_medium::<f64>(c.spec, lambda, |m| m.all_levels(&c.packet, r, 1e-12));
    }

    /// At the realizability bound (`|μ|²` within 1 % of it) the Full level stays valid.
    #[test]
    fn valid_outputs_at_the_bochner_bound(
        parts in packet_parts(0.01),
        f in frame(),
        spec in medium_spec(),
        exit in exit_direction(),
    ) {
        let c = case::<f64>(parts, f, 0.5, 4.0, spec).unwrap();
        let r = exit_of(c.packet.frame(), exit);
        with_medium::<f64>(c.spec, 0.5, |m| m.all_levels(&c.packet, r, 1e-12));
    }

    /// f32: the same promises.
    #[test]
    fn valid_outputs_f32(
        parts in packet_parts(1.0),
        f in frame(),
        lambda in log_uniform(0.1, 10.0),
        zz in log_uniform(0.1, 1e3),
        spec in medium_spec(),
        exit in exit_direction(),
    ) {
        let c = case::<f32>(parts, f, lambda, zz, spec).unwrap();
        let r = exit_of(c.packet.frame(), exit);
        with_medium::<f32>(c.spec, lambda, |m| m.all_levels(&c.packet, r, 2e-6));
    }
}

/// A packet on the standard frame turned about y by `tilt`, unpolarized or not, with isotropic
/// or anisotropic transverse shapes (length units of `lambda`).
fn simple<T: Real>(
    stokes: [f64; 4],
    shape: Matrix2<f64>,
    zz: Option<f64>,
    lambda: f64,
) -> WavePacket<T> {
    let f = Frame::from_direction_and_x(
        Vector3::new(0.2, -0.3, 0.93).map(T::lit),
        Vector3::new(1.0, 0.1, 0.0).map(T::lit),
    )
    .unwrap();
    let p = WavePacket::from_stokes(
        Stokes::new(
            T::lit(stokes[0]),
            T::lit(stokes[1]),
            T::lit(stokes[2]),
            T::lit(stokes[3]),
        )
        .unwrap(),
        CoherenceShape::new(shape.map(T::lit)).unwrap(),
        f,
        T::lit(lambda),
    )
    .unwrap();
    match zz {
        Some(z) => p.with_longitudinal_coherence(T::lit(z)).unwrap(),
        None => p,
    }
}

fn gaussian<T: Real>(ell: f64) -> RandomMedium<GaussianPsd<T, 3>, Dipole> {
    RandomMedium::new(
        GaussianPsd::<T, 3>::isotropic(T::lit(2e-3), T::lit(ell)).unwrap(),
        Dipole,
    )
}

fn turned(d: &Vector3<f64>, t: f64, phi: f64) -> Vector3<f64> {
    let x = if d.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (x - d * d.dot(&x)).normalize();
    let e2 = d.cross(&e1);
    (d * t.cos() + (e1 * phi.cos() + e2 * phi.sin()) * t.sin()).normalize()
}

/// f32 against f64 on the same (f32-representable) inputs, every level, exits from forward to
/// backward: `dI/dV` within `max|ΔS|/S0 ≤ 1e-4` and `σ_s` within 1e-5 relative (measured
/// 1.8e-5 and 1.7e-6), for `kℓ` from 0.01 to 60 and coherence widths 1–100 λ.
#[test]
fn f32_agrees_with_f64() {
    let mut worst = (0.0f64, 0.0f64);
    for ell in [0.001, 0.05, 0.5, 5.0] {
        for (w, zz) in [(0.5, 1.0), (5.0, 50.0), (50.0, 3.0)] {
            let stokes = [1.0, 0.3, -0.5, 0.4];
            let shape = Matrix2::new(w * w, 0.3 * w * w, 0.3 * w * w, 2.0 * w * w);
            let (m32, m64) = (gaussian::<f32>(ell), gaussian::<f64>(ell));
            let p32 = simple::<f32>(stokes, shape, Some(zz), 0.5);
            let p64 = widened(&p32);
            let ph32 = PhaseFunction::new(&m32, Kernel::<Full, Partial>::default());
            let ph64 = PhaseFunction::new(&m64, Kernel::<Full, Partial>::default());
            let (i32_, i64_) = (ph32.prepare(&p32).unwrap(), ph64.prepare(&p64).unwrap());
            let ds = (f64::from(i32_.scattering_coefficient()) / i64_.scattering_coefficient()
                - 1.0)
                .abs();
            worst.1 = worst.1.max(ds);
            let d = p64.frame().k();
            for t in [0.0, 1e-3, 0.1, 0.8, 1.6, 2.5, 3.1, std::f64::consts::PI] {
                let r64 = turned(&d, t, 0.7);
                let r32 = r64.map(|x| x as f32);
                let r64 = r32.map(f64::from);
                let a = ph32
                    .differential_scattering(&i32_, r32)
                    .unwrap()
                    .light
                    .vector()
                    .map(f64::from);
                let b = ph64
                    .differential_scattering(&i64_, r64)
                    .unwrap()
                    .light
                    .vector();
                if b[0] > 1e-30 {
                    let e = (a - b).amax() / b[0];
                    worst.0 = worst.0.max(e);
                    assert!(
                        e <= 2e-4,
                        "ℓ {ell} w {w} θ {t}: f32 {a:?} f64 {b:?} ({e:e})"
                    );
                }
            }
        }
    }
    println!(
        "f32 vs f64: max |ΔS|/S0 = {:.2e}, max σ_s relative = {:.2e}",
        worst.0, worst.1
    );
    assert!(worst.1 <= 1e-5);
}

/// The f64 packet with the numbers of an f32 one (the frame renormalised).
fn widened(p: &WavePacket<f32>) -> WavePacket<f64> {
    let f = p.frame();
    // (f32 unit vectors are not unit to f64's 256 ε: renormalised, a ~1e-7 change.)
    let fr = Frame::from_direction_and_x(f.k().map(f64::from), f.x().map(f64::from)).unwrap();
    let s = p.stokes().vector().map(f64::from);
    let c = |ch| CoherenceShape::new(p.shape(ch).map(f64::from)).unwrap();
    let out = WavePacket::new(
        Stokes::new(s[0], s[1], s[2], s[3]).unwrap(),
        c(gmueller::packet::Channel::X),
        c(gmueller::packet::Channel::Y),
        fr,
        f64::from(p.wavelength()),
    )
    .unwrap();
    let inv = f64::from(p.inverse_longitudinal_variance());
    if inv > 0.0 {
        out.with_longitudinal_coherence(inv.sqrt().recip()).unwrap()
    } else {
        out
    }
}

/// `F`, `σ_s` and the pdf do not depend on the packet's brightness, and `dI/dV` is
/// proportional to it: `S0` from 1e-300 to 1e300 (f64) and 1e-30 to 1e30 (f32), to 1e-12
/// (f64) and 1e-5 (f32) relative — the weights meet `ln S0` in log space.
#[test]
fn brightness_invariance() {
    fn run<T: Real>(scales: &[f64], tol: f64) {
        let m = gaussian::<T>(0.3);
        let base = [1.0, 0.2, -0.3, 0.6];
        let shape = Matrix2::new(9.0, 2.0, 2.0, 4.0);
        let phase = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
        let p1 = simple::<T>(base, shape, Some(2.0), 0.5);
        let i1 = phase.prepare(&p1).unwrap();
        let r = turned(&p1.frame().k().map(|x| x.to_f64()), 0.9, 1.0).map(T::lit);
        let f1 = phase
            .eval(&i1, r)
            .unwrap()
            .phase
            .matrix()
            .map(|x| x.to_f64());
        let d1 = phase
            .differential_scattering(&i1, r)
            .unwrap()
            .light
            .vector()
            .map(|x| x.to_f64());
        for &c in scales {
            let p = simple::<T>(base.map(|v| v * c), shape, Some(2.0), 0.5);
            let i = phase.prepare(&p).unwrap();
            assert_close(
                "σ_s",
                i.scattering_coefficient().to_f64(),
                i1.scattering_coefficient().to_f64(),
                Tol::new(0.0, tol),
            );
            let f = phase
                .eval(&i, r)
                .unwrap()
                .phase
                .matrix()
                .map(|x| x.to_f64());
            assert!((f - f1).amax() <= tol * f1.amax(), "F at S0 × {c:e}");
            let d = phase
                .differential_scattering(&i, r)
                .unwrap()
                .light
                .vector()
                .map(|x| x.to_f64());
            for k in 0..4 {
                assert_close(
                    &format!("dI/dV[{k}] at S0 × {c:e}"),
                    d[k] / c,
                    d1[k],
                    Tol::new(tol * d1[0], tol),
                );
            }
            assert_close(
                "pdf",
                phase.pdf(&i, &r).to_f64(),
                phase.pdf(&i1, &r).to_f64(),
                Tol::new(0.0, tol),
            );
        }
    }
    run::<f64>(&[1e-300, 1e-150, 1e-20, 1e20, 1e150, 1e300], 1e-12);
    run::<f32>(&[1e-30, 1e-10, 1e10, 1e30], 1e-5);
}

/// The length unit: scaling λ, ℓ, the coherence widths and `σ_zz` by `c` leaves `F` and the pdf
/// unchanged and divides `σ_s` (and `dI/dV`) by `c` (`k⁴ p` with `p ∝ σ² ℓ³`), for `c` from
/// 1e-6 to 1e6 (f64) and 1e-3 to 1e3 (f32).
#[test]
fn length_unit_invariance() {
    fn run<T: Real>(scales: &[f64], tol: f64) {
        let base = |c: f64| {
            let m = gaussian::<T>(0.3 * c);
            let p = simple::<T>(
                [1.0, 0.2, -0.3, 0.6],
                Matrix2::new(9.0, 2.0, 2.0, 4.0) * (c * c),
                Some(2.0 * c),
                0.5 * c,
            );
            (m, p)
        };
        let (m1, p1) = base(1.0);
        let ph1 = PhaseFunction::new(&m1, Kernel::<Full, Partial>::default());
        let i1 = ph1.prepare(&p1).unwrap();
        let r = turned(&p1.frame().k().map(|x| x.to_f64()), 2.0, -0.4).map(T::lit);
        let f1 = ph1.eval(&i1, r).unwrap().phase.matrix().map(|x| x.to_f64());
        for &c in scales {
            let (m, p) = base(c);
            let ph = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
            let i = ph.prepare(&p).unwrap();
            assert_close(
                &format!("σ_s c at c = {c:e}"),
                i.scattering_coefficient().to_f64() * c,
                i1.scattering_coefficient().to_f64(),
                Tol::new(0.0, tol),
            );
            let f = ph.eval(&i, r).unwrap().phase.matrix().map(|x| x.to_f64());
            assert!(
                (f - f1).amax() <= tol * f1.amax(),
                "F at c = {c:e}: {}",
                (f - f1).amax() / f1.amax()
            );
            assert_close(
                "pdf",
                ph.pdf(&i, &r).to_f64(),
                ph1.pdf(&i1, &r).to_f64(),
                Tol::new(0.0, tol),
            );
        }
    }
    run::<f64>(&[1e-6, 1e-2, 1e2, 1e6], 1e-11);
    run::<f32>(&[1e-3, 1e3], 2e-5);
}

/// Across the forward and backward frame switch (`|d̂ × r̂| = √ε`) the scattered light, seen in
/// a frame that does not switch, is continuous: within `50 θ²` (the `O(θ²)` change of the dipole
/// matrix and of the lobe) plus 1e-12 (f64) or `2e-6 (1 + m)` (f32, `m = 2(kℓ)²` the lobe's
/// exponent at backscatter: an f32 direction moves the exponent by `ε₃₂ m`) of the exact
/// forward or backward value, for the dipole and the scalar scatterer.
#[test]
fn forward_and_backward_are_continuous() {
    fn run<T: Real, M: gmueller::medium::Scatterer<T>>(
        scatterer: M,
        angles: &[f64],
        f32_like: bool,
    ) {
        let ell = 0.4;
        let m = RandomMedium::new(
            GaussianPsd::<T, 3>::isotropic(T::lit(2e-3), T::lit(ell)).unwrap(),
            scatterer,
        );
        let p = simple::<T>(
            [1.0, 0.5, 0.3, -0.6],
            Matrix2::new(4.0, 0.0, 0.0, 4.0),
            Some(2.0),
            0.5,
        );
        let k = p.wavenumber().to_f64();
        let tol = if f32_like {
            2e-6 * (1.0 + 2.0 * (k * ell).powi(2))
        } else {
            1e-12
        };
        let phase = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
        let inc = phase.prepare(&p).unwrap();
        let d = p.frame().k().map(|x| x.to_f64());
        let x = p.frame().x().map(|x| x.to_f64());
        for sign in [1.0, -1.0] {
            let fixed = |r: &Vector3<f64>| {
                Frame::<T>::from_direction_and_x(r.map(T::lit), x.map(T::lit)).unwrap()
            };
            let at = |r: Vector3<f64>| {
                let v = phase.differential_scattering(&inc, r.map(T::lit)).unwrap();
                stokes_to_frame(
                    &Stokes::from_vector_unchecked(v.light.vector()),
                    v.geometry.exit_frame(),
                    &fixed(&r),
                )
                .vector()
                .map(|x| x.to_f64())
            };
            let exact = at(d * sign);
            for &t in angles {
                for phi in [0.0, 1.1, 2.5, 4.0] {
                    let r = turned(&(d * sign), t, phi);
                    let v = at(r);
                    let dev = (v - exact).amax() / exact[0];
                    let allowed = tol + 50.0 * t * t;
                    assert!(
                        dev <= allowed,
                        "{} θ = {t:e} φ = {phi}: {dev:e} > {allowed:e}",
                        if sign > 0.0 { "forward" } else { "backward" }
                    );
                }
            }
        }
    }
    run::<f64, _>(Dipole, &[1e-12, 1e-9, 1.4e-8, 1.6e-8, 1e-7, 1e-5], false);
    run::<f64, _>(Scalar, &[1e-12, 1.4e-8, 1.6e-8, 1e-5], false);
    run::<f32, _>(Dipole, &[1e-5, 3.4e-4, 3.6e-4, 1e-3], true);
}

/// The limits of the coherence levels: `Partial` → `PlaneWave` as the coherence grows (w and
/// `σ_zz` 1e4 ℓ: within 1e-6), → `Incoherent` as it shrinks (1e-3 ℓ: within 1e-5); `Full` on a
/// single-shape packet is `OneShape` exactly; `Partial` with unbounded `σ_zz` is its limit
/// (`σ_zz = 1e8 ℓ` within 1e-9), `Incoherent` with unbounded `σ_zz` is refused.
#[test]
fn coherence_level_limits() {
    let ell = 0.5;
    let m = gaussian::<f64>(ell);
    let st = [1.0, 0.3, 0.1, -0.2];
    let r0 = Vector3::new(0.2, -0.3, 0.93).normalize();
    let exits: Vec<Vector3<f64>> = [0.0, 0.05, 0.4, 1.3, 2.9]
        .iter()
        .map(|&t| turned(&r0, t, 0.6))
        .collect();
    let s0 = |pk: &WavePacket<f64>, r: &Vector3<f64>, partial: bool| -> Vector4<f64> {
        if partial {
            m.differential_scattering(&Kernel::<Full, Partial>::default(), pk, *r)
                .unwrap()
                .light
                .vector()
        } else {
            m.differential_scattering(&Kernel::<Full, PlaneWave>::default(), pk, *r)
                .unwrap()
                .light
                .vector()
        }
    };
    let wide = simple::<f64>(
        st,
        Matrix2::identity() * (1e4 * ell).powi(2),
        Some(1e4 * ell),
        0.5,
    );
    for r in &exits {
        let (a, b) = (s0(&wide, r, true), s0(&wide, r, false));
        assert!(
            (a - b).amax() <= 1e-6 * b[0],
            "Partial → PlaneWave at {r:?}: {a:?} vs {b:?}"
        );
    }
    let narrow = simple::<f64>(
        st,
        Matrix2::identity() * (1e-3 * ell).powi(2),
        Some(1e-3 * ell),
        0.5,
    );
    for r in &exits {
        let a = s0(&narrow, r, true);
        let b = m
            .differential_scattering(&Kernel::<Full, Incoherent>::default(), &narrow, *r)
            .unwrap()
            .light
            .vector();
        assert!(
            (a - b).amax() <= 1e-5 * b[0],
            "Partial → Incoherent at {r:?}: {a:?} vs {b:?}"
        );
    }
    let p = simple::<f64>(st, Matrix2::new(3.0, 1.0, 1.0, 2.0), Some(1.5), 0.5);
    for r in &exits {
        let full = m
            .differential_scattering(&Kernel::<Full, Partial>::default(), &p, *r)
            .unwrap()
            .light;
        let one = m
            .differential_scattering(&Kernel::<OneShape, Partial>::default(), &p, *r)
            .unwrap()
            .light;
        assert_eq!(full, one);
    }
    let unbounded = simple::<f64>(st, Matrix2::new(3.0, 1.0, 1.0, 2.0), None, 0.5);
    let long = simple::<f64>(st, Matrix2::new(3.0, 1.0, 1.0, 2.0), Some(1e8 * ell), 0.5);
    for r in &exits {
        let (a, b) = (s0(&unbounded, r, true), s0(&long, r, true));
        assert!(
            (a - b).amax() <= 1e-9 * b[0],
            "σ_zz = ∞ vs 1e8 ℓ at {r:?}: {a:?} vs {b:?}"
        );
    }
    let refused = m.differential_scattering(&Kernel::<Full, Incoherent>::default(), &unbounded, r0);
    assert!(
        matches!(refused, Err(gmueller::Error::Singular { .. })),
        "{refused:?}"
    );
    let phase = PhaseFunction::new(&m, Kernel::<Full, Incoherent>::default());
    assert!(phase.prepare(&unbounded).is_err());
}

/// Bad exit directions are errors, never NaN or a panic; huge and tiny finite ones are fine.
#[test]
fn bad_exit_directions() {
    let m = gaussian::<f64>(0.5);
    let p = simple::<f64>(
        [1.0, 0.0, 0.0, 0.0],
        Matrix2::identity() * 4.0,
        Some(2.0),
        0.5,
    );
    let phase = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
    let inc = phase.prepare(&p).unwrap();
    for bad in [
        Vector3::zeros(),
        Vector3::new(f64::NAN, 0.0, 1.0),
        Vector3::new(0.0, f64::INFINITY, 0.0),
    ] {
        assert!(phase.eval(&inc, bad).is_err());
        assert!(phase.differential_scattering(&inc, bad).is_err());
        assert!(
            m.differential_scattering(&Kernel::<Full, Partial>::default(), &p, bad)
                .is_err()
        );
    }
    for s in [1e-300, 1e300, f64::MAX, f64::MIN_POSITIVE * f64::EPSILON] {
        let v = phase.eval(&inc, Vector3::new(s, -s, s)).unwrap();
        assert!(v.phase.is_finite());
        assert!(phase.pdf(&inc, &v.geometry.exit_direction()).is_finite());
    }
}

/// Extreme anisotropy and scales: transverse coherence widths with a ratio up to 1e3 (1e6 in
/// `Θ⊥`), turned; `σ_zz` from 1e-3 to 1e6 λ; Gaussian media with ℓ from 1e-3 to 1e3 λ and a
/// correlation anisotropy of 100. Every level and precision either prepares and returns
/// finite, valid outputs with a finite `σ_s ≥ 0` and a finite positive pdf, or refuses the packet
/// with an error — never a panic or a NaN.
#[test]
fn extreme_anisotropy_and_scales() {
    fn run<T: Real>(tol: f64) -> (usize, usize) {
        let (mut ok, mut refused) = (0, 0);
        let lambda = 0.5;
        for &ratio in &[1e-3, 1.0, 1e3] {
            for &zz in &[1e-3, 1.0, 1e6] {
                for &ell in &[1e-3, 1.0, 1e3] {
                    let w = 3.0_f64;
                    let rot = |a: f64| Matrix2::new(a.cos(), -a.sin(), a.sin(), a.cos());
                    let r = rot(0.4);
                    let shape = r
                        * Matrix2::new(w * w, 0.0, 0.0, (w * ratio).powi(2))
                        * r.transpose()
                        * (lambda * lambda);
                    let shape = (shape + shape.transpose()) * 0.5;
                    let Ok(cs) = CoherenceShape::new(shape.map(T::lit)) else {
                        refused += 1;
                        continue;
                    };
                    let f = Frame::from_direction_and_x(
                        Vector3::new(0.2, -0.3, 0.93).map(T::lit),
                        Vector3::new(1.0, 0.1, 0.0).map(T::lit),
                    )
                    .unwrap();
                    let Ok(p) = WavePacket::from_stokes(
                        Stokes::new(T::one(), T::lit(0.3), T::lit(-0.4), T::lit(0.5)).unwrap(),
                        cs,
                        f,
                        T::lit(lambda),
                    )
                    .and_then(|p| p.with_longitudinal_coherence(T::lit(zz * lambda))) else {
                        refused += 1;
                        continue;
                    };
                    let l = ell * lambda;
                    let cov = Matrix3::new(
                        l * l,
                        0.0,
                        0.0,
                        0.0,
                        1e-4 * l * l,
                        0.0,
                        0.0,
                        0.0,
                        0.3 * l * l,
                    );
                    let Ok(corr) = gmueller::gaussian::Gaussian::new(cov.map(T::lit)) else {
                        refused += 1;
                        continue;
                    };
                    let Ok(psd) = GaussianPsd::from_autocorrelation(T::lit(1e-6), &corr) else {
                        refused += 1;
                        continue;
                    };
                    let m = RandomMedium::new(psd, Dipole);
                    let d = p.frame().k().map(|x| x.to_f64());
                    for t in [0.0, 1e-3, 0.5, 2.0, std::f64::consts::PI] {
                        let r = turned(&d, t, 0.3).map(T::lit);
                        for outcome in [
                            probe(&m, Kernel::<Full, Partial>::default(), &p, r, tol),
                            probe(&m, Kernel::<Full, Incoherent>::default(), &p, r, tol),
                            probe(&m, Kernel::<Intensity, PlaneWave>::default(), &p, r, tol),
                        ] {
                            if outcome { ok += 1 } else { refused += 1 }
                        }
                    }
                }
            }
        }
        (ok, refused)
    }
    let (ok64, no64) = run::<f64>(1e-12);
    let (ok32, no32) = run::<f32>(2e-6);
    println!("f64: {ok64} evaluated, {no64} refused; f32: {ok32} evaluated, {no32} refused");
    assert!(ok64 > 0 && ok32 > 0);
}

/// One level at one exit: `true` if it prepared and every output is finite and valid, `false`
/// if it refused the packet with an error (a NaN or an invalid output fails the test).
fn probe<T, P, Pol, Coh>(
    m: &RandomMedium<P, Dipole>,
    kernel: Kernel<Pol, Coh>,
    p: &WavePacket<T>,
    r: Vector3<T>,
    tol: f64,
) -> bool
where
    T: Real,
    P: VolumePsd<T>,
    Pol: PolarizationModel,
    Coh: VolumeCoherence<T, P>,
{
    let phase = PhaseFunction::new(m, kernel);
    let inc = match phase.prepare(p) {
        Ok(i) => i,
        Err(e) => {
            println!(
                "refused: {e} (Θ⊥ {:?}, 1/σ_zz² {:?})",
                p.shape(gmueller::packet::Channel::X),
                p.inverse_longitudinal_variance()
            );
            return false;
        }
    };
    let sigma = inc.scattering_coefficient();
    assert!(sigma.is_finite() && sigma >= T::zero(), "σ_s = {sigma:?}");
    let f = phase.eval(&inc, r).unwrap().phase;
    assert!(f.is_finite());
    let d = phase.differential_scattering(&inc, r).unwrap().light;
    let light = <Pol::Throughput<T> as Throughput<T>>::light_stokes(&d).map_or_else(
        || {
            Vector4::new(
                <Pol::Throughput<T> as Throughput<T>>::intensity(&d),
                T::zero(),
                T::zero(),
                T::zero(),
            )
        },
        |s| s.vector(),
    );
    assert_valid_stokes("dI/dV", light.map(|x| x.to_f64()), Tol::new(0.0, tol));
    let pdf = phase.pdf(&inc, &r);
    assert!(pdf.is_finite() && pdf > T::zero(), "pdf {pdf:?}");
    let s = phase.sample(&inc, T::lit(0.6), [T::lit(0.2), T::lit(0.9)]);
    assert!(s.pdf.is_finite() && s.pdf > T::zero() && s.weight.is_finite());
    true
}

/// A medium that does not scatter (`δε = 0`): `σ_s = 0`, `F = 0`, `dI/dV = 0`, and the sampler
/// still draws with a finite positive pdf; a dark packet (`S0 = 0`) scatters nothing but has
/// the phase matrix and `σ_s` of unpolarized light of its coherence.
#[test]
fn silent_medium_and_dark_packet() {
    let silent = RandomMedium::new(GaussianPsd::<f64, 3>::isotropic(0.0, 0.5).unwrap(), Dipole);
    let p = simple::<f64>(
        [1.0, 0.2, 0.0, 0.1],
        Matrix2::identity() * 4.0,
        Some(2.0),
        0.5,
    );
    let phase = PhaseFunction::new(&silent, Kernel::<Full, Partial>::default());
    let inc = phase.prepare(&p).unwrap();
    assert_eq!(inc.scattering_coefficient(), 0.0);
    let r = Vector3::new(0.3, 0.1, 0.9);
    assert_eq!(
        phase.eval(&inc, r).unwrap().phase.matrix(),
        nalgebra::Matrix4::zeros()
    );
    assert_eq!(
        phase.differential_scattering(&inc, r).unwrap().light.s0(),
        0.0
    );
    let s = phase.sample(&inc, 0.5, [0.5, 0.5]);
    assert!(s.pdf.is_finite() && s.pdf > 0.0);

    let m = gaussian::<f64>(0.5);
    let phase = PhaseFunction::new(&m, Kernel::<Full, Partial>::default());
    let dark = simple::<f64>(
        [0.0, 0.0, 0.0, 0.0],
        Matrix2::identity() * 4.0,
        Some(2.0),
        0.5,
    );
    let lit = simple::<f64>(
        [1.0, 0.0, 0.0, 0.0],
        Matrix2::identity() * 4.0,
        Some(2.0),
        0.5,
    );
    let (a, b) = (phase.prepare(&dark).unwrap(), phase.prepare(&lit).unwrap());
    assert_close(
        "σ_s",
        a.scattering_coefficient(),
        b.scattering_coefficient(),
        Tol::new(0.0, 1e-14),
    );
    assert_eq!(
        phase.differential_scattering(&a, r).unwrap().light.s0(),
        0.0
    );
    let (fa, fb) = (
        phase.eval(&a, r).unwrap().phase.matrix(),
        phase.eval(&b, r).unwrap().phase.matrix(),
    );
    assert!((fa - fb).amax() <= 1e-14 * fb.amax());
}
