//! The random medium (`gmueller::medium`) against independent computations: the first-Born
//! vector integral for Gaussian ingredients written from the field (not from the PSD or its
//! blur), the textbook Rayleigh cross-section of small spheres (the absolute constant), the
//! closed-form scattering coefficient of a Gaussian medium, adaptive quadrature of the
//! differential scattering over the sphere (`σ_s` and the phase matrix's normalisation), van de
//! Hulst's / Bohren & Huffman's Rayleigh matrix, and the crate's `volume_coherence_term`.
//!
//! # The Born oracle
//! ```text
//! r² ⟨E_s E_s†⟩/V = (k⁴/16π²) Σ_α f_α(h) C_α,   f_α(h) = ∫ R(ξ) g^{Θ_α}(Qᵀξ) e^{−ih·ξ} d³ξ
//!   R(ξ) = σ² exp(−½ ξᵀC⁻¹ξ)  ⇒  f_α(h) = σ² (2π)^{3/2} |G_α|^{−1/2} exp(−½ hᵀG_α⁻¹h),  G_α = C⁻¹ + QΘ_α⁻¹Qᵀ
//!   C_x = S_x x̂x̂ᵀ,  C_y = S_y ŷŷᵀ,  C_½ = ½(S2 − iS3) x̂ŷᵀ + ½(S2 + iS3) ŷx̂ᵀ        (3×3, world)
//! ```
//! then the exit frame's components `C'_ij = ê_iᵀ C ê_j` (the transverse projection
//! `I − r̂r̂ᵀ` of the dipole is implicit in components along ê ⊥ r̂) and Stokes by S1.2. The
//! Gaussian ξ-integral is checked once against a brute-force 3-D trapezoid sum.

use crate::common;

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use common::{Tol, assert_close};
use gmueller::frame::Frame;
use gmueller::interaction::coherence::volume_coherence_term;
use gmueller::interaction::polarization::{PolarizationModel, Throughput};
use gmueller::interaction::{Full, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave};
use gmueller::medium::{Dipole, PhaseFunction, RandomMedium, Scalar, Scatterer, VolumeCoherence};
use gmueller::packet::{Channel, CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, GaussianPsd, KCorrelation};
use gmueller::stokes::Stokes;
use gmueller::verify::oracle::stokes_of_csd;
use gmueller::verify::quadrature::{cube_quad, integrate};
use nalgebra::{Complex, Matrix2, Matrix3, Rotation3, Unit, Vector3, Vector4};

type C64 = Complex<f64>;

// ------------------------------------------------------------------ scene (test-side)

/// The light as the oracle sees it: frame `Q = [x̂ ŷ d̂]`, transverse shapes, `σ_zz`, Stokes.
#[derive(Clone, Copy)]
struct Light {
    q: Matrix3<f64>,
    theta_x: Matrix2<f64>,
    theta_y: Matrix2<f64>,
    sigma_zz: f64,
    stokes: Vector4<f64>,
    wavelength: f64,
}

impl Light {
    fn k(&self) -> f64 {
        TAU / self.wavelength
    }
    fn col(&self, j: usize) -> Vector3<f64> {
        self.q.column(j).into()
    }
    fn packet(&self) -> WavePacket<f64> {
        let frame = Frame::new(self.col(0), self.col(1), self.col(2)).unwrap();
        WavePacket::new(
            Stokes::new(
                self.stokes[0],
                self.stokes[1],
                self.stokes[2],
                self.stokes[3],
            )
            .unwrap(),
            CoherenceShape::new(self.theta_x).unwrap(),
            CoherenceShape::new(self.theta_y).unwrap(),
            frame,
            self.wavelength,
        )
        .unwrap()
        .with_longitudinal_coherence(self.sigma_zz)
        .unwrap()
    }
    /// `Q Θ⁻¹ Qᵀ` of a transverse shape, built here.
    fn precision(&self, theta: &Matrix2<f64>) -> Matrix3<f64> {
        let mut inv = Matrix3::zeros();
        inv.fixed_view_mut::<2, 2>(0, 0)
            .copy_from(&theta.try_inverse().unwrap());
        inv[(2, 2)] = 1.0 / (self.sigma_zz * self.sigma_zz);
        self.q * inv * self.q.transpose()
    }
    /// The channel CSDs `(C_x, C_y, C_½)` in world coordinates.
    fn channel_csds(&self) -> [nalgebra::Matrix3<C64>; 3] {
        let s = self.stokes;
        let (x, y) = (self.col(0).map(C64::from), self.col(1).map(C64::from));
        let sx = 0.5 * (s[0] + s[1]);
        let sy = 0.5 * (s[0] - s[1]);
        let cxy = C64::new(0.5 * s[2], -0.5 * s[3]);
        [
            x * x.transpose() * C64::from(sx),
            y * y.transpose() * C64::from(sy),
            x * y.transpose() * cxy + y * x.transpose() * cxy.conj(),
        ]
    }
}

