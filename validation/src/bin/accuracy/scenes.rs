//! The fixed scene suite: materials, coherence widths, incidences, input polarizations and the
//! grid of exit directions, built in either precision from one f64 description.

use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::pbsdf::{FresnelReflection, RayleighRice};
use gmueller::interaction::{Geometry, RoughDielectric, RoughSurface};
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::{
    BlurMethod, ClosedForm, ClosedFormBlur, Form, GaussianMixturePsd, GaussianPsd, Grating,
    KCorrelation, OrderCutoff, Psd, Shape,
};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, SVector, Vector2, Vector3};
use num_complex::Complex;

/// Wavelength (µm); every length below is given in units of λ and multiplied by it.
pub const LAMBDA: f64 = 0.5;
/// rms height of every rough material (λ units): `kσ = 0.126`, first order holds.
pub const SIGMA: f64 = 0.02;
/// Solid angle of the sun (sr) and the coherence width it gives by van Cittert–Zernike,
/// `w = λ/√(πΩ)` ([`WavePacket::from_distant_disk_source`]): 68.4 λ.
pub const SUN_SOLID_ANGLE: f64 = 6.8e-5;
/// Glass and aluminium (≈ 550 nm) relative indices.
pub const GLASS: (f64, f64) = (1.5, 0.0);
/// Aluminium.
pub const ALUMINIUM: (f64, f64) = (0.96, 6.69);
/// Mixture-fit sizes for the K-correlation.
pub const MIXTURES: [usize; 2] = [4, 8];

/// The sunlight coherence width in λ units.
pub fn sun_width() -> f64 {
    1.0 / (core::f64::consts::PI * SUN_SOLID_ANGLE).sqrt()
}

/// A material of the suite (description, precision-free).
#[derive(Debug, Clone, Copy)]
pub enum MaterialSpec {
    /// Isotropic Gaussian PSD with correlation length ℓ (λ units) on glass.
    Gaussian { ell: f64 },
    /// K-correlation (ABC) PSD, `√T` in λ units, exponent γ, on aluminium.
    KCorr { sqrt_t: f64, gamma: f64 },
    /// 1-D lamellar (binary, duty ½) height grating of period Λ (λ units), half-depth σ, on aluminium.
    Grating { period: f64 },
    /// Brushed aluminium: anisotropic Gaussian PSD, ℓ across/along the grooves (λ units).
    Brushed { ell_x: f64, ell_y: f64 },
    /// Transmission through a rough glass interface (light from the air into the glass):
    /// isotropic Gaussian PSD with correlation length ℓ (λ units), exits inside the glass.
    GlassTransmission { ell: f64 },
}

impl MaterialSpec {
    /// Short name for tables.
    pub fn name(&self) -> String {
        match *self {
            Self::Gaussian { ell } => format!("Gauss ℓ={ell}λ"),
            Self::KCorr { sqrt_t, gamma } => format!("K γ={gamma} √T={sqrt_t}λ"),
            Self::Grating { period } => format!("grating Λ={period}λ"),
            Self::Brushed { ell_x, ell_y } => format!("brushed Al {ell_x}×{ell_y}λ"),
            Self::GlassTransmission { ell } => format!("glass T ℓ={ell}λ"),
        }
    }

    /// The relative index of the medium the light enters, for transmission materials.
    pub fn transmission(&self) -> Option<f64> {
        match self {
            Self::GlassTransmission { .. } => Some(GLASS.0),
            _ => None,
        }
    }

    /// Whether the PSD is a continuous function (quadrature blur methods apply).
    pub fn continuous(&self) -> bool {
        !matches!(self, Self::Grating { .. })
    }

    /// Whether the PSD is a Gaussian (closed-form blur exact).
    pub fn gaussian(&self) -> bool {
        matches!(
            self,
            Self::Gaussian { .. } | Self::Brushed { .. } | Self::GlassTransmission { .. }
        )
    }
}

