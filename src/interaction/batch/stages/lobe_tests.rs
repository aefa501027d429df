//! The stages of the partially coherent lobe batch (`channels`, `specular`) against their
//! scalar twins at every back-end.
//!
//! Every test runs in `f64` and `f32`, at every back-end of [`every_width`], on the fixture's
//! scenes ([`scenes`]: normal, oblique and grazing incidence on a dielectric and two absorbing
//! substrates, exits around the specular direction and near the normal) with packets of two
//! coherence shapes (isotropic, `Θ_x = 25 I`, `Θ_y = 42.25 I`, and an anisotropic pair, see
//! [`cases`]), so that the `Full` level mixes three channels ([`LobePrep::three`]). Each bound
//! is stated on its check with its reasoning, in units of `ε` (the type's machine epsilon); the
//! worst error relative to each bound is printed (`cargo test --lib lobe_tests --
//! --nocapture`). Every test counts the lanes it checked and asserts the count, so none is
//! vacuous.
//!
//! `ulp(x) ≤ ε |x|` for a normal `x` and `ε · MIN_POSITIVE` for a subnormal one, so a value
//! within `n` ulp is within `n ε max(|x|, MIN_POSITIVE)`.

use core::cell::Cell;

use nalgebra::{Matrix2, Matrix4, Vector2, Vector4};
use num_complex::Complex;
use pulp::Simd;

use super::channels::{
    channel_mix, halves, ln_small, log_gaussian, mat_vec, mixture_log, onto_cone, scaled,
};
use super::fixture::{PerWidth, chunks, every_width, lanes_of, load, same, scenes};
use super::specular::fresnel_stokes;
use crate::interaction::batch::prep::{LobePrep, LogGaussian};
use crate::interaction::coherence::{CoherenceModel, CoherenceWeights};
use crate::interaction::pbsdf::{FresnelReflection, Pbsdf};
use crate::interaction::{Full, Geometry, Kernel, Partial, PreparedPacket};
use crate::numerics::principal_sqrt;
use crate::packet::{CoherenceShape, WavePacket};
use crate::psd::{ClosedForm, GaussianMixturePsd, GaussianPsd, Psd};
use crate::real::Real;
use crate::stokes::Stokes;

/// One fixture scene with a two-shape packet (its Stokes vector times `brightness`), the
/// scalar kernel's prepared packet and the lane constants built from it.
struct Case<F: Real> {
    prepared: PreparedPacket<F, Full, Partial>,
    prep: LobePrep<F>,
    psd: GaussianPsd<F, 2>,
    /// The Fresnel index `η` (`√ε` of the scene's Rayleigh–Rice permittivity).
    eta: Complex<F>,
    /// The scene's Rayleigh–Rice permittivity, its packet and surface.
    epsilon: Complex<F>,
    packet: WavePacket<F>,
    surface: crate::frame::Frame<F>,
    geometries: Vec<Geometry<F>>,
}

/// The [`Case`]s of every fixture scene, the packet's `S0` scaled by `brightness`: with the
/// isotropic shapes `Θ_x = 25 I`, `Θ_y = 42.25 I` (whose sections are diagonal in the surface
/// frame, `ℓ₁₀ = 0`), and with two anisotropic, rotated ones (`ℓ₁₀ ≠ 0` in every Cholesky
/// factor).
fn cases<F: Real>(brightness: f64) -> Vec<Case<F>> {
    let shape = |m: [f64; 3]| {
        CoherenceShape::new(Matrix2::new(m[0], m[1], m[1], m[2]).map(F::lit)).unwrap()
    };
    let shapes = [
        (shape([25.0, 0.0, 25.0]), shape([42.25, 0.0, 42.25])),
        (shape([25.0, 8.0, 30.0]), shape([42.25, -5.0, 36.0])),
    ];
    let mut out = Vec::new();
    for sc in scenes::<F>() {
        for (shape_x, shape_y) in shapes {
            let p = &sc.packet;
            let st = p.stokes().0 * F::lit(brightness);
            let packet = WavePacket::new(
                Stokes::new(st[0], st[1], st[2], st[3]).unwrap(),
                shape_x,
                shape_y,
                *p.frame(),
                p.wavelength(),
            )
            .unwrap();
            let prepared = Kernel::<Full, Partial>::default()
                .prepare(&packet, &sc.surface)
                .unwrap();
            let epsilon = sc.scatter.permittivity();
            let eta = principal_sqrt(epsilon);
            let prep = LobePrep::new(
                &prepared,
                core::slice::from_ref(&sc.psd),
                sc.psd.variance(),
                (eta, epsilon),
                &packet,
                (&sc.surface, false),
                true,
            )
            .expect("the lane constants of a fixture scene");
            assert!(
                prep.three,
                "two shapes at the Full level mix three channels"
            );
            assert!(prepared.sections.iter().all(Option::is_some));
            let geometries = sc
                .exits
                .iter()
                .map(|&e| Geometry::for_packet(&packet, &sc.surface, e).unwrap())
                .collect();
            out.push(Case {
                prepared,
                prep,
                psd: sc.psd,
                eta,
                epsilon,
                packet,
                surface: sc.surface,
                geometries,
            });
        }
    }
    out
}

/// The largest error seen relative to its bound (1 = at the bound), and as the coefficient
/// `(err − abs part) / (ε · scale)` of bounds of the form `k ε · scale (+ an absolute part)`,
/// over every back-end.
#[derive(Default)]
struct Worst {
    of_bound: Cell<f64>,
    coefficient: Cell<f64>,
}

impl Worst {
    /// Asserts `err ≤ k ε scale + abs` and records it.
    fn check<F: Real>(
        &self,
        err: f64,
        k: f64,
        scale: f64,
        abs: f64,
        what: impl FnOnce() -> String,
    ) {
        let eps = F::EPSILON.to_f64();
        let bound = k * eps * scale + abs;
        assert!(err <= bound, "{}: {err:e} > {bound:e}", what());
        if bound > 0.0 {
            self.of_bound.set(self.of_bound.get().max(err / bound));
        }
        if scale > 0.0 {
            let k = (err - abs).max(0.0) / scale / eps;
            self.coefficient.set(self.coefficient.get().max(k));
        }
    }

    fn report(&self, test: &str) {
        println!(
            "{test}: worst error {:.3} of the bound, coefficient {:.3}",
            self.of_bound.get(),
            self.coefficient.get()
        );
    }
}

/// `|a − b|`, 0 when both are the same infinity (or the same bits).
fn diff<F: Real>(a: F, b: F) -> f64 {
    if same(a, b) || a == b {
        0.0
    } else {
        (a.to_f64() - b.to_f64()).abs()
    }
}

/// The values of `f` on `0..len` as one vector.
fn lanes<S: Simd, F: Real>(s: S, len: usize, f: impl Fn(usize) -> F) -> F::V<S> {
    let v: Vec<F> = (0..len).map(f).collect();
    load::<S, F>(s, &v)
}

/// `ln 2π`.
const LN_2PI: f64 = 1.8378770664093453;

// ---------------------------------------------------------------------------------------------
// log_gaussian

