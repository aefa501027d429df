//! Test support for the vector functions: a per-lane map run over a slice on several back-ends
//! (the dispatched one, pulp's one-lane `Scalar` and four-lane `Scalar256b`, AVX2 + FMA when
//! present), and ulp distances against the standard library.

use pulp::{Simd, WithSimd};

use super::Lanes;
use super::driver::LaneMap;

/// `f32` and `f64` as the tests need them: the standard library's functions and an ordered
/// integer image of the bit pattern (adjacent floats differ by 1, `−0` and `+0` coincide).
pub(crate) trait Float: Lanes + Copy + PartialOrd + core::fmt::LowerExp {
    /// The ulp of 1.
    const EPS: f64;
    fn of(x: f64) -> Self;
    fn f64(self) -> f64;
    fn ord(self) -> i64;
    fn std_ln(self) -> Self;
    fn std_sin_cos(self) -> (Self, Self);
}

impl Float for f64 {
    const EPS: f64 = f64::EPSILON;
    fn of(x: f64) -> Self {
        x
    }
    fn f64(self) -> f64 {
        self
    }
    fn ord(self) -> i64 {
        let i = self.to_bits() as i64;
        if i < 0 { i64::MIN - i } else { i }
    }
    fn std_ln(self) -> Self {
        self.ln()
    }
    fn std_sin_cos(self) -> (Self, Self) {
        self.sin_cos()
    }
}

impl Float for f32 {
    const EPS: f64 = f32::EPSILON as f64;
    fn of(x: f64) -> Self {
        x as f32
    }
    fn f64(self) -> f64 {
        f64::from(self)
    }
    fn ord(self) -> i64 {
        let i = i64::from(self.to_bits() as i32);
        if i < 0 { i64::from(i32::MIN) - i } else { i }
    }
    fn std_ln(self) -> Self {
        self.ln()
    }
    fn std_sin_cos(self) -> (Self, Self) {
        self.sin_cos()
    }
}

/// The number of floats of `a`'s type from `a` to `b`: their distance in ulps (both finite).
pub(crate) fn ulps<F: Float>(a: F, b: F) -> u64 {
    a.ord().abs_diff(b.ord())
}

/// `M` on every element of `xs` into `out[0..L]`, one vector at a time (partial loads and
/// stores for the remainder).
struct MapAll<'a, F, M, const L: usize> {
    m: &'a M,
    xs: &'a [F],
    out: &'a mut [Vec<F>; L],
}

impl<F: Lanes, M: LaneMap<F, 1, L>, const L: usize> WithSimd for MapAll<'_, F, M, L> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) {
        let lanes = F::width::<S>();
        for (i, x) in self.xs.chunks(lanes).enumerate() {
            let v = self.m.eval(s, [F::load_partial(s, x)]);
            for (o, v) in self.out.iter_mut().zip(v) {
                F::store_partial(s, &mut o[i * lanes..(i * lanes + x.len())], v);
            }
        }
    }
}

/// `m` over `xs` on each back-end; `check(back-end, outputs)` after each.
pub(crate) fn on_back_ends<F: Float, M: LaneMap<F, 1, L>, const L: usize>(
    m: &M,
    xs: &[F],
    mut check: impl FnMut(&str, &[Vec<F>; L]),
) {
    let mut out: [Vec<F>; L] = core::array::from_fn(|_| vec![F::of(0.0); xs.len()]);
    super::dispatch(MapAll {
        m,
        xs,
        out: &mut out,
    });
    check("dispatch", &out);
    MapAll {
        m,
        xs,
        out: &mut out,
    }
    .with_simd(pulp::Scalar);
    check("Scalar", &out);
    MapAll {
        m,
        xs,
        out: &mut out,
    }
    .with_simd(pulp::Scalar256b);
    check("Scalar256b", &out);
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = pulp::x86::V3::try_new() {
        Simd::vectorize(
            v3,
            MapAll {
                m,
                xs,
                out: &mut out,
            },
        );
        check("V3", &out);
    }
}

/// The worst case of a sweep: `(ulps, input, result, reference)`.
pub(crate) type Worst<F> = (u64, F, F, F);

/// Keeps the larger of `worst` and `(u, x, got, want)`.
pub(crate) fn track<F: Float>(worst: &mut Worst<F>, u: u64, x: F, got: F, want: F) {
    if u > worst.0 {
        *worst = (u, x, got, want);
    }
}
