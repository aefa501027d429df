//! Verifies the kernel in BSDF form (`Kernel::evaluate_mueller`, `MuellerResponse`) and the
//! promises of the renderer layer around it (`gmueller::bsdf`), against the kernel's Stokes form
//! and against computations of this file:
//! - **Matrix form = Stokes form** (property tests from the fixed seed of `tests/common`, f64 and
//!   f32): random realizable packets (Stokes vectors inside the cone, near and on its surface;
//!   one coherence shape, or two with `|μ|` up to the Bochner bound, the bound itself included),
//!   five materials (rough glass lit from either side, a conductor, K-correlation blurred by
//!   `Partial(GaussHermite)`, a Gaussian mixture, a sinusoidal height grating), exits on both
//!   sides up to 89.99° and at any azimuth (half of them within a few lobe widths of the specular
//!   direction), all nine levels: `evaluate_mueller(..).apply(S)` equals `evaluate(..)` per lobe,
//!   entry by entry, within `16 S0 MIN_POSITIVE + (8 ε ln MAX + 64 ε κ) · max(S0_a, S0_b,
//!   max|M_ij| S0)` (`max|M_ij| S0` the size of the terms of `M S`; the exponentials of log-space
//!   scales and the pBSDF product, `κ` its conditioning, see `tolerances`). Skipped and counted:
//!   lobes the matrix flushes to 0 (asserted to be below `MIN_POSITIVE` in scale, ≤ 10 %). The
//!   two-shape Full/Partial cases where a quadrature blur's weights break Cauchy–Schwarz are
//!   compared too (counted): both forms cap for `|μ|_max` since
//!   `two_shape_forms_agree_with_a_quadrature_blur` found them apart.
//!   At least 40 % of every lobe that is not a delta compares a nonzero value.
//! - The intensity level's scalar equals `M₀₀` of the one-shape level's matrix.
//! - **Validity**: one-shape matrices are Cloude-realizable and map valid Stokes vectors to valid
//!   ones (a matrix whose entries are all subnormal is flushed to 0:
//!   `subnormal_matrices_are_flushed`, a regression test of that bug); two-shape (Full) matrices map every Stokes vector the shapes admit to a
//!   valid one, and a fully correlated vector the shapes do not admit to an invalid one (at the
//!   specular direction, where the cap is exact: degree 1 at the bound, 1.166 beyond it).
//! - `Bsdf::eval`/`eval_stokes` equal the kernel's two forms; `Bsdf::prepare` and
//!   `Kernel::try_evaluate` reject packets and geometries of another wavelength, medium or
//!   direction; the new API returns errors, never panics, on bad finite input and NaN uniforms.
//! - **Delta lobes**: the plane-wave level's Dirac throughputs (`exit_weight`/`incident_weight`
//!   × pdf) equal the limit of the partially coherent lobe's integral as the coherence width grows
//!   (adaptive Gauss–Legendre quadrature of the `Partial` lobe at w = 50, 200, 1000 µm), for the
//!   specular reflection and transmission of rough glass and a grating order, forward and
//!   backward; and backward = η² × forward for the same pair of directions.
//! - `SurfaceCoherence::packet`'s section is `I/σ²`; `Frame::from_normal` is orthonormal and
//!   right-handed; `Grating::sinusoidal_height` has the orders of its formula; `Bsdf::flags`.

use crate::common;

use std::cell::RefCell;

use common::Tol;
use common::quadrature::integrate;
use gmueller::Real;
use gmueller::bsdf::{Bsdf, LobeFlags, SurfaceCoherence};
use gmueller::error::Error;
use gmueller::frame::Frame;
use gmueller::interaction::coherence::{
    CoherenceWeights, surface_coherence_term, surface_inverse_coherence,
};
use gmueller::interaction::pbsdf::Pbsdf;
use gmueller::interaction::polarization::{
    KernelOutput, MuellerResponse, PolarizationModel, Response,
};
use gmueller::interaction::{
    Full, Geometry, Incoherent, Intensity, Kernel, OneShape, Partial, PlaneWave, RoughConductor,
    RoughDielectric, RoughSurface, SmoothConductor, SmoothDielectric,
};
use gmueller::mueller::Mueller;
use gmueller::packet::{Channel, CoherenceShape, WavePacket};
use gmueller::psd::{
    BlurMethod, ClosedForm, GaussHermite, GaussianMixturePsd, GaussianPsd, Grating, KCorrelation,
    Psd,
};
use gmueller::stokes::Stokes;
use nalgebra::{Matrix2, Matrix4, Vector2, Vector3, Vector4};
use num_complex::Complex;
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestRunner};

/// The vacuum wavelength (µm) and the relative index of the dielectrics.
const LAMBDA: f64 = 0.5;
const ETA: f64 = 1.5;

// ------------------------------------------------------------------ materials

fn glass<T: Real>() -> RoughDielectric<T, GaussianPsd<T, 2>> {
    RoughDielectric::new(
        GaussianPsd::isotropic(T::lit(0.02), T::lit(1.0)).unwrap(),
        T::lit(ETA),
    )
    .unwrap()
}

fn gold<T: Real>() -> RoughConductor<T, GaussianPsd<T, 2>> {
    let eta = Complex::new(T::lit(0.47), T::lit(2.4));
    RoughConductor::new(
        GaussianPsd::isotropic(T::lit(0.015), T::lit(1.5)).unwrap(),
        eta,
    )
    .unwrap()
}

fn k_correlated<T: Real>() -> RoughDielectric<T, KCorrelation<T, 2>> {
    let psd = KCorrelation::new(T::lit(4e-4), T::lit(4.0), T::lit(2.5)).unwrap();
    RoughDielectric::new(psd, T::lit(ETA)).unwrap()
}

fn mixture<T: Real>() -> RoughDielectric<T, GaussianMixturePsd<T, 2>> {
    let mix = GaussianMixturePsd::new(vec![
        GaussianPsd::isotropic(T::lit(0.01), T::lit(0.7)).unwrap(),
        GaussianPsd::isotropic(T::lit(0.02), T::lit(3.0)).unwrap(),
    ])
    .unwrap();
    RoughDielectric::new(mix, T::lit(ETA)).unwrap()
}

fn grating<T: Real>() -> RoughConductor<T, Grating<T, 2>> {
    let d = Vector2::new(T::lit(0.9), T::lit(0.3));
    let g = Grating::sinusoidal_height(T::lit(0.03), T::lit(2.0), &d).unwrap();
    RoughConductor::new(g, Complex::new(T::lit(0.2), T::lit(3.4))).unwrap()
}

const MATERIALS: [&str; 5] = ["glass", "gold", "K-correlation", "mixture", "grating"];

/// The level names, in the order the tally keeps them (coherence-major).
const LEVELS: [&str; 9] = [
    "Intensity/PlaneWave",
    "OneShape/PlaneWave",
    "Full/PlaneWave",
    "Intensity/Partial",
    "OneShape/Partial",
    "Full/Partial",
    "Intensity/Incoherent",
    "OneShape/Incoherent",
    "Full/Incoherent",
];

// ------------------------------------------------------------------ the random case

/// A coherence shape drawn as `(width, anisotropy, angle)` ([`shape_matrix`]).
type ShapeDraw = (f64, f64, f64);

/// One random interaction, in plain numbers (mapped to `T` by [`Built::new`]).
#[derive(Debug, Clone)]
struct Case {
    material: usize,
    /// The shading normal `(tx, ty, 1)`.
    tilt: (f64, f64),
    /// `θ_i` (degrees), `φ_i` (degrees), light from below (dielectrics only).
    incidence: (f64, f64, bool),
    /// The packet frame's rotation about its direction.
    psi: f64,
    /// `S0`, the degree of polarization, the Poincaré direction (z, azimuth).
    stokes: (f64, f64, f64, f64),
    /// Two coherence shapes; each `(width, anisotropy, angle)`; `|μ|/|μ|_max`; `S1/S0`.
    shapes: (bool, ShapeDraw, ShapeDraw, f64, f64),
    /// Transmitted side, near the specular direction, `θ_o` (degrees), `φ_o` (degrees), the offset
    /// from the specular direction in lobe widths.
    exit: (bool, bool, f64, f64, (f64, f64)),
    /// Three more Stokes directions `(t, φ, degree)` for the validity checks.
    probes: [(f64, f64, f64); 3],
}

/// A degree of polarization: uniform inside the cone, near its surface (`1 − 10^−e`), on it.
fn degree() -> impl Strategy<Value = f64> {
    prop_oneof![
        2 => 0.0..=1.0f64,
        1 => (2.0..12.0f64).prop_map(|e| 1.0 - 10f64.powf(-e)),
        1 => Just(1.0),
    ]
}

fn shape_draw() -> impl Strategy<Value = (f64, f64, f64)> {
    (0.0..2.0f64, 1.0..4.0f64, 0.0..std::f64::consts::PI)
        .prop_map(|(lw, a, t)| (10f64.powf(lw), a, t))
}

fn case() -> impl Strategy<Value = Case> {
    (
        0..MATERIALS.len(),
        (-0.4..0.4f64, -0.4..0.4f64),
        (0.0..89.99f64, 0.0..360.0f64, any::<bool>()),
        common::angle(),
        (
            (-3.0..3.0f64).prop_map(|e| 10f64.powf(e)),
            degree(),
            -1.0..=1.0f64,
            0.0..std::f64::consts::TAU,
        ),
        (
            any::<bool>(),
            shape_draw(),
            shape_draw(),
            prop_oneof![3 => 0.0..=1.0f64, 1 => Just(1.0)],
            -0.99..0.99f64,
        ),
        (
            any::<bool>(),
            any::<bool>(),
            0.0..89.99f64,
            0.0..360.0f64,
            (-3.0..3.0f64, -3.0..3.0f64),
        ),
        proptest::array::uniform3((-1.0..=1.0f64, 0.0..std::f64::consts::TAU, degree())),
    )
        .prop_map(
            |(material, tilt, incidence, psi, stokes, shapes, exit, probes)| Case {
                material,
                tilt,
                incidence,
                psi,
                stokes,
                shapes,
                exit,
                probes,
            },
        )
}

/// `R(t) diag(w², (w/a)²) R(t)ᵀ`.
fn shape_matrix((w, a, t): (f64, f64, f64)) -> Matrix2<f64> {
    let (s, c) = t.sin_cos();
    let r = Matrix2::new(c, -s, s, c);
    r * Matrix2::new(w * w, 0.0, 0.0, (w / a) * (w / a)) * r.transpose()
}

/// `|μ|_max = (√(|Θx||Θy|)/|Θ½|)^{1/2}`, the Bochner bound of two shapes (`crate::packet`).
fn mu_max(x: &Matrix2<f64>, y: &Matrix2<f64>) -> f64 {
    ((x.determinant() * y.determinant()).sqrt() / ((x + y) * 0.5).determinant()).sqrt()
}

/// The Stokes vector `S0 (1, t, 2√((1+t)(1−t)/4) m cos φ, … sin φ)`: `S_x/S_y` from `t`, the
/// degree of correlation `m e^{iφ}`.
fn stokes_with_correlation(s0: f64, t: f64, m: f64, phi: f64) -> Vector4<f64> {
    let c = ((1.0 + t) * (1.0 - t)).sqrt() * m;
    Vector4::new(1.0, t, c * phi.cos(), c * phi.sin()) * s0
}

/// A Stokes vector of degree `p`, Poincaré direction `(z, az)`.
fn stokes_on_sphere(s0: f64, p: f64, z: f64, az: f64) -> Vector4<f64> {
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vector4::new(1.0, p * r * az.cos(), p * r * az.sin(), p * z) * s0
}

fn to_stokes<T: Real>(v: &Vector4<f64>) -> Stokes<T> {
    Stokes::new(T::lit(v[0]), T::lit(v[1]), T::lit(v[2]), T::lit(v[3])).unwrap()
}