/// The height PSD of a lamellar grating: `σ²` times the reflection-function PSD of a binary
/// π-phase grating (whose `e^{iφ} = ±1` is the unit square wave, so its correlation is that of a
/// square-wave height profile of unit amplitude; orders odd m, `η_m = 4/(πm)²`, no zeroth order).
#[derive(Debug, Clone)]
pub struct HeightGrating<T: Real> {
    grating: Grating<T, 2>,
    variance_scale: T,
}

impl<T: Real> Psd<T, 2> for HeightGrating<T> {
    fn value(&self, _zeta: &SVector<T, 2>) -> T {
        T::zero()
    }
    fn variance(&self) -> T {
        self.variance_scale * self.grating.variance()
    }
    /// The grating's orders (weights `η_m/Σ η`, the same once scaled).
    fn form(&self) -> Form<'_, T, 2> {
        Form::closest(Shape::Orders(self.grating.orders()))
    }
}

/// The closed form lives on the PSD side ([`ClosedFormBlur`]), so this crate can give its own
/// PSD one, generic over the precision.
impl<T: Real> ClosedFormBlur<T, 2> for HeightGrating<T> {
    fn closed_form_blur(&self, cov: &Gaussian<T, 2>, h: &SVector<T, 2>) -> T {
        self.variance_scale * ClosedForm.blur(&self.grating, cov, h)
    }
}

type Surface<T, P> = RoughSurface<P, FresnelReflection<T>, RayleighRice<T>>;

/// A material built in precision `T`.
pub enum Material<T: Real> {
    /// Gaussian PSD (isotropic or brushed).
    Gauss(Surface<T, GaussianPsd<T, 2>>),
    /// K-correlation, exact and its mixture fits ([`MIXTURES`]).
    K {
        exact: Surface<T, KCorrelation<T, 2>>,
        mixtures: Vec<Surface<T, GaussianMixturePsd<T, 2>>>,
    },
    /// Height grating.
    Grating(Surface<T, HeightGrating<T>>),
    /// A rough glass interface, evaluated in transmission.
    Interface(RoughDielectric<T, GaussianPsd<T, 2>>),
}

fn surface<T: Real, P>(psd: P, eta: (f64, f64)) -> Surface<T, P> {
    let eta = Complex::new(T::lit(eta.0), T::lit(eta.1));
    RoughSurface {
        psd,
        specular: FresnelReflection::new(eta).expect("valid index"),
        scatter: RayleighRice::new(eta).expect("valid index"),
    }
}

/// Builds a material in precision `T` (µm units).
pub fn build_material<T: Real>(spec: &MaterialSpec) -> Material<T> {
    let l = LAMBDA;
    let sigma = SIGMA * l;
    match *spec {
        MaterialSpec::Gaussian { ell } => Material::Gauss(surface(
            GaussianPsd::isotropic(T::lit(sigma), T::lit(ell * l)).expect("valid"),
            GLASS,
        )),
        MaterialSpec::GlassTransmission { ell } => Material::Interface(
            RoughDielectric::new(
                GaussianPsd::isotropic(T::lit(sigma), T::lit(ell * l)).expect("valid"),
                T::lit(GLASS.0),
            )
            .expect("valid index"),
        ),
        MaterialSpec::Brushed { ell_x, ell_y } => {
            let corr = Gaussian::new(Matrix2::new(
                T::lit((ell_x * l).powi(2)),
                T::zero(),
                T::zero(),
                T::lit((ell_y * l).powi(2)),
            ))
            .expect("SPD");
            Material::Gauss(surface(
                GaussianPsd::from_autocorrelation(T::lit(sigma * sigma), &corr).expect("valid"),
                ALUMINIUM,
            ))
        }
        MaterialSpec::KCorr { sqrt_t, gamma } => {
            let k = KCorrelation::<T, 2>::new(
                T::lit(sigma * sigma),
                T::lit((sqrt_t * l).powi(2)),
                T::lit(gamma),
            )
            .expect("valid");
            let mixtures = MIXTURES
                .iter()
                .map(|&m| surface(k.mixture_fit(m).expect("fit").0, ALUMINIUM))
                .collect();
            Material::K {
                exact: surface(k, ALUMINIUM),
                mixtures,
            }
        }
        MaterialSpec::Grating { period } => {
            let k = core::f64::consts::TAU / l;
            let cut = OrderCutoff {
                max_frequency: T::lit(2.05 * k),
                tail: T::zero(),
            };
            let grating = Grating::rectangular(
                T::lit(period * l),
                &Vector2::new(T::one(), T::zero()),
                T::pi(),
                T::lit(0.5),
                cut,
            )
            .expect("valid grating");
            Material::Grating(surface(
                HeightGrating {
                    grating,
                    variance_scale: T::lit(sigma * sigma),
                },
                ALUMINIUM,
            ))
        }
    }
}

