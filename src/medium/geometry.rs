//! The geometry of one scattering event in a medium: the scattering vector `h`, the scattering
//! angle, and the scattering-plane frames the phase matrix maps between.
//!
//! # Formula
//! ```text
//! h = k(r̂ − d̂) = k(r̂ + ŝ),   cos Θ = r̂·d̂,   |h| = 2k sin(Θ/2)
//! ê_⊥ = d̂ × r̂ / |d̂ × r̂|                                  (normal of the scattering plane)
//! incident frame (ê_⊥, d̂ × ê_⊥, d̂),   exit frame (ê_⊥, r̂ × ê_⊥, r̂)
//! ```
//! d̂ is the packet's travel direction (`ŝ = −d̂` points toward the source), r̂ the exit
//! direction. **Forward and backward** (`|d̂ × r̂| < √ε`, within ≈ 1.5e-8 rad in `f64`,
//! 3.5e-4 rad in `f32`): the scattering plane is undefined, and `ê_⊥` is the packet's own x̂
//! made orthogonal to r̂. A scatterer whose forward and backward matrices are those of a
//! symmetric particle ([`super::Scatterer`]) then gives the same light whichever ê_⊥ is chosen:
//! the switch moves the result by the `O(Θ²) ≤ ε` by which `m̄(cos Θ)` differs from `m̄(±1)`
//! (the frames' own vectors are orthonormal to rounding on both sides of it).

use nalgebra::Vector3;

use crate::error::{Error, ensure_finite};
use crate::frame::Frame;
use crate::real::Real;

/// `v` minus its component along the unit vector `k`, normalized, twice ("twice is enough"):
/// orthogonal to `k` to rounding. The caller guarantees `|v − (v·k)k|` is not small.
#[inline]
fn orthogonalize<T: Real>(v: &Vector3<T>, k: &Vector3<T>) -> Vector3<T> {
    let a = v - k * v.dot(k);
    let a = a / a.norm();
    let b = a - k * a.dot(k);
    b / b.norm()
}

/// One exit direction of a packet scattered in a medium: the scattering vector, the scattering
/// angle and the scattering-plane frames the phase matrix maps between.
///
/// # Formula
/// ```text
/// h = k(r̂ − d̂) = k(r̂ + ŝ),   cos Θ = r̂·d̂,   |h| = 2k sin(Θ/2)
/// ê_⊥ = d̂ × r̂ / |d̂ × r̂|                                  (normal of the scattering plane)
/// incident frame (ê_⊥, d̂ × ê_⊥, d̂),   exit frame (ê_⊥, r̂ × ê_⊥, r̂)
/// ```
/// d̂ is the packet's travel direction (`ŝ = −d̂` points toward the source), r̂ the exit
/// direction. **Forward and backward** (`|d̂ × r̂| < √ε`, within ≈ 1.5e-8 rad in `f64`,
/// 3.5e-4 rad in `f32`): the scattering plane is undefined, and `ê_⊥` is the packet's own x̂
/// made orthogonal to r̂. A scatterer whose forward and backward matrices are those of a
/// symmetric particle ([`super::Scatterer`]) then gives the same light whichever ê_⊥ is chosen
/// (`tests/medium/limits.rs`: continuous in a fixed frame across the switch).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScatteringGeometry<T: Real> {
    pub(crate) h: Vector3<T>,
    pub(crate) cos_theta: T,
    pub(crate) incident: Frame<T>,
    pub(crate) exit: Frame<T>,
}

impl<T: Real> ScatteringGeometry<T> {
    /// The geometry of light travelling along `packet_frame.k()` with wavenumber `k` (in the
    /// medium) and leaving along `exit` (any length).
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN or ∞ components; [`Error::InvalidBasis`] for a zero
    /// exit direction.
    pub fn new(packet_frame: &Frame<T>, k: T, exit: Vector3<T>) -> Result<Self, Error> {
        ensure_finite("exit direction", exit.iter().copied())?;
        let r = crate::numerics::unit_by_largest(&exit).ok_or(Error::InvalidBasis {
            reason: "zero exit direction",
        })?;
        Ok(Self::from_unit(packet_frame, k, r))
    }

    /// [`Self::new`] for a finite unit `r` (hot paths).
    #[inline]
    pub(crate) fn from_unit(packet_frame: &Frame<T>, k: T, r: Vector3<T>) -> Self {
        let d = packet_frame.k;
        let c = d.cross(&r);
        let sin_theta = c.norm();
        // Forward or backward (|d̂ × r̂| < √ε): the packet's own x̂ (orthogonal to d̂ already).
        let perp = if sin_theta >= T::EPSILON.sqrt() {
            c / sin_theta
        } else {
            packet_frame.x
        };
        let x_i = orthogonalize(&perp, &d);
        let x_o = orthogonalize(&perp, &r);
        Self {
            h: (r - d) * k,
            cos_theta: r.dot(&d).clamp(-T::one(), T::one()),
            incident: Frame {
                x: x_i,
                y: d.cross(&x_i),
                k: d,
            },
            exit: Frame {
                x: x_o,
                y: r.cross(&x_o),
                k: r,
            },
        }
    }

    /// The scattering vector `h = k(r̂ − d̂)` (rad/length).
    #[inline]
    #[must_use]
    pub fn scattering_vector(&self) -> Vector3<T> {
        self.h
    }

    /// `cos Θ = r̂·d̂`.
    #[inline]
    #[must_use]
    pub fn cos_theta(&self) -> T {
        self.cos_theta
    }

    /// The incident scattering-plane frame `(ê_⊥, d̂ × ê_⊥, d̂)`.
    #[inline]
    #[must_use]
    pub fn incident_frame(&self) -> &Frame<T> {
        &self.incident
    }

    /// The exit scattering-plane frame `(ê_⊥, r̂ × ê_⊥, r̂)`: the frame of the scattered
    /// Stokes vectors and the output side of the phase matrix.
    #[inline]
    #[must_use]
    pub fn exit_frame(&self) -> &Frame<T> {
        &self.exit
    }

    /// The unit exit direction r̂.
    #[inline]
    #[must_use]
    pub fn exit_direction(&self) -> Vector3<T> {
        self.exit.k
    }
}