/// A direction at polar angle `deg` from `side · n̂`, azimuth `phi_deg`, in frame `f`.
fn local<T: Real>(f: &Frame<T>, deg: f64, phi_deg: f64, side: f64) -> Vector3<T> {
    let (t, p) = (deg.to_radians(), phi_deg.to_radians());
    let lit = T::lit;
    f.x() * lit(t.sin() * p.cos()) + f.y() * lit(t.sin() * p.sin()) + f.k() * lit(side * t.cos())
}

/// The inputs of one case in `T`.
struct Built<T: Real> {
    packet: WavePacket<T>,
    geometry: Geometry<T>,
    /// Valid Stokes vectors (single shape), or vectors the two shapes admit.
    probes: Vec<Stokes<T>>,
}

impl<T: Real> Built<T> {
    fn new(case: &Case, eta: Option<f64>) -> Self {
        let surface = Frame::<T>::from_normal(Vector3::new(
            T::lit(case.tilt.0),
            T::lit(case.tilt.1),
            T::one(),
        ))
        .unwrap();
        let (ti, pi, below) = case.incidence;
        let below = below && eta.is_some();
        let side = if below { -1.0 } else { 1.0 };
        let s = local(&surface, ti, pi, side);
        let lambda = if below { LAMBDA / ETA } else { LAMBDA };
        let frame = Frame::sp(-s, surface.k())
            .unwrap()
            .rotated(T::lit(case.psi));
        let (two, dx, dy, mu_frac, t) = case.shapes;
        let (s0, p, z, az) = case.stokes;
        let (tx, ty) = (
            shape_matrix(dx),
            if two {
                shape_matrix(dy)
            } else {
                shape_matrix(dx)
            },
        );
        let bound = mu_max(&tx, &ty);
        let stokes = if two {
            stokes_with_correlation(s0, t, mu_frac * bound, az)
        } else {
            stokes_on_sphere(s0, p, z, az)
        };
        let shape = |m: &Matrix2<f64>| CoherenceShape::new(m.map(T::lit)).unwrap();
        let packet = WavePacket::new(
            to_stokes(&stokes),
            shape(&tx),
            shape(&ty),
            frame,
            T::lit(lambda),
        )
        .unwrap();
        let k = packet.wavenumber();
        let geometry = |r: Vector3<T>| match eta {
            Some(e) => Geometry::at_interface(k, &surface, T::lit(e), s, r),
            None => Geometry::new(k, &surface, s, r),
        };
        let (transmit, near, to, po, off) = case.exit;
        let transmit = transmit && eta.is_some();
        let n = surface.facing(&s).k();
        let out_side = if transmit { -n } else { n };
        let random = local(
            &surface.facing(&s),
            to,
            po,
            if transmit { -1.0 } else { 1.0 },
        );
        let mut exit = random;
        if near {
            let spec = geometry(out_side).unwrap().specular_direction();
            if let Some(spec) = spec {
                // A few lobe widths off: Δu ≈ 1/(k_exit w).
                let k_exit = geometry(out_side).unwrap().exit_wavenumber().to_f64();
                let du = 1.0 / (k_exit * dx.0);
                let f = surface.facing(&s);
                let r = spec + f.x() * T::lit(off.0 * du) + f.y() * T::lit(off.1 * du);
                let r = r / r.norm();
                if (r.dot(&out_side)).to_f64() > 1e-3 {
                    exit = r;
                }
            }
        }
        let geometry = geometry(exit).unwrap();
        let probes = case
            .probes
            .iter()
            .map(|&(t, phi, p)| {
                let v = if two {
                    stokes_with_correlation(1.0, t * 0.99, p.min(1.0) * bound, phi)
                } else {
                    stokes_on_sphere(1.0, p, t, phi)
                };
                to_stokes(&v)
            })
            .chain(std::iter::once(packet.stokes()))
            .collect();
        Self {
            packet,
            geometry,
            probes,
        }
    }
}

// ------------------------------------------------------------------ matrix form = Stokes form

/// What the property tests saw, per level (the order of [`LEVELS`]) and lobe (specular,
/// scattered).
#[derive(Debug, Default)]
struct Tally {
    cases: usize,
    /// Compared with a nonzero result.
    compared: [[usize; 2]; 9],
    /// Both forms exactly 0.
    both_zero: [[usize; 2]; 9],
    /// The matrix flushed to 0 (its scale below the smallest normal), the Stokes form not.
    flushed: [[usize; 2]; 9],
    /// The largest `(|Δ_j| − abs)/(reference (1 + κ product/exp))` per level (1 = the tolerance's
    /// exponential part).
    worst: [f64; 9],
    /// The most negative coherency eigenvalue over the trace of a one-shape matrix.
    worst_cloude: f64,
    /// The largest `(|S_pol| − S0)/(κ max|M_ij| S0_in)` of an output.
    worst_validity: f64,
    /// Full/Partial scattered lobes of two-shape packets not compared: the blur's weights break
    /// Cauchy–Schwarz, `K_½ |μ|_max > √(K_x K_y)` (see `two_shape_forms_agree_with_a_quadrature_blur`).
    capped: usize,
    /// Nonzero matrices whose entries are all subnormal (validity not checked).
    subnormal: usize,
}

impl Tally {
    fn report(&self, name: &str) {
        println!("{name}: {} cases", self.cases);
        for (i, level) in LEVELS.iter().enumerate() {
            println!(
                "  {level:<22} compared {:>4}/{:>4}  both 0 {:>4}/{:>4}  flushed {:>3}/{:>3}  max (|Δ| − abs)/(ref (1 + κ p/e)) {:.2e}",
                self.compared[i][0],
                self.compared[i][1],
                self.both_zero[i][0],
                self.both_zero[i][1],
                self.flushed[i][0],
                self.flushed[i][1],
                self.worst[i]
            );
        }
        println!(
            "  most negative coherency eigenvalue / tr H {:.2e}; largest (|S_pol| − S0)/(κ max|M_ij| S0) {:.2e}",
            self.worst_cloude, self.worst_validity
        );
        println!(
            "  two-shape Full/Partial cases whose blur weights break Cauchy–Schwarz (compared, both forms cap for |μ|_max): {}",
            self.capped
        );
        println!(
            "  nonzero matrices with every entry subnormal (validity not checked): {}",
            self.subnormal
        );
    }
}

/// The agreement of the two forms: `|Δ_j| ≤ abs + (exp + product · κ) · reference`.
#[derive(Debug, Clone, Copy)]
struct Agreement {
    /// The exponentials of the log-space scales.
    exp: f64,
    /// The product of the pBSDF with the (effective) Stokes vector, per unit of its
    /// conditioning κ ([`conditioning`]).
    product: f64,
}

/// The tolerances of one scalar type (module docs).
#[derive(Debug, Clone, Copy)]
struct Tolerances {
    /// Matrix form against Stokes form, relative to the reference.
    rel: Agreement,
    /// `Mueller::is_physically_realizable`'s tolerance.
    cloude: f64,
    /// Validity of `M S`: `|S_pol| − S0 ≤ validity · κ · max|M_ij| S0_in`.
    validity: f64,
}

fn tolerances<T: Real>() -> Tolerances {
    let eps = T::EPSILON.to_f64();
    Tolerances {
        // Both forms round the same factors in a different order: exponentials of log-space
        // scales (|ln e| ≤ ln MAX: up to 710 ulps in f64, 89 in f32; 8 ε ln MAX = 1.3e-12 and
        // 8.4e-5) and the product of the pBSDF with the (effective) Stokes vector, amplified
        // where the pBSDF nearly extinguishes it (Brewster's angle: κ in the thousands; both
        // forms are then off f64 by ~1e-3 in f32, in different ways): 64 ε κ.
        rel: Agreement {
            exp: 8.0 * eps * T::MAX.to_f64().ln(),
            product: 64.0 * eps,
        },
        // Rank-one coherency of a Jones-derived matrix, to rounding (measured 3e-16, 2e-7).
        cloude: 64.0 * eps,
        // Fully polarized outputs (a two-shape lobe with K_x ≫ K_y, a vector at the bound |μ|_max
        // through the specular lobe at its cap) sit on the cone, to the rounding of M T D̂
        // amplified by the pBSDF's conditioning κ (`conditioning`), and of the Full level's
        // r_½ = e^{a_½ − m}, an exponential of a log-space difference (≤ 2 ln MAX ulps):
        // (64 + 2 ln MAX) ε κ = 3.3e-13 κ (f64), 2.9e-5 κ (f32).
        validity: (64.0 + 2.0 * T::MAX.to_f64().ln()) * eps,
    }
}

/// One lobe: `via` (the matrix form applied) against `direct` (the Stokes form); `zero` when
/// the matrix is 0, `pbsdf` the largest entry of the lobe's pBSDF, `m00` the matrix's largest
/// entry (`M₀₀` for one shape), `s0` the packet's `S0`.
#[expect(clippy::too_many_arguments, reason = "one comparison, spelled out")]
fn compare_lobe<T: Real>(
    tally: &mut Tally,
    (level, lobe): (usize, usize),
    via: Vector4<T>,
    direct: Vector4<T>,
    (zero, pbsdf): (bool, &Matrix4<f64>),
    m00: T,
    s0: T,
    rel: Agreement,
) -> Result<(), TestCaseError> {
    let (a, b) = (via.map(T::to_f64), direct.map(T::to_f64));
    let (m00, s0, tiny) = (m00.to_f64(), s0.to_f64(), T::MIN_POSITIVE.to_f64());
    let kappa = conditioning(pbsdf);
    let pbsdf = pbsdf.amax();
    let what = format!("{} {}", LEVELS[level], ["specular", "scattered"][lobe]);
    if zero {
        prop_assert!(a == Vector4::zeros(), "{what}: a zero matrix gave {a:?}");
        if b == Vector4::zeros() {
            tally.both_zero[level][lobe] += 1;
        } else {
            // Flushed: the scale per unit S0 was below the smallest normal number, so the Stokes
            // form is below MIN_POSITIVE S0 times the pBSDF's size (|M_0k v_k| ≤ 8 max|M_pbsdf|:
            // the effective Stokes vector v of the Full level has entries ≤ 2); or every entry
            // of the matrix was, so the Stokes form is below 4 MIN_POSITIVE S0.
            prop_assert!(
                b[0] <= (8.0 * pbsdf).max(4.0) * tiny * s0,
                "{what}: matrix flushed to 0 but the Stokes form is {b:?} (S0 = {s0:e})"
            );
            tally.flushed[level][lobe] += 1;
        }
        return Ok(());
    }
    let reference = a[0].abs().max(b[0].abs()).max(m00.abs() * s0);
    let abs = 16.0 * tiny * s0;
    for j in 0..4 {
        let d = (a[j] - b[j]).abs();
        let tol = (rel.exp + rel.product * kappa) * reference;
        prop_assert!(
            d <= abs + tol,
            "{what}[{j}]: matrix form {a:?} vs Stokes form {b:?} (|Δ| = {d:e}, reference {reference:e}, S0 {s0:e}, m00 {m00:e})"
        );
        let excess = (d - abs).max(0.0) / (reference * (1.0 + rel.product / rel.exp * kappa));
        tally.worst[level] = tally.worst[level].max(excess);
    }
    if b == Vector4::zeros() {
        tally.both_zero[level][lobe] += 1;
    } else {
        tally.compared[level][lobe] += 1;
    }
    Ok(())
}

/// The specular and scattering pBSDFs at `g`.
fn pbsdf_matrices<T: Real, P, Sp: Pbsdf<T>, Sc: Pbsdf<T>>(
    material: &RoughSurface<P, Sp, Sc>,
    g: &Geometry<T>,
) -> [Matrix4<f64>; 2] {
    [
        material.specular.mueller(g).matrix().map(T::to_f64),
        material.scatter.mueller(g).matrix().map(T::to_f64),
    ]
}

