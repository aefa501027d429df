//! The one structure-of-arrays view of the batch paths: `K` component slices of one common
//! length ([`Soa`], [`SoaMut`]), cut from one buffer `stride` elements apart, and the stride
//! [`padded_stride`] that keeps them off one L1 cache set.

use core::fmt;

/// Why `K` slices do not fit a buffer or do not share one length (converted to
/// [`crate::Error::OutOfRange`] with the same fields by the batch paths).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayoutError {
    /// What is out of range.
    pub what: &'static str,
    /// The offending value.
    pub value: f64,
    /// The accepted range, in words.
    pub expected: &'static str,
}

impl fmt::Display for LayoutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} = {} out of range (expected {})",
            self.what, self.value, self.expected
        )
    }
}

impl core::error::Error for LayoutError {}

/// `K` input slices of one batch: component `k` of element `i` is `c[k][i]` (a test below
/// builds one from a strided buffer).
#[derive(Debug, Clone, Copy)]
pub struct Soa<'a, T, const K: usize> {
    /// The component slices.
    pub c: [&'a [T]; K],
}

/// `K` output slices of one batch: component `k` of element `i` is `c[k][i]`.
#[derive(Debug)]
pub struct SoaMut<'a, T, const K: usize> {
    /// The component slices.
    pub c: [&'a mut [T]; K],
}

impl<'a, T, const K: usize> Soa<'a, T, K> {
    /// The `K` slices of `n` elements of `buf`, `stride` elements apart: component `k` starts
    /// at `k · stride`.
    ///
    /// # Errors
    /// When `stride < n` or `buf.len() < (K − 1) stride + n`.
    pub fn from_strided(buf: &'a [T], n: usize, stride: usize) -> Result<Self, LayoutError> {
        Ok(Self {
            c: strided(buf, n, stride)?,
        })
    }
}

impl<'a, T, const K: usize> SoaMut<'a, T, K> {
    /// [`Soa::from_strided`] for an output buffer.
    ///
    /// # Errors
    /// When `stride < n` or `buf.len() < (K − 1) stride + n`.
    pub fn from_strided(buf: &'a mut [T], n: usize, stride: usize) -> Result<Self, LayoutError> {
        Ok(Self {
            c: strided_mut(buf, n, stride)?,
        })
    }
}

/// `Ok` when `count` slices of `n` elements, `stride` apart, fit in `len` elements.
fn check_strided(len: usize, count: usize, n: usize, stride: usize) -> Result<(), LayoutError> {
    if stride < n {
        return Err(LayoutError {
            what: "batch stride",
            value: stride as f64,
            expected: "at least the number of elements n",
        });
    }
    let need = count
        .saturating_sub(1)
        .saturating_mul(stride)
        .saturating_add(n);
    if len < need {
        return Err(LayoutError {
            what: "batch buffer length",
            value: len as f64,
            expected: "at least (slices − 1) · stride + n",
        });
    }
    Ok(())
}

/// `K` slices of `n` elements of `buf`, `stride` apart (the layout of every `from_strided`).
pub(crate) fn strided<T, const K: usize>(
    buf: &[T],
    n: usize,
    stride: usize,
) -> Result<[&[T]; K], LayoutError> {
    check_strided(buf.len(), K, n, stride)?;
    Ok(core::array::from_fn(|k| &buf[k * stride..k * stride + n]))
}

/// [`strided`] for mutable slices.
pub(crate) fn strided_mut<T, const K: usize>(
    buf: &mut [T],
    n: usize,
    stride: usize,
) -> Result<[&mut [T]; K], LayoutError> {
    check_strided(buf.len(), K, n, stride)?;
    let mut chunks = buf.chunks_mut(stride.max(1));
    Ok(core::array::from_fn(|_| match chunks.next() {
        Some(c) => &mut c[..n],
        None => &mut [],
    }))
}

/// A stride (in elements of `T`) for the slices of a batch of `n` elements in one buffer,
/// chosen so the slices do not start at addresses that are equal modulo 4 KiB.
///
/// A batch loop streams through many slices at once (24 for Jones → Mueller). When their start
/// addresses agree modulo 4 KiB (one buffer with `stride = n` and `n · size_of::<T>()` a
/// multiple of 4 KiB, e.g. `n = 1024`; or separately allocated page-aligned slices) they all map
/// to the same set of the 8-way L1 data cache and the loop runs several times slower (measured
/// on AMD EPYC, 1024 Jones → Mueller matrices in `f64`: 27–38 µs instead of 2.6–4.2 µs, over
/// several runs). This returns the smallest `s ≥ n`, a whole number of 64-byte cache lines, for
/// which slices `s` elements apart start at least three cache lines apart modulo 4 KiB (for up
/// to 16 slices); it wastes at most about 4 KiB per slice.
///
/// # Examples
/// ```
/// use gmueller::mueller::batch::padded_stride;
/// assert_eq!(padded_stride::<f64>(1024), 1048); // 1024 · 8 B is a multiple of 4 KiB
/// assert!(padded_stride::<f32>(1000) >= 1000);
/// ```
#[must_use]
pub fn padded_stride<T>(n: usize) -> usize {
    const PAGE: usize = 4096;
    const LINE: usize = 64;
    const MIN_GAP: usize = 3 * LINE;
    let size = core::mem::size_of::<T>().max(1);
    let per_line = (LINE / size).max(1);
    let first = n.div_ceil(per_line) * per_line;
    let spread = |s: usize| {
        let d = s.wrapping_mul(size) % PAGE;
        (1..16).all(|k| {
            let x = (k * d) % PAGE;
            x.min(PAGE - x) >= MIN_GAP
        })
    };
    (0..PAGE / LINE)
        .map(|j| first + j * per_line)
        .find(|&s| spread(s))
        .unwrap_or(first)
}

#[cfg(test)]
mod tests {
    use super::{Soa, padded_stride};

    /// The example the private type's docs had: two components of three elements, `s` apart.
    #[test]
    fn from_strided_gives_k_slices_of_n() {
        let (n, s) = (3, padded_stride::<f32>(3));
        let buf = vec![1.0_f32; 2 * s];
        let soa = Soa::<f32, 2>::from_strided(&buf, n, s).unwrap();
        assert_eq!((soa.c[0].len(), soa.c[1].len()), (3, 3));
        assert!(Soa::<f32, 2>::from_strided(&buf, n, 2 * s).is_err()); // past the buffer
    }
}
