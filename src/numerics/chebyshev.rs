//! Piecewise Chebyshev tables of a cumulative distribution: the adaptive interpolant of a
//! non-negative function `a` on an interval, its exact antiderivative per panel, and the
//! inversion `x(t)` of `∫ a = t` by safeguarded Newton.
//!
//! # Formula
//! ```text
//! a(x) ≈ Σₖ cₖ Tₖ(s),  s = 2(x − x₀)/w − 1 ∈ [−1, 1]     (per panel [x₀, x₀ + w], degree DEG)
//! ∫_{x₀}^{x} a = (w/2) P(s),  P = Σₖ Bₖ Tₖ,  B₁ = c₀ − c₂/2,  Bₖ = (cₖ₋₁ − cₖ₊₁)/(2k),  P(−1) = 0
//! panel mass = (w/2)(P(1) − P(−1)) = w Σ_{k odd} Bₖ
//! ```
//! The coefficients come from the `DEG + 1` Chebyshev–Lobatto points; a panel is accepted when
//! its two tail coefficients and three off-node checks are below the tolerance, otherwise it is
//! halved (depth first, so the panels come out sorted).

use crate::real::Real;

/// Degree of the per-panel Chebyshev interpolants.
pub(crate) const DEG: usize = 16;

/// Why a table could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TableError {
    /// `a` is zero (or not finite) at every probe point.
    NoMass,
    /// The adaptive refinement needed more panels than allowed.
    TooManyPanels,
}

/// Clenshaw summation of `Σ cₖ Tₖ(x)`.
#[inline]
pub(crate) fn clenshaw<T: Real>(c: &[T], x: T) -> T {
    let (mut b1, mut b2) = (T::zero(), T::zero());
    for &ck in c.iter().skip(1).rev() {
        let b0 = ck + (x + x) * b1 - b2;
        b2 = b1;
        b1 = b0;
    }
    c[0] + x * b1 - b2
}

/// One panel of a [`CdfTable`].
#[derive(Debug, Clone, Copy, PartialEq)]
struct Panel<T> {
    start: T,
    width: T,
    /// `∫ a` over all earlier panels.
    cumulative: T,
    /// `∫ a` over this panel.
    mass: T,
    /// Chebyshev coefficients of `a(x(s))`, `s ∈ [−1, 1]`.
    value: [T; DEG + 1],
    /// Chebyshev coefficients of its antiderivative, zero at `s = −1`.
    integral: [T; DEG + 2],
}

/// The cumulative distribution `t(x) = ∫_{lo}^{x} a` of a non-negative function, tabulated on
/// adaptive panels (module docs); built in `f64`, evaluated in any precision.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CdfTable<T> {
    panels: Vec<Panel<T>>,
    total: T,
}

/// Chebyshev coefficients of `f` on `[lo, lo + width]` from the DEG + 1 Lobatto points, and an
/// error estimate (tail coefficients and three off-node checks).
fn chebyshev_fit(f: &impl Fn(f64) -> f64, lo: f64, width: f64) -> ([f64; DEG + 1], f64) {
    let n = DEG as f64;
    let pi = core::f64::consts::PI;
    let at = |x: f64| f(lo + 0.5 * width * (x + 1.0));
    let mut vals = [0.0; DEG + 1];
    for (j, v) in vals.iter_mut().enumerate() {
        *v = at((pi * j as f64 / n).cos());
    }
    let mut c = [0.0; DEG + 1];
    for (k, ck) in c.iter_mut().enumerate() {
        let mut s = 0.0;
        for (j, v) in vals.iter().enumerate() {
            let w = if j == 0 || j == DEG { 0.5 } else { 1.0 };
            s += w * v * (pi * (j * k) as f64 / n).cos();
        }
        *ck = s * if k == 0 || k == DEG { 1.0 / n } else { 2.0 / n };
    }
    let mut err = c[DEG].abs().max(c[DEG - 1].abs());
    for x in [-0.6180339887, 0.2360679775, 0.75] {
        err = err.max((clenshaw(&c, x) - at(x)).abs());
    }
    (c, err)
}