/// `f(h) = σ² (2π)^{3/2} |G|^{−1/2} exp(−½ hᵀG⁻¹h)` (module docs); `precision = None` is the
/// plane wave (`G = C⁻¹`).
fn born_xi_integral(
    sigma2: f64,
    c: &Matrix3<f64>,
    precision: Option<&Matrix3<f64>>,
    h: &Vector3<f64>,
) -> f64 {
    let g = c.try_inverse().unwrap() + precision.copied().unwrap_or_else(Matrix3::zeros);
    sigma2 * TAU.powf(1.5) / g.determinant().sqrt()
        * (-0.5 * h.dot(&(g.try_inverse().unwrap() * h))).exp()
}

/// The Born oracle: Stokes `dI/dV` in the exit frame `(e_x, e_y)`.
fn born_stokes(
    light: &Light,
    sigma2: f64,
    c: &Matrix3<f64>,
    coherent: bool,
    exit_x: &Vector3<f64>,
    exit_y: &Vector3<f64>,
    r: &Vector3<f64>,
) -> Vector4<f64> {
    let k = light.k();
    let h = (r - light.col(2)) * k;
    let half = (light.theta_x + light.theta_y) * 0.5;
    let prec = [
        light.precision(&light.theta_x),
        light.precision(&light.theta_y),
        light.precision(&half),
    ];
    let csd = light.channel_csds();
    let mut total = nalgebra::Matrix3::<C64>::zeros();
    for a in 0..3 {
        let f = born_xi_integral(sigma2, c, (!coherent).then_some(&prec[a]), &h);
        total += csd[a] * C64::from(f);
    }
    total *= C64::from(k.powi(4) / (16.0 * PI * PI));
    let (ex, ey) = (exit_x.map(C64::from), exit_y.map(C64::from));
    let m = Matrix2::new(
        (ex.transpose() * total * ex)[0],
        (ex.transpose() * total * ey)[0],
        (ey.transpose() * total * ex)[0],
        (ey.transpose() * total * ey)[0],
    );
    stokes_of_csd(&m)
}

fn rot(axis: Vector3<f64>, a: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Unit::new_normalize(axis), a).matrix()
}