/// `log_gaussian` against `Partial::log_specular_weight` (`LobePrep::spec[α]`) and
/// `Partial::log_scatter_weight` (`LobePrep::scat[α]`) of the section `Ξ_α`, for the three
/// channels, at `h_t` of every exit.
///
/// Bound: `5 ε (P + Y² + Z²)`. The lanes add the constant `c` once, built at `h = 0` from the
/// same parts the scalar adds at `h`: `ln 2π`, `ln(σ²|Λ|^{1/2})`, `½ ln|Λ⁻¹|`, `½ ln|Λ⁻¹ + Ξ|`
/// (scattered) or `ln 2π`, `½ ln|Ξ|` (specular), of absolute sum `P`. At most three roundings
/// on the scalar side, two in `c` and the final fused multiply–add on the lane side, each of
/// `ε/2` of a partial sum no larger than `P + ½|L⁻¹h|²`: `3 ε (P + ½ m)`. The Mahalanobis
/// term (derived for the earlier form with both reciprocals and a fused `h₁ − ℓ₁₀ y₀`, and kept:
/// the present form, `y₀` and `h₁ − ℓ₁₀ y₀` bit for bit the scalar's, only lowers the error):
/// with `Y = |y₀|` and `Z = (|ℓ₁₀ y₀| + |h₁ − ℓ₁₀ y₀|)/ℓ₁₁ ≥ |y₁|` (the cancellation in
/// `h₁ − ℓ₁₀ y₀` makes the error of `y₁` relative to `Z`, not to `|y₁|`), `|Δy₀| ≤ 1.5 ε Y`,
/// `|Δy₁| ≤ 2 ε Z`, and `|Δm| ≤ 2 Y |Δy₀| + 2 Z |Δy₁| + 1.5 ε m ≤ 5.5 ε (Y² + Z²)`, of which
/// half enters. With `m ≤ Y² + Z²`: `3 ε P + 4.25 ε (Y² + Z²) ≤ 5 ε (P + Y² + Z²)`.
struct LogGaussians<F: Real>(Vec<Case<F>>, Worst);

/// One weight of [`LogGaussians`]: its name, its lane constants, the absolute sum `P` of the
/// parts of its constant, and its scalar twin at `h_t`.
type WeightCheck<'a, F> = (
    &'static str,
    &'a LogGaussian<F>,
    f64,
    &'a dyn Fn(&Vector2<F>) -> F,
);

impl<F: Real> PerWidth for LogGaussians<F> {
    fn run<S: Simd>(&self, s: S, what: &str) {
        let mut checked = 0;
        for (ci, c) in self.0.iter().enumerate() {
            let lsd = c.psd.spectral_shape().log_det().to_f64();
            let amp = c.psd.log_value(&Vector2::zeros()).to_f64();
            chunks::<S, F>(c.geometries.len(), |i, len| {
                let h: Vec<Vector2<F>> =
                    c.geometries[i..i + len].iter().map(Geometry::h_t).collect();
                let h0 = lanes::<S, F>(s, len, |j| h[j].x);
                let h1 = lanes::<S, F>(s, len, |j| h[j].y);
                for ch in 0..3 {
                    let xi = c.prepared.sections[ch].as_ref();
                    let xi_det = xi.unwrap().log_det().to_f64();
                    let sum = crate::gaussian::cholesky_of_sum(c.psd.spectral_shape(), xi.unwrap())
                        .unwrap();
                    let sum_det = 2.0 * (sum[(0, 0)].to_f64().ln() + sum[(1, 1)].to_f64().ln());
                    let checks: [WeightCheck<'_, F>; 2] = [
                        (
                            "spec",
                            &c.prep.spec[ch],
                            LN_2PI + 0.5 * xi_det.abs(),
                            &|h| Partial::<ClosedForm>::default().log_specular_weight(xi, h),
                        ),
                        (
                            "scat",
                            &c.prep.scat[ch][0],
                            LN_2PI + amp.abs() + 0.5 * (lsd.abs() + sum_det.abs()),
                            &|h| {
                                CoherenceWeights::<F, GaussianPsd<F, 2>>::log_scatter_weight(
                                    &Partial::<ClosedForm>::default(),
                                    &c.psd,
                                    xi,
                                    h,
                                )
                            },
                        ),
                    ];
                    for (kind, g, parts, scalar) in checks {
                        let got = lanes_of::<S, F>(s, log_gaussian::<S, F>(s, g, h0, h1));
                        for j in 0..len {
                            let want = scalar(&h[j]);
                            let (hx, hy) = (h[j].x.to_f64(), h[j].y.to_f64());
                            let y0 = hx * g.l00.to_f64().recip();
                            let l10y0 = g.l10.to_f64() * y0;
                            let z = (l10y0.abs() + (hy - l10y0).abs()) * g.l11.to_f64().recip();
                            let err = diff(got[j], want);
                            self.1
                                .check::<F>(err, 5.0, parts + y0 * y0 + z * z, 0.0, || {
                                    let (e, got) = (i + j, got[j]);
                                    format!("{what}: case {ci}, exit {e}, {kind}[{ch}]: {got:?}")
                                });
                            checked += 1;
                        }
                    }
                }
            });
        }
        assert!(checked > 1000, "{what}: {checked} lanes");
    }
}

#[test]
fn log_gaussian_matches_the_scalar_channel_weights() {
    let t = LogGaussians(cases::<f64>(1.0), Worst::default());
    every_width(&t);
    t.1.report("log_gaussian f64");
    let t = LogGaussians(cases::<f32>(1.0), Worst::default());
    every_width(&t);
    t.1.report("log_gaussian f32");
}

// ---------------------------------------------------------------------------------------------
// ln_small and mixture_log (Gaussian-mixture PSDs)

/// `ln_small` against `f64::ln` at 4001 points of `[1, 8]` (ends included), rounded to `F`.
///
/// Bound: `4 ε` absolute. After the two Halley steps the iteration error is below `1e-20`
/// (see `ln_small`); what remains is the last step's rounding: `eʸ` within 2 ulp, so
/// `f − eʸ` and the correction `2 (f − eʸ)/(f + eʸ)` carry `≈ 2 ε` of `y`, plus the final sum's
/// `½ ulp(y)` and the rounding of `f` itself (`½ ε` relative, `½ ε` in `ln f`): `3 ε`, with
/// one `ε` of margin for the correction's own three roundings (each `ε/2` of a term below
/// `1e-7`).
struct LnSmall(Worst);

impl PerWidth for LnSmall {
    fn run<S: Simd>(&self, s: S, what: &str) {
        fn per<S: Simd, F: Real>(s: S, w: &Worst, what: &str) -> usize {
            let xs: Vec<F> = (0..=4000)
                .map(|i| F::lit(1.0 + 7.0 * f64::from(i) / 4000.0))
                .collect();
            let mut checked = 0;
            chunks::<S, F>(xs.len(), |i, len| {
                let got =
                    lanes_of::<S, F>(s, ln_small::<S, F>(s, load::<S, F>(s, &xs[i..i + len])));
                for j in 0..len {
                    let x = xs[i + j].to_f64();
                    let err = (got[j].to_f64() - x.ln()).abs();
                    w.check::<F>(err, 4.0, 1.0, 0.0, || format!("{what}: ln {x}"));
                    checked += 1;
                }
            });
            checked
        }
        let n = per::<S, f64>(s, &self.0, what) + per::<S, f32>(s, &self.0, what);
        assert_eq!(n, 8002, "{what}: lanes checked");
    }
}

