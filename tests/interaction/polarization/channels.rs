//! Verifies the `Full` polarization level of the S2.20 kernel channel by channel, for polarized
//! light with `Θ_x ≠ Θ_y`, against an oracle that never calls the crate: the S2.10 double
//! integral of each channel in closed form, combined at the field level (CSD and Jones matrices,
//! no Mueller matrix), cross-checked by a second test-side route (literal S1.7 Mueller matrices,
//! S2.4's `T`). `OneShape` is compared with the same oracle with `Θ_½` in every channel (its
//! documented approximation), and its distance from the true oracle is printed.
//!
//! # The oracle (derivation)
//! The packet (Definition 3.1, `src/packet.rs`) has the two-point CSD matrix, in its frame
//! (x̂, ŷ, k̂), at a separation ξ,
//! ```text
//! C(ξ) = e^{ik k̂·ξ} [[ S_x g^{Θ_x}(ξ),        c g^{Θ_½}(ξ) ],
//!                     [ c* g^{Θ_½}(ξ),  S_y g^{Θ_y}(ξ)   ]],   c = ⟨E_x E_y*⟩ = (S2 − i S3)/2
//! S_x = (S0 + S1)/2,  S_y = (S0 − S1)/2,  Θ_½ = (Θ_x + Θ_y)/2            (S2.16 in CSD form)
//! ```
//! (its `A_mül` image is the packet's `S_x g^{Θ_x}(1,1,0,0) + S_y g^{Θ_y}(1,−1,0,0) +
//! g^{Θ_½}(0,0,S2,S3)`). S2.2 carries the CSD into the incident s/p basis by `τ C τᵀ` (S2.3,
//! `τ_ij = ê′_i·ê_j`); the matter acts as `J C J†` (S1.4) with the Jones matrix of the pBSDF,
//! constant over the lobe (S2.19); S2.10's double integral then acts entry by entry on the
//! spatial factors, each being one channel's integral, divided by the area (the window drops out
//! exactly, `tests/interaction/s2_10.rs`):
//! ```text
//! f_α(h_t) = ∫ e^{−i h·ξ} R(ξ) g^{Θ_α}(Qᵀξ) d²ξ = σ² 2π |G_α|^{−1/2} exp(−½ h_tᵀ G_α⁻¹ h_t),
//! G_α = C_R⁻¹ + Ξ_α,   Ξ_α = Bᵀ Q Θ_α⁻¹ Qᵀ B,   h = k(r̂ + ŝ)
//! ```
//! for `R(ξ) = σ² exp(−½ ξᵀ C_R⁻¹ ξ)` (`GaussianPsd::isotropic(σ, ℓ)`: `C_R = ℓ² I`); the specular
//! part is the same with `R ≡ 1` (`C_R⁻¹ = 0`, `σ² = 1`: the smooth mean surface), the
//! incoherent level with `R ≡ σ²`, the plane wave `f = 2π p(h_t)` for every channel. So
//! ```text
//! L = (cos θ_o / λ²) α · Stokes( J τ [F ∘ C₀] τᵀ J† ),   F = [[f_x, f_½], [f_½, f_y]],
//! α = exp(−(kσ(cos θ_i + cos θ_o))²),   Stokes(C) = (C₁₁ + C₂₂, C₁₁ − C₂₂, 2 Re C₁₂, 2 Im C₂₁)
//! ```
//! with `C₀ = C(0)` and `∘` the entrywise product: the x and y field components carry their own
//! shapes, their correlation the mean shape. Germer's Rayleigh–Rice factors give the scattering
//! `J = 2k cos θ_i [[ss, ps], [sp, pp]]` (tests/common/oracle.rs); the specular pBSDF is a
//! constant, general complex Jones matrix chosen here (`ConstantMueller` of its literal S1.7
//! Mueller matrix). The oracle is closed form: its error is rounding, ~1e-14 relative.
//!
//! # The test sees the bug (mutations of the crate, run once, never committed)
//! `full_level_matches_channel_oracle` prints, per level and part, the relative difference
//! `max|a − b| / max|b|` of the crate from the oracle over its 147 cases (3 scenes × 7
//! polarizations × 7 exits); the tolerance is 1e-10 and the unmutated crate stays below 5.2e-13.
//! With `src/interaction/mod.rs` mutated:
//! ```text
//!                                      Partial scattered        Partial specular   Incoherent scat.
//! mutation                             min     median  max      min      median    min      median
//! Θ_x ↔ Θ_y (PreparedPacket::new)      1.2e-1  6.2e-1  1.2e2    7.3e-2   9.2e-1    6.0e-2   9.0e-1
//! Channel::Half for every channel      2.8e-2  3.2e-1  6.1e0    7.5e-3   4.9e-1    7.5e-3   5.2e-1
//! S_x, S_y split in the s/p frame      3.9e-2  4.3e-1  1.0e2    3.5e-2   6.2e-1    3.0e-2   6.3e-1
//! ```
//! every case fails at every shape-using level (588 of 882 comparisons; `PlaneWave`, which uses
//! no shapes, is unchanged at ≤ 2.3e-14), and so do the f32 test and the proptest; the rest of
//! the interaction tests (`interaction::laws`, `interaction::s2_10`, `interaction::prepared`) pass
//! with each mutation. `channel_oracle_is_sensitive_to_the_shapes` asserts, test-side, that the
//! oracle separates the first two readings by > 1e-2 in every scene and polarization.

