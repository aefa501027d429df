//! Verifies the structure-of-arrays batch path `mueller::batch::mueller_from_jones_soa` (run-time
//! dispatched SIMD: AVX2 + FMA on this machine) entry by entry against the single-matrix closed
//! form `Mueller::from_jones` (itself tested against the literal S1.7 formula in
//! tests/mueller/matrix.rs) in f64 and f32, relative to the matrix scale `N = ½‖J‖²_F`: random
//! inputs, lengths that are not multiples of the SIMD width, zero and huge / tiny magnitudes; the
//! f32 path also against the literal S1.7 formula evaluated in f64; plus the strided layouts
//! (`from_strided`, `padded_stride`) and the length validation.
//!
//! Tolerance: each entry `M_kl` is a sum of four products (or of eight squares times ½) whose
//! absolute values add up to at most `N`; computed with at most four roundings it is within
//! `4 u N = 2 ε N` of the exact value, with or without fused multiply–adds (`u = ε/2`). Two such
//! evaluations differ by at most `4 ε N`: the tolerance is `abs = T::MIN_POSITIVE` (so the zero
//! matrix must come out exactly zero up to the smallest normal) and `rel = 4 ε` of `N`.

use crate::common;

use common::{Tol, assert_close, complex_matrix2};
use gmueller::Error;
use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::mueller::batch::{JonesSoa, MuellerSoa, mueller_from_jones_soa, padded_stride};
use gmueller::real::Real;
use gmueller::stack::kron;
use gmueller::stokes::{a_mul, a_mul_inv};
use nalgebra::{Matrix2, Matrix4};
use num_complex::Complex;
use proptest::prelude::*;

/// `n` seeded matrices; entry `e` of each is scaled by `scales[e % scales.len()]`.
fn seeded(n: usize, seed: u64, scales: &[f64]) -> Vec<Matrix2<Complex<f64>>> {
    // The shared `SplitMix64`, entries in [−1, 1).
    let mut rng = common::SplitMix64(seed);
    (0..n)
        .map(|_| {
            let mut e = 0;
            let mut c = || {
                let s = scales[e % scales.len()];
                e += 1;
                Complex::new(s * rng.signed(), s * rng.signed())
            };
            Matrix2::new(c(), c(), c(), c())
        })
        .collect()
}

/// The matrices rounded to `T`, then the batch output `out[4 k + l][i]` as `f64`.
fn run_batch<T: Real>(ms: &[Matrix2<Complex<T>>]) -> Vec<Vec<f64>> {
    let n = ms.len();
    // Row-major entries a, b, c, d.
    let entry = |m: &Matrix2<Complex<T>>, e: usize| m[(e / 2, e % 2)];
    let re: Vec<Vec<T>> = (0..4)
        .map(|e| ms.iter().map(|m| entry(m, e).re).collect())
        .collect();
    let im: Vec<Vec<T>> = (0..4)
        .map(|e| ms.iter().map(|m| entry(m, e).im).collect())
        .collect();
    let soa = JonesSoa {
        re: [&re[0], &re[1], &re[2], &re[3]],
        im: [&im[0], &im[1], &im[2], &im[3]],
    };
    // Poison the buffer so an entry left unwritten cannot pass.
    let stride = padded_stride::<T>(n);
    let mut buf = vec![T::lit(f64::NAN); 16 * stride];
    let mut out = MuellerSoa::from_strided(&mut buf, n, stride).unwrap();
    mueller_from_jones_soa(&soa, &mut out).unwrap();
    out.m
        .iter()
        .map(|s| s.iter().map(|x| x.to_f64()).collect())
        .collect()
}

fn to_t<T: Real>(m: &Matrix2<Complex<f64>>) -> Matrix2<Complex<T>> {
    m.map(|z| Complex::new(T::lit(z.re), T::lit(z.im)))
}

/// `N = ½‖J‖²_F` in f64 (exact enough: the inputs are `T` values).
fn scale<T: Real>(m: &Matrix2<Complex<T>>) -> f64 {
    0.5 * m
        .iter()
        .map(|z| z.re.to_f64().powi(2) + z.im.to_f64().powi(2))
        .sum::<f64>()
}

/// Asserts `|got − want| ≤ abs + rel N` for all 16 entries.
fn assert_entries(what: &str, i: usize, got: &[f64], want: &[f64], n_scale: f64, tol: Tol) {
    for k in 0..16 {
        let (g, w) = (got[k], want[k]);
        let bound = tol.abs + tol.rel * n_scale;
        assert!(
            (g - w).abs() <= bound,
            "{what}: matrix {i}, M_{}{}: {g:e} vs {w:e} (diff {:e} > {bound:e} = abs {:e} + rel {:e} × N {n_scale:e})",
            k / 4,
            k % 4,
            (g - w).abs(),
            tol.abs,
            tol.rel,
        );
    }
}

