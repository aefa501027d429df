//! Random realizations of matter: stationary Gaussian fields with an exactly known
//! autocorrelation (circulant embedding on a periodic grid), and locally-stationary random
//! Jones fields built on them (S2.7–S2.8).
//!
//! The random source is a parameter, a closure returning uniform numbers in `[0, 1)` (e.g.
//! `|| rng.unit()` with `gmueller::verify::rng::SplitMix64`), so the crate needs no random
//! number dependency and every draw is reproducible from the caller's seed. The generator
//! lives in the library, not in the verification kit, because a realization of matter is
//! physics a renderer or a brute-force tracer uses (the validation crate's 3-D Born sums draw
//! their permittivity from it), not only a testing tool. Everything here is `f64`: it is a
//! reference computation, and the circulant eigenvalues need the precision.

use nalgebra::{Matrix2, SVector};
use num_complex::Complex;

use super::StationaryCorrelation;
use crate::error::Error;
use crate::jones::JonesMatrix;
use crate::mueller::GeneralizedMueller;
use crate::numerics::dft_in_place;

type C = Complex<f64>;

/// The largest total weight of negative circulant eigenvalues accepted, relative to `R(0)`:
/// the draws' covariance then equals the embedded `R` to this relative accuracy.
const CLIP_TOLERANCE: f64 = 1e-6;

/// A stationary, zero-mean Gaussian random field on a periodic grid whose covariance is a given
/// autocorrelation `R`, exactly: circulant embedding (Dietrich & Newsam 1997; Wood & Chan 1994).
///
/// # Formula
/// ```text
/// c_j = R(x_j),  x_j the minimal-image displacement of grid index j (|x_j,a| ≤ nₐdₐ/2)
/// λ_q = Σ_j c_j e^{−2πi q·j/n}              circulant eigenvalues (real: c is real and even)
/// u_j = Σ_q √(λ_q/n_tot) w_q e^{+2πi q·j/n},  w_q i.i.d. complex normal, ⟨|w|²⟩ = 1
/// ⇒  ⟨u_j u_l*⟩ = c_{j−l} = R(x_j − x_l at the minimal image),   ⟨u_j u_l⟩ = 0
/// ```
/// Negative `λ_q` (the embedding is not positive semi-definite when R is too wide for the
/// grid) are set to 0 when their total weight `Σ|λ_q|/n_tot` is at most `1e-6 R(0)` — the
/// covariance is then `R` to that accuracy ([`StationaryField::covariance_error`]) — and
/// rejected otherwise. Periodicity: points more than half the grid apart see `R` at the
/// minimal image, so a grid should be at least twice the correlation length wider than the
/// region used.
///
/// Grid points are stored first axis fastest and sit at `xₐ = (iₐ − (nₐ − 1)/2) dₐ`, centred on
/// the origin ([`StationaryField::position`]).
///
/// # Examples
/// ```
/// use gmueller::matter::StationaryField;
/// use nalgebra::Vector2;
/// use num_complex::Complex;
///
/// // A 2-D field with R(ξ) = exp(−|ξ|²/(2·0.25²)) on a 32 × 32 grid of spacing 0.1: the
/// // grid is 12.8 correlation lengths wide, R = 1.3e-9 at its half-width, and the draws'
/// // covariance is R within 1.6e-10.
/// let field = StationaryField::new([32, 32], [0.1, 0.1],
///     |xi: &Vector2<f64>| (-0.5 * xi.norm_squared() / 0.0625).exp())?;
/// assert!(field.covariance_error() < 1e-9);
/// // Any uniform source in [0, 1) will do; here a 64-bit LCG (Knuth's MMIX constants).
/// let mut state = 1_u64;
/// let mut uniform = move || {
///     state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
///     (state >> 11) as f64 / (1_u64 << 53) as f64
/// };
/// let mut u = vec![Complex::new(0.0, 0.0); field.len()];
/// // ⟨|u|²⟩ = R(0) = 1: the mean over the grid of many draws.
/// let mut mean = 0.0;
/// for _ in 0..200 {
///     field.sample_complex(&mut uniform, &mut u);
///     mean += u.iter().map(|z| z.norm_sqr()).sum::<f64>() / (200.0 * u.len() as f64);
/// }
/// assert!((mean - 1.0).abs() < 0.05);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct StationaryField<const N: usize> {
    dims: [usize; N],
    spacing: [f64; N],
    /// `c_j`, the autocorrelation at the minimal-image displacement of index j.
    embedded: Vec<f64>,
    /// `√(max(λ_q, 0)/n_tot)`.
    amplitudes: Vec<f64>,
    /// `Σ_{λ_q < 0} |λ_q| / n_tot`.
    clipped: f64,
}

