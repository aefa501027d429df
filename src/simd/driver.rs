//! The per-lane map of a batch kernel ([`LaneMap`], `K` input slices to `L` output slices) and
//! the remainder shared by the batch kernels, after each kernel's own loop over whole vectors
//! of a [`pulp::Simd`] back-end.

use pulp::Simd;

use super::Lanes;

/// A per-lane computation of `L` outputs from `K` inputs. `eval` must be `#[inline(always)]`:
/// it is compiled inside pulp's `#[target_feature]` function only when it is inlined there.
pub(crate) trait LaneMap<F: Lanes, const K: usize, const L: usize> {
    /// The outputs of one vector of elements.
    fn eval<S: Simd>(&self, s: S, x: [F::V<S>; K]) -> [F::V<S>; L];
}

/// The remainder of a batch after the caller's loop over its `nv` whole vectors: with at least
/// one whole vector, the last whole vector of the batch `n − lanes .. n` again (the elements it
/// shares with the loop get the same values again, and no masked store is needed — those are
/// slow on AMD processors); shorter batches go through masked loads and stores (the unused
/// lanes compute on zeros and are discarded). Nothing to do when `nv · lanes = n`.
///
/// The whole vectors are the caller's loop, over input and output slices bound to locals and
/// re-sliced to `nv` vectors (so that no bounds check is left in it): a generic loop over arrays
/// of `K` and `L` slices here measured 20–50 % slower on the Jones → Mueller batch. The
/// outputs come by reference (`&mut out.m`), not as a fresh array of reborrows: building one
/// with `each_mut().map(..)` compiled to an out-of-line `array::try_map` call and 16 slices
/// spilled to the stack, about 190 instructions per call (a third more at `n = 7`).
///
/// # Panics
/// If a slice is shorter than `n`.
#[inline(always)]
pub(crate) fn remainder<S: Simd, F: Lanes, M: LaneMap<F, K, L>, const K: usize, const L: usize>(
    s: S,
    f: &M,
    inputs: [&[F]; K],
    outputs: &mut [&mut [F]; L],
    n: usize,
    nv: usize,
) {
    let lanes = F::width::<S>();
    if nv * lanes == n {
        return;
    }
    let start = if nv > 0 { n - lanes } else { 0 };
    let mut x = [F::vlit(s, 0.0); K];
    for k in 0..K {
        let t = &inputs[k][start..n];
        x[k] = if nv > 0 {
            F::vsplit::<S>(t).0[0]
        } else {
            F::load_partial(s, t)
        };
    }
    let m = f.eval(s, x);
    for (o, mk) in outputs.iter_mut().zip(m) {
        let t = &mut o[start..n];
        if nv > 0 {
            F::vsplit_mut::<S>(t).0[0] = mk;
        } else {
            F::store_partial(s, t, mk);
        }
    }
}
