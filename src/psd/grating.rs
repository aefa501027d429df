//! Periodic gratings: diffraction orders with efficiencies, blurred into Gaussian lobes.

use nalgebra::SVector;

use super::{BlurMethod, ClosedForm, ClosedFormBlur, Form, Psd, Shape};
use crate::error::Error;
use crate::gaussian::Gaussian;
use crate::real::Real;

/// Bessel functions `J_0(a), …, J_M(a)` of integer order (f64), by Miller's backward recurrence.
///
/// # Formula
/// ```text
/// J_{k−1}(a) = (2k/a) J_k(a) − J_{k+1}(a),    normalised by  J_0 + 2 Σ_{k≥1} J_{2k} = 1
/// ```
/// Started at an even index `K ≥ max(M, a) + 20 + √(40 max(M, a))` (Numerical Recipes'
/// `bessj` rule), rescaled to avoid overflow. `J_m(−a) = (−1)^m J_m(a)`. Accurate to ~1e-15
/// absolute for `|a| ≤ 10³`.
///
/// # Examples
/// ```
/// use gmueller::psd::bessel_j;
/// let j = bessel_j(2, 1.0);
/// // Abramowitz & Stegun, Table 9.1: J0(1), J1(1), J2(1).
/// assert!((j[0] - 0.7651976865579666).abs() < 1e-15);
/// assert!((j[1] - 0.4400505857449335).abs() < 1e-15);
/// assert!((j[2] - 0.1149034849319005).abs() < 1e-15);
/// ```
#[must_use]
pub fn bessel_j(max_order: usize, a: f64) -> Vec<f64> {
    let mut out = vec![0.0; max_order + 1];
    if !a.is_finite() {
        return out;
    }
    let x = a.abs();
    if x < 1e-5 {
        // Two series terms: J_m(x) = (x/2)^m/m! (1 − (x/2)²/(m+1) + …), error ~ x⁴ relative.
        let mut term = 1.0;
        for (m, v) in out.iter_mut().enumerate() {
            if m > 0 {
                term *= 0.5 * x / m as f64;
            }
            *v = term * (1.0 - 0.25 * x * x / (m + 1) as f64);
            if a < 0.0 && m % 2 == 1 {
                *v = -*v;
            }
        }
        return out;
    }
    let big = (max_order as f64).max(x);
    let mut k = (big + 20.0 + (40.0 * big).sqrt()) as usize;
    k += k % 2;
    let (mut jp, mut j) = (0.0_f64, 1e-300_f64); // J_{k+1}, J_k (arbitrary scale)
    let mut norm = 0.0_f64; // J_0 + 2 Σ J_{2i}, on the running scale
    for i in (1..=k).rev() {
        let jm = (2.0 * i as f64 / x) * j - jp;
        jp = j;
        j = jm; // now j = J_{i−1}
        let idx = i - 1;
        if idx <= max_order {
            out[idx] = j;
        }
        if idx % 2 == 0 && idx > 0 {
            norm += 2.0 * j;
        }
        if j.abs() > 1e250 {
            jp *= 1e-250;
            j *= 1e-250;
            norm *= 1e-250;
            for v in out.iter_mut() {
                *v *= 1e-250;
            }
        }
    }
    norm += j; // J_0
    for (m, v) in out.iter_mut().enumerate() {
        *v /= norm;
        if a < 0.0 && m % 2 == 1 {
            *v = -*v;
        }
    }
    out
}

/// Which diffraction orders a [`Grating`] keeps.
///
/// Rule: orders are taken in increasing `|m|` (both signs together), keeping only those with
/// `|ζ_m| ≤ max_frequency` (`+∞`: no frequency limit) and an efficiency that is positive in the
/// scalar type, and the enumeration stops once the efficiency not yet kept,
/// `total − Σ_kept η`, is at most `tail`, or at `|m| = 100 000`. If the rule keeps more than
/// [`Grating::MAX_ORDERS`] orders, construction fails (see there). A typical `max_frequency`
/// is `2k` (every order that can reach a propagating direction for some incidence),
/// `tail = 1e-12`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrderCutoff<T: Real> {
    /// Largest kept order frequency `|ζ_m|` (rad/length).
    pub max_frequency: T,
    /// Stop once the remaining efficiency is at most this.
    pub tail: T,
}

