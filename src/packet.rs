//! The canonical wave packet (the paper's Definition 3.1): a classical Stokes vector together with
//! the Gaussian shapes of its spatial coherence.
//!
//! # Formula
//! ```text
//! L(ξ) = e^{i k ξ_z} [ S_x g^{Θ_x}(ξ) (1, 1, 0, 0) + S_y g^{Θ_y}(ξ) (1, −1, 0, 0)
//!                      + √(S_x S_y) g^{Θ_½}(ξ) (0, 0, χ, ς) ]
//! Θ_α = blockdiag(Θ⊥_α, σ_zz²),   Θ_½ = (Θ_x + Θ_y)/2,   μ = (χ + i ς)/2,   |μ| ≤ 1
//! ```
//! where ξ is a separation in the packet frame (x̂, ŷ, k̂) (k̂ the propagation direction),
//! `Θ⊥_α` the 2×2 transverse coherence covariances (length², a coherence *width* w gives
//! `Θ⊥ = w² I`), `σ_zz` the longitudinal coherence length and `g^Σ(ξ) = exp(−½ ξᵀ Σ⁻¹ ξ)`.
//! At ξ = 0, `L = (S_x + S_y, S_x − S_y, √(S_xS_y) χ, √(S_xS_y) ς)` is a classical Stokes vector:
//! the packet stores that vector and derives `S_x = (S0 + S1)/2`, `S_y = (S0 − S1)/2`,
//! `χ = S2/√(S_xS_y)`, `ς = S3/√(S_xS_y)`, so nothing divides by `√(S_xS_y)` when it vanishes.
//!
//! The complex degree of correlation between the x and y components is
//! `μ = (χ + iς)/2 = (S2 + i S3)/(2 √(S_x S_y))`; in terms of the CSD,
//! `⟨E_x E_y*⟩ = √(S_xS_y) μ*`.
//!
//! # Realizability
//! A packet whose x and y components have different coherence shapes cannot be fully
//! correlated. Bochner's theorem applied to the 2×2 CSD matrix function requires, at every
//! spatial frequency, a positive semidefinite spectral matrix; since `Θ_½` is the mean of `Θ_x`
//! and `Θ_y` the Gaussian factors cancel except at the origin, and the condition is exactly
//! ```text
//! |μ|² ≤ √(|Θ_x| |Θ_y|) / |Θ_½|          (≤ 1, with equality iff Θ_x = Θ_y)
//! ```
//! [`WavePacket::new`] returns [`Error::Unrealizable`] when it is violated (beyond a rounding
//! slack of `64 ε S0²` on `|S2 + iS3|²/4`, and beyond the reach of the shapes' rounding, below)
//! rather than clamping: a clamp would silently change the light's degree of polarization, and
//! the caller (who chose the shapes) is the one who knows whether to shrink `|μ|` or make the
//! shapes equal.
//!
//! **The shapes' rounding.** The bound of nearly singular shapes is ill-conditioned: rounding
//! every entry of `Θ_x`, `Θ_y` by `δ` of itself moves `B = √(|Θ_x||Θ_y|)/|Θ_½|` by up to
//! `K δ B`, `K` [`WavePacket::realizability_conditioning`] (about the anisotropy: `10⁶` for a
//! `10⁶`-anisotropic shape turned by 45°). A renderer's `f32` shapes (rounded from its own
//! numbers, or computed in `f32`) then hold a bound up to ~`K ε₃₂` (12 % at `K = 10⁶`) below the
//! one it meant, and `|μ|` chosen at 0.999 of the intended bound was refused (issue 36: 4 953
//! in-range packets). A packet with `|μ|² ≤ B (1 + 4 K ε)` is therefore accepted — it is
//! realizable for shapes within four ulps per entry of the ones held — and its `S2`, `S3` are
//! scaled onto the bound of the shapes held (`|μ|² = B`), so every packet is realizable for
//! the matrices it carries. Beyond that reach it is refused; for well-conditioned shapes the
//! reach is a few `ε` (`K = 2` for equal isotropic shapes), so `|μ| = √B (1 + 10⁻⁶)` is refused
//! in `f64` (up to `K ≈ 2·10⁹`) and `|μ| = √B (1 + 10⁻³)` in `f32` up to `K ≈ 4000`.
//!
//! # Sources (van Cittert–Zernike)
//! A distant incoherent source with angular radiance profile `I(θ)` (θ the small-angle offset
//! from k̂) gives the degree of coherence `μ(ξ) = ∫ I(θ) e^{i k θ·ξ} d²θ / ∫ I(θ) d²θ`:
//! ```text
//! uniform disk, Ω = π α²:  μ = 2J₁(kα|ξ|)/(kα|ξ|) = 1 − (kα|ξ|)²/8 + …  ⇒  Θ⊥ = 4/(kα)² I = λ²/(πΩ) I
//! area A at distance r:    Ω = A/r²                                    ⇒  Θ⊥ = λ² r²/(π A) I
//! Gaussian, covariance C_θ: μ = exp(−½ k² ξᵀ C_θ ξ)  (exact)            ⇒  Θ⊥ = (k² C_θ)⁻¹
//! ```
//! The disk constant is the Gaussian that matches `μ` in value and curvature at ξ = 0.
//!
//! # Verification (`tests/packet.rs`)
//! - `van_cittert_zernike_uniform_disk`: direct 2-D quadrature over the disk reproduces
//!   `2J₁(x)/x` (series) to 1e-12 and the packet's `−1/w²` matches its curvature at 0 to 1e-6
//!   (Richardson finite differences) for Ω = 6.8·10⁻⁵, 10⁻³, 2·10⁻² sr. At `|ξ| = w` the disk
//!   gives `μ = J₁(2) = 0.5767` against the Gaussian's `e^{−½} = 0.6065` (4.9 % high); the
//!   Gaussian has no zero where the disk's coherence first vanishes (`|ξ| = 1.92 w`).
//!   `sun_coherence_width`: Ω = 6.8·10⁻⁵ sr, λ = 0.5 µm gives `w = 34.2 µm`.
//! - `gaussian_source_against_quadrature`: the Gaussian-source shape against trapezoid
//!   quadrature of the angular spectrum, to 1e-10.
//! - `realizability_matches_bochner`: accepted packets have a positive semidefinite spectral
//!   matrix on a grid of q, rejected ones a negative determinant at q = 0 (3000 random cases);
//!   `realizability_bound_is_sharp`: `|μ| = √B (1 ∓ 10⁻⁶)` accepted / rejected.
//! - `area_source_and_propagation`: `propagate(d)` from distance r equals the same source built
//!   at `r + d`; `rotation_*`: see [`WavePacket::rotated`]; `shape_3d_and_world_precision`
//!   against nalgebra.

