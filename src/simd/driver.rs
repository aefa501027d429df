//! The chunk loop shared by the batch kernels: whole vectors of a [`pulp::Simd`] back-end, then
//! the remainder, mapping `K` input slices to `L` output slices through a [`LaneMap`].

use pulp::Simd;

use super::Lanes;

/// A per-lane computation of `L` outputs from `K` inputs. `eval` must be `#[inline(always)]`:
/// it is compiled inside pulp's `#[target_feature]` function only when it is inlined there.
pub(crate) trait LaneMap<F: Lanes, const K: usize, const L: usize> {
    /// The outputs of one vector of elements.
    fn eval<S: Simd>(&self, s: S, x: [F::V<S>; K]) -> [F::V<S>; L];
}

/// Runs `f` over the first `n` elements of every input and output slice (each at least `n`
/// long): whole vectors first; then, with at least one whole vector, the last whole vector of
/// the batch `n − lanes .. n` again (the elements it shares with the loop get the same values
/// again, and no masked store is needed — those are slow on AMD processors); shorter batches
/// go through masked loads and stores (the unused lanes compute on zeros and are discarded).
///
/// # Panics
/// If a slice is shorter than `n`.
#[inline(always)]
pub(crate) fn map<S: Simd, F: Lanes, M: LaneMap<F, K, L>, const K: usize, const L: usize>(
    s: S,
    f: &M,
    inputs: [&[F]; K],
    outputs: &mut [&mut [F]; L],
    n: usize,
) {
    let lanes = F::width::<S>();
    let nv = n / lanes;
    let zero = F::vlit(s, 0.0);
    {
        let mut heads: [&[F::V<S>]; K] = [&[]; K];
        for k in 0..K {
            heads[k] = &F::vsplit::<S>(&inputs[k][..n]).0[..nv];
        }
        let mut out_heads: [&mut [F::V<S>]; L] = core::array::from_fn(|_| Default::default());
        for (h, o) in out_heads.iter_mut().zip(outputs.iter_mut()) {
            *h = &mut F::vsplit_mut::<S>(&mut o[..n]).0[..nv];
        }
        for i in 0..nv {
            let mut x = [zero; K];
            for k in 0..K {
                x[k] = heads[k][i];
            }
            let m = f.eval(s, x);
            for k in 0..L {
                out_heads[k][i] = m[k];
            }
        }
    }
    if nv * lanes == n {
        return;
    }
    let start = if nv > 0 { n - lanes } else { 0 };
    let mut x = [zero; K];
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