impl<const N: usize> StationaryField<N> {
    /// The field on a grid of `dims` points with spacings `spacing` whose covariance is
    /// `autocorrelation` (a [`StationaryCorrelation`]: a `GaussianPsd` or a closure).
    ///
    /// # Errors
    /// - [`Error::OutOfRange`] for a zero grid size, a spacing that is not finite and positive,
    ///   or `R(0) ≤ 0`;
    /// - [`Error::NonFinite`] if `R` is not finite at a grid displacement;
    /// - [`Error::NotPositiveDefinite`] if the circulant embedding's negative eigenvalues weigh
    ///   more than `1e-6 R(0)` (R too wide for the grid, or not positive definite): enlarge the
    ///   grid. `min_eigenvalue` reports the most negative `λ_q/n_tot` relative to `R(0)`.
    pub fn new(
        dims: [usize; N],
        spacing: [f64; N],
        autocorrelation: impl StationaryCorrelation<f64, N>,
    ) -> Result<Self, Error> {
        if let Some(n) = dims.iter().find(|n| **n == 0) {
            return Err(Error::OutOfRange {
                what: "grid size",
                value: *n as f64,
                expected: "≥ 1 on every axis",
            });
        }
        if let Some(d) = spacing.iter().find(|d| !(d.is_finite() && **d > 0.0)) {
            return Err(Error::OutOfRange {
                what: "grid spacing",
                value: *d,
                expected: "(0, ∞)",
            });
        }
        let total: usize = dims.iter().product();
        let mut embedded = Vec::with_capacity(total);
        for j in 0..total {
            let r = autocorrelation.correlation(&minimal_image(&dims, &spacing, j));
            if !r.is_finite() {
                return Err(Error::NonFinite {
                    what: "autocorrelation at a grid displacement",
                });
            }
            embedded.push(r);
        }
        let r0 = embedded[0];
        if r0.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return Err(Error::OutOfRange {
                what: "autocorrelation R(0)",
                value: r0,
                expected: "(0, ∞)",
            });
        }
        let mut spectrum: Vec<C> = embedded.iter().map(|&c| C::new(c, 0.0)).collect();
        dft_in_place(&mut spectrum, &dims, false);
        let n = total as f64;
        let clipped = spectrum.iter().map(|l| (-l.re).max(0.0)).sum::<f64>() / n;
        if clipped > CLIP_TOLERANCE * r0 {
            let min = spectrum.iter().map(|l| l.re).fold(f64::INFINITY, f64::min);
            return Err(Error::NotPositiveDefinite {
                what: "circulant embedding of the autocorrelation (enlarge the grid)",
                min_eigenvalue: min / n / r0,
            });
        }
        let amplitudes = spectrum
            .iter()
            .map(|l| (l.re.max(0.0) / n).sqrt())
            .collect();
        Ok(Self {
            dims,
            spacing,
            embedded,
            amplitudes,
            clipped,
        })
    }

    /// The number of grid points.
    #[must_use]
    pub fn len(&self) -> usize {
        self.embedded.len()
    }

    /// Always `false` (a grid has at least one point).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.embedded.is_empty()
    }

    /// The grid size on each axis.
    #[must_use]
    pub fn dims(&self) -> [usize; N] {
        self.dims
    }

    /// The grid spacing on each axis.
    #[must_use]
    pub fn spacing(&self) -> [f64; N] {
        self.spacing
    }

    /// The position of grid point `index`: `xₐ = (iₐ − (nₐ − 1)/2) dₐ` (first axis fastest).
    ///
    /// # Panics
    /// If `index ≥ len()` (a caller bug).
    #[must_use]
    pub fn position(&self, index: usize) -> SVector<f64, N> {
        assert!(index < self.len(), "grid index {index} ≥ {}", self.len());
        let mut rest = index;
        SVector::from_fn(|a, _| {
            let i = rest % self.dims[a];
            rest /= self.dims[a];
            (i as f64 - 0.5 * (self.dims[a] as f64 - 1.0)) * self.spacing[a]
        })
    }

    /// The exact covariance `⟨u_j u_l*⟩` of two grid points `j`, `l` of a draw: the embedded
    /// autocorrelation at the minimal image of their displacement (within
    /// [`Self::covariance_error`]).
    ///
    /// # Panics
    /// If an index is `≥ len()` (a caller bug).
    #[must_use]
    pub fn covariance(&self, j: usize, l: usize) -> f64 {
        assert!(j < self.len() && l < self.len(), "grid index out of range");
        let (mut a, mut b, mut diff, mut stride) = (j, l, 0, 1);
        for &n in &self.dims {
            let d = (a % n + n - b % n) % n;
            diff += d * stride;
            stride *= n;
            a /= n;
            b /= n;
        }
        self.embedded[diff]
    }

    /// `Σ_{λ_q<0} |λ_q| / n_tot`: the largest possible difference between the draws'
    /// covariance and the embedded autocorrelation (0 when every circulant eigenvalue is ≥ 0).
    #[must_use]
    pub fn covariance_error(&self) -> f64 {
        self.clipped
    }

    /// One draw of the complex field: circular Gaussian, `⟨u_j u_l*⟩ = c_{j−l}`, `⟨u_j u_l⟩ = 0`.
    /// `uniform` must return independent uniform numbers in `[0, 1)`; it is called `2·len()`
    /// times. Allocates the transform's scratch line (not a hot path).
    ///
    /// # Panics
    /// If `out.len() != len()` (a caller bug).
    pub fn sample_complex(&self, uniform: &mut impl FnMut() -> f64, out: &mut [C]) {
        assert_eq!(out.len(), self.len(), "output of the wrong length");
        let h = core::f64::consts::FRAC_1_SQRT_2;
        for (o, a) in out.iter_mut().zip(&self.amplitudes) {
            // Box–Muller; 1 − U ∈ (0, 1] keeps the logarithm finite.
            let r = (-2.0 * (1.0 - uniform()).ln()).sqrt();
            let (s, c) = (core::f64::consts::TAU * uniform()).sin_cos();
            *o = C::new(r * c, r * s) * (h * a);
        }
        dft_in_place(out, &self.dims, true);
    }

    /// Two independent real fields in one draw: afterwards `out[j].re` and `out[j].im` are each
    /// a real Gaussian field with `⟨u_j u_l⟩ = c_{j−l}`, and the two are independent
    /// (`√2` times a complex draw).
    ///
    /// # Panics
    /// If `out.len() != len()` (a caller bug).
    pub fn sample_real_pair(&self, uniform: &mut impl FnMut() -> f64, out: &mut [C]) {
        self.sample_complex(uniform, out);
        let s = core::f64::consts::SQRT_2;
        for o in out.iter_mut() {
            *o *= s;
        }
    }
}

