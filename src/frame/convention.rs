//! Converters between this crate's conventions and other libraries'.
//!
//! Each function is an involution (its own inverse), so one function converts both ways.
//!
//! | other convention | who | converter |
//! |---|---|---|
//! | time dependence `e^{+iωt}` (S3 sign) | Mitsuba 3, pypolar, py-pol's elements | `flip_time_convention_*` |
//! | frame rotation `rotator(θ)` | Mitsuba 3 | [`mitsuba_rotator`] |
//! | component order (p, s) instead of (s, p) | various Fresnel codes | `swap_sp_*` |
//! | complex index `n − iκ` | `e^{+iωt}` codes | [`flip_time_convention_index`] |

use nalgebra::{Matrix2, Matrix4, Vector2};
use num_complex::Complex;

use super::rotation_mueller;
use crate::jones::{JonesMatrix, JonesVector};
use crate::mueller::Mueller;
use crate::real::Real;
use crate::stokes::Stokes;

/// Converts a Stokes vector between `e^{−iωt}` (this crate) and `e^{+iωt}` (Mitsuba 3,
/// pypolar, py-pol's elements): `S ↦ D S`, `D = diag(1, 1, 1, −1)`.
///
/// The same physical circular state has the opposite S3 sign in the two conventions.
///
/// # Examples
/// ```
/// use gmueller::{frame::convention::flip_time_convention_stokes, stokes::Stokes};
/// let s = Stokes::new(1.0_f64, 0.0, 0.0, 1.0).unwrap();
/// assert_eq!(flip_time_convention_stokes(&s).vector()[3], -1.0);
/// ```
#[must_use]
pub fn flip_time_convention_stokes<T: Real>(s: &Stokes<T>) -> Stokes<T> {
    let mut v = s.0;
    v[3] = -v[3];
    Stokes(v)
}

/// Converts a Mueller matrix between `e^{−iωt}` (this crate) and `e^{+iωt}` (Mitsuba 3,
/// pypolar, py-pol's elements): `M ↦ D M D`, `D = diag(1, 1, 1, −1)`.
///
/// Equals the Mueller matrix of the conjugated Jones matrix
/// ([`flip_time_convention_jones_matrix`]).
///
/// # Examples
/// ```
/// use gmueller::{frame::convention::flip_time_convention_mueller, jones::JonesMatrix,
///                mueller::Mueller};
/// // Quarter-wave plate, fast axis x̂: M[3][2] = +1 here, −1 in Mitsuba 3.
/// let q = Mueller::from_jones(&JonesMatrix::<f64>::linear_retarder(0.0, core::f64::consts::FRAC_PI_2));
/// assert!((q.matrix()[(3, 2)] - 1.0).abs() < 1e-15);
/// assert!((flip_time_convention_mueller(&q).matrix()[(3, 2)] + 1.0).abs() < 1e-15);
/// ```
#[must_use]
pub fn flip_time_convention_mueller<T: Real>(m: &Mueller<T>) -> Mueller<T> {
    let mut out = m.0;
    for i in 0..3 {
        out[(3, i)] = -out[(3, i)];
        out[(i, 3)] = -out[(i, 3)];
    }
    Mueller(out)
}

/// Converts a Jones vector between `e^{−iωt}` and `e^{+iωt}`: complex conjugation.
///
/// # Examples
/// ```
/// use gmueller::{frame::convention::flip_time_convention_jones_vector, jones::JonesVector};
/// use num_complex::Complex;
/// let j = JonesVector::new(Complex::new(1.0_f64, 0.0), Complex::new(0.0, 1.0)).unwrap();
/// assert_eq!(flip_time_convention_jones_vector(&j).ey(), Complex::new(0.0, -1.0));
/// ```
#[must_use]
pub fn flip_time_convention_jones_vector<T: Real>(j: &JonesVector<T>) -> JonesVector<T> {
    JonesVector(j.0.map(|z| z.conj()))
}

/// Converts a Jones matrix between `e^{−iωt}` and `e^{+iωt}`: complex conjugation (a
/// quarter-wave plate `diag(1, i)` here is `diag(1, −i)` there).
///
/// # Examples
/// ```
/// use gmueller::{frame::convention::flip_time_convention_jones_matrix, jones::JonesMatrix};
/// let q = JonesMatrix::<f64>::linear_retarder(0.0, core::f64::consts::FRAC_PI_2);
/// assert!((flip_time_convention_jones_matrix(&q).matrix()[(1, 1)].im + 1.0).abs() < 1e-15);
/// ```
#[must_use]
pub fn flip_time_convention_jones_matrix<T: Real>(j: &JonesMatrix<T>) -> JonesMatrix<T> {
    JonesMatrix(j.0.map(|z| z.conj()))
}

/// Converts a complex refractive index between `n + iκ` (this crate, `e^{−iωt}`, κ ≥ 0
/// absorbing) and `n − iκ` (`e^{+iωt}` codes): complex conjugation.
///
/// # Examples
/// ```
/// use gmueller::frame::convention::flip_time_convention_index;
/// use num_complex::Complex;
/// assert_eq!(flip_time_convention_index(Complex::new(0.2_f64, 3.0)), Complex::new(0.2, -3.0));
/// ```
#[must_use]
pub fn flip_time_convention_index<T: Real>(eta: Complex<T>) -> Complex<T> {
    eta.conj()
}