#[test]
fn ln_small_matches_ln_on_one_to_eight() {
    let t = LnSmall(Worst::default());
    every_width(&t);
    t.0.report("ln_small f64 and f32");
}

/// Three Gaussian components: the fixture's PSD, a narrower-in-space (wider in frequency)
/// and a longer-correlated one.
fn mixture_of<F: Real>(psd: &GaussianPsd<F, 2>) -> Vec<GaussianPsd<F, 2>> {
    vec![
        *psd,
        GaussianPsd::<F, 2>::isotropic(F::lit(0.012), F::lit(0.6)).unwrap(),
        GaussianPsd::<F, 2>::isotropic(F::lit(0.006), F::lit(4.0)).unwrap(),
    ]
}

/// `mixture_log` (the components' `LobePrep::scat[α][j]` of a three-component mixture)
/// against `Partial::log_scatter_weight` of the [`GaussianMixturePsd`], the three channels of
/// every case, at `h_t` of every exit.
///
/// Bound: `6 ε B + 9 ε`, `B = maxⱼ (Pⱼ + Yⱼ² + Zⱼ²)` of the components (as in
/// [`LogGaussians`]). Each component's logarithm is within `5 ε (Pⱼ + Yⱼ² + Zⱼ²)` of the
/// scalar's on both sides; a weighted mean of those errors enters the logarithm of the sum. The
/// lanes then add: `lⱼ − m` (`½ ε` of it, at most `½ ε · |lⱼ − m| e^{−|lⱼ−m|} ≤ ε/5` after
/// weighting), `exp` (2 ulp: `2 ε`), the sum of three (`1 ε`), `ln_small` (`4 ε`) and
/// `m + ln f` (`½ ulp` of a result `≤ B`: `½ ε B`); the scalar: its sum and its one
/// logarithm (`1.5 ε`). `5 ε B + ½ ε B + 8.7 ε`.
struct MixtureLogs<F: Real>(Vec<Case<F>>, Worst);

impl<F: Real> PerWidth for MixtureLogs<F> {
    fn run<S: Simd>(&self, s: S, what: &str) {
        let mut checked = 0;
        for (ci, c) in self.0.iter().enumerate() {
            let comps = mixture_of(&c.psd);
            let mix = GaussianMixturePsd::new(comps.clone()).unwrap();
            let variance = mix.variance();
            let prep = LobePrep::new(
                &c.prepared,
                &comps,
                variance,
                (c.eta, c.epsilon),
                &c.packet,
                (&c.surface, false),
                true,
            )
            .expect("the lane constants of a mixture");
            assert_eq!(prep.components, 3);
            chunks::<S, F>(c.geometries.len(), |i, len| {
                let h: Vec<Vector2<F>> =
                    c.geometries[i..i + len].iter().map(Geometry::h_t).collect();
                let h0 = lanes::<S, F>(s, len, |j| h[j].x);
                let h1 = lanes::<S, F>(s, len, |j| h[j].y);
                for ch in 0..3 {
                    let xi = c.prepared.sections[ch].as_ref();
                    let got =
                        lanes_of::<S, F>(s, mixture_log::<S, F>(s, &prep.scat[ch][..3], h0, h1));
                    for j in 0..len {
                        let want =
                            CoherenceWeights::<F, GaussianMixturePsd<F, 2>>::log_scatter_weight(
                                &Partial::<ClosedForm>::default(),
                                &mix,
                                xi,
                                &h[j],
                            );
                        let b = comps
                            .iter()
                            .zip(&prep.scat[ch])
                            .map(|(comp, g)| {
                                let lsd = comp.spectral_shape().log_det().to_f64();
                                let amp = comp.log_value(&Vector2::zeros()).to_f64();
                                let sum = crate::gaussian::cholesky_of_sum(
                                    comp.spectral_shape(),
                                    xi.unwrap(),
                                )
                                .unwrap();
                                let sum_det =
                                    2.0 * (sum[(0, 0)].to_f64().ln() + sum[(1, 1)].to_f64().ln());
                                let (hx, hy) = (h[j].x.to_f64(), h[j].y.to_f64());
                                let y0 = hx * g.l00.to_f64().recip();
                                let l10y0 = g.l10.to_f64() * y0;
                                let z = (l10y0.abs() + (hy - l10y0).abs()) * g.l11.to_f64().recip();
                                LN_2PI
                                    + amp.abs()
                                    + 0.5 * (lsd.abs() + sum_det.abs())
                                    + y0 * y0
                                    + z * z
                            })
                            .fold(0.0, f64::max);
                        let err = diff(got[j], want);
                        let eps = F::EPSILON.to_f64();
                        self.1.check::<F>(err, 6.0, b, 9.0 * eps, || {
                            format!(
                                "{what}: case {ci}, exit {}, channel {ch}: {:?} vs {want:?}",
                                i + j,
                                got[j]
                            )
                        });
                        checked += 1;
                    }
                }
            });
        }
        assert!(checked > 1000, "{what}: {checked} lanes");
    }
}

#[test]
fn mixture_log_matches_the_scalar_mixture_weights() {
    let t = MixtureLogs(cases::<f64>(1.0), Worst::default());
    every_width(&t);
    t.1.report("mixture_log f64");
    let t = MixtureLogs(cases::<f32>(1.0), Worst::default());
    every_width(&t);
    t.1.report("mixture_log f32");
}

// ---------------------------------------------------------------------------------------------
// channel_mix (with mat_vec)

/// The channel weights fed to both mixes: the scalar `(ln K_x, ln K_y, ln K_½)` of both parts
/// at every exit, and each shifted so that one ratio `r_α` is small (`e^{−30}`), subnormal,
/// or 0 (beyond the underflow threshold), with `ln K_½` above the Cauchy–Schwarz cap (the
/// `min`s bind), with `ln K_½ = −∞` (`r_½ = 0`), and all three `−∞` (`m = −∞`).
fn mix_inputs<F: Real>(c: &Case<F>) -> Vec<[F; 3]> {
    let sub = F::MIN_POSITIVE.to_f64().ln() - 8.0;
    let gone = F::MIN_POSITIVE.to_f64().ln() * 1.2;
    let ninf = f64::NEG_INFINITY;
    let shifts = [
        [0.0, 0.0, 0.0],
        [0.0, -30.0, 0.0],
        [-30.0, 0.0, 0.0],
        [0.0, sub, 0.0],
        [gone, 0.0, 0.0],
        [0.0, 0.0, 5.0],
        [0.0, 0.0, ninf],
        [ninf, ninf, ninf],
    ];
    let partial = Partial::<ClosedForm>::default();
    let mut out = Vec::new();
    for g in &c.geometries {
        let h = g.h_t();
        let xi = |ch: usize| c.prepared.sections[ch].as_ref();
        let spec: [F; 3] = core::array::from_fn(|ch| partial.log_specular_weight(xi(ch), &h));
        let scat: [F; 3] = core::array::from_fn(|ch| {
            CoherenceWeights::<F, GaussianPsd<F, 2>>::log_scatter_weight(
                &partial,
                &c.psd,
                xi(ch),
                &h,
            )
        });
        for l in [spec, scat] {
            for d in shifts {
                out.push(core::array::from_fn(|k| l[k] + F::lit(d[k])));
            }
        }
    }
    out
}

