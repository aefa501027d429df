//! Assertions of physical validity, with the crate's tolerances and messages that print the
//! offending input.

use nalgebra::{Matrix4, Vector4};

use super::tol::Tol;
use crate::mueller::Mueller;

/// Panics unless `s` is a valid Stokes vector within `tol`: finite, `S0 ≥ −abs`, and
/// `√(S1² + S2² + S3²) ≤ S0 + abs + rel · S0`. The norm is taken on ratios to the largest
/// entry (no under- or overflow of squares near `1e∓300`; use `abs = 0` there, since any
/// absolute part swamps such values).
///
/// ```
/// use gmueller::verify::{check::assert_valid_stokes, tol::F64};
/// use nalgebra::Vector4;
/// assert_valid_stokes("on the cone", Vector4::new(2.0, 0.0, 1.2, -1.6), F64);
/// let r = std::panic::catch_unwind(|| {
///     assert_valid_stokes("outside", Vector4::new(1.0, 0.8, 0.8, 0.0), F64)
/// });
/// assert!(r.is_err());
/// ```
///
/// # Panics
/// When `s` is not valid within `tol`.
#[track_caller]
pub fn assert_valid_stokes(what: &str, s: Vector4<f64>, tol: Tol) {
    assert!(
        s.iter().all(|v| v.is_finite()),
        "{what}: {s:?} is not finite"
    );
    let s0 = s[0];
    assert!(s0 >= -tol.abs, "{what}: S0 = {s0:e} < 0 in {s:?}");
    let scale = s.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let polarized = if scale > 0.0 {
        let (a, b, c) = (s[1] / scale, s[2] / scale, s[3] / scale);
        (a * a + b * b + c * c).sqrt() * scale
    } else {
        0.0
    };
    assert!(
        polarized <= s0 + tol.abs + tol.rel * s0.abs(),
        "{what}: |(S1, S2, S3)| = {polarized:e} > S0 = {s0:e} (excess {:e}) in {s:?}",
        polarized - s0
    );
}

/// Panics unless `m` is physically realizable in Cloude's sense within `tol`
/// ([`Mueller::is_physically_realizable`]: every eigenvalue of the coherency matrix
/// `≥ −tol · tr H`); the message prints the matrix and the eigenvalues.
///
/// ```
/// use gmueller::verify::check::assert_realizable;
/// use nalgebra::{Matrix4, Vector4};
/// assert_realizable("depolarizer", &Matrix4::from_diagonal(&Vector4::new(1.0, 0.3, 0.3, 0.3)), 1e-12);
/// // The handedness flip maps Stokes vectors to Stokes vectors but is not realizable.
/// let flip = Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, 1.0, -1.0));
/// assert!(std::panic::catch_unwind(|| assert_realizable("flip", &flip, 1e-12)).is_err());
/// ```
///
/// # Panics
/// When `m` is not finite or not realizable within `tol`.
#[track_caller]
pub fn assert_realizable(what: &str, m: &Matrix4<f64>, tol: f64) {
    let mm = Mueller::from_matrix(*m)
        .unwrap_or_else(|e| panic!("{what}: {m} is not a Mueller matrix: {e}"));
    assert!(
        mm.is_physically_realizable(tol),
        "{what}: not realizable within {tol:e}: coherency eigenvalues {:?} (trace {:e}) of{m}",
        mm.coherency_eigenvalues().as_slice(),
        m[(0, 0)]
    );
}

/// Panics unless every entry of `a` and `b` agrees within `tol` relative to the larger matrix:
/// `|a_ij − b_ij| ≤ abs + rel · max(max|a|, max|b|)` (a Mueller matrix's small entries are
/// compared on the scale of its largest); the message prints both matrices.
///
/// # Panics
/// When an entry does not agree, or one is not finite.
#[track_caller]
pub fn assert_mueller_close(what: &str, a: &Matrix4<f64>, b: &Matrix4<f64>, tol: Tol) {
    let scale = a.amax().max(b.amax());
    for r in 0..4 {
        for c in 0..4 {
            let (x, y) = (a[(r, c)], b[(r, c)]);
            assert!(
                x.is_finite() && y.is_finite() && (x - y).abs() <= tol.abs + tol.rel * scale,
                "{what}: entry ({r}, {c}) {x:e} vs {y:e} (diff {:e}, tol abs {:e} rel {:e} of \
                 {scale:e}); whole:{a}vs{b}",
                (x - y).abs(),
                tol.abs,
                tol.rel
            );
        }
    }
}

