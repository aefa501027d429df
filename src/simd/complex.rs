//! Complex numbers in lanes: a pair of vectors and `num_complex`'s operations on them, in its
//! order and without fused multiply–adds (so lane results round as the scalar ones), plus the
//! fused conjugate products of the Mueller closed form.

use num_complex::Complex;
use pulp::Simd;

use super::Lanes;

/// A complex number as two vectors.
#[derive(Clone, Copy)]
pub(crate) struct C<V> {
    pub(crate) re: V,
    pub(crate) im: V,
}

/// Complex arithmetic on vectors of back-end `S`, with `num_complex`'s operations in its order
/// and without fused multiply–adds.
#[derive(Clone, Copy)]
pub(crate) struct Cx<S>(pub(crate) S);

impl<S: Simd> Cx<S> {
    /// `z` on every lane.
    #[inline(always)]
    pub(crate) fn splat<F: Lanes>(self, z: Complex<F>) -> C<F::V<S>> {
        C {
            re: F::vsplat(self.0, z.re),
            im: F::vsplat(self.0, z.im),
        }
    }
    /// `(a.re b.re − a.im b.im) + i (a.re b.im + a.im b.re)`.
    #[inline(always)]
    pub(crate) fn mul<F: Lanes>(self, a: C<F::V<S>>, b: C<F::V<S>>) -> C<F::V<S>> {
        let s = self.0;
        C {
            re: F::vsub(s, F::vmul(s, a.re, b.re), F::vmul(s, a.im, b.im)),
            im: F::vadd(s, F::vmul(s, a.re, b.im), F::vmul(s, a.im, b.re)),
        }
    }
    /// `z · t` for real `t`.
    #[inline(always)]
    pub(crate) fn scale<F: Lanes>(self, z: C<F::V<S>>, t: F::V<S>) -> C<F::V<S>> {
        C {
            re: F::vmul(self.0, z.re, t),
            im: F::vmul(self.0, z.im, t),
        }
    }
    /// `1/z = z̄/|z|²` with one division. The imaginary part is `−(Im z · inv)`, exactly the
    /// scalar's `−Im z · inv` including the sign of a zero (`0 − Im z` turned `+0` into `+0`
    /// where the scalar has `−0`): `−0 − Im z · inv`, one rounding fused or not.
    #[inline(always)]
    pub(crate) fn recip<F: Lanes>(self, z: C<F::V<S>>) -> C<F::V<S>> {
        let s = self.0;
        let n2 = F::vadd(s, F::vmul(s, z.re, z.re), F::vmul(s, z.im, z.im));
        let inv = F::vdiv(s, F::vlit(s, 1.0), n2);
        C {
            re: F::vmul(s, z.re, inv),
            im: F::vneg_mul_add(s, z.im, inv, F::vlit(s, -0.0)),
        }
    }
}

/// `Re(x ȳ) = x.re y.re + x.im y.im` (one fused multiply–add).
#[inline(always)]
pub(crate) fn re_conj<S: Simd, F: Lanes>(s: S, x: C<F::V<S>>, y: C<F::V<S>>) -> F::V<S> {
    F::vmul_add(s, x.re, y.re, F::vmul(s, x.im, y.im))
}

/// `Im(x ȳ) = x.im y.re − x.re y.im` (one fused multiply–add).
#[inline(always)]
pub(crate) fn im_conj<S: Simd, F: Lanes>(s: S, x: C<F::V<S>>, y: C<F::V<S>>) -> F::V<S> {
    F::vneg_mul_add(s, x.re, y.im, F::vmul(s, x.im, y.re))
}
