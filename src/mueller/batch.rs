//! A structure-of-arrays batch path for Jones → Mueller: the same closed form as
//! [`Mueller::from_jones`](super::Mueller::from_jones), over slices, with explicit SIMD chosen at
//! run time.
//!
//! The inputs are the real and imaginary parts of the four Jones entries (eight slices), the
//! outputs the sixteen Mueller entries (sixteen slices), one element per matrix. `f32` and `f64`
//! run a hand-vectorised kernel through [`pulp`]: the CPU is queried once per call and the kernel
//! is compiled for AVX-512 (x86-64-v4), AVX2 + FMA (x86-64-v3) or NEON (aarch64) when present, with a portable
//! loop otherwise. No `unsafe` is written in this crate and no `RUSTFLAGS` are needed. Lay a
//! batch out with [`padded_stride`] (see there why).

use pulp::{Simd, WithSimd};

use crate::error::Error;
use crate::real::Real;
use crate::simd::complex::{C, im_conj, re_conj};
use crate::simd::driver::{self, LaneMap};
use crate::simd::{LayoutError, Soa, SoaMut};

pub use crate::simd::padded_stride;

/// A batch of Jones matrices `[[a, b], [c, d]]` as eight slices of equal length (real and
/// imaginary parts of `a, b, c, d`, row-major).
#[derive(Debug, Clone, Copy)]
pub struct JonesSoa<'a, T> {
    /// Real parts of `a, b, c, d`.
    pub re: [&'a [T]; 4],
    /// Imaginary parts of `a, b, c, d`.
    pub im: [&'a [T]; 4],
}

/// The output of a batch of Mueller matrices: sixteen slices of equal length, one per entry in
/// row-major order (`m[4 k + l]` holds `M_kl` of every matrix).
#[derive(Debug)]
pub struct MuellerSoa<'a, T> {
    /// Entries `M_00, M_01, …, M_33`.
    pub m: [&'a mut [T]; 16],
}

impl<'a, T> JonesSoa<'a, T> {
    /// The eight input slices of `n` matrices from one buffer, `stride` elements apart:
    /// `Re a, Re b, Re c, Re d, Im a, Im b, Im c, Im d` start at `0, stride, …, 7 stride`.
    ///
    /// Use [`padded_stride`] for `stride` (see there why a stride of exactly `n` can be slow).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when `stride < n` or `buf.len() < 7 stride + n`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::mueller::batch::{JonesSoa, padded_stride};
    /// let (n, s) = (3, padded_stride::<f64>(3));
    /// let buf = vec![1.0_f64; 8 * s];
    /// assert_eq!(JonesSoa::from_strided(&buf, n, s).unwrap().im[3].len(), 3);
    /// ```
    pub fn from_strided(buf: &'a [T], n: usize, stride: usize) -> Result<Self, Error> {
        let [ar, br, cr, dr, ai, bi, ci, di] = Soa::<T, 8>::from_strided(buf, n, stride)?.c;
        Ok(Self {
            re: [ar, br, cr, dr],
            im: [ai, bi, ci, di],
        })
    }
}

impl<'a, T> MuellerSoa<'a, T> {
    /// The sixteen entry slices of `n` matrices in one buffer, `stride` elements apart: entry
    /// `M_kl` of matrix `i` lands at `buf[(4 k + l) stride + i]`.
    ///
    /// Use [`padded_stride`] for `stride` (see there why a stride of exactly `n` can be slow).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when `stride < n` or `buf.len() < 15 stride + n`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::mueller::batch::{MuellerSoa, padded_stride};
    /// let (n, s) = (3, padded_stride::<f64>(3));
    /// let mut buf = vec![0.0_f64; 16 * s];
    /// let out = MuellerSoa::from_strided(&mut buf, n, s).unwrap();
    /// assert_eq!(out.len(), 3);
    /// ```
    pub fn from_strided(buf: &'a mut [T], n: usize, stride: usize) -> Result<Self, Error> {
        Ok(Self {
            m: SoaMut::<T, 16>::from_strided(buf, n, stride)?.c,
        })
    }

    /// The number of matrices, taken from the first entry slice (`M_00`).
    #[must_use]
    pub fn len(&self) -> usize {
        self.m[0].len()
    }

    /// `true` when the batch holds no matrix.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The layout errors of the structure-of-arrays views (`simd::Soa`) as the crate's [`Error::OutOfRange`].
impl From<LayoutError> for Error {
    fn from(e: LayoutError) -> Self {
        Error::OutOfRange {
            what: e.what,
            value: e.value,
            expected: e.expected,
        }
    }
}

/// Writes the Mueller matrices of a batch of Jones matrices into the sixteen entry slices of
/// `out`, one element per matrix.
///
/// # Formula
/// ```text
/// S1.7 with p₁ = p₂:   M_kl = ½ tr(σ_k J σ_l J†),   J = [[a, b], [c, d]]
/// with |x|² = Re² x + Im² x and x ȳ for the products of entries:
///   M_00 = ½(|a|²+|b|²+|c|²+|d|²)   M_01 = ½(|a|²−|b|²+|c|²−|d|²)   M_02 = Re(a b̄ + c d̄)   M_03 = Im(a b̄ + c d̄)
///   M_10 = ½(|a|²+|b|²−|c|²−|d|²)   M_11 = ½(|a|²−|b|²−|c|²+|d|²)   M_12 = Re(a b̄ − c d̄)   M_13 = Im(a b̄ − c d̄)
///   M_20 = Re(a c̄ + b d̄)            M_21 = Re(a c̄ − b d̄)            M_22 = Re(b c̄ + a d̄)   M_23 = Im(a d̄ − b c̄)
///   M_30 = −Im(a c̄ + b d̄)           M_31 = Im(b d̄ − a c̄)            M_32 = −Im(b c̄ + a d̄)  M_33 = Re(a d̄ − b c̄)
/// ```
/// This is [`Mueller::from_jones`](super::Mueller::from_jones) written out entry by entry.
///
/// Instruction sets: for `f32` and `f64` the CPU is detected at run time ([`pulp::Arch`], no
/// `RUSTFLAGS` needed); on x86-64 with AVX-512 (x86-64-v4) the loop handles 8 (`f64`) or 16
/// (`f32`) matrices per instruction, with AVX2 and FMA (x86-64-v3) 4 or 8, with fused
/// multiply–adds, on aarch64 it uses NEON (2 / 4 lanes), elsewhere (and for other [`Real`]
/// types) it is a portable loop. A remainder shorter than the SIMD width goes through
/// masked loads and stores. No heap allocation.
///
/// Accuracy: the fused multiply–adds round once instead of twice, so entries can differ from
/// `Mueller::from_jones` by a few ulps of the matrix scale `N = ½‖J‖²_F` (each entry is within
/// `2 ε N` of the exact value either way, so the two agree to `4 ε N`; tested); results are the
/// same from call to call on one machine, but can differ in the last bits between machines with
/// and without FMA.
///
/// Speed: the loop streams 24 slices. Keep their start addresses from agreeing modulo 4 KiB
/// (that maps them all to one set of the L1 cache): lay a batch out with
/// [`JonesSoa::from_strided`] / [`MuellerSoa::from_strided`] and [`padded_stride`].
///
/// # Errors
/// [`Error::OutOfRange`] when the 8 input and 16 output slices do not all have the same length
/// (`value` is the length of `j.re[0]`).
///
/// # Examples
/// ```
/// use gmueller::jones::JonesMatrix;
/// use gmueller::mueller::{Mueller, batch::{JonesSoa, MuellerSoa, mueller_from_jones_soa, padded_stride}};
/// // Three copies of one retarder, split into real and imaginary parts of a, b, c, d.
/// let j = JonesMatrix::<f64>::linear_retarder(0.3, 1.1).matrix();
/// let entry = |k: usize| j[(k / 2, k % 2)];
/// let re: Vec<Vec<f64>> = (0..4).map(|k| vec![entry(k).re; 3]).collect();
/// let im: Vec<Vec<f64>> = (0..4).map(|k| vec![entry(k).im; 3]).collect();
/// let soa = JonesSoa {
///     re: [&re[0], &re[1], &re[2], &re[3]],
///     im: [&im[0], &im[1], &im[2], &im[3]],
/// };
/// let mut buf = vec![0.0; 16 * padded_stride::<f64>(3)];
/// let mut out = MuellerSoa::from_strided(&mut buf, 3, padded_stride::<f64>(3)).unwrap();
/// mueller_from_jones_soa(&soa, &mut out).unwrap();
/// let single = Mueller::from_jones(&JonesMatrix::linear_retarder(0.3, 1.1)).matrix();
/// for k in 0..4 {
///     for l in 0..4 {
///         assert!((out.m[4 * k + l][2] - single[(k, l)]).abs() < 1e-15);
///     }
/// }
/// ```
pub fn mueller_from_jones_soa<T: Real>(
    j: &JonesSoa<'_, T>,
    out: &mut MuellerSoa<'_, T>,
) -> Result<(), Error> {
    let n = j.re[0].len();
    let same =
        j.re.iter().chain(j.im.iter()).all(|s| s.len() == n) && out.m.iter().all(|s| s.len() == n);
    if !same {
        return Err(Error::OutOfRange {
            what: "batch slice length",
            value: n as f64,
            expected: "8 input slices and 16 output slices of one common length",
        });
    }
    kernel_simd(j, out);
    Ok(())
}

/// The portable kernel (any [`Real`]): a plain loop over slices re-sliced to one length and bound
/// to locals, so bounds checks are hoisted and the compiler may vectorise it for the target's
/// baseline instruction set. Lengths must already be equal (checked by
/// [`mueller_from_jones_soa`]).
///
/// # Panics
/// If a slice is shorter than `j.re[0]`.
#[cfg(test)]
pub(crate) fn kernel_portable<T: Real>(j: &JonesSoa<'_, T>, out: &mut MuellerSoa<'_, T>) {
    let n = j.re[0].len();
    let [ar, br, cr, dr] = j.re.map(|s| &s[..n]);
    let [ai, bi, ci, di] = j.im.map(|s| &s[..n]);
    let [
        m00,
        m01,
        m02,
        m03,
        m10,
        m11,
        m12,
        m13,
        m20,
        m21,
        m22,
        m23,
        m30,
        m31,
        m32,
        m33,
    ] = &mut out.m;
    let (m00, m01, m02, m03) = (&mut m00[..n], &mut m01[..n], &mut m02[..n], &mut m03[..n]);
    let (m10, m11, m12, m13) = (&mut m10[..n], &mut m11[..n], &mut m12[..n], &mut m13[..n]);
    let (m20, m21, m22, m23) = (&mut m20[..n], &mut m21[..n], &mut m22[..n], &mut m23[..n]);
    let (m30, m31, m32, m33) = (&mut m30[..n], &mut m31[..n], &mut m32[..n], &mut m33[..n]);
    let half = T::lit(0.5);
    for i in 0..n {
        let (ar, ai, br, bi) = (ar[i], ai[i], br[i], bi[i]);
        let (cr, ci, dr, di) = (cr[i], ci[i], dr[i], di[i]);
        let aa = ar * ar + ai * ai;
        let bb = br * br + bi * bi;
        let cc = cr * cr + ci * ci;
        let dd = dr * dr + di * di;
        // x ȳ = (x.re y.re + x.im y.im) + i (x.im y.re − x.re y.im); `n..` = −Im.
        let (ac_r, nac_i) = (ar * cr + ai * ci, ar * ci - ai * cr);
        let (bd_r, bd_i) = (br * dr + bi * di, bi * dr - br * di);
        let (ab_r, ab_i) = (ar * br + ai * bi, ai * br - ar * bi);
        let (cd_r, cd_i) = (cr * dr + ci * di, ci * dr - cr * di);
        let (bc_r, nbc_i) = (br * cr + bi * ci, br * ci - bi * cr);
        let (ad_r, ad_i) = (ar * dr + ai * di, ai * dr - ar * di);
        let (s_ab, d_ab, s_cd, d_cd) = (aa + bb, aa - bb, cc + dd, cc - dd);
        m00[i] = half * (s_ab + s_cd);
        m01[i] = half * (d_ab + d_cd);
        m02[i] = ab_r + cd_r;
        m03[i] = ab_i + cd_i;
        m10[i] = half * (s_ab - s_cd);
        m11[i] = half * (d_ab - d_cd);
        m12[i] = ab_r - cd_r;
        m13[i] = ab_i - cd_i;
        m20[i] = ac_r + bd_r;
        m21[i] = ac_r - bd_r;
        m22[i] = bc_r + ad_r;
        m23[i] = ad_i + nbc_i;
        m30[i] = nac_i - bd_i;
        m31[i] = nac_i + bd_i;
        m32[i] = nbc_i - ad_i;
        m33[i] = ad_r - bc_r;
    }
}

/// The SIMD kernel: detects the instruction set and runs [`Kernel`]. Lengths must already be
/// equal (checked by [`mueller_from_jones_soa`]).
///
/// # Panics
/// If a slice is shorter than `j.re[0]`.
#[inline]
fn kernel_simd<F: Real>(j: &JonesSoa<'_, F>, out: &mut MuellerSoa<'_, F>) {
    crate::simd::dispatch(Kernel { j, out });
}

/// `Re(x ȳ)` of two entries given as real and imaginary vectors.
#[inline(always)]
fn re<S: Simd, F: Real>(s: S, xr: F::V<S>, xi: F::V<S>, yr: F::V<S>, yi: F::V<S>) -> F::V<S> {
    re_conj::<S, F>(s, C { re: xr, im: xi }, C { re: yr, im: yi })
}

/// `Im(x ȳ)` of two entries given as real and imaginary vectors.
#[inline(always)]
fn im<S: Simd, F: Real>(s: S, xr: F::V<S>, xi: F::V<S>, yr: F::V<S>, yi: F::V<S>) -> F::V<S> {
    im_conj::<S, F>(s, C { re: xr, im: xi }, C { re: yr, im: yi })
}

/// The closed form on one vector of matrices: inputs `[a_re, b_re, c_re, d_re, a_im, …, d_im]`,
/// outputs `M_00 … M_33` row-major (see [`mueller_from_jones_soa`]).
#[inline(always)]
fn mueller_lanes<S: Simd, F: Real>(s: S, x: [F::V<S>; 8]) -> [F::V<S>; 16] {
    let [ar, br, cr, dr, ai, bi, ci, di] = x;
    let half = F::vsplat(s, F::lit(0.5));
    let (add, sub, re, im) = (F::vadd::<S>, F::vsub::<S>, re::<S, F>, im::<S, F>);
    // |x|² = x.re² + x.im² (one fused multiply–add).
    let aa = F::vmul_add(s, ar, ar, F::vmul(s, ai, ai));
    let bb = F::vmul_add(s, br, br, F::vmul(s, bi, bi));
    let cc = F::vmul_add(s, cr, cr, F::vmul(s, ci, ci));
    let dd = F::vmul_add(s, dr, dr, F::vmul(s, di, di));
    // x ȳ = (x.re y.re + x.im y.im) + i (x.im y.re − x.re y.im); `n..` holds −Im = Im(x̄ y).
    let (ac_r, nac_i) = (re(s, ar, ai, cr, ci), im(s, cr, ci, ar, ai));
    let (bd_r, bd_i) = (re(s, br, bi, dr, di), im(s, br, bi, dr, di));
    let (ab_r, ab_i) = (re(s, ar, ai, br, bi), im(s, ar, ai, br, bi));
    let (cd_r, cd_i) = (re(s, cr, ci, dr, di), im(s, cr, ci, dr, di));
    let (bc_r, nbc_i) = (re(s, br, bi, cr, ci), im(s, cr, ci, br, bi));
    let (ad_r, ad_i) = (re(s, ar, ai, dr, di), im(s, ar, ai, dr, di));
    let (s_ab, d_ab) = (add(s, aa, bb), sub(s, aa, bb));
    let (s_cd, d_cd) = (add(s, cc, dd), sub(s, cc, dd));
    [
        F::vmul(s, half, add(s, s_ab, s_cd)),
        F::vmul(s, half, add(s, d_ab, d_cd)),
        add(s, ab_r, cd_r),
        add(s, ab_i, cd_i),
        F::vmul(s, half, sub(s, s_ab, s_cd)),
        F::vmul(s, half, sub(s, d_ab, d_cd)),
        sub(s, ab_r, cd_r),
        sub(s, ab_i, cd_i),
        add(s, ac_r, bd_r),
        sub(s, ac_r, bd_r),
        add(s, bc_r, ad_r),
        add(s, ad_i, nbc_i),
        sub(s, nac_i, bd_i),
        add(s, nac_i, bd_i),
        sub(s, nbc_i, ad_i),
        sub(s, ad_r, bc_r),
    ]
}

/// The SIMD loop, instantiated by [`pulp::Arch::dispatch`] once per instruction set.
struct Kernel<'r, 'j, 'o, F> {
    j: &'r JonesSoa<'j, F>,
    out: &'r mut MuellerSoa<'o, F>,
}

/// [`mueller_lanes`] as the driver's per-lane map (8 inputs, 16 outputs).
struct MuellerLanes;

impl<F: Real> LaneMap<F, 8, 16> for MuellerLanes {
    #[inline(always)]
    fn eval<S: Simd>(&self, s: S, x: [F::V<S>; 8]) -> [F::V<S>; 16] {
        mueller_lanes::<S, F>(s, x)
    }
}

impl<F: Real> WithSimd for Kernel<'_, '_, '_, F> {
    type Output = ();

    // `inline(always)`: the body must be compiled inside pulp's `#[target_feature]` function.
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) {
        let Self { j, out } = self;
        let n = j.re[0].len();
        let inputs = [
            j.re[0], j.re[1], j.re[2], j.re[3], j.im[0], j.im[1], j.im[2], j.im[3],
        ];
        // The whole vectors, the inputs bound to locals re-sliced to `nv` (no bounds checks).
        let mut heads: [&[F::V<S>]; 8] = [&[]; 8];
        for k in 0..8 {
            heads[k] = F::vsplit::<S>(&inputs[k][..n]).0;
        }
        let nv = heads[0].len();
        let [h0, h1, h2, h3, h4, h5, h6, h7] = heads;
        let (h0, h1, h2, h3) = (&h0[..nv], &h1[..nv], &h2[..nv], &h3[..nv]);
        let (h4, h5, h6, h7) = (&h4[..nv], &h5[..nv], &h6[..nv], &h7[..nv]);
        {
            let mut out_heads: [&mut [F::V<S>]; 16] = Default::default();
            for (k, o) in out.m.iter_mut().enumerate() {
                out_heads[k] = F::vsplit_mut::<S>(&mut o[..n]).0;
            }
            for i in 0..nv {
                let x = [h0[i], h1[i], h2[i], h3[i], h4[i], h5[i], h6[i], h7[i]];
                let m = mueller_lanes::<S, F>(s, x);
                for k in 0..16 {
                    out_heads[k][i] = m[k];
                }
            }
        }
        driver::remainder::<S, F, MuellerLanes, 8, 16>(s, &MuellerLanes, inputs, &mut out.m, n, nv);
    }
}

