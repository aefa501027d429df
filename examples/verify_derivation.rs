//! Verify a derivation with the kit (`gmueller::verify`, feature `verify`; the examples have it
//! on): the claim "S1.7, `M = A_mül (J* ⊗ J) A_mül⁻¹`, equals the crate's closed-form Jones →
//! Mueller conversion" is checked over 256 random general Jones matrices. The claim holds for
//! the column-stacked Kronecker form, and proptest finds and shrinks a counterexample for the
//! row-stacked one, `A_mül (J ⊗ J*) A_mül⁻¹` — an erratum-sized slip in a derivation.
//!
//! Then a claim with no closed form to lean on: Lemma S2.1, `F{g^Σ(Bξ)}(q)`, against the
//! Fourier transform computed by quadrature (`oracle::lemma_s2_1_by_quadrature`), over 32 random
//! SPD `Σ`, non-singular `B` and `q`. The corrected form (`B⁻ᵀ q`, `|det B|`) holds; the
//! printed one (`B⁻¹ q`) fails, and proptest shrinks the counterexample toward a small `B`.
//!
//! Run: `cargo run --example verify_derivation`. It exits with status 1 unless the right form
//! passes and the wrong one fails.
//! See `docs/verifying.md`.

use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::verify::proptest::prelude::*;
use gmueller::verify::proptest::test_runner::{TestError, TestRunner};
use gmueller::verify::{oracle, strategy};
use nalgebra::{Matrix2, Matrix4, Vector2};
use num_complex::Complex;

type Jones = Matrix2<Complex<f64>>;

/// "`form(J)` is the Mueller matrix of `J`", checked over 256 cases; the shrunk counterexample
/// on failure.
fn check(form: fn(&Jones) -> Matrix4<f64>) -> Result<(), TestError<Jones>> {
    // No regression file for an example (proptest would look for one beside its source).
    let config = strategy::proptest_config(256);
    let mut runner = TestRunner::new(gmueller::verify::proptest::test_runner::Config {
        failure_persistence: None,
        ..config
    });
    runner.run(&strategy::complex_matrix2(1.0), |j| {
        let closed = Mueller::from_jones(&JonesMatrix::from_matrix(j).unwrap()).matrix();
        let d = (form(&j) - closed).amax();
        prop_assert!(d <= 1e-12 * closed.amax().max(1e-300), "off by {d:e}");
        Ok(())
    })
}

/// S1.7 with column stacking, `vec(C) = (C_xx, C_yx, C_xy, C_yy)` (the crate's convention).
fn column_stacked(j: &Jones) -> Matrix4<f64> {
    oracle::mueller_literal(j)
}

/// The same with the Kronecker factors swapped (row stacking): the deliberate slip.
fn row_stacked(j: &Jones) -> Matrix4<f64> {
    let k = oracle::kron(j, &j.map(|z| z.conj()));
    (oracle::a_mul() * k * oracle::a_mul_inv()).map(|z| z.re)
}

/// A Lemma S2.1 case: the covariance Σ, the map B (|det B| ≥ 0.2) and the frequency q.
type LemmaCase = (Matrix2<f64>, Matrix2<f64>, Vector2<f64>);

/// Points per axis for the quadrature of `g^Σ(Bξ)`, whose covariance `C = B⁻¹ΣB⁻ᵀ` can be
/// elongated (`|det B|` down to 0.2 with entries up to 1.5): the box reaches `9 σ_max` each way, and
/// the step must stay below half the narrowest `σ_min` (the trapezoid's aliasing error is then
/// `~e^{−8π²}`): `36 σ_max/σ_min` points, at least 241 (1081 at `σ_max/σ_min = 30`). A fixed 241 missed
/// 1e-6 relative in fresh-seed runs (`GMUELLER_PROPTEST_SEARCH=50`: 8e-6 at `σ_max/σ_min ≈ 30`).
fn points(cov: &Matrix2<f64>, b: &Matrix2<f64>) -> usize {
    let bi = b.try_inverse().expect("|det B| ≥ 0.2");
    let e = (bi * cov * bi.transpose()).symmetric_eigenvalues();
    let ratio = (e.max() / e.min()).sqrt();
    ((36.0 * ratio).ceil() as usize).max(241) | 1
}