/// `channel_mix` against `PreparedPacket::channel_mix`, fed the same weights ([`mix_inputs`]):
/// `m` bit for bit, and `T v̂` within `8 ε Σⱼ |T_ij| wⱼ + 32 ε MIN_POSITIVE`, where
/// `w = (r_x + r_y, r_x + r_y, 2 r_½ |cos arg μ|, 2 r_½ |sin arg μ|)` bounds `|v̂|`.
///
/// Both sides form `a_α`, `m` and `a_α − m` with the same operations (`min`, `max` exact), so
/// these agree bit for bit; each `r_α = e^{a_α − m}` is within 2 ulp (`vexp`) and 1 ulp (the
/// scalar `exp`) of the exact value: `|Δr| ≤ 3 ε max(r, MIN_POSITIVE)`. `v̂` adds one rounding
/// on each side (`½ ε` each): `|Δv̂ⱼ| ≤ 4 ε wⱼ + 6 ε MIN_POSITIVE`. `T v̂`: four fused roundings
/// (`mat_vec`) against nalgebra's four products and three sums, each `ε/2` of at most
/// `Σⱼ |T_ij| wⱼ`: `3.5 ε` more; `|T_ij| ≤ 1` (a rotation) bounds the absolute part by
/// `4 · 6 ε MIN_POSITIVE + 4 ε MIN_POSITIVE`. `m = −∞` (all weights −∞) leaves the lanes'
/// vector unspecified: only `m` is compared there.
struct Mixes<F: Real>(Vec<Case<F>>, Worst);

impl<F: Real> PerWidth for Mixes<F> {
    fn run<S: Simd>(&self, s: S, what: &str) {
        let tiny = 32.0 * F::EPSILON.to_f64() * F::MIN_POSITIVE.to_f64();
        let (mut checked, mut dark) = (0, 0);
        for (ci, c) in self.0.iter().enumerate() {
            let p = &c.prepared;
            let inputs = mix_inputs(c);
            chunks::<S, F>(inputs.len(), |i, len| {
                let l = &inputs[i..i + len];
                let (v, m) = channel_mix::<S, F>(
                    s,
                    &c.prep,
                    lanes::<S, F>(s, len, |j| l[j][0]),
                    lanes::<S, F>(s, len, |j| l[j][1]),
                    lanes::<S, F>(s, len, |j| l[j][2]),
                );
                let (v, m) = (v.map(|x| lanes_of::<S, F>(s, x)), lanes_of::<S, F>(s, m));
                for j in 0..len {
                    let [lx, ly, lh] = l[j];
                    let (want, wm) = p.channel_mix(lx, ly, lh);
                    let at = || format!("{what}: case {ci}, input {}", i + j);
                    assert!(same(m[j], wm), "{}: m {:?} vs {wm:?}", at(), m[j]);
                    if wm.to_f64() == f64::NEG_INFINITY {
                        dark += 1;
                        continue;
                    }
                    // The ratios of the scalar formula (for the bound only).
                    let half = F::lit(0.5);
                    let (ax, ay) = (lx + p.ln_sx, ly + p.ln_sy);
                    let ah =
                        (lh.min((lx + ly) * half - p.ln_mu_max) + p.ln_c).min((ax + ay) * half);
                    let r = |a: F| (a - wm).to_f64().exp();
                    let (rx, ry, rh) = (r(ax), r(ay), r(ah));
                    let w = [
                        rx + ry,
                        rx + ry,
                        2.0 * rh * p.phase.0.to_f64().abs(),
                        2.0 * rh * p.phase.1.to_f64().abs(),
                    ];
                    for k in 0..4 {
                        let size: f64 = (0..4).map(|q| p.t[(k, q)].to_f64().abs() * w[q]).sum();
                        self.1
                            .check::<F>(diff(v[k][j], want[k]), 8.0, size, tiny, || {
                                format!("{}, (T v̂)_{k}: {:?} vs {:?}", at(), v[k][j], want[k])
                            });
                    }
                    checked += 1;
                }
            });
        }
        assert!(
            checked > 1000 && dark > 100,
            "{what}: {checked} lanes, {dark} dark"
        );
    }
}

#[test]
fn channel_mix_matches_prepared_packet_channel_mix() {
    let t = Mixes(cases::<f64>(1.0), Worst::default());
    every_width(&t);
    t.1.report("channel_mix f64");
    let t = Mixes(cases::<f32>(1.0), Worst::default());
    every_width(&t);
    t.1.report("channel_mix f32");
}

/// `mat_vec` against nalgebra's `Matrix4 * Vector4` within `4 ε Σⱼ |M_ij vⱼ|` (four fused
/// roundings against four products and three sums, each `ε/2` of at most `Σⱼ |M_ij vⱼ|`),
/// for the rotations `T` and the Fresnel matrices of every case and a matrix of mixed signs and
/// magnitudes; and `halves` bit for bit `((v₀ + v₁)/2, (v₀ − v₁)/2, v₂, v₃)`.
struct MatVec<F: Real>(Vec<Case<F>>, Worst);

impl<F: Real> PerWidth for MatVec<F> {
    fn run<S: Simd>(&self, s: S, what: &str) {
        #[rustfmt::skip]
        let mixed = Matrix4::new(
            1.0, -0.3, 2.5e-3, 7.0,
            -1e3, 0.25, 0.0, -0.125,
            3.3, 1e-4, -2.0, 0.6,
            0.0, -5.0, 4.0, 1e2,
        )
        .map(F::lit);
        let mut matrices = vec![mixed];
        for c in &self.0 {
            matrices.push(c.prep.t);
            matrices.push(c.prep.fresnel);
        }
        let vectors: Vec<Vector4<F>> = (0..37)
            .map(|i| {
                let x = i as f64;
                Vector4::new(
                    1.0 + x,
                    (0.3 * x).sin(),
                    -(0.7 * x).cos() * 1e-2,
                    0.5 - x * x,
                )
                .map(F::lit)
            })
            .collect();
        let mut checked = 0;
        for (mi, m) in matrices.iter().enumerate() {
            chunks::<S, F>(vectors.len(), |i, len| {
                let v = &vectors[i..i + len];
                let lv: [F::V<S>; 4] = core::array::from_fn(|k| lanes::<S, F>(s, len, |j| v[j][k]));
                let got = mat_vec::<S, F>(s, m, lv).map(|x| lanes_of::<S, F>(s, x));
                let hv = halves::<S, F>(s, lv).map(|x| lanes_of::<S, F>(s, x));
                for j in 0..len {
                    let want = m * v[j];
                    for k in 0..4 {
                        let size: f64 = (0..4).map(|q| (m[(k, q)] * v[j][q]).to_f64().abs()).sum();
                        self.1
                            .check::<F>(diff(got[k][j], want[k]), 4.0, size, 0.0, || {
                                format!("{what}: matrix {mi}, vector {}, row {k}", i + j)
                            });
                    }
                    let half = F::lit(0.5);
                    let h = [
                        (v[j][0] + v[j][1]) * half,
                        (v[j][0] - v[j][1]) * half,
                        v[j][2],
                        v[j][3],
                    ];
                    for k in 0..4 {
                        assert!(same(hv[k][j], h[k]), "{what}: halves of vector {}", i + j);
                    }
                    checked += 1;
                }
            });
        }
        assert!(checked > 300, "{what}: {checked} lanes");
    }
}

