//! Transverse frames and their changes: τ (S2.3) and the Mueller rotation T(φ) (S2.4).
//!
//! A [`Frame`] (x̂, ŷ, k̂) is a right-handed orthonormal triple, `x̂ × ŷ = k̂`: k̂ is the propagation
//! direction and (x̂, ŷ) the transverse basis in which Jones vectors `(E_x, E_y)`, Stokes vectors
//! and Mueller matrices are written. Every polarimetric quantity is only meaningful together with
//! its frame; this module changes frames.
//!
//! # Conventions
//! - **Rotation sense.** "Turned by ψ counter-clockwise about k̂" means the right-handed rotation
//!   about k̂, which takes x̂ toward ŷ: `x̂′ = cos ψ x̂ + sin ψ ŷ`, `ŷ′ = −sin ψ x̂ + cos ψ ŷ`. It looks
//!   counter-clockwise to an observer looking *against* k̂, i.e. facing the source with the beam
//!   coming toward them ([`Frame::rotated`]).
//! - **τ maps components, not vectors.** `τ` (S2.3) takes the field components in the old basis
//!   to the components of the same field in the new basis, `j′ = τ j`. For the new basis turned by
//!   ψ, `τ = [[cos ψ, sin ψ], [−sin ψ, cos ψ]]`.
//! - **φ = −ψ.** The Mueller matrix of that change is `T = A_mül (τ ⊗ τ) A_mül⁻¹` = S2.4 with
//!   `φ = −ψ`, S2.3's "angle between x̂′⊥ and x̂" measured from x̂′⊥ to x̂. [`rotation_angle`]
//!   returns this φ, so `T = rotation_mueller(rotation_angle(from, to))`. Identical frames give
//!   τ = I and T = I exactly.
//! - **Backward frames.** When `k̂ · k̂′ < 0` the projection of the new basis on the old
//!   transverse plane reverses orientation (its determinant is `k̂ · k̂′`), so S2.3's normalized
//!   projections form a reflection, not a rotation. τ is then `diag(1, −1) R`, the rotation to
//!   [`Frame::reversed`] of the new frame followed by the handedness flip; T gains a factor
//!   `diag(1, 1, −1, −1)`. See [`tau`].
//! - **Mitsuba 3** `rotator(θ)` rotates the reference frame by +θ: it is our
//!   `rotation_mueller(−θ)` ([`convention::mitsuba_rotator`]).

use nalgebra::{Matrix2, Matrix4, Vector3};
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::jones::{JonesMatrix, JonesVector};
use crate::mueller::Mueller;
use crate::real::Real;
use crate::stokes::Stokes;

/// A right-handed orthonormal frame (x̂, ŷ, k̂): the transverse basis of a beam travelling along k̂.
///
/// Invariant (checked by every constructor): the three vectors are finite, of unit length and
/// mutually orthogonal within `TOLERANCE_ULPS · ε`, and `x̂ × ŷ = k̂` (right-handed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame<T: Real> {
    pub(crate) x: Vector3<T>,
    pub(crate) y: Vector3<T>,
    pub(crate) k: Vector3<T>,
}