/// A periodic grating: `p = (2π)^{n/2} Σ_m η_m δ(ζ − ζ_m)`, blurred into Gaussian lobes.
///
/// # Formula
/// ```text
/// R(x) = Σ_m η_m e^{i ζ_m·x}  ⇒  p(ζ) = (2π)^{n/2} Σ_m η_m δ(ζ − ζ_m),   R(0) = Σ_m η_m
/// (p * g^Σ)(h) = Σ_m η_m g^Σ(h − ζ_m)
/// 1-D, period Λ, direction d̂:   ζ_m = m (2π/Λ) d̂
/// sinusoidal phase φ(x) = a sin(2πx/Λ):     η_m = J_m(a)²
/// binary phase, depth φ₀, duty D:           η_0 = 1 − 2D(1−D)(1 − cos φ₀),
///                                           η_m = 2(1 − cos φ₀) sin²(π m D)/(π m)²
/// crossed (two 1-D profiles added):        η_{m₁m₂} = η_{m₁} η_{m₂},  ζ = ζ_{m₁} + ζ_{m₂}
/// ```
/// `R` here is the correlation of the interface's reflection function `e^{iφ}`, so `Σ η_m = 1`
/// for a lossless phase grating; [`Psd::variance`] is the efficiency actually kept. [`Psd::value`]
/// (the continuous part) is 0; use [`ClosedForm`] to blur.
#[derive(Debug, Clone, PartialEq)]
pub struct Grating<T: Real, const N: usize> {
    orders: Vec<(SVector<T, N>, T)>,
    kept: T,
    dropped: T,
}

/// `Err(OutOfRange)` for more than [`Grating::MAX_ORDERS`] orders.
fn too_many_orders(count: usize) -> Error {
    Error::OutOfRange {
        what: "number of grating orders kept by the cutoff",
        value: count as f64,
        expected: "≤ Grating::MAX_ORDERS = 10001 (narrow the OrderCutoff: max_frequency ≈ 2k, \
                   or a larger tail)",
    }
}

impl<T: Real, const N: usize> Grating<T, N> {
    /// The most orders a grating may keep: `10 001` (`|m| ≤ 5000` of a 1-D grating; all
    /// propagating orders, `max_frequency = 2k`, of periods up to 2500 λ).
    ///
    /// Every blur sums over the kept orders (≈ 40 ns each), so the cap bounds a blur by ≈ 0.4 ms.
    /// A cutoff that would keep more is an error at construction rather than a silent
    /// truncation: for a renderer, a scene that asks for an energy tail below what the cap can
    /// deliver (e.g. a rectangular grating, `η_m ∝ 1/m²`, with `tail = 1e-12` and no frequency
    /// limit, which silently built 200 001 orders) is better refused with the knob to turn than
    /// rendered slowly or with unreported energy loss. [`Grating::dropped_efficiency`] reports
    /// what an accepted cutoff drops.
    pub const MAX_ORDERS: usize = 10_001;

    /// The orders `m = 0, ±1, …` with efficiencies `eta(m)` (zero beyond `m_end`).
    fn from_efficiencies(
        period: T,
        direction: &SVector<T, N>,
        cutoff: OrderCutoff<T>,
        m_end: usize,
        eta: impl Fn(usize) -> f64,
    ) -> Result<Self, Error> {
        if !(period.is_finite() && period > T::zero()) {
            return Err(Error::OutOfRange {
                what: "grating period",
                value: period.to_f64(),
                expected: "(0, ∞)",
            });
        }
        // Normalised by the largest entry first: a direction of 1e-200 (or 1e200) is not zero
        // (or infinite) because its squared norm under- (or over-)flows.
        let scale = direction.amax();
        if !(scale.is_finite() && scale > T::zero()) {
            return Err(Error::InvalidBasis {
                reason: "grating direction must be a non-zero finite vector",
            });
        }
        let unit = (direction / scale).normalize();
        if !(cutoff.max_frequency >= T::zero() && cutoff.tail >= T::zero()) {
            return Err(Error::OutOfRange {
                what: "order cutoff",
                value: cutoff.max_frequency.min(cutoff.tail).to_f64(),
                expected: "max_frequency ≥ 0 and tail ≥ 0",
            });
        }
        let gnorm = T::two_pi() / period;
        let bad_period = Error::OutOfRange {
            what: "grating period",
            value: period.to_f64(),
            expected: "order positions m·2π/Λ finite (Λ ≥ 2π·|m|/T::MAX)",
        };
        if !gnorm.is_finite() {
            return Err(bad_period);
        }
        let g = unit * gnorm;
        let mut orders = Vec::new();
        let mut kept = 0.0_f64;
        for m in 0..=m_end.min(100_000) {
            let remaining = 1.0 - kept;
            if m > 0 && remaining <= cutoff.tail.to_f64() {
                break;
            }
            if m as f64 * gnorm.to_f64() > cutoff.max_frequency.to_f64() {
                break;
            }
            let e = eta(m);
            let et = T::lit(e);
            if !(e > 0.0 && et > T::zero()) {
                continue;
            }
            let signs: &[T] = if m == 0 {
                &[T::one()]
            } else {
                &[T::one(), T::lit(-1.0)]
            };
            if orders.len() + signs.len() > Self::MAX_ORDERS {
                return Err(too_many_orders(orders.len() + signs.len()));
            }
            let zeta = g * T::lit(m as f64);
            if !zeta.iter().all(|v| v.is_finite()) {
                return Err(bad_period);
            }
            for &s in signs {
                orders.push((zeta * s, et));
                kept += e;
            }
        }
        Ok(Self {
            kept: T::lit(kept),
            dropped: T::lit((1.0 - kept).max(0.0)),
            orders,
        })
    }