/// `κ = max|P_ij| / (P₀₀ (1 − D))`, `D` the diattenuation of the pBSDF `P`: how much the
/// rounding of `P v` (≈ ε |P| |v|) is amplified relative to the output, since
/// `(P v)₀ ≥ P₀₀ (1 − D) v₀` for a valid `v`. Large where the pBSDF nearly extinguishes a
/// polarization (Brewster's angle); ∞ for a perfect polarizer (no bound is then claimed).
fn conditioning(p: &Matrix4<f64>) -> f64 {
    let d = Vector3::new(p[(0, 1)], p[(0, 2)], p[(0, 3)]).norm() / p[(0, 0)];
    let k = p.amax() / (p[(0, 0)] * (1.0 - d));
    if k.is_finite() && k > 0.0 {
        k.max(1.0)
    } else {
        f64::INFINITY
    }
}

/// A Stokes-level kernel (`OneShape`, `Full`): both forms, compared lobe by lobe; returns the
/// matrix form.
fn stokes_level<T, P, Sp, Sc, Pol, Coh>(
    tally: &mut Tally,
    level: usize,
    kernel: &Kernel<Pol, Coh>,
    material: &RoughSurface<P, Sp, Sc>,
    built: &Built<T>,
    (rel, skip_scattered): (Agreement, bool),
) -> Result<MuellerResponse<T, Mueller<T>>, TestCaseError>
where
    T: Real,
    P: Psd<T, 2>,
    Sp: Pbsdf<T>,
    Sc: Pbsdf<T>,
    Pol: PolarizationModel<Output<T> = Response<T>, Throughput<T> = Mueller<T>>,
    Coh: CoherenceWeights<T, P>,
{
    let (p, g) = (&built.packet, &built.geometry);
    let direct = kernel.evaluate(material, p, g);
    let form = kernel.evaluate_mueller(material, p, g);
    let via = form.apply(&p.stokes());
    prop_assert_eq!(via.attenuation, direct.attenuation);
    prop_assert_eq!(via.side, direct.side);
    let pbsdf = pbsdf_matrices(material, g);
    for (lobe, (m, v, d)) in [
        (form.specular, via.specular, direct.specular),
        (form.scattered, via.scattered, direct.scattered),
    ]
    .into_iter()
    .enumerate()
    {
        if lobe == 1 && skip_scattered {
            tally.capped += 1;
            continue;
        }
        let mm = m.matrix();
        compare_lobe(
            tally,
            (level, lobe),
            v.vector(),
            d.vector(),
            (mm == Matrix4::zeros(), &pbsdf[lobe]),
            mm.amax(),
            p.stokes().s0(),
            rel,
        )?;
    }
    Ok(form)
}

/// Validity of one matrix: Cloude-realizable if `cloude`, and `M S` valid for every probe, to
/// `validity · κ` ([`conditioning`]).
fn check_validity<T: Real>(
    tally: &mut Tally,
    what: &str,
    m: &Mueller<T>,
    probes: &[Stokes<T>],
    (cloude, kappa): (bool, f64),
    tol: Tolerances,
) -> Result<(), TestCaseError> {
    let mm = m.matrix().map(T::to_f64);
    if mm != Matrix4::zeros() && mm.amax() < T::MIN_POSITIVE.to_f64() {
        // Every entry subnormal: a few digits each (see `subnormal_matrices_are_flushed`).
        tally.subnormal += 1;
        return Ok(());
    }
    if cloude && mm != Matrix4::zeros() {
        prop_assert!(
            m.is_physically_realizable(T::lit(tol.cloude)),
            "{what}: not realizable: {mm}"
        );
        let l = m.coherency_eigenvalues().map(T::to_f64);
        let trace = l.sum();
        tally.worst_cloude = tally.worst_cloude.max(-l.min() / trace);
    }
    for s in probes {
        // Normalised first: the squares of entries ~1e-159 would be subnormal.
        let n = mm.amax();
        if n == 0.0 {
            continue;
        }
        let out = (mm / n) * s.vector().map(T::to_f64);
        let pol = Vector3::new(out[1], out[2], out[3]).norm();
        // The size of the terms of M S (for two shapes |M_ij| ≤ M₀₀ fails; M S can cancel).
        let scale = s.s0().to_f64();
        if scale > 0.0 {
            let excess = (pol - out[0]) / scale;
            prop_assert!(
                excess <= tol.validity * kappa,
                "{what}: M S invalid: S = {:?}, M S = {out:?} (excess {excess:e})",
                s.vector()
            );
            tally.worst_validity = tally.worst_validity.max(excess / kappa);
        }
    }
    Ok(())
}

/// The three polarization levels at coherence level `ci` (0 plane wave, 1 partial, 2
/// incoherent) with the coherence model `coh`; `capped`: the blur's two-shape weights break
/// Cauchy–Schwarz here (the Full level's scattered lobe is then not compared).
fn coherence_level<T, P, Sp, Sc, Coh>(
    tally: &mut Tally,
    ci: usize,
    coh: Coh,
    material: &RoughSurface<P, Sp, Sc>,
    built: &Built<T>,
    capped: bool,
) -> Result<(), TestCaseError>
where
    T: Real,
    P: Psd<T, 2>,
    Sp: Pbsdf<T>,
    Sc: Pbsdf<T>,
    Coh: CoherenceWeights<T, P>,
{
    let tol = tolerances::<T>();
    let (p, g) = (&built.packet, &built.geometry);
    let s0 = p.stokes().s0();
    let kernel = Kernel::<Intensity, Coh>::new(coh.clone());
    let direct = kernel.evaluate(material, p, g);
    let scalar = kernel.evaluate_mueller(material, p, g);
    let via = scalar.apply(s0);
    prop_assert_eq!(via.attenuation, direct.attenuation);
    let pbsdf = pbsdf_matrices(material, g);
    for (lobe, (m, v, d)) in [
        (scalar.specular, via.specular, direct.specular),
        (scalar.scattered, via.scattered, direct.scattered),
    ]
    .into_iter()
    .enumerate()
    {
        let z = T::zero();
        compare_lobe(
            tally,
            (3 * ci, lobe),
            Vector4::new(v, z, z, z),
            Vector4::new(d, z, z, z),
            (m == z, &pbsdf[lobe]),
            m,
            s0,
            tol.rel,
        )?;
    }
    let one = stokes_level(
        tally,
        3 * ci + 1,
        &Kernel::<OneShape, Coh>::new(coh.clone()),
        material,
        built,
        (tol.rel, false),
    )?;
    let full = stokes_level(
        tally,
        3 * ci + 2,
        &Kernel::<Full, Coh>::new(coh),
        material,
        built,
        (tol.rel, capped),
    )?;
    // The intensity level is the one-shape level's M₀₀ (the rotation T keeps S0).
    for (a, m) in [
        (scalar.specular, one.specular),
        (scalar.scattered, one.scattered),
    ] {
        let (a, b) = (a.to_f64(), m.matrix()[(0, 0)].to_f64());
        prop_assert!(
            // 8 ulps, or 64 subnormal ulps where the values are subnormal (their few digits).
            (a - b).abs()
                <= T::EPSILON.to_f64()
                    * (8.0 * a.abs().max(b.abs()) + 64.0 * T::MIN_POSITIVE.to_f64()),
            "{}: intensity {a:e} vs one-shape M₀₀ {b:e}",
            LEVELS[3 * ci]
        );
    }
    for (lobe, (o, f)) in [
        (one.specular, full.specular),
        (one.scattered, full.scattered),
    ]
    .iter()
    .enumerate()
    {
        let name = |l: usize| format!("{} lobe {lobe}", LEVELS[3 * ci + l]);
        let kappa = conditioning(&pbsdf_matrices(material, g)[lobe]);
        check_validity(tally, &name(1), o, &built.probes, (true, kappa), tol)?;
        let two = (p.has_single_shape(), kappa);
        check_validity(tally, &name(2), f, &built.probes, two, tol)?;
    }
    Ok(())
}

/// `K_½ |μ|_max / √(K_x K_y)` of the blurred weights `blur` gives the three channels at the
/// case's geometry (`surface_coherence_term`): ≤ 1 for exact weights (Cauchy–Schwarz over the
/// positive semidefinite spectral matrix of an admitted packet, `crate::packet`), 0 for one
/// shape.
fn cauchy_schwarz_ratio<T, P, Sp, Sc, B>(
    material: &RoughSurface<P, Sp, Sc>,
    blur: &B,
    built: &Built<T>,
) -> f64
where
    T: Real,
    P: Psd<T, 2>,
    B: BlurMethod<T, 2, P>,
{
    let (p, g) = (&built.packet, &built.geometry);
    if p.has_single_shape() {
        return 0.0;
    }
    let k = [Channel::X, Channel::Y, Channel::Half]
        .map(|c| surface_coherence_term(&material.psd, blur, p, c, g.surface(), &g.h_t()).to_f64());
    let shapes = [Channel::X, Channel::Y].map(|c| p.shape(c).map(T::to_f64));
    k[2] * mu_max(&shapes[0], &shapes[1]) / (k[0] * k[1]).sqrt()
}

/// All nine levels for one material.
fn all_levels<T, P, Sp, Sc, B>(
    tally: &mut Tally,
    material: &RoughSurface<P, Sp, Sc>,
    blur: B,
    eta: Option<f64>,
    case: &Case,
) -> Result<(), TestCaseError>
where
    T: Real,
    P: Psd<T, 2>,
    Sp: Pbsdf<T>,
    Sc: Pbsdf<T>,
    B: BlurMethod<T, 2, P> + Clone + std::fmt::Debug,
{
    let built = Built::<T>::new(case, eta);
    // Where the blur's weights break Cauchy–Schwarz beyond rounding the two forms used to cap
    // `K_½` differently (the matrix form for `|μ|_max`, the Stokes form for `|μ|`).
    // Both forms now cap for `|μ|_max`, so these are compared too; the count is reported.
    if cauchy_schwarz_ratio(material, &blur, &built) > 1.0 + 1e-6 {
        tally.capped += 1;
    }
    coherence_level(tally, 0, PlaneWave, material, &built, false)?;
    coherence_level(tally, 1, Partial(blur), material, &built, false)?;
    coherence_level(tally, 2, Incoherent, material, &built, false)
}

fn one_case<T: Real>(tally: &mut Tally, case: &Case) -> Result<(), TestCaseError> {
    tally.cases += 1;
    match case.material {
        0 => all_levels::<T, _, _, _, _>(tally, &glass::<T>(), ClosedForm, Some(ETA), case),
        1 => all_levels::<T, _, _, _, _>(tally, &gold::<T>(), ClosedForm, None, case),
        2 => all_levels::<T, _, _, _, _>(
            tally,
            &k_correlated::<T>(),
            GaussHermite::<T>::new(8).unwrap(),
            Some(ETA),
            case,
        ),
        3 => all_levels::<T, _, _, _, _>(tally, &mixture::<T>(), ClosedForm, Some(ETA), case),
        _ => all_levels::<T, _, _, _, _>(tally, &grating::<T>(), ClosedForm, None, case),
    }
}

/// Runs the property over `cases` cases and checks that most lobes were compared.
/// A runner with the crate's fixed-seed configuration (`tests/common`); failures are reported
/// with their case (these runners are not `proptest!` blocks, so there is no source file to
/// persist them next to).
fn runner(cases: u32) -> TestRunner {
    let mut config = common::proptest_config(cases);
    config.failure_persistence = None;
    TestRunner::new(config)
}

fn matrix_form_equals_stokes_form<T: Real>(name: &str, cases: u32) {
    let tally = RefCell::new(Tally::default());
    let mut runner = runner(cases);
    runner
        .run(&case(), |c| one_case::<T>(&mut tally.borrow_mut(), &c))
        .unwrap();
    let t = tally.into_inner();
    t.report(name);
    for (level, level_name) in LEVELS.iter().enumerate() {
        let total = |l: usize| t.compared[level][l] + t.both_zero[level][l] + t.flushed[level][l];
        for lobe in 0..2 {
            let what = format!("{name} {level_name} lobe {lobe}");
            // Skipped (flushed to 0 with the Stokes form nonzero): far tails only.
            assert!(
                t.flushed[level][lobe] * 10 <= total(lobe),
                "{what}: {} of {} flushed",
                t.flushed[level][lobe],
                total(lobe)
            );
            if level < 3 && lobe == 0 {
                // The plane-wave specular lobe is a Dirac delta: 0 in both forms, always.
                assert_eq!(t.both_zero[level][0], total(0), "{what}: a delta in eval");
            } else {
                // A nonzero result compared (the rest is 0 in both forms: lobes narrower than
                // the exits' spread, grating orders, the incoherent level's coherence lobe).
                assert!(
                    t.compared[level][lobe] * 5 >= total(lobe) * 2,
                    "{what}: only {} of {} compared nonzero",
                    t.compared[level][lobe],
                    total(lobe)
                );
            }
        }
    }
}

