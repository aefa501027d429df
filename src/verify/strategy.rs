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
/// [`PROPTEST_SEARCH_VAR`] holds a factor `f` — `f · cases` cases from a random seed, with `f`
/// times proptest's budget of global rejects (`prop_assume!`), so that a test that rejects a
/// fixed share of its inputs does not abort for "too many global rejects" once its cases grow.
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
    config_for(cases, factor)
}

/// [`proptest_config`] for a given search factor.
fn config_for(cases: u32, factor: Option<u32>) -> Config {
    match factor {
        Some(f) => Config {
            cases: cases.saturating_mul(f),
            rng_seed: RngSeed::Random,
            max_global_rejects: Config::default().max_global_rejects.saturating_mul(f),
            ..Config::default()
        },
        None => Config {
            cases,
            rng_seed: RngSeed::Fixed(PROPTEST_SEED),
            ..Config::default()
        },
    }
}

/// `n` values drawn from `s` with the run configuration of [`proptest_config`] (the fixed seed
/// in a normal run, a fresh one under [`PROPTEST_SEARCH_VAR`]), without shrinking: for counting
/// how often a strategy reaches a boundary (coverage) and for sweeps outside `proptest!`.
///
/// ```
/// use gmueller::verify::strategy::{polar_angle, sample};
/// let v = sample(polar_angle(), 400);
/// let normal = v.iter().filter(|&&t| t == 0.0).count();
/// assert!(normal > 400 / 16, "exact normal incidence in about 1/8 of the draws: {normal}");
/// ```
///
/// # Panics
/// If `s` rejects more values than proptest allows (a filter that is too strict).
pub fn sample<S: Strategy>(s: S, n: usize) -> Vec<S::Value> {
    let mut runner = proptest::test_runner::TestRunner::new(proptest_config(1));
    (0..n)
        .map(|_| {
            proptest::strategy::ValueTree::current(
                &s.new_tree(&mut runner)
                    .expect("the strategy generates a value"),
            )
        })
        .collect()
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
    stokes_vector_in(1e-3, 10.0, 0.0, 1.0)
}