use crate::common;

use std::f64::consts::{PI, TAU};

use common::oracle::{
    a_mul_inverse_is_inverse, coherence_integral, exit_azimuth, gaussian_psd, mueller_literal,
    rayleigh_rice_factors, rotation_literal, section, sp_basis, stokes_of_csd, tau,
};
use common::{Tol, assert_all_close};
use gmueller::Real;
use gmueller::frame::Frame;
use gmueller::interaction::coherence::CoherenceWeights;
use gmueller::interaction::pbsdf::{ConstantMueller, RayleighRice};
use gmueller::interaction::polarization::{PolarizationModel, Response};
use gmueller::interaction::{
    Full, Geometry, Incoherent, Kernel, OneShape, Partial, PlaneWave, RoughSurface,
};
use gmueller::mueller::Mueller;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::GaussianPsd;
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3, Vector4};
use num_complex::Complex;
use proptest::prelude::*;

type C64 = Complex<f64>;

// ------------------------------------------------------------------ scene (test-side)

/// One interaction: light, surface and material, all as plain numbers.
#[derive(Debug, Clone)]
struct Scene {
    lambda: f64,
    /// Incidence polar angle and the azimuth of the forward direction (world).
    theta_i: f64,
    phi_i: f64,
    /// The packet frame turned by ψ about k̂ from the incident s/p frame.
    psi: f64,
    /// The surface tangents turned by β about n̂ = ẑ.
    beta: f64,
    theta_x: Matrix2<f64>,
    theta_y: Matrix2<f64>,
    stokes: [f64; 4],
    sigma: f64,
    ell: f64,
    eta: C64,
}

/// A rotated anisotropic shape `R(a) diag(w₁², w₂²) R(a)ᵀ` (length²).
fn shape(w1: f64, w2: f64, a: f64) -> Matrix2<f64> {
    let (s, c) = a.sin_cos();
    let r = Matrix2::new(c, -s, s, c);
    r * Matrix2::new(w1 * w1, 0.0, 0.0, w2 * w2) * r.transpose()
}

fn det2(m: &Matrix2<f64>) -> f64 {
    m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)]
}

/// The realizability bound `|μ|² ≤ √(|Θ_x||Θ_y|)/|Θ_½|` (Bochner; `src/packet.rs` docs).
fn mu2_bound(tx: &Matrix2<f64>, ty: &Matrix2<f64>) -> f64 {
    (det2(tx) * det2(ty)).sqrt() / det2(&((tx + ty) * 0.5))
}