use nalgebra::{Matrix2, Matrix3, Vector3};
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::frame::{Frame, rotation_mueller};
use crate::numerics::{
    det2, det2_of_mean, inverse_cholesky_of_mean, inverse_cholesky2, inverse2, pow2_scale,
};
use crate::real::Real;
use crate::stokes::Stokes;

/// Which polarization channel of a packet a shape matrix belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// The x̂ component, weight `S_x (1, 1, 0, 0)`, shape `Θ_x`.
    X,
    /// The ŷ component, weight `S_y (1, −1, 0, 0)`, shape `Θ_y`.
    Y,
    /// The x–y correlation, weight `√(S_xS_y) (0, 0, χ, ς)`, shape `Θ_½ = (Θ_x + Θ_y)/2`.
    Half,
}

/// A validated 2×2 symmetric positive-definite transverse coherence covariance `Θ⊥` (length²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoherenceShape<T: Real>(Matrix2<T>);

impl<T: Real> CoherenceShape<T> {
    /// From a symmetric positive-definite matrix (length²).
    ///
    /// # Errors
    /// [`Error::NonFinite`], [`Error::NotHermitian`] (asymmetric beyond rounding), or
    /// [`Error::NotPositiveDefinite`].
    pub fn new(m: Matrix2<T>) -> Result<Self, Error> {
        validate_spd(m, "coherence shape matrix").map(Self)
    }

    /// An isotropic shape `w² I` for a coherence width `w` (length, the 1/√e radius of the degree
    /// of coherence `exp(−|ξ|²/(2w²))`).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `w` is finite and positive.
    pub fn isotropic(width: T) -> Result<Self, Error> {
        if !(width.is_finite() && width > T::zero()) {
            return Err(Error::OutOfRange {
                what: "coherence width",
                value: width.to_f64(),
                expected: "finite and > 0",
            });
        }
        Self::new(Matrix2::identity() * (width * width))
    }

    /// The covariance matrix `Θ⊥` (length²).
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Matrix2<T> {
        self.0
    }

    /// `|Θ⊥|`.
    #[inline]
    #[must_use]
    pub fn determinant(&self) -> T {
        self.0[(0, 0)] * self.0[(1, 1)] - self.0[(0, 1)] * self.0[(1, 0)]
    }
}

/// Checks that `m` is finite, symmetric up to 64 ε (relative to its largest entry) and positive
/// definite; returns its symmetrized copy.
fn validate_spd<T: Real>(m: Matrix2<T>, what: &'static str) -> Result<Matrix2<T>, Error> {
    ensure_finite(what, m.iter().copied())?;
    let scale = m.amax();
    let asym = (m[(0, 1)] - m[(1, 0)]).abs();
    if asym > T::lit(64.0) * T::EPSILON * scale {
        return Err(Error::NotHermitian {
            what,
            asymmetry: asym.to_f64(),
        });
    }
    let off = (m[(0, 1)] + m[(1, 0)]) * T::lit(0.5);
    let sym = Matrix2::new(m[(0, 0)], off, off, m[(1, 1)]);
    let det = sym[(0, 0)] * sym[(1, 1)] - off * off;
    if !(sym[(0, 0)] > T::zero() && det > T::zero()) {
        return Err(Error::NotPositiveDefinite {
            what,
            min_eigenvalue: smallest_eigenvalue(&sym).to_f64(),
        });
    }
    Ok(sym)
}

fn smallest_eigenvalue<T: Real>(m: &Matrix2<T>) -> T {
    let half_tr = (m[(0, 0)] + m[(1, 1)]) * T::lit(0.5);
    let half_diff = (m[(0, 0)] - m[(1, 1)]) * T::lit(0.5);
    half_tr - half_diff.hypot(m[(0, 1)])
}

