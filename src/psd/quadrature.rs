//! Quadrature blur methods for PSDs without a closed form: Gauss–Hermite and adaptive.

use nalgebra::{DMatrix, SMatrix, SVector};

use super::{BlurMethod, Psd};
use crate::error::Error;
use crate::gaussian::Gaussian;
use crate::real::Real;

/// Tensor-product Gauss–Hermite quadrature of a fixed order, for any [`Psd`].
///
/// # Formula
/// ```text
/// (p * g^Σ)(h) = |Σ|^{1/2} E_{u∼𝒩(0,I)}[p(h − L u)] ≈ |Σ|^{1/2} Σ_{i₁…i_N} w_{i₁}⋯w_{i_N} p(h − L u_i)
/// ```
/// with the probabilists' Gauss–Hermite nodes `uᵢ` and weights `wᵢ` (weight `e^{−u²/2}/√(2π)`),
/// computed once at construction by Golub–Welsch (eigen-decomposition of the Jacobi matrix with
/// off-diagonal `√k`). `orderᴺ` PSD evaluations per blur.
///
/// # Error bound
/// Exact when `p(h − L u)` is a polynomial of degree ≤ `2·order − 1` in each `u_d`. For `p`
/// analytic in a strip of half-width `δ` around the real axis (in `u`), the error decays like
/// `exp(−c δ √order)`; for the K-correlation `δ ≈ 1/(√T · ‖L‖)`. It is therefore accurate when the
/// blur is narrow compared with the PSD's correlation scale (high coherence), and slow when it is
/// wide — there, use the mixture fit. No a-priori guarantee for other PSDs; see the accuracy sweep
/// in `tests/psd/models.rs` for measured errors.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussHermite<T: Real> {
    nodes: Vec<T>,
    weights: Vec<T>,
}

impl<T: Real> GaussHermite<T> {
    /// Nodes and weights of the given order (`1 ≤ order ≤ 256`).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for an order outside `[1, 256]`.
    pub fn new(order: usize) -> Result<Self, Error> {
        if !(1..=256).contains(&order) {
            return Err(Error::OutOfRange {
                what: "Gauss–Hermite order",
                value: order as f64,
                expected: "[1, 256]",
            });
        }
        let jac = DMatrix::<f64>::from_fn(order, order, |i, j| {
            if i + 1 == j || j + 1 == i {
                (i.max(j) as f64).sqrt()
            } else {
                0.0
            }
        });
        let eig = jac.symmetric_eigen();
        let mut pairs: Vec<(f64, f64)> = (0..order)
            .map(|i| (eig.eigenvalues[i], eig.eigenvectors[(0, i)].powi(2)))
            .collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let total: f64 = pairs.iter().map(|p| p.1).sum();
        Ok(Self {
            nodes: pairs.iter().map(|p| T::lit(p.0)).collect(),
            weights: pairs.iter().map(|p| T::lit(p.1 / total)).collect(),
        })
    }

    /// The order (nodes per dimension).
    #[must_use]
    pub fn order(&self) -> usize {
        self.nodes.len()
    }

    /// Nodes (ascending) and probability weights (summing to 1).
    #[must_use]
    pub fn nodes_weights(&self) -> (&[T], &[T]) {
        (&self.nodes, &self.weights)
    }
}

impl<T: Real, const N: usize, P: Psd<T, N> + ?Sized> BlurMethod<T, N, P> for GaussHermite<T> {
    fn blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.normalized_blur(psd, cov, h) * (T::lit(0.5) * cov.log_det()).exp()
    }

    /// `E[p(h − L u)]` by the tensor rule, without the `|Σ|^{1/2}` factor.
    fn normalized_blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        let l = cov.cholesky_factor();
        let n = self.nodes.len();
        let mut idx = [0usize; N];
        let mut sum = T::zero();
        loop {
            let mut u = SVector::<T, N>::zeros();
            let mut w = T::one();
            for d in 0..N {
                u[d] = self.nodes[idx[d]];
                w *= self.weights[idx[d]];
            }
            sum += w * psd.value(&(h - l * u));
            let mut d = 0;
            loop {
                if d == N {
                    return sum;
                }
                idx[d] += 1;
                if idx[d] < n {
                    break;
                }
                idx[d] = 0;
                d += 1;
            }
        }
    }
}