#[test]
fn matrix_form_equals_stokes_form_f64() {
    matrix_form_equals_stokes_form::<f64>("f64", 2048);
}

#[test]
fn matrix_form_equals_stokes_form_f32() {
    matrix_form_equals_stokes_form::<f32>("f32", 2048);
}

/// A case with a quadrature blur whose two-shape weights break Cauchy–Schwarz
/// (`Tally::capped`). Before the fix the matrix form capped `K_½` for `|μ|_max` and the Stokes
/// form for the packet's own `|μ|`, and they disagreed; now both cap for `|μ|_max`. K-correlation blurred by `GaussHermite(8)`, rough glass
/// lit from below at 5.5°, `Θ_x ≈ (2.0 µm)² · diag(1, 0.24)`, `Θ_y = (1 µm)² · diag(1, 0.61)`,
/// `|μ| = 0.98 |μ|_max`: `K_½|μ|_max/√(K_x K_y)` is 1.075 with 8 nodes (0.968 with an adaptive
/// blur), and the scattered lobe's S1 differs by 1.5 %, S2 by 5 % (f64). In f32 a case with
/// `|μ| = 0.1 |μ|_max` has the ratio 1.99 and S2 off by a factor 2.
#[test]
fn two_shape_forms_agree_with_a_quadrature_blur() {
    let case = Case {
        material: 2,
        tilt: (0.0, 0.0),
        incidence: (5.5472854298385625, 290.57412820552463, true),
        psi: -1.4812816707669376,
        stokes: (1.0, 0.0, 0.0, 0.0),
        shapes: (
            true,
            (2.020597699612936, 2.026372333150757, 2.404425182857418),
            (1.0, 1.277051031486104, 0.0),
            0.9809935032190285,
            0.0,
        ),
        exit: (
            false,
            false,
            4.838380975832933,
            306.18170771808394,
            (0.0, 0.0),
        ),
        probes: [(0.0, 0.0, 0.0); 3],
    };
    let built = Built::<f64>::new(&case, Some(ETA));
    let m = k_correlated::<f64>();
    let blur = GaussHermite::new(8).unwrap();
    let ratio = cauchy_schwarz_ratio(&m, &blur, &built);
    println!("K_½ |μ|_max / √(K_x K_y) with GaussHermite(8): {ratio:.4}");
    let kernel = Kernel::<Full, _>::new(Partial(blur));
    let (p, g) = (&built.packet, &built.geometry);
    let via = kernel
        .evaluate_mueller(&m, p, g)
        .apply(&p.stokes())
        .scattered;
    let direct = kernel.evaluate(&m, p, g).scattered;
    println!("matrix form {via:?}\nStokes form {direct:?}");
    common::assert_all_close(
        "two-shape scattered lobe, matrix vs Stokes form",
        via.vector().iter().copied(),
        direct.vector().iter().copied(),
        Tol::new(0.0, 1e-12),
    );
}

/// A matrix whose entries are all subnormal keeps only a few digits per entry: not realizable,
/// and `M S` not valid (`Tally::subnormal`). The flush used to test the scale `e^{ln e}` alone,
/// not the entries `m e` (it now tests both): a scale just above `MIN_POSITIVE` times a pBSDF of entries ~1e-3 (grazing
/// transmission of the mixture glass in f32, 89.88° in, 87.65° out) gives entries ~4e-42.
#[test]
fn subnormal_matrices_are_flushed() {
    let case = Case {
        material: 3,
        tilt: (0.0, 0.0),
        incidence: (89.88021534956519, 181.49313745809027, false),
        psi: 0.0,
        stokes: (1.0, 0.0, 0.0, 0.0),
        shapes: (false, (1.0, 1.0, 0.0), (1.0, 1.0, 0.0), 0.0, 0.0),
        exit: (
            true,
            false,
            87.65290935263941,
            68.58219019459501,
            (0.0, 0.0),
        ),
        probes: [(0.0, 0.0, 0.0); 3],
    };
    let built = Built::<f32>::new(&case, Some(ETA));
    let m = mixture::<f32>();
    let r = Kernel::<OneShape, PlaneWave>::default().evaluate_mueller(
        &m,
        &built.packet,
        &built.geometry,
    );
    let mm = r.scattered.matrix();
    println!(
        "largest entry {:e} (MIN_POSITIVE {:e})",
        mm.amax(),
        f32::MIN_POSITIVE
    );
    assert!(
        mm == Matrix4::zeros() || mm.amax() >= f32::MIN_POSITIVE,
        "a nonzero matrix with every entry subnormal: {mm:e}"
    );
}

// ------------------------------------------------------------------ the two-shape cap

/// The Full level's cap `K_½ ≤ √(K_x K_y)/|μ|_max` is exact at the specular direction (`h_t = 0`:
/// `K_α = 2π/√|Ξ_α|`, `|Ξ_α| = |A|²/|Θ_α|`), so the cap is sharp there. For `Θ_x = w² I`,
/// `Θ_y = 4 w² I` (`|μ|_max = 0.8`, `r = K_x/K_y = √(|Θ_x|/|Θ_y|) = 1/4`) the vector at the bound,
/// `(1, 0, 0.8, 0)`, leaves fully polarized; the fully correlated `(1, 0, 1, 0)` — which
/// `WavePacket::new` rejects for these shapes — becomes `((1 + r), (r − 1), 2√r/|μ|_max, 0)/2` before
/// the Fresnel matrix, of degree `√((1 − r)² + 4r/|μ|²_max)/(1 + r) = 1.1662`: at normal incidence
/// (where the Fresnel matrix keeps the degree) that is what leaves, and at 30° it leaves invalid
/// (`|S_pol| > S0`). Near the specular direction every admitted vector stays valid.
#[test]
fn two_shape_matrix_is_valid_exactly_on_the_admitted_vectors() {
    let m = glass::<f64>();
    let surface = Frame::from_normal(Vector3::new(0.1, 0.2, 1.0)).unwrap();
    let w = 10.0;
    let (wx, wy) = (
        CoherenceShape::isotropic(w).unwrap(),
        CoherenceShape::isotropic(2.0 * w).unwrap(),
    );
    let mu = mu_max(&wx.matrix(), &wy.matrix());
    assert!((mu - 0.8).abs() < 1e-15);
    let kernel = Kernel::<Full, Partial>::default();
    let dop = |v: Vector4<f64>| Vector3::new(v[1], v[2], v[3]).norm() / v[0];
    for theta in [0.0, 30.0] {
        let s = local(&surface, theta, 40.0, 1.0);
        let frame = Frame::sp(-s, surface.k()).unwrap();
        let admitted = Stokes::new(1.0, 0.0, mu, 0.0).unwrap();
        let full = Stokes::new(1.0, 0.0, 1.0, 0.0).unwrap();
        assert!(matches!(
            WavePacket::new(full, wx, wy, frame, LAMBDA),
            Err(Error::Unrealizable { .. })
        ));
        let packet = WavePacket::new(admitted, wx, wy, frame, LAMBDA).unwrap();
        let g = m.geometry_for_packet(&packet, &surface, s).unwrap();
        let spec = g.specular_direction().unwrap();
        let g = m.geometry_for_packet(&packet, &surface, spec).unwrap();
        assert!(g.h_t().norm() < 1e-12);
        let mm = kernel.evaluate_mueller(&m, &packet, &g).specular.matrix();
        let (at_bound, beyond) = (dop(mm * admitted.vector()), dop(mm * full.vector()));
        println!(
            "θ_i = {theta}°: DoP of (1, 0, |μ|_max, 0) → {at_bound:.15}, of (1, 0, 1, 0) → {beyond:.6}"
        );
        common::assert_close(
            "admitted vector at the bound",
            at_bound,
            1.0,
            Tol::new(1e-13, 0.0),
        );
        if theta == 0.0 {
            let r = 0.25;
            let expected = ((1.0 - r) * (1.0 - r) + 4.0 * r / (mu * mu)).sqrt() / (1.0 + r);
            common::assert_close(
                "DoP beyond the bound",
                beyond,
                expected,
                Tol::new(1e-12, 0.0),
            );
        } else {
            assert!(
                beyond > 1.01,
                "(1, 0, 1, 0) should leave invalid: DoP {beyond}"
            );
        }
        // Admitted vectors (|μ| ≤ |μ|_max, any S_x/S_y and phase) near the specular direction.
        let mut rng = common::SplitMix64(7 + theta as u64);
        for _ in 0..200 {
            let f = g.surface();
            let off = 3.0 / (g.k() * w);
            let r = spec + f.x() * (rng.signed() * off) + f.y() * (rng.signed() * off);
            let g = m.geometry_for_packet(&packet, &surface, r).unwrap();
            let mm = kernel.evaluate_mueller(&m, &packet, &g).specular.matrix();
            let v = stokes_with_correlation(
                1.0,
                rng.signed() * 0.99,
                mu * rng.unit().sqrt(),
                rng.uniform_in(0.0, 6.3),
            );
            let out = mm * v;
            if out[0] > 0.0 {
                assert!(dop(out) <= 1.0 + 1e-12, "admitted {v:?} → {out:?}");
            }
        }
    }
}

// ------------------------------------------------------------------ Bsdf against the kernel

/// `Bsdf::eval(..).response` is `Kernel::evaluate_mueller` and `Bsdf::eval_stokes` is
/// `Kernel::evaluate` for the same packet and the geometry `eval` reports (bit for bit: the same
/// per-packet work and evaluation), from both sides of glass and on a conductor, f64 and f32.
fn bsdf_matches_kernel<T: Real>() {
    let f = Frame::<T>::from_normal(Vector3::new(T::lit(0.2), T::lit(-0.1), T::one())).unwrap();
    let c = SurfaceCoherence::new(T::lit(3.0)).unwrap();
    let kernel = Kernel::<Full, Partial>::default();
    let glass = glass::<T>();
    let gold = gold::<T>();
    let bg = Bsdf::new(&glass, kernel, f, T::lit(LAMBDA)).unwrap();
    let bm = Bsdf::new(&gold, kernel, f, T::lit(LAMBDA)).unwrap();
    let stokes = Stokes::new(T::one(), T::lit(0.3), T::lit(-0.4), T::lit(0.5)).unwrap();
    let mut rng = common::SplitMix64(11);
    for i in 0..200 {
        let s_side = if i % 2 == 0 { 1.0 } else { -1.0 };
        let s = local(
            &f,
            rng.uniform_in(0.0, 89.0),
            rng.uniform_in(0.0, 360.0),
            s_side,
        );
        let r_side = if rng.unit() < 0.5 { 1.0 } else { -1.0 };
        let r = local(
            &f,
            rng.uniform_in(0.0, 89.0),
            rng.uniform_in(0.0, 360.0),
            r_side,
        );
        let packet = bg
            .surface_packet(stokes, s, &c)
            .unwrap()
            .rotated(T::lit(0.7));
        let inc = bg.prepare(&packet).unwrap();
        let v = bg.eval(&inc, r).unwrap();
        // The coherent lobe divided by its mass over the propagating directions.
        let norm = inc.specular_mass(v.geometry.side()).recip();
        assert_eq!(
            v.response,
            kernel
                .evaluate_mueller(&glass, &packet, &v.geometry)
                .specular_scaled(norm)
        );
        assert_eq!(
            bg.eval_stokes(&inc, r).unwrap(),
            kernel
                .evaluate(&glass, &packet, &v.geometry)
                .specular_scaled(norm)
        );
        if s_side > 0.0 && r_side > 0.0 {
            let inc = bm.prepare(&packet).unwrap();
            let v = bm.eval(&inc, r).unwrap();
            let norm = inc.specular_mass(v.geometry.side()).recip();
            assert_eq!(
                v.response,
                kernel
                    .evaluate_mueller(&gold, &packet, &v.geometry)
                    .specular_scaled(norm)
            );
            assert_eq!(
                bm.eval_stokes(&inc, r).unwrap(),
                kernel
                    .evaluate(&gold, &packet, &v.geometry)
                    .specular_scaled(norm)
            );
        }
    }
}