/// Input polarization of a scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// Unpolarized, one coherence shape `w² I` for both components (sunlight).
    Unpolarized,
    /// Stokes (1, 0.5, 0.5, 0.3) in the incident s/p frame (`DoP` 0.77) with unequal component
    /// coherence `Θ_x = w² I`, `Θ_y = (1.3 w)² I` (light that already met matter), so that the
    /// one-shape level differs from the full one.
    Polarized,
}

/// One scene of the suite.
#[derive(Debug, Clone, Copy)]
pub struct SceneSpec {
    /// Index into the material list.
    pub material: usize,
    /// Incidence angle (degrees).
    pub theta_i: f64,
    /// Index into the width list.
    pub width: usize,
    /// Coherence width (λ units).
    pub width_lambda: f64,
    /// Input polarization.
    pub input: Input,
}

/// The packet and the exit geometries of a scene, in precision `T`; for the batch rows also the
/// surface frame, the exit directions as a structure of arrays and the interface index.
pub struct SceneData<T: Real> {
    pub packet: WavePacket<T>,
    pub geoms: Vec<Geometry<T>>,
    /// The surface frame the geometries were built with (normal +z).
    pub surface: Frame<T>,
    /// The exit directions, `x, y, z` components (the same directions as `geoms`, in order).
    pub exits: [Vec<T>; 3],
    /// The relative index of the medium below for a transmission material (`evaluate_batch`'s
    /// `interface`), `None` in reflection.
    pub interface: Option<T>,
}

/// The exit directions (unit vectors, surface normal +z, incidence in the x–z plane travelling
/// toward +x): `θ_o` ∈ {5°, 20°, …, 80°} × φ ∈ {0°, 45°, …, 180°} from the forward plane of
/// incidence, plus in-plane near-specular directions `θ_i` ± 1°, ± 3° and the in-plane directions of
/// the grating's diffraction orders m = ±1, ±2, ±3 (period `grating_period` λ). The exact
/// specular direction is left out: there the plane-wave level's specular lobe is a Dirac delta.
pub fn exit_directions(theta_i: f64, grating_period: f64, quick: bool) -> Vec<Vector3<f64>> {
    let mut out = grid(quick);
    let in_plane = |s: f64| Vector3::new(s, 0.0, (1.0 - s * s).sqrt());
    for d in [-3.0_f64, -1.0, 1.0, 3.0] {
        let t = theta_i + d;
        if t.abs() < 89.0 {
            out.push(in_plane(t.to_radians().sin()));
        }
    }
    for m in [-3.0_f64, -2.0, -1.0, 1.0, 2.0, 3.0] {
        let s = theta_i.to_radians().sin() + m / grating_period;
        if s.abs() < 0.995 {
            out.push(in_plane(s));
        }
    }
    out
}