#[cfg(test)]
mod tests {
    //! Every instantiation of the SIMD loop (pulp's scalar back-ends of 1, 2, 4 and 8 `f64`
    //! lanes, which exercise the remainder logic at every width, and AVX2 + FMA and AVX-512
    //! when the CPU has them) against the portable loop, on seeded inputs of lengths 0–41. The scalar back-end
    //! rounds like the portable loop and must agree bit for bit; the others within `4 ε N`
    //! (`N = ½‖J‖²_F`, see `tests/mueller/batch.rs`).
    use super::*;

    fn inputs<F: Real>(n: usize, seed: u64) -> Vec<Vec<F>> {
        let mut x = seed;
        (0..8)
            .map(|_| {
                (0..n)
                    .map(|_| {
                        x = x
                            .wrapping_mul(6364136223846793005)
                            .wrapping_add(1442695040888963407);
                        F::lit((x >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0)
                    })
                    .collect()
            })
            .collect()
    }

    fn run<F: Real>(
        v: &[Vec<F>],
        op: impl FnOnce(&JonesSoa<'_, F>, &mut MuellerSoa<'_, F>),
    ) -> Vec<Vec<F>> {
        let n = v[0].len();
        let j = JonesSoa {
            re: [&v[0][..], &v[1], &v[2], &v[3]],
            im: [&v[4][..], &v[5], &v[6], &v[7]],
        };
        let mut buf = vec![F::lit(f64::NAN); 16 * n];
        let mut out = MuellerSoa::from_strided(&mut buf, n, n).unwrap();
        op(&j, &mut out);
        out.m.iter().map(|s| s.to_vec()).collect()
    }

    fn check<F: Real>() {
        for n in 0..42 {
            let v = inputs::<F>(n, 7 + n as u64);
            let reference = run(&v, kernel_portable);
            let scale: Vec<f64> = (0..n)
                .map(|i| 0.5 * v.iter().map(|s| s[i].to_f64().powi(2)).sum::<f64>())
                .collect();
            let close = |what: &str, got: &[Vec<F>]| {
                for k in 0..16 {
                    for i in 0..n {
                        let d = (got[k][i].to_f64() - reference[k][i].to_f64()).abs();
                        let bound = 4.0 * F::EPSILON.to_f64() * scale[i];
                        assert!(
                            d <= bound,
                            "{what}: n {n}, entry {k}, matrix {i}: {d:e} > {bound:e}"
                        );
                    }
                }
            };
            let scalar = run(&v, |j, out| Kernel { j, out }.with_simd(pulp::Scalar));
            assert_eq!(scalar, reference, "pulp::Scalar, n {n}");
            close(
                "Scalar128b",
                &run(&v, |j, out| Kernel { j, out }.with_simd(pulp::Scalar128b)),
            );
            close(
                "Scalar256b",
                &run(&v, |j, out| Kernel { j, out }.with_simd(pulp::Scalar256b)),
            );
            close(
                "Scalar512b",
                &run(&v, |j, out| Kernel { j, out }.with_simd(pulp::Scalar512b)),
            );
            close("dispatched", &run(&v, kernel_simd));
            #[cfg(target_arch = "x86_64")]
            if let Some(v3) = pulp::x86::V3::try_new() {
                close(
                    "V3",
                    &run(&v, |j, out| Simd::vectorize(v3, Kernel { j, out })),
                );
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(v4) = pulp::x86::V4::try_new() {
                close(
                    "V4",
                    &run(&v, |j, out| Simd::vectorize(v4, Kernel { j, out })),
                );
            }
        }
    }

    #[test]
    fn every_back_end_matches_the_portable_loop_f64() {
        check::<f64>();
    }

    #[test]
    fn every_back_end_matches_the_portable_loop_f32() {
        check::<f32>();
    }
}
