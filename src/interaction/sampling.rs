//! Importance sampling of the wave BSDF (the main paper's "Importance sampling"): one proposal
//! lobe per
//! (material, incident direction, wavelength) that serves every packet, with `sample` and `pdf`
//! that agree exactly.
//!
//! **Renderers: use [`crate::bsdf`] instead.** This sampler tabulates an angular CDF at
//! construction (about a thousand kernel-sized evaluations, ~50 µs, on the heap), targets only
//! the scattered part of the reflection side (not the coherent specular lobe, which under
//! sunlight carries most of the energy), and samples exit directions only. The renderer layer's
//! [`crate::bsdf::LobeSampler`] draws every lobe of both sides in closed form from the packet's
//! own coherence, in either tracing direction, for a few hundred nanoseconds and no allocation.
//! This one stays as the main paper's maximally-incoherent proposal (one table for all packets
//! of a minimum width), with its tests.
//!
//! # Formula (the proposal and its Jacobians)
//! ```text
//! u = r̂_t = (r̂·t̂₁, r̂·t̂₂) ∈ unit disk,  c = −ŝ_t     (projected-disk coordinates; h_t = k(u − c))
//! d²u = cos θ_o dω            ⇒  p_ω(r̂) = p_u(u) cos θ_o                  (J1: disk → solid angle)
//! d²h_t = k² d²u              ⇒  p_u(u) = k² p_h(h_t)                        (J2: h space → disk)
//! u = c + L z (L lower △)     ⇒  p_u(u) = p_z(z) / |L|                       (J3: whitening)
//! z = ρ (cos ψ, sin ψ)        ⇒  p_z(z) = p(ψ, ρ) / ρ                        (J4: polar about c)
//! p_z(z) = q(|z|) / m  inside the disk,   m = (2π)⁻¹ ∫₀^{2π} F(ρ_max(ψ)) dψ   (truncation)
//! ```
//! with `q` an isotropic unit-mass profile in `z` and `F` its radial CDF:
//! ```text
//! Gaussian:  q(ρ) = e^{−ρ²/2} / (2π),                  F(ρ) = 1 − e^{−ρ²/2}
//! Power:     q(ρ) = (γ−1)/(2π) (1 + ρ²)^{−(γ+1)/2},    F(ρ) = 1 − (1 + ρ²)^{−(γ−1)/2}
//! ρ_max(ψ):  the positive root of |d|²ρ² + 2 (c·d) ρ − (1 − |c|²) = 0,  d = L (cos ψ, sin ψ)
//! ```
//! (the disk is convex and contains `c`, so every ray from `c` leaves it once, at `ρ_max`).
//!
//! # Lobes
//! The kernel's scattered weight at coherence `Ξ` is `∝ (p * g^Ξ)(h_t)` (S2.20). For a packet
//! with transverse coherence `Θ⊥ ⪰ w² I` and `σ_zz ≥ w`, `Ξ = Aᵀ Θ⊥⁻¹ A + b bᵀ/σ_zz² ⪯ I/w²`
//! (as `AᵀA = I − b bᵀ`), so the *maximally incoherent* lobe is the blur by `Ξ_max = I/w_min²`
//! (isotropic: the `cos² θ_i` narrowing in the plane of incidence is deliberately not used, which
//! keeps the bound valid for any `σ_zz ≥ w_min`).
//! - [`GaussianPsd`] with spectral covariance `C_p`: the blurred lobe is Gaussian, covariance
//!   `C_h = C_p + Ξ_max` in `h_t`, i.e. `L Lᵀ = C_h / k²` in `u`.
//! - [`KCorrelation`]: the PSD's own radial lobe (Holzschuch & Pacanowski 2017), the power
//!   profile with `L = I/(k√T)`, mixed with weight ½ with the Gaussian lobe
//!   `C_h = I/((γ+1)T) + Ξ_max` (the curvature of `p` at 0 plus the blur), so that broad
//!   incoherent packets are covered too. A mixture's pdf is the weighted sum of the truncated
//!   component pdfs, each normalised by its own exact mass.
//!
//! Packets narrower than `w_min` (more incoherent) are still sampled without bias — every lobe
//! has full support on the disk — only with a larger variance.
//!
//! # Sampling (two uniforms, no rejection)
//! `ψ` is drawn by inverting its marginal CDF `∫ F(ρ_max) dψ / (2π m)`, tabulated at
//! construction on adaptive panels, each holding the degree-16 Chebyshev interpolant of
//! `F(ρ_max(ψ))` (accepted when its error is below `1e-13 · max F(ρ_max)`); its integral is the
//! mass `m` (Clenshaw–Curtis, the same to that tolerance). Within a panel the CDF is the
//! interpolant's antiderivative, inverted by safeguarded Newton. Then `ρ = F⁻¹(v F(ρ_max(ψ)))` in
//! closed form. The density of the returned direction is therefore `pdf` up to the tabulation
//! error (≤ 1e-13 relative to the peak, far below any Monte Carlo resolution); `Sample::pdf` is
//! `pdf(direction)` itself, so the two agree to the last bit.
//!
//! # The unit interval's endpoint
//! Both inversions take their uniform in `[0, 1)`: an input is clamped into `[0, 1 − ε/2]`
//! (the largest `T` below 1; NaN becomes 0). `v = 1` would be the truncation boundary
//! `ρ = ρ_max`, the horizon, where `p_ω = 0`: for every lobe whose mass inside the disk rounds
//! to 1 (`F⁻¹(1) = ∞`, clamped to the boundary) `[v, 1]` drew a horizon direction with
//! `pdf = 0`. From `1 − ε/2` the radial draw stays at `1 − F ≥ ε/2`, where the density is a
//! normal number. A draw that rounding still puts within a few ulps of the horizon is pulled in
//! by a few ulps, so `pdf > 0` for every sample.