/// `a · b` summed in a fixed order, so that `dot(a, b) == dot(b, a)` bit for bit (this makes the
/// frame change between identical frames exactly the identity).
#[inline]
fn dot<T: Real>(a: &Vector3<T>, b: &Vector3<T>) -> T {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// `v / |v|`, scaled first by its largest component so that huge or tiny finite inputs neither
/// overflow nor underflow.
fn normalize_checked<T: Real>(v: &Vector3<T>, what: &'static str) -> Result<Vector3<T>, Error> {
    ensure_finite(what, v.iter().copied())?;
    crate::numerics::unit_by_largest(v).ok_or(Error::InvalidBasis {
        reason: "zero vector",
    })
}

/// `v` minus its component along the unit vector `k`, normalized; done twice ("twice is enough")
/// so the result is orthogonal to `k` to rounding even when `v` was nearly parallel to it.
/// The caller guarantees that `|v − (v·k)k| ≥ √ε` for unit `v`.
fn orthogonalize<T: Real>(v: &Vector3<T>, k: &Vector3<T>) -> Vector3<T> {
    let a = v - k * dot(v, k);
    let a = a / a.norm();
    let b = a - k * dot(&a, k);
    b / b.norm()
}

/// The first tangent of the branchless orthonormal basis of a unit vector `n` (Duff et al.,
/// "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017, Listing 3): a unit vector
/// orthogonal to `n` that depends on `n` only.
fn duff_tangent<T: Real>(n: &Vector3<T>) -> Vector3<T> {
    let one = T::one();
    let sign = one.copysign(n.z);
    let a = -one / (sign + n.z);
    let b = n.x * n.y * a;
    Vector3::new(one + sign * n.x * n.x * a, sign * b, -sign * n.x)
}

impl<T: Real> Frame<T> {
    /// The tolerance of [`Frame::new`], in machine epsilons: unit length and orthogonality are
    /// accepted within `256 ε` (`≈ 5.7e-14` for `f64`, `≈ 3.1e-5` for `f32`).
    pub const TOLERANCE_ULPS: f64 = 256.0;

    fn tolerance() -> T {
        T::lit(Self::TOLERANCE_ULPS) * T::EPSILON
    }

    /// Below this `|d̂ × n̂|` (or `|ĥ × k̂|`) two directions count as parallel: `√ε`
    /// (`≈ 1.5e-8` rad for `f64`, `≈ 3.5e-4` rad for `f32`). Above it, the direction of the
    /// normalized cross product is accurate to `≲ √ε`.
    fn parallel_tolerance() -> T {
        T::EPSILON.sqrt()
    }

    /// A validated frame from its three basis vectors, stored as given.
    ///
    /// # Formula
    /// ```text
    /// |x̂| = |ŷ| = |k̂| = 1,   x̂·ŷ = ŷ·k̂ = k̂·x̂ = 0,   x̂ × ŷ = k̂      (each within 256 ε)
    /// ```
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞ components; [`Error::InvalidBasis`] with reason
    /// `"zero vector"`, `"basis vector is not of unit length"`, `"basis vectors are not
    /// orthogonal"` or `"basis is left-handed (x̂ × ŷ = −k̂)"`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use nalgebra::Vector3;
    /// let f = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// assert!((f.k() - Vector3::<f64>::z()).norm() < 1e-15);
    /// // (ŷ, x̂, k̂) is left-handed:
    /// assert!(Frame::new(Vector3::<f64>::y(), Vector3::x(), Vector3::z()).is_err());
    /// ```
    pub fn new(x: Vector3<T>, y: Vector3<T>, k: Vector3<T>) -> Result<Self, Error> {
        ensure_finite(
            "frame basis vector",
            x.iter().chain(y.iter()).chain(k.iter()).copied(),
        )?;
        let tol = Self::tolerance();
        for v in [&x, &y, &k] {
            if v.amax() == T::zero() {
                return Err(Error::InvalidBasis {
                    reason: "zero vector",
                });
            }
            if (v.norm() - T::one()).abs() > tol {
                return Err(Error::InvalidBasis {
                    reason: "basis vector is not of unit length",
                });
            }
        }
        if dot(&x, &y).abs() > tol || dot(&y, &k).abs() > tol || dot(&k, &x).abs() > tol {
            return Err(Error::InvalidBasis {
                reason: "basis vectors are not orthogonal",
            });
        }
        // Orthonormal x̂, ŷ, k̂: x̂ × ŷ = ±k̂, the sign is that of (x̂ × ŷ)·k̂.
        if dot(&x.cross(&y), &k) < T::zero() {
            return Err(Error::InvalidBasis {
                reason: "basis is left-handed (x̂ × ŷ = −k̂)",
            });
        }
        Ok(Self { x, y, k })
    }

    /// The frame with propagation direction `k` and x̂ in the direction of `x_hint` made
    /// orthogonal to k̂ (Gram–Schmidt); ŷ = k̂ × x̂.
    ///
    /// Neither input needs unit length.
    ///
    /// # Formula
    /// ```text
    /// k̂ = k/|k|,   x̂ = (h − (h·k̂) k̂)/|…|,   ŷ = k̂ × x̂        (so x̂ × ŷ = k̂)
    /// ```
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞; [`Error::InvalidBasis`] if either vector is zero
    /// (`"zero vector"`) or `x_hint` is parallel to `k` (`|ĥ × k̂| < √ε`, reason
    /// `"x hint is parallel to the direction"`).
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use nalgebra::Vector3;
    /// let f = Frame::from_direction_and_x(Vector3::new(0.0, 0.0, 2.0), Vector3::new(1.0, 0.0, 1.0))
    ///     .unwrap();
    /// assert!((f.x() - Vector3::x()).norm() < 1e-15 && (f.y() - Vector3::y()).norm() < 1e-15);
    /// ```
    pub fn from_direction_and_x(k: Vector3<T>, x_hint: Vector3<T>) -> Result<Self, Error> {
        let k = normalize_checked(&k, "frame direction")?;
        let h = normalize_checked(&x_hint, "frame x hint")?;
        if h.cross(&k).norm() < Self::parallel_tolerance() {
            return Err(Error::InvalidBasis {
                reason: "x hint is parallel to the direction",
            });
        }
        let x = orthogonalize(&h, &k);
        let y = k.cross(&x);
        Ok(Self { x, y, k })
    }

    /// A shading frame (t̂₁, t̂₂, n̂) from a surface normal alone: t̂₁ the first tangent of the
    /// branchless orthonormal basis of n̂ (Duff et al., "Building an Orthonormal Basis,
    /// Revisited", JCGT 6(1), 2017), t̂₂ = n̂ × t̂₁. It depends on n̂ only (continuous except
    /// across the sign change of `n̂_z`), so a renderer gets the same frame wherever it meets the
    /// same normal. `normal` need not be unit.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞; [`Error::InvalidBasis`] for a zero normal.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use nalgebra::Vector3;
    /// let f = Frame::from_normal(Vector3::new(0.3_f64, -0.2, 0.9)).unwrap();
    /// assert!((f.k() - Vector3::new(0.3, -0.2, 0.9).normalize()).norm() < 1e-15);
    /// assert!(f.x().dot(&f.k()).abs() < 1e-15 && (f.x().cross(&f.y()) - f.k()).norm() < 1e-15);
    /// ```
    pub fn from_normal(normal: Vector3<T>) -> Result<Self, Error> {
        let n = normalize_checked(&normal, "surface normal")?;
        let t1 = orthogonalize(&duff_tangent(&n), &n);
        let t2 = n.cross(&t1);
        Ok(Self { x: t1, y: t2, k: n })
    }

    /// The s/p frame of a beam travelling along `direction` that meets a surface with normal
    /// `normal`: x̂ = ŝ (perpendicular to the plane of incidence), ŷ = p̂, k̂ = d̂.
    ///
    /// Neither input needs unit length, and the sign of `normal` is the caller's choice (flipping
    /// it flips ŝ and p̂).
    ///
    /// # Formula
    /// ```text
    /// ŝ = (d̂ × n̂)/|d̂ × n̂|,   p̂ = d̂ × ŝ,   k̂ = d̂            (ŝ × p̂ = d̂: right-handed)
    /// ```
    /// The reflected direction `r = d − 2(d·n)n` and any refracted direction in the plane of
    /// incidence (with a positive d̂ component) give the *same* ŝ, so incident, reflected and
    /// transmitted s/p frames share x̂ = ŝ.
    ///
    /// **Normal incidence** (`|d̂ × n̂| < √ε`, i.e. within ≈ 1.5e-8 rad for `f64`, 3.5e-4 rad for
    /// `f32`): the plane of incidence is undefined, and ŝ is the first tangent of the branchless
    /// orthonormal basis of n̂ (Duff et al., JCGT 2017) made orthogonal to d̂. It depends on n̂ only,
    /// so `d` and `−d` get the same ŝ, and `sp(−d, n)` is `sp(d, n).reversed()` bit for bit.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞; [`Error::InvalidBasis`] (`"zero vector"`) if either
    /// input is zero.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use nalgebra::Vector3;
    /// // Incidence in the x–z plane onto the surface z = 0 (normal +z): ŝ = ±ŷ.
    /// let d = Vector3::new(1.0_f64, 0.0, -1.0);
    /// let f = Frame::sp(d, Vector3::z()).unwrap();
    /// assert!((f.x() - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-15);
    /// assert!((f.x().cross(&f.y()) - f.k()).norm() < 1e-15);
    /// // Normal incidence: the same ŝ for both directions.
    /// let up = Frame::<f64>::sp(Vector3::z(), Vector3::z()).unwrap();
    /// let down = Frame::<f64>::sp(-Vector3::z(), Vector3::z()).unwrap();
    /// assert_eq!(up.x(), down.x());
    /// ```
    pub fn sp(direction: Vector3<T>, normal: Vector3<T>) -> Result<Self, Error> {
        let d = normalize_checked(&direction, "propagation direction")?;
        let n = normalize_checked(&normal, "surface normal")?;
        Ok(Self::sp_unit(d, n))
    }

    /// [`Frame::sp`] for inputs the caller knows to be finite unit vectors (hot paths).
    ///
    /// Away from normal incidence (`|d̂ × n̂| ≥ 1/8`) the normalized cross product is orthogonal
    /// to d̂ within a few ε and is used as is; closer to the normal it is re-orthogonalized
    /// against d̂ (twice), and below `√ε` replaced by the tangent of n̂, as documented on `sp`.
    #[inline]
    pub(crate) fn sp_unit(d: Vector3<T>, n: Vector3<T>) -> Self {
        let c = d.cross(&n);
        let c2 = c.norm_squared();
        let s = if c2 >= T::lit(1.0 / 64.0) {
            c / c2.sqrt()
        } else if c2.sqrt() < Self::parallel_tolerance() {
            // Degenerate plane of incidence: a tangent from n̂ alone (same for ±d̂).
            orthogonalize(&duff_tangent(&n), &d)
        } else {
            orthogonalize(&c, &d)
        };
        let p = d.cross(&s);
        Self { x: s, y: p, k: d }
    }

    /// x̂.
    #[inline]
    #[must_use]
    pub fn x(&self) -> Vector3<T> {
        self.x
    }

    /// ŷ.
    #[inline]
    #[must_use]
    pub fn y(&self) -> Vector3<T> {
        self.y
    }

    /// k̂, the propagation direction.
    #[inline]
    #[must_use]
    pub fn k(&self) -> Vector3<T> {
        self.k
    }

    /// The frame of the reversed beam: (x̂, −ŷ, −k̂).
    ///
    /// Reversing k̂ alone would make the frame left-handed; negating ŷ too keeps `x̂ × ŷ = k̂`.
    ///
    /// # Formula
    /// ```text
    /// (x̂, ŷ, k̂) ↦ (x̂, −ŷ, −k̂);   the same field has Jones components (E_x, −E_y),
    /// Stokes vector diag(1, 1, −1, −1) S, and a Mueller matrix M ↦ D M D with D = diag(1, 1, −1, −1)
    /// ```
    /// S2 and S3 change sign: a +45° linear state reads −45°, and the circular sense, which is
    /// defined relative to k̂, reverses. [`tau`] and [`frame_change_mueller`] from a frame to its
    /// reverse return exactly `diag(1, −1)` and `diag(1, 1, −1, −1)`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::{Frame, frame_change_mueller};
    /// use nalgebra::{Matrix4, Vector3};
    /// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
    /// let r = f.reversed();
    /// assert_eq!(r.k(), -f.k());
    /// let t = frame_change_mueller(&f, &r).matrix();
    /// assert!((t - Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0, 1.0, -1.0, -1.0))).norm() < 1e-15);
    /// ```
    #[must_use]
    pub fn reversed(&self) -> Self {
        Self {
            x: self.x,
            y: -self.y,
            k: -self.k,
        }
    }

    /// This surface frame oriented toward `to_source`: itself when `to_source · k̂ ≥ 0`,
    /// [`Frame::reversed`] (t̂₂ and n̂ negated) otherwise — the frame an interface geometry uses
    /// for light arriving from below ([`crate::interaction::Geometry::at_interface`]), and the
    /// one to give [`crate::interaction::Kernel::prepare`] for such light.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use nalgebra::Vector3;
    /// let f = Frame::<f64>::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// assert_eq!(f.facing(&Vector3::new(0.0, 0.3, 1.0)), f);
    /// assert_eq!(f.facing(&Vector3::new(0.0, 0.3, -1.0)).k(), -Vector3::z());
    /// ```
    #[must_use]
    pub fn facing(&self, to_source: &Vector3<T>) -> Self {
        if to_source.dot(&self.k) < T::zero() {
            self.reversed()
        } else {
            *self
        }
    }

    /// The frame turned by `psi` counter-clockwise about k̂ (k̂ unchanged).
    ///
    /// # Formula
    /// ```text
    /// x̂′ = cos ψ x̂ + sin ψ ŷ,   ŷ′ = −sin ψ x̂ + cos ψ ŷ,   k̂′ = k̂
    /// ```
    /// Counter-clockwise as seen looking against k̂ (facing the source): x̂ turns toward ŷ. The
    /// frame change from `self` to the result has `τ = [[cos ψ, sin ψ], [−sin ψ, cos ψ]]` and
    /// `T = rotation_mueller(−ψ)`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::{Frame, rotation_angle};
    /// use nalgebra::Vector3;
    /// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
    /// let g = f.rotated(0.3);
    /// assert!((rotation_angle(&f, &g) + 0.3).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn rotated(&self, psi: T) -> Self {
        let (s, c) = psi.sin_cos();
        Self {
            x: self.x * c + self.y * s,
            y: self.y * c - self.x * s,
            k: self.k,
        }
    }
}