/// The adaptive reference: nested adaptive Gauss–Kronrod (G7–K15) to a relative tolerance.
///
/// # Formula
/// ```text
/// (p * g^Σ)(h) = |Σ|^{1/2} ∫_{ℝᴺ} p(h − L u) Πᵈ φ(u_d) dᴺu,     φ(x) = e^{−x²/2}/√(2π)
/// ```
/// integrated one coordinate at a time (`u_N` innermost). Each coordinate runs over
/// `[−R, R]`, `R = √(2 ln(10/tol)) + ½`, plus the PSD's peak neighbourhood if it lies outside
/// (within 40 of R), with a breakpoint where the line meets the PSD's peak ([`Psd::peak`]) and
/// panels graded geometrically (×4) from the PSD's feature width ([`Psd::feature_width`]) around
/// it, then global bisection of the worst panel (QUADPACK QAG style, up to 500 panels
/// per level, on the stack) until the summed Kronrod–Gauss differences `Σ|K15 − G7|` are below
/// `tol/2 · |total|`; panels whose difference is below twice the noise of the inner integrations
/// (inner levels use `tol/8`) count as converged. As the integrand is positive, inner relative
/// errors add to the outer one: `tol/2 + tol/4 + tol/8 < tol`.
///
/// # Error bound
/// The target is a relative error `tol`; `|K15 − G7|` over-estimates the K15 error for smooth
/// integrands, so the achieved error is usually far below `tol` (down to ~1e-13 in f64). Not
/// guaranteed once 500 panels per level or the budget of 5·10⁷ PSD evaluations per blur are spent
/// (refinement then stops).
/// Slow (10⁴–10⁶ PSD evaluations in 2-D; the cube of the 1-D count in 3-D); meant as the
/// reference, not for rendering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adaptive<T: Real> {
    tol: T,
}

impl<T: Real> Adaptive<T> {
    /// Relative tolerance `tol ∈ [10·ε, 0.5]`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] otherwise.
    pub fn new(tol: T) -> Result<Self, Error> {
        if !(tol >= T::EPSILON * T::lit(10.0) && tol <= T::lit(0.5)) {
            return Err(Error::OutOfRange {
                what: "adaptive tolerance",
                value: tol.to_f64(),
                expected: "[10ε, 0.5]",
            });
        }
        Ok(Self { tol })
    }

    /// The relative tolerance.
    #[must_use]
    pub fn tolerance(&self) -> T {
        self.tol
    }
}

// QUADPACK qk15: Kronrod nodes (descending, last is 0), Kronrod and Gauss weights.
const XGK: [f64; 8] = [
    0.991455371120812639206854697526329,
    0.949107912342758524526189684047851,
    0.864864423359769072789712788640926,
    0.741531185599394439863864773280788,
    0.586087235467691130294144845693013,
    0.405845151377397166906606412076961,
    0.207784955007898467600689403773245,
    0.0,
];
const WGK: [f64; 8] = [
    0.022935322010529224963732008058970,
    0.063092092629978553290700663189204,
    0.104790010322250183839876322541518,
    0.140653259715525918745189590510238,
    0.169004726639267902826583426598550,
    0.190350578064785409913256402421014,
    0.204432940075298892414161999234649,
    0.209482141084727828012999174891714,
];
const WG: [f64; 4] = [
    0.129484966168869693270611432679082,
    0.279705391489276667901467771423780,
    0.381830050505118944950369775488975,
    0.417959183673469387755102040816327,
];
/// Capacity of the per-level panel list.
const PANELS: usize = 500;
/// Budget of PSD evaluations per blur: refinement stops (and the result may miss `tol`) beyond it.
const MAX_EVALS: u64 = 50_000_000;

struct Nested<'a, T: Real, const N: usize, P: ?Sized> {
    psd: &'a P,
    l: SMatrix<T, N, N>,
    h: SVector<T, N>,
    peak: SVector<T, N>,
    r: T,
    feature_width: T,
    /// PSD evaluations so far (refinement stops past [`MAX_EVALS`]).
    evals: core::cell::Cell<u64>,
}

