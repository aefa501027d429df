//! Issue 36, the kernel: promises of `docs/numerical.md` that failed only in `f32`, each
//! against `f64` on the same `f32` inputs (the inputs rounded to `f32` once, then cast).
//!
//! - **The Kirchhoff series in far tails** (`KirchhoffSeries::sum`): for long-correlated,
//!   rough surfaces (ℓ = 10⁴–10⁷ λ, σ = 10⁻⁴–100 λ) the logarithms of the series' terms reach
//!   ~10⁶ in the tails, where `f32` rounds them in steps of 0.125 — wider than the step between
//!   neighbouring orders — and the sum was `+∞` (ℓ = 9.6·10⁶ λ, σ = 5.7 λ, λ = 0.193 µm, 0.5°
//!   off the specular direction: `f64` −1.24·10⁶). The series is now summed in `f64`; its
//!   logarithm in `f32` agrees with `f64` to `16 ε₃₂ (|ln Σ| + 1)`.

use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::{
    Geometry, Intensity, Kernel, KirchhoffDielectric, KirchhoffSeries, Partial, PlaneWave,
};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use gmueller::verify::rng::SplitMix64;
use nalgebra::Vector3;

/// Log-uniform on `[lo, hi]`.
fn log_uniform(rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.unit() * (hi / lo).ln()).exp()
}

/// `x` rounded to `f32`.
fn r32(x: f64) -> f64 {
    f64::from(x as f32)
}

/// One scene of the series sweep (lengths in λ, angles in radians).
#[derive(Debug, Clone, Copy)]
struct SeriesScene {
    lambda: f64,
    sigma: f64,
    ell: f64,
    theta_i: f64,
    offset: f64,
    width: f64,
}

impl SeriesScene {
    fn draw(rng: &mut SplitMix64) -> Self {
        let sign = if rng.unit() < 0.5 { 1.0 } else { -1.0 };
        Self {
            lambda: r32(log_uniform(rng, 0.1, 100.0)),
            sigma: log_uniform(rng, 1e-4, 100.0),
            ell: log_uniform(rng, 1e4, 1e7),
            theta_i: rng.unit() * 80f64.to_radians(),
            offset: sign * log_uniform(rng, 1e-9, 1e-2),
            width: log_uniform(rng, 1.0, 1e6),
        }
    }

    /// Rough glass (`KirchhoffDielectric`, η = 1.5), its packet and the exit geometry, in `T`;
    /// the PSD `(σ², spectral covariance)` given (the `f32` run's, cast) or from the scene.
    #[allow(clippy::type_complexity)]
    fn build<T: Real>(
        &self,
        psd: Option<(f64, nalgebra::Matrix2<f64>)>,
    ) -> (
        KirchhoffDielectric<T, GaussianPsd<T, 2>>,
        WavePacket<T>,
        Geometry<T>,
    ) {
        let l = |x: f64| T::lit(r32(x));
        let psd = match psd {
            Some((var, cov)) => GaussianPsd::<T, 2>::from_spectral_shape(
                T::lit(var),
                gmueller::gaussian::Gaussian::new(cov.map(T::lit)).unwrap(),
            ),
            None => GaussianPsd::<T, 2>::isotropic(
                l(self.sigma * self.lambda),
                l(self.ell * self.lambda),
            ),
        }
        .unwrap();
        let glass = KirchhoffDielectric::new(psd, l(1.5)).unwrap();
        let surface = Frame::<T>::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let t = self.theta_i;
        let travel = Vector3::new(t.sin(), 0.0, -t.cos()).map(l);
        let packet = WavePacket::from_stokes(
            Stokes::unpolarized(T::one()).unwrap(),
            CoherenceShape::isotropic(l(self.width * self.lambda)).unwrap(),
            Frame::sp(travel, Vector3::z()).unwrap(),
            l(self.lambda),
        )
        .unwrap();
        let to = t + self.offset;
        let exit = Vector3::new(to.sin(), 0.0, to.cos()).map(l);
        let g = Geometry::for_packet_at_interface(&packet, &surface, l(1.5), exit).unwrap();
        (glass, packet, g)
    }
}