#[test]
fn mat_vec_and_halves_match_nalgebra() {
    let t = MatVec(cases::<f64>(1.0), Worst::default());
    every_width(&t);
    t.1.report("mat_vec f64");
    let t = MatVec(cases::<f32>(1.0), Worst::default());
    every_width(&t);
    t.1.report("mat_vec f32");
}

// ---------------------------------------------------------------------------------------------
// onto_cone

/// The inputs of the cone tests: `u₀` of the magnitudes `sizes`, positive, 0 and negative, with
/// polarized parts along six directions of lengths `ρ u₀`, `ρ` from 0 through the cone
/// (`1 − 4ε`, 1, `1 + 4ε`, `1 + 10⁻⁶`) to `10³`; and the zero vector.
fn cone_inputs<F: Real>(sizes: &[f64]) -> Vec<Vector4<F>> {
    let eps = F::EPSILON.to_f64();
    let dirs: [[f64; 3]; 6] = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, -1.0],
        [0.3, -0.5, 0.6],
        [-0.8, 0.1, -0.59],
        [1.0, 1.0, 1.0],
    ];
    let mut out = vec![Vector4::zeros()];
    for &u0 in sizes {
        for sign in [1.0, 0.0, -1.0] {
            for d in dirs {
                let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                for rho in [
                    0.0,
                    0.5,
                    1.0 - 4.0 * eps,
                    1.0,
                    1.0 + 4.0 * eps,
                    1.0 + 1e-6,
                    2.0,
                    1e3,
                ] {
                    // The polarized part in F from the unit direction, so that ρ = 1 lies on
                    // the cone to the rounding of F.
                    let unit = d.map(|x| F::lit(x / n));
                    let r = F::lit(u0) * F::lit(rho);
                    out.push(Vector4::new(
                        F::lit(sign * u0),
                        unit[0] * r,
                        unit[1] * r,
                        unit[2] * r,
                    ));
                }
            }
        }
    }
    out
}

/// `onto_cone` against the scalar `onto_cone`: `u₀` bit for bit (the zero vector, bit for bit,
/// where `u₀ ≤ 0`), the polarized part within `6 ε |u_k|`, and the result in the cone,
/// `|u_pol|² ≤ u₀² (1 + 8ε)` (evaluated in f64, as `Σ (u_k/u₀)²`).
///
/// Where neither side scales, both return `u` itself. Where both scale, the lanes'
/// `u_k · (u₀/√|u_pol|²)` is within `2.25 ε` (the fused `|u_pol|²` `1.5 ε`, its root, the
/// quotient and the product `½ ε` each, the root halving the error of its argument), the
/// scalar `u_k / √Σ(u_j/u₀)²` within `3.25 ε` (the reciprocal, the quotients, the squares and
/// sums, the root, its reciprocal, the product): `5.5 ε`. Where only one side scales,
/// `|u_pol|/u₀` is within the few ε of the two tests from 1, and the scale factor within that
/// of 1. In the cone: unscaled lanes have `fl(|u_pol|²) ≤ fl(u₀²)`, `|u_pol|² ≤ u₀²(1 + 2ε)`;
/// scaled ones `|u_pol|² = u₀² (|u_pol|²/fl(|u_pol|²)) (1 + 3ε) ≤ u₀² (1 + 4.5 ε)`; the f64
/// check adds `2 ε` in f64 (two quotients, squares and sums).
struct Cone<F: Real>(Vec<Vector4<F>>, Worst);

impl<F: Real> PerWidth for Cone<F> {
    fn run<S: Simd>(&self, s: S, what: &str) {
        let eps = F::EPSILON.to_f64();
        let inputs = &self.0;
        let (mut checked, mut scaled_lanes) = (0, 0);
        chunks::<S, F>(inputs.len(), |i, len| {
            let u = &inputs[i..i + len];
            let lu: [F::V<S>; 4] = core::array::from_fn(|k| lanes::<S, F>(s, len, |j| u[j][k]));
            let got = onto_cone::<S, F>(s, lu).map(|x| lanes_of::<S, F>(s, x));
            for j in 0..len {
                let want = crate::interaction::polarization::onto_cone(u[j]);
                let at = || format!("{what}: input {} = {:?}", i + j, u[j]);
                assert!(
                    same(got[0][j], want[0]),
                    "{}: u0 {:?} vs {:?}",
                    at(),
                    got[0][j],
                    want[0]
                );
                if u[j][0] <= F::zero() {
                    for k in 0..4 {
                        assert!(same(got[k][j], F::zero()), "{}: not 0", at());
                        assert!(same(want[k], F::zero()), "{}: scalar not 0", at());
                    }
                } else {
                    for k in 1..4 {
                        let size = u[j][k].to_f64().abs();
                        self.1
                            .check::<F>(diff(got[k][j], want[k]), 6.0, size, 0.0, || {
                                format!("{}, u{k}: {:?} vs {:?}", at(), got[k][j], want[k])
                            });
                    }
                    if want != u[j] {
                        scaled_lanes += 1;
                    }
                }
                let o: [f64; 4] = core::array::from_fn(|k| got[k][j].to_f64());
                if o[0] > 0.0 {
                    let pol2: f64 = o[1..].iter().map(|x| (x / o[0]).powi(2)).sum();
                    assert!(pol2 <= 1.0 + 8.0 * eps, "{}: outside the cone", at());
                }
                checked += 1;
            }
        });
        assert!(
            checked > 500 && scaled_lanes > 90,
            "{what}: {checked} lanes, {scaled_lanes} scaled"
        );
    }
}

#[test]
fn onto_cone_matches_the_scalar_projection() {
    // Magnitudes from 10⁻¹⁵ to 10¹⁵, where every square is a normal number in both types.
    let sizes = [1.0, 3.7e-3, 2.5e4, 1e-15, 1e15];
    let t = Cone(cone_inputs::<f64>(&sizes), Worst::default());
    every_width(&t);
    t.1.report("onto_cone f64");
    let t = Cone(cone_inputs::<f32>(&sizes), Worst::default());
    every_width(&t);
    t.1.report("onto_cone f32");
}

/// [`Cone`] at normal magnitudes whose squares are not normal numbers (`|u| ≲ √MIN_POSITIVE`
/// or `≳ √MAX`: `10⁻³⁰⁰`, `10⁻¹⁶⁰`, `10¹⁶⁰`, `10³⁰⁰` in f64, `10⁻³⁰`, `10⁻²²`, `10²²`, `10³⁰` in
/// f32), where the scalar projection, which divides by `u₀` first, is unchanged. (A first
/// version of the lanes compared `u₀²` with `|u_pol|²` directly and failed here: both squares
/// 0 or ∞ left `|u_pol| = 1.5 u₀` outside the cone.)
#[test]
fn onto_cone_matches_the_scalar_projection_at_every_magnitude() {
    let t = Cone(
        cone_inputs::<f64>(&[1e-300, 1e-160, 1e160, 1e300]),
        Worst::default(),
    );
    every_width(&t);
    t.1.report("onto_cone f64, extreme magnitudes");
    let t = Cone(
        cone_inputs::<f32>(&[1e-30, 1e-22, 1e22, 1e30]),
        Worst::default(),
    );
    every_width(&t);
    t.1.report("onto_cone f32, extreme magnitudes");
}