use nalgebra::{Matrix2, Vector2, Vector3};

use super::coherence::CoherenceWeights;
use super::polarization::{KernelOutput, PolarizationModel, Response};
use super::{Geometry, Kernel, Surface};
use crate::error::Error;
use crate::frame::Frame;
use crate::numerics::chebyshev::{CdfTable, TableError};
use crate::psd::{GaussianPsd, KCorrelation};
use crate::real::Real;

/// Interpolation tolerance relative to the peak of `F(ρ_max(ψ))`.
const TABLE_TOL: f64 = 1e-13;
/// The most panels a table may use.
const MAX_PANELS: usize = 1 << 14;
/// The narrowest lobe a sampler accepts, in machine epsilons of the scalar type (see
/// [`ScatterSampler::gaussian`]).
const MIN_WIDTH_ULPS: f64 = 8.0;
/// The weight of the K-correlation lobe in its mixture with the Gaussian (incoherent) lobe.
pub const K_CORRELATION_LOBE_WEIGHT: f64 = 0.5;

/// The radial profile of a lobe in whitened coordinates `z` (see the module formula).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RadialProfile<T: Real> {
    /// `q(ρ) = e^{−ρ²/2}/(2π)`.
    Gaussian,
    /// `q(ρ) = (γ−1)/(2π) (1 + ρ²)^{−(γ+1)/2}`, `γ > 1` (the K-correlation PSD's shape).
    Power {
        /// The exponent `γ`.
        gamma: T,
    },
}

/// One direction drawn by [`ScatterSampler::sample`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample<T: Real> {
    /// The exit direction r̂ (unit, world coordinates, strictly above the surface).
    pub direction: Vector3<T>,
    /// Its density per unit solid angle, `== ScatterSampler::pdf(direction)`.
    pub pdf: T,
}

/// A sample together with the kernel's response `R` (the output of the kernel's polarization
/// level) and the Monte Carlo weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WeightedSample<T: Real, R = Response<T>> {
    /// The exit direction and its pdf per solid angle.
    pub sample: Sample<T>,
    /// The kernel evaluated at the sample.
    pub response: R,
    /// `response / pdf` (both parts): an unbiased estimate of `∫ L_o dω` over the hemisphere.
    pub weight: R,
}