/// A valid Stokes vector with the intensity `S0` in `[s0_lo, s0_hi)` and the degree of
/// polarization in `[dop_lo, dop_hi]` (`0 ≤ dop_lo ≤ dop_hi ≤ 1`: `dop_lo = dop_hi = 1` is the
/// cone, `0` the unpolarized axis), direction uniform-ish on the Poincaré sphere.
/// [`stokes_vector`] is `stokes_vector_in(1e-3, 10, 0, 1)`.
pub fn stokes_vector_in(
    s0_lo: f64,
    s0_hi: f64,
    dop_lo: f64,
    dop_hi: f64,
) -> impl Strategy<Value = Vector4<f64>> {
    (s0_lo..s0_hi, dop_lo..=dop_hi, -1.0..=1.0f64, angle()).prop_map(|(s0, dop, z, az)| {
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
    packet_parts_in(PacketRanges {
        closeness,
        ..PacketRanges::default()
    })
}

/// The ranges of [`packet_parts_in`]; [`PacketRanges::default`] is those of [`packet_parts`]
/// with `closeness = 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PacketRanges {
    /// The larger eigenvalue of each shape is drawn from `[shape_lo, shape_hi]` (area, e.g. λ²).
    pub shape_lo: f64,
    /// See [`PacketRanges::shape_lo`].
    pub shape_hi: f64,
    /// The largest condition number of a shape (≥ 1; log-uniform up to it).
    pub max_condition: f64,
    /// `S0` in `[s0_lo, s0_hi)`.
    pub s0_lo: f64,
    /// See [`PacketRanges::s0_lo`].
    pub s0_hi: f64,
    /// `|S1/S0| ≤ max_s1_ratio < 1` (`S1/S0 = ±1` leaves no correlated channel).
    pub max_s1_ratio: f64,
    /// `|μ|²` is a fraction in `[1 − closeness, 1]` of the Bochner bound.
    pub closeness: f64,
}

impl Default for PacketRanges {
    fn default() -> Self {
        Self {
            shape_lo: 0.25,
            shape_hi: 100.0,
            max_condition: 50.0,
            s0_lo: 1e-3,
            s0_hi: 10.0,
            max_s1_ratio: 0.99,
            closeness: 1.0,
        }
    }
}

/// [`packet_parts`] with every range the caller's ([`PacketRanges`]).
pub fn packet_parts_in(
    r: PacketRanges,
) -> impl Strategy<Value = (Vector4<f64>, Matrix2<f64>, Matrix2<f64>)> {
    let lo = (1.0 - r.closeness).clamp(0.0, 1.0);
    (
        spd2_conditioned(r.shape_lo, r.shape_hi, r.max_condition),
        spd2_conditioned(r.shape_lo, r.shape_hi, r.max_condition),
        r.s0_lo..r.s0_hi,
        -r.max_s1_ratio..=r.max_s1_ratio,
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
    polar_angle_with(PolarAngles::default())
}

/// The mix of [`polar_angle_with`]: weights of the exact normal, the exact `max`, and the
/// angles in between, which are uniform in `[0, max)` or, with `dense_near_grazing`,
/// `π/2 − d` with `d` log-uniform in `[π/2 − max, π/2]` (every decade of the distance from
/// grazing equally often). [`PolarAngles::default`] is [`polar_angle`]'s: 1 : 1 : 6, uniform,
/// `max = 89.99°`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarAngles {
    /// Weight of exactly 0 (normal incidence).
    pub normal: u32,
    /// Weight of exactly `max`.
    pub grazing: u32,
    /// Weight of the angles in between.
    pub between: u32,
    /// The largest angle in radians, `0 < max < π/2`.
    pub max: f64,
    /// Draw the angles in between log-uniformly in their distance from grazing.
    pub dense_near_grazing: bool,
}

impl Default for PolarAngles {
    fn default() -> Self {
        Self {
            normal: 1,
            grazing: 1,
            between: 6,
            max: 89.99f64.to_radians(),
            dense_near_grazing: false,
        }
    }
}

/// An angle from the normal in radians, drawn as [`PolarAngles`] says.
pub fn polar_angle_with(p: PolarAngles) -> BoxedStrategy<f64> {
    let half_pi = std::f64::consts::FRAC_PI_2;
    let between = if p.dense_near_grazing {
        log_uniform(half_pi - p.max, half_pi)
            .prop_map(move |d| half_pi - d)
            .boxed()
    } else {
        (0.0..p.max).boxed()
    };
    prop_oneof![
        p.normal => Just(0.0),
        p.grazing => Just(p.max),
        p.between => between,
    ]
    .boxed()
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

/// A standard Jones element drawn by [`jones_element`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JonesElement {
    /// [`JonesMatrix::linear_polarizer`]`(θ)`.
    LinearPolarizer {
        /// Transmission axis (radians from x̂ toward ŷ).
        theta: f64,
    },
    /// [`JonesMatrix::linear_retarder`]`(θ, δ)`.
    LinearRetarder {
        /// Fast axis.
        theta: f64,
        /// Retardance.
        retardance: f64,
    },
    /// [`JonesMatrix::diattenuator`]`(tx, ty, θ)`.
    Diattenuator {
        /// Amplitude transmission along the axis.
        tx: f64,
        /// Amplitude transmission across it.
        ty: f64,
        /// Axis.
        theta: f64,
    },
    /// [`JonesMatrix::rotator`]`(θ)`.
    Rotator {
        /// Rotation angle.
        theta: f64,
    },
    /// [`JonesMatrix::circular_retarder`]`(δ)`.
    CircularRetarder {
        /// Retardance.
        retardance: f64,
    },
    /// [`JonesMatrix::circular_polarizer`] passing `S3 = +1` (`true`) or `S3 = −1`.
    CircularPolarizer {
        /// [`crate::jones::Handedness::PositiveS3`] for `true`.
        positive_s3: bool,
    },
}

impl JonesElement {
    /// The element's Jones matrix, from the crate's constructors.
    #[must_use]
    pub fn matrix(&self) -> Matrix2<Complex<f64>> {
        use crate::jones::Handedness;
        match *self {
            Self::LinearPolarizer { theta } => JonesMatrix::linear_polarizer(theta),
            Self::LinearRetarder { theta, retardance } => {
                JonesMatrix::linear_retarder(theta, retardance)
            }
            Self::Diattenuator { tx, ty, theta } => {
                JonesMatrix::diattenuator(tx, ty, theta).expect("tx, ty in [0, 1]")
            }
            Self::Rotator { theta } => JonesMatrix::rotator(theta),
            Self::CircularRetarder { retardance } => JonesMatrix::circular_retarder(retardance),
            Self::CircularPolarizer { positive_s3 } => {
                JonesMatrix::circular_polarizer(if positive_s3 {
                    Handedness::PositiveS3
                } else {
                    Handedness::NegativeS3
                })
            }
        }
        .matrix()
    }
}

/// A standard element at a random angle: linear polarizer, linear retarder, diattenuator
/// (amplitude transmissions in `[0, 1]`), rotator, circular retarder, circular polarizer, in
/// equal shares. Its matrix is [`JonesElement::matrix`].
pub fn jones_element() -> impl Strategy<Value = JonesElement> {
    prop_oneof![
        angle().prop_map(|theta| JonesElement::LinearPolarizer { theta }),
        (angle(), angle())
            .prop_map(|(theta, retardance)| JonesElement::LinearRetarder { theta, retardance }),
        (0.0..=1.0f64, 0.0..=1.0f64, angle())
            .prop_map(|(tx, ty, theta)| JonesElement::Diattenuator { tx, ty, theta }),
        angle().prop_map(|theta| JonesElement::Rotator { theta }),
        angle().prop_map(|retardance| JonesElement::CircularRetarder { retardance }),
        any::<bool>().prop_map(|positive_s3| JonesElement::CircularPolarizer { positive_s3 }),
    ]
}

/// The Mueller matrix of a Jones matrix (the crate's closed form).
fn mueller_of(j: &Matrix2<Complex<f64>>) -> Matrix4<f64> {
    Mueller::from_jones(&JonesMatrix(*j)).0
}

/// A depolarizer `M_u D M_v`: `D = diag(1, a, b, c)` a convex sum of the four Pauli Mueller
/// matrices `diag(1, 1, 1, 1)`, `diag(1, 1, −1, −1)`, `diag(1, −1, 1, −1)`, `diag(1, −1, −1, 1)`
/// (the tetrahedron of realizable diagonal depolarizers, vertices and faces included, since the
/// weights are drawn with a zero in a quarter of the cases each), turned by the Mueller matrices
/// of two unitary Jones matrices ([`unitary_jones`]). Realizable, `M₀₀ = 1`.
pub fn depolarizer() -> impl Strategy<Value = Matrix4<f64>> {
    let weight = prop_oneof![1 => Just(0.0), 3 => 0.0..1.0f64];
    (
        proptest::array::uniform4(weight),
        unitary_jones(),
        unitary_jones(),
    )
        .prop_map(|(w, u, v)| {
            let total: f64 = w.iter().sum();
            let w = if total > 0.0 {
                w.map(|x| x / total)
            } else {
                [1.0, 0.0, 0.0, 0.0]
            };
            let d = Matrix4::from_diagonal(&Vector4::new(
                1.0,
                w[0] + w[1] - w[2] - w[3],
                w[0] - w[1] + w[2] - w[3],
                w[0] - w[1] - w[2] + w[3],
            ));
            mueller_of(&u) * d * mueller_of(&v)
        })
}

/// A realizable Mueller matrix within `distance` of the realizability boundary:
/// `(1 − t) M₁ + t M`, `M₁` non-depolarizing (its coherency matrix has rank 1, so three
/// eigenvalues are 0), `M` from [`realizable_mueller`]`(3)`, `t` in `[0, distance]`: the
/// smallest coherency eigenvalue is at most `t` times `M`'s share of the trace.
pub fn realizable_mueller_near_boundary(distance: f64) -> impl Strategy<Value = Matrix4<f64>> {
    (
        complex_matrix2(1.0),
        realizable_mueller(3),
        0.0..=distance.clamp(0.0, 1.0),
    )
        .prop_map(|(j, m, t)| mueller_of(&j) * (1.0 - t) + m * t)
}

/// A one-point CSD (coherency) matrix `C = ⟨E E†⟩`: Hermitian positive semidefinite, the Gram
/// matrix `X X†` of a complex 2×m `X` (m = 1: fully polarized, rank 1, on the cone; m = 2:
/// partially polarized) with entries of modulus ≲ `scale`.
pub fn one_point_csd(scale: f64) -> impl Strategy<Value = Matrix2<Complex<f64>>> {
    (complex_matrix2(scale), any::<bool>()).prop_map(|(mut x, rank_one)| {
        if rank_one {
            x[(0, 1)] = Complex::new(0.0, 0.0);
            x[(1, 1)] = Complex::new(0.0, 0.0);
        }
        x * x.adjoint()
    })
}

/// The CSD matrices of a field at two points, `C(rᵢ, rⱼ) = ⟨E(rᵢ) E(rⱼ)†⟩`: the blocks of one
/// positive semidefinite 4×4 matrix, so that they belong to one realizable field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoPointCsd {
    /// `C(r₁, r₁)`, one-point (Hermitian, PSD).
    pub at_1: Matrix2<Complex<f64>>,
    /// `C(r₂, r₂)`, one-point.
    pub at_2: Matrix2<Complex<f64>>,
    /// `C(r₁, r₂)`, two-point (any complex matrix; `C(r₂, r₁) = C(r₁, r₂)†`).
    pub cross: Matrix2<Complex<f64>>,
}

