//! Verify a derivation with the kit (`gmueller::verify`, feature `verify`; the examples have it
//! on): the claim "S1.7, `M = A_mül (J* ⊗ J) A_mül⁻¹`, equals the crate's closed-form Jones →
//! Mueller conversion" is checked over 256 random general Jones matrices. The claim holds for
//! the column-stacked Kronecker form, and proptest finds and shrinks a counterexample for the
//! row-stacked one, `A_mül (J ⊗ J*) A_mül⁻¹` — an erratum-sized slip in a derivation.
//!
//! Run: `cargo run --example verify_derivation`. It exits with status 1 unless the right form
//! passes and the wrong one fails.
//! See `docs/verifying.md`.

use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::verify::proptest::prelude::*;
use gmueller::verify::proptest::test_runner::{TestError, TestRunner};
use gmueller::verify::{oracle, strategy};
use nalgebra::{Matrix2, Matrix4};
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

fn main() {
    let mut ok = true;
    match check(column_stacked) {
        Ok(()) => println!("column-stacked S1.7: holds in 256 cases"),
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
}