/// The orthogonal 2×2 frame change: `τ = R(ψ)` or `diag(1, −1) R(ψ)` with `ψ = −phi`.
#[derive(Debug, Clone, Copy)]
struct Change<T> {
    /// `cos φ`, `sin φ` of S2.3's angle, from the normalised entries of P (no trigonometry:
    /// the frame change sits on the kernel's hot path).
    cos: T,
    sin: T,
    flip: bool,
}

fn change<T: Real>(from: &Frame<T>, to: &Frame<T>) -> Change<T> {
    // P = S2.3 before normalization: P_ij = ê′_i · ê_j (rows: new basis, columns: old).
    let a = dot(&to.x, &from.x);
    let b = dot(&to.x, &from.y);
    let c = dot(&to.y, &from.x);
    let d = dot(&to.y, &from.y);
    // det P = k̂·k̂′: the projection keeps orientation iff k̂·k̂′ ≥ 0. S2.3's singular case
    // (x̂′ ∥ k̂ or ŷ′ ∥ k̂) has k̂·k̂′ = 0, which rounding (frames are orthonormal to 256 ε) may
    // make slightly negative: it counts as a rotation, as the text says, unless k̂·k̂′ < −256 ε.
    let flip = dot(&from.k, &to.k) < -Frame::<T>::tolerance();
    let (x, y) = if flip {
        // Closest reflection [[cos ψ, sin ψ], [sin ψ, −cos ψ]] to P: ψ = atan2(b + c, a − d).
        // It is diag(1, −1) times the rotation to `to.reversed()` (rows (a, b), (−c, −d)).
        (a - d, -(b + c))
    } else {
        // Closest rotation [[cos ψ, sin ψ], [−sin ψ, cos ψ]] to P (polar decomposition):
        // ψ = atan2(b − c, a + d), and φ = −ψ. a + d = b − c = 0 would need P = 0, impossible.
        (a + d, c - b)
    };
    // φ = atan2(y, x); identical frames give (x, y) = (2, 0) and so exactly cos φ = 1, sin φ = 0.
    // |x|, |y| ≤ 2 and r = σ₁ ± σ₂ ≥ 1 − 256 ε (P's singular values are 1 and |k̂·k̂′|), so
    // √(x² + y²) neither over- nor underflows.
    let r = (x * x + y * y).sqrt();
    Change {
        cos: x / r,
        sin: y / r,
        flip,
    }
}