/// The norm-relative tolerance of the header: `abs = T::MIN_POSITIVE`, `rel = 4 ε`.
fn tol<T: Real>() -> Tol {
    let eps = T::EPSILON.to_f64();
    let min_positive = if eps == f64::EPSILON {
        f64::MIN_POSITIVE
    } else {
        f64::from(f32::MIN_POSITIVE)
    };
    Tol::new(min_positive, 4.0 * eps)
}

/// Batch against `Mueller::from_jones` in `T`, per matrix, relative to `N`.
fn check_against_single<T: Real>(ms: &[Matrix2<Complex<f64>>]) {
    let ms_t: Vec<Matrix2<Complex<T>>> = ms.iter().map(to_t::<T>).collect();
    let out = run_batch(&ms_t);
    for (i, m) in ms_t.iter().enumerate() {
        let single = Mueller::from_jones(&JonesMatrix::from_matrix(*m).unwrap()).matrix();
        let want: Vec<f64> = (0..16).map(|k| single[(k / 4, k % 4)].to_f64()).collect();
        let got: Vec<f64> = (0..16).map(|k| out[k][i]).collect();
        assert_entries("batch vs from_jones", i, &got, &want, scale(m), tol::<T>());
    }
}

/// The literal S1.7 formula `A_mül (J* ⊗ J) A_mül⁻¹` in f64.
fn literal(m: &Matrix2<Complex<f64>>) -> Matrix4<f64> {
    let full = a_mul::<f64>() * kron(&m.map(|z| z.conj()), m) * a_mul_inv::<f64>();
    full.map(|z| z.re)
}

proptest! {
    #![proptest_config(common::proptest_config(256))]
    #[test]
    fn batch_equals_single(ms in proptest::collection::vec(complex_matrix2(2.0), 0..40)) {
        check_against_single::<f64>(&ms);
        check_against_single::<f32>(&ms);
    }

    /// The f32 batch against the literal formula evaluated in f64 on the same (f32) inputs: the
    /// f64 rounding (≲ 1e-15 N) is negligible, so the f32 bound `2 ε₃₂ N` of the header applies.
    #[test]
    fn f32_batch_matches_literal_formula(ms in proptest::collection::vec(complex_matrix2(3.0), 1..20)) {
        let ms32: Vec<Matrix2<Complex<f32>>> = ms.iter().map(to_t::<f32>).collect();
        let out = run_batch(&ms32);
        let t = Tol::new(1e-30, 2.0 * f64::from(f32::EPSILON) + 1e-14);
        for (i, m) in ms32.iter().enumerate() {
            let exact = literal(&m.map(|z| Complex::new(f64::from(z.re), f64::from(z.im))));
            let want: Vec<f64> = (0..16).map(|k| exact[(k / 4, k % 4)]).collect();
            let got: Vec<f64> = (0..16).map(|k| out[k][i]).collect();
            assert_entries("f32 batch vs literal f64", i, &got, &want, scale(m), t);
        }
    }
}

#[test]
fn lengths_around_the_simd_width() {
    for (seed, n) in [0_usize, 1, 3, 7, 17, 1023].into_iter().enumerate() {
        let ms = seeded(n, 0xBA7C + seed as u64, &[1.0]);
        check_against_single::<f64>(&ms);
        check_against_single::<f32>(&ms);
    }
}

#[test]
fn huge_and_tiny_magnitudes() {
    // f64: all entries ~1e±150, and entries of mixed 1e150 / 1 / 1e-150 in one matrix.
    for scales in [&[1e150][..], &[1e-150], &[1e150, 1e-150, 1.0, 1e-150]] {
        check_against_single::<f64>(&seeded(19, 0xE1, scales));
    }
    // f32: ~1e±18 (squares 1e±36 stay normal).
    for scales in [&[1e18_f64][..], &[1e-18], &[1e18, 1e-18, 1.0, 1e-18]] {
        check_against_single::<f32>(&seeded(19, 0xE2, scales));
    }
}

#[test]
fn zero_matrices_and_zero_entries() {
    // Zero matrices at every position of a 9-long batch (a full vector and a tail), and matrices
    // with single zero entries.
    let mut ms = seeded(9, 0x2E, &[1.0]);
    for i in [0, 3, 8] {
        ms[i] = Matrix2::zeros();
    }
    ms[5][(0, 1)] = Complex::new(0.0, 0.0);
    ms[6][(1, 0)] = Complex::new(0.0, 0.0);
    check_against_single::<f64>(&ms);
    check_against_single::<f32>(&ms);
    let out = run_batch(&ms.iter().map(to_t::<f64>).collect::<Vec<_>>());
    for entry in &out {
        for i in [0, 3, 8] {
            assert_close("zero matrix entry", entry[i], 0.0, Tol::new(0.0, 0.0));
        }
    }
}