/// The canonical wave packet: a classical Stokes vector, the coherence shapes of its x and y
/// components, its frame and wavenumber (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WavePacket<T: Real> {
    stokes: Stokes<T>,
    shape_x: Matrix2<T>,
    shape_y: Matrix2<T>,
    /// `1/σ_zz²` (0 for unbounded longitudinal coherence).
    inv_sigma_zz_sq: T,
    frame: Frame<T>,
    k: T,
    /// Distance from the source, if the coherence grows with propagation (van Cittert–Zernike).
    distance: Option<T>,
}

impl<T: Real> WavePacket<T> {
    /// Slack on the realizability bound, in machine epsilons: `|μ|²·4S_xS_y` may exceed
    /// `4S_xS_y·√(|Θ_x||Θ_y|)/|Θ_½|` by `4·REALIZABILITY_SLACK_ULPS·ε·S0²` (twice the slack of
    /// [`Stokes::new`], so every accepted Stokes vector is realizable with `Θ_x = Θ_y`).
    pub const REALIZABILITY_SLACK_ULPS: f64 = 64.0;

    /// How many ulps of rounding the shapes' entries may carry (module docs, "Realizability"):
    /// `|μ|²` up to `B (1 + SHAPE_ROUNDING_ULPS · K ε)` is projected onto the bound `B` of the
    /// shapes held, `K` the bound's condition number ([`WavePacket::realizability_conditioning`]).
    pub const SHAPE_ROUNDING_ULPS: f64 = 4.0;

    /// The condition number `K` of the realizability bound `B = √(|Θ_x||Θ_y|)/|Θ_½|` under
    /// relative perturbations of the shapes' entries: a change of every entry by `δ` of itself
    /// moves `B` by at most `K δ` of itself (to first order).
    ///
    /// # Formula
    /// ```text
    /// K = ½ κ(Θ_x) + ½ κ(Θ_y) + κ_½,   κ(Θ) = (|Θ₁₁Θ₂₂| + Θ₁₂²)/|Θ|
    /// κ_½ = [ |h₁₁| m₂₂ + |h₂₂| m₁₁ + 2 |h₁₂| m₁₂ ] / |Θ_½|,   h = Θ_½,  m_ij = (|x_ij| + |y_ij|)/2
    /// ```
    /// 2 for equal isotropic shapes; about the anisotropy for elongated ones (`10⁶` at an
    /// anisotropy of `10⁶` turned by 45°).
    #[must_use]
    pub fn realizability_conditioning(&self) -> T {
        let scale = pow2_scale(self.shape_x.amax().max(self.shape_y.amax()));
        bound_conditioning(&(self.shape_x / scale), &(self.shape_y / scale))
    }

    /// A packet from its classical Stokes vector (irradiance, in `frame`), the transverse
    /// coherence shapes of its x and y components, its frame (x̂, ŷ, k̂ = propagation direction)
    /// and its wavelength (length, > 0). Longitudinal coherence is unbounded (`σ_zz = ∞`) until
    /// set with [`WavePacket::with_longitudinal_coherence`].
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a non-positive or non-finite wavelength;
    /// [`Error::Unrealizable`] if `|μ|² > √(|Θ_x||Θ_y|)/|Θ_½|` by more than the rounding of
    /// the shapes reaches (module docs, "Realizability"; within it `S2`, `S3` are scaled onto
    /// the bound).
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    /// let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// let w = CoherenceShape::<f64>::isotropic(20.0).unwrap(); // 20 µm coherence width
    /// let s = Stokes::new(1.0, 0.0, 1.0, 0.0).unwrap(); // +45° linear
    /// let p = WavePacket::new(s, w, w, frame, 0.5).unwrap();
    /// assert!((p.correlation().re - 0.5).abs() < 1e-15 && (p.chi() - 2.0).abs() < 1e-15);
    /// // x and y with different shapes cannot stay fully correlated:
    /// let w2 = CoherenceShape::isotropic(40.0).unwrap();
    /// assert!(WavePacket::new(s, w, w2, frame, 0.5).is_err());
    /// ```
    pub fn new(
        stokes: Stokes<T>,
        shape_x: CoherenceShape<T>,
        shape_y: CoherenceShape<T>,
        frame: Frame<T>,
        wavelength: T,
    ) -> Result<Self, Error> {
        let k = wavenumber(wavelength)?;
        let mut p = Self {
            stokes,
            shape_x: shape_x.0,
            shape_y: shape_y.0,
            inv_sigma_zz_sq: T::zero(),
            frame,
            k,
            distance: None,
        };
        p.realize()?;
        Ok(p)
    }

    /// A packet whose x and y components share one coherence shape (always realizable).
    ///
    /// # Errors
    /// As [`WavePacket::new`] (wavelength).
    pub fn from_stokes(
        stokes: Stokes<T>,
        shape: CoherenceShape<T>,
        frame: Frame<T>,
        wavelength: T,
    ) -> Result<Self, Error> {
        Self::new(stokes, shape, shape, frame, wavelength)
    }