/// `value / pdf`, the Monte Carlo weight of one sample (`0` when `pdf` is `0`, where the
/// proposal has no mass and so nothing is ever drawn).
///
/// # Examples
/// ```
/// use gmueller::interaction::sampling::weight;
/// assert!((weight(3.0_f64, 1.5) - 2.0).abs() < 1e-15);
/// assert_eq!(weight(0.0_f64, 0.0), 0.0);
/// ```
#[inline]
#[must_use]
pub fn weight<T: Real>(value: T, pdf: T) -> T {
    if pdf > T::zero() {
        value / pdf
    } else {
        T::zero()
    }
}

/// A radially symmetric lobe in whitened coordinates, truncated to the unit disk.
#[derive(Debug, Clone, PartialEq)]
pub struct TruncatedLobe<T: Real> {
    profile: RadialProfile<T>,
    centre: Vector2<T>,
    /// Lower-triangular `L` as (l₀₀, l₁₀, l₁₁).
    l: [T; 3],
    /// `1 − |c|² = cos² θ_i`.
    inside: T,
    /// Exact truncated mass `m`.
    mass: T,
    /// `ln(q-normalisation / (m |L|))`.
    log_norm: T,
    /// `(γ − 1)/2` and `−(γ + 1)/2` for the power profile.
    exps: (T, T),
    /// The angular CDF `∫ F(ρ_max(ψ)) dψ` on `[0, 2π)`.
    table: CdfTable<T>,
}

/// Radial CDF `F(ρ)` (f64 or T), from `ρ²`.
#[inline]
fn radial_cdf<T: Real>(profile: &RadialProfile<T>, half_exp: T, rho2: T) -> T {
    match profile {
        // 1 − e^{−ρ²/2}, expm1 for small ρ.
        RadialProfile::Gaussian => -(-rho2 * T::lit(0.5)).exp_m1(),
        // 1 − (1 + ρ²)^{−(γ−1)/2}.
        RadialProfile::Power { .. } => -(-half_exp * rho2.ln_1p()).exp_m1(),
    }
}

/// `ρ²` with `F(ρ) = t` (the closed-form inverse radial CDF).
#[inline]
fn radial_cdf_inverse_sq<T: Real>(profile: &RadialProfile<T>, half_exp: T, t: T) -> T {
    match profile {
        // ρ² = −2 ln(1 − t).
        RadialProfile::Gaussian => -T::lit(2.0) * (-t).ln_1p(),
        // ρ² = (1 − t)^{−2/(γ−1)} − 1.
        RadialProfile::Power { .. } => (-(-t).ln_1p() / half_exp).exp_m1(),
    }
}