fn dir(theta: f64, phi: f64) -> Vector3<f64> {
    Vector3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// The test's own vectors for a scene: surface tangents, ŝ, the incident s/p basis and the
/// packet frame `Q = [x̂ ŷ k̂]`.
struct Vectors {
    t1: Vector3<f64>,
    t2: Vector3<f64>,
    to_source: Vector3<f64>,
    sp_in: [Vector3<f64>; 2],
    q: Matrix3<f64>,
}

impl Scene {
    fn k(&self) -> f64 {
        TAU / self.lambda
    }

    fn vectors(&self) -> Vectors {
        let (sb, cb) = self.beta.sin_cos();
        let t1 = Vector3::new(cb, sb, 0.0);
        let t2 = Vector3::new(-sb, cb, 0.0);
        // ŝ toward the source: the specular direction dir(θ_i, φ_i) mirrored in the normal.
        let (st, ct) = self.theta_i.sin_cos();
        let to_source = Vector3::new(-st * self.phi_i.cos(), -st * self.phi_i.sin(), ct);
        let d = -to_source;
        let sp_in = sp_basis(&d, &Vector3::z());
        let (sp, cp) = self.psi.sin_cos();
        let x = sp_in[0] * cp + sp_in[1] * sp;
        let y = sp_in[1] * cp - sp_in[0] * sp;
        Vectors {
            t1,
            t2,
            to_source,
            sp_in,
            q: Matrix3::from_columns(&[x, y, d]),
        }
    }

    /// The exit direction at exit-tangent offset `delta` (world x, y) from the specular one.
    fn exit_near_specular(&self, delta: Vector2<f64>) -> Vector3<f64> {
        let spec = dir(self.theta_i, self.phi_i);
        let rt = Vector2::new(spec.x, spec.y) + delta;
        // Below the horizon (|r_t| ≥ 1): z = 0, which every caller skips.
        Vector3::new(rt.x, rt.y, (1.0 - rt.norm_squared()).max(0.0).sqrt())
    }
}

/// The coherence levels the oracle knows.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Level {
    Partial,
    Incoherent,
    PlaneWave,
}

/// The oracle's answer: specular and scattered Stokes radiances in the exit s/p frame.
#[derive(Debug, Clone, Copy)]
struct Expected {
    specular: Vector4<f64>,
    scattered: Vector4<f64>,
    /// `(f_x, f_y, f_½)` of the specular and of the scattered part, to report how different
    /// the channels are.
    channels: [[f64; 3]; 2],
}

/// Which shapes the oracle gives the x, y and correlation channels.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shapes {
    /// The physics: `Θ_x`, `Θ_y`, `Θ_½`.
    True,
    /// `Θ_½` for every channel (what `OneShape` computes).
    AllHalf,
    /// `Θ_y`, `Θ_x`, `Θ_½` (a swapped-channel bug).
    Swapped,
}