#[test]
fn bsdf_eval_is_the_kernel_f64_and_f32() {
    bsdf_matches_kernel::<f64>();
    bsdf_matches_kernel::<f32>();
}

/// `Bsdf::prepare` accepts a packet at the wavelength of the medium it arrives from and rejects
/// the vacuum wavelength inside the glass, the glass wavelength in the air, and another
/// wavelength (`Error::OutOfRange`); `Bsdf::wavelength` names the right one.
#[test]
fn prepare_rejects_a_packet_at_the_wrong_wavelength() {
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let glass = glass::<f64>();
    let b = Bsdf::new(&glass, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let c = SurfaceCoherence::new(3.0).unwrap();
    let u = Stokes::unpolarized(1.0).unwrap();
    let (above, below) = (local(&f, 30.0, 20.0, 1.0), local(&f, 25.0, 200.0, -1.0));
    assert!((b.wavelength(&above).unwrap() - LAMBDA).abs() < 1e-15);
    assert!((b.wavelength(&below).unwrap() - LAMBDA / ETA).abs() < 1e-15);
    for (s, lambda, ok) in [
        (above, LAMBDA, true),
        (below, LAMBDA / ETA, true),
        (below, LAMBDA, false),       // the vacuum wavelength inside the glass
        (above, LAMBDA / ETA, false), // the glass wavelength in the air
        (above, 0.6, false),
        (below, 0.6 / ETA, false),
        (above, LAMBDA * (1.0 + 1e-9), false),
    ] {
        let packet = c.packet(u, s, &f, lambda).unwrap();
        let r = b.prepare(&packet);
        if ok {
            assert!(r.is_ok(), "λ = {lambda} from {s:?}");
        } else {
            assert!(
                matches!(r, Err(Error::OutOfRange { .. })),
                "λ = {lambda} from {s:?} accepted"
            );
        }
    }
    // An opaque surface is lit from above only.
    let gold = gold::<f64>();
    let b = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    assert!(b.prepare(&c.packet(u, below, &f, LAMBDA).unwrap()).is_err());
}

/// `Kernel::try_evaluate` accepts the packet's own geometry (to a rounding of the direction) and
/// rejects one built for another wavelength, for the packet's wavelength in the other medium, or
/// for another source direction.
#[test]
fn try_evaluate_rejects_a_foreign_geometry() {
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let glass = glass::<f64>();
    let kernel = Kernel::<Full, Partial>::default();
    let c = SurfaceCoherence::new(3.0).unwrap();
    let u = Stokes::unpolarized(1.0).unwrap();
    let s = local(&f, 30.0, 20.0, -1.0); // from inside the glass
    let packet = c.packet(u, s, &f, LAMBDA / ETA).unwrap();
    let r = local(&f, 10.0, 150.0, 1.0);
    let k = packet.wavenumber();
    let geometry = |k: f64, s: Vector3<f64>| glass.geometry(k, &f, s, r).unwrap();
    assert!(
        kernel
            .try_evaluate(&glass, &packet, &geometry(k, s))
            .is_ok()
    );
    let nudged = s + Vector3::new(1e-15, -1e-15, 0.0);
    assert!(
        kernel
            .try_evaluate(&glass, &packet, &geometry(k, nudged))
            .is_ok()
    );
    let tau = std::f64::consts::TAU;
    for (what, g) in [
        ("vacuum wavenumber", geometry(tau / LAMBDA, s)),
        ("another wavelength", geometry(tau / 0.6 * ETA, s)),
        ("k (1 + 1e-12)", geometry(k * (1.0 + 1e-12), s)),
        (
            "another direction",
            geometry(k, local(&f, 31.0, 20.0, -1.0)),
        ),
        (
            "the mirrored direction",
            geometry(k, local(&f, 30.0, 200.0, -1.0)),
        ),
    ] {
        assert!(
            matches!(
                kernel.try_evaluate(&glass, &packet, &g),
                Err(Error::OutOfRange { .. })
            ),
            "{what} accepted"
        );
    }
}

/// The renderer layer on bad finite input (directions in the plane, zero vectors, exits below an
/// opaque surface, nonpositive widths and wavelengths, delta samples with garbage fields) and on
/// NaN, infinite and out-of-range uniforms: an error or a finite answer, never a panic.
fn nothing_panics<T: Real>() {
    let lit = T::lit;
    let f = Frame::<T>::from_normal(Vector3::new(lit(0.2), lit(-0.1), T::one())).unwrap();
    let glass = glass::<T>();
    let gold = gold::<T>();
    let smooth = SmoothDielectric::<T>::smooth(lit(ETA)).unwrap();
    let c = SurfaceCoherence::new(lit(3.0)).unwrap();
    let u = Stokes::unpolarized(T::one()).unwrap();
    let zero = Vector3::zeros();
    let tangent = f.x() * lit(0.6) + f.y() * lit(0.8);
    let below = local(&f, 20.0, 30.0, -1.0);
    let above = local(&f, 40.0, 10.0, 1.0);
    let nan = Vector3::new(T::lit(f64::NAN), T::one(), T::one());
    let directions = [
        zero,
        tangent,
        below,
        above,
        nan,
        f.k() * lit(1e30),
        f.k() * lit(1e-30),
    ];
    for lambda in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(Bsdf::new(&glass, Kernel::<Full, Partial>::default(), f, lit(lambda)).is_err());
    }
    for lambda in [1e-300, 1e300, 1e-30, 1e30] {
        // Accepted where 2π/λ and η 2π/λ are normal numbers of T, rejected otherwise.
        let _ = Bsdf::new(&glass, Kernel::<Full, Partial>::default(), f, lit(lambda));
    }
    for w in [0.0, -1.0, 1e-300, 1e300, f64::INFINITY] {
        assert!(SurfaceCoherence::new(lit(w)).is_err(), "width {w}");
    }
    assert!(Frame::<T>::from_normal(zero).is_err() && Frame::<T>::from_normal(nan).is_err());
    let uniforms = [
        0.0,
        1.0,
        -1.0,
        2.0,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        0.999_999_9,
    ];
    let finite = |m: &Matrix4<T>| m.iter().all(|x| x.is_finite());
    macro_rules! exercise {
        ($b:expr) => {{
            let b = $b;
            let _ = b.flags();
            for d in directions {
                let _ = b.wavenumber(&d);
                let _ = b.surface_packet(u, d, &c);
                let _ = b.distant_packet(u, lit(6.8e-5), d);
                let _ = b.distant_packet(u, T::zero(), d);
                let _ = b.incident_sampler(d, &c);
                for e in directions {
                    let _ = b.geometry(d, e);
                }
            }
            for s in [above, below] {
                let Ok(packet) = b.surface_packet(u, s, &c) else {
                    continue;
                };
                let Ok(inc) = b.prepare(&packet) else {
                    continue;
                };
                for e in directions {
                    if let Ok(v) = b.eval(&inc, e) {
                        assert!(finite(&v.response.total().matrix()), "eval along {e:?}");
                    }
                    let _ = b.eval_stokes(&inc, e);
                }
                let sampler = b.exit_sampler(&inc).unwrap();
                for &x in &uniforms {
                    let x = lit(x);
                    if let Ok(Some(s)) = b.sample_exit(&inc, x, [x, x]) {
                        assert!(
                            finite(&s.weight.matrix()) && s.sample.pdf.is_finite(),
                            "{s:?}"
                        );
                    }
                    if let Some(mut s) = sampler.sample(x, [x, x]) {
                        let _ = b.exit_weight(&inc, &s);
                        s.direction = zero;
                        assert!(b.exit_weight(&inc, &s).is_err());
                        s.direction = tangent;
                        let _ = b.exit_weight(&inc, &s);
                    }
                }
            }
            for e in directions {
                for &x in &uniforms {
                    let x = lit(x);
                    if let Ok(Some(s)) = b.sample_incident(e, &c, x, [x, x]) {
                        assert!(finite(&s.weight.matrix()), "{s:?}");
                    }
                }
            }
        }};
    }
    exercise!(Bsdf::new(&glass, Kernel::<Full, Partial>::default(), f, lit(LAMBDA)).unwrap());
    exercise!(
        Bsdf::new(
            &glass,
            Kernel::<OneShape, PlaneWave>::default(),
            f,
            lit(LAMBDA)
        )
        .unwrap()
    );
    exercise!(Bsdf::new(&gold, Kernel::<Full, Incoherent>::default(), f, lit(LAMBDA)).unwrap());
    exercise!(
        Bsdf::new(
            &smooth,
            Kernel::<Full, PlaneWave>::default(),
            f,
            lit(LAMBDA)
        )
        .unwrap()
    );
    // Below an opaque surface: every call that needs a direction there is an error.
    let b = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), f, lit(LAMBDA)).unwrap();
    assert!(b.wavenumber(&below).is_err() && b.incident_sampler(below, &c).is_err());
    assert!(b.surface_packet(u, below, &c).is_err() && b.geometry(above, below).is_err());
    let inc = b.prepare(&b.surface_packet(u, above, &c).unwrap()).unwrap();
    assert!(b.eval(&inc, below).is_err() && b.eval(&inc, zero).is_err());
    assert!(b.eval(&inc, nan).is_err());
    // Exactly in the plane (an untilted frame: `tangent` above is a few ulps off it).
    let flat = Frame::<T>::from_normal(Vector3::z()).unwrap();
    let in_plane = Vector3::new(lit(0.6), lit(0.8), T::zero());
    let b = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), flat, lit(LAMBDA)).unwrap();
    let inc = b.prepare(&b.surface_packet(u, above, &c).unwrap()).unwrap();
    assert!(b.eval(&inc, in_plane).is_err() && b.surface_packet(u, in_plane, &c).is_err());
    assert!(b.incident_sampler(in_plane, &c).is_err() && b.wavenumber(&in_plane).is_err());
    let b = Bsdf::new(
        &glass,
        Kernel::<Full, Partial>::default(),
        flat,
        lit(LAMBDA),
    )
    .unwrap();
    let inc = b.prepare(&b.surface_packet(u, above, &c).unwrap()).unwrap();
    assert!(b.eval(&inc, in_plane).is_err() && b.incident_sampler(in_plane, &c).is_err());
}

#[test]
fn bad_input_gives_errors_not_panics() {
    nothing_panics::<f64>();
    nothing_panics::<f32>();
}

// ------------------------------------------------------------------ delta lobes

/// `∫ F(h) d²h` entry by entry over the disk `|h − centre| ≤ 9/w` (a lobe `𝒩(centre, I/w²)` to
/// `e^{−40}`), in polar coordinates about `centre`: adaptive Gauss–Legendre
/// (`tests/common/quadrature.rs`) in the angle and the radius, to `1e-11` of the peak's
/// integral. `F` is 0 where it returns `None` (an evanescent direction). The sixteen entries are
/// integrated one after the other on the same nodes, so `F` is evaluated once per node (cached).
fn lobe_integral(
    centre: Vector2<f64>,
    w: f64,
    f: &dyn Fn(Vector2<f64>) -> Option<Matrix4<f64>>,
) -> Matrix4<f64> {
    let cache = RefCell::new(std::collections::HashMap::<(u64, u64), Matrix4<f64>>::new());
    let at = |psi: f64, rho: f64| {
        *cache
            .borrow_mut()
            .entry((psi.to_bits(), rho.to_bits()))
            .or_insert_with(|| {
                let h = centre + Vector2::new(psi.cos(), psi.sin()) * (rho / w);
                f(h).map_or(Matrix4::zeros(), |m| m * (rho / (w * w)))
            })
    };
    let peak = f(centre).expect("the lobe's centre propagates").amax();
    let tol = 1e-11 * peak / (w * w);
    Matrix4::from_fn(|i, j| {
        integrate(
            &mut |psi| integrate(&mut |rho| at(psi, rho)[(i, j)], 0.0, 9.0, 3, tol),
            0.0,
            std::f64::consts::TAU,
            2,
            tol,
        )
    })
}