    /// Light from a distant, uniform, incoherent disk source of solid angle `solid_angle` (sr),
    /// e.g. the sun (`Ω ≈ 6.8·10⁻⁵ sr`), by the van Cittert–Zernike theorem.
    ///
    /// # Formula
    /// ```text
    /// μ(ξ) = 2 J₁(k α |ξ|)/(k α |ξ|)          (disk of angular radius α, Ω = π α²)
    ///      ≈ exp(−|ξ|²/(2w²))  with  w² = 4/(k α)² = λ²/(π Ω)
    /// ```
    /// The Gaussian matches the true degree of coherence in value and curvature at ξ = 0
    /// (`2J₁(x)/x = 1 − x²/8 + …`); it is the packet's isotropic shape `Θ⊥ = w² I`. At `|ξ| = w`
    /// it reads 0.607 where the disk gives `J₁(2) = 0.577`. For the sun at λ = 0.5 µm this gives
    /// `w ≈ 34 µm` (the disk's coherence first vanishes at `|ξ| = 3.83/(kα) ≈ 1.92 w ≈ 66 µm`,
    /// the "coherence width" usually quoted). Small-angle: `Ω = π α²` and θ the projected
    /// direction offset; for large sources this is only indicative. The source is far:
    /// propagation leaves the shape unchanged ([`WavePacket::propagate`]).
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::packet::{Channel, WavePacket};
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    /// let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// let sun = WavePacket::from_distant_disk_source(
    ///     Stokes::<f64>::unpolarized(1.0).unwrap(), 6.8e-5, frame, 0.5).unwrap();
    /// let w = sun.shape(Channel::X)[(0, 0)].sqrt();
    /// assert!((w - 34.209).abs() < 1e-3); // µm
    /// ```
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `0 < Ω < 2π` is finite, and as [`WavePacket::new`].
    pub fn from_distant_disk_source(
        stokes: Stokes<T>,
        solid_angle: T,
        frame: Frame<T>,
        wavelength: T,
    ) -> Result<Self, Error> {
        if !(solid_angle.is_finite() && solid_angle > T::zero() && solid_angle < T::two_pi()) {
            return Err(Error::OutOfRange {
                what: "source solid angle",
                value: solid_angle.to_f64(),
                expected: "(0, 2π) sr",
            });
        }
        wavenumber(wavelength)?;
        let w2 = wavelength * wavelength / (T::pi() * solid_angle);
        Self::from_stokes(
            stokes,
            CoherenceShape::new(Matrix2::identity() * w2)?,
            frame,
            wavelength,
        )
    }

    /// Light from an incoherent, uniform disk source of area `area` seen face-on from
    /// `distance`: [`WavePacket::from_distant_disk_source`] with `Ω = A/r²`, which also records
    /// the distance so that [`WavePacket::propagate`] grows the coherence area as `r²`.
    ///
    /// # Formula
    /// ```text
    /// Θ⊥ = λ² r² / (π A) · I
    /// ```
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for non-positive or non-finite `area` or `distance`, or
    /// `A/r² ≥ 2π`; as [`WavePacket::new`].
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::packet::{Channel, WavePacket};
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    /// let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// // A 1 mm² lamp seen from 1 m (lengths in µm), λ = 0.5 µm.
    /// let p = WavePacket::from_area_source(
    ///     Stokes::unpolarized(1.0).unwrap(), 1e6, 1e6, frame, 0.5).unwrap();
    /// let theta = 0.25 * 1e12 / (core::f64::consts::PI * 1e6);
    /// assert!((p.shape(Channel::X)[(0, 0)] / theta - 1.0).abs() < 1e-12);
    /// // Twice as far: four times the coherence area.
    /// let q = p.propagate(1e6).unwrap();
    /// assert!((q.shape(Channel::X)[(0, 0)] / (4.0 * theta) - 1.0).abs() < 1e-12);
    /// ```
    pub fn from_area_source(
        stokes: Stokes<T>,
        area: T,
        distance: T,
        frame: Frame<T>,
        wavelength: T,
    ) -> Result<Self, Error> {
        for (what, v) in [("source area", area), ("source distance", distance)] {
            if !(v.is_finite() && v > T::zero()) {
                return Err(Error::OutOfRange {
                    what,
                    value: v.to_f64(),
                    expected: "finite and > 0",
                });
            }
        }
        let mut p = Self::from_distant_disk_source(
            stokes,
            area / (distance * distance),
            frame,
            wavelength,
        )?;
        p.distance = Some(distance);
        Ok(p)
    }

