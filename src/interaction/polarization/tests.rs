//! [`super::scatter_weight_forms`] against the two trait methods it stands for.

use nalgebra::{Matrix2, Vector3};

use super::scatter_weight_forms;
use crate::frame::Frame;
use crate::gaussian::Gaussian;
use crate::interaction::coherence::{CoherenceWeights, Incoherent, Partial};
use crate::interaction::geometry::Geometry;
use crate::interaction::roughness::{FirstOrder, RoughnessWeights};
use crate::numerics::{same, splitmix64};
use crate::psd::{ClosedForm, GaussianMixturePsd, GaussianPsd, Psd};
use crate::real::Real;

/// A uniform number in `[0, 1)`.
fn uniform(state: &mut u64) -> f64 {
    (splitmix64(state) >> 11) as f64 / (1u64 << 53) as f64
}

/// A direction in the upper (`up`) or lower hemisphere, `cos θ` in `[0.02, 1)`.
fn direction(state: &mut u64, up: bool) -> Vector3<f64> {
    let z = 0.02 + 0.98 * uniform(state);
    let phi = core::f64::consts::TAU * uniform(state);
    let r = (1.0 - z * z).sqrt();
    Vector3::new(r * phi.cos(), r * phi.sin(), if up { z } else { -z })
}

/// An anisotropic section `Ξ` (rad²/µm²) of coherence widths 10⁻¹–10⁵ µm, at most 10:1.
fn section<T: Real>(state: &mut u64) -> Gaussian<T, 2> {
    let a = 10f64.powf(-1.0 + 5.0 * uniform(state));
    let b = a * 10f64.powf(uniform(state));
    let t = core::f64::consts::PI * uniform(state);
    let (c, s) = (t.cos(), t.sin());
    let (ia, ib) = (1.0 / (a * a), 1.0 / (b * b));
    let m = Matrix2::new(
        c * c * ia + s * s * ib,
        c * s * (ia - ib),
        c * s * (ia - ib),
        s * s * ia + c * c * ib,
    );
    Gaussian::new(m.map(T::lit)).unwrap()
}

/// `scatter_weight_forms` and the trait methods over random geometries, sections and PSDs:
/// `(linear, log)` must be the trait methods' values bit for bit. Returns how many cases
/// returned the logarithm and how many did not.
fn agreement<T: Real, P: Psd<T, 2>, Coh: CoherenceWeights<T, P>>(
    psds: &[P],
    coherence: &Coh,
    seed: u64,
) -> (usize, usize) {
    let mut state = seed;
    let surface = Frame::<T>::from_normal(Vector3::z()).unwrap();
    let (mut with_log, mut without) = (0, 0);
    for i in 0..4000 {
        let psd = &psds[i % psds.len()];
        let lambda = 0.3 + 1.7 * uniform(&mut state);
        let k = T::lit(core::f64::consts::TAU / lambda);
        let to_source = direction(&mut state, true).map(T::lit);
        let g = if i % 3 == 0 {
            let exit = direction(&mut state, false).map(T::lit);
            Geometry::at_interface(k, &surface, T::lit(1.5), to_source, exit)
        } else {
            Geometry::new(
                k,
                &surface,
                to_source,
                direction(&mut state, true).map(T::lit),
            )
        }
        .unwrap();
        let xi = (i % 7 != 0).then(|| section::<T>(&mut state));
        let (linear, log) = scatter_weight_forms(coherence, &FirstOrder, psd, xi.as_ref(), &g);
        let want = FirstOrder.scatter_weight(coherence, psd, xi.as_ref(), &g);
        assert!(same(linear, want), "case {i}: {linear:?} vs {want:?}");
        match log {
            Some(l) => {
                let want = FirstOrder.log_scatter_weight(coherence, psd, xi.as_ref(), &g);
                assert!(same(l, want), "case {i}: ln {l:?} vs {want:?}");
                with_log += 1;
            }
            None => without += 1,
        }
    }
    (with_log, without)
}

fn run<T: Real>() {
    let gaussians: Vec<GaussianPsd<T, 2>> = [(0.002, 0.5), (0.02, 2.0), (0.2, 10.0)]
        .iter()
        .map(|&(s, l)| GaussianPsd::isotropic(T::lit(s), T::lit(l)).unwrap())
        .collect();
    let (with_log, without) = agreement(&gaussians, &Partial(ClosedForm), 7);
    // Both forms occur: the far tails return the logarithm, the lobes the linear form.
    assert!(
        with_log > 400 && without > 400,
        "{with_log} with ln, {without} without"
    );
    // The other weights never return it.
    let mixture = vec![GaussianMixturePsd::new(gaussians.clone()).unwrap()];
    assert_eq!(agreement(&mixture, &Partial(ClosedForm), 8).0, 0);
    assert_eq!(agreement(&gaussians, &Incoherent, 9).0, 0);
}

#[test]
fn the_forms_are_the_trait_methods_bit_for_bit() {
    run::<f64>();
    run::<f32>();
}