/// The antiderivative coefficients `B` (zero at `s = −1`) of the Chebyshev series `c`, and the
/// panel mass `w Σ_{k odd} Bₖ`.
fn antiderivative(c: &[f64; DEG + 1], w: f64) -> ([f64; DEG + 2], f64) {
    let coef = |k: usize| if k <= DEG { c[k] } else { 0.0 };
    let mut b = [0.0; DEG + 2];
    b[1] = coef(0) - 0.5 * coef(2);
    for (k, bk) in b.iter_mut().enumerate().skip(2) {
        *bk = (coef(k - 1) - coef(k + 1)) / (2.0 * k as f64);
    }
    let alt: f64 = (1..=DEG + 1)
        .map(|k| if k % 2 == 0 { b[k] } else { -b[k] })
        .sum();
    b[0] = -alt;
    let odd: f64 = (1..=DEG + 1).step_by(2).map(|k| b[k]).sum();
    (b, w * odd)
}

impl CdfTable<f64> {
    /// Tabulates `∫ a` over `[lo, hi)`: 16 initial panels, each halved until its interpolation
    /// error is at most `rel_tol` times the peak of `a` (probed at 256 points) or its width at
    /// most `min_width`.
    ///
    /// # Errors
    /// [`TableError::NoMass`] when the probed peak is 0 or not finite;
    /// [`TableError::TooManyPanels`] when more than `max_panels` panels would be needed.
    pub(crate) fn build(
        a: &impl Fn(f64) -> f64,
        (lo, hi): (f64, f64),
        rel_tol: f64,
        min_width: f64,
        max_panels: usize,
    ) -> Result<Self, TableError> {
        let span = hi - lo;
        let initial = 16;
        let mut peak = 0.0_f64;
        for i in 0..256 {
            peak = peak.max(a(lo + span * i as f64 / 256.0));
        }
        if !(peak.is_finite() && peak > 0.0) {
            return Err(TableError::NoMass);
        }
        let tol = rel_tol * peak;
        let mut out: Vec<Panel<f64>> = Vec::new();
        // Depth-first, left to right, so panels come out sorted.
        let mut stack: Vec<(f64, f64)> = (0..initial)
            .rev()
            .map(|i| (lo + span * i as f64 / initial as f64, span / initial as f64))
            .collect();
        while let Some((x0, w)) = stack.pop() {
            let (c, err) = chebyshev_fit(a, x0, w);
            if err > tol && w > min_width {
                if out.len() + stack.len() >= max_panels {
                    return Err(TableError::TooManyPanels);
                }
                stack.push((x0 + 0.5 * w, 0.5 * w));
                stack.push((x0, 0.5 * w));
                continue;
            }
            let (b, mass) = antiderivative(&c, w);
            let cumulative = out.last().map_or(0.0, |p| p.cumulative + p.mass);
            out.push(Panel {
                start: x0,
                width: w,
                cumulative,
                mass: mass.max(0.0),
                value: c,
                integral: b,
            });
        }
        let total = out.iter().map(|p| p.mass).sum();
        Ok(Self { panels: out, total })
    }

    /// The table in precision `T` (every entry rounded once).
    pub(crate) fn to_precision<T: Real>(&self) -> CdfTable<T> {
        CdfTable {
            panels: self
                .panels
                .iter()
                .map(|p| Panel {
                    start: T::lit(p.start),
                    width: T::lit(p.width),
                    cumulative: T::lit(p.cumulative),
                    mass: T::lit(p.mass),
                    value: p.value.map(T::lit),
                    integral: p.integral.map(T::lit),
                })
                .collect(),
            total: T::lit(self.total),
        }
    }
}

impl<T: Real> CdfTable<T> {
    /// `∫ a` over the whole interval (the sum of the panel masses).
    #[inline]
    pub(crate) fn total(&self) -> T {
        self.total
    }