    /// Light from a distant, incoherent source whose radiance falls off as a Gaussian in angle
    /// (angular covariance `C_θ`, rad², in the packet frame's (x̂, ŷ) coordinates), by the van
    /// Cittert–Zernike theorem. Unlike the disk, the Gaussian shape is then exact.
    ///
    /// # Formula
    /// ```text
    /// I(θ) ∝ exp(−½ θᵀ C_θ⁻¹ θ)      (θ the small-angle direction offset from k̂)
    /// μ(ξ) = ∫ I(θ) e^{i k θ·ξ} d²θ / ∫ I(θ) d²θ = exp(−½ k² ξᵀ C_θ ξ)
    /// Θ⊥ = (k² C_θ)⁻¹ = λ² C_θ⁻¹ / (4π²)
    /// ```
    /// An isotropic source of angular standard deviation `σ_θ` (`C_θ = σ_θ² I`) gives a coherence
    /// width `w = 1/(k σ_θ) = λ/(2π σ_θ)`. The source is far: propagation leaves the shape
    /// unchanged ([`WavePacket::propagate`]).
    ///
    /// # Errors
    /// [`Error::NonFinite`], [`Error::NotHermitian`] or [`Error::NotPositiveDefinite`] for a
    /// covariance that is not finite, symmetric and positive definite; [`Error::NotPositiveDefinite`]
    /// or [`Error::NonFinite`] if the resulting `Θ⊥` over- or underflows; as [`WavePacket::new`].
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::packet::{Channel, WavePacket};
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::{Matrix2, Vector3};
    /// let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// let sigma = 1e-3; // 1 mrad angular spread
    /// let p = WavePacket::from_gaussian_source(
    ///     Stokes::unpolarized(1.0).unwrap(), Matrix2::identity() * (sigma * sigma), frame, 0.5).unwrap();
    /// let w = 0.5 / (2.0 * core::f64::consts::PI * sigma); // ≈ 79.6 µm
    /// assert!((p.shape(Channel::X)[(0, 0)] / (w * w) - 1.0).abs() < 1e-12);
    /// ```
    pub fn from_gaussian_source(
        stokes: Stokes<T>,
        angular_covariance: Matrix2<T>,
        frame: Frame<T>,
        wavelength: T,
    ) -> Result<Self, Error> {
        let c = validate_spd(angular_covariance, "angular covariance of the source")?;
        let k = wavenumber(wavelength)?;
        // Θ⊥ = (k² C_θ)⁻¹, inverted before scaling so that tiny C_θ does not underflow first.
        let shape = CoherenceShape::new(inverse2(&c) / (k * k))?;
        Self::from_stokes(stokes, shape, frame, wavelength)
    }

    /// Sets the longitudinal coherence length `σ_zz` (length), the `ξ_z` extent of the 3-D shape
    /// matrices `Θ_α = blockdiag(Θ⊥_α, σ_zz²)`.
    ///
    /// A `σ_zz` whose square overflows is unbounded coherence (`1/σ_zz² = 0`), as its limit.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `σ_zz` is finite and positive with `1/σ_zz²` finite.
    pub fn with_longitudinal_coherence(mut self, sigma_zz: T) -> Result<Self, Error> {
        if !(sigma_zz.is_finite() && sigma_zz > T::zero()) {
            return Err(Error::OutOfRange {
                what: "longitudinal coherence length",
                value: sigma_zz.to_f64(),
                expected: "finite and > 0",
            });
        }
        let inv = (sigma_zz * sigma_zz).recip();
        if !inv.is_finite() {
            return Err(Error::OutOfRange {
                what: "longitudinal coherence length",
                value: sigma_zz.to_f64(),
                expected: "σ_zz² a normal number (σ_zz ≳ 1.1e-19 in f32, 1.5e-154 in f64)",
            });
        }
        self.inv_sigma_zz_sq = inv;
        Ok(self)
    }

    /// Checks the realizability bound (module docs, "Realizability"), projecting onto it a
    /// packet that exceeds it by no more than the rounding of its shapes.
    fn realize(&mut self) -> Result<(), Error> {
        // The bound is scale-invariant: normalize first, since |Θ| over- or underflows f32 for
        // entries beyond ~1e19 or below ~1e-19 (length²) while the ratio is harmless.
        let scale = pow2_scale(self.shape_x.amax().max(self.shape_y.amax()));
        let (nx, ny) = (self.shape_x / scale, self.shape_y / scale);
        let dx = det2(&nx);
        let dy = det2(&ny);
        let dh = det2_of_mean(&nx, &ny);
        // |μ|² ≤ √(|Θx||Θy|)/|Θ½|  ⇔  (S2² + S3²)/4 ≤ SxSy √(|Θx||Θy|)/|Θ½|, on S/S0 (the test is
        // homogeneous of degree 2 in S: on S itself the squares over- or underflowed beyond
        // S0 ≈ 1e±154 in f64 and 1e±19 in f32, accepting |μ| = 1 with Θy = 4Θx at S0 = 1e±200).
        // The slack is absolute, relative to S0²: SxSy = (S0² − S1²)/4 loses all its digits for
        // nearly fully polarized light (S1 → ±S0), and a Stokes vector that `Stokes::new`
        // accepted (|S| ≤ S0 (1 + 64 ε), i.e. S1² + S2² + S3² ≤ S0² + 128 ε S0²) must pass here
        // when Θx = Θy. A relative slack on SxSy alone rejected (1, cos t, sin t, 0) for t ≲ 1e-8.
        let s = self.stokes.vector();
        if s[0] <= T::zero() {
            return Ok(()); // a dark packet (S = 0, as Stokes::new guarantees)
        }
        let n = s / s[0];
        let lhs = (n[2] * n[2] + n[3] * n[3]) * T::lit(0.25);
        let bound = (dx / dh).sqrt() * (dy / dh).sqrt();
        let half = T::lit(0.5);
        let rhs = ((n[0] + n[1]) * half) * ((n[0] - n[1]) * half) * bound;
        let tol = T::lit(Self::REALIZABILITY_SLACK_ULPS) * T::EPSILON;
        if lhs <= rhs + tol {
            return Ok(());
        }
        // The shapes' entries are known to a few ulps (rounded to T, or computed in T), and
        // the bound of nearly singular shapes moves by `K ε` per ulp of their entries: within
        // `SHAPE_ROUNDING_ULPS · K ε` of it, the packet is realizable for shapes its own
        // represent, and |μ| is scaled onto the bound of the shapes held (module docs).
        let k = bound_conditioning(&nx, &ny);
        let reach = T::lit(Self::SHAPE_ROUNDING_ULPS) * T::EPSILON * k;
        if lhs <= rhs * (T::one() + reach) + tol {
            let f = (rhs / lhs).sqrt();
            let v = self.stokes.0;
            self.stokes = Stokes(nalgebra::Vector4::new(v[0], v[1], v[2] * f, v[3] * f));
            return Ok(());
        }
        Err(Error::Unrealizable {
            reason: "|μ|² exceeds √(|Θx||Θy|)/|Θ½|: x and y components with different \
                     coherence shapes cannot be this strongly correlated",
        })
    }