/// The direction on side `side` (±1 along n̂ of `f`) of wavenumber `k_b` whose tangential
/// scattering vector with the known direction `d_a` (wavenumber `k_a`) is `h`:
/// `u_b = (h − k_a u_a)/k_b` in the tangents of `f`; `None` where it is evanescent.
fn direction_of(
    f: &Frame<f64>,
    (d_a, k_a): (Vector3<f64>, f64),
    (side, k_b): (f64, f64),
    h: Vector2<f64>,
) -> Option<Vector3<f64>> {
    let ua = Vector2::new(d_a.dot(&f.x()), d_a.dot(&f.y()));
    let u = (h - ua * k_a) / k_b;
    let c2 = 1.0 - u.norm_squared();
    (c2 > 0.0).then(|| f.x() * u.x + f.y() * u.y + f.k() * (side * c2.sqrt()))
}

const WIDTHS: [f64; 3] = [50.0, 200.0, 1000.0];

/// The delta's throughput `A` against the partially coherent lobe's integrals `I(w)`: prints
/// `|I(w) − A|/|A|` and the Richardson extrapolation in `1/w²` of the two widest; asserts that
/// the deviation falls at least as fast as `1/w`, is below `tol` at 1000 µm, and that the
/// extrapolation is the delta to 1e-10 (measured ≤ 8e-14; the deviations fall as `1/w²`).
fn compare_with_limit(name: &str, delta: &Matrix4<f64>, integrals: &[Matrix4<f64>; 3], tol: f64) {
    let dev: Vec<f64> = integrals
        .iter()
        .map(|i| (i - delta).amax() / delta.amax())
        .collect();
    let (a, b) = (integrals[1], integrals[2]);
    let r = (b * (WIDTHS[2] / WIDTHS[1]).powi(2) - a) / ((WIDTHS[2] / WIDTHS[1]).powi(2) - 1.0);
    let extrapolated = (r - delta).amax() / delta.amax();
    println!(
        "{name}: |I(w) − A|/|A| at w = 50, 200, 1000 µm: {:.2e} {:.2e} {:.2e}; extrapolated {extrapolated:.2e}; A₀₀ = {:.6e}",
        dev[0],
        dev[1],
        dev[2],
        delta[(0, 0)]
    );
    assert!(
        dev[2] <= tol,
        "{name}: lobe integral at 1000 µm off the delta by {:e}",
        dev[2]
    );
    // The lobe's integral is A (1 + c/w² + O(1/w⁴)): the extrapolation removes c/w².
    assert!(
        extrapolated <= 1e-10,
        "{name}: extrapolated limit off the delta by {extrapolated:e}"
    );
    assert!(
        dev[1] <= dev[0] * WIDTHS[0] / WIDTHS[1] + 1e-12,
        "{name}: no convergence: {dev:?}"
    );
}

type Glass = RoughDielectric<f64, GaussianPsd<f64, 2>>;

/// Forward: the delta of part `part` (0 reflected specular, 1 reflected scattered, 2
/// transmitted specular) drawn for light from `s`, its `weight × pdf`, against the integral
/// `∫ M cos θ_o/cos θ_i dω_o = ∫ M/(cos θ_i k_o²) d²h` of the `Partial` lobe about the same
/// centre. The packets are turned by `turn` in their frame (the rotation `T` is in both).
fn forward_delta<P, Sp, Sc>(
    name: &str,
    material: &RoughSurface<P, Sp, Sc>,
    (s, turn): (Vector3<f64>, f64),
    part: usize,
    tol: f64,
) where
    P: gmueller::psd::Psd<f64, 2>,
    Sp: gmueller::bsdf::Interface<f64>,
    Sc: Pbsdf<f64>,
    ClosedForm: BlurMethod<f64, 2, P>,
{
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let u = Stokes::unpolarized(1.0).unwrap();
    let plane = Bsdf::new(material, Kernel::<Full, PlaneWave>::default(), f, LAMBDA).unwrap();
    let c = SurfaceCoherence::new(50.0).unwrap();
    let inc = plane
        .prepare(&plane.surface_packet(u, s, &c).unwrap().rotated(turn))
        .unwrap();
    let mut probs = [0.0; 4];
    probs[part] = 1.0;
    let sample = plane
        .exit_sampler(&inc)
        .unwrap()
        .with_part_probabilities(probs)
        .sample(0.25, [0.5, 0.5])
        .unwrap();
    assert!(sample.lobe.delta, "{name}: not a delta: {sample:?}");
    let (weight, g) = plane.exit_weight(&inc, &sample).unwrap();
    let delta = weight.matrix() * sample.pdf;
    let centre = g.h_t(); // 0, or the grating order ζ_m (the oriented frame is f from above)
    let partial = Bsdf::new(material, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let (k_a, side) = (
        plane.wavenumber(&s).unwrap(),
        sample.direction.dot(&f.k()).signum(),
    );
    let k_b = plane.wavenumber(&sample.direction).unwrap();
    let integrals = WIDTHS.map(|w| {
        let c = SurfaceCoherence::new(w).unwrap();
        let inc = partial
            .prepare(&partial.surface_packet(u, s, &c).unwrap().rotated(turn))
            .unwrap();
        lobe_integral(centre, w, &|h| {
            let r = direction_of(&f, (s, k_a), (side, k_b), h)?;
            let v = partial.eval(&inc, r).ok()?;
            let m = if part.is_multiple_of(2) {
                v.response.specular
            } else {
                v.response.scattered
            };
            Some(m.matrix() / (v.geometry.cos_i() * k_b * k_b))
        })
    });
    compare_with_limit(name, &delta, &integrals, tol);
}

/// Backward: the delta drawn for light leaving along `r` (part `part` of the incident sampler),
/// `weight × pdf`, against `∫ M(ŝ → r̂) dω_s = ∫ M/(cos θ_s k_s²) d²h` of the `Partial` lobe (a
/// surface packet of width w from each ŝ).
fn backward_delta(name: &str, material: &Glass, r: Vector3<f64>, part: usize, tol: f64) {
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let u = Stokes::unpolarized(1.0).unwrap();
    let plane = Bsdf::new(material, Kernel::<Full, PlaneWave>::default(), f, LAMBDA).unwrap();
    let c = SurfaceCoherence::new(50.0).unwrap();
    let mut probs = [0.0; 4];
    probs[part] = 1.0;
    let sample = plane
        .incident_sampler(r, &c)
        .unwrap()
        .with_part_probabilities(probs)
        .sample(0.25, [0.5, 0.5])
        .unwrap();
    assert!(sample.lobe.delta, "{name}: not a delta: {sample:?}");
    let (weight, _) = plane.incident_weight(r, &c, &sample).unwrap();
    let delta = weight.matrix() * sample.pdf;
    let s = sample.direction;
    let partial = Bsdf::new(material, Kernel::<Full, Partial>::default(), f, LAMBDA).unwrap();
    let (k_a, k_b) = (plane.wavenumber(&r).unwrap(), plane.wavenumber(&s).unwrap());
    let side = s.dot(&f.k()).signum();
    let integrals = WIDTHS.map(|w| {
        let c = SurfaceCoherence::new(w).unwrap();
        lobe_integral(Vector2::zeros(), w, &|h| {
            let s = direction_of(&f, (r, k_a), (side, k_b), h)?;
            let light = partial.surface_packet(u, s, &c).ok()?;
            let v = partial.eval(&partial.prepare(&light).ok()?, r).ok()?;
            Some(v.response.specular.matrix() / (v.geometry.cos_i() * k_b * k_b))
        })
    });
    compare_with_limit(name, &delta, &integrals, tol);
}

/// The plane-wave level's Dirac throughputs are the limits of the partially coherent lobes
/// (module docs), forward for the specular reflection and transmission of rough glass (both
/// sides) and a grating's order, backward for the specular transmission and reflection; and
/// the backward delta for a pair `(ŝ, r̂)` is `η²` times the forward one for the same pair,
/// `η = n_o/n_i` (the exit medium's index over the source's):
/// ```text
/// forward  A = ∫ M cos θ_o/cos θ_i dω_o                    (r̂ about the specular direction of ŝ)
/// backward B = ∫ M dω_s = A (k_o/k_i)² = η² A              (M = A cos θ_i/cos θ_o δ(ω_o − ω_spec);
///          d²u_o = (k_i/k_o)² d²u_i by phase matching,  d²u = cos θ dω)
/// ```
/// so transmitted radiance carries the `n²` of the exit medium (air → glass: 2.25).
#[test]
fn delta_throughputs_are_the_limits_of_the_coherent_lobes() {
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let glass = glass::<f64>();
    let s = local(&f, 35.0, 30.0, 1.0);
    forward_delta("glass reflection, forward", &glass, (s, 0.4), 0, 1e-6);
    forward_delta(
        "glass transmission air → glass, forward",
        &glass,
        (s, 0.4),
        2,
        1e-6,
    );
    let up = local(&f, 25.0, 200.0, -1.0);
    forward_delta(
        "glass transmission glass → air, forward",
        &glass,
        (up, 0.4),
        2,
        1e-6,
    );
    let metal = grating::<f64>();
    let to_grating = (local(&f, 20.0, 0.0, 1.0), 0.4);
    forward_delta("grating order, forward", &metal, to_grating, 1, 1e-5);
    // Backward, for light leaving along the Snell direction of `s` inside the glass.
    let plane = Bsdf::new(&glass, Kernel::<Full, PlaneWave>::default(), f, LAMBDA).unwrap();
    let r = plane
        .geometry(s, -f.k())
        .unwrap()
        .specular_direction()
        .unwrap();
    backward_delta(
        "glass transmission air → glass, backward",
        &glass,
        r,
        2,
        1e-6,
    );
    // backward = η² forward for the same pair (forward with an unturned packet: T = I, as the
    // backward weight's incident s/p frame), in both transmissions and both reflections.
    let c = SurfaceCoherence::new(50.0).unwrap();
    let u = Stokes::unpolarized(1.0).unwrap();
    let draw = |sampler: gmueller::bsdf::LobeSampler<'_, f64>, part: usize| {
        let mut probs = [0.0; 4];
        probs[part] = 1.0;
        let d = sampler
            .with_part_probabilities(probs)
            .sample(0.25, [0.5, 0.5])
            .unwrap();
        assert!(d.lobe.delta);
        d
    };
    for (name, r, part, eta) in [
        ("air → glass", r, 2, ETA),
        ("glass → air", local(&f, 20.0, 70.0, 1.0), 2, 1.0 / ETA),
        ("reflection above", local(&f, 40.0, 100.0, 1.0), 0, 1.0),
        ("reflection below", local(&f, 30.0, 300.0, -1.0), 0, 1.0),
    ] {
        let back = draw(plane.incident_sampler(r, &c).unwrap(), part);
        let b = plane.incident_weight(r, &c, &back).unwrap().0.matrix() * back.pdf;
        let inc = plane
            .prepare(&plane.surface_packet(u, back.direction, &c).unwrap())
            .unwrap();
        let fwd = draw(plane.exit_sampler(&inc).unwrap(), part);
        assert!(
            (fwd.direction - r).norm() < 1e-12,
            "{name}: forward delta {:?} ≠ r̂",
            fwd.direction
        );
        let a = plane.exit_weight(&inc, &fwd).unwrap().0.matrix() * fwd.pdf;
        println!(
            "{name}: backward B₀₀ = {:.6e}, forward A₀₀ = {:.6e}, B₀₀/A₀₀ = {:.12}",
            b[(0, 0)],
            a[(0, 0)],
            b[(0, 0)] / a[(0, 0)]
        );
        common::assert_all_close(
            &format!("backward = η² × forward ({name})"),
            common::entries4(&b),
            common::entries4(&(a * (eta * eta))),
            Tol::new(1e-14 * b.amax(), 1e-12),
        );
    }
}