    /// A sinusoidal phase grating `φ(x) = a sin(2π d̂·x/Λ)`: `η_m = J_m(a)²`.
    ///
    /// Derived quantities checked: the order positions `m (2π/Λ) d̂` finite (a period of
    /// `10⁻³⁰⁸` gave `2π/Λ = ∞`), at most [`Grating::MAX_ORDERS`] orders kept.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a non-positive or non-finite period, `|a| > 10⁴` or non-finite,
    /// a negative or NaN cutoff, order positions that overflow (naming the period), or more than
    /// [`Grating::MAX_ORDERS`] orders; [`Error::InvalidBasis`] for a zero or non-finite direction.
    ///
    /// # Examples
    /// ```
    /// use gmueller::psd::{Grating, OrderCutoff};
    /// use nalgebra::Vector2;
    /// let cut = OrderCutoff { max_frequency: f64::INFINITY, tail: 1e-12 };
    /// assert!(Grating::<f64, 2>::sinusoidal(1e-308, &Vector2::x(), 1.0, cut).is_err());
    /// let g = Grating::<f64, 2>::sinusoidal(1.0, &Vector2::x(), 1.0, cut).unwrap();
    /// assert!(g.orders().len() < 30 && g.dropped_efficiency() <= 1e-12);
    /// ```
    pub fn sinusoidal(
        period: T,
        direction: &SVector<T, N>,
        phase_amplitude: T,
        cutoff: OrderCutoff<T>,
    ) -> Result<Self, Error> {
        let a = phase_amplitude.to_f64();
        if !a.is_finite() || a.abs() > 1e4 {
            return Err(Error::OutOfRange {
                what: "phase amplitude",
                value: a,
                expected: "|a| ≤ 1e4",
            });
        }
        let period_f = period.to_f64();
        let mmax = if period_f > 0.0 {
            ((cutoff.max_frequency.to_f64() * period_f / core::f64::consts::TAU).min(1e5)) as usize
        } else {
            0
        };
        let j = bessel_j(mmax.min(a.abs() as usize + 200), a);
        Self::from_efficiencies(period, direction, cutoff, j.len() - 1, |m| {
            j.get(m).map_or(0.0, |v| v * v)
        })
    }

    /// A sinusoidal **height** grating `z(x) = a sin(2π d̂·x/Λ)` as the PSD of a rough surface
    /// (first order in the height, the model of [`crate::interaction::RoughSurface`]): the two
    /// orders `±1` of efficiency `a²/4` each.
    ///
    /// # Formula
    /// ```text
    /// R(x) = ⟨z(x₀) z(x₀ + x)⟩ = (a²/2) cos(2π d̂·x/Λ) = (a²/4) (e^{iζ₁·x} + e^{−iζ₁·x}),   ζ₁ = (2π/Λ) d̂
    /// p = (2π)^{n/2} (a²/4) [δ(ζ − ζ₁) + δ(ζ + ζ₁)],   σ² = R(0) = a²/2
    /// ```
    /// The kernel's Debye–Waller factor `exp(−(vσ)²)` then uses the height variance `a²/2`
    /// (µm² for a µm amplitude), and the first-order model holds while `v a ≲ 0.3`. Not to be
    /// confused with [`Grating::sinusoidal`], the *phase* grating `e^{iφ}` whose efficiencies sum
    /// to 1 (dimensionless): in a `RoughSurface` its "variance" of 1 reads as a height variance
    /// of 1 length² and makes the surface black (`α ≈ e^{−v²}`).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `0 ≤ a` and `0 < Λ` are finite with `a²` and `2π/Λ` finite;
    /// [`Error::InvalidBasis`] for a zero or non-finite direction.
    ///
    /// # Examples
    /// ```
    /// use gmueller::psd::{Grating, Psd};
    /// use nalgebra::Vector2;
    /// // 20 nm amplitude, 5 µm period, along x.
    /// let g = Grating::<f64, 2>::sinusoidal_height(0.02, 5.0, &Vector2::x()).unwrap();
    /// assert_eq!(g.orders().len(), 2);
    /// assert!((g.variance() - 0.5 * 0.02 * 0.02).abs() < 1e-18);
    /// assert!((g.orders()[0].0.x - std::f64::consts::TAU / 5.0).abs() < 1e-15);
    /// ```
    pub fn sinusoidal_height(
        amplitude: T,
        period: T,
        direction: &SVector<T, N>,
    ) -> Result<Self, Error> {
        let a2 = amplitude * amplitude;
        if !(amplitude >= T::zero() && a2.is_finite()) {
            return Err(Error::OutOfRange {
                what: "height amplitude",
                value: amplitude.to_f64(),
                expected: "finite and ≥ 0, with a² finite",
            });
        }
        let quarter = a2 * T::lit(0.25);
        let unit = Self::from_efficiencies(
            period,
            direction,
            OrderCutoff {
                max_frequency: T::MAX,
                tail: T::zero(),
            },
            1,
            |m| if m == 1 { 0.5 } else { 0.0 },
        )?;
        let orders = unit.orders.iter().map(|(z, _)| (*z, quarter)).collect();
        Ok(Self {
            orders,
            kept: quarter + quarter,
            dropped: T::zero(),
        })
    }