/// The grid `θ_o` ∈ {5°, 20°, …, 80°} × φ ∈ {0°, 45°, …, 180°} above the surface (quick:
/// {15°, 45°, 75°} × {0°, 90°, 180°}).
fn grid(quick: bool) -> Vec<Vector3<f64>> {
    let mut out = Vec::new();
    let thetas: Vec<f64> = if quick {
        vec![15.0, 45.0, 75.0]
    } else {
        (0..6).map(|i| 5.0 + 15.0 * f64::from(i)).collect()
    };
    let phis: Vec<f64> = if quick {
        vec![0.0, 90.0, 180.0]
    } else {
        (0..5).map(|i| 45.0 * f64::from(i)).collect()
    };
    let dir = |t: f64, p: f64| {
        let (t, p) = (t.to_radians(), p.to_radians());
        Vector3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    };
    for &t in &thetas {
        for &p in &phis {
            out.push(dir(t, p));
        }
    }
    out
}

/// The exit directions of a transmission scene (inside the medium of relative index `eta`,
/// below the surface): the grid of [`exit_directions`] mirrored below the surface, plus in-plane
/// directions `θ_t` ± 1°, ± 3° about Snell's direction (which itself is left out, as the exact
/// specular direction is in reflection).
pub fn exit_directions_transmitted(theta_i: f64, eta: f64, quick: bool) -> Vec<Vector3<f64>> {
    let mut out: Vec<Vector3<f64>> = grid(quick)
        .into_iter()
        .map(|d| Vector3::new(d.x, d.y, -d.z))
        .collect();
    let theta_t = (theta_i.to_radians().sin() / eta).asin().to_degrees();
    for d in [-3.0_f64, -1.0, 1.0, 3.0] {
        let t = (theta_t + d).to_radians();
        out.push(Vector3::new(t.sin(), 0.0, -t.cos()));
    }
    out
}

/// Builds a scene's packet and geometries in precision `T`.
///
/// `transmission`: the relative index of the medium below for a transmission material (the
/// geometries are then those of the interface, [`Geometry::at_interface`]).
pub fn build_scene<T: Real>(
    s: &SceneSpec,
    exits: &[Vector3<f64>],
    transmission: Option<f64>,
) -> SceneData<T> {
    let ti = s.theta_i.to_radians();
    let travel = Vector3::new(T::lit(ti.sin()), T::zero(), T::lit(-ti.cos()));
    let normal = Vector3::new(T::zero(), T::zero(), T::one());
    let frame = Frame::sp(travel, normal).expect("valid direction");
    let w = s.width_lambda * LAMBDA;
    let shape = |w: f64| CoherenceShape::isotropic(T::lit(w)).expect("positive width");
    let packet = match s.input {
        Input::Unpolarized => WavePacket::new(
            Stokes::unpolarized(T::one()).expect("valid"),
            shape(w),
            shape(w),
            frame,
            T::lit(LAMBDA),
        ),
        Input::Polarized => WavePacket::new(
            Stokes::new(T::one(), T::lit(0.5), T::lit(0.5), T::lit(0.3)).expect("valid"),
            shape(w),
            shape(1.3 * w),
            frame,
            T::lit(LAMBDA),
        ),
    }
    .expect("realizable packet");
    let surface = Frame::new(
        Vector3::new(T::one(), T::zero(), T::zero()),
        Vector3::new(T::zero(), T::one(), T::zero()),
        normal,
    )
    .expect("orthonormal");
    let geoms = exits
        .iter()
        .map(|e| match transmission {
            None => Geometry::for_packet(&packet, &surface, e.map(T::lit)).expect("above"),
            Some(eta) => {
                Geometry::for_packet_at_interface(&packet, &surface, T::lit(eta), e.map(T::lit))
                    .expect("a valid interface geometry")
            }
        })
        .collect();
    let component = |c: usize| exits.iter().map(|e| T::lit(e[c])).collect();
    SceneData {
        packet,
        geoms,
        surface,
        exits: [component(0), component(1), component(2)],
        interface: transmission.map(T::lit),
    }
}