/// The oracle of the module docs, by the field (CSD) route, and — asserted equal to it — by the
/// Stokes route `front · M T Σ_α f_α S_α` with literal S1.7/S2.4 matrices.
fn oracle(
    sc: &Scene,
    exit: &Vector3<f64>,
    level: Level,
    shapes: Shapes,
    j_spec: &Matrix2<C64>,
) -> Expected {
    let v = sc.vectors();
    let n = Vector3::z();
    let k = sc.k();
    let (ci, co) = (v.to_source.dot(&n), exit.dot(&n));
    let h = (exit + v.to_source) * k;
    let ht = Vector2::new(h.dot(&v.t1), h.dot(&v.t2));
    let half = (sc.theta_x + sc.theta_y) * 0.5;
    let [tx, ty, th] = match shapes {
        Shapes::True => [sc.theta_x, sc.theta_y, half],
        Shapes::AllHalf => [half, half, half],
        Shapes::Swapped => [sc.theta_y, sc.theta_x, half],
    };
    let sigma2 = sc.sigma * sc.sigma;
    let c_inv = Matrix2::identity() / (sc.ell * sc.ell);
    let weights = |theta: &Matrix2<f64>| -> (f64, f64) {
        let xi = section(&v.q, theta, 0.0, &v.t1, &v.t2);
        let spec = coherence_integral(1.0, &Matrix2::zeros(), &xi, &ht);
        match level {
            Level::Partial => (spec, coherence_integral(sigma2, &c_inv, &xi, &ht)),
            Level::Incoherent => (
                spec,
                coherence_integral(sigma2, &Matrix2::zeros(), &xi, &ht),
            ),
            Level::PlaneWave => {
                let c = Matrix2::identity() * (sc.ell * sc.ell);
                (0.0, TAU * gaussian_psd(sigma2, &c, &ht))
            }
        }
    };
    let (wx, wy, wh) = (weights(&tx), weights(&ty), weights(&th));
    let alpha = (-(k * sc.sigma * (ci + co)).powi(2)).exp();
    let front = co / (sc.lambda * sc.lambda) * alpha;
    // Jones matrices from the incident to the exit s/p basis.
    let sp_out = sp_basis(exit, &n);
    let (cphi, sphi) = exit_azimuth(&v.sp_in[0], &sp_out[0], &n);
    let eps = sc.eta * sc.eta;
    let j_scat = rayleigh_rice_factors(eps, ci, co, cphi, sphi) * C64::new(2.0 * k * ci, 0.0);
    // Field route.
    let s = sc.stokes;
    let (sx, sy) = ((s[0] + s[1]) * 0.5, (s[0] - s[1]) * 0.5);
    let corr = C64::new(s[2], -s[3]) * 0.5; // ⟨E_x E_y*⟩
    let packet_basis = [v.q.column(0).into(), v.q.column(1).into()];
    let t = tau(packet_basis, v.sp_in).map(|x| C64::new(x, 0.0));
    let field = |fx: f64, fy: f64, fh: f64, j: &Matrix2<C64>| {
        let c0 = Matrix2::new(
            C64::new(sx * fx, 0.0),
            corr * fh,
            corr.conj() * fh,
            C64::new(sy * fy, 0.0),
        );
        let out = j * t * c0 * t.transpose() * j.adjoint();
        stokes_of_csd(&out) * front
    };
    let specular = field(wx.0, wy.0, wh.0, j_spec);
    let scattered = field(wx.1, wy.1, wh.1, &j_scat);
    // Stokes route, with S2.16's channel vectors.
    let tm = rotation_literal(packet_basis, v.sp_in);
    // Returns the result and the size of its terms before cancellation, |M| |T| Σ f_α |S_α|
    // (entrywise absolute values): both routes round relative to the latter.
    let stokes_route = |fx: f64, fy: f64, fh: f64, j: &Matrix2<C64>| {
        let sx_v = Vector4::new(sx, sx, 0.0, 0.0) * fx;
        let sy_v = Vector4::new(sy, -sy, 0.0, 0.0) * fy;
        let sh_v = Vector4::new(0.0, 0.0, s[2], s[3]) * fh;
        let m = mueller_literal(j);
        let terms = m.abs() * tm.abs() * (sx_v.abs() + sy_v.abs() + sh_v.abs()) * front;
        (m * tm * (sx_v + sy_v + sh_v) * front, terms.amax())
    };
    for (a, (b, terms), what) in [
        (specular, stokes_route(wx.0, wy.0, wh.0, j_spec), "specular"),
        (
            scattered,
            stokes_route(wx.1, wy.1, wh.1, &j_scat),
            "scattered",
        ),
    ] {
        assert_all_close(
            &format!("oracle: field route vs Stokes route ({what})"),
            a.iter().copied(),
            b.iter().copied(),
            Tol::new(1e-13 * terms + 1e-300, 0.0),
        );
    }
    Expected {
        specular,
        scattered,
        channels: [[wx.0, wy.0, wh.0], [wx.1, wy.1, wh.1]],
    }
}

/// A general complex Jones matrix for the specular pBSDF (a lossy retarder–diattenuator with
/// cross-coupling; any Jones matrix gives a realizable, non-depolarizing Mueller matrix).
fn specular_jones() -> Matrix2<C64> {
    Matrix2::new(
        C64::new(0.62, 0.21),
        C64::new(0.08, -0.17),
        C64::new(-0.12, 0.09),
        C64::new(-0.35, 0.44),
    )
}

// ------------------------------------------------------------------ the crate, from the scene

type Material<T> = RoughSurface<GaussianPsd<T, 2>, ConstantMueller<T>, RayleighRice<T>>;

fn crate_setup<T: Real>(sc: &Scene) -> (WavePacket<T>, Frame<T>, Material<T>) {
    let v = sc.vectors();
    let lit3 = |x: Vector3<f64>| x.map(T::lit);
    let col = |j: usize| -> Vector3<f64> { v.q.column(j).into() };
    let frame = Frame::new(lit3(col(0)), lit3(col(1)), lit3(col(2))).unwrap();
    let surface = Frame::new(lit3(v.t1), lit3(v.t2), Vector3::z()).unwrap();
    let s = sc.stokes.map(T::lit);
    let packet = WavePacket::new(
        Stokes::new(s[0], s[1], s[2], s[3]).unwrap(),
        CoherenceShape::new(sc.theta_x.map(T::lit)).unwrap(),
        CoherenceShape::new(sc.theta_y.map(T::lit)).unwrap(),
        frame,
        T::lit(sc.lambda),
    )
    .unwrap();
    let m_spec = mueller_literal(&specular_jones()).map(T::lit);
    let material = RoughSurface {
        psd: GaussianPsd::isotropic(T::lit(sc.sigma), T::lit(sc.ell)).unwrap(),
        specular: ConstantMueller(Mueller::from_matrix(m_spec).unwrap()),
        scatter: RayleighRice::new(Complex::new(T::lit(sc.eta.re), T::lit(sc.eta.im))).unwrap(),
    };
    (packet, surface, material)
}

