//! Shared tolerances, comparison helpers and proptest strategies for the integration tests.
//!
//! Every comparison states an absolute *and* a relative tolerance: `|a − b| ≤ abs + rel·max(|a|, |b|)`.
//! Strategies produce inputs that are valid by construction and bounded.
#![allow(
    dead_code,
    reason = "each test file uses a different subset of the helpers"
)]

use nalgebra::{Matrix2, Matrix4, Vector3, Vector4};
use num_complex::Complex;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

/// An absolute and a relative tolerance.
#[derive(Debug, Clone, Copy)]
pub struct Tol {
    pub abs: f64,
    pub rel: f64,
}

/// For f64 results of short closed-form computations.
pub const F64: Tol = Tol {
    abs: 1e-12,
    rel: 1e-12,
};
/// For f32 results of short closed-form computations.
pub const F32: Tol = Tol {
    abs: 2e-5,
    rel: 2e-5,
};

impl Tol {
    pub const fn new(abs: f64, rel: f64) -> Self {
        Self { abs, rel }
    }
    /// `|a − b| ≤ abs + rel·max(|a|, |b|)` for finite values; a non-finite value is accepted
    /// only against the very same value (`rel·∞` would otherwise accept ∞ against anything).
    pub fn accepts(self, a: f64, b: f64) -> bool {
        if !(a.is_finite() && b.is_finite()) {
            return a == b;
        }
        (a - b).abs() <= self.abs + self.rel * a.abs().max(b.abs())
    }
}

/// Panics with both values unless `a` and `b` agree within `tol`.
#[track_caller]
pub fn assert_close(what: &str, a: f64, b: f64, tol: Tol) {
    assert!(
        tol.accepts(a, b),
        "{what}: {a:e} vs {b:e} (diff {:e}, tol abs {:e} rel {:e})",
        (a - b).abs(),
        tol.abs,
        tol.rel
    );
}

/// Element-wise [`assert_close`] over any iterable pair of real values.
#[track_caller]
pub fn assert_all_close(
    what: &str,
    a: impl IntoIterator<Item = f64>,
    b: impl IntoIterator<Item = f64>,
    tol: Tol,
) {
    let a: Vec<f64> = a.into_iter().collect();
    let b: Vec<f64> = b.into_iter().collect();
    assert_eq!(a.len(), b.len(), "{what}: length mismatch");
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!(
            tol.accepts(*x, *y),
            "{what}[{i}]: {x:e} vs {y:e} (diff {:e}); whole:\n{a:?}\nvs\n{b:?}",
            (x - y).abs()
        );
    }
}

/// Element-wise comparison of complex values (real and imaginary parts separately).
#[track_caller]
pub fn assert_complex_close(
    what: &str,
    a: impl IntoIterator<Item = Complex<f64>>,
    b: impl IntoIterator<Item = Complex<f64>>,
    tol: Tol,
) {
    let flat = |v: Vec<Complex<f64>>| v.into_iter().flat_map(|z| [z.re, z.im]).collect::<Vec<_>>();
    assert_all_close(
        what,
        flat(a.into_iter().collect()),
        flat(b.into_iter().collect()),
        tol,
    );
}

/// `Matrix4<f64>` entries, row-major, for comparisons.
pub fn entries4(m: &Matrix4<f64>) -> Vec<f64> {
    (0..4)
        .flat_map(|r| (0..4).map(move |c| m[(r, c)]))
        .collect()
}

/// A 4×4 matrix from nested rows (as in the reference JSON).
pub fn matrix4_from_rows(rows: &[Vec<f64>]) -> Matrix4<f64> {
    assert_eq!(rows.len(), 4);
    Matrix4::from_fn(|r, c| rows[r][c])
}

// ---------------------------------------------------------------- proptest configuration

/// The seed every property test starts from in a normal run (`cargo test`, CI): the same inputs
/// on every machine and every run, so a submission never passes or fails by chance.
pub const PROPTEST_SEED: u64 = 0x6d75_656c_6c65_7221;

/// The environment variable that turns every property test into a randomized search:
/// `GMUELLER_PROPTEST_SEARCH=20 cargo test --release` runs each property with fresh random seeds
/// and 20× its usual number of cases (any positive integer factor). A failure is shrunk and
/// written to the test's `*.proptest-regressions` file, which every later run (CI included)
/// replays first: commit it.
pub const PROPTEST_SEARCH_VAR: &str = "GMUELLER_PROPTEST_SEARCH";