impl<T: Real> Change<T> {
    fn phi(self) -> T {
        self.sin.atan2(self.cos)
    }

    fn tau(self) -> Matrix2<T> {
        let (s, c) = (self.sin, self.cos);
        // R(ψ) with ψ = −φ: [[cos φ, −sin φ], [sin φ, cos φ]].
        let sign = if self.flip { -T::one() } else { T::one() };
        Matrix2::new(c, -s, sign * s, sign * c)
    }

    fn mueller(self) -> Matrix4<T> {
        // cos 2φ, sin 2φ by the double-angle formulas.
        let (c, s) = (self.cos, self.sin);
        let mut m = rotation_mueller_cs(c * c - s * s, (s + s) * c);
        if self.flip {
            // A_mül (F ⊗ F) A_mül⁻¹ with F = diag(1, −1) is diag(1, 1, −1, −1).
            for col in 0..4 {
                m[(2, col)] = -m[(2, col)];
                m[(3, col)] = -m[(3, col)];
            }
        }
        m
    }
}

/// S2.3's angle φ of the frame change `from → to`, in `[−π, π]`: the new transverse basis is the
/// old one turned by `ψ = −φ` counter-clockwise about k̂ (seen facing the source).
///
/// # Formula
/// ```text
/// P = ⎡ x̂′·x̂  x̂′·ŷ ⎤ = ⎡ a  b ⎤      (S2.3 before normalizing the projections)
///     ⎣ ŷ′·x̂  ŷ′·ŷ ⎦   ⎣ c  d ⎦
/// k̂·k̂′ ≥ −256 ε:  φ = atan2(c − b, a + d)      (τ = R(−φ), the rotation closest to P)
/// k̂·k̂′ < −256 ε:  φ = atan2(−(b + c), a − d)   (τ = diag(1, −1) R(−φ), the closest reflection)
/// ```
/// When x̂′⊥ and ŷ′⊥ are orthogonal (same k̂, or k̂′ tilted about x̂′ or ŷ′), P's normalized rows
/// are exactly τ and φ is the angle from x̂′⊥ to x̂, as in S2.3. In S2.3's singular case (x̂′ ∥ k̂,
/// so x̂′⊥ is undefined) the first row of P vanishes and the formula reduces to the angle between
/// ŷ′⊥ and ŷ, continuously with nearby frames. For a general tilt, the projections are not
/// orthogonal and S2.3's matrix is not a rotation; φ is then the angle of the closest rotation
/// (polar decomposition of P), which is also the angle of parallel transport: turning the old
/// frame by ψ about k̂ and then tilting it by the minimal rotation k̂ → k̂′ gives φ = −ψ exactly.
///
/// Identical frames give `φ = 0` exactly. See [`tau`] for the backward case `k̂·k̂′ < 0`.
///
/// # Examples
/// ```
/// use gmueller::frame::{Frame, rotation_angle, rotation_mueller, frame_change_mueller};
/// use nalgebra::Vector3;
/// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
/// let g = f.rotated(0.25); // turned by ψ = 0.25 counter-clockwise about k̂
/// let phi = rotation_angle(&f, &g);
/// assert!((phi + 0.25).abs() < 1e-15);
/// assert!((rotation_mueller(phi).matrix() - frame_change_mueller(&f, &g).matrix()).norm() < 1e-15);
/// ```
#[must_use]
pub fn rotation_angle<T: Real>(from: &Frame<T>, to: &Frame<T>) -> T {
    change(from, to).phi()
}

