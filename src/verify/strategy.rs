//! proptest strategies of objects that are valid by construction, and the run configuration
//! the crate's own property tests use.
//!
//! Every strategy is built from proptest's ranges and maps, so a failure shrinks toward the
//! small end of each range, and proptest's persistence (`*.proptest-regressions`) records it.
//! The values are `f64`; convert with [`crate::Real::lit`] for an `f32` test.

use nalgebra::{Matrix2, Matrix4, Vector3, Vector4};
use num_complex::Complex;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

use crate::jones::JonesMatrix;
use crate::mueller::Mueller;

/// The seed every property test starts from in a normal run (`cargo test`, CI): the same inputs
/// on every machine and every run, so a submission never passes or fails by chance.
pub const PROPTEST_SEED: u64 = 0x6d75_656c_6c65_7221;

/// The environment variable that turns every property test into a randomized search:
/// `GMUELLER_PROPTEST_SEARCH=20 cargo test --release` runs each property with fresh random seeds
/// and 20× its usual number of cases (any positive integer factor). A failure is shrunk and
/// written to the test's `*.proptest-regressions` file, which every later run replays first:
/// commit it.
pub const PROPTEST_SEARCH_VAR: &str = "GMUELLER_PROPTEST_SEARCH";

/// The configuration of a property test: `cases` cases from [`PROPTEST_SEED`], or — when
/// [`PROPTEST_SEARCH_VAR`] holds a factor `f` — `f · cases` cases from a random seed.
///
/// ```
/// use gmueller::verify::strategy::proptest_config;
/// let c = proptest_config(64);
/// assert!(c.cases >= 64);
/// ```
#[must_use]
pub fn proptest_config(cases: u32) -> Config {
    let factor = std::env::var(PROPTEST_SEARCH_VAR)
        .ok()
        .and_then(|v| v.trim().parse::<u32>().ok())
        .filter(|&f| f > 0);
    match factor {
        Some(f) => Config {
            cases: cases.saturating_mul(f),
            rng_seed: RngSeed::Random,
            ..Config::default()
        },
        None => Config {
            cases,
            rng_seed: RngSeed::Fixed(PROPTEST_SEED),
            ..Config::default()
        },
    }
}

/// A finite real in `[-scale, scale]`.
pub fn real(scale: f64) -> impl Strategy<Value = f64> {
    -scale..=scale
}

/// An angle in `[-2π, 2π]`.
pub fn angle() -> impl Strategy<Value = f64> {
    -std::f64::consts::TAU..=std::f64::consts::TAU
}

/// A complex number with both parts in `[-scale, scale]`.
pub fn complex(scale: f64) -> impl Strategy<Value = Complex<f64>> {
    (real(scale), real(scale)).prop_map(|(re, im)| Complex::new(re, im))
}

/// A general complex 2×2 matrix with entries of modulus ≲ `scale`.
pub fn complex_matrix2(scale: f64) -> impl Strategy<Value = Matrix2<Complex<f64>>> {
    proptest::array::uniform4(complex(scale)).prop_map(|[a, b, c, d]| Matrix2::new(a, b, c, d))
}

/// A valid Stokes vector `(S0, S1, S2, S3)`: intensity in `[1e-3, 10]`, degree of polarization
/// in `[0, 1]`, direction uniform-ish on the Poincaré sphere.
pub fn stokes_vector() -> impl Strategy<Value = Vector4<f64>> {
    (1e-3..10.0f64, 0.0..=1.0f64, -1.0..=1.0f64, angle()).prop_map(|(s0, dop, z, az)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        let p = s0 * dop;
        Vector4::new(s0, p * r * az.cos(), p * r * az.sin(), p * z)
    })
}

/// A fully polarized Stokes vector, on the cone `S1² + S2² + S3² = S0²` to rounding: intensity
/// in `[1e-3, 10]`, direction uniform-ish on the Poincaré sphere.
pub fn stokes_on_cone() -> impl Strategy<Value = Vector4<f64>> {
    (1e-3..10.0f64, -1.0..=1.0f64, angle()).prop_map(|(s0, z, az)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vector4::new(s0, s0 * r * az.cos(), s0 * r * az.sin(), s0 * z)
    })
}

/// A unit vector in ℝ³ (rejecting near-zero draws).
pub fn unit_vector3() -> impl Strategy<Value = Vector3<f64>> {
    (real(1.0), real(1.0), real(1.0))
        .prop_filter("non-degenerate", |(x, y, z)| x * x + y * y + z * z > 1e-2)
        .prop_map(|(x, y, z)| Vector3::new(x, y, z).normalize())
}