/// What the `f32` run hands the `f64` one: `h_t`, the phase factor and the PSD's `σ²` and
/// spectral covariance (the `f64` run's own would round differently: `g = (vσ)²` reaches 10⁵
/// here, and its rounding alone moves `ln Σ` by `ε g`).
type SeriesInputs = (f64, f64, f64, f64, nalgebra::Matrix2<f64>);

/// The series' logarithm `ln Σ (w_n/g) K[p_n]` (plane wave) and the kernel's scattered part
/// at `Intensity · PlaneWave` and `Intensity · Partial`, in `T`, as `f64`, with the inputs for
/// the `f64` run.
fn series_scene<T: Real>(s: &SeriesScene, given: Option<SeriesInputs>) -> (SeriesInputs, [f64; 3]) {
    use gmueller::psd::Psd;
    let (glass, packet, g) = s.build::<T>(given.map(|x| (x.3, x.4)));
    let (h, v) = match given {
        Some((hx, hy, v, _, _)) => (nalgebra::Vector2::new(T::lit(hx), T::lit(hy)), T::lit(v)),
        None => (g.h_t(), g.phase_factor()),
    };
    let inputs = (
        h.x.to_f64(),
        h.y.to_f64(),
        v.to_f64(),
        glass.psd.variance().to_f64(),
        glass.psd.spectral_shape().covariance().map(|x| x.to_f64()),
    );
    let series = KirchhoffSeries::new(1e-4).unwrap();
    let sum = series.sum(&PlaneWave, &glass.psd, None, &h, v);
    let plane = Kernel::<Intensity, PlaneWave>::default()
        .with_roughness(series)
        .evaluate(&glass, &packet, &g);
    let partial = Kernel::<Intensity, Partial>::default()
        .with_roughness(series)
        .evaluate(&glass, &packet, &g);
    (
        inputs,
        [
            sum.log_weight.to_f64(),
            plane.scattered.to_f64(),
            partial.scattered.to_f64(),
        ],
    )
}

/// 30 000 seeded scenes: the `f32` series never returns `+∞` or NaN, its logarithm is the
/// `f64` one (on the same `h_t`, phase factor, `σ²` and spectral covariance: what is left is
/// the `f32` Cholesky factor of the covariance, a few ε₃₂ in every exponent) within
/// `16 ε₃₂ (|ln Σ| + 1)`, and the
/// kernel's scattered part is finite and non-negative wherever `f64`'s is below `f32::MAX`.
#[test]
fn kirchhoff_series_far_tails_are_finite_in_f32() {
    let mut rng = SplitMix64(36);
    let eps = f64::from(f32::EPSILON);
    let (mut compared, mut deep, mut worst) = (0, 0, 0.0f64);
    for _ in 0..30_000 {
        let s = SeriesScene::draw(&mut rng);
        let (hv, [l32, p32, q32]) = series_scene::<f32>(&s, None);
        let (_, [l64, p64, q64]) = series_scene::<f64>(&s, Some(hv));
        assert!(!l32.is_nan() && l32 < f64::INFINITY, "{s:?}: ln Σ = {l32} (f64 {l64})");
        if l64.is_finite() {
            let err = (l32 - l64).abs() / (16.0 * eps * (l64.abs() + 1.0));
            assert!(err <= 1.0, "{s:?}: ln Σ {l32} vs {l64}");
            worst = worst.max(err);
            compared += 1;
            if l64 < -1e5 {
                deep += 1;
            }
        } else {
            assert_eq!(l32, f64::NEG_INFINITY, "{s:?}: f64 {l64}");
        }
        for (a, b) in [(p32, p64), (q32, q64)] {
            assert!(a >= 0.0 && !a.is_nan(), "{s:?}: kernel {a:e} (f64 {b:e})");
            if b < 0.5 * f64::from(f32::MAX) {
                assert!(a.is_finite(), "{s:?}: kernel {a:e} (f64 {b:e})");
            }
        }
    }
    println!("series compared {compared} (ln Σ below −10⁵: {deep}), worst {worst:.3} of the bound");
    assert!(compared > 20_000 && deep > 100, "{compared} {deep}");
}