/// The reverse-path Mueller matrix that reciprocity predicts, `D Mᵀ D` with
/// `D = diag(1, 1, −1, 1)`, both in the s/p frames of the crate's BSDF
/// (`docs/renderer.md`): `f(b → a) = D f(a → b)ᵀ D` for a plane-wave BSDF `f = M/cos θ_i` in
/// reflection (`tests/bsdf/reciprocity.rs` found it the only one of the sixteen sign and
/// transpose candidates that holds for rough glass and conductors at any azimuth).
#[must_use]
pub fn reciprocal(m: &Matrix4<f64>) -> Matrix4<f64> {
    let d = Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, -1.0, 1.0));
    d * m.transpose() * d
}

/// Panics unless `reverse` equals [`reciprocal`]`(forward)` within `tol` on the matrices' scale
/// ([`assert_mueller_close`]).
///
/// ```
/// use gmueller::verify::{check, tol::F64};
/// use nalgebra::Matrix4;
/// let m = Matrix4::new(1.0, 0.2, 0.1, 0.0, 0.2, 0.9, 0.3, 0.1, -0.1, 0.2, 0.8, 0.2, 0.0, 0.1, -0.2, 0.7);
/// check::assert_reciprocal("constructed", &m, &check::reciprocal(&m), F64);
/// // A non-symmetric matrix is not its own reverse.
/// assert!(std::panic::catch_unwind(|| check::assert_reciprocal("same", &m, &m, F64)).is_err());
/// ```
///
/// # Panics
/// When an entry does not agree.
#[track_caller]
pub fn assert_reciprocal(what: &str, forward: &Matrix4<f64>, reverse: &Matrix4<f64>, tol: Tol) {
    assert_mueller_close(
        &format!("{what} (reverse against D Mᵀ D of the forward)"),
        reverse,
        &reciprocal(forward),
        tol,
    );
}

/// The largest fraction of the incident power that the Mueller matrix `m` passes, over all
/// incident Stokes vectors: `max_S (m S)₀/S₀ = M₀₀ + √(M₀₁² + M₀₂² + M₀₃²)` (reached by the fully
/// polarized state along `(M₀₁, M₀₂, M₀₃)`). For an albedo matrix
/// ([`super::quadrature::hemisphere_albedo`]) it is the energy a surface returns at worst.
#[must_use]
pub fn max_transmittance(m: &Matrix4<f64>) -> f64 {
    m[(0, 0)] + (m[(0, 1)].powi(2) + m[(0, 2)].powi(2) + m[(0, 3)].powi(2)).sqrt()
}

/// Panics unless the Mueller matrix `m` is passive within `tol`: every incident Stokes vector
/// keeps at most its power, [`max_transmittance`]`(m) ≤ 1 + tol` (energy ≤ 1), and no state is
/// passed with negative power, `M₀₀ − √(M₀₁² + M₀₂² + M₀₃²) ≥ −tol`. The message prints the
/// matrix and the worst incident state.
///
/// ```
/// use gmueller::verify::check::assert_passive;
/// use nalgebra::Matrix4;
/// // An ideal polarizer: 1/2 of unpolarized light, all of the state along its axis.
/// let pol = Matrix4::new(0.5, 0.5, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
/// assert_passive("polarizer", &pol, 1e-12);
/// // The same with M₀₀ = 0.6 passes 1.1 of the light along its axis: not passive.
/// let mut gain = pol;
/// gain[(0, 0)] = 0.6;
/// assert!(std::panic::catch_unwind(|| assert_passive("gain", &gain, 1e-12)).is_err());
/// ```
///
/// # Panics
/// When `m` is not finite or not passive within `tol`.
#[track_caller]
pub fn assert_passive(what: &str, m: &Matrix4<f64>, tol: f64) {
    assert!(m.iter().all(|v| v.is_finite()), "{what}: not finite:{m}");
    let d = (m[(0, 1)].powi(2) + m[(0, 2)].powi(2) + m[(0, 3)].powi(2)).sqrt();
    let worst = if d > 0.0 {
        [1.0, m[(0, 1)] / d, m[(0, 2)] / d, m[(0, 3)] / d]
    } else {
        [1.0, 0.0, 0.0, 0.0]
    };
    assert!(
        m[(0, 0)] + d <= 1.0 + tol,
        "{what}: passes {:e} of the power of the state {worst:?} (energy > 1 + {tol:e}):{m}",
        m[(0, 0)] + d
    );
    assert!(
        m[(0, 0)] - d >= -tol,
        "{what}: passes {:e} (negative) of the power of the state opposite {worst:?}:{m}",
        m[(0, 0)] - d
    );
}