fn run<T, Pol, Coh>(sc: &Scene, exit: &Vector3<f64>) -> Response<T>
where
    T: Real,
    Pol: PolarizationModel<Output<T> = Response<T>>,
    Coh: CoherenceWeights<T, GaussianPsd<T, 2>> + Default,
{
    let (packet, surface, material) = crate_setup::<T>(sc);
    let g = Geometry::for_packet(&packet, &surface, exit.map(T::lit)).unwrap();
    Kernel::<Pol, Coh>::default().evaluate(&material, &packet, &g)
}

fn to64<T: Real>(s: Stokes<T>) -> Vector4<f64> {
    s.vector().map(|x| x.to_f64())
}

/// `max|a − b| / max|b|` (0 when both vanish); max norms, as the Euclidean norm's squares
/// underflow for the ~1e-170 radiances far from the specular lobe.
fn rel(a: &Vector4<f64>, b: &Vector4<f64>) -> f64 {
    let d = (a - b).amax();
    if d == 0.0 { 0.0 } else { d / b.amax() }
}

/// Component-wise `a ≈ b` within `rel_tol · max|b|` (the Stokes vector's scale) plus 1e-300.
#[track_caller]
fn assert_stokes(what: &str, a: &Vector4<f64>, b: &Vector4<f64>, rel_tol: f64) {
    assert_all_close(
        what,
        a.iter().copied(),
        b.iter().copied(),
        Tol::new(rel_tol * b.amax() + 1e-300, 0.0),
    );
}

// ------------------------------------------------------------------ the cases

/// Inputs: x̂-, ŷ-, ±45°-, right/left-circular and elliptical light (the correlated ones at 0.95
/// of the realizability bound for the scene's shapes).
fn polarizations(tx: &Matrix2<f64>, ty: &Matrix2<f64>) -> Vec<(&'static str, [f64; 4])> {
    let m = 0.95 * mu2_bound(tx, ty).sqrt(); // |μ| for S1 = 0: S2, S3 up to |μ|
    // Elliptical, S1 = 0.4: S_xS_y = 0.21, |S2 + iS3|² ≤ 4·0.21·|μ|².
    let e = m * (4.0 * 0.21_f64).sqrt() / 2.0_f64.sqrt();
    vec![
        ("x", [1.0, 1.0, 0.0, 0.0]),
        ("y", [1.0, -1.0, 0.0, 0.0]),
        ("+45", [1.0, 0.0, m, 0.0]),
        ("-45", [1.0, 0.0, -m, 0.0]),
        ("R", [1.0, 0.0, 0.0, m]),
        ("L", [1.0, 0.0, 0.0, -m]),
        ("ell", [1.0, 0.4, e, -e]),
    ]
}

/// Three scenes: oblique glass, grazing-ish metal, normal incidence; anisotropic rotated shapes
/// with width ratios up to 4 between the channels, comparable with the correlation length.
fn scenes() -> Vec<Scene> {
    let base = |theta_i: f64, phi_i: f64, psi: f64, beta: f64, tx, ty, eta, ell, lambda| Scene {
        lambda,
        theta_i,
        phi_i,
        psi,
        beta,
        theta_x: tx,
        theta_y: ty,
        stokes: [1.0, 0.0, 0.0, 0.0],
        sigma: 0.02,
        ell,
        eta,
    };
    vec![
        base(
            35.0 * PI / 180.0,
            0.4,
            0.6,
            0.3,
            shape(2.0, 1.0, 0.5),
            shape(0.5, 1.5, -0.7),
            C64::new(1.5, 0.0),
            1.5,
            0.5,
        ),
        base(
            62.0 * PI / 180.0,
            -2.0,
            -1.1,
            -0.8,
            shape(0.6, 2.4, 1.2),
            shape(1.8, 0.7, 0.2),
            C64::new(0.2, 3.0),
            2.0,
            0.6,
        ),
        base(
            0.0,
            0.0,
            2.3,
            1.0,
            shape(1.2, 0.4, -0.3),
            shape(0.8, 1.6, 0.9),
            C64::new(1.8, 0.05),
            2.5,
            0.55,
        ),
    ]
}