impl<T: Real> TruncatedLobe<T> {
    /// Builds the lobe `u = c + L z`, `z ~ q`, truncated to the unit disk (f64 internally).
    fn new(
        profile: RadialProfile<T>,
        centre: Vector2<f64>,
        l: [f64; 3],
        inside: f64,
    ) -> Result<Self, Error> {
        let (half_exp, neg_exp, norm_q) = match profile {
            RadialProfile::Gaussian => (0.0, 0.0, 1.0 / core::f64::consts::TAU),
            RadialProfile::Power { gamma } => {
                let g = gamma.to_f64();
                (
                    0.5 * (g - 1.0),
                    -0.5 * (g + 1.0),
                    (g - 1.0) / core::f64::consts::TAU,
                )
            }
        };
        let prof64: RadialProfile<f64> = match profile {
            RadialProfile::Gaussian => RadialProfile::Gaussian,
            RadialProfile::Power { gamma } => RadialProfile::Power {
                gamma: gamma.to_f64(),
            },
        };
        // The lobe's width in u (|det L|/‖L‖_F ≤ the smallest singular value of L, times the
        // profile's own width, 1/√(γ + 1) for the power profile) must resolve on the disk's
        // float grid (spacing ≤ ε): a narrower lobe puts every representable direction but its
        // centre so many widths out that its density underflows to 0.
        let profile_width = match prof64 {
            RadialProfile::Gaussian => 1.0,
            RadialProfile::Power { gamma } => (gamma + 1.0).sqrt().recip(),
        };
        let frob = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
        let width = (l[0] * l[2]).abs() / frob * profile_width;
        if width.is_nan() || width < MIN_WIDTH_ULPS * T::EPSILON.to_f64() {
            return Err(Error::Unrealizable {
                reason: "sampling lobe narrower than 8ε in the projected disk (not resolvable \
                         in the scalar type): use a smaller minimum coherence width, or f64",
            });
        }
        let a = |psi: f64| {
            let rho = rho_max(&centre, &l, inside, psi);
            radial_cdf(&prof64, half_exp, rho * rho)
        };
        let table = CdfTable::build(
            &a,
            (0.0, core::f64::consts::TAU),
            TABLE_TOL,
            1e-11,
            MAX_PANELS,
        )
        .map_err(|e| Error::Unrealizable {
            reason: match e {
                TableError::NoMass => "sampling lobe has no mass on the hemisphere",
                TableError::TooManyPanels => "sampling table did not converge within 16384 panels",
            },
        })?;
        let total = table.total();
        let mass = total / core::f64::consts::TAU;
        if !(mass.is_finite() && mass > 0.0) {
            return Err(Error::Unrealizable {
                reason: "sampling lobe has no mass on the hemisphere",
            });
        }
        let det_l = l[0] * l[2];
        let log_norm = norm_q.ln() - mass.ln() - det_l.ln();
        // Everything the sampler evaluates in T must be a finite T (f32: a lobe wider than
        // 3e38, or γ above 3e38, is not).
        let in_t = [l[0], l[1], l[2], mass, total, log_norm, half_exp, neg_exp];
        if !in_t.iter().all(|&x| T::lit(x).is_finite()) {
            return Err(Error::Unrealizable {
                reason: "sampling lobe not representable in the scalar type (width or exponent \
                         overflows)",
            });
        }
        Ok(Self {
            profile,
            centre: centre.map(T::lit),
            l: l.map(T::lit),
            inside: T::lit(inside),
            mass: T::lit(mass),
            log_norm: T::lit(log_norm),
            exps: (T::lit(half_exp), T::lit(neg_exp)),
            table: table.to_precision(),
        })
    }

    /// The truncated mass `m`: the fraction of the untruncated lobe inside the unit disk.
    #[must_use]
    pub fn truncated_mass(&self) -> T {
        self.mass
    }

    /// The centre `c = −ŝ_t` in disk coordinates.
    #[must_use]
    pub fn centre(&self) -> Vector2<T> {
        self.centre
    }

    /// The whitening matrix `L` (lower triangular, `u = c + L z`).
    #[must_use]
    pub fn whitening(&self) -> Matrix2<T> {
        Matrix2::new(self.l[0], T::zero(), self.l[1], self.l[2])
    }

    /// The radial profile.
    #[must_use]
    pub fn profile(&self) -> RadialProfile<T> {
        self.profile
    }

    /// The number of panels of the angular CDF table.
    #[must_use]
    pub fn table_size(&self) -> usize {
        self.table.len()
    }

    /// The density per unit disk area at `u` (`0` outside the open unit disk).
    #[must_use]
    pub fn disk_pdf(&self, u: &Vector2<T>) -> T {
        if u.norm_squared() >= T::one() {
            return T::zero();
        }
        let (l00, l10, l11) = (self.l[0], self.l[1], self.l[2]);
        // J3: z = L⁻¹ (u − c).
        let z0 = (u.x - self.centre.x) / l00;
        let z1 = (u.y - self.centre.y - l10 * z0) / l11;
        let rho2 = z0 * z0 + z1 * z1;
        let log_q = match self.profile {
            RadialProfile::Gaussian => -T::lit(0.5) * rho2,
            RadialProfile::Power { .. } => self.exps.1 * rho2.ln_1p(),
        };
        (self.log_norm + log_q).exp()
    }

