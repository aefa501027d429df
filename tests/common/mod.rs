//! Shared tolerances, comparison helpers and proptest strategies for the integration tests.
//!
//! Every comparison states an absolute *and* a relative tolerance: `|a − b| ≤ abs + rel·max(|a|, |b|)`.
//! Strategies produce inputs that are valid by construction and bounded.
#![allow(
    dead_code,
    reason = "each test file uses a different subset of the helpers"
)]

use nalgebra::{Matrix4, Vector4};

// Tolerances and comparisons: the verification kit's (`gmueller::verify::tol`).
pub use gmueller::verify::tol::{
    F32, F64, Tol, assert_all_close, assert_close, assert_complex_close,
};

/// Two Monte Carlo estimates of one Mueller matrix, each from the sums of its draws and of their
/// squares over `n` draws (refused draws count as zeros): their means agree within `z_max`
/// standard errors in every entry. Returns the two means and their standard errors.
pub fn assert_same_mean(
    what: &str,
    a: (Matrix4<f64>, Matrix4<f64>, usize),
    b: (Matrix4<f64>, Matrix4<f64>, usize),
    z_max: f64,
) -> [(Matrix4<f64>, Matrix4<f64>); 2] {
    let stats = |(sum, sq, n): (Matrix4<f64>, Matrix4<f64>, usize)| {
        let mean = sum / n as f64;
        let var = (sq / n as f64 - mean.component_mul(&mean)) / (n as f64 - 1.0);
        (mean, var.map(f64::sqrt))
    };
    let ((ma, sa), (mb, sb)) = (stats(a), stats(b));
    for k in 0..16 {
        let se = sa[k].hypot(sb[k]);
        let z = (ma[k] - mb[k]) / se.max(1e-12);
        assert!(
            z.abs() < z_max,
            "{what}: entry {k}: {} vs {} (z {z})",
            ma[k],
            mb[k]
        );
    }
    [(ma, sa), (mb, sb)]
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

// ---------------------------------------------------------------- proptest configuration and strategies

// The run configuration (fixed seed; `GMUELLER_PROPTEST_SEARCH=f` for fresh seeds and f× the
// cases) and the strategies of valid objects: the verification kit's
// (`gmueller::verify::strategy`).
pub use gmueller::verify::strategy::{
    angle, complex, complex_matrix2, frame, log_uniform, proptest_config, real, spd2,
    stokes_vector, unit_vector3,
};

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

pub use gmueller::verify::quadrature::cube_quad;

/// Gauss–Legendre nodes and weights on [−1, 1] (the kit's rule, as two vectors).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let r = gmueller::verify::quadrature::gauss_legendre(n);
    (r.nodes, r.weights)
}

// ---------------------------------------------------------------- test-side formulas

/// Independent (crate-free) formulas used as expected values: see `tests/common/oracle.rs`.
pub mod chi2;
pub mod hemisphere;
pub mod medium;
pub mod oracle;
pub mod quadrature;
pub mod rng;
pub mod scene;
pub mod shading;

#[allow(unused_imports, reason = "not every test binary uses the generator")]
pub use rng::{Lcg, SplitMix64};
