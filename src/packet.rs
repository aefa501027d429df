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
//! [`WavePacket::new`] returns [`Error::Unrealizable`] when it is violated (beyond rounding)
//! rather than clamping: a clamp would silently change the light's degree of polarization.

use nalgebra::{Matrix2, Matrix3, Vector3};
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::frame::{Frame, rotation_mueller};
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
        ensure_finite("coherence shape matrix entry", m.iter().copied())?;
        let scale = m.amax();
        let asym = (m[(0, 1)] - m[(1, 0)]).abs();
        if asym > T::lit(64.0) * T::EPSILON * scale {
            return Err(Error::NotHermitian {
                what: "coherence shape matrix",
                asymmetry: asym.to_f64(),
            });
        }
        let off = (m[(0, 1)] + m[(1, 0)]) * T::lit(0.5);
        let sym = Matrix2::new(m[(0, 0)], off, off, m[(1, 1)]);
        let det = sym[(0, 0)] * sym[(1, 1)] - off * off;
        if !(sym[(0, 0)] > T::zero() && det > T::zero()) {
            return Err(Error::NotPositiveDefinite {
                what: "coherence shape matrix",
                min_eigenvalue: smallest_eigenvalue(&sym).to_f64(),
            });
        }
        Ok(Self(sym))
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
    /// Relative slack on the realizability bound, in machine epsilons.
    pub const REALIZABILITY_SLACK_ULPS: f64 = 64.0;

    /// A packet from its classical Stokes vector (irradiance, in `frame`), the transverse
    /// coherence shapes of its x and y components, its frame (x̂, ŷ, k̂ = propagation direction)
    /// and its wavelength (length, > 0). Longitudinal coherence is unbounded (`σ_zz = ∞`) until
    /// set with [`WavePacket::with_longitudinal_coherence`].
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a non-positive or non-finite wavelength;
    /// [`Error::Unrealizable`] if `|μ|² > √(|Θ_x||Θ_y|)/|Θ_½|` (module docs, "Realizability").
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
        let p = Self {
            stokes,
            shape_x: shape_x.0,
            shape_y: shape_y.0,
            inv_sigma_zz_sq: T::zero(),
            frame,
            k,
            distance: None,
        };
        p.check_realizable()?;
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
    /// (`2J₁(x)/x = 1 − x²/8 + …`); it is the packet's isotropic shape `Θ⊥ = w² I`. For the sun
    /// at λ = 0.5 µm this gives `w ≈ 34 µm`. The source is far: propagation leaves the shape
    /// unchanged ([`WavePacket::propagate`]).
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

    /// Sets the longitudinal coherence length `σ_zz` (length), the `ξ_z` extent of the 3-D shape
    /// matrices `Θ_α = blockdiag(Θ⊥_α, σ_zz²)`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `σ_zz` is finite and positive.
    pub fn with_longitudinal_coherence(mut self, sigma_zz: T) -> Result<Self, Error> {
        if !(sigma_zz.is_finite() && sigma_zz > T::zero()) {
            return Err(Error::OutOfRange {
                what: "longitudinal coherence length",
                value: sigma_zz.to_f64(),
                expected: "finite and > 0",
            });
        }
        self.inv_sigma_zz_sq = (sigma_zz * sigma_zz).recip();
        Ok(self)
    }

    fn check_realizable(&self) -> Result<(), Error> {
        let dx = det2(&self.shape_x);
        let dy = det2(&self.shape_y);
        let dh = det2(&((self.shape_x + self.shape_y) * T::lit(0.5)));
        // |μ|² ≤ √(|Θx||Θy|)/|Θ½|  ⇔  (S2² + S3²)/4 ≤ SxSy √(|Θx||Θy|)/|Θ½|
        let s = self.stokes.vector();
        let lhs = (s[2] * s[2] + s[3] * s[3]) * T::lit(0.25);
        let bound = (dx.sqrt() * dy.sqrt()) / dh;
        let rhs = self.sx() * self.sy() * bound;
        let slack = T::one() + T::lit(Self::REALIZABILITY_SLACK_ULPS) * T::EPSILON;
        if lhs > rhs * slack + T::lit(Self::REALIZABILITY_SLACK_ULPS) * T::EPSILON * lhs {
            return Err(Error::Unrealizable {
                reason: "|μ|² exceeds √(|Θx||Θy|)/|Θ½|: x and y components with different \
                         coherence shapes cannot be this strongly correlated",
            });
        }
        Ok(())
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
    #[must_use]
    pub fn degree_of_correlation(&self) -> Complex<T> {
        let n = (self.sx() * self.sy()).sqrt();
        if n > T::zero() {
            self.correlation() / n
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
    /// source, or built from a shape) are unchanged.
    ///
    /// NaN or negative `d` leaves the packet unchanged (this function cannot fail).
    #[must_use]
    pub fn propagate(&self, d: T) -> Self {
        let mut p = *self;
        if let Some(r) = self.distance
            && d > T::zero()
            && d.is_finite()
        {
            let grow = (r + d) / r;
            let g2 = grow * grow;
            p.shape_x *= g2;
            p.shape_y *= g2;
            p.distance = Some(r + d);
        }
        p
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
    /// (and `Θ′_y` with `s ↔ c`, `S2 → −S2`), falling back to `Θ_½` where that is not positive
    /// definite or a channel carries no light. The result may then be slightly unrealizable by
    /// the bound above; it is returned as is.
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
                let p = (ix * (cc * sx) + iy * (ss * sy) + ih * (cross * s2)) / w;
                if w > T::zero() && p[(0, 0)] > T::zero() && det2(&p) > T::zero() {
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

fn wavenumber<T: Real>(wavelength: T) -> Result<T, Error> {
    if !(wavelength.is_finite() && wavelength > T::zero()) {
        return Err(Error::OutOfRange {
            what: "wavelength",
            value: wavelength.to_f64(),
            expected: "finite and > 0",
        });
    }
    Ok(T::two_pi() / wavelength)
}

#[inline]
fn det2<T: Real>(m: &Matrix2<T>) -> T {
    m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)]
}

/// Inverse of a 2×2 matrix by its adjugate (the callers pass SPD matrices).
#[inline]
pub(crate) fn inverse2<T: Real>(m: &Matrix2<T>) -> Matrix2<T> {
    let d = det2(m);
    Matrix2::new(m[(1, 1)], -m[(0, 1)], -m[(1, 0)], m[(0, 0)]) / d
}
