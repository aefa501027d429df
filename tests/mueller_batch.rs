//! Verifies the structure-of-arrays batch path `mueller::batch::mueller_from_jones_soa` against
//! the single-matrix closed form `Mueller::from_jones` (itself tested against the literal S1.7
//! formula in tests/mueller.rs), in f64 and f32, and its length validation.

mod common;

use common::{F32, F64, Tol, assert_all_close, complex_matrix2};
use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::mueller::batch::{JonesSoa, mueller_from_jones_soa};
use gmueller::real::Real;
use nalgebra::Matrix2;
use num_complex::Complex;
use proptest::prelude::*;

fn check<T: Real>(ms: &[Matrix2<Complex<f64>>], tol: Tol) {
    let n = ms.len();
    // Row-major entries a, b, c, d.
    let entry = |m: &Matrix2<Complex<f64>>, e: usize| m[(e / 2, e % 2)];
    let re: Vec<Vec<T>> = (0..4)
        .map(|e| ms.iter().map(|m| T::lit(entry(m, e).re)).collect())
        .collect();
    let im: Vec<Vec<T>> = (0..4)
        .map(|e| ms.iter().map(|m| T::lit(entry(m, e).im)).collect())
        .collect();
    let soa = JonesSoa {
        re: [&re[0], &re[1], &re[2], &re[3]],
        im: [&im[0], &im[1], &im[2], &im[3]],
    };
    let mut out = vec![vec![T::zero(); n]; 16];
    let mut slices: Vec<&mut [T]> = out.iter_mut().map(Vec::as_mut_slice).collect();
    mueller_from_jones_soa(&soa, &mut slices).unwrap();
    for (i, m) in ms.iter().enumerate() {
        let j =
            JonesMatrix::from_matrix(m.map(|z| Complex::new(T::lit(z.re), T::lit(z.im)))).unwrap();
        let single = Mueller::from_jones(&j).matrix();
        let expected: Vec<f64> = (0..16).map(|k| single[(k / 4, k % 4)].to_f64()).collect();
        let got: Vec<f64> = (0..16).map(|k| out[k][i].to_f64()).collect();
        assert_all_close("batch vs single", got, expected, tol);
    }
}

proptest! {
    #[test]
    fn batch_equals_single(ms in proptest::collection::vec(complex_matrix2(2.0), 1..40)) {
        check::<f64>(&ms, F64);
        check::<f32>(&ms, F32);
    }
}

#[test]
fn mismatched_lengths_are_rejected() {
    let a = [1.0_f64; 3];
    let b = [1.0_f64; 2];
    let soa = JonesSoa {
        re: [&a, &a, &a, &b],
        im: [&a, &a, &a, &a],
    };
    let mut out = vec![vec![0.0; 3]; 16];
    let mut slices: Vec<&mut [f64]> = out.iter_mut().map(Vec::as_mut_slice).collect();
    assert!(mueller_from_jones_soa(&soa, &mut slices).is_err());
    let soa = JonesSoa {
        re: [&a, &a, &a, &a],
        im: [&a, &a, &a, &a],
    };
    let mut short: Vec<&mut [f64]> = out.iter_mut().take(15).map(Vec::as_mut_slice).collect();
    assert!(mueller_from_jones_soa(&soa, &mut short).is_err());
}