/// The minimal-image displacement of grid index `j` (first axis fastest).
fn minimal_image<const N: usize>(
    dims: &[usize; N],
    spacing: &[f64; N],
    j: usize,
) -> SVector<f64, N> {
    let mut rest = j;
    SVector::from_fn(|a, _| {
        let n = dims[a];
        let i = rest % n;
        rest /= n;
        let signed = if 2 * i <= n {
            i as f64
        } else {
            i as f64 - n as f64
        };
        signed * spacing[a]
    })
}

/// Whether a random Jones field's stationary process is real (e.g. permittivity fluctuations)
/// or complex circular (random phases). Both give the same `⟨𝓜⟩`, which involves `⟨u u*⟩` only.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fluctuation {
    /// Real Gaussian processes (two per complex draw).
    Real,
    /// Complex circular Gaussian processes.
    Complex,
}

/// A generator of locally-stationary random Jones fields: slowly varying mean Jones fields
/// times independent stationary Gaussian processes of a known autocorrelation (S2.7–S2.8).
///
/// # Formula
/// ```text
/// J(p) = Σ_t J̄_t(p) u_t(p),   u_t independent draws of a StationaryField (covariance c)
/// S2.7:  ⟨𝓜(p₁, p₂)⟩ = c(p₁ − p₂) Σ_t 𝓜[J̄_t(p₁), J̄_t(p₂)]         (exact; 𝓜 of S1.7)
/// ```
/// This is S2.8's `m̄((p₁ + p₂)/2) R(p₁ − p₂)` to first order when the `J̄_t` vary slowly over
/// the correlation length, and **exactly** for Gaussian windows of one shape W,
/// `J̄_t(p) = e^{−¼(p − c_t)ᵀW⁻¹(p − c_t)} J_t` (Silverman 1957), because
/// `e^{−¼ p₁ᵀW⁻¹p₁} e^{−¼ p₂ᵀW⁻¹p₂} = g^W(ζ) e^{−⅛ ξᵀW⁻¹ξ}` (centred at `c_t`):
/// ```text
/// m̄(ζ) = Σ_t g^W(ζ − c_t) Mueller(J_t),   R(ξ) = c(ξ) e^{−⅛ ξᵀW⁻¹ξ}
/// ```
/// ([`crate::matter::GaussianWindow`]s summed in a `Vec`). Several terms at one centre give a
/// depolarizing `m̄` (any Cloude-realizable Mueller matrix is a sum of at most four
/// `Mueller(J_t)`).
///
/// # Examples
/// ```
/// use gmueller::jones::JonesMatrix;
/// use gmueller::matter::{Fluctuation, JonesFieldGenerator, StationaryField};
/// use nalgebra::Vector3;
///
/// let field = StationaryField::new([16, 16, 16], [0.1; 3],
///     |xi: &Vector3<f64>| (-0.5 * xi.norm_squared() / 0.01).exp())?;
/// // One term: a polarizer in a Gaussian window of W = 0.3² I.
/// let mut generator = JonesFieldGenerator::new(field, 1, |_, p: &Vector3<f64>| {
///     JonesMatrix::linear_polarizer(0.0).scaled((-0.25 * p.norm_squared() / 0.09).exp().into())
/// }, Fluctuation::Real)?;
/// // Any uniform source in [0, 1) will do; here a 64-bit LCG (Knuth's MMIX constants).
/// let mut state = 1_u64;
/// let mut uniform = move || {
///     state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
///     (state >> 11) as f64 / (1_u64 << 53) as f64
/// };
/// let mut j = vec![JonesMatrix::identity(); generator.len()];
/// generator.sample(&mut uniform, &mut j);
/// assert_eq!(j[100].matrix()[(1, 1)].norm(), 0.0); // a polarizer everywhere
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct JonesFieldGenerator<const N: usize> {
    field: StationaryField<N>,
    terms: usize,
    /// `J̄_t(p_j)` at `t · len + j`.
    means: Vec<Matrix2<C>>,
    fluctuation: Fluctuation,
    draw: Vec<C>,
}