    /// The classical Stokes vector (ξ = 0) in the packet frame.
    #[inline]
    #[must_use]
    pub fn stokes(&self) -> Stokes<T> {
        self.stokes
    }

    /// `S_x = (S0 + S1)/2`.
    #[inline]
    #[must_use]
    pub fn sx(&self) -> T {
        (self.stokes.0[0] + self.stokes.0[1]) * T::lit(0.5)
    }

    /// `S_y = (S0 − S1)/2`.
    #[inline]
    #[must_use]
    pub fn sy(&self) -> T {
        (self.stokes.0[0] - self.stokes.0[1]) * T::lit(0.5)
    }

    /// `√(S_xS_y) μ = (S2 + i S3)/2`: the correlation channel's weight without the division by
    /// `√(S_xS_y)`.
    #[inline]
    #[must_use]
    pub fn correlation(&self) -> Complex<T> {
        Complex::new(self.stokes.0[2], self.stokes.0[3]) * T::lit(0.5)
    }

    /// The complex degree of correlation `μ = (S2 + iS3)/(2√(S_xS_y))`, `|μ| ≤ 1`; 0 when
    /// `S_x S_y = 0` (then `S2 = S3 = 0` too).
    ///
    /// For nearly fully polarized light `S_xS_y = (S0² − S1²)/4` is computed with cancellation,
    /// and a Stokes vector on the edge of the Poincaré sphere (within [`Stokes::new`]'s rounding
    /// slack) can give a ratio with modulus above 1 — by orders of magnitude when `S_y` is a few
    /// ulps of `S0`. The result is therefore clamped to `|μ| ≤ 1` (its phase kept).
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    /// let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// let w = CoherenceShape::<f64>::isotropic(20.0).unwrap();
    /// // Right-circular light: S_x = S_y = 1/2, μ = i.
    /// let p = WavePacket::from_stokes(Stokes::new(1.0, 0.0, 0.0, 1.0).unwrap(), w, frame, 0.5).unwrap();
    /// let mu = p.degree_of_correlation();
    /// assert!(mu.re.abs() < 1e-15 && (mu.im - 1.0).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn degree_of_correlation(&self) -> Complex<T> {
        let n = (self.sx() * self.sy()).sqrt();
        if n > T::zero() {
            let mu = self.correlation() / n;
            let m = mu.re.hypot(mu.im);
            if m > T::one() { mu / m } else { mu }
        } else {
            Complex::new(T::zero(), T::zero())
        }
    }

    /// The seed's `χ = 2 Re μ`.
    #[must_use]
    pub fn chi(&self) -> T {
        self.degree_of_correlation().re * T::lit(2.0)
    }

    /// The seed's `ς = 2 Im μ`.
    #[must_use]
    pub fn varsigma(&self) -> T {
        self.degree_of_correlation().im * T::lit(2.0)
    }

    /// The transverse shape `Θ⊥_α` of a channel (length²), in the packet frame.
    #[inline]
    #[must_use]
    pub fn shape(&self, channel: Channel) -> Matrix2<T> {
        match channel {
            Channel::X => self.shape_x,
            Channel::Y => self.shape_y,
            Channel::Half => (self.shape_x + self.shape_y) * T::lit(0.5),
        }
    }

    /// `L⁻¹` of the Cholesky factor of the channel's shape `Θ⊥_α = L Lᵀ` (`Θ_½` from `Θ_x` and
    /// `Θ_y` without rounding their mean first); `None` if it over- or underflows.
    #[inline]
    pub(crate) fn shape_inverse_cholesky(&self, channel: Channel) -> Option<Matrix2<T>> {
        match channel {
            Channel::X => inverse_cholesky2(&self.shape_x),
            Channel::Y => inverse_cholesky2(&self.shape_y),
            Channel::Half => inverse_cholesky_of_mean(&self.shape_x, &self.shape_y),
        }
    }

    /// `true` when `Θ_x = Θ_y` (one shape matrix describes the packet exactly).
    #[inline]
    #[must_use]
    pub fn has_single_shape(&self) -> bool {
        self.shape_x == self.shape_y
    }

    /// The 3-D shape `Θ_α = blockdiag(Θ⊥_α, σ_zz²)` in the packet frame, or `None` for unbounded
    /// longitudinal coherence.
    #[must_use]
    pub fn shape_3d(&self, channel: Channel) -> Option<Matrix3<T>> {
        if self.inv_sigma_zz_sq == T::zero() {
            return None;
        }
        let t = self.shape(channel);
        let mut m = Matrix3::zeros();
        m.fixed_view_mut::<2, 2>(0, 0).copy_from(&t);
        m[(2, 2)] = self.inv_sigma_zz_sq.recip();
        Some(m)
    }

    /// The inverse shape `Θ_α⁻¹` in world coordinates, `Q Θ_α⁻¹ Qᵀ` with `Q = [x̂ ŷ k̂]` mapping
    /// packet to world coordinates (S2.18's Ξ before the 2π and k factors): the precision of the
    /// packet's coherence function at a world-space separation.
    #[must_use]
    pub fn world_precision(&self, channel: Channel) -> Matrix3<T> {
        let inv = inverse2(&self.shape(channel));
        let (x, y, k) = (self.frame.x, self.frame.y, self.frame.k);
        x * x.transpose() * inv[(0, 0)]
            + (x * y.transpose() + y * x.transpose()) * inv[(0, 1)]
            + y * y.transpose() * inv[(1, 1)]
            + k * k.transpose() * self.inv_sigma_zz_sq
    }

    /// `1/σ_zz²` (0 for unbounded longitudinal coherence).
    #[inline]
    #[must_use]
    pub fn inverse_longitudinal_variance(&self) -> T {
        self.inv_sigma_zz_sq
    }

    /// The packet frame (x̂, ŷ, k̂), k̂ the propagation direction.
    #[inline]
    #[must_use]
    pub fn frame(&self) -> &Frame<T> {
        &self.frame
    }

    /// The propagation direction k̂.
    #[inline]
    #[must_use]
    pub fn direction(&self) -> Vector3<T> {
        self.frame.k
    }

    /// The wavenumber `k = 2π/λ` (rad/length).
    #[inline]
    #[must_use]
    pub fn wavenumber(&self) -> T {
        self.k
    }

    /// The packet at exactly the wavenumber `k` of its source (the shading point's, which owns
    /// it: [`crate::bsdf::Bsdf::wavenumber`]), in place of the `2π/(2π/k)` its wavelength
    /// round trip gave (within an ulp or two: [`same_wavenumber`]).
    #[inline]
    #[must_use]
    pub(crate) fn at_wavenumber(mut self, k: T) -> Self {
        debug_assert!(same_wavenumber(self.k, k), "{:?} vs {:?}", self.k, k);
        self.k = k;
        self
    }

    /// The wavelength `λ = 2π/k`.
    #[inline]
    #[must_use]
    pub fn wavelength(&self) -> T {
        T::two_pi() / self.k
    }

    /// The distance from the source, when the packet was built from a source at finite distance.
    #[inline]
    #[must_use]
    pub fn distance(&self) -> Option<T> {
        self.distance
    }

    /// Free propagation over `d` (length, ≥ 0) along k̂: the generalized radiance is conserved, so
    /// the Stokes vector is unchanged, and the coherence area of light from a source at distance
    /// `r` grows as `r²`: `Θ⊥ ← Θ⊥ ((r + d)/r)²`. Packets without a recorded distance (a distant
    /// source, or built from a shape) are unchanged; `d = 0` is the identity.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a negative or non-finite `d`, or when the grown shape or the
    /// new distance overflows the type (in `f32`, e.g. a lamp at 1 m propagated by 1e20 µm):
    /// the packet would otherwise carry infinite or NaN shapes.
    pub fn propagate(&self, d: T) -> Result<Self, Error> {
        if !(d.is_finite() && d >= T::zero()) {
            return Err(Error::OutOfRange {
                what: "propagation distance",
                value: d.to_f64(),
                expected: "finite and ≥ 0",
            });
        }
        let mut p = *self;
        if let Some(r) = self.distance
            && d > T::zero()
        {
            let grow = (r + d) / r;
            let g2 = grow * grow;
            p.shape_x *= g2;
            p.shape_y *= g2;
            p.distance = Some(r + d);
            let finite = |m: &Matrix2<T>| m.iter().all(|x| x.is_finite());
            if !(finite(&p.shape_x) && finite(&p.shape_y) && (r + d).is_finite()) {
                return Err(Error::OutOfRange {
                    what: "propagation distance (the grown coherence shape overflows)",
                    value: d.to_f64(),
                    expected: "(r + d)/r · |Θ⊥|^{1/2} finite",
                });
            }
        }
        Ok(p)
    }

    /// The same light described in the frame turned by `psi` counter-clockwise about k̂
    /// (x̂ toward ŷ): the Stokes vector is rotated by S2.4's `T(−ψ)`, the shape matrices are
    /// expressed in the new coordinates, `Θ′ = R Θ Rᵀ` with `R` the 2×2 coordinate rotation.
    ///
    /// The x′ and y′ components mix the old x and y: when `Θ_x = Θ_y` the result is exact. When
    /// they differ, the coherence function of a mixed component is a sum of Gaussians, which the
    /// canonical packet cannot hold; each new channel then gets the Gaussian that matches its
    /// value and curvature at ξ = 0 (its intensity-weighted precision):
    /// ```text
    /// Θ′_x⁻¹ = (c² S_x Θ_x⁻¹ + s² S_y Θ_y⁻¹ + c s S2 Θ_½⁻¹) / S′_x,   c = cos ψ, s = sin ψ
    /// ```
    /// (and `Θ′_y` with `s ↔ c`, `S2 → −S2`). For a realizable packet this precision is positive
    /// definite: it is the second moment of the mixed channel's spectral density
    /// `(c, s) M(q) (c, s)ᵀ ≥ 0` (Bochner, module docs); `Θ_½` is the fallback should rounding
    /// break that. A channel that carries no light (`S′_x = 0`) gets the field-weight mixture
    /// `(c² Θ_x⁻¹ + s² Θ_y⁻¹)⁻¹`, so `rotated(0)` is the identity. The result may be slightly
    /// unrealizable by the bound above (the matched Gaussians are approximations); it is returned
    /// as is.
    ///
    /// Verified in `tests/packet.rs` (`rotation_single_shape`, `rotation_curvature_matching`):
    /// the Stokes vector against the field-level `C′ = τ C τᵀ`, the shapes against the same
    /// physical separation, and the matched precision against a finite-difference Hessian.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::packet::{Channel, CoherenceShape, WavePacket};
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::{Matrix2, Vector3};
    /// let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// // Anisotropic coherence, 4× wider along x̂, x̂-polarized light.
    /// let w = CoherenceShape::new(Matrix2::new(16.0, 0.0, 0.0, 1.0)).unwrap();
    /// let p = WavePacket::from_stokes(Stokes::new(1.0, 1.0, 0.0, 0.0).unwrap(), w, frame, 0.5).unwrap();
    /// let q = p.rotated(core::f64::consts::FRAC_PI_2);
    /// // Now ŷ-polarized, and wide along the new ŷ′ (the old x̂).
    /// assert!((q.stokes().s1() + 1.0).abs() < 1e-12);
    /// assert!((q.shape(Channel::X)[(1, 1)] - 16.0).abs() < 1e-12);
    /// ```
    #[must_use]
    pub fn rotated(&self, psi: T) -> Self {
        let (s, c) = psi.sin_cos();
        // Coordinates in the new frame: ξ′ = R ξ, R = [[c, s], [−s, c]].
        let r = Matrix2::new(c, s, -s, c);
        let stokes = Stokes(rotation_mueller(-psi).0 * self.stokes.0);
        let half = self.shape(Channel::Half);
        let (shape_x, shape_y) = if self.has_single_shape() {
            (self.shape_x, self.shape_y)
        } else {
            let (ix, iy, ih) = (
                inverse2(&self.shape_x),
                inverse2(&self.shape_y),
                inverse2(&half),
            );
            let (sx, sy, s2) = (self.sx(), self.sy(), self.stokes.0[2]);
            let mix = |cc: T, ss: T, cross: T| {
                let w = cc * sx + ss * sy + cross * s2;
                if w <= T::zero() {
                    // A dark channel: any shape carries no light; take the field-weight mixture
                    // so that `rotated(0)` keeps Θ_x, Θ_y exactly.
                    return inverse2(&(ix * cc + iy * ss));
                }
                let p = (ix * (cc * sx) + iy * (ss * sy) + ih * (cross * s2)) / w;
                if p[(0, 0)] > T::zero() && det2(&p) > T::zero() {
                    inverse2(&p)
                } else {
                    half
                }
            };
            (mix(c * c, s * s, c * s), mix(s * s, c * c, -c * s))
        };
        let frame = self.frame.rotated(psi);
        Self {
            stokes,
            shape_x: r * shape_x * r.transpose(),
            shape_y: r * shape_y * r.transpose(),
            frame,
            ..*self
        }
    }
}