/// `true` when the frame change `from → to` reverses transverse handedness (`k̂·k̂′ < 0`, beyond a
/// rounding margin of `256 ε` so that S2.3's singular case `k̂·k̂′ = 0` counts as a rotation), so that
/// [`tau`] is a reflection and [`frame_change_mueller`] flips the signs of S2 and S3.
///
/// # Examples
/// ```
/// use gmueller::frame::{Frame, reverses_handedness};
/// use nalgebra::Vector3;
/// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
/// assert!(!reverses_handedness(&f, &f) && reverses_handedness(&f, &f.reversed()));
/// ```
#[must_use]
pub fn reverses_handedness<T: Real>(from: &Frame<T>, to: &Frame<T>) -> bool {
    change(from, to).flip
}

/// τ of S2.3: maps the Jones components of a field in `from`'s basis to its components in `to`'s
/// basis, `j′ = τ j`. Always exactly orthogonal.
///
/// # Formula
/// ```text
/// S2.3:  τ = ⎡ x̂′⊥·x̂  x̂′⊥·ŷ ⎤,   x̂′⊥, ŷ′⊥ = normalized projections of x̂′, ŷ′ on the plane ⊥ k̂
///            ⎣ ŷ′⊥·x̂  ŷ′⊥·ŷ ⎦
/// computed as   τ = ⎡ cos φ  −sin φ ⎤  (k̂·k̂′ ≥ 0),    τ = ⎡  cos φ  −sin φ ⎤  (k̂·k̂′ < 0)
///                   ⎣ sin φ   cos φ ⎦                     ⎣ −sin φ  −cos φ ⎦
/// with φ = rotation_angle(from, to).
/// ```
/// For the new basis turned by ψ counter-clockwise about k̂, `τ = [[cos ψ, sin ψ], [−sin ψ, cos ψ]]`
/// (φ = −ψ). Where S2.3's normalized projections are orthogonal this *is* S2.3's matrix; otherwise
/// it is the orthogonal matrix closest to it (see [`rotation_angle`]).
///
/// **Backward frames** (`k̂·k̂′ < 0`, e.g. specular reflection at incidence below 45° in s/p
/// frames): the projection reverses orientation and S2.3's matrix is a reflection. τ is then
/// `diag(1, −1) τ(from, to.reversed())`. It is discontinuous across `k̂·k̂′ = 0`, where the
/// projection loses a dimension; exactly at `k̂·k̂′ = 0` (S2.3's singular case) and within a
/// rounding margin of `256 ε` below it, τ is the rotation. `τ(to, from) = τ(from, to)ᵀ` always.
///
/// # Examples
/// ```
/// use gmueller::frame::{Frame, tau};
/// use nalgebra::{Matrix2, Vector3};
/// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
/// assert_eq!(tau(&f, &f), Matrix2::identity());
/// let psi = 0.4_f64;
/// let t = tau(&f, &f.rotated(psi));
/// let expected = Matrix2::new(psi.cos(), psi.sin(), -psi.sin(), psi.cos());
/// assert!((t - expected).norm() < 1e-15);
/// ```
#[must_use]
pub fn tau<T: Real>(from: &Frame<T>, to: &Frame<T>) -> Matrix2<T> {
    change(from, to).tau()
}