/// Exit-tangent offsets from the specular direction: on it, inside the lobes (where the specular
/// weights of the channels differ by up to orders of magnitude), and out to the scattering
/// tails (φ ≠ 0 everywhere but the first).
fn offsets() -> Vec<Vector2<f64>> {
    let mut v = vec![Vector2::zeros()];
    for (r, a) in [
        (0.02, 0.7_f64),
        (0.05, 2.1),
        (0.08, -1.3),
        (0.12, 3.9),
        (0.2, 5.0),
        (0.3, 1.6),
        (0.45, -2.6),
    ] {
        v.push(Vector2::new(a.cos(), a.sin()) * r);
    }
    v
}

/// Runs `check` on every (scene, polarization, exit) with `cos θ_o > 0.25`.
fn for_all_cases(mut check: impl FnMut(&Scene, &str, &Vector3<f64>)) {
    for base in scenes() {
        for (name, stokes) in polarizations(&base.theta_x, &base.theta_y) {
            let sc = Scene {
                stokes,
                ..base.clone()
            };
            for d in offsets() {
                let exit = sc.exit_near_specular(d);
                if exit.z <= 0.25 {
                    continue;
                }
                check(&sc, name, &exit);
            }
        }
    }
}

const TOL: f64 = 1e-10;

// ------------------------------------------------------------------ tests