/// Mitsuba 3's `rotator(θ)` (a rotation of the reference frame by +θ), expressed in this
/// crate: `rotation_mueller(−θ)`.
///
/// # Formula
/// ```text
/// rotator(θ) = T(−θ) = ⎡ 1    0       0      0 ⎤
///                      ⎢ 0  cos 2θ  sin 2θ   0 ⎥
///                      ⎢ 0 −sin 2θ  cos 2θ   0 ⎥
///                      ⎣ 0    0       0      1 ⎦
/// ```
/// It has no S3 coupling, so the time-convention flip leaves it unchanged.
///
/// # Examples
/// ```
/// use gmueller::frame::convention::mitsuba_rotator;
/// let m = mitsuba_rotator(0.3_f64).matrix();
/// assert!((m[(1, 2)] - 0.6_f64.sin()).abs() < 1e-15);
/// ```
#[must_use]
pub fn mitsuba_rotator<T: Real>(theta: T) -> Mueller<T> {
    rotation_mueller(-theta)
}

fn swap<T: Real>() -> Matrix2<Complex<T>> {
    let (o, z) = (
        Complex::new(T::one(), T::zero()),
        Complex::new(T::zero(), T::zero()),
    );
    Matrix2::new(z, o, o, z)
}

/// Swaps the component order of a Jones vector, (s, p) ↔ (p, s): `j ↦ P j`,
/// `P = [[0, 1], [1, 0]]`.
///
/// Note that (p̂, ŝ, k̂) is left-handed: S3 changes sign with the order
/// ([`swap_sp_stokes`]).
///
/// # Examples
/// ```
/// use gmueller::{frame::convention::swap_sp_jones_vector, jones::JonesVector};
/// use num_complex::Complex;
/// let j = JonesVector::new(Complex::new(1.0_f64, 0.0), Complex::new(2.0, 0.0)).unwrap();
/// assert_eq!(swap_sp_jones_vector(&j).ex().re, 2.0);
/// ```
#[must_use]
pub fn swap_sp_jones_vector<T: Real>(j: &JonesVector<T>) -> JonesVector<T> {
    JonesVector(Vector2::new(j.0[1], j.0[0]))
}

/// Swaps the component order of a Jones matrix, (s, p) ↔ (p, s): `J ↦ P J P`,
/// `P = [[0, 1], [1, 0]]`.
///
/// # Examples
/// ```
/// use gmueller::{frame::convention::swap_sp_jones_matrix, jones::JonesMatrix};
/// let j = JonesMatrix::<f64>::linear_polarizer(0.0);
/// assert!((swap_sp_jones_matrix(&j).matrix()[(1, 1)].re - 1.0).abs() < 1e-15);
/// ```
#[must_use]
pub fn swap_sp_jones_matrix<T: Real>(j: &JonesMatrix<T>) -> JonesMatrix<T> {
    let p = swap::<T>();
    JonesMatrix(p * j.0 * p)
}

/// Swaps the component order of a Stokes vector, (s, p) ↔ (p, s): `S ↦ E S`,
/// `E = diag(1, −1, 1, −1)`.
///
/// # Formula
/// ```text
/// E_x ↔ E_y:  S1 = |E_x|² − |E_y|² ↦ −S1,   S2 = 2 Re(E_x E_y*) ↦ S2,
///             S3 = 2 Im(E_x* E_y) ↦ −S3
/// ```
///
/// # Examples
/// ```
/// use gmueller::{frame::convention::swap_sp_stokes, stokes::Stokes};
/// let s = Stokes::new(1.0_f64, 0.6, 0.0, 0.8).unwrap();
/// assert_eq!(swap_sp_stokes(&s).vector(), nalgebra::Vector4::new(1.0, -0.6, 0.0, -0.8));
/// ```
#[must_use]
pub fn swap_sp_stokes<T: Real>(s: &Stokes<T>) -> Stokes<T> {
    let mut v = s.0;
    v[1] = -v[1];
    v[3] = -v[3];
    Stokes(v)
}

/// Swaps the component order of a Mueller matrix, (s, p) ↔ (p, s): `M ↦ E M E`,
/// `E = diag(1, −1, 1, −1)`; equals the Mueller matrix of [`swap_sp_jones_matrix`].
///
/// # Examples
/// ```
/// use gmueller::{frame::convention::swap_sp_mueller, jones::JonesMatrix, mueller::Mueller};
/// let m = Mueller::from_jones(&JonesMatrix::<f64>::linear_polarizer(0.0));
/// assert!((swap_sp_mueller(&m).matrix()[(0, 1)] + 0.5).abs() < 1e-15);
/// ```
#[must_use]
pub fn swap_sp_mueller<T: Real>(m: &Mueller<T>) -> Mueller<T> {
    let e = Matrix4::from_diagonal(&nalgebra::Vector4::new(
        T::one(),
        -T::one(),
        T::one(),
        -T::one(),
    ));
    Mueller(e * m.0 * e)
}
