//! The kernel's prediction for a brute-force [`Scene`]: gmueller's scalar S2.20 kernel with the
//! `PhaseScreen` pBSDF (`M = |r|² v² I₄`, `|r|² = 1`) for the scattered part and a constant
//! identity Mueller matrix (a perfect mirror) for the specular part.
//!
//! Transmission ([`Scene::eta_t`] = `Some(η)`, light from above into the medium below): the
//! brute force's aperture model (the field on the mean plane is the incident field times the
//! phase screen, `t = 1`) is `PhaseScreen::interface(1, τ = η |t|² = η)` for the scattered part
//! and the constant `η I₄` for the specular part (the smooth interface then transmits
//! `η cos θ_t/cos θ_i`, as the brute force's flat surface does), evaluated with
//! `Geometry::at_interface(k, surface, η, ŝ, r̂)` (`k` the packet's wavenumber, in the medium of
//! incidence) for exits below the surface. The kernel's radiance is then the one in the exit
//! medium (prefactor `cos θ_o/λ_t²`, `λ_t = λ/η`).
//!
//! Roughness: [`Order::First`] (the first-order kernel) or [`Order::Series`] (all orders of the
//! Kirchhoff phase screen: `KirchhoffSeries` at tolerance 10⁻⁶ for the Gaussian PSD,
//! `KirchhoffQuadrature` at 10⁻⁶ for the exponential one — the K-correlation itself, not its
//! mixture fit; the grating stays at first order).
//!
//! Height PSDs: `GaussianPsd::isotropic(σ, ℓ)`; the exponential correlation is
//! `KCorrelation(σ², T = ℓ², γ = 2)`, blurred with a Gaussian-mixture fit (`ClosedForm`); the
//! sinusoidal height grating `a sin(2πx/Λ + φ)` has `R(ξ) = (a²/2) cos(2πξ/Λ)`, i.e. a
//! [`Grating`] with the two orders `±2π/Λ` of efficiency `a²/4` each and no zeroth order.
//! `Grating` has no public constructor from an order list, so it is built from public ones:
//! a sinusoidal *phase* grating of depth `j₀,₁` (first zero of `J₀`: `η₀ = J₀(j₀,₁)² ≈ 10⁻³³`,
//! `η±1 = J₁(j₀,₁)²`) crossed with a zeroth-order-only grating of efficiency
//! `J₀(b)² = a²/(4 J₁(j₀,₁)²)`, dropping products below `10⁻⁶ a²`.

#![allow(dead_code)]

use gmueller::frame::Frame;
use gmueller::interaction::pbsdf::{ConstantMueller, PhaseScreen};
use gmueller::interaction::roughness::{
    FirstOrder, KirchhoffQuadrature, KirchhoffSeries, RoughnessWeights,
};
use gmueller::interaction::{Geometry, Intensity, Kernel, Partial, RoughSurface, Side};
use gmueller::mueller::Mueller;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{
    BlurMethod, ClosedForm, GaussHermite, GaussianPsd, Grating, KCorrelation, OrderCutoff, Psd,
    bessel_j,
};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Matrix4, Vector2, Vector3};

use crate::brute::{Matter, Scene};

/// The kernel's answer per exit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// Specular (coherent) part of `L`.
    pub specular: f64,
    /// Scattered part of `L`.
    pub scattered: f64,
}

impl Prediction {
    /// `L = specular + scattered` (`response.total().s0()`).
    #[must_use]
    pub fn total(&self) -> f64 {
        self.specular + self.scattered
    }
}

/// The packet for `scene`: unpolarized, `S0 = 1`, shape `Θ⊥`, frame = the brute force's s/p frame.
///
/// # Panics
/// On invalid scene parameters.
#[must_use]
pub fn packet(scene: &Scene) -> WavePacket<f64> {
    let f = scene.packet_frame();
    let v = |a: [f64; 3]| Vector3::new(a[0], a[1], a[2]);
    let frame = Frame::new(v(f[0]), v(f[1]), v(f[2])).expect("packet frame");
    let t = scene.theta;
    let shape = CoherenceShape::new(Matrix2::new(t[0][0], t[0][1], t[1][0], t[1][1]))
        .expect("coherence shape");
    WavePacket::from_stokes(
        Stokes::unpolarized(1.0).expect("stokes"),
        shape,
        frame,
        scene.wavelength,
    )
    .expect("packet")
}