/// A realizable two-point CSD ([`TwoPointCsd`]): `G = Y Y†` with `Y` complex 4×m (m in
/// `1..=4`, entries ≲ 1), the cross block scaled by a coherence `c` in
/// `[coherence_lo, coherence_hi] ⊂ [0, 1]` (`c G + (1 − c) blockdiag(G₁₁, G₂₂)` stays PSD:
/// `c = 1`, m = 1 is a fully coherent, fully polarized field; `c = 0` two uncorrelated points).
pub fn two_point_csd(coherence_lo: f64, coherence_hi: f64) -> impl Strategy<Value = TwoPointCsd> {
    let (lo, hi) = (coherence_lo.clamp(0.0, 1.0), coherence_hi.clamp(0.0, 1.0));
    (
        proptest::collection::vec(complex(1.0), 16),
        1usize..=4,
        lo..=hi.max(lo),
    )
        .prop_map(|(y, m, c)| {
            let y = nalgebra::Matrix4::from_fn(|r, col| {
                if col < m {
                    y[4 * r + col]
                } else {
                    Complex::new(0.0, 0.0)
                }
            });
            let g = y * y.adjoint();
            let block = |r: usize, col: usize| g.fixed_view::<2, 2>(r, col).into_owned();
            TwoPointCsd {
                at_1: block(0, 0),
                at_2: block(2, 2),
                cross: block(0, 2) * Complex::new(c, 0.0),
            }
        })
}