impl<const N: usize> JonesFieldGenerator<N> {
    /// A generator of `terms` terms; `mean(t, p)` is `J̄_t(p)`, evaluated once at every grid
    /// point of `field`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for `terms = 0`; [`Error::NonFinite`] if a mean Jones matrix is
    /// not finite.
    pub fn new(
        field: StationaryField<N>,
        terms: usize,
        mean: impl Fn(usize, &SVector<f64, N>) -> JonesMatrix<f64>,
        fluctuation: Fluctuation,
    ) -> Result<Self, Error> {
        if terms == 0 {
            return Err(Error::OutOfRange {
                what: "number of terms",
                value: 0.0,
                expected: "≥ 1",
            });
        }
        let len = field.len();
        let mut means = Vec::with_capacity(terms * len);
        for t in 0..terms {
            for j in 0..len {
                let m = mean(t, &field.position(j)).0;
                if !m.iter().all(|z| z.re.is_finite() && z.im.is_finite()) {
                    return Err(Error::NonFinite {
                        what: "mean Jones matrix",
                    });
                }
                means.push(m);
            }
        }
        Ok(Self {
            draw: vec![C::new(0.0, 0.0); len],
            field,
            terms,
            means,
            fluctuation,
        })
    }

    /// The number of grid points.
    #[must_use]
    pub fn len(&self) -> usize {
        self.field.len()
    }