/// The Mueller matrix of a rotation of the transverse frame, T(φ) of S2.4, in closed form.
///
/// # Formula
/// ```text
/// S2.4:  T(φ) = A_mül (τ ⊗ τ) A_mül⁻¹ = ⎡ 1    0        0      0 ⎤
///                                        ⎢ 0  cos 2φ  −sin 2φ   0 ⎥
///                                        ⎢ 0  sin 2φ   cos 2φ   0 ⎥
///                                        ⎣ 0    0        0      1 ⎦
/// with τ = [[cos φ, −sin φ], [sin φ, cos φ]].
/// ```
/// φ is S2.3's angle from x̂′⊥ to x̂: a frame turned by ψ counter-clockwise about k̂ (seen
/// facing the source) has `T = rotation_mueller(−ψ)`. Mitsuba 3's `rotator(θ)` is
/// `rotation_mueller(−θ)`. T(0) = I exactly, T(φ₁) T(φ₂) = T(φ₁ + φ₂), T(π) = I.
///
/// # Examples
/// ```
/// use gmueller::frame::rotation_mueller;
/// use nalgebra::{Matrix4, Vector4};
/// assert_eq!(rotation_mueller(0.0_f64).matrix(), Matrix4::identity());
/// // Turning the frame by ψ = 45° makes x̂-polarized light (S1 = 1) read S2 = −1.
/// let s = rotation_mueller(-core::f64::consts::FRAC_PI_4).matrix() * Vector4::new(1.0, 1.0, 0.0, 0.0);
/// assert!((s - Vector4::new(1.0, 0.0, -1.0, 0.0)).norm() < 1e-15);
/// ```
#[must_use]
pub fn rotation_mueller<T: Real>(phi: T) -> Mueller<T> {
    let (s, c) = (phi + phi).sin_cos();
    Mueller(rotation_mueller_cs(c, s))
}

/// S2.4's T from `cos 2φ` and `sin 2φ`.
#[inline]
fn rotation_mueller_cs<T: Real>(c: T, s: T) -> Matrix4<T> {
    let (o, z) = (T::one(), T::zero());
    Matrix4::new(
        o, z, z, z, //
        z, c, -s, z, //
        z, s, c, z, //
        z, z, z, o,
    )
}