/// "`form(Σ, B, q)` is the Fourier transform of `g^Σ(Bξ)` at q", against quadrature, 32 cases.
fn check_lemma(form: fn(&LemmaCase) -> f64) -> Result<(), TestError<LemmaCase>> {
    let config = strategy::proptest_config(32);
    let mut runner = TestRunner::new(gmueller::verify::proptest::test_runner::Config {
        failure_persistence: None,
        ..config
    });
    let b = proptest::array::uniform4(-1.5..1.5f64)
        .prop_map(|[a, b, c, d]| Matrix2::new(a, b, c, d))
        .prop_filter("non-singular", |b: &Matrix2<f64>| {
            b.determinant().abs() >= 0.2
        });
    let q = (-1.5..1.5f64, -1.5..1.5f64).prop_map(|(x, y)| Vector2::new(x, y));
    let cases = (strategy::spd2_conditioned(0.3, 2.0, 5.0), b, q);
    runner.run(&cases, |case| {
        let (cov, b, q) = case;
        let quadrature = oracle::lemma_s2_1_by_quadrature(&cov, &b, &q, points(&cov, &b)).re;
        let d = (form(&case) - quadrature).abs();
        prop_assert!(
            d <= 1e-7 + 1e-6 * quadrature.abs(),
            "off by {d:e} (quadrature {quadrature:e})"
        );
        Ok(())
    })
}

fn main() {
    let mut ok = true;
    match check(column_stacked) {
        Ok(()) => println!(
            "column-stacked S1.7: holds in {} cases",
            strategy::proptest_config(256).cases
        ),
        Err(e) => {
            println!("column-stacked S1.7: FAILED (unexpected): {e}");
            ok = false;
        }
    }
    match check(row_stacked) {
        Err(TestError::Fail(why, j)) => {
            println!("row-stacked S1.7: fails, as it should; shrunk counterexample ({why}):");
            println!("J = {j}");
        }
        other => {
            println!("row-stacked S1.7: not rejected (unexpected): {other:?}");
            ok = false;
        }
    }
    match check_lemma(|(cov, b, q)| oracle::lemma_s2_1(cov, b, q)) {
        Ok(()) => println!(
            "Lemma S2.1 with B⁻ᵀq: holds in {} cases",
            strategy::proptest_config(32).cases
        ),
        Err(e) => {
            println!("Lemma S2.1 with B⁻ᵀq: FAILED (unexpected): {e}");
            ok = false;
        }
    }
    match check_lemma(|(cov, b, q)| oracle::lemma_s2_1_printed(cov, b, q)) {
        Err(TestError::Fail(why, (cov, b, q))) => {
            println!(
                "Lemma S2.1 as printed (B⁻¹q): fails, as it should; shrunk counterexample ({why}):"
            );
            println!("Σ = {cov}B = {b}q = {q}");
        }
        other => {
            println!("Lemma S2.1 as printed: not rejected (unexpected): {other:?}");
            ok = false;
        }
    }
    if !ok {
        std::process::exit(1);
    }
}

/// `cargo test` runs this (the example is declared with `test = true`): the outcomes `main`
/// prints are asserted.
#[test]
fn the_right_form_holds_and_the_wrong_one_is_caught() {
    assert!(check(column_stacked).is_ok());
    assert!(matches!(check(row_stacked), Err(TestError::Fail(..))));
    assert!(check_lemma(|(cov, b, q)| oracle::lemma_s2_1(cov, b, q)).is_ok());
    assert!(matches!(
        check_lemma(|(cov, b, q)| oracle::lemma_s2_1_printed(cov, b, q)),
        Err(TestError::Fail(..))
    ));
}