/// A symmetric positive-definite 2×2 matrix `XᵀX + 0.05 I` with `X` in `[-2, 2]`.
pub fn spd2() -> impl Strategy<Value = Matrix2<f64>> {
    proptest::array::uniform4(real(2.0)).prop_map(|[a, b, c, d]| {
        let x = Matrix2::new(a, b, c, d);
        x.transpose() * x + Matrix2::identity() * 0.05
    })
}

/// A symmetric positive-definite 2×2 matrix of chosen condition: the larger eigenvalue in
/// `[lo, hi]`, the condition number `λ₁/λ₂` in `[1, max_condition]` (log-uniform, so both
/// ends are reached), the eigenvectors turned by a uniform angle. `0 < lo ≤ hi`,
/// `max_condition ≥ 1`.
pub fn spd2_conditioned(
    lo: f64,
    hi: f64,
    max_condition: f64,
) -> impl Strategy<Value = Matrix2<f64>> {
    let ln_c = max_condition.max(1.0).ln();
    (lo..=hi, 0.0..=ln_c, angle()).prop_map(|(l1, lc, t)| {
        let l2 = l1 / lc.exp();
        let (c, s) = (t.cos(), t.sin());
        let r = Matrix2::new(c, -s, s, c);
        r * Matrix2::new(l1, 0.0, 0.0, l2) * r.transpose()
    })
}

/// A unitary Jones matrix `e^{iα} [[a, −b̄], [b, ā]]`, `|a|² + |b|² = 1`: every lossless
/// element (retarders and rotators at any angle).
pub fn unitary_jones() -> impl Strategy<Value = Matrix2<Complex<f64>>> {
    (angle(), 0.0..=std::f64::consts::FRAC_PI_2, angle(), angle()).prop_map(|(alpha, chi, p, q)| {
        let a = Complex::from_polar(chi.cos(), p);
        let b = Complex::from_polar(chi.sin(), q);
        Matrix2::new(a, -b.conj(), b, a.conj()) * Complex::from_polar(1.0, alpha)
    })
}

/// A Hermitian Jones matrix `[[p, c], [c̄, q]]` with `p, q` in `[-scale, scale]` and both parts
/// of `c` too (a diattenuator when it is positive semi-definite).
pub fn hermitian_jones(scale: f64) -> impl Strategy<Value = Matrix2<Complex<f64>>> {
    (real(scale), real(scale), complex(scale))
        .prop_map(|(p, q, c)| Matrix2::new(Complex::new(p, 0.0), c, c.conj(), Complex::new(q, 0.0)))
}

/// A physically realizable Mueller matrix: a convex sum of 1 to `max_terms` Jones-derived
/// Mueller matrices of general Jones matrices (entries ≲ 1), with weights summing to 1. One term
/// is non-depolarizing (on the realizability boundary: its coherency matrix has rank 1).
pub fn realizable_mueller(max_terms: usize) -> impl Strategy<Value = Matrix4<f64>> {
    proptest::collection::vec((complex_matrix2(1.0), 0.01..1.0f64), 1..=max_terms.max(1)).prop_map(
        |terms| {
            let total: f64 = terms.iter().map(|(_, w)| w).sum();
            terms.iter().fold(Matrix4::zeros(), |acc, (j, w)| {
                acc + Mueller::from_jones(&JonesMatrix(*j)).0 * (w / total)
            })
        },
    )
}

/// The Bochner bound of a packet's `x`–`y` correlation, `|μ|² ≤ √(|Θx||Θy|)/|Θ½|` with
/// `Θ½ = (Θx + Θy)/2` (≤ 1, = 1 for equal shapes): the largest `|μ|²` two channels of these
/// shapes can have.
#[must_use]
pub fn bochner_bound(shape_x: &Matrix2<f64>, shape_y: &Matrix2<f64>) -> f64 {
    let half = (shape_x + shape_y) * 0.5;
    (shape_x.determinant() * shape_y.determinant()).sqrt() / half.determinant()
}

/// `|μ|²` of a Stokes vector, `(S2² + S3²)/(S0² − S1²)` (0 for `S0² = S1²`).
#[must_use]
pub fn mu_squared(s: &Vector4<f64>) -> f64 {
    let d = s[0] * s[0] - s[1] * s[1];
    if d > 0.0 {
        (s[2] * s[2] + s[3] * s[3]) / d
    } else {
        0.0
    }
}