    /// Draws `u` in the disk from two uniforms (see the module docs).
    fn sample_disk(&self, v0: T, v1: T) -> Vector2<T> {
        let psi = self.table.invert(clamp01(v0) * self.table.total());
        let tol = T::lit(4.0) * T::EPSILON;
        let (s, c) = psi.sin_cos();
        let l = &self.l;
        let d = Vector2::new(l[0] * c, l[1] * c + l[2] * s);
        let rho_m = rho_max(&self.centre, l, self.inside, psi);
        let f_m = radial_cdf(&self.profile, self.exps.0, rho_m * rho_m);
        let rho2 = radial_cdf_inverse_sq(&self.profile, self.exps.0, clamp01(v1) * f_m);
        let rho = rho2.max(T::zero()).sqrt().min(rho_m * (T::one() - tol));
        let mut u = self.centre + d * rho;
        let n2 = u.norm_squared();
        if n2 > T::one() - tol {
            // Rounding put the draw on the horizon: pull it in by a few ulps.
            u *= ((T::one() - tol) / n2).sqrt();
        }
        u
    }
}

/// A uniform clamped into `[0, 1⁻]`, `1⁻ = 1 − ε/2` the largest `T` below 1 (NaN → 0): the
/// inverse CDFs are defined on `[0, 1)`, whose image is the open support (the endpoint 1 is the
/// truncation boundary, the horizon, where `p_ω = cos θ_o p_u = 0`).
#[inline]
fn clamp01<T: Real>(v: T) -> T {
    v.max(T::zero()).min(T::one() - T::lit(0.5) * T::EPSILON)
}

/// The distance along `d = L (cos ψ, sin ψ)` from `c` to the unit circle, in units of `|d|`
/// steps: the positive root of `|d|²ρ² + 2(c·d)ρ − (1 − |c|²) = 0`, in its cancellation-free form.
#[inline]
fn rho_max<T: Real>(c: &Vector2<T>, l: &[T; 3], inside: T, psi: T) -> T {
    let (s, co) = psi.sin_cos();
    let d = Vector2::new(l[0] * co, l[1] * co + l[2] * s);
    let a = d.norm_squared();
    let b = c.dot(&d);
    let root = (b * b + a * inside).sqrt();
    if b >= T::zero() {
        inside / (b + root)
    } else {
        (root - b) / a
    }
}

/// An importance sampler for the wave BSDF at one incident direction (see the module docs).
///
/// Built once per (PSD, incident direction, surface frame, wavenumber, minimum coherence
/// width); [`ScatterSampler::sample`] and [`ScatterSampler::pdf`] allocate nothing.
///
/// # Examples
/// ```
/// use gmueller::frame::Frame;
/// use gmueller::interaction::sampling::ScatterSampler;
/// use gmueller::psd::GaussianPsd;
/// use nalgebra::Vector3;
///
/// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
/// let to_source = Vector3::new(-0.5_f64, 0.0, 0.75_f64.sqrt()); // 30° incidence
/// let psd = GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap();
/// let k = std::f64::consts::TAU / 0.5;
/// let sampler = ScatterSampler::gaussian(&psd, &surface, &to_source, k, 1.0).unwrap();
/// let s = sampler.sample([0.3, 0.7]);
/// assert!(s.direction.z > 0.0 && (s.direction.norm() - 1.0).abs() < 1e-12);
/// assert!((sampler.pdf(&s.direction) - s.pdf).abs() <= 1e-12 * s.pdf);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ScatterSampler<T: Real> {
    surface: Frame<T>,
    /// Components and their mixture weights (cumulative weights for selection).
    components: Vec<(T, TruncatedLobe<T>)>,
}