/// Each lane's projection is its own: a vector of inputs of ordinary magnitude gives, bit for
/// bit, the same lanes when one of them is replaced by an input that needs the scalar's
/// operations (squares outside the normal range). A first version sent the whole vector down
/// those operations: 2 ulp apart, seen as a batch of 15 exits differing from one of 41 on an
/// AVX2 machine.
struct ConeNeighbours<F: Real>(Vec<Vector4<F>>, Vec<Vector4<F>>);

impl<F: Real> PerWidth for ConeNeighbours<F> {
    fn run<S: Simd>(&self, s: S, what: &str) {
        let (plain, extreme) = (&self.0, &self.1);
        let w = F::width::<S>();
        let mut compared = 0;
        for (e, x) in extreme.iter().enumerate() {
            chunks::<S, F>(plain.len(), |i, len| {
                let u = &plain[i..i + len];
                let lu: [F::V<S>; 4] = core::array::from_fn(|k| lanes::<S, F>(s, len, |j| u[j][k]));
                let alone = onto_cone::<S, F>(s, lu).map(|v| lanes_of::<S, F>(s, v));
                // The extreme input in lane e mod w, the others as before.
                let at = e % w;
                let mixed: [F::V<S>; 4] = core::array::from_fn(|k| {
                    lanes::<S, F>(s, len.max(at + 1), |j| {
                        if j == at { x[k] } else { u[j.min(len - 1)][k] }
                    })
                });
                let with = onto_cone::<S, F>(s, mixed).map(|v| lanes_of::<S, F>(s, v));
                for j in (0..len).filter(|&j| j != at) {
                    for k in 0..4 {
                        assert_eq!(
                            with[k][j].to_f64().to_bits(),
                            alone[k][j].to_f64().to_bits(),
                            "{what}: input {} S{k} changed beside {x:?}",
                            i + j
                        );
                        compared += 1;
                    }
                }
            });
        }
        assert!(w == 1 || compared > 0, "{what}: nothing compared");
    }
}

/// Eight of `inputs` with `u₀ > 0`, spread over them.
fn extremes<F: Real>(inputs: Vec<Vector4<F>>) -> Vec<Vector4<F>> {
    let pos: Vec<_> = inputs.into_iter().filter(|u| u[0] > F::zero()).collect();
    let step = (pos.len() / 8).max(1);
    pos.into_iter().step_by(step).take(8).collect()
}

#[test]
fn onto_cone_gives_each_lane_its_own_result() {
    let t = ConeNeighbours(
        cone_inputs::<f64>(&[1.0, 3.7e-3, 2.5e4]),
        extremes(cone_inputs::<f64>(&[1e-300, 1e300])),
    );
    every_width(&t);
    let t = ConeNeighbours(
        cone_inputs::<f32>(&[1.0, 3.7e-3, 2.5e4]),
        extremes(cone_inputs::<f32>(&[1e-30, 1e30])),
    );
    every_width(&t);
}

// ---------------------------------------------------------------------------------------------
// scaled

/// The exponents of the scale tests: across the range of the type (`−800 … 800` in f64,
/// `−110 … 90` in f32), ±∞, NaN, and within 3 ulp of the dark threshold (`ln` of the smallest
/// subnormal number) and of the edges of the normal range (`ln MIN_POSITIVE`, `ln MAX`).
fn scale_exponents<F: Real>() -> Vec<F> {
    let wide: &[f64] = if F::EPSILON.to_f64() < 1e-10 {
        &[
            -800.0, -760.0, -745.5, -744.5, -744.0, -730.0, -720.0, -709.0, -708.5, -708.0, -700.0,
            -300.0, -50.0, -1.0, 0.0, 1.0, 50.0, 300.0, 700.0, 709.0, 709.5, 709.8, 710.0, 720.0,
            800.0,
        ]
    } else {
        &[
            -110.0, -104.5, -103.5, -103.0, -95.0, -88.0, -87.5, -87.0, -50.0, -1.0, 0.0, 1.0,
            50.0, 88.0, 88.5, 88.8, 89.0, 90.0,
        ]
    };
    let mut out: Vec<F> = wide.iter().map(|&x| F::lit(x)).collect();
    // Values with every bit of the significand set, where `fl(fl(ln_e − ln S0) + ln S0)` is
    // not `ln_e` again.
    let (lo, hi) = (wide[0], wide[wide.len() - 1]);
    let steps = 97;
    out.extend(
        (0..=steps)
            .map(|i| F::lit(lo + (hi - lo) * (f64::from(i) + 0.123456789) / f64::from(steps))),
    );
    out.extend([f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -0.0].map(F::lit));
    let edges = [
        crate::interaction::coherence::ln_smallest_subnormal::<F>(),
        F::MIN_POSITIVE.to_f64().ln(),
        F::MAX.to_f64().ln(),
    ];
    for x in edges {
        let x = F::lit(x);
        for k in -3..=3 {
            out.push(x + x * F::EPSILON * F::lit(f64::from(k)));
        }
    }
    out
}