    /// The number of panels.
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.panels.len()
    }

    /// The `x` with `∫_{lo}^{x} a = t` (`t` clamped into the panel's mass), by safeguarded
    /// Newton on the panel's antiderivative: stops when the residual is at rounding level
    /// (`2ε` of the panel's scaled mass) or the bracket or step is below `4ε` in `s`.
    pub(crate) fn invert(&self, t: T) -> T {
        // Last panel whose cumulative mass is ≤ t.
        let j = self
            .panels
            .partition_point(|p| p.cumulative <= t)
            .saturating_sub(1);
        let p = &self.panels[j];
        let half = p.width * T::lit(0.5);
        let target = ((t - p.cumulative).max(T::zero())).min(p.mass) / half;
        let top = p.mass / half;
        let (mut lo, mut hi) = (-T::one(), T::one());
        let mut x = if top > T::zero() {
            T::lit(2.0) * target / top - T::one()
        } else {
            T::zero()
        };
        let tol = T::lit(4.0) * T::EPSILON;
        for _ in 0..64 {
            let f = clenshaw(&p.integral, x) - target;
            if f.abs() <= T::lit(2.0) * T::EPSILON * top {
                break; // the CDF residual is at rounding level
            }
            if f < T::zero() {
                lo = x;
            } else {
                hi = x;
            }
            let d = clenshaw(&p.value, x);
            let mut next = x - f / d;
            if !(d > T::zero() && next > lo && next < hi) {
                next = (lo + hi) * T::lit(0.5);
            }
            let step = (next - x).abs();
            x = next;
            if step <= tol || hi - lo <= tol {
                break;
            }
        }
        p.start + half * (x + T::one())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The density `(2 + cos 3ψ + ½ sin ψ)² ≥ ¼` and its antiderivative from 0, expanded by
    /// hand: `(2 + C + S/2)² = 4 + 4C + 2S + C² + CS + S²/4` with `C = cos 3ψ`, `S = sin ψ`,
    /// `C² = (1 + cos 6ψ)/2`, `CS = (sin 4ψ − sin 2ψ)/2`, `S² = (1 − cos 2ψ)/2`.
    fn a(x: f64) -> f64 {
        let v = 2.0 + (3.0 * x).cos() + 0.5 * x.sin();
        v * v
    }

    fn exact_cdf(x: f64) -> f64 {
        4.0 * x
            + 4.0 * (3.0 * x).sin() / 3.0
            + 2.0 * (1.0 - x.cos())
            + 0.5 * x
            + (6.0 * x).sin() / 12.0
            + 0.5 * ((1.0 - (4.0 * x).cos()) / 4.0 - (1.0 - (2.0 * x).cos()) / 2.0)
            + 0.125 * x
            - (2.0 * x).sin() / 16.0
    }

    #[test]
    fn table_integrates_and_inverts_a_known_cdf() {
        let tau = core::f64::consts::TAU;
        let table = CdfTable::build(&a, (0.0, tau), 1e-13, 1e-11, 1 << 14).unwrap();
        assert!((table.total() - exact_cdf(tau)).abs() < 1e-12 * exact_cdf(tau));
        for i in 1..200 {
            let x = tau * f64::from(i) / 200.0;
            let back = table.invert(exact_cdf(x));
            assert!((back - x).abs() < 1e-10, "x = {x}: inverted to {back}");
        }
        // In f32 the inversion is accurate to the type.
        let t32 = table.to_precision::<f32>();
        for i in 1..50 {
            let x = tau * f64::from(i) / 50.0;
            let back = f64::from(t32.invert(exact_cdf(x) as f32));
            assert!((back - x).abs() < 2e-5, "f32, x = {x}: inverted to {back}");
        }
    }

    #[test]
    fn table_reports_no_mass_and_refinement_limit() {
        let tau = core::f64::consts::TAU;
        assert_eq!(
            CdfTable::build(&|_| 0.0, (0.0, tau), 1e-13, 1e-11, 64),
            Err(TableError::NoMass)
        );
        // A kink cannot be resolved to 1e-13 within 20 panels.
        assert_eq!(
            CdfTable::build(&|x: f64| (x - 1.0).abs(), (0.0, tau), 1e-13, 1e-11, 20),
            Err(TableError::TooManyPanels)
        );
    }
}