// ------------------------------------------------------------------ sources, frames, gratings

/// `Ξ` of a packet in the basis `(ŝ_perp, n̂ × ŝ_perp)` of the surface tangents (`ŝ_perp` the
/// incident beam's s vector, which lies in the surface), from `surface_inverse_coherence`.
fn section_in_sp_basis<T: Real>(p: &WavePacket<T>, surface: &Frame<T>) -> Matrix2<f64> {
    let facing = surface.facing(&-p.direction());
    let xi = surface_inverse_coherence(p, Channel::Half, &facing).unwrap();
    let xi = xi.covariance().map(T::to_f64);
    let n = facing.k().map(T::to_f64);
    let es = Frame::sp(-p.direction(), facing.k())
        .unwrap()
        .x()
        .map(T::to_f64);
    let ep = n.cross(&es);
    let (t1, t2) = (facing.x().map(T::to_f64), facing.y().map(T::to_f64));
    let b = Matrix2::new(es.dot(&t1), ep.dot(&t1), es.dot(&t2), ep.dot(&t2));
    b.transpose() * xi * b
}

/// `SurfaceCoherence::packet` for random directions from both sides of a tilted surface has
/// the section `Ξ = I/σ²`; the beam-isotropic `σ² I` (the trap of `bsdf::sources`) has
/// `diag(1/σ², cos²θ_i/σ²)` in the (s, in-plane tangent) basis instead.
fn surface_coherence_section<T: Real>(seed_tol: f64) {
    let mut runner = runner(256);
    let strategy = (
        (-0.5..0.5f64, -0.5..0.5f64),
        0.0..89.9f64,
        0.0..360.0f64,
        any::<bool>(),
        -1.0..2.0f64,
    );
    runner
        .run(&strategy, |((tx, ty), theta, phi, below, lw)| {
            let n = Vector3::new(T::lit(tx), T::lit(ty), T::one());
            let surface = Frame::<T>::from_normal(n).unwrap();
            let s = local(&surface, theta, phi, if below { -1.0 } else { 1.0 });
            let sigma = 10f64.powf(lw);
            // The width exactly σ (no horizon rule), whose section this checks.
            let c = SurfaceCoherence::fixed(T::lit(sigma)).unwrap();
            let u = Stokes::unpolarized(T::one()).unwrap();
            let p = c.packet(u, s, &surface, T::lit(LAMBDA)).unwrap();
            let xi = section_in_sp_basis(&p, &surface) * (sigma * sigma);
            // cos θ_i is a dot product (absolute error ~ε): relative ε/cos θ_i in Ξ near grazing.
            let grazing = 8.0 * T::EPSILON.to_f64() / theta.to_radians().cos();
            let tol = Tol::new(seed_tol + grazing, seed_tol + grazing);
            for (got, want) in common::entries4(&embed(&xi))
                .iter()
                .zip(common::entries4(&embed(&Matrix2::identity())))
            {
                prop_assert!(
                    tol.accepts(*got, want),
                    "σ²Ξ = {xi} (θ {theta}°, below {below})"
                );
            }
            let frame = Frame::sp(-s, surface.k()).unwrap();
            let trap = WavePacket::from_stokes(
                u,
                CoherenceShape::isotropic(T::lit(sigma)).unwrap(),
                frame,
                T::lit(LAMBDA),
            )
            .unwrap();
            let xi = section_in_sp_basis(&trap, &surface) * (sigma * sigma);
            let cos2 = theta.to_radians().cos().powi(2);
            let want = Matrix2::new(1.0, 0.0, 0.0, cos2);
            for (got, want) in common::entries4(&embed(&xi))
                .iter()
                .zip(common::entries4(&embed(&want)))
            {
                prop_assert!(
                    tol.accepts(*got, want),
                    "trap: σ²Ξ = {xi}, expected diag(1, {cos2})"
                );
            }
            Ok(())
        })
        .unwrap();
}

/// A 2×2 matrix in the top-left corner of a 4×4 one (for `common::entries4`).
fn embed(m: &Matrix2<f64>) -> Matrix4<f64> {
    Matrix4::from_fn(|i, j| if i < 2 && j < 2 { m[(i, j)] } else { 0.0 })
}

#[test]
fn surface_coherence_packet_has_section_identity_over_sigma_squared() {
    surface_coherence_section::<f64>(1e-12);
    surface_coherence_section::<f32>(2e-5);
}

/// `Frame::from_normal`: unit, mutually orthogonal, right-handed (`x̂ × ŷ = k̂`), `k̂ = n/|n|`, for
/// random normals including near and at `±ẑ` (the branch of Duff's basis) and magnitudes from
/// tiny to huge.
fn from_normal_is_orthonormal<T: Real>(magnitudes: [f64; 5], tol: f64) {
    let mut runner = runner(512);
    let direction = prop_oneof![
        common::unit_vector3(),
        (-1e-6..1e-6f64, -1e-6..1e-6f64, any::<bool>()).prop_map(|(x, y, up)| Vector3::new(
            x,
            y,
            if up { 1.0 } else { -1.0 }
        )),
        Just(Vector3::z()),
        Just(-Vector3::z()),
        (-1e-30..1e-30f64).prop_map(|x| Vector3::new(x, 0.0, -1.0)),
    ];
    runner
        .run(
            &(direction, proptest::sample::select(magnitudes.to_vec())),
            |(d, m)| {
                let n = (d * m).map(T::lit);
                let f = Frame::<T>::from_normal(n).unwrap();
                let (x, y, k) = (
                    f.x().map(T::to_f64),
                    f.y().map(T::to_f64),
                    f.k().map(T::to_f64),
                );
                let expected = n.map(T::to_f64) / n.map(T::to_f64).amax();
                let expected = expected / expected.norm();
                let t = Tol::new(tol, 0.0);
                for (what, a, b) in [
                    ("|x|", x.norm(), 1.0),
                    ("|y|", y.norm(), 1.0),
                    ("|k|", k.norm(), 1.0),
                    ("x·y", x.dot(&y), 0.0),
                    ("x·k", x.dot(&k), 0.0),
                    ("y·k", y.dot(&k), 0.0),
                    ("|x × y − k|", (x.cross(&y) - k).norm(), 0.0),
                    ("|k − n̂|", (k - expected).norm(), 0.0),
                ] {
                    prop_assert!(t.accepts(a, b), "{what} = {a:e} for n = {n:?}");
                }
                Ok(())
            },
        )
        .unwrap();
}

#[test]
fn from_normal_is_a_right_handed_orthonormal_frame() {
    from_normal_is_orthonormal::<f64>([1e-300, 1e-30, 1.0, 1e30, 1e300], 4e-15);
    from_normal_is_orthonormal::<f32>([1e-30, 1e-10, 1.0, 1e10, 1e30], 4e-7);
}

/// `Grating::sinusoidal_height(a, Λ, d)`: the two orders `±(2π/Λ) d̂` of efficiency `a²/4` and
/// nothing else, variance `a²/2`, for any length of `d`. These are the orders
/// `validation/src/kernel_side.rs::height_grating` builds along x̂ from public constructors (a
/// phase grating of depth `j₀,₁` crossed with a zeroth-order grating of efficiency
/// `a²/(4 J₁(j₀,₁)²)`, its ±1 orders of efficiency `a²/4` to bisection precision, variance
/// `a²/2` to 1e-9): the expected values here are the formula's, not that construction's. (Run
/// once against it from the validation crate, for (a, Λ) = (0.03, 2), (0.01, 5), (0.2, 1.3):
/// the same order positions bit for bit, efficiencies within 1.2e-14.)
#[test]
fn sinusoidal_height_grating_orders() {
    let mut runner = runner(256);
    let strategy = (
        1e-3..1.0f64,
        -1.0..2.0f64,
        0.0..std::f64::consts::TAU,
        -3.0..3.0f64,
    );
    runner
        .run(&strategy, |(a, lp, angle, ld)| {
            let period = 10f64.powf(lp);
            let d = Vector2::new(angle.cos(), angle.sin()) * 10f64.powf(ld);
            let g = Grating::<f64, 2>::sinusoidal_height(a, period, &d).unwrap();
            let z1 = Vector2::new(angle.cos(), angle.sin()) * (std::f64::consts::TAU / period);
            let orders = g.orders();
            prop_assert_eq!(orders.len(), 2);
            let t = Tol::new(1e-15, 1e-13);
            let mut signs = Vec::new();
            for (z, eta) in orders {
                let sign = if z.dot(&z1) > 0.0 { 1.0 } else { -1.0 };
                signs.push(sign);
                let want = z1 * sign;
                prop_assert!(
                    t.accepts(z.x, want.x) && t.accepts(z.y, want.y),
                    "order {z:?} vs {want:?}"
                );
                prop_assert!(
                    t.accepts(*eta, a * a / 4.0),
                    "efficiency {eta} vs {}",
                    a * a / 4.0
                );
            }
            prop_assert!(signs[0] != signs[1], "both orders on one side: {orders:?}");
            prop_assert!(t.accepts(Psd::<f64, 2>::variance(&g), a * a / 2.0));
            prop_assert!(g.dropped_efficiency().abs() <= 1e-15);
            Ok(())
        })
        .unwrap();
    // The validation harness's case (along x̂): a = 0.03 µm, Λ = 2 µm.
    let g = Grating::<f64, 2>::sinusoidal_height(0.03, 2.0, &Vector2::x()).unwrap();
    let zeta = std::f64::consts::TAU / 2.0;
    let mut xs: Vec<f64> = g.orders().iter().map(|(z, _)| z.x).collect();
    xs.sort_by(f64::total_cmp);
    assert_eq!(xs, vec![-zeta, zeta]);
    assert!(
        g.orders()
            .iter()
            .all(|(z, e)| z.y == 0.0 && (e - 2.25e-4).abs() < 1e-18)
    );
}

// ------------------------------------------------------------------ lobe flags

/// `Bsdf::flags` for each material at each of the nine levels: REFLECTION always, TRANSMISSION
/// exactly for dielectrics, DELTA exactly at the plane-wave level (the specular lobe; a grating's
/// orders too), `COHERENT_SPECULAR` exactly otherwise, SCATTERED for rough surfaces except a
/// grating of plane waves (its orders are deltas), never for smooth ones.
#[test]
fn lobe_flags_of_each_material_and_level() {
    let f = Frame::from_normal(Vector3::new(0.2, -0.1, 1.0)).unwrap();
    let (glass, gold, kc, mix, grat) = (glass(), gold(), k_correlated(), mixture(), grating());
    let smooth_glass = SmoothDielectric::<f64>::smooth(ETA).unwrap();
    let mirror = SmoothConductor::<f64>::smooth(Complex::new(0.2, 3.4)).unwrap();
    // (name, dielectric, rough, grating, flags at [PlaneWave, Partial, Incoherent] × 3 polarizations)
    macro_rules! flags_of {
        ($m:expr) => {{
            let m = $m;
            let blur = Partial(GaussHermite::new(8).unwrap());
            let l = LAMBDA;
            [
                Bsdf::new(m, Kernel::<Intensity, PlaneWave>::default(), f, l)
                    .unwrap()
                    .flags(),
                Bsdf::new(m, Kernel::<OneShape, PlaneWave>::default(), f, l)
                    .unwrap()
                    .flags(),
                Bsdf::new(m, Kernel::<Full, PlaneWave>::default(), f, l)
                    .unwrap()
                    .flags(),
                Bsdf::new(m, Kernel::<Intensity, _>::new(blur.clone()), f, l)
                    .unwrap()
                    .flags(),
                Bsdf::new(m, Kernel::<OneShape, _>::new(blur.clone()), f, l)
                    .unwrap()
                    .flags(),
                Bsdf::new(m, Kernel::<Full, _>::new(blur), f, l)
                    .unwrap()
                    .flags(),
                Bsdf::new(m, Kernel::<Intensity, Incoherent>::default(), f, l)
                    .unwrap()
                    .flags(),
                Bsdf::new(m, Kernel::<OneShape, Incoherent>::default(), f, l)
                    .unwrap()
                    .flags(),
                Bsdf::new(m, Kernel::<Full, Incoherent>::default(), f, l)
                    .unwrap()
                    .flags(),
            ]
        }};
    }
    for (name, dielectric, rough, orders, flags) in [
        ("rough glass", true, true, false, flags_of!(&glass)),
        ("rough gold", false, true, false, flags_of!(&gold)),
        ("K-correlation glass", true, true, false, flags_of!(&kc)),
        ("mixture glass", true, true, false, flags_of!(&mix)),
        ("grating", false, true, true, flags_of!(&grat)),
        ("smooth glass", true, false, false, flags_of!(&smooth_glass)),
        ("smooth mirror", false, false, false, flags_of!(&mirror)),
    ] {
        for (i, got) in flags.iter().enumerate() {
            let plane = i < 3;
            let mut want = LobeFlags::REFLECTION;
            if dielectric {
                want = want | LobeFlags::TRANSMISSION;
            }
            want = want
                | if plane {
                    LobeFlags::DELTA
                } else {
                    LobeFlags::COHERENT_SPECULAR
                };
            if rough && !(orders && plane) {
                want = want | LobeFlags::SCATTERED;
            }
            assert_eq!(*got, want, "{name} at {}: {got:?}", LEVELS[i]);
            assert_eq!(
                got.contains(LobeFlags::DELTA),
                plane,
                "{name}: DELTA ⇔ plane wave"
            );
        }
    }
}