/// A beam meeting a surface, with its s/p frame: `(d, n, Frame::sp(d, n))` for a unit travel
/// direction `d` at a polar angle from [`polar_angle`] (exact normal incidence, where the frame
/// falls back to its documented basis, and 89.99°, included) toward a surface of unit normal `n`
/// in any orientation ([`unit_vector3`]), coming from either side.
pub fn sp_frame() -> impl Strategy<Value = (Vector3<f64>, Vector3<f64>, crate::frame::Frame<f64>)> {
    (unit_vector3(), polar_angle(), angle(), any::<bool>()).prop_map(
        |(n, theta, phi, from_above)| {
            let basis = crate::frame::Frame::from_normal(n).expect("unit normal");
            let toward = if from_above { -1.0 } else { 1.0 };
            let d = (basis.x() * phi.cos() + basis.y() * phi.sin()) * theta.sin()
                + n * (toward * theta.cos());
            let f = crate::frame::Frame::sp(d, n).expect("non-zero d and n");
            (d, n, f)
        },
    )
}

/// A symmetric positive-definite `N × N` matrix of chosen condition: the largest eigenvalue in
/// `[lo, hi]`, each other one smaller by a factor log-uniform in `[1, max_condition]`, the
/// eigenvectors turned by Givens rotations of uniform angles in every coordinate plane.
pub fn spd_conditioned<const N: usize>(
    lo: f64,
    hi: f64,
    max_condition: f64,
) -> impl Strategy<Value = nalgebra::SMatrix<f64, N, N>> {
    let ln_c = max_condition.max(1.0).ln();
    (
        lo..=hi,
        proptest::collection::vec(0.0..=ln_c, N),
        proptest::collection::vec(angle(), N * N),
    )
        .prop_map(|(l1, lc, angles)| {
            let mut d = nalgebra::SMatrix::<f64, N, N>::zeros();
            for i in 0..N {
                d[(i, i)] = if i == 0 { l1 } else { l1 / lc[i].exp() };
            }
            let mut r = nalgebra::SMatrix::<f64, N, N>::identity();
            for i in 0..N {
                for j in (i + 1)..N {
                    let (s, c) = angles[i * N + j].sin_cos();
                    let mut g = nalgebra::SMatrix::<f64, N, N>::identity();
                    g[(i, i)] = c;
                    g[(j, j)] = c;
                    g[(i, j)] = -s;
                    g[(j, i)] = s;
                    r = g * r;
                }
            }
            let m = r * d * r.transpose();
            (m + m.transpose()) * 0.5
        })
}