    /// Always `false`.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.field.is_empty()
    }

    /// The stationary field (grid, positions, covariance).
    #[must_use]
    pub fn field(&self) -> &StationaryField<N> {
        &self.field
    }

    /// One realization `J(p_j)` at every grid point into `out`.
    ///
    /// # Panics
    /// If `out.len() != len()` (a caller bug).
    pub fn sample(&mut self, uniform: &mut impl FnMut() -> f64, out: &mut [JonesMatrix<f64>]) {
        let len = self.len();
        assert_eq!(out.len(), len, "output of the wrong length");
        for o in out.iter_mut() {
            o.0 = Matrix2::zeros();
        }
        let mut t = 0;
        while t < self.terms {
            match self.fluctuation {
                Fluctuation::Complex => {
                    self.field.sample_complex(uniform, &mut self.draw);
                    self.accumulate(t, |u| u, out);
                    t += 1;
                }
                Fluctuation::Real => {
                    self.field.sample_real_pair(uniform, &mut self.draw);
                    self.accumulate(t, |u| C::new(u.re, 0.0), out);
                    if t + 1 < self.terms {
                        self.accumulate(t + 1, |u| C::new(u.im, 0.0), out);
                    }
                    t += 2;
                }
            }
        }
    }

    /// `out_j += J̄_t(p_j) pick(u_j)`.
    fn accumulate(&self, t: usize, pick: impl Fn(C) -> C, out: &mut [JonesMatrix<f64>]) {
        let len = self.len();
        let means = &self.means[t * len..(t + 1) * len];
        for ((o, m), u) in out.iter_mut().zip(means).zip(&self.draw) {
            o.0 += m * pick(*u);
        }
    }

    /// The exact ensemble mean of the draws' generalized Mueller matrix between grid points
    /// `j` and `l` (S2.7): `c(p_j − p_l) Σ_t 𝓜[J̄_t(p_j), J̄_t(p_l)]`.
    ///
    /// # Panics
    /// If an index is `≥ len()` (a caller bug).
    #[must_use]
    pub fn expected_mueller(&self, j: usize, l: usize) -> GeneralizedMueller<f64> {
        let len = self.len();
        let c = self.field.covariance(j, l);
        let mut sum = nalgebra::Matrix4::zeros();
        for t in 0..self.terms {
            let a = JonesMatrix(self.means[t * len + j]);
            let b = JonesMatrix(self.means[t * len + l]);
            sum += GeneralizedMueller::from_jones_pair(&a, &b).0;
        }
        GeneralizedMueller(sum * C::new(c, 0.0))
    }
}