    /// A binary (rectangular) phase grating of depth `φ₀` and duty cycle `D ∈ (0, 1)`.
    ///
    /// Its efficiencies decay only like `1/m²`, so the cutoff's `tail` is reached late: without
    /// a frequency limit, `tail = 10⁻¹²` would need ~10¹¹ orders. Such a cutoff is an error
    /// (more than [`Grating::MAX_ORDERS`] orders) — it used to build 200 001 orders silently
    /// (milliseconds per blur); a frequency limit (`max_frequency ≈ 2k`) or a larger tail keeps
    /// it within the cap, with [`Grating::dropped_efficiency`] reporting the rest.
    ///
    /// # Errors
    /// As [`Grating::sinusoidal`], plus [`Error::OutOfRange`] for `D ∉ (0, 1)` or a non-finite
    /// phase depth.
    ///
    /// # Examples
    /// ```
    /// use gmueller::psd::{Grating, OrderCutoff};
    /// use nalgebra::Vector2;
    /// let loose = OrderCutoff { max_frequency: f64::INFINITY, tail: 1e-12 };
    /// assert!(Grating::<f64, 2>::rectangular(1.0, &Vector2::x(), 1.0, 0.3, loose).is_err());
    /// let k = std::f64::consts::TAU / 0.5; // λ = 0.5 µm
    /// let cut = OrderCutoff { max_frequency: 2.0 * k, tail: 1e-12 };
    /// let g = Grating::<f64, 2>::rectangular(1.0, &Vector2::x(), 1.0, 0.3, cut).unwrap();
    /// assert_eq!(g.orders().len(), 9); // |m| ≤ 2Λ/λ = 4
    /// assert!(g.dropped_efficiency() > 0.0 && g.dropped_efficiency() < 0.05);
    /// ```
    pub fn rectangular(
        period: T,
        direction: &SVector<T, N>,
        phase_depth: T,
        duty: T,
        cutoff: OrderCutoff<T>,
    ) -> Result<Self, Error> {
        let (p0, d) = (phase_depth.to_f64(), duty.to_f64());
        if !p0.is_finite() {
            return Err(Error::NonFinite {
                what: "phase depth",
            });
        }
        if !(d > 0.0 && d < 1.0) {
            return Err(Error::OutOfRange {
                what: "duty cycle",
                value: d,
                expected: "(0, 1)",
            });
        }
        let c = 1.0 - p0.cos();
        Self::from_efficiencies(period, direction, cutoff, usize::MAX, |m| {
            if m == 0 {
                1.0 - 2.0 * d * (1.0 - d) * c
            } else {
                let x = core::f64::consts::PI * m as f64;
                2.0 * c * (x * d).sin().powi(2) / (x * x)
            }
        })
    }