/// The Mueller matrix T of the frame change `from → to`: `S′ = T S` re-expresses a Stokes vector.
///
/// # Formula
/// ```text
/// T = A_mül (τ ⊗ τ) A_mül⁻¹ = T(φ) (S2.4)              when k̂·k̂′ ≥ 0
///                          = diag(1, 1, −1, −1) T(φ)    when k̂·k̂′ < 0,    φ = rotation_angle(from, to)
/// ```
/// Exactly orthogonal; `T(to → from) = T(from → to)ᵀ`; identical frames give I exactly.
///
/// # Examples
/// ```
/// use gmueller::frame::{Frame, frame_change_mueller};
/// use nalgebra::{Matrix4, Vector3};
/// let f = Frame::<f64>::sp(Vector3::new(1.0, 0.0, -1.0), Vector3::z()).unwrap();
/// assert_eq!(frame_change_mueller(&f, &f).matrix(), Matrix4::identity());
/// ```
#[must_use]
pub fn frame_change_mueller<T: Real>(from: &Frame<T>, to: &Frame<T>) -> Mueller<T> {
    Mueller(change(from, to).mueller())
}

/// `frame_change_mueller(from, to) · m` without the 4×4 product: `T` keeps row 0, turns rows
/// 1 and 2 by `2φ` and negates rows 2 and 3 for a flip, so only those rows are formed. The
/// same numbers as the product for finite `m` (the product's other terms are exact zeros).
#[inline]
#[must_use]
pub(crate) fn frame_change_times<T: Real>(
    from: &Frame<T>,
    to: &Frame<T>,
    m: &Mueller<T>,
) -> Mueller<T> {
    let ch = change(from, to);
    let (c, s) = (ch.cos, ch.sin);
    let (c2, s2) = (c * c - s * s, (s + s) * c);
    let mut out = m.0;
    for col in 0..4 {
        let (a, b) = (m.0[(1, col)], m.0[(2, col)]);
        out[(1, col)] = c2 * a - s2 * b;
        out[(2, col)] = s2 * a + c2 * b;
        if ch.flip {
            out[(2, col)] = -out[(2, col)];
            out[(3, col)] = -out[(3, col)];
        }
    }
    Mueller(out)
}

/// Re-expresses a Stokes vector given in `from` in the frame `to`: `S′ = T S`.
///
/// # Formula
/// ```text
/// S′ = T(from → to) S        (see frame_change_mueller; S2.4)
/// ```
/// The result describes the same field as the Jones vector re-expressed by τ
/// ([`jones_vector_to_frame`]): `Stokes(τ j) = T Stokes(j)`.
///
/// # Examples
/// ```
/// use gmueller::{frame::{Frame, stokes_to_frame}, stokes::Stokes};
/// use nalgebra::Vector3;
/// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
/// let s = Stokes::new(1.0, 1.0, 0.0, 0.0).unwrap(); // x̂-polarized
/// let s2 = stokes_to_frame(&s, &f, &f.rotated(core::f64::consts::FRAC_PI_2));
/// assert!((s2.vector()[1] + 1.0).abs() < 1e-15); // now along −ŷ′ direction: S1 = −1
/// ```
#[must_use]
pub fn stokes_to_frame<T: Real>(s: &Stokes<T>, from: &Frame<T>, to: &Frame<T>) -> Stokes<T> {
    Stokes(change(from, to).mueller() * s.0)
}

/// Re-expresses a Mueller matrix given for input frame `in_from` and output frame `out_from` in
/// the frames `in_to` (input) and `out_to` (output).
///
/// # Formula
/// ```text
/// S_out,to = T_out S_out,from = T_out M S_in,from = T_out M T_in⁻¹ S_in,to
/// ⇒  M′ = T_out M T_inᵀ,   T_in = T(in_from → in_to),  T_out = T(out_from → out_to)
/// ```
/// (T is orthogonal, so `T_in⁻¹ = T_inᵀ = T(in_to → in_from)`.)
///
/// # Examples
/// ```
/// use gmueller::{frame::{Frame, mueller_to_frames}, jones::JonesMatrix, mueller::Mueller};
/// use nalgebra::Vector3;
/// // A polarizer along x̂ re-expressed in frames turned by 90°: a polarizer along ŷ′.
/// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
/// let g = f.rotated(core::f64::consts::FRAC_PI_2);
/// let m = Mueller::from_jones(&JonesMatrix::linear_polarizer(0.0));
/// let m2 = mueller_to_frames(&m, &f, &g, &f, &g);
/// let expected = Mueller::from_jones(&JonesMatrix::linear_polarizer(core::f64::consts::FRAC_PI_2));
/// assert!((m2.matrix() - expected.matrix()).norm() < 1e-15);
/// ```
#[must_use]
pub fn mueller_to_frames<T: Real>(
    m: &Mueller<T>,
    in_from: &Frame<T>,
    in_to: &Frame<T>,
    out_from: &Frame<T>,
    out_to: &Frame<T>,
) -> Mueller<T> {
    let t_in = change(in_from, in_to).mueller();
    let t_out = change(out_from, out_to).mueller();
    Mueller(t_out * m.0 * t_in.transpose())
}