/// Validated `(c, 1 − |c|², k, 1/w_min²)` in f64.
fn common_setup<T: Real>(
    surface: &Frame<T>,
    to_source: &Vector3<T>,
    k: T,
    min_coherence_width: T,
) -> Result<(Vector2<f64>, f64, f64, f64), Error> {
    crate::error::ensure_finite("direction to the source", to_source.iter().copied())?;
    let s = to_source.map(Real::to_f64);
    // Where |s|² would leave the normal range (a component below ~1e-154 or above ~1e154),
    // the shared normaliser rescales by the largest component first: a subnormal square loses
    // its digits, and the "unit" vector came out 1.0001 long (regression seed de4db7 of
    // tests/bad_input.rs: a lobe centre outside the disk, samples with pdf 0). In the normal
    // range the plain division is kept (the sampler's outputs are unchanged bit for bit).
    let n2 = s.norm_squared();
    let s = if (f64::MIN_POSITIVE / f64::EPSILON..=f64::MAX / 4.0).contains(&n2) {
        s / n2.sqrt()
    } else {
        crate::numerics::unit_by_largest(&s).ok_or(Error::InvalidBasis {
            reason: "zero direction vector",
        })?
    };
    let (t1, t2, n) = (
        surface.x().map(Real::to_f64),
        surface.y().map(Real::to_f64),
        surface.k().map(Real::to_f64),
    );
    let cos_i = s.dot(&n);
    if !(cos_i > 0.0 && cos_i.is_finite()) {
        return Err(Error::OutOfRange {
            what: "cos θ_i (source below the surface)",
            value: cos_i,
            expected: "> 0",
        });
    }
    let k = k.to_f64();
    if !(k.is_finite() && k > 0.0) {
        return Err(Error::OutOfRange {
            what: "wavenumber",
            value: k,
            expected: "(0, ∞)",
        });
    }
    let w = min_coherence_width.to_f64();
    if w.is_nan() || w <= 0.0 {
        return Err(Error::OutOfRange {
            what: "minimum coherence width",
            value: w,
            expected: "(0, ∞]",
        });
    }
    // c = −ŝ_t: h_t = k (u + ŝ_t) vanishes there (the specular direction).
    let c = Vector2::new(-s.dot(&t1), -s.dot(&t2));
    Ok((c, cos_i * cos_i, k, 1.0 / (w * w)))
}

/// The Gaussian lobe with covariance `C_h` in `h_t`, i.e. `C_h / k²` in `u`.
fn gaussian_lobe<T: Real>(
    c: Vector2<f64>,
    inside: f64,
    k: f64,
    cov_h: [f64; 3],
) -> Result<TruncatedLobe<T>, Error> {
    let k2 = k * k;
    let (a, b, d) = (cov_h[0] / k2, cov_h[1] / k2, cov_h[2] / k2);
    if !(a > 0.0 && a * d - b * b > 0.0 && a.is_finite() && d.is_finite()) {
        return Err(Error::NotPositiveDefinite {
            what: "sampling lobe covariance",
            min_eigenvalue: a.min(a * d - b * b),
        });
    }
    let l00 = a.sqrt();
    let l10 = b / l00;
    let l11 = (d - l10 * l10).sqrt();
    TruncatedLobe::new(RadialProfile::Gaussian, c, [l00, l10, l11], inside)
}