/// The parts of a realizable two-shape wave packet: a Stokes vector and the coherence shapes
/// `Θx`, `Θy` ([`spd2_conditioned`], eigenvalues in `[0.25, 100]` λ², condition ≤ 50), with
/// `|μ|²` a fraction in `[1 − closeness, 1]` of the Bochner bound ([`bochner_bound`]):
/// `closeness = 1` spans every realizable correlation, `closeness = 0.01` stays within 1 % of
/// the bound. `S0` in `[1e-3, 10]`, `S1/S0` in `[−0.99, 0.99]`.
pub fn packet_parts(
    closeness: f64,
) -> impl Strategy<Value = (Vector4<f64>, Matrix2<f64>, Matrix2<f64>)> {
    let lo = (1.0 - closeness).clamp(0.0, 1.0);
    (
        spd2_conditioned(0.25, 100.0, 50.0),
        spd2_conditioned(0.25, 100.0, 50.0),
        1e-3..10.0f64,
        -0.99..=0.99f64,
        lo..=1.0f64,
        angle(),
    )
        .prop_map(|(tx, ty, s0, q, f, phase)| {
            let s1 = s0 * q;
            let mu = (f * bochner_bound(&tx, &ty)).sqrt();
            // (S2, S3) = 2 √(Sx Sy) μ (cos, sin), √(Sx Sy) = ½ √(S0² − S1²).
            let r = (s0 * s0 - s1 * s1).sqrt() * mu;
            (
                Vector4::new(s0, s1, r * phase.cos(), r * phase.sin()),
                tx,
                ty,
            )
        })
}

/// Log-uniform in `[lo, hi]`, `0 < lo ≤ hi` (every decade equally often).
pub fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> + Clone {
    (lo.ln()..=hi.ln()).prop_map(f64::exp)
}

/// A right-handed orthonormal frame of any orientation
/// ([`crate::frame::Frame::from_direction_and_x`] of two unit vectors at least 0.1 apart in
/// their cross product).
pub fn frame() -> impl Strategy<Value = crate::frame::Frame<f64>> {
    (unit_vector3(), unit_vector3())
        .prop_filter("hint not near k", |(k, h)| k.cross(h).norm() > 0.1)
        .prop_map(|(k, h)| crate::frame::Frame::from_direction_and_x(k, h).expect("valid"))
}

/// An angle from the normal in radians: exactly 0 (normal incidence, where the s/p frame falls
/// back to its documented basis) in 1/8 of the cases, exactly 89.99° (grazing) in 1/8, else
/// uniform in between.
pub fn polar_angle() -> impl Strategy<Value = f64> {
    let grazing = 89.99f64.to_radians();
    prop_oneof![
        1 => Just(0.0),
        1 => Just(grazing),
        6 => 0.0..grazing,
    ]
}

/// The kind of an exit direction drawn by [`incidence_and_exit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExitKind {
    /// The mirror direction of the incidence.
    Specular,
    /// Straight back toward the source.
    BackScatter,
    /// At 89.99° from the normal, any azimuth.
    Grazing,
    /// Any direction of the upper hemisphere (polar angle by [`polar_angle`], any azimuth).
    Any,
}

/// A geometry on a surface of normal `+ẑ`: the unit travel direction of the incident light
/// (downward, polar angle by [`polar_angle`], azimuth φ ≠ 0 in general) and a unit exit
/// direction of the upper hemisphere of each [`ExitKind`] in equal shares.
pub fn incidence_and_exit() -> impl Strategy<Value = (Vector3<f64>, Vector3<f64>, ExitKind)> {
    let kind = prop_oneof![
        Just(ExitKind::Specular),
        Just(ExitKind::BackScatter),
        Just(ExitKind::Grazing),
        Just(ExitKind::Any),
    ];
    (polar_angle(), angle(), polar_angle(), angle(), kind).prop_map(
        |(theta_i, phi_i, theta_o, phi_o, kind)| {
            let dir = |t: f64, p: f64| Vector3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
            let to_source = dir(theta_i, phi_i);
            let travel = -to_source;
            let exit = match kind {
                ExitKind::Specular => Vector3::new(travel.x, travel.y, -travel.z),
                ExitKind::BackScatter => to_source,
                ExitKind::Grazing => dir(89.99f64.to_radians(), phi_o),
                ExitKind::Any => dir(theta_o, phi_o),
            };
            (travel, exit, kind)
        },
    )
}

/// A coherence shape `Θ = R(ψ) diag(a², b²) R(ψ)ᵀ`: an ellipse of widths `a, b` in `[lo, hi)`
/// (length, e.g. in λ) turned by `ψ` in `[−max_angle, max_angle)`.
pub fn coherence_shape(lo: f64, hi: f64, max_angle: f64) -> impl Strategy<Value = Matrix2<f64>> {
    (lo..hi, lo..hi, -max_angle..max_angle).prop_map(|(a, b, psi)| {
        let (s, c) = psi.sin_cos();
        let r = Matrix2::new(c, -s, s, c);
        r * Matrix2::new(a * a, 0.0, 0.0, b * b) * r.transpose()
    })
}