/// The first-order height-grating PSD (see the module docs).
///
/// # Panics
/// If the construction does not give exactly the two ±1 orders.
#[must_use]
pub fn height_grating(amplitude: f64, period: f64) -> Grating<f64, 2> {
    const J01: f64 = 2.404_825_557_695_773;
    let dir = Vector2::x();
    let g = std::f64::consts::TAU / period;
    let base = Grating::sinusoidal(
        period,
        &dir,
        J01,
        OrderCutoff {
            max_frequency: 1.5 * g,
            tail: 0.0,
        },
    )
    .expect("grating");
    let eta1 = bessel_j(1, J01)[1].powi(2);
    let target = amplitude * amplitude / 4.0;
    assert!(
        target < eta1,
        "height amplitude too large for this construction"
    );
    // J₀ decreases on [0, j₀,₁]: bisect J₀(b)² = target/eta1.
    let want = target / eta1;
    let (mut lo, mut hi) = (0.0_f64, J01);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if bessel_j(0, mid)[0].powi(2) > want {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let scale = Grating::sinusoidal(
        period,
        &dir,
        0.5 * (lo + hi),
        OrderCutoff {
            max_frequency: 0.5 * g,
            tail: 0.0,
        },
    )
    .expect("grating");
    let out =
        Grating::crossed(&base, &scale, 1e-6 * amplitude * amplitude).expect("crossed grating");
    assert_eq!(out.orders().len(), 2, "expected the ±1 orders only");
    assert!((out.variance() / (0.5 * amplitude * amplitude) - 1.0).abs() < 1e-9);
    out
}

/// The roughness level of a prediction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Order {
    /// The first-order kernel (`FirstOrder`): valid while `vσ ≲ 0.3`.
    First,
    /// The Kirchhoff series (`KirchhoffSeries`, tolerance 10⁻⁶) where the PSD has its powers
    /// (the Gaussian), first order otherwise.
    Series,
}

fn predict_with<P, B, R>(
    scene: &Scene,
    psd: P,
    blur: B,
    rough: R,
    exits: &[[f64; 3]],
    min_seconds: f64,
) -> (Vec<Prediction>, f64)
where
    P: Psd<f64, 2>,
    B: BlurMethod<f64, 2, P> + Clone + std::fmt::Debug,
    R: RoughnessWeights<f64, P, Partial<B>>,
{
    let packet = packet(scene);
    let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).expect("surface");
    let material = match scene.eta_t {
        None => RoughSurface {
            psd,
            specular: ConstantMueller(Mueller::identity()),
            scatter: PhaseScreen::new(1.0).expect("phase screen"),
        },
        // The aperture model: t = 1, τ = η|t|² = η (module docs).
        Some(eta) => RoughSurface {
            psd,
            specular: ConstantMueller(
                Mueller::from_matrix(Matrix4::identity() * eta).expect("η I₄"),
            ),
            scatter: PhaseScreen::interface(1.0, eta).expect("phase screen"),
        },
    };
    let geometry = |r: &[f64; 3]| -> Geometry<f64> {
        let exit = Vector3::new(r[0], r[1], r[2]);
        match scene.eta_t {
            None => Geometry::for_packet(&packet, &surface, exit).expect("geometry"),
            Some(eta) => {
                let g = Geometry::at_interface(
                    packet.wavenumber(),
                    &surface,
                    eta,
                    -packet.direction(),
                    exit,
                )
                .expect("geometry");
                assert_eq!(
                    g.side(),
                    Side::Transmission,
                    "exit {r:?} not below the surface"
                );
                g
            }
        }
    };
    let kernel = Kernel::<Intensity, Partial<B>>::new(Partial(blur)).with_roughness(rough);
    let once = || -> Vec<Prediction> {
        // One packet, many exit directions: the per-packet work once.
        let prepared = kernel
            .prepare(&packet, &surface)
            .expect("packet toward the surface");
        exits
            .iter()
            .map(|r| {
                let g = geometry(r);
                let resp = kernel.evaluate_prepared(&material, &prepared, &g);
                Prediction {
                    specular: resp.specular,
                    scattered: resp.scattered,
                }
            })
            .collect()
    };
    let out = once();
    // Time the evaluations alone (geometry included, material set-up excluded).
    let start = std::time::Instant::now();
    let mut reps = 0usize;
    while start.elapsed().as_secs_f64() < min_seconds {
        std::hint::black_box(once());
        reps += 1;
    }
    let per = start.elapsed().as_secs_f64() / (reps.max(1) * exits.len().max(1)) as f64;
    (out, per)
}

/// The first-order kernel's `L` (per unit `S0`) for each exit direction.
///
/// # Panics
/// On invalid scene parameters.
#[must_use]
pub fn predict(scene: &Scene, exits: &[[f64; 3]]) -> Vec<Prediction> {
    predict_timed(scene, exits, 0.0).0
}