impl<T: Real> ScatterSampler<T> {
    /// The sampler for a Gaussian PSD: the truncated Gaussian of covariance
    /// `(C_p + I/w_min²)/k²` about `c = −ŝ_t` in the projected disk.
    ///
    /// # Formula
    /// ```text
    /// p_ω(r̂) = cos θ_o · 𝒩(u; c, (C_p + I/w_min²)/k²) / m,    u = r̂_t,  c = −ŝ_t
    /// ```
    /// `C_p` the PSD's spectral covariance (rad²/length²), `k` the wavenumber (rad/length),
    /// `w_min` the smallest coherence width served efficiently (length; `∞` for plane waves
    /// only), `to_source` ŝ (need not be unit), `surface` the frame (t̂₁, t̂₂, n̂).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for `ŝ·n̂ ≤ 0`, `k ≤ 0` or `w_min ≤ 0`; [`Error::NonFinite`],
    /// [`Error::InvalidBasis`] for a bad ŝ; [`Error::NotPositiveDefinite`] if the lobe
    /// covariance under- or overflows; [`Error::Unrealizable`] if the table does not converge,
    /// or if the lobe is narrower than `8ε` (machine epsilons of `T`) in the projected disk —
    /// too narrow for the float grid of directions there, so that drawn directions would have
    /// `pdf = 0` (f64: widths below 1.8e-15, i.e. `1/(k ℓ)` for `ℓ` above ~10¹⁴ λ; f32: below
    /// 9.5e-7, `ℓ` above ~1.7·10⁵ λ), or too wide for `T` (f32: a width `√(1/w_min²)/k` above
    /// `f32::MAX`).
    pub fn gaussian(
        psd: &GaussianPsd<T, 2>,
        surface: &Frame<T>,
        to_source: &Vector3<T>,
        k: T,
        min_coherence_width: T,
    ) -> Result<Self, Error> {
        let (c, inside, k, xi) = common_setup(surface, to_source, k, min_coherence_width)?;
        let cp = psd.spectral_shape().covariance().map(Real::to_f64);
        let cov_h = [
            cp[(0, 0)] + xi,
            0.5 * (cp[(0, 1)] + cp[(1, 0)]),
            cp[(1, 1)] + xi,
        ];
        let lobe = gaussian_lobe(c, inside, k, cov_h)?;
        Ok(Self {
            surface: *surface,
            components: vec![(T::one(), lobe)],
        })
    }

    /// The sampler for a K-correlation PSD: the PSD's radial lobe mixed (weight
    /// [`K_CORRELATION_LOBE_WEIGHT`]) with a maximally incoherent Gaussian lobe.
    ///
    /// # Formula
    /// ```text
    /// p_ω = cos θ_o [ ½ q_K(u)/m_K + ½ 𝒩(u; c, (I/((γ+1)T) + I/w_min²)/k²)/m_G ]
    /// q_K(u) = k²T (γ−1)/(2π) (1 + k²T |u − c|²)^{−(γ+1)/2}      (= p(h_t)/∫p · k², J2)
    /// ```
    /// Arguments as in [`ScatterSampler::gaussian`].
    ///
    /// # Errors
    /// As [`ScatterSampler::gaussian`].
    pub fn k_correlation(
        psd: &KCorrelation<T, 2>,
        surface: &Frame<T>,
        to_source: &Vector3<T>,
        k: T,
        min_coherence_width: T,
    ) -> Result<Self, Error> {
        let (c, inside, k, xi) = common_setup(surface, to_source, k, min_coherence_width)?;
        let (t, gamma) = (psd.t().to_f64(), psd.gamma().to_f64());
        // J2: h = k (u − c) with p(h) ∝ (1 + T|h|²)^{−ν}  ⇒  z = k√T (u − c).
        let scale = 1.0 / (k * t.sqrt());
        let power = TruncatedLobe::new(
            RadialProfile::Power { gamma: psd.gamma() },
            c,
            [scale, 0.0, scale],
            inside,
        )?;
        let core = 1.0 / ((gamma + 1.0) * t);
        let gauss = gaussian_lobe(c, inside, k, [core + xi, 0.0, core + xi])?;
        let w = T::lit(K_CORRELATION_LOBE_WEIGHT);
        Ok(Self {
            surface: *surface,
            components: vec![(w, power), (T::one() - w, gauss)],
        })
    }

    /// The mixture components and their weights.
    pub fn components(&self) -> impl Iterator<Item = (T, &TruncatedLobe<T>)> {
        self.components.iter().map(|(w, l)| (*w, l))
    }