impl<T: Real, const N: usize, P: Psd<T, N> + ?Sized> Nested<'_, T, N, P> {
    fn integrand(&self, d: usize, x: T, u: &mut SVector<T, N>, tol: T) -> T {
        u[d] = x;
        let w = (-T::lit(0.5) * x * x).exp() * T::lit(1.0 / core::f64::consts::TAU.sqrt());
        if w == T::zero() {
            return T::zero();
        }
        let inner = if d + 1 == N {
            self.evals.set(self.evals.get() + 1);
            self.psd.value(&(self.h - self.l * *u))
        } else {
            self.level(d + 1, u, tol * T::lit(0.125))
        };
        w * inner
    }

    fn gk15(&self, d: usize, a: T, b: T, u: &mut SVector<T, N>, tol: T) -> (T, T) {
        let c = (a + b) * T::lit(0.5);
        let hw = (b - a) * T::lit(0.5);
        let fc = self.integrand(d, c, u, tol);
        let mut k = fc * T::lit(WGK[7]);
        let mut g = fc * T::lit(WG[3]);
        for j in 0..7 {
            let dx = hw * T::lit(XGK[j]);
            let f = self.integrand(d, c - dx, u, tol) + self.integrand(d, c + dx, u, tol);
            k += f * T::lit(WGK[j]);
            if j % 2 == 1 {
                g += f * T::lit(WG[j / 2]);
            }
        }
        (k * hw, ((k - g) * hw).abs())
    }

    fn level(&self, d: usize, u: &mut SVector<T, N>, tol: T) -> T {
        // Where the line u_d ↦ ζ_d = h_d − Σ_{j≤d} L_dj u_j crosses the PSD's peak coordinate.
        let mut s = self.h[d] - self.peak[d];
        for j in 0..d {
            s -= self.l[(d, j)] * u[j];
        }
        let pd = s / self.l[(d, d)];
        let pd = if pd.is_finite() { pd } else { T::zero() };
        // Breakpoints: the Gaussian core [−R, R] in 4 pieces; the peak and its neighbourhood when
        // within reach of the weight (e^{−x²/2} underflows 40 beyond R); and, around the peak, a
        // geometric grading pd ± w·4ʲ from the PSD's feature width w (mapped to this coordinate)
        // up to the core size, so that a peak much sharper than the Gaussian is never missed.
        let r = self.r;
        let half = T::lit(0.5);
        let mut bp = [T::zero(); 64];
        bp[..5].copy_from_slice(&[-r, -r * half, T::zero(), r * half, r]);
        let mut nb = 5;
        let reach = r + T::lit(40.0);
        if pd.abs() < reach {
            bp[nb] = pd;
            bp[nb + 1] = pd - T::one();
            bp[nb + 2] = pd + T::one();
            nb += 3;
            let mut w = self.feature_width / self.l[(d, d)].abs();
            let span = T::lit(2.0) * reach;
            while w.is_finite() && w > T::zero() && w < span && nb + 2 <= bp.len() {
                bp[nb] = pd - w;
                bp[nb + 1] = pd + w;
                nb += 2;
                w *= T::lit(4.0);
            }
        }
        let lo = (-r).min(if pd.abs() < reach { pd - T::one() } else { -r });
        let hi = r.max(if pd.abs() < reach { pd + T::one() } else { r });
        let bp = &mut bp[..nb];
        for v in bp.iter_mut() {
            *v = v.max(lo).min(hi);
        }
        bp.sort_unstable_by(|a, b| a.partial_cmp(b).unwrap_or(core::cmp::Ordering::Equal));
        let mut panels = [(T::zero(), T::zero()); 63];
        let mut np = 0;
        for w in bp.windows(2) {
            if w[1] > w[0] {
                panels[np] = (w[0], w[1]);
                np += 1;
            }
        }
        // Globally adaptive (QUADPACK QAG style): bisect the panel with the largest error until
        // the summed error is below tol/2 of the running total. Robust to a first estimate that
        // misses a sharp peak. Fixed-capacity panel list on the stack: no heap.
        let mut buf = [(T::zero(), T::zero(), T::zero(), T::zero()); PANELS];
        for (slot, p) in buf.iter_mut().zip(panels[..np].iter()) {
            let (k, e) = self.gk15(d, p.0, p.1, u, tol);
            *slot = (p.0, p.1, k, e);
        }
        let mut n = np;
        // Below the noise of the inner integrations (relative tol/8 each) the outer level cannot
        // resolve anything: such panels count as converged (costs ≤ tol/4 of relative error).
        let noise = if d + 1 == N {
            T::EPSILON * T::lit(50.0)
        } else {
            tol * T::lit(0.25)
        };
        loop {
            let mut total = T::zero();
            let mut err_sum = T::zero();
            let mut worst = None;
            let mut worst_err = T::zero();
            for (i, &(lo, hi, k, e)) in buf[..n].iter().enumerate() {
                total += k;
                if e <= noise * k.abs() {
                    continue;
                }
                err_sum += e;
                let splittable = (hi - lo) > T::EPSILON * T::lit(100.0) * lo.abs().max(hi.abs());
                if splittable && e > worst_err {
                    worst_err = e;
                    worst = Some(i);
                }
            }
            let done = err_sum <= tol * T::lit(0.5) * total.abs();
            match worst {
                Some(i) if !done && n < PANELS && self.evals.get() < MAX_EVALS => {
                    let (lo, hi, _, _) = buf[i];
                    let m = (lo + hi) * half;
                    let (kl, el) = self.gk15(d, lo, m, u, tol);
                    let (kr, er) = self.gk15(d, m, hi, u, tol);
                    buf[i] = (lo, m, kl, el);
                    buf[n] = (m, hi, kr, er);
                    n += 1;
                }
                _ => return total,
            }
        }
    }
}

impl<T: Real, const N: usize, P: Psd<T, N> + ?Sized> BlurMethod<T, N, P> for Adaptive<T> {
    fn blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.normalized_blur(psd, cov, h) * (T::lit(0.5) * cov.log_det()).exp()
    }

    /// The nested integral of `p(h − L u)` against the standard normal, without `|Σ|^{1/2}`.
    fn normalized_blur(&self, psd: &P, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        let r = (T::lit(2.0) * (T::lit(10.0) / self.tol).ln()).sqrt() + T::lit(0.5);
        let ctx = Nested {
            psd,
            l: *cov.cholesky_factor(),
            h: *h,
            peak: psd.peak(),
            r,
            feature_width: psd.feature_width(),
            evals: core::cell::Cell::new(0),
        };
        let mut u = SVector::<T, N>::zeros();
        ctx.level(0, &mut u, self.tol)
    }
}