/// The ranges of the PSD strategies: rms height `σ` and correlation length `ℓ` log-uniform in
/// their ranges, `ℓ` the largest axis of an anisotropic correlation whose other axes are
/// shorter by up to `max_anisotropy` (1: isotropic).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PsdRanges {
    /// `σ` in `[rms_lo, rms_hi]` (length).
    pub rms_lo: f64,
    /// See [`PsdRanges::rms_lo`].
    pub rms_hi: f64,
    /// `ℓ` in `[length_lo, length_hi]` (length).
    pub length_lo: f64,
    /// See [`PsdRanges::length_lo`].
    pub length_hi: f64,
    /// Ratio of the longest to the shortest correlation axis, ≥ 1.
    pub max_anisotropy: f64,
}

impl Default for PsdRanges {
    /// `σ` in 1e-4–0.05, `ℓ` in 0.05–50 (µm, at visible wavelengths: the first-order range
    /// `kσ ≲ 0.3` at 0.5 µm and correlation lengths from 0.1 λ to 100 λ), anisotropy ≤ 10.
    fn default() -> Self {
        Self {
            rms_lo: 1e-4,
            rms_hi: 0.05,
            length_lo: 0.05,
            length_hi: 50.0,
            max_anisotropy: 10.0,
        }
    }
}

/// A Gaussian PSD in `N` dimensions: `R(ξ) = σ² exp(−½ ξᵀ C⁻¹ ξ)` with `σ` and the correlation
/// covariance `C` ([`spd_conditioned`] of eigenvalues `ℓ²`) drawn from `r`.
pub fn gaussian_psd<const N: usize>(
    r: PsdRanges,
) -> impl Strategy<Value = crate::psd::GaussianPsd<f64, N>> {
    (
        log_uniform(r.rms_lo, r.rms_hi),
        log_uniform(r.length_lo, r.length_hi),
        spd_conditioned::<N>(1.0, 1.0, r.max_anisotropy * r.max_anisotropy),
    )
        .prop_map(|(sigma, ell, shape)| {
            let c = crate::gaussian::Gaussian::new(shape * (ell * ell)).expect("SPD");
            crate::psd::GaussianPsd::from_autocorrelation(sigma * sigma, &c).expect("valid")
        })
}

/// A K-correlation (ABC) PSD in `N` dimensions,
/// `p(ζ) ∝ σ² (1 + T|ζ|²)^{−(γ+1)/2}` with `σ` and `√T = ℓ` from `r` and `γ` in
/// `(N − 1, N − 1 + max_excess]`, half the draws within 1 % of the lower bound `γ → N − 1`
/// (where the PSD's tail is heaviest).
pub fn kcorrelation_psd<const N: usize>(
    r: PsdRanges,
    max_excess: f64,
) -> impl Strategy<Value = crate::psd::KCorrelation<f64, N>> {
    let n1 = N as f64 - 1.0;
    let excess = prop_oneof![
        log_uniform(1e-4, 1e-2),
        log_uniform(1e-2, max_excess.max(2e-2)),
    ];
    (
        log_uniform(r.rms_lo, r.rms_hi),
        log_uniform(r.length_lo, r.length_hi),
        excess,
    )
        .prop_map(move |(sigma, ell, e)| {
            crate::psd::KCorrelation::new(sigma * sigma, ell * ell, n1 + e).expect("valid")
        })
}

/// A mixture of 1 to `max_components` Gaussian PSDs ([`gaussian_psd`]).
pub fn mixture_psd<const N: usize>(
    r: PsdRanges,
    max_components: usize,
) -> impl Strategy<Value = crate::psd::GaussianMixturePsd<f64, N>> {
    proptest::collection::vec(gaussian_psd::<N>(r), 1..=max_components.max(1))
        .prop_map(|c| crate::psd::GaussianMixturePsd::new(c).expect("valid"))
}

#[cfg(test)]
mod tests {
    use super::{Config, PROPTEST_SEED, RngSeed, config_for};

    /// A normal run is the fixed seed and the given cases; a search scales the cases and the
    /// reject budget by its factor (`propagation::s2_5_is_s2_2_under_a_mul` rejects a quarter
    /// of its inputs and aborted at 50× with proptest's fixed budget of 1024).
    #[test]
    fn search_scales_cases_and_rejects() {
        let fixed = config_for(64, None);
        assert_eq!(fixed.cases, 64);
        assert_eq!(fixed.rng_seed, RngSeed::Fixed(PROPTEST_SEED));
        assert_eq!(
            fixed.max_global_rejects,
            Config::default().max_global_rejects
        );
        let search = config_for(64, Some(50));
        assert_eq!(search.cases, 3200);
        assert_eq!(search.rng_seed, RngSeed::Random);
        assert_eq!(
            search.max_global_rejects,
            50 * Config::default().max_global_rejects
        );
    }
}
