//! The mean scattering matrix `m̄` of a random medium (S2.8, S2.19): the Mueller matrix with
//! which one volume element scatters, as a function of the scattering angle, in
//! scattering-plane frames.
//!
//! # Formula
//! ```text
//! Dipole (first Born, E_s ∝ (I − r̂r̂ᵀ) E):   J = diag(1, cos Θ)
//!   M = ½ [[1 + c², 1 − c², 0, 0], [1 − c², 1 + c², 0, 0], [0, 0, 2c, 0], [0, 0, 0, 2c]],  c = cos Θ
//! Scalar (the scalar Born approximation, no polarization):  M = diag(1, 0, 0, 0)
//! ```
//! in the frames `(ê_⊥, d̂ × ê_⊥, d̂) → (ê_⊥, r̂ × ê_⊥, r̂)`, `ê_⊥ = d̂ × r̂/|d̂ × r̂|` the normal of
//! the scattering plane (x̂ = ⊥ = "s", ŷ = ∥ = "p"), d̂ the travel direction of the light and r̂
//! the exit direction; `M = A_mül (J* ⊗ J) A_mül⁻¹` (S1.7 with `p₁ = p₂`). With `S1 = I_⊥ − I_∥`
//! this is van de Hulst's Rayleigh matrix (*Light Scattering by Small Particles*, 1957, §6.1;
//! Chandrasekhar, *Radiative Transfer*, 1950, §17) without its normalisation.

use nalgebra::Matrix4;

use crate::mueller::Mueller;
use crate::real::Real;

/// The mean scattering matrix `m̄` of a medium whose scatterers are randomly oriented and
/// mirror-symmetric: a Mueller matrix that depends on the scattering angle Θ only, acting on
/// Stokes vectors in the incident scattering-plane frame `(ê_⊥, d̂ × ê_⊥, d̂)` and returning them
/// in the exit scattering-plane frame `(ê_⊥, r̂ × ê_⊥, r̂)` (`ê_⊥ = d̂ × r̂/|d̂ × r̂|`, d̂ the
/// light's travel direction, r̂ the exit; x̂ = ⊥ = "s", ŷ = ∥ = "p").
///
/// The medium multiplies it by the Born constant `k⁴/16π²` and the coherence weights `K³_α`
/// ([`crate::medium`]); `m̄` itself is dimensionless, normalised as the Born dipole is
/// (`M₀₀ = 1` in the forward direction for [`Dipole`] and [`Scalar`]).
///
/// Implement it for another scatterer (a depolarizing Rayleigh matrix, a tabulated Mie
/// matrix). The forward and backward matrices must be those of a symmetric scatterer: at
/// `cos Θ = ±1` the scattering plane is undefined and the medium uses a frame of its own
/// choice, so `M(1)` must commute with the rotations `T(φ)` of S2.4 and `M(−1)` satisfy
/// `M(−1) T(φ) = T(−φ) M(−1)` (true of every matrix of the form
/// `[[a, b, 0, 0], [b, a, 0, 0], [0, 0, c, d], [0, 0, −d, c]]` with `b = 0` at `Θ = 0, π`).
///
/// # Examples
/// A depolarizing Rayleigh scatterer (Chandrasekhar's ρ-form) written downstream:
/// ```
/// use gmueller::medium::{Dipole, Scatterer};
/// use gmueller::mueller::Mueller;
/// use gmueller::real::Real;
/// use nalgebra::Matrix4;
///
/// /// The dipole matrix mixed with an isotropic depolarizer: `(1 − w) M_dipole + w diag(1, 0, 0, 0)`.
/// struct Depolarized<T>(T);
/// impl<T: Real> Scatterer<T> for Depolarized<T> {
///     fn mueller(&self, cos_theta: T) -> Mueller<T> {
///         let d = Dipole.mueller(cos_theta).matrix() * (T::one() - self.0);
///         let mut m = Matrix4::zeros();
///         m[(0, 0)] = self.0;
///         Mueller::from_matrix(d + m).unwrap()
///     }
/// }
/// let m = Depolarized(0.2_f64).mueller(0.0); // 90°
/// assert!((m.matrix()[(0, 0)] - 0.6).abs() < 1e-15 && (m.matrix()[(0, 1)] - 0.4).abs() < 1e-15);
/// ```
pub trait Scatterer<T: Real> {
    /// `m̄(cos Θ)` in the scattering-plane frames (see the trait docs); `cos_theta ∈ [−1, 1]`.
    #[must_use]
    fn mueller(&self, cos_theta: T) -> Mueller<T>;