/// The vectors scaled: valid Stokes vectors of several degrees of polarization and sizes, one
/// with zero entries, and the zero vector.
fn scale_vectors<F: Real>() -> Vec<Vector4<F>> {
    [
        [1.0, 0.3, -0.5, 0.6],
        [2.5e-3, -1e-3, 0.0, 2e-3],
        [3.0, 3.0, 0.0, 0.0],
        [1e3, 0.0, 0.0, -999.0],
        [0.7, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
    ]
    .iter()
    .map(|v| Vector4::from(*v).map(F::lit))
    .collect()
}

/// `scaled` against `PreparedPacket::is_dark` and `PreparedPacket::scaled` of
/// `ln_e − ln S0` (the lanes' `ln_e` holds `ln S0`, the scalar adds it), for `S0 = 1`, `10¹⁰`,
/// `3.7·10⁻⁹` and `10^{±150}` (f64) or `10^{±13}` (f32), [`scale_vectors`] × [`scale_exponents`]:
///
/// - where the scalar part is dark, the lanes are exactly 0 and not redone;
/// - where it is lit, the lanes are dark only when `ln_e` lies below the threshold by less
///   than the rounding of `ln_e − ln S0` (`ε (|ln_e| + |ln S0|)`): rounding is monotonic, so
///   `ln_e ≥ ln_dark` gives `fl(ln_e − ln S0) ≥ fl(ln_dark − ln S0)`, but not conversely
///   (never with `S0 = 1`, where the subtraction is exact; seen at `S0 = 10¹⁵⁰`, where
///   `ln_dark − ln S0` lies in the next binade);
/// - lit lanes are redone exactly where `e^{ln_e}` (in f64, for the reference) is not a normal
///   number, except within `3 ε` of `MIN_POSITIVE` or `MAX` (`vexp` is within 2 ulp);
/// - the lanes not redone agree within `(4 + |ln_e| + |ln S0|) ε |u_k| e^{ln_e} + 2 ε
///   MIN_POSITIVE`: `vexp` within 2 ulp, the scalar `exp` within 1, their arguments
///   `ln_e` and `fl(fl(ln_e − ln S0) + ln S0)` within `ε (|ln_e| + |ln S0|)` (exact when
///   `S0 = 1`), a product `½ ε` on each side, a subnormal product `ε MIN_POSITIVE / 2`. Where the
///   scalar folds `|u|` into the exponent (its own `e` not normal, at the edges above), its
///   argument adds `ln u₀` and its quotient and rounding: `(8 + 2 |ln_e| + 2 |ln S0| +
///   2 |ln u₀|) ε`. An infinite entry on either side must be the same infinity or face a
///   value within the bound of overflow.
///
/// Two cases where the scalar twin itself is off, both where its own `e` overflows (at
/// `ln_e ≈ ln MAX` with `S0 = 10⁻¹⁵⁰`, the rounding of its argument carrying it past
/// `ln MAX`) while the lanes' `e` is normal, are checked against the exact value instead and
/// counted ([`ScaleCounts`]): the folded exponent `ln_e + ln S0 + ln u₀` overflows and with it
/// every nonzero entry, those smaller than `u₀` (finite in exact arithmetic) too; and for
/// `u₀ ≤ 0` the scalar returns `u · ∞`, NaN for the zero entries (the lanes: exactly 0).
struct Scales<F: Real>(Vec<Case<F>>, Worst, ScaleCounts);

/// What the scale tests met, over every back-end.
#[derive(Default, Debug)]
struct ScaleCounts {
    /// Lanes dark, the scalar lit, by the rounding of `ln_e − ln S0` only.
    rounding: Cell<usize>,
    /// Lit lanes within `3 ε` of the edges of the normal range (the redo test not asserted).
    edge: Cell<usize>,
    /// Lanes compared where the scalar folded `|u|` into the exponent.
    folded: Cell<usize>,
    /// Entries where the scalar's folded exponent overflowed (compared with the exact value).
    early: Cell<usize>,
    /// Entries where the scalar returned `0 · ∞ = NaN` (the lanes must be 0).
    nan: Cell<usize>,
    /// Lit lanes whose `S0` is below `MIN_POSITIVE/2` (written as 0).
    negligible: Cell<usize>,
}

impl<F: Real> PerWidth for Scales<F> {
    fn run<S: Simd>(&self, s: S, what: &str) {
        let eps = F::EPSILON.to_f64();
        let (min, max) = (F::MIN_POSITIVE.to_f64(), F::MAX.to_f64());
        let mut pairs = Vec::new();
        for u in scale_vectors::<F>() {
            for e in scale_exponents::<F>() {
                pairs.push((u, e));
            }
        }
        let (mut dark, mut lit, mut redone, mut compared) = (0, 0, 0, 0);
        for (ci, c) in self.0.iter().enumerate() {
            let p = &c.prepared;
            let ln_s0 = p.ln_s0;
            chunks::<S, F>(pairs.len(), |i, len| {
                let pr = &pairs[i..i + len];
                let lu: [F::V<S>; 4] =
                    core::array::from_fn(|k| lanes::<S, F>(s, len, |j| pr[j].0[k]));
                let le = lanes::<S, F>(s, len, |j| pr[j].1);
                let (got, redo) = scaled::<S, F>(s, &c.prep, lu, le);
                let got = got.map(|x| lanes_of::<S, F>(s, x));
                let one = F::vsplat(s, F::one());
                let redo = lanes_of::<S, F>(s, F::vselect(s, redo, one, F::vsplat(s, F::zero())));
                for j in 0..len {
                    let (u, ln_e) = pr[j];
                    let redo = redo[j] != F::zero();
                    let at = || format!("{what}: case {ci}, u = {u:?}, ln_e = {ln_e:?}");
                    let ln_es = ln_e - ln_s0;
                    let lane_lit = c.prep.ln_dark <= ln_e;
                    if p.is_dark(ln_es) || !lane_lit {
                        if !p.is_dark(ln_es) {
                            // Lit for the scalar, dark for the lanes: by the rounding only.
                            let gap = (c.prep.ln_dark - ln_e).to_f64();
                            let tol = eps * (ln_e.to_f64().abs() + ln_s0.to_f64().abs());
                            assert!(gap > 0.0 && gap <= tol, "{}: dark lanes, lit scalar", at());
                            self.2.rounding.set(self.2.rounding.get() + 1);
                        }
                        assert!(!lane_lit, "{}: lit lanes, dark scalar", at());
                        let zero = got.iter().all(|x| same(x[j], F::zero()));
                        assert!(zero, "{}: dark entry not 0", at());
                        assert!(!redo, "{}: a dark lane redone", at());
                        dark += 1;
                        continue;
                    }
                    lit += 1;
                    // Negligible (S0 below MIN_POSITIVE/2, in logarithms: e may be subnormal):
                    // written as 0, not redone; within a few ε of the threshold either way.
                    let u0 = u[0].to_f64();
                    let ln_s0_ref = if u0 > 0.0 {
                        u0.ln() + ln_e.to_f64()
                    } else {
                        f64::NEG_INFINITY
                    };
                    let ln_half = (0.5 * min).ln();
                    let near_half = (ln_s0_ref - ln_half).abs()
                        <= 4.0 * eps * (64.0 + ln_e.to_f64().abs() + u0.ln().abs());
                    if near_half {
                        self.2.edge.set(self.2.edge.get() + 1);
                        continue;
                    }
                    if ln_s0_ref < ln_half {
                        let zero = got.iter().all(|x| same(x[j], F::zero()));
                        assert!(
                            zero && !redo,
                            "{}: a negligible part not 0, or redone",
                            at()
                        );
                        self.2.negligible.set(self.2.negligible.get() + 1);
                        continue;
                    }
                    let e_ref = ln_e.to_f64().exp();
                    let normal = (min..=max).contains(&e_ref);
                    // A positive S0 of the result below the smallest normal number is redone
                    // too (the scalar moves a subnormal vector back into the cone).
                    let s0_ref = u[0].to_f64() * e_ref;
                    let tiny = s0_ref > 0.0 && s0_ref < min;
                    let edge = (e_ref - min).abs() <= 3.0 * eps * min
                        || (e_ref - max).abs() <= 3.0 * eps * max
                        || (s0_ref - min).abs() <= 3.0 * eps * min;
                    if edge {
                        self.2.edge.set(self.2.edge.get() + 1);
                    } else {
                        assert_eq!(redo, !normal || tiny, "{}: redo", at());
                    }
                    if redo {
                        redone += 1;
                        continue;
                    }
                    let want = p.scaled(u, ln_es);
                    let e_s = (ln_es + ln_s0).exp();
                    let folded = !(e_s >= F::MIN_POSITIVE && e_s <= F::MAX) && u[0] > F::zero();
                    let (le, ls) = (ln_e.to_f64().abs(), ln_s0.to_f64().abs());
                    if folded {
                        self.2.folded.set(self.2.folded.get() + 1);
                    }
                    let k = if folded {
                        8.0 + 2.0 * le + 2.0 * ls + 2.0 * u[0].to_f64().ln().abs()
                    } else {
                        4.0 + le + ls
                    };
                    for q in 0..4 {
                        let (a, b) = (got[q][j], want[q]);
                        let exact = u[q].to_f64().abs() * e_ref;
                        let at_q = || format!("{}, entry {q}: {a:?} vs {b:?}", at());
                        if b.to_f64().is_nan() && u[q] == F::zero() && e_s.to_f64().is_infinite() {
                            // The scalar's `u · e` where its own `e` overflowed and `u₀ ≤ 0`:
                            // `0 · ∞` (a NaN where the entry is 0); the lanes' `e` is normal.
                            assert!(same(a, F::zero()), "{}: a zero entry not 0", at_q());
                            self.2.nan.set(self.2.nan.get() + 1);
                            continue;
                        }
                        let (ia, ib) = (a.to_f64().is_infinite(), b.to_f64().is_infinite());
                        if ib && !ia && folded && u[0].to_f64() * e_ref >= max * (1.0 - k * eps) {
                            // The scalar's folded exponent `ln_e + ln u₀` overflowed, and with
                            // it every nonzero entry, those below `u₀` too: the lanes against
                            // the exact value there (2 ulp, the reference's 1, a product).
                            self.2.early.set(self.2.early.get() + 1);
                            self.1.check::<F>(
                                diff(a, F::lit(exact).copysign(a)),
                                4.0,
                                exact,
                                2.0 * eps * min,
                                at_q,
                            );
                            continue;
                        }
                        if ia || ib {
                            let near = exact >= max * (1.0 - k * eps);
                            let signs = a.to_f64().signum() == b.to_f64().signum();
                            assert!(near && signs, "{}: overflow", at_q());
                            continue;
                        }
                        self.1
                            .check::<F>(diff(a, b), k, exact, 2.0 * eps * min, at_q);
                    }
                    compared += 1;
                }
            });
        }
        assert!(
            dark > 100 && lit > 300 && redone > 50 && compared > 200,
            "{what}: {dark} dark, {lit} lit, {redone} redone, {compared} compared"
        );
    }
}

#[test]
fn scaled_matches_prepared_packet_scaled_and_is_dark() {
    for bright in [1.0, 1e10, 3.7e-9, 1e150, 1e-150] {
        let t = Scales(
            cases::<f64>(bright),
            Worst::default(),
            ScaleCounts::default(),
        );
        every_width(&t);
        assert!(
            t.2.negligible.get() > 0,
            "no negligible part among the cases"
        );
        t.1.report(&format!("scaled f64, S0 = {bright:e}"));
        println!("  {:?}", t.2);
    }
    for bright in [1.0, 1e10, 3.7e-9, 1e13, 1e-13] {
        let t = Scales(
            cases::<f32>(bright),
            Worst::default(),
            ScaleCounts::default(),
        );
        every_width(&t);
        assert!(
            t.2.negligible.get() > 0,
            "no negligible part among the cases"
        );
        t.1.report(&format!("scaled f32, S0 = {bright:e}"));
        println!("  {:?}", t.2);
    }
}

// ---------------------------------------------------------------------------------------------
// fresnel_stokes

/// `fresnel_stokes` against `FresnelReflection::mueller(g) v`, for the unit exit `r̂ = g.exit()`
/// and `ŝ_out = g.exit_sp().x()` of every exit (those within `√ε` of the normal included: the
/// stage is given the scalar `ŝ_out`) and six vectors `v` (the effective `T S/S0`, the four unit
/// vectors, one of mixed signs), within `16 ε M₀₀ Σ|v_k|`; the exits include frame changes that
/// flip (`r̂·r̂_spec < −256 ε`) and exits within `√ε` of the normal.
///
/// The lanes apply the Fresnel matrix first (`M_F v`, four fused roundings: `2 ε M₀₀ Σ|v_k|`,
/// as `|M_ij| ≤ M₀₀` for the Mueller matrix of a Jones matrix) and then the frame change;
/// the scalar multiplies the two matrices (`2 ε` per entry of `T M_F`, `|T_ij| ≤ 1`) and applies
/// the product (four products and three sums, `3.5 ε`). The four dot products and `(x, y)` are
/// formed with the same operations on both sides; `√(x² + y²)` (fused in the lanes) differs by
/// `ε`, so `cos φ`, `sin φ` by `1.5 ε` and `cos 2φ` (fused), `sin 2φ` by `4 ε`, times
/// `|w₁| + |w₂| ≤ 2 M₀₀ Σ|v_k|`. In all `2 + 2 + 3.5 + 8 ≤ 16`.
struct Fresnel<F: Real>(Vec<Case<F>>, Vec<Vector4<F>>, Worst);

impl<F: Real> PerWidth for Fresnel<F> {
    fn run<S: Simd>(&self, s: S, what: &str) {
        let (mut checked, mut flipped, mut near_normal) = (0, 0, 0);
        for (ci, c) in self.0.iter().enumerate() {
            let fresnel = FresnelReflection::new(c.eta).unwrap();
            for g in &c.geometries {
                if c.prep.spec_frame.k().dot(&g.exit()) < -c.prep.flip_tol {
                    flipped += 1;
                }
                if g.exit().cross(&c.prep.n).norm() < c.prep.parallel_tol {
                    near_normal += 1;
                }
            }
            let mut vs = self.1.clone();
            vs.push(c.prep.t_stokes);
            chunks::<S, F>(c.geometries.len(), |i, len| {
                let g = &c.geometries[i..i + len];
                let r: [F::V<S>; 3] =
                    core::array::from_fn(|k| lanes::<S, F>(s, len, |j| g[j].exit()[k]));
                let so: [F::V<S>; 3] =
                    core::array::from_fn(|k| lanes::<S, F>(s, len, |j| g[j].exit_sp().x()[k]));
                let m: Vec<Matrix4<F>> = g.iter().map(|g| fresnel.mueller(g).0).collect();
                for (vi, v) in vs.iter().enumerate() {
                    let lv: [F::V<S>; 4] = core::array::from_fn(|k| F::vsplat(s, v[k]));
                    let got = fresnel_stokes::<S, F>(
                        s,
                        (&c.prep.fresnel, &c.prep.spec_frame, c.prep.flip_tol),
                        r,
                        so,
                        lv,
                    )
                    .map(|x| lanes_of::<S, F>(s, x));
                    let size: f64 = v.iter().map(|x| x.to_f64().abs()).sum();
                    for j in 0..len {
                        let want = m[j] * v;
                        let m00 = m[j][(0, 0)].to_f64();
                        for k in 0..4 {
                            self.2.check::<F>(
                                diff(got[k][j], want[k]),
                                16.0,
                                m00 * size,
                                0.0,
                                || {
                                    format!(
                                        "{what}: case {ci}, exit {}, v {vi}, S{k}: {:?} vs {:?}",
                                        i + j,
                                        got[k][j],
                                        want[k]
                                    )
                                },
                            );
                        }
                        checked += 1;
                    }
                }
            });
        }
        assert!(
            checked > 1000 && flipped > 10 && near_normal > 10,
            "{what}: {checked} lanes, {flipped} flipped, {near_normal} within √ε of the normal"
        );
    }
}

#[test]
fn fresnel_stokes_matches_fresnel_reflection_mueller() {
    let vectors = |_: ()| -> Vec<[f64; 4]> {
        vec![
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
            [1.0, -0.3, 0.5, 0.8],
        ]
    };
    let t = Fresnel(
        cases::<f64>(1.0),
        vectors(()).into_iter().map(Vector4::from).collect(),
        Worst::default(),
    );
    every_width(&t);
    t.2.report("fresnel_stokes f64");
    let t = Fresnel(
        cases::<f32>(1.0),
        vectors(())
            .into_iter()
            .map(|v| Vector4::from(v).map(f32::lit))
            .collect(),
        Worst::default(),
    );
    every_width(&t);
    t.2.report("fresnel_stokes f32");
}
