//! A structure-of-arrays batch path for Jones → Mueller: the same closed form as
//! [`Mueller::from_jones`](super::Mueller::from_jones), over slices, laid out so the compiler can
//! vectorise the loop.

use crate::error::Error;
use crate::real::Real;

/// A batch of Jones matrices `[[a, b], [c, d]]` as eight slices of equal length (real and
/// imaginary parts of `a, b, c, d`, row-major).
#[derive(Debug, Clone, Copy)]
pub struct JonesSoa<'a, T> {
    /// Real parts of `a, b, c, d`.
    pub re: [&'a [T]; 4],
    /// Imaginary parts of `a, b, c, d`.
    pub im: [&'a [T]; 4],
}

/// Writes the Mueller matrices of a batch of Jones matrices into 16 output slices (row-major
/// entries `M_00, M_01, …, M_33`), one element per matrix.
///
/// # Formula
/// ```text
/// M_kl = ½ tr(σ_k J σ_l J†)          (S1.7 with p₁ = p₂; see Mueller::from_jones)
/// ```
///
/// # Errors
/// [`Error::OutOfRange`] when the 24 slices do not all have the same length.
///
/// # Examples
/// ```
/// use gmueller::jones::JonesMatrix;
/// use gmueller::mueller::{Mueller, batch::{JonesSoa, mueller_from_jones_soa}};
/// let j = JonesMatrix::<f64>::linear_retarder(0.3, 1.1).matrix();
/// let (re, im): (Vec<f64>, Vec<f64>) = j.transpose().iter().map(|z| (z.re, z.im)).unzip();
/// let col = |v: &Vec<f64>, i: usize| vec![v[i]; 3];
/// let (r, m) = ((0..4).map(|i| col(&re, i)).collect::<Vec<_>>(), (0..4).map(|i| col(&im, i)).collect::<Vec<_>>());
/// let soa = JonesSoa { re: [&r[0], &r[1], &r[2], &r[3]], im: [&m[0], &m[1], &m[2], &m[3]] };
/// let mut out = vec![vec![0.0; 3]; 16];
/// let mut slices: Vec<&mut [f64]> = out.iter_mut().map(|v| v.as_mut_slice()).collect();
/// mueller_from_jones_soa(&soa, &mut slices).unwrap();
/// let single = Mueller::from_jones(&JonesMatrix::linear_retarder(0.3, 1.1)).matrix();
/// assert!((out[5][2] - single[(1, 1)]).abs() < 1e-15);
/// ```
pub fn mueller_from_jones_soa<T: Real>(
    j: &JonesSoa<'_, T>,
    out: &mut [&mut [T]],
) -> Result<(), Error> {
    let n = j.re[0].len();
    let same = j.re.iter().chain(j.im.iter()).all(|s| s.len() == n)
        && out.len() == 16
        && out.iter().all(|s| s.len() == n);
    if !same {
        return Err(Error::OutOfRange {
            what: "batch slice length",
            value: n as f64,
            expected: "8 input slices and 16 output slices of one common length",
        });
    }
    let half = T::lit(0.5);
    let (ar, br, cr, dr) = (&j.re[0][..n], &j.re[1][..n], &j.re[2][..n], &j.re[3][..n]);
    let (ai, bi, ci, di) = (&j.im[0][..n], &j.im[1][..n], &j.im[2][..n], &j.im[3][..n]);
    let mut m = [T::zero(); 16];
    for i in 0..n {
        let (a, b, c, d) = (
            (ar[i], ai[i]),
            (br[i], bi[i]),
            (cr[i], ci[i]),
            (dr[i], di[i]),
        );
        let aa = a.0 * a.0 + a.1 * a.1;
        let bb = b.0 * b.0 + b.1 * b.1;
        let cc = c.0 * c.0 + c.1 * c.1;
        let dd = d.0 * d.0 + d.1 * d.1;
        // x ȳ = (x.re y.re + x.im y.im, x.im y.re − x.re y.im)
        let mulc = |x: (T, T), y: (T, T)| (x.0 * y.0 + x.1 * y.1, x.1 * y.0 - x.0 * y.1);
        let (ac, bd, ab, cd, bc, ad) = (
            mulc(a, c),
            mulc(b, d),
            mulc(a, b),
            mulc(c, d),
            mulc(b, c),
            mulc(a, d),
        );
        let h11 = [aa + bb, aa - bb, ab.0 + ab.0, ab.1 + ab.1];
        let h22 = [cc + dd, cc - dd, cd.0 + cd.0, cd.1 + cd.1];
        // H12 for l = 0..3; l = 3 is i (b c̄ − a d̄).
        let h12 = [
            (ac.0 + bd.0, ac.1 + bd.1),
            (ac.0 - bd.0, ac.1 - bd.1),
            (bc.0 + ad.0, bc.1 + ad.1),
            (-(bc.1 - ad.1), bc.0 - ad.0),
        ];
        for l in 0..4 {
            m[l] = half * (h11[l] + h22[l]);
            m[4 + l] = half * (h11[l] - h22[l]);
            m[8 + l] = h12[l].0;
            m[12 + l] = -h12[l].1;
        }
        for (o, v) in out.iter_mut().zip(m.iter()) {
            o[i] = *v;
        }
    }
    Ok(())
}