fn complexify<T: Real>(m: Matrix2<T>) -> Matrix2<Complex<T>> {
    m.map(|v| Complex::new(v, T::zero()))
}

/// Re-expresses a Jones vector given in `from` in the frame `to`: `j′ = τ j` (S2.3).
///
/// # Examples
/// ```
/// use gmueller::{frame::{Frame, jones_vector_to_frame}, jones::JonesVector};
/// use nalgebra::Vector3;
/// use num_complex::Complex;
/// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
/// let j = JonesVector::new(Complex::new(1.0, 0.0), Complex::new(0.0, 0.0)).unwrap();
/// let j2 = jones_vector_to_frame(&j, &f, &f.reversed());
/// assert!((j2.ex().re - 1.0).abs() < 1e-15 && j2.ey().norm() < 1e-15);
/// ```
#[must_use]
pub fn jones_vector_to_frame<T: Real>(
    j: &JonesVector<T>,
    from: &Frame<T>,
    to: &Frame<T>,
) -> JonesVector<T> {
    JonesVector(complexify(change(from, to).tau()) * j.0)
}

/// Re-expresses a Jones matrix given for frames (`in_from` → `out_from`) in the frames
/// (`in_to` → `out_to`).
///
/// # Formula
/// ```text
/// J′ = τ_out J τ_inᵀ,   τ_in = τ(in_from → in_to),  τ_out = τ(out_from → out_to)   (τ⁻¹ = τᵀ)
/// ```
/// Its Mueller matrix is [`mueller_to_frames`] of the Mueller matrix of J.
///
/// # Examples
/// ```
/// use gmueller::{frame::{Frame, jones_matrix_to_frames}, jones::JonesMatrix};
/// use nalgebra::Vector3;
/// let f = Frame::<f64>::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
/// let g = f.rotated(0.7);
/// let j = JonesMatrix::linear_retarder(0.2, 1.0);
/// let back = jones_matrix_to_frames(&jones_matrix_to_frames(&j, &f, &g, &f, &g), &g, &f, &g, &f);
/// assert!((back.matrix() - j.matrix()).norm() < 1e-15);
/// ```
#[must_use]
pub fn jones_matrix_to_frames<T: Real>(
    j: &JonesMatrix<T>,
    in_from: &Frame<T>,
    in_to: &Frame<T>,
    out_from: &Frame<T>,
    out_to: &Frame<T>,
) -> JonesMatrix<T> {
    let t_in = complexify(change(in_from, in_to).tau());
    let t_out = complexify(change(out_from, out_to).tau());
    JonesMatrix(t_out * j.0 * t_in.transpose())
}

pub mod convention;

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform in [−1, 1).
    fn next(state: &mut u64) -> f64 {
        (crate::numerics::splitmix64(state) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn direction(state: &mut u64) -> Vector3<f64> {
        Vector3::new(next(state), next(state), next(state) + 1e-3)
    }

    /// `frame_change_times` is `frame_change_mueller(from, to) · m` bit for bit, f64 and f32,
    /// over 20 000 random pairs of s/p frames (about half of them across reversed k̂, the
    /// flip), and m with entries of magnitudes 10^±30.
    #[test]
    fn frame_change_times_is_the_product() {
        let mut state = 0xf1a7;
        let n = Vector3::z();
        let mut flips = 0;
        for _ in 0..20_000 {
            let (a, b) = (direction(&mut state), direction(&mut state));
            let from = Frame::sp(a, n).unwrap();
            let to = Frame::sp(if next(&mut state) < 0.0 { -b } else { b }, n).unwrap();
            flips += usize::from(from.k().dot(&to.k()) < 0.0);
            let m = Mueller(Matrix4::from_fn(|_, _| {
                next(&mut state) * 10f64.powf(30.0 * next(&mut state))
            }));
            let product = (frame_change_mueller(&from, &to) * m).0;
            assert_eq!(frame_change_times(&from, &to, &m).0, product);
            let (from, to) = (from.map_f32(), to.map_f32());
            let m = Mueller(m.0.map(|x| x as f32));
            assert_eq!(
                frame_change_times(&from, &to, &m).0,
                (frame_change_mueller(&from, &to) * m).0
            );
        }
        assert!(flips > 5000, "{flips}");
    }

    impl Frame<f64> {
        fn map_f32(&self) -> Frame<f32> {
            Frame {
                x: self.x.map(|v| v as f32),
                y: self.y.map(|v| v as f32),
                k: self.k.map(|v| v as f32),
            }
        }
    }
}
