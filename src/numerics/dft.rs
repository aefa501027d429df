//! Discrete Fourier transforms of complex data on periodic grids of any dimension, unnormalised
//! in both directions:
//!
//! ```text
//! forward  X_q = Σ_j x_j e^{−2πi q·j/n},     inverse  x_j = Σ_q X_q e^{+2πi q·j/n}
//! ```
//! (so inverse ∘ forward multiplies by the number of points). Grids are stored with the first
//! axis fastest: the point `(i₀, i₁, …)` of a grid `(n₀, n₁, …)` is at `i₀ + n₀ (i₁ + n₁ (…))`.
//! Lengths that are powers of two use an iterative radix-2 transform; other lengths the direct
//! sum with an exact twiddle table (`O(n²)` per line, meant for short lines).
//!
//! The random-field generator of `matter` is the only user; the transforms are not a hot path
//! (one per realization), so the scratch line is allocated once per call.

use num_complex::Complex;

type C = Complex<f64>;

/// `e^{sign·2πi m/n}` for `m` in `0..n`, each from its own `sin_cos` (no accumulated rounding).
fn twiddles(n: usize, sign: f64) -> Vec<C> {
    (0..n)
        .map(|m| {
            let (s, c) = (sign * core::f64::consts::TAU * m as f64 / n as f64).sin_cos();
            C::new(c, s)
        })
        .collect()
}

/// One line of length `n` in place; `tw` is [`twiddles`]`(n, sign)`, `tmp` a scratch of length n.
fn line(x: &mut [C], tw: &[C], tmp: &mut [C]) {
    let n = x.len();
    if n <= 1 {
        return;
    }
    if n.is_power_of_two() {
        // Bit-reversal permutation, then butterflies; stage of span m uses e^{±2πi j/m} =
        // tw[j·n/m].
        let bits = n.trailing_zeros();
        for i in 0..n {
            let r = i.reverse_bits() >> (usize::BITS - bits);
            if r > i {
                x.swap(i, r);
            }
        }
        let mut m = 2;
        while m <= n {
            let step = n / m;
            for start in (0..n).step_by(m) {
                for j in 0..m / 2 {
                    let w = tw[j * step];
                    let a = x[start + j];
                    let b = x[start + j + m / 2] * w;
                    x[start + j] = a + b;
                    x[start + j + m / 2] = a - b;
                }
            }
            m *= 2;
        }
    } else {
        for (q, out) in tmp.iter_mut().enumerate() {
            let mut acc = C::new(0.0, 0.0);
            for (j, v) in x.iter().enumerate() {
                acc += v * tw[(q * j) % n];
            }
            *out = acc;
        }
        x.copy_from_slice(tmp);
    }
}

/// The DFT of `data` on the grid `dims` (first axis fastest), in place: forward (`e^{−2πi…}`)
/// unless `inverse`. Unnormalised both ways.
///
/// # Panics
/// If `data.len()` is not the product of `dims` (a caller bug).
pub(crate) fn dft_in_place(data: &mut [C], dims: &[usize], inverse: bool) {
    let total: usize = dims.iter().product();
    assert_eq!(data.len(), total, "grid of {dims:?} needs {total} values");
    let sign = if inverse { 1.0 } else { -1.0 };
    let mut stride = 1;
    for &n in dims {
        if n > 1 {
            let tw = twiddles(n, sign);
            let mut buf = vec![C::new(0.0, 0.0); n];
            let mut tmp = vec![C::new(0.0, 0.0); n];
            // Lines along this axis start at every index whose coordinate on the axis is 0.
            let block = stride * n;
            for outer in (0..total).step_by(block) {
                for inner in 0..stride {
                    let base = outer + inner;
                    for (i, b) in buf.iter_mut().enumerate() {
                        *b = data[base + i * stride];
                    }
                    line(&mut buf, &tw, &mut tmp);
                    for (i, b) in buf.iter().enumerate() {
                        data[base + i * stride] = *b;
                    }
                }
            }
        }
        stride *= n;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The direct N-D sum, the oracle.
    fn naive(data: &[C], dims: &[usize], sign: f64) -> Vec<C> {
        let total: usize = dims.iter().product();
        let coords = |mut i: usize| -> Vec<usize> {
            dims.iter()
                .map(|&n| {
                    let c = i % n;
                    i /= n;
                    c
                })
                .collect()
        };
        (0..total)
            .map(|q| {
                let cq = coords(q);
                let mut acc = C::new(0.0, 0.0);
                for (j, v) in data.iter().enumerate() {
                    let cj = coords(j);
                    let phase: f64 = cq
                        .iter()
                        .zip(&cj)
                        .zip(dims)
                        .map(|((a, b), n)| (a * b) as f64 / *n as f64)
                        .sum();
                    let (s, c) = (sign * core::f64::consts::TAU * phase).sin_cos();
                    acc += v * C::new(c, s);
                }
                acc
            })
            .collect()
    }

    fn data(n: usize) -> Vec<C> {
        (0..n)
            .map(|i| C::new((i as f64 * 0.37).sin() + 0.1, (i as f64 * 1.3).cos()))
            .collect()
    }

    #[test]
    fn matches_direct_sum_in_1_2_3_dimensions_and_mixed_lengths() {
        for dims in [
            vec![8],
            vec![6],
            vec![4, 3],
            vec![8, 16],
            vec![5, 4, 3],
            vec![4, 4, 8],
        ] {
            let total: usize = dims.iter().product();
            let x = data(total);
            for inverse in [false, true] {
                let mut y = x.clone();
                dft_in_place(&mut y, &dims, inverse);
                let z = naive(&x, &dims, if inverse { 1.0 } else { -1.0 });
                let err = y
                    .iter()
                    .zip(&z)
                    .map(|(a, b)| (a - b).norm())
                    .fold(0.0, f64::max);
                assert!(
                    err < 1e-12 * total as f64,
                    "{dims:?} inverse={inverse}: {err:e}"
                );
            }
        }
    }

    #[test]
    fn inverse_of_forward_is_total_times_identity() {
        let dims = [16, 8, 4];
        let x = data(512);
        let mut y = x.clone();
        dft_in_place(&mut y, &dims, false);
        dft_in_place(&mut y, &dims, true);
        for (a, b) in x.iter().zip(&y) {
            assert!((a * 512.0 - b).norm() < 1e-11);
        }
    }
}