    /// A crossed grating from two 1-D gratings (phase profiles added): orders are sums, efficiencies
    /// products. Orders whose product efficiency is below `min_efficiency` (or is 0 in `T`) are
    /// dropped, and counted in [`Grating::dropped_efficiency`].
    ///
    /// The kept orders are counted before anything is allocated: two gratings of
    /// [`Grating::MAX_ORDERS`] orders each would otherwise ask for 10⁸ orders.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a NaN or negative `min_efficiency`, for more than
    /// [`Grating::MAX_ORDERS`] kept orders, and for order positions `ζ_a + ζ_b` that overflow.
    ///
    /// # Examples
    /// ```
    /// use gmueller::psd::{Grating, OrderCutoff};
    /// use nalgebra::Vector2;
    /// let cut = OrderCutoff { max_frequency: 20.0, tail: 1e-12 };
    /// let gx = Grating::<f64, 2>::sinusoidal(1.0, &Vector2::x(), 1.0, cut).unwrap();
    /// let gy = Grating::<f64, 2>::sinusoidal(1.5, &Vector2::y(), 0.5, cut).unwrap();
    /// let xg = Grating::crossed(&gx, &gy, 0.0).unwrap();
    /// assert_eq!(xg.orders().len(), gx.orders().len() * gy.orders().len());
    /// assert!(Grating::crossed(&gx, &gy, f64::NAN).is_err());
    /// ```
    pub fn crossed(a: &Self, b: &Self, min_efficiency: T) -> Result<Self, Error> {
        if min_efficiency.partial_cmp(&T::zero()).is_none() || min_efficiency < T::zero() {
            return Err(Error::OutOfRange {
                what: "minimum efficiency of a crossed grating",
                value: min_efficiency.to_f64(),
                expected: "[0, ∞)",
            });
        }
        let keep = |ea: T, eb: T| {
            let e = ea * eb;
            e > T::zero() && e >= min_efficiency
        };
        let mut count = 0usize;
        for (_, ea) in &a.orders {
            for (_, eb) in &b.orders {
                count += usize::from(keep(*ea, *eb));
            }
            if count > Self::MAX_ORDERS {
                return Err(too_many_orders(count));
            }
        }
        let mut orders = Vec::with_capacity(count);
        let mut kept = T::zero();
        for (za, ea) in &a.orders {
            for (zb, eb) in &b.orders {
                if keep(*ea, *eb) {
                    let z = za + zb;
                    if !z.iter().all(|v| v.is_finite()) {
                        return Err(Error::OutOfRange {
                            what: "crossed grating order positions ζ_a + ζ_b",
                            value: f64::INFINITY,
                            expected: "finite",
                        });
                    }
                    orders.push((z, *ea * *eb));
                    kept += *ea * *eb;
                }
            }
        }
        let dropped = (T::one() - kept).max(T::zero());
        Ok(Self {
            orders,
            kept,
            dropped,
        })
    }

    /// The kept orders `(ζ_m, η_m)`.
    #[must_use]
    pub fn orders(&self) -> &[(SVector<T, N>, T)] {
        &self.orders
    }

    /// `1 − Σ_kept η` (the efficiency the cutoff dropped, for a lossless grating).
    #[must_use]
    pub fn dropped_efficiency(&self) -> T {
        self.dropped
    }
}

impl<T: Real, const N: usize> Psd<T, N> for Grating<T, N> {
    #[inline]
    fn value(&self, _zeta: &SVector<T, N>) -> T {
        T::zero()
    }
    #[inline]
    fn variance(&self) -> T {
        self.kept
    }
    #[inline]
    fn form(&self) -> Form<'_, T, N> {
        Form::exact(Shape::Orders(&self.orders))
    }
}

impl<T: Real, const N: usize> ClosedFormBlur<T, N> for Grating<T, N> {
    #[inline]
    fn closed_form_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        self.orders
            .iter()
            .fold(T::zero(), |acc, (z, e)| acc + *e * cov.value(&(h - z)))
    }
    /// `Σ e_m g^Σ(h − ζ_m) |Σ|^{−1/2}`, each term in log space.
    #[inline]
    fn closed_form_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        let half_log_det = T::lit(0.5) * cov.log_det();
        self.orders.iter().fold(T::zero(), |acc, (z, e)| {
            acc + *e * (cov.log_value(&(h - z)) - half_log_det).exp()
        })
    }
    /// The logarithm of the linear sum where that is a safely normal number, log-sum-exp over
    /// the orders of `ln e_m + ln g^Σ(h − ζ_m) − ½ ln|Σ|` otherwise.
    #[inline]
    fn closed_form_log_normalized_blur(&self, cov: &Gaussian<T, N>, h: &SVector<T, N>) -> T {
        let v = ClosedForm.normalized_blur(self, cov, h);
        if crate::numerics::in_normal_range(v) {
            return v.ln();
        }
        let half_log_det = T::lit(0.5) * cov.log_det();
        crate::numerics::log_sum_exp(
            self.orders
                .iter()
                .map(|(z, e)| e.ln() + cov.log_value(&(h - z)) - half_log_det),
        )
    }
}