/// The kernel's `L` (per unit `S0`) for each exit direction at the roughness level `order`.
///
/// # Panics
/// On invalid scene parameters.
#[must_use]
pub fn predict_at(scene: &Scene, exits: &[[f64; 3]], order: Order) -> Vec<Prediction> {
    predict_timed_at(scene, exits, 0.0, order).0
}

/// As [`predict`] (first order), and the time per direction of the evaluations, measured by
/// repeating them for at least `min_seconds` (the material — e.g. a mixture fit — is built
/// once, untimed).
///
/// # Panics
/// On invalid scene parameters.
#[must_use]
pub fn predict_timed(
    scene: &Scene,
    exits: &[[f64; 3]],
    min_seconds: f64,
) -> (Vec<Prediction>, f64) {
    predict_timed_at(scene, exits, min_seconds, Order::First)
}

/// As [`predict_at`], timed as [`predict_timed`].
///
/// # Panics
/// On invalid scene parameters.
#[must_use]
pub fn predict_timed_at(
    scene: &Scene,
    exits: &[[f64; 3]],
    min_seconds: f64,
    order: Order,
) -> (Vec<Prediction>, f64) {
    match scene.matter {
        Matter::Gaussian { sigma, ell } => {
            let psd = GaussianPsd::<f64, 2>::isotropic(sigma, ell).expect("psd");
            match order {
                Order::First => {
                    predict_with(scene, psd, ClosedForm, FirstOrder, exits, min_seconds)
                }
                Order::Series => predict_with(
                    scene,
                    psd,
                    ClosedForm,
                    KirchhoffSeries::new(1e-6).expect("tolerance"),
                    exits,
                    min_seconds,
                ),
            }
        }
        Matter::Exponential { sigma, ell } => {
            let k = KCorrelation::<f64, 2>::new(sigma * sigma, ell * ell, 2.0).expect("psd");
            match order {
                Order::First => {
                    let (fit, _, _) = k.mixture_fit_to(1e-6).expect("mixture fit");
                    predict_with(scene, fit, ClosedForm, FirstOrder, exits, min_seconds)
                }
                // The quadrature blurs by itself; the Partial level's method is not used.
                Order::Series => predict_with(
                    scene,
                    k,
                    GaussHermite::new(1).expect("order"),
                    KirchhoffQuadrature::new(1e-6).expect("tolerance"),
                    exits,
                    min_seconds,
                ),
            }
        }
        Matter::Sinusoid { amplitude, period } => predict_with(
            scene,
            height_grating(amplitude, period),
            ClosedForm,
            FirstOrder,
            exits,
            min_seconds,
        ),
    }
}

/// Whether `order` sums every order of the phase screen for `scene` (the Gaussian and the
/// exponential PSDs), not first order.
#[must_use]
pub fn uses_series(scene: &Scene, order: Order) -> bool {
    order == Order::Series && !matches!(scene.matter, Matter::Sinusoid { .. })
}

/// A short name of the kernel level used for `scene` at the roughness level `order`.
#[must_use]
pub fn method_name(scene: &Scene, order: Order) -> String {
    let base = match (scene.eta_t.is_some(), scene.matter) {
        (true, Matter::Gaussian { .. }) => {
            "Intensity/Partial/ClosedForm, GaussianPsd, at_interface, PhaseScreen::interface(1, η)"
        }
        (true, Matter::Exponential { .. }) => {
            "Intensity/Partial/ClosedForm, KCorrelation γ=2 mixture fit 1e-6, at_interface"
        }
        (true, Matter::Sinusoid { .. }) => {
            "Intensity/Partial/ClosedForm, Grating ±1 orders, at_interface"
        }
        (false, Matter::Gaussian { .. }) => "Intensity/Partial/ClosedForm, GaussianPsd",
        (false, Matter::Exponential { .. }) => {
            "Intensity/Partial/ClosedForm, KCorrelation γ=2 mixture fit 1e-6"
        }
        (false, Matter::Sinusoid { .. }) => "Intensity/Partial/ClosedForm, Grating ±1 orders",
    };
    if uses_series(scene, order) {
        match scene.matter {
            Matter::Exponential { .. } => {
                "Intensity/Partial, KCorrelation γ=2, KirchhoffQuadrature 1e-6".to_string()
            }
            _ => format!("{base}, KirchhoffSeries 1e-6"),
        }
    } else {
        format!("{base}, first order")
    }
}