/// `Bsdf::prepare_surface` (the packet-free prepared form of unpolarized light with surface
/// coherence, which the backward weights use) gives what `prepare(surface_packet(..))` gives:
/// the responses of both at random pairs of directions (either side of tilted glass, on a
/// conductor, 0–89°) under the horizon rule and at fixed widths (0.3–300 µm), at four levels,
/// and the specular masses within `64 ε`. The two paths compute the same function of the
/// wavenumber and the width from inputs rounded differently (`k` through `2π/λ` and back, the
/// section through the packet's frame, ŝ normalised in another order: a few ulps), so each
/// entry must agree within `t max|M| + 16 MIN_POSITIVE`,
/// `t = 8 ε ln MAX + 64 ε + 16 ε (|S_k| + |S_w| + |S_s|)`,
/// with `S_k = ∂ ln M₀₀/∂ ln λ`, `S_w = ∂ ln M₀₀/∂ ln w` and `S_s` the
/// larger `|∂ ln M₀₀/∂ŝ|` along the two tangents, measured here by finite differences (in the
/// tail of a narrow coherent lobe `M` is `e^{−q}` with `q` in the hundreds and these reach
/// ~10³–10⁴).
/// `b_h` is `b` at the wavelength `λ(1 + h)`. Returns whether the response is nonzero.
fn prepare_surface_pair<T, S, K>(
    b: &Bsdf<'_, T, S, K>,
    b_h: (&Bsdf<'_, T, S, K>, f64),
    s: Vector3<T>,
    r: Vector3<T>,
    c: &SurfaceCoherence<T>,
) -> bool
where
    T: Real,
    S: gmueller::bsdf::BsdfSurface<T>,
    K: gmueller::bsdf::BsdfKernel<T, S::Psd>,
{
    use gmueller::interaction::polarization::Throughput as _;
    let eps = T::EPSILON.to_f64();
    let direct = b.prepare_surface(s, c).unwrap();
    let packet = b
        .surface_packet(Stokes::unpolarized(T::one()).unwrap(), s, c)
        .unwrap();
    let via = b.prepare(&packet).unwrap();
    for side in [
        gmueller::interaction::Side::Reflection,
        gmueller::interaction::Side::Transmission,
    ] {
        let (a, w) = (
            direct.specular_mass(side).to_f64(),
            via.specular_mass(side).to_f64(),
        );
        assert!((a - w).abs() <= 64.0 * eps * w, "E {a} vs {w} ({side:?})");
    }
    let (Ok(a), Ok(w)) = (b.eval(&direct, r), b.eval(&via, r)) else {
        panic!("eval failed at s {s:?}, r {r:?}");
    };
    let f64s = |m: Mueller<T>| Matrix4::from_fn(|i, j| m.matrix()[(i, j)].to_f64());
    let (ma, mw) = (
        f64s(a.response.total().to_mueller()),
        f64s(w.response.total().to_mueller()),
    );
    let scale = mw.amax().max(ma.amax());
    // The condition numbers, at the width the rule gives this direction (held fixed).
    let (bh, h) = b_h;
    let width = b.surface_width(&s, c).unwrap();
    let m00 = |b: &Bsdf<'_, T, S, K>, w: f64, s: Vector3<T>| {
        let c = SurfaceCoherence::fixed(T::lit(w)).unwrap();
        let v = b.eval(&b.prepare_surface(s, &c).unwrap(), r).unwrap();
        v.response.total().to_mueller().matrix()[(0, 0)].to_f64()
    };
    let w = width.to_f64();
    let m = m00(b, w, s);
    let turned = |axis: Vector3<T>| (s + axis * T::lit(h)).normalize();
    let (s_k, s_w, s_s) = if m > 0.0 {
        let tilt = |axis| ((m00(b, w, turned(axis)) / m - 1.0) / h).abs();
        (
            (m00(bh, w, s) / m - 1.0) / h,
            (m00(b, w * (1.0 + h), s) / m - 1.0) / h,
            tilt(b.surface().x()).max(tilt(b.surface().y())),
        )
    } else {
        (0.0, 0.0, 0.0)
    };
    let tol =
        8.0 * eps * T::MAX.to_f64().ln() + 64.0 * eps + 16.0 * eps * (s_k.abs() + s_w.abs() + s_s);
    let bound = tol * scale + 16.0 * T::MIN_POSITIVE.to_f64();
    assert!(
        (ma - mw).amax() <= bound,
        "{}: prepare_surface {ma} vs packet {mw} (s {s:?}, r {r:?}, width {}, S {s_k} {s_w} {s_s})",
        core::any::type_name::<K>(),
        c.width().to_f64()
    );
    scale > 0.0
}

fn prepare_surface_matches<T, Pol, Coh>(kernel: Kernel<Pol, Coh>) -> usize
where
    T: Real,
    Pol: PolarizationModel,
    Coh: CoherenceWeights<T, GaussianPsd<T, 2>>,
{
    let f = Frame::<T>::from_normal(Vector3::new(T::lit(0.2), T::lit(-0.1), T::one())).unwrap();
    let (glass, gold) = (glass::<T>(), gold::<T>());
    // The step of the finite differences: well above the rounding of `T`.
    let h = 4.0 * T::EPSILON.to_f64().sqrt();
    let at = |lambda: f64| {
        (
            Bsdf::new(&glass, kernel.clone(), f, T::lit(lambda)).unwrap(),
            Bsdf::new(&gold, kernel.clone(), f, T::lit(lambda)).unwrap(),
        )
    };
    let ((bg, bm), (bg_h, bm_h)) = (at(LAMBDA), at(LAMBDA * (1.0 + h)));
    let mut rng = common::SplitMix64(0x5eed_f00d);
    let mut nonzero = 0;
    for i in 0..400 {
        let width = 10f64.powf(rng.uniform_in(-0.5, 2.5));
        let c = if i % 3 == 0 {
            SurfaceCoherence::fixed(T::lit(width)).unwrap()
        } else {
            SurfaceCoherence::new(T::lit(width)).unwrap()
        };
        let conductor = i % 4 == 3;
        let s_side = if conductor || rng.unit() < 0.5 {
            1.0
        } else {
            -1.0
        };
        let s = local(
            &f,
            rng.uniform_in(0.0, 89.0),
            rng.uniform_in(0.0, 360.0),
            s_side,
        );
        // Half of the exits near the mirror direction, where the coherent lobe lives.
        let r_side = if conductor || rng.unit() < 0.7 {
            s_side
        } else {
            -s_side
        };
        let r = if rng.unit() < 0.5 {
            let mirror = f.k() * (T::lit(2.0) * s.dot(&f.k())) - s;
            let jitter = local(
                &f,
                rng.uniform_in(0.0, 2.0),
                rng.uniform_in(0.0, 360.0),
                1.0,
            );
            (mirror * T::lit(r_side * s_side) + (jitter - f.k()) * T::lit(0.5)).normalize()
        } else {
            local(
                &f,
                rng.uniform_in(0.0, 89.0),
                rng.uniform_in(0.0, 360.0),
                r_side,
            )
        };
        if r.dot(&f.k()).abs() < T::lit(1e-3) {
            continue;
        }
        let lit = if conductor {
            prepare_surface_pair(&bm, (&bm_h, h), s, r, &c)
        } else {
            prepare_surface_pair(&bg, (&bg_h, h), s, r, &c)
        };
        nonzero += usize::from(lit);
    }
    nonzero
}

#[test]
fn prepare_surface_is_the_surface_packet_prepared() {
    fn all<T: Real>() {
        let counts = [
            prepare_surface_matches::<T, _, _>(Kernel::<Full, Partial>::default()),
            prepare_surface_matches::<T, _, _>(Kernel::<Intensity, Incoherent>::default()),
            prepare_surface_matches::<T, _, _>(Kernel::<OneShape, Partial>::default()),
            prepare_surface_matches::<T, _, _>(Kernel::<Full, PlaneWave>::default()),
        ];
        // At least 35 % of the pairs compare a nonzero response (a dark pair compares zeros:
        // half of them at the incoherent level, more in `f32`'s narrower range).
        assert!(counts.iter().all(|&n| n >= 140), "{counts:?}");
    }
    all::<f64>();
    all::<f32>();
}

/// The shading point owns the wavelength: the packets a `Bsdf` builds (`surface_packet`,
/// `distant_packet`) carry exactly its `wavenumber` of the source's side — no `2π/(2π/k)` round
/// trip — above and below an interface, in `f32` and `f64`, over wavelengths spread across
/// the visible (where the round trip moved `k` by an ulp for some of them, counted here).
#[test]
fn packets_carry_the_shading_points_wavenumber() {
    fn run<T: Real>() -> usize {
        let material = glass::<T>();
        let kernel = Kernel::<Full, Partial>::default();
        let frame = Frame::from_normal(Vector3::new(0.1, -0.2, 1.0).map(T::lit)).unwrap();
        let coherence = SurfaceCoherence::<T>::fixed(T::lit(3.0)).unwrap();
        let stokes = Stokes::new(T::one(), T::zero(), T::zero(), T::zero()).unwrap();
        let mut round_trip_moved = 0;
        for i in 0..200 {
            let lambda = T::lit(0.38 + 0.0021 * f64::from(i));
            let bsdf = Bsdf::new(&material, kernel, frame, lambda).unwrap();
            for side in [1.0, -1.0] {
                let s = (frame.x() * T::lit(0.3) + frame.k() * T::lit(side)).normalize();
                let k = bsdf.wavenumber(&s).unwrap();
                let a = bsdf.surface_packet(stokes, s, &coherence).unwrap();
                let b = bsdf.distant_packet(stokes, T::lit(6.8e-5), s).unwrap();
                assert_eq!(a.wavenumber(), k);
                assert_eq!(b.wavenumber(), k);
                assert!(bsdf.prepare(&a).is_ok() && bsdf.prepare(&b).is_ok());
                round_trip_moved += usize::from(T::two_pi() / (T::two_pi() / k) != k);
            }
        }
        round_trip_moved
    }
    let (a, b) = (run::<f32>(), run::<f64>());
    println!("of 400 wavenumbers, the λ round trip moved {a} in f32 and {b} in f64");
    // Without the owner the packets would have carried the moved ones: the check can fail.
    assert!(a + b > 0);
}