    /// The surface frame (t̂₁, t̂₂, n̂) the sampler was built for.
    #[must_use]
    pub fn surface(&self) -> &Frame<T> {
        &self.surface
    }

    /// The density per unit disk area at `u = r̂_t` (`0` outside the open unit disk).
    #[must_use]
    pub fn disk_pdf(&self, u: &Vector2<T>) -> T {
        self.components
            .iter()
            .fold(T::zero(), |acc, (w, l)| acc + *w * l.disk_pdf(u))
    }

    /// The density per unit solid angle of exit direction `direction` (normalised here);
    /// `0` at or below the horizon.
    ///
    /// # Formula
    /// ```text
    /// p_ω(r̂) = cos θ_o · Σⱼ wⱼ p_u,j(r̂_t)          (J1; p_u,j as in the module formula)
    /// ```
    #[must_use]
    pub fn pdf(&self, direction: &Vector3<T>) -> T {
        let n = direction.norm();
        if !(n > T::zero() && n.is_finite()) {
            return T::zero();
        }
        let r = direction / n;
        let cos_o = r.dot(&self.surface.k());
        if !(cos_o > T::zero() && cos_o.is_finite()) {
            return T::zero();
        }
        let u = Vector2::new(r.dot(&self.surface.x()), r.dot(&self.surface.y()));
        cos_o * self.disk_pdf(&u)
    }

    /// Draws an exit direction from two uniforms `u ∈ [0, 1)²`, exactly from
    /// [`ScatterSampler::pdf`] (see the module docs). For a mixture the first uniform also
    /// selects the component (and is rescaled).
    ///
    /// Every input is accepted without panic: each uniform is clamped into `[0, 1 − ε/2]`
    /// (values above, including 1 and `+∞`, act as the largest `T` below 1; values below 0,
    /// `−∞` and NaN as 0). The result is always a finite unit direction strictly above the
    /// surface with `pdf` finite and `> 0`, equal to [`ScatterSampler::pdf`] of it.
    #[must_use]
    pub fn sample(&self, u: [T; 2]) -> Sample<T> {
        let mut v0 = clamp01(u[0]);
        let last = self.components.len() - 1;
        let mut chosen = &self.components[last].1;
        let mut acc = T::zero();
        for (j, (w, lobe)) in self.components.iter().enumerate() {
            if v0 < acc + *w || j == last {
                // Reuse the first uniform within the chosen component.
                v0 = clamp01((v0 - acc) / *w);
                chosen = lobe;
                break;
            }
            acc += *w;
        }
        let d = chosen.sample_disk(v0, u[1]);
        let cos_o = (T::one() - d.norm_squared()).max(T::zero()).sqrt();
        let f = &self.surface;
        let direction = f.x() * d.x + f.y() * d.y + f.k() * cos_o;
        Sample {
            direction,
            pdf: self.pdf(&direction),
        }
    }

    /// Draws a direction and evaluates `kernel` there: the weight `response.total()/pdf`.
    ///
    /// `packet` must arrive from the direction and at the wavenumber the sampler was built
    /// for. With the [`super::PlaneWave`] model the specular delta is not part of
    /// `response` (it has to be handled by the caller). `None` only if the geometry is
    /// rejected ([`Geometry::for_packet`], e.g. a packet arriving from below).
    #[must_use]
    pub fn sample_weighted<Pol, Coh, S>(
        &self,
        kernel: &Kernel<Pol, Coh>,
        material: &S,
        packet: &crate::packet::WavePacket<T>,
        u: [T; 2],
    ) -> Option<WeightedSample<T, Pol::Output<T>>>
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, S::Psd>,
        S: Surface<T>,
    {
        let sample = self.sample(u);
        let g = Geometry::for_packet(packet, &self.surface, sample.direction).ok()?;
        let response = kernel.evaluate(material, packet, &g);
        Some(WeightedSample {
            sample,
            response,
            weight: response.scaled(weight(T::one(), sample.pdf)),
        })
    }
}