/// `true` when two wavenumbers of the same light agree within 16 ulps: a packet's own, and one
/// derived from its wavelength elsewhere (`λ/η` computed another way, a geometry's). The one
/// test of "the same wavelength" for the kernel's and the BSDF layer's checks.
#[inline]
pub(crate) fn same_wavenumber<T: Real>(a: T, b: T) -> bool {
    crate::numerics::within_ulps(a, b, 16.0)
}

/// `k = 2π/λ` for a finite, positive, normal wavelength whose `k` is finite (a subnormal λ
/// gave `k = ∞`).
fn wavenumber<T: Real>(wavelength: T) -> Result<T, Error> {
    let k = T::two_pi() / wavelength;
    if !(wavelength.is_finite() && wavelength >= T::MIN_POSITIVE && k.is_finite()) {
        return Err(Error::OutOfRange {
            what: "wavelength",
            value: wavelength.to_f64(),
            expected: "finite and > 0, a normal number with 2π/λ finite",
        });
    }
    Ok(k)
}

/// `K` of [`WavePacket::realizability_conditioning`] for the shapes `x`, `y` (scaled by a
/// common power of two), in `f64`.
fn bound_conditioning<T: Real>(x: &Matrix2<T>, y: &Matrix2<T>) -> T {
    let (x, y) = (x.map(|v| v.to_f64()), y.map(|v| v.to_f64()));
    let kappa = |m: &Matrix2<f64>| {
        let d = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
        ((m[(0, 0)] * m[(1, 1)]).abs() + (m[(0, 1)] * m[(1, 0)]).abs()) / d
    };
    let h = (x + y) * 0.5;
    let mag = (x.abs() + y.abs()) * 0.5;
    let dh = h[(0, 0)] * h[(1, 1)] - h[(0, 1)] * h[(1, 0)];
    let kh = (h[(0, 0)].abs() * mag[(1, 1)]
        + h[(1, 1)].abs() * mag[(0, 0)]
        + 2.0 * h[(0, 1)].abs() * mag[(0, 1)])
        / dh;
    let k = 0.5 * kappa(&x) + 0.5 * kappa(&y) + kh;
    T::lit(if k.is_finite() && k > 0.0 {
        k
    } else {
        f64::INFINITY
    })
}