/// The configuration of every property test: `cases` cases from [`PROPTEST_SEED`], or — when
/// [`PROPTEST_SEARCH_VAR`] holds a factor `f` — `f · cases` cases from a random seed.
pub fn proptest_config(cases: u32) -> ProptestConfig {
    let factor = std::env::var(PROPTEST_SEARCH_VAR)
        .ok()
        .and_then(|v| v.trim().parse::<u32>().ok())
        .filter(|&f| f > 0);
    match factor {
        Some(f) => ProptestConfig {
            cases: cases.saturating_mul(f),
            rng_seed: RngSeed::Random,
            ..ProptestConfig::default()
        },
        None => ProptestConfig {
            cases,
            rng_seed: RngSeed::Fixed(PROPTEST_SEED),
            ..ProptestConfig::default()
        },
    }
}

// ---------------------------------------------------------------- strategies

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

/// A valid Stokes vector `(S0, S1, S2, S3)`: intensity in `[1e-3, 10]`, degree of polarization in
/// `[0, 1]`, direction uniform-ish on the Poincaré sphere.
pub fn stokes_vector() -> impl Strategy<Value = Vector4<f64>> {
    (1e-3..10.0f64, 0.0..=1.0f64, -1.0..=1.0f64, angle()).prop_map(|(s0, dop, z, az)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        let p = s0 * dop;
        Vector4::new(s0, p * r * az.cos(), p * r * az.sin(), p * z)
    })
}

/// A unit vector in ℝ³ (rejecting near-zero draws).
pub fn unit_vector3() -> impl Strategy<Value = Vector3<f64>> {
    (real(1.0), real(1.0), real(1.0))
        .prop_filter("non-degenerate", |(x, y, z)| x * x + y * y + z * z > 1e-2)
        .prop_map(|(x, y, z)| Vector3::new(x, y, z).normalize())
}

/// A symmetric positive-definite 2×2 matrix `XᵀX + εI` with eigenvalues in a bounded range.
pub fn spd2() -> impl Strategy<Value = Matrix2<f64>> {
    proptest::array::uniform4(real(2.0)).prop_map(|[a, b, c, d]| {
        let x = Matrix2::new(a, b, c, d);
        x.transpose() * x + Matrix2::identity() * 0.05
    })
}

// ---------------------------------------------------------------- reference values

/// The cases of one `kind` in `tests/data/peer_values.json` (values computed by Mitsuba 3,
/// py-pol and pySCATMECH, each in its own convention; see `tests/data/README.md`).
pub fn peer_cases(kind: &str) -> Vec<serde_json::Value> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/peer_values.json");
    let text = std::fs::read_to_string(path).expect("reference file tests/data/peer_values.json");
    let all: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
    let out: Vec<_> = all["cases"]
        .as_array()
        .expect("a `cases` array")
        .iter()
        .filter(|c| c["kind"] == kind)
        .cloned()
        .collect();
    assert!(!out.is_empty(), "no reference cases of kind {kind}");
    out
}

/// A JSON array of arrays of numbers as nested rows.
pub fn json_rows(v: &serde_json::Value) -> Vec<Vec<f64>> {
    v.as_array()
        .expect("an array of rows")
        .iter()
        .map(|r| {
            r.as_array()
                .expect("a row")
                .iter()
                .map(|x| x.as_f64().expect("a number"))
                .collect()
        })
        .collect()
}

/// `D M D` with `D = diag(1, 1, 1, −1)`: flips the sign of S3 (`e^{+iωt}` ↔ `e^{−iωt}`).
pub fn flip_s3(m: Matrix4<f64>) -> Matrix4<f64> {
    let d = Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, 1.0, -1.0));
    d * m * d
}

// ---------------------------------------------------------------- quadrature

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the three-term recurrence).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for j in 2..=n {
                let p2 = ((2 * j - 1) as f64 * z * p1 - (j - 1) as f64 * p0) / j as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

/// Trapezoid rule over `[−half, half]ᴺ` with `n` points per axis, of a complex integrand.
pub fn cube_quad<const N: usize>(
    f: impl Fn(&nalgebra::SVector<f64, N>) -> Complex<f64>,
    half: f64,
    n: usize,
) -> Complex<f64> {
    let step = 2.0 * half / (n - 1) as f64;
    let mut idx = [0usize; N];
    let mut sum = Complex::new(0.0, 0.0);
    loop {
        let x = nalgebra::SVector::<f64, N>::from_fn(|d, _| -half + step * idx[d] as f64);
        sum += f(&x);
        let mut d = 0;
        loop {
            if d == N {
                return sum * step.powi(N as i32);
            }
            idx[d] += 1;
            if idx[d] < n {
                break;
            }
            idx[d] = 0;
            d += 1;
        }
    }
}

// ---------------------------------------------------------------- test-side formulas

/// Independent (crate-free) formulas used as expected values: see `tests/common/oracle.rs`.
pub mod chi2;
pub mod hemisphere;
pub mod oracle;
pub mod quadrature;
pub mod rng;
pub mod scene;

#[allow(unused_imports, reason = "not every test binary uses the generator")]
pub use rng::{Lcg, SplitMix64};