fn dir(theta: f64, phi: f64) -> Vector3<f64> {
    Vector3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// A polarized two-shape packet on a tilted, turned frame, and an anisotropic medium.
fn anisotropic_case() -> (Light, f64, Matrix3<f64>) {
    let q = rot(Vector3::new(0.3, -0.5, 0.8), 1.1) * rot(Vector3::z(), 0.4);
    let (tx, ty) = (
        Matrix2::new(4.0, 0.6, 0.6, 2.5),
        Matrix2::new(5.0, -0.3, -0.3, 3.0),
    );
    // |μ| within the Bochner bound of the two shapes.
    let b = gmueller::verify::strategy::bochner_bound(&tx, &ty).sqrt();
    let (s0, s1) = (1.7_f64, 0.4_f64);
    let r = (s0 * s0 - s1 * s1).sqrt() * 0.9 * b;
    let light = Light {
        q,
        theta_x: tx,
        theta_y: ty,
        sigma_zz: 1.5,
        stokes: Vector4::new(s0, s1, r * 0.6, r * 0.8),
        wavelength: 0.6,
    };
    let c = Matrix3::new(0.30, 0.05, -0.02, 0.05, 0.20, 0.04, -0.02, 0.04, 0.25);
    (light, 2.5e-5, c)
}

/// The medium for the oracle's `R = σ² exp(−½ ξᵀC⁻¹ξ)`.
fn gaussian_medium(sigma2: f64, c: &Matrix3<f64>) -> RandomMedium<GaussianPsd<f64, 3>, Dipole> {
    let corr = gmueller::gaussian::Gaussian::new(*c).unwrap();
    RandomMedium::new(
        GaussianPsd::from_autocorrelation(sigma2, &corr).unwrap(),
        Dipole,
    )
}

/// Exit directions: generic, near-forward, exact forward, exact backward, grazing to d̂.
fn exits(light: &Light) -> Vec<Vector3<f64>> {
    let d = light.col(2);
    let x = light.col(0);
    let mut v: Vec<Vector3<f64>> = [
        (0.3, 0.4),
        (1.2, 2.0),
        (2.0, -1.0),
        (2.9, 0.7),
        (FRAC_PI_2, 4.0),
    ]
    .iter()
    .map(|&(t, p)| light.q * dir(t, p))
    .collect();
    v.push(d);
    v.push(-d);
    v.push((d + x * 1e-5).normalize());
    v.push((-d + x * 3e-9).normalize());
    v
}

// ------------------------------------------------------------------ 1. the Born integral

/// The brute-force 3-D sum of the ξ-integral agrees with its closed form (the oracle's one
/// analytic step), for the anisotropic case at one exit.
#[test]
fn born_xi_integral_against_brute_force() {
    let (light, sigma2, c) = anisotropic_case();
    let r = light.q * dir(0.5, 1.0);
    let h = (r - light.col(2)) * light.k();
    let prec = light.precision(&light.theta_x);
    let ci = c.try_inverse().unwrap();
    let f = |xi: &Vector3<f64>| {
        let a = -0.5 * xi.dot(&((ci + prec) * xi));
        C64::from_polar(sigma2 * a.exp(), -h.dot(xi))
    };
    let brute = cube_quad::<3>(f, 4.5, 121);
    let closed = born_xi_integral(sigma2, &c, Some(&prec), &h);
    println!("ξ-integral: brute {brute:.12e}, closed {closed:.12e}");
    assert_close("Re", brute.re, closed, Tol::new(0.0, 1e-9));
    assert_close("Im", brute.im, 0.0, Tol::new(1e-9 * closed, 0.0));
}

/// `dI/dV` of `Full·Partial` (two shapes, polarized, finite `σ_zz`, tilted frame, anisotropic
/// medium) equals the Born oracle in every Stokes parameter, forward and backward included;
/// `Full·PlaneWave` the oracle without the envelope.
#[test]
fn differential_scattering_is_the_born_integral() {
    let (light, sigma2, c) = anisotropic_case();
    let medium = gaussian_medium(sigma2, &c);
    let packet = light.packet();
    for r in exits(&light) {
        for (coherent, name) in [(false, "Partial"), (true, "PlaneWave")] {
            let (got, g) = if coherent {
                let s = medium
                    .differential_scattering(&Kernel::<Full, PlaneWave>::default(), &packet, r)
                    .unwrap();
                (s.light.vector(), s.geometry)
            } else {
                let s = medium
                    .differential_scattering(&Kernel::<Full, Partial>::default(), &packet, r)
                    .unwrap();
                (s.light.vector(), s.geometry)
            };
            let f = g.exit_frame();
            assert!((f.k() - r.normalize()).norm() < 1e-15);
            let want = born_stokes(&light, sigma2, &c, coherent, &f.x(), &f.y(), &r.normalize());
            for i in 0..4 {
                assert_close(
                    &format!("{name} S{i} at {r:?}"),
                    got[i],
                    want[i],
                    Tol::new(1e-12 * want[0], 1e-11),
                );
            }
        }
    }
}

/// The one-weight levels are the Born integral of the `Θ_½` envelope for every channel:
/// `OneShape` equals the oracle run on a packet with `Θ_x = Θ_y = Θ_½` (same Stokes vector),
/// `Intensity` its `S0` with `m̄₀₀` alone (the S1 term of the dipole dropped).
#[test]
fn one_weight_levels() {
    let (mut light, sigma2, c) = anisotropic_case();
    let medium = gaussian_medium(sigma2, &c);
    let packet = light.packet();
    let half = (light.theta_x + light.theta_y) * 0.5;
    light.theta_x = half;
    light.theta_y = half;
    for r in exits(&light) {
        let one = medium
            .differential_scattering(&Kernel::<OneShape, Partial>::default(), &packet, r)
            .unwrap();
        let f = one.geometry.exit_frame();
        let want = born_stokes(&light, sigma2, &c, false, &f.x(), &f.y(), &r.normalize());
        for i in 0..4 {
            assert_close(
                "OneShape",
                one.light.vector()[i],
                want[i],
                Tol::new(1e-12 * want[0], 1e-11),
            );
        }
        let int = medium
            .differential_scattering(&Kernel::<Intensity, Partial>::default(), &packet, r)
            .unwrap();
        // [m̄ T S]₀ = m̄₀₀ S0 + m̄₀₁ S1' (S' = T S in the incident scattering-plane frame).
        let m = Dipole.mueller(r.normalize().dot(&light.col(2))).matrix();
        let s1 = light_s1_in_scattering_frame(&light, &one.geometry);
        let s0 = light.stokes[0];
        let intensity = want[0] * m[(0, 0)] * s0 / (m[(0, 0)] * s0 + m[(0, 1)] * s1);
        assert_close(
            "Intensity",
            int.light,
            intensity,
            Tol::new(1e-12 * want[0], 1e-11),
        );
    }
}

/// `S1` of the packet in the incident scattering-plane frame (the dipole's `M₀₁` multiplies it).
fn light_s1_in_scattering_frame(
    light: &Light,
    g: &gmueller::medium::ScatteringGeometry<f64>,
) -> f64 {
    let from = Frame::new(light.col(0), light.col(1), light.col(2)).unwrap();
    let s = Stokes::new(
        light.stokes[0],
        light.stokes[1],
        light.stokes[2],
        light.stokes[3],
    )
    .unwrap();
    gmueller::frame::stokes_to_frame(&s, &from, g.incident_frame()).s1()
}

/// The `Partial` weight `K³` is the crate's `volume_coherence_term` (itself checked against the
/// 6-D closed form of S2.10 in `tests/interaction/s2_10.rs`), channel by channel.
#[test]
fn partial_weight_is_volume_coherence_term() {
    let (light, sigma2, c) = anisotropic_case();
    let medium = gaussian_medium(sigma2, &c);
    let packet = light.packet();
    for r in exits(&light) {
        let h = (r.normalize() - light.col(2)) * light.k();
        for (ch, theta) in [
            (Channel::X, light.theta_x),
            (Channel::Y, light.theta_y),
            (Channel::Half, (light.theta_x + light.theta_y) * 0.5),
        ] {
            let xi = gmueller::gaussian::Gaussian::new(light.precision(&theta)).unwrap();
            let ours = Partial(ClosedForm)
                .log_volume_weight(&medium.psd, Some(&xi), &h)
                .exp();
            let term = volume_coherence_term(&medium.psd, &ClosedForm, &packet, ch, &h).unwrap();
            assert_close(
                "K³ vs volume_coherence_term",
                ours,
                term,
                Tol::new(1e-300, 1e-12),
            );
        }
    }
}

// ------------------------------------------------------------------ 2. the constant and σ_s

/// `∫₋₁¹ e^{−a(1−μ)} (1 + μ²) dμ` in closed form (`t = 1 − μ`: `∫₀² e^{−at}(2 − 2t + t²) dt`),
/// by its Taylor series for small `a`.
fn rayleigh_gauss_integral(a: f64) -> f64 {
    if a < 1.0 {
        // ∫₀² tⁿ e^{−at} dt = Σ_j (−a)^j 2^{n+j+1}/(j! (n+j+1))
        let m = |n: i32| {
            let (mut s, mut term) = (0.0, 1.0);
            for j in 0..80 {
                s += term * 2f64.powi(n + j + 1) / f64::from(n + j + 1);
                term *= -a / f64::from(j + 1);
            }
            s
        };
        2.0 * m(0) - 2.0 * m(1) + m(2)
    } else {
        let e = (-2.0 * a).exp();
        let i0 = -(-2.0 * a).exp_m1() / a;
        let i1 = (1.0 - e * (1.0 + 2.0 * a)) / (a * a);
        let i2 = (2.0 - e * (2.0 + 4.0 * a + 4.0 * a * a)) / (a * a * a);
        2.0 * i0 - 2.0 * i1 + i2
    }
}

/// `σ_s` of an isotropic Gaussian medium under a plane wave, exactly (module docs of
/// `gmueller::medium`): `(k⁴/16π²)(2π)^{3/2} σ² ℓ³ π ∫₋₁¹ e^{−k²ℓ²(1−μ)} (1 + μ²) dμ`, for every
/// polarization of the light (an isotropic medium), `kℓ` from 1e-3 to 60.
#[test]
fn scattering_coefficient_of_a_gaussian_medium() {
    let lambda = 0.5;
    let k = TAU / lambda;
    let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let mut worst = 0.0_f64;
    for &ell in &[1e-4, 1e-3, 0.01, 0.05, 0.2, 1.0, 5.0] {
        let sigma = 3e-3;
        let medium = RandomMedium::new(
            GaussianPsd::<f64, 3>::isotropic(sigma, ell).unwrap(),
            Dipole,
        );
        let exact = k.powi(4) / (16.0 * PI * PI)
            * TAU.powf(1.5)
            * sigma
            * sigma
            * ell.powi(3)
            * PI
            * rayleigh_gauss_integral(k * k * ell * ell);
        for s in [
            Stokes::unpolarized(1.0).unwrap(),
            Stokes::new(2.0, 1.2, -0.9, 1.1).unwrap(),
        ] {
            let light =
                WavePacket::from_stokes(s, CoherenceShape::isotropic(5.0).unwrap(), frame, lambda)
                    .unwrap();
            let phase = PhaseFunction::new(&medium, Kernel::<Full, PlaneWave>::default());
            let got = phase.prepare(&light).unwrap().scattering_coefficient();
            let rel = (got / exact - 1.0).abs();
            println!(
                "kℓ = {:.1e}: σ_s = {got:.12e}, exact {exact:.12e}, rel {rel:.1e}",
                k * ell
            );
            worst = worst.max(rel);
        }
    }
    assert!(worst < 1e-12, "worst relative error {worst:e}");
}

/// The absolute constant `k⁴/16π²`: a medium whose `⟨δε²⟩ V_c` is that of a dilute cloud of
/// small spheres (`N δε² V²`, `V = 4πa³/3`) scatters `N` times the textbook Rayleigh
/// cross-section of one sphere, `C_sca = (8π/3) k⁴ a⁶ |(m² − 1)/(m² + 2)|²` (Bohren & Huffman
/// 1983, §5.1; van de Hulst 1957, §6.1), `m² = 1 + δε`, up to `O(δε)` and `O((ka)²)`; and its
/// phase function is Rayleigh's, `(3/16π)(1 + cos²Θ)` (Chandrasekhar 1950, §17).
#[test]
fn rayleigh_limit_against_small_spheres() {
    let lambda = 0.5;
    let k = TAU / lambda;
    let (a, deps, n) = (1e-4_f64, 1e-6_f64, 3e5_f64); // radius µm, δε, spheres per µm³
    let v = 4.0 * PI * a.powi(3) / 3.0;
    let ell = a;
    // σ² (2π)^{3/2} ℓ³ = N δε² V²
    let sigma2 = n * deps * deps * v * v / (TAU.powf(1.5) * ell.powi(3));
    let medium = RandomMedium::new(
        GaussianPsd::<f64, 3>::isotropic(sigma2.sqrt(), ell).unwrap(),
        Dipole,
    );
    // (m² − 1)/(m² + 2) with m² = 1 + δε, formed without the rounding of 1 + δε.
    let c_sca = 8.0 * PI / 3.0 * k.powi(4) * a.powi(6) * (deps / (3.0 + deps)).powi(2);
    let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    let light = WavePacket::from_stokes(
        Stokes::unpolarized(1.0).unwrap(),
        CoherenceShape::isotropic(10.0).unwrap(),
        frame,
        lambda,
    )
    .unwrap();
    let phase = PhaseFunction::new(&medium, Kernel::<Full, PlaneWave>::default());
    let inc = phase.prepare(&light).unwrap();
    let sigma_s = inc.scattering_coefficient();
    let ratio = sigma_s / (n * c_sca);
    println!(
        "σ_s = {sigma_s:.9e} /µm, N C_sca = {:.9e}: ratio − 1 = {:.2e} ((ka)² = {:.1e}, δε = {deps:.0e})",
        n * c_sca,
        ratio - 1.0,
        (k * a).powi(2)
    );
    assert_close("σ_s / (N C_sca)", ratio, 1.0, Tol::new(0.0, 2e-6));
    // The deviation is the two first-order corrections: −(kℓ)² from the Gaussian form factor
    // (∫(1 − μ)(1 + μ²) = ∫(1 + μ²)) and +2δε/3 from |(m² − 1)/(m² + 2)|² = (δε/3)²(1 + δε/3)⁻².
    let predicted = -(k * ell).powi(2) + 2.0 * deps / 3.0;
    assert_close("ratio − 1", ratio - 1.0, predicted, Tol::new(2e-11, 0.0));
    // (k⁴/6π) ⟨δε²⟩ V_c, V_c = (2π)^{3/2} ℓ³
    let rayleigh = k.powi(4) / (6.0 * PI) * sigma2 * TAU.powf(1.5) * ell.powi(3);
    assert_close(
        "σ_s vs (k⁴/6π)⟨δε²⟩V_c",
        sigma_s,
        rayleigh,
        Tol::new(0.0, 2e-6),
    );
    for t in [0.0, 0.7, FRAC_PI_2, 2.4, PI] {
        let r = dir(t, 0.3);
        let f = phase.eval(&inc, r).unwrap().phase;
        let c = t.cos();
        let want = 3.0 / (16.0 * PI) * (1.0 + c * c);
        assert_close(
            "F₀₀ = (3/16π)(1 + cos²Θ)",
            f.matrix()[(0, 0)],
            want,
            Tol::new(0.0, 2e-6),
        );
        // Bohren & Huffman's small-sphere matrix in their basis (Q = I_∥ − I_⊥):
        // S11 = ½(1 + c²), S12 = ½(c² − 1), S33 = S44 = c; ours has x̂ = ⊥ (S1 = I_⊥ − I_∥, and
        // S2 with it), so S12 and S21 change sign. Normalised by (3/8π).
        let bh = bohren_huffman(c);
        let d = nalgebra::Matrix4::from_diagonal(&Vector4::new(1.0, -1.0, -1.0, 1.0));
        let literal = d * bh * d * (3.0 / (8.0 * PI));
        // The matrix is in the scattering-plane frames: remove the packet → scattering-frame
        // rotation T that F includes.
        let g = phase.eval(&inc, r).unwrap().geometry;
        let t_in = gmueller::frame::frame_change_mueller(&frame, g.incident_frame()).matrix();
        let in_plane = f.matrix() * t_in.transpose();
        gmueller::verify::check::assert_mueller_close(
            "Rayleigh phase matrix",
            &in_plane,
            &literal,
            Tol::new(1e-12, 2e-6),
        );
    }
}

/// Bohren & Huffman's small-sphere scattering matrix (their basis, `Q = I_∥ − I_⊥`),
/// unnormalised.
fn bohren_huffman(c: f64) -> nalgebra::Matrix4<f64> {
    #[rustfmt::skip]
    let m = nalgebra::Matrix4::new(
        0.5 * (1.0 + c * c), 0.5 * (c * c - 1.0), 0.0, 0.0,
        0.5 * (c * c - 1.0), 0.5 * (1.0 + c * c), 0.0, 0.0,
        0.0, 0.0, c, 0.0,
        0.0, 0.0, 0.0, c,
    );
    m
}

/// The dipole matrix is S1.7 of the Jones matrix `J_ab = ê_o,a · (I − r̂r̂ᵀ) ê_i,b` between the
/// scattering-plane frames (`diag(1, cos Θ)`), and Mueller–Jones (realizable, DoP-preserving).
#[test]
fn dipole_is_the_projected_field() {
    for t in [0.0, 1e-9, 0.3, 1.2, FRAC_PI_2, 2.8, PI] {
        let d = Vector3::z();
        let r = dir(t, 0.0);
        let perp = if t.sin().abs() > 1e-12 {
            d.cross(&r).normalize()
        } else {
            Vector3::x()
        };
        let (xi, yi) = (perp, d.cross(&perp));
        let (xo, yo) = (perp, r.cross(&perp));
        let p = nalgebra::Matrix3::identity() - r * r.transpose();
        let j = Matrix2::new(
            xo.dot(&(p * xi)),
            xo.dot(&(p * yi)),
            yo.dot(&(p * xi)),
            yo.dot(&(p * yi)),
        )
        .map(C64::from);
        let literal = gmueller::verify::oracle::mueller_literal(&j);
        gmueller::verify::check::assert_mueller_close(
            &format!("dipole at Θ = {t}"),
            &Dipole.mueller(t.cos()).matrix(),
            &literal,
            Tol::new(1e-15, 1e-14),
        );
        gmueller::verify::check::assert_realizable("dipole", &literal, 1e-12);
        let mut depolarizer = nalgebra::Matrix4::zeros();
        depolarizer[(0, 0)] = 1.0;
        assert_eq!(Scalar.mueller(t.cos()).matrix(), depolarizer);
        assert_close(
            "m00",
            Dipole.m00(t.cos()),
            literal[(0, 0)],
            Tol::new(1e-15, 1e-15),
        );
    }
}

// ------------------------------------------------------------------ 3. σ_s by adaptive quadrature

/// `∫ g dΩ` about d̂ in Lambert coordinates `(u, φ)`, `dΩ = u du dφ/k²`, adaptive G8/G12 on
/// radial panels with edges at `s · 2^j` (s the lobe's scale) and 16 azimuthal panels.
fn sphere_integral(
    d: &Frame<f64>,
    k: f64,
    s: f64,
    tol: f64,
    g: &dyn Fn(&Vector3<f64>) -> f64,
) -> f64 {
    let mut edges = vec![0.0];
    let mut e = s / 16.0;
    while e < 2.0 * k {
        edges.push(e);
        e *= 2.0;
    }
    edges.push(2.0 * k);
    let mut total = 0.0;
    for w in edges.windows(2) {
        let mut outer = |u: f64| {
            let a2 = (u / (2.0 * k)).powi(2).min(1.0);
            let (cos, sin) = (1.0 - 2.0 * a2, 2.0 * (a2 * (1.0 - a2)).sqrt());
            let mut inner = |phi: f64| {
                let r = d.k() * cos + (d.x() * phi.cos() + d.y() * phi.sin()) * sin;
                g(&r.normalize())
            };
            u / (k * k) * integrate(&mut inner, 0.0, TAU, 16, tol)
        };
        total += integrate(&mut outer, w[0], w[1], 2, tol);
    }
    total
}

pub(crate) fn check_coefficient<P, Pol, Coh>(
    name: &str,
    medium: &RandomMedium<P, Dipole>,
    kernel: Kernel<Pol, Coh>,
    packet: &WavePacket<f64>,
    scale: f64,
    tol: f64,
) -> f64
where
    P: gmueller::psd::Psd<f64, 3>,
    Pol: PolarizationModel,
    Coh: VolumeCoherence<f64, P>,
{
    let phase = PhaseFunction::new(medium, kernel);
    let inc = phase.prepare(packet).unwrap();
    let s0 = packet.stokes().s0();
    let k = packet.wavenumber();
    let sigma = inc.scattering_coefficient();
    // The reference: the differential scattering, integrated adaptively.
    let reference = sphere_integral(packet.frame(), k, scale, 1e-11 * sigma, &|r| {
        let l = phase.differential_scattering(&inc, *r).unwrap().light;
        <Pol::Throughput<f64> as Throughput<f64>>::intensity(&l) / s0
    });
    // The phase matrix's normalisation on the packet's own Stokes vector.
    let light = <Pol::Throughput<f64> as Throughput<f64>>::light(&packet.stokes());
    let norm = sphere_integral(packet.frame(), k, scale, 1e-11, &|r| {
        let f = phase.eval(&inc, *r).unwrap().phase;
        <Pol::Throughput<f64> as Throughput<f64>>::intensity(&f.apply(&light)) / s0
    });
    let rel = (sigma / reference - 1.0).abs();
    println!(
        "{name}: σ_s = {sigma:.12e}, adaptive {reference:.12e}, rel {rel:.1e}; ∫F S/S0 = {norm:.12}"
    );
    assert!(rel <= tol, "{name}: relative error {rel:e} > {tol:e}");
    assert_close(
        &format!("{name}: ∫[F S]₀ dΩ / S0"),
        norm,
        1.0,
        Tol::new(0.0, 2.0 * tol + 1e-10),
    );
    rel
}

/// `σ_s` (the crate's fixed rule) against adaptive quadrature of `dI/dV` over the sphere, for
/// media and packets whose integrand is not symmetric about d̂ (anisotropic medium and
/// coherence, two shapes, polarized) and for the other PSDs and levels; and the phase matrix
/// integrates to 1 on the packet's Stokes vector.
#[test]
fn scattering_coefficient_against_adaptive_quadrature() {
    let (light, sigma2, c) = anisotropic_case();
    let medium = gaussian_medium(sigma2, &c);
    let packet = light.packet();
    check_coefficient(
        "anisotropic Full·Partial",
        &medium,
        Kernel::<Full, Partial>::default(),
        &packet,
        1.0,
        1e-9,
    );
    check_coefficient(
        "anisotropic Full·PlaneWave",
        &medium,
        Kernel::<Full, PlaneWave>::default(),
        &packet,
        1.0,
        1e-9,
    );
    check_coefficient(
        "anisotropic OneShape·Incoherent",
        &medium,
        Kernel::<OneShape, Incoherent>::default(),
        &packet,
        0.5,
        1e-9,
    );
    check_coefficient(
        "anisotropic Intensity·Partial",
        &medium,
        Kernel::<Intensity, Partial>::default(),
        &packet,
        1.0,
        1e-9,
    );
    // Forward-peaked: ℓ = 4 µm against λ = 0.6 µm, anisotropic 20 µm × 60 µm coherence.
    let fwd = RandomMedium::new(GaussianPsd::<f64, 3>::isotropic(1e-3, 4.0).unwrap(), Dipole);
    let mut narrow = light;
    narrow.theta_x = Matrix2::new(400.0, 300.0, 300.0, 3600.0);
    narrow.theta_y = narrow.theta_x;
    narrow.stokes = Vector4::new(1.0, 0.3, 0.2, -0.4);
    check_coefficient(
        "forward-peaked Full·Partial",
        &fwd,
        Kernel::<Full, Partial>::default(),
        &narrow.packet(),
        0.25,
        1e-9,
    );
    // The Debye–Bueche medium (K-correlation γ = 3) and a K-correlation with a heavy tail.
    for (t, gamma) in [(0.25, 3.0), (1.0, 2.2)] {
        let kc = RandomMedium::new(KCorrelation::<f64, 3>::new(1e-6, t, gamma).unwrap(), Dipole);
        check_coefficient(
            "K-correlation PlaneWave",
            &kc,
            Kernel::<Full, PlaneWave>::default(),
            &packet,
            1.0 / t.sqrt(),
            1e-9,
        );
        check_coefficient(
            "K-correlation Partial (Gauss–Hermite blur)",
            &kc,
            Kernel::<Full, _>::new(Partial(gmueller::psd::GaussHermite::new(6).unwrap())),
            &packet,
            1.0 / t.sqrt(),
            3e-7,
        );
    }
    // A mixture: the 3-D K-correlation's Gaussian fit.
    let (mix, _) = KCorrelation::<f64, 3>::new(1e-6, 0.25, 3.0)
        .unwrap()
        .mixture_fit(16)
        .unwrap();
    let mix = RandomMedium::new(mix, Dipole);
    check_coefficient(
        "mixture Full·Partial",
        &mix,
        Kernel::<Full, Partial>::default(),
        &packet,
        2.0,
        1e-9,
    );
}