    /// `m̄₀₀(cos Θ)`, what the [`crate::interaction::Intensity`] level uses (by default from
    /// [`Scatterer::mueller`]).
    #[inline]
    #[must_use]
    fn m00(&self, cos_theta: T) -> T {
        self.mueller(cos_theta).0[(0, 0)]
    }
}

/// The first-Born scatterer of a fluctuating permittivity: the induced dipole radiates
/// `E_s ∝ (I − r̂r̂ᵀ) E = −r̂ × (r̂ × E)`, i.e. the Rayleigh matrix: with `S1 = I_⊥ − I_∥`, van
/// de Hulst's (*Light Scattering by Small Particles*, 1957, §6.1) without its normalisation
/// (`tests/medium/born.rs` compares it with Bohren & Huffman's small-sphere matrix).
///
/// # Formula
/// ```text
/// J = diag(1, cos Θ)   (⊥, ∥),     M = ½ [[1 + c², s², 0, 0], [s², 1 + c², 0, 0], [0, 0, 2c, 0], [0, 0, 0, 2c]]
/// ```
/// with `c = cos Θ`, `s² = (1 − c)(1 + c)` (formed so, not as `1 − c²`: accurate near
/// `Θ = 0, π`).
///
/// # Examples
/// ```
/// use gmueller::medium::{Dipole, Scatterer};
/// // At 90° unpolarized light becomes fully polarized perpendicular to the scattering plane.
/// let m = Dipole.mueller(0.0_f64).matrix();
/// assert!((m[(0, 0)] - 0.5).abs() < 1e-15 && (m[(1, 0)] - 0.5).abs() < 1e-15);
/// assert!(m[(2, 2)].abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Dipole;

impl<T: Real> Scatterer<T> for Dipole {
    #[inline]
    fn mueller(&self, cos_theta: T) -> Mueller<T> {
        let c = cos_theta;
        let half = T::lit(0.5);
        let s2 = (T::one() - c) * (T::one() + c) * half;
        let a = (T::one() + c * c) * half;
        let z = T::zero();
        #[rustfmt::skip]
        let m = Matrix4::new(
            a, s2, z, z,
            s2, a, z, z,
            z, z, c, z,
            z, z, z, c,
        );
        Mueller(m)
    }

    #[inline]
    fn m00(&self, cos_theta: T) -> T {
        (T::one() + cos_theta * cos_theta) * T::lit(0.5)
    }
}

/// The scalar scatterer of the scalar Born approximation: a scalar wave has no polarization, so
/// the scattered light has the intensity of the scalar theory (`m̄₀₀ = 1`, the same in every
/// direction for the same `K³`) and is unpolarized, `M = diag(1, 0, 0, 0)` — the only
/// rotation-invariant choice that is also valid backward (the identity between the
/// scattering-plane frames is not: at `Θ = π` it depends on the arbitrary `ê_⊥`).
///
/// # Examples
/// ```
/// use gmueller::medium::{Scalar, Scatterer};
/// let m = Scalar.mueller(0.3_f64).matrix();
/// assert_eq!(m[(0, 0)], 1.0);
/// assert_eq!(m.iter().filter(|&&x| x != 0.0).count(), 1);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Scalar;

impl<T: Real> Scatterer<T> for Scalar {
    #[inline]
    fn mueller(&self, _cos_theta: T) -> Mueller<T> {
        let mut m = Matrix4::zeros();
        m[(0, 0)] = T::one();
        Mueller(m)
    }

    #[inline]
    fn m00(&self, _cos_theta: T) -> T {
        T::one()
    }
}