#[test]
fn strided_layout() {
    // One input buffer (Re a..d, Im a..d, `stride` apart) and one output buffer: entry M_kl of
    // matrix i is at out_buf[(4 k + l) stride + i]; the padding is left untouched.
    let (n, stride) = (5, 9);
    let ms = seeded(n, 0x1A, &[1.0]);
    let mut in_buf = vec![0.0; 8 * stride];
    for (i, m) in ms.iter().enumerate() {
        for e in 0..4 {
            in_buf[e * stride + i] = m[(e / 2, e % 2)].re;
            in_buf[(4 + e) * stride + i] = m[(e / 2, e % 2)].im;
        }
    }
    let soa = JonesSoa::from_strided(&in_buf, n, stride).unwrap();
    let mut buf = vec![-7.0; 16 * stride];
    let mut out = MuellerSoa::from_strided(&mut buf, n, stride).unwrap();
    assert_eq!(out.len(), n);
    mueller_from_jones_soa(&soa, &mut out).unwrap();
    for (i, m) in ms.iter().enumerate() {
        let single = Mueller::from_jones(&JonesMatrix::from_matrix(*m).unwrap()).matrix();
        let want: Vec<f64> = (0..16).map(|k| single[(k / 4, k % 4)]).collect();
        let got: Vec<f64> = (0..16).map(|k| buf[k * stride + i]).collect();
        assert_entries("strided layout", i, &got, &want, scale(m), tol::<f64>());
    }
    for k in 0..16 {
        assert!(
            buf[k * stride + n..(k + 1) * stride]
                .iter()
                .all(|&x| x == -7.0)
        );
    }
    // Shortest buffers accepted: (slices − 1) · stride + n.
    assert!(JonesSoa::from_strided(&in_buf[..7 * stride + n], n, stride).is_ok());
    assert!(MuellerSoa::from_strided(&mut buf[..15 * stride + n], n, stride).is_ok());
    let mut empty: [f64; 0] = [];
    assert!(
        MuellerSoa::from_strided(&mut empty, 0, 0)
            .unwrap()
            .is_empty()
    );
    // Errors: a buffer one element short, a stride below n.
    for (len, st) in [(15 * stride + n - 1, stride), (16 * stride, n - 1)] {
        assert!(matches!(
            MuellerSoa::from_strided(&mut buf[..len], n, st),
            Err(Error::OutOfRange { .. })
        ));
    }
    for (len, st) in [(7 * stride + n - 1, stride), (8 * stride, n - 1)] {
        assert!(matches!(
            JonesSoa::from_strided(&in_buf[..len], n, st),
            Err(Error::OutOfRange { .. })
        ));
    }
}

/// `padded_stride`: at least `n`, whole 64-byte lines, at most 4 KiB of padding, and 16 slices
/// `s` apart start at least 192 bytes apart modulo 4 KiB (circular distance).
fn check_padded_stride<T>(n: usize) {
    let size = std::mem::size_of::<T>();
    let s = padded_stride::<T>(n);
    assert!(s >= n && (s * size).is_multiple_of(64), "n {n}: stride {s}");
    assert!(
        (s - n) * size <= 4096 + 64,
        "n {n}: stride {s} pads too much"
    );
    for k in 1..16 {
        let x = (k * s * size) % 4096;
        assert!(
            x.min(4096 - x) >= 192,
            "n {n}: stride {s}, slice {k} at {x} B mod 4 KiB"
        );
    }
}

#[test]
fn padded_stride_spreads_slices_over_the_cache() {
    for n in (0..3000).chain([4096, 8192, 1 << 16, (1 << 20) + 3]) {
        check_padded_stride::<f64>(n);
        check_padded_stride::<f32>(n);
    }
    // The case that motivated it: 1024 · 8 B = 8 KiB.
    assert_ne!(padded_stride::<f64>(1024), 1024);
}

#[test]
fn mismatched_lengths_are_rejected() {
    let long = [1.0_f64; 5];
    let short = [1.0_f64; 4];
    // Each of the 8 inputs shortened in turn.
    for bad in 0..8 {
        let pick = |k: usize| -> &[f64] { if k == bad { &short } else { &long } };
        let soa = JonesSoa {
            re: [pick(0), pick(1), pick(2), pick(3)],
            im: [pick(4), pick(5), pick(6), pick(7)],
        };
        let mut buf = vec![0.0; 16 * 5];
        let mut out = MuellerSoa::from_strided(&mut buf, 5, 5).unwrap();
        let err = mueller_from_jones_soa(&soa, &mut out);
        assert!(
            matches!(err, Err(Error::OutOfRange { .. })),
            "input {bad}: {err:?}"
        );
    }
    // Each of the 16 outputs shortened in turn.
    let soa = JonesSoa {
        re: [&long[..]; 4],
        im: [&long[..]; 4],
    };
    for bad in 0..16 {
        let mut bufs: Vec<Vec<f64>> = (0..16)
            .map(|k| vec![0.0; if k == bad { 4 } else { 5 }])
            .collect();
        let slices: Vec<&mut [f64]> = bufs.iter_mut().map(Vec::as_mut_slice).collect();
        let mut out = MuellerSoa {
            m: slices.try_into().unwrap(),
        };
        let err = mueller_from_jones_soa(&soa, &mut out);
        assert!(
            matches!(err, Err(Error::OutOfRange { .. })),
            "output {bad}: {err:?}"
        );
        // Nothing was written.
        assert!(bufs.iter().flatten().all(|&x| x == 0.0));
    }
}