/// `Full × Partial`, `Full × Incoherent` and `Full × PlaneWave` (f64) against the channel oracle,
/// specular and scattered parts, every component within 1e-10 of the Stokes vector's scale
/// (max norm). Every comparison is made before the test fails, and a table per level and part
/// is printed — cases, failures, and the smallest, median and largest relative difference
/// `max|a − b|/max|b|` — so that a failure says how far off the crate is, not only where.
#[test]
fn full_level_matches_channel_oracle() {
    assert!(a_mul_inverse_is_inverse());
    let j = specular_jones();
    // (level, part) → relative differences; the failing cases' descriptions.
    let mut diffs: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    let mut failures = Vec::new();
    let mut count = 0;
    for_all_cases(|sc, name, exit| {
        let checks: [(Level, Response<f64>); 3] = [
            (Level::Partial, run::<f64, Full, Partial>(sc, exit)),
            (Level::Incoherent, run::<f64, Full, Incoherent>(sc, exit)),
            (Level::PlaneWave, run::<f64, Full, PlaneWave>(sc, exit)),
        ];
        for (level, got) in &checks {
            let want = oracle(sc, exit, *level, Shapes::True, &j);
            for (part, a, b) in [
                ("specular", to64(got.specular), want.specular),
                ("scattered", to64(got.scattered), want.scattered),
            ] {
                let tol = Tol::new(TOL * b.amax() + 1e-300, 0.0);
                let ok = a.iter().zip(b.iter()).all(|(x, y)| tol.accepts(*x, *y));
                let key = format!("{level:?} {part}");
                diffs.entry(key.clone()).or_default().push(rel(&a, &b));
                if !ok {
                    failures.push(format!(
                        "{key} {name} θi={:.3} exit {exit:?}: {a:?} vs {b:?} (rel {:.3e})",
                        sc.theta_i,
                        rel(&a, &b)
                    ));
                }
            }
        }
        count += 1;
    });
    println!("{count} cases (scene × polarization × exit):");
    for (key, mut v) in diffs {
        v.sort_by(f64::total_cmp);
        let failing: Vec<f64> = v.iter().copied().filter(|d| *d > TOL).collect();
        println!(
            "  {key:<22} relative difference min {:.2e} median {:.2e} max {:.2e}; \
             above {TOL:e}: {} (smallest of those {:.2e})",
            v[0],
            v[v.len() / 2],
            v[v.len() - 1],
            failing.len(),
            failing.first().copied().unwrap_or(0.0)
        );
    }
    assert!(count >= 100, "the case set ran: {count}");
    assert!(
        failures.is_empty(),
        "{} of {} comparisons fail; first: {}",
        failures.len(),
        6 * count,
        failures
            .iter()
            .take(3)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// The oracle itself separates the physics from the two bugs this file exists to catch — x and
/// y shapes swapped, `Θ_½` for every channel — by far more than the tolerance: for every scene
/// and every input polarization, the largest relative difference over the exits exceeds 1e-2
/// (10⁸ × TOL) in the specular *and* in the scattered part, for both readings (printed).
#[test]
fn channel_oracle_is_sensitive_to_the_shapes() {
    let j = specular_jones();
    // (scene, polarization) → max over exits of [swap spec, swap scat, half spec, half scat].
    let mut table: std::collections::BTreeMap<String, [f64; 4]> = Default::default();
    for_all_cases(|sc, name, exit| {
        let truth = oracle(sc, exit, Level::Partial, Shapes::True, &j);
        let swap = oracle(sc, exit, Level::Partial, Shapes::Swapped, &j);
        let half = oracle(sc, exit, Level::Partial, Shapes::AllHalf, &j);
        let row = table
            .entry(format!("θi={:.2} {name:>3}", sc.theta_i))
            .or_insert([0.0; 4]);
        let d = [
            rel(&swap.specular, &truth.specular),
            rel(&swap.scattered, &truth.scattered),
            rel(&half.specular, &truth.specular),
            rel(&half.scattered, &truth.scattered),
        ];
        for (r, d) in row.iter_mut().zip(d) {
            *r = r.max(d);
        }
    });
    println!("max relative difference from the oracle: swapped (spec, scat), all-Θ½ (spec, scat)");
    for (key, row) in &table {
        println!(
            "  {key}: swapped {:.2e} {:.2e}, all-Θ½ {:.2e} {:.2e}",
            row[0], row[1], row[2], row[3]
        );
        assert!(
            row.iter().all(|d| *d > 1e-2),
            "{key}: not separated: {row:?}"
        );
    }
    assert_eq!(table.len(), 21, "3 scenes × 7 polarizations");
}

/// `OneShape × Partial` equals the oracle with `Θ_½` in every channel (the documented
/// approximation, to 1e-10), and differs from the true oracle by the printed amount: per scene
/// and polarization, the median and largest relative difference over the exits of the scattered
/// part, and the median of the specular part (not asserted: the size of the approximation).
#[test]
fn one_shape_is_the_all_half_oracle() {
    let j = specular_jones();
    let mut diffs: std::collections::BTreeMap<String, (Vec<f64>, Vec<f64>)> = Default::default();
    for_all_cases(|sc, name, exit| {
        let got = run::<f64, OneShape, Partial>(sc, exit);
        let approx = oracle(sc, exit, Level::Partial, Shapes::AllHalf, &j);
        let truth = oracle(sc, exit, Level::Partial, Shapes::True, &j);
        let (gs, gd) = (to64(got.specular), to64(got.scattered));
        let what = format!("OneShape {name} θi={:.3} exit {exit:?}", sc.theta_i);
        assert_stokes(&format!("{what} specular"), &gs, &approx.specular, TOL);
        assert_stokes(&format!("{what} scattered"), &gd, &approx.scattered, TOL);
        let e = diffs
            .entry(format!("θi={:.2} {name:>3}", sc.theta_i))
            .or_default();
        e.0.push(rel(&gd, &truth.scattered));
        e.1.push(rel(&gs, &truth.specular));
    });
    println!("OneShape vs the Full oracle (relative difference over the exits):");
    for (key, (mut scat, mut spec)) in diffs {
        scat.sort_by(f64::total_cmp);
        spec.sort_by(f64::total_cmp);
        println!(
            "  {key}: scattered median {:.2e} max {:.2e}; specular median {:.2e}",
            scat[scat.len() / 2],
            scat[scat.len() - 1],
            spec[spec.len() / 2]
        );
    }
}

/// f32 `Full × Partial` against the f64 oracle: within 2e-4 of the Stokes vector's scale.
#[test]
fn full_level_matches_channel_oracle_f32() {
    let j = specular_jones();
    let mut worst = 0.0_f64;
    for_all_cases(|sc, name, exit| {
        let want = oracle(sc, exit, Level::Partial, Shapes::True, &j);
        let got = run::<f32, Full, Partial>(sc, exit);
        let (gs, gd) = (to64(got.specular), to64(got.scattered));
        let what = format!("f32 {name} θi={:.3} exit {exit:?}", sc.theta_i);
        // Within 2e-4 of the scale, or (below f32's normal range) within 1e-37 absolute.
        for (a, b, part) in [
            (gs, want.specular, "specular"),
            (gd, want.scattered, "scattered"),
        ] {
            assert_all_close(
                &format!("{what} {part}"),
                a.iter().copied(),
                b.iter().copied(),
                Tol::new(2e-4 * b.amax() + 1e-37, 0.0),
            );
        }
        worst = worst.max(rel(&gd, &want.scattered));
    });
    println!("f32: worst relative difference (scattered) {worst:.2e}");
}

/// Where the channels differ: per scene, the largest ratio `max f_α / min f_α` of the channel
/// weights over the exits, asserted ≥ 100 for the specular lobe and ≥ 10 for the scattered part
/// (printed), so the cases above include exits where the x and y lobes differ strongly.
#[test]
fn cases_include_strongly_different_lobes() {
    let j = specular_jones();
    for base in scenes() {
        let mut best = [1.0_f64; 2];
        for d in offsets() {
            let exit = base.exit_near_specular(d);
            if exit.z <= 0.25 {
                continue;
            }
            let e = oracle(&base, &exit, Level::Partial, Shapes::True, &j);
            for (b, [fx, fy, fh]) in best.iter_mut().zip(e.channels) {
                *b = b.max(fx.max(fy).max(fh) / fx.min(fy).min(fh));
            }
        }
        println!(
            "θi = {:.2}: largest channel ratio f_max/f_min: specular {:.3e}, scattered {:.3e}",
            base.theta_i, best[0], best[1]
        );
        assert!(
            best[0] >= 100.0 && best[1] >= 10.0,
            "channels too similar: {best:?}"
        );
    }
}

proptest! {
    #![proptest_config(common::proptest_config(64))]
    /// Random scenes: incidence, azimuths, frame turn ψ, tangent turn β, two independent rotated
    /// anisotropic shapes, a realizable random Stokes vector, random exit; `Full × Partial` and
    /// `Full × Incoherent` against the oracle.
    #[test]
    fn full_level_matches_oracle_proptest(
        theta_i in 0.0..1.2_f64, phi_i in -PI..PI, psi in -PI..PI, beta in -PI..PI,
        (a1, a2, r1) in (0.3..3.0_f64, 0.3..3.0_f64, -PI..PI),
        (b1, b2, r2) in (0.3..3.0_f64, 0.3..3.0_f64, -PI..PI),
        s in common::stokes_vector(),
        (dr, da) in (0.0..0.5_f64, -PI..PI),
        ell in 0.3..3.0_f64,
        metal in any::<bool>(),
    ) {
        let (tx, ty) = (shape(a1, a2, r1), shape(b1, b2, r2));
        // Scale S2, S3 into the realizability bound (0.99 of it).
        let four_sxsy = s[0] * s[0] - s[1] * s[1];
        let mu2 = (s[2] * s[2] + s[3] * s[3]) / four_sxsy.max(1e-300);
        let bound = 0.99 * mu2_bound(&tx, &ty);
        let f = if mu2 > bound { (bound / mu2).sqrt() } else { 1.0 };
        let sc = Scene {
            lambda: 0.5, theta_i, phi_i, psi, beta, theta_x: tx, theta_y: ty,
            stokes: [s[0], s[1], s[2] * f, s[3] * f], sigma: 0.02, ell,
            eta: if metal { C64::new(0.2, 3.0) } else { C64::new(1.5, 0.0) },
        };
        let exit = sc.exit_near_specular(Vector2::new(da.cos(), da.sin()) * dr);
        prop_assume!(exit.z > 0.1);
        let j = specular_jones();
        let want = oracle(&sc, &exit, Level::Partial, Shapes::True, &j);
        let got = run::<f64, Full, Partial>(&sc, &exit);
        assert_stokes("Partial specular", &to64(got.specular), &want.specular, TOL);
        assert_stokes("Partial scattered", &to64(got.scattered), &want.scattered, TOL);
        let want = oracle(&sc, &exit, Level::Incoherent, Shapes::True, &j);
        let got = run::<f64, Full, Incoherent>(&sc, &exit);
        assert_stokes("Incoherent scattered", &to64(got.scattered), &want.scattered, TOL);
    }
}
