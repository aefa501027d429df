//! Fresnel amplitude coefficients of a planar interface, as Jones matrices in an explicit s/p basis.
//!
//! Light arrives from a lossless medium of real index `n₁` onto a medium of complex index
//! `n₂ = n + iκ`; everything depends only on the relative index `η = n₂/n₁` (`η = n + iκ` when
//! `n₁ = 1`), with `Re η > 0` and `Im η = κ ≥ 0` absorbing (time dependence `e^{−iωt}`, crate
//! conventions).
//!
//! # Bases
//! Each beam (incident, reflected, transmitted) is described in its own right-handed transverse
//! basis `(x̂, ŷ, k̂)` with `x̂ = ŝ`, the unit normal of the plane of incidence (common to all three
//! beams), and `ŷ = p̂ = k̂ × ŝ`. At normal incidence the reflected `p̂` is therefore the
//! *opposite* of the incident one, and `r_p = −r_s`: the Mueller matrix of reflection is that of a
//! mirror, `R · diag(1, 1, −1, −1)` (S2 and S3 change sign). This is Born & Wolf's choice for
//! `r_∥` (*Principles of Optics*, 7th ed., §1.5.2, eq. 21) and reproduces Mitsuba 3's
//! `specular_reflection` after the `e^{±iωt}` conversion `D M D`, `D = diag(1, 1, 1, −1)`.
//!
//! # Branch of `cos θ_t`
//! `cos θ_t = √(1 − sin²θ_i/η²)` on the principal branch (as Mitsuba 3 does). For `Re η > 0`,
//! `Im η ≥ 0` this equals `q/η` with `q = η cos θ_t = √(η² − sin²θ_i)` principal and in the closed
//! first quadrant, so `Im(η cos θ_t) ≥ 0`: the transmitted wave `e^{i k₀ n₁ q z}` decays into the
//! second medium. Under total internal reflection (real `η < 1`, `sin θ_i > η`) `q = +i√(sin²θ_i − η²)`
//! (an imaginary part `−0.0` from rounding is replaced by `+0.0` so the branch cut cannot flip it).
//! The code works with `q` directly and never divides by `cos θ_i` or `η cos θ_t`. It forms
//! `q² = (η² − 1) + cos²θ_i`, so that `η = 1` (no interface) gives `r_s = r_p = 0` exactly at
//! every angle whose `cos²θ_i` is a normal number (`tests/fresnel.rs`).

use nalgebra::Matrix2;
use num_complex::Complex;

use crate::error::Error;
use crate::jones::JonesMatrix;
use crate::numerics::principal_sqrt;
use crate::real::{Real, complex_is_finite};

/// The Fresnel amplitude coefficients of one interface at one angle of incidence, with the inputs
/// they were computed from.
///
/// Built by [`coefficients`] (infallible) or [`try_coefficients`] (validated). `r` are ratios of
/// reflected to incident field amplitudes, `t` of transmitted to incident ones, each in the s/p
/// bases of the [module documentation](self).
///
/// # Formula
/// ```text
/// q = η cos θ_t = √(η² − sin²θ_i),  c = cos θ_i
/// r_s = (c − q)/(c + q)               = (cos θ_i − η cos θ_t)/(cos θ_i + η cos θ_t)
/// r_p = (η² c − q)/(η² c + q)         = (η cos θ_i − cos θ_t)/(η cos θ_i + cos θ_t)
/// t_s = 2c/(c + q)                    = 2 cos θ_i/(cos θ_i + η cos θ_t)
/// t_p = 2ηc/(η² c + q)                = 2 cos θ_i/(η cos θ_i + cos θ_t)
/// ```
/// (Born & Wolf §1.5.2 eqs. 20–21 with `n₁ = 1`, `n₂ = η`; `1 + r_s = t_s`, `1 + r_p = η t_p`.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FresnelCoefficients<T: Real> {
    /// `r_s`, reflection of the s (TE) component.
    pub rs: Complex<T>,
    /// `r_p`, reflection of the p (TM) component (sign: see the module docs).
    pub rp: Complex<T>,
    /// `t_s`, field transmission of the s component.
    pub ts: Complex<T>,
    /// `t_p`, field transmission of the p component (ratio of electric field amplitudes).
    pub tp: Complex<T>,
    /// `cos θ_t` on the branch described in the module docs (`Im(η cos θ_t) ≥ 0`).
    pub cos_theta_t: Complex<T>,
    /// `cos θ_i` after clamping into `[0, 1]`.
    pub cos_theta_i: T,
    /// The relative index `η` used.
    pub eta: Complex<T>,
}

impl<T: Real> FresnelCoefficients<T> {
    /// Reflectance of s-polarized light, `R_s = |r_s|²`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::fresnel::coefficients;
    /// use num_complex::Complex;
    /// let f = coefficients(1.0_f64, Complex::new(1.5, 0.0));
    /// assert!((f.reflectance_s() - 0.04).abs() < 1e-15);
    /// ```
    #[inline]
    #[must_use]
    pub fn reflectance_s(&self) -> T {
        self.rs.norm_sqr()
    }

    /// Reflectance of p-polarized light, `R_p = |r_p|²`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::fresnel::coefficients;
    /// use num_complex::Complex;
    /// let n = 1.5_f64;
    /// let brewster = (1.0 / (1.0 + n * n)).sqrt(); // cos θ_B, tan θ_B = n
    /// assert!(coefficients(brewster, Complex::new(n, 0.0)).reflectance_p() < 1e-30);
    /// ```
    #[inline]
    #[must_use]
    pub fn reflectance_p(&self) -> T {
        self.rp.norm_sqr()
    }

    /// Transmittance (power fraction) of s-polarized light.
    ///
    /// # Formula
    /// ```text
    /// T_s = Re(η cos θ_t)/cos θ_i · |t_s|² = 4 c Re q / |c + q|²
    /// ```
    /// The ratio of the normal components of the time-averaged Poynting vectors just below and
    /// above the interface, so `R_s + T_s = 1` for every passive medium (also absorbing ones), and
    /// `T_s = 0` under total internal reflection. At grazing incidence (`c = 0`) it is 0.
    ///
    /// # Examples
    /// ```
    /// use gmueller::fresnel::coefficients;
    /// use num_complex::Complex;
    /// let f = coefficients(0.6_f64, Complex::new(1.5, 0.0));
    /// assert!((f.reflectance_s() + f.transmittance_s() - 1.0).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn transmittance_s(&self) -> T {
        let c = self.cos_theta_i;
        let q = self.eta * self.cos_theta_t;
        let d = Complex::new(c, T::zero()) + q;
        let den = d.norm_sqr();
        if den > T::zero() {
            T::lit(4.0) * c * q.re.max(T::zero()) / den
        } else {
            // η = 1 at grazing incidence: no interface.
            T::one()
        }
    }

    /// Transmittance (power fraction) of p-polarized light.
    ///
    /// # Formula
    /// ```text
    /// T_p = Re(η* cos θ_t)/cos θ_i · |t_p|² = 4 c Re(η*² q) / |η² c + q|²
    /// ```
    /// For p light the magnetic field is transverse and `E = Z₀ H/η`, so the Poynting flux carries
    /// `Re(η* cos θ_t)` (not `Re(η cos θ_t)`, which it equals only for real η). With it,
    /// `R_p + T_p = 1` for every passive medium, and `T_p = 0` under total internal reflection.
    ///
    /// # Examples
    /// ```
    /// use gmueller::fresnel::coefficients;
    /// use num_complex::Complex;
    /// let f = coefficients(0.6_f64, Complex::new(0.2, 3.0));
    /// assert!((f.reflectance_p() + f.transmittance_p() - 1.0).abs() < 1e-14);
    /// ```
    #[must_use]
    pub fn transmittance_p(&self) -> T {
        let c = self.cos_theta_i;
        let eta2 = self.eta * self.eta;
        let q = self.eta * self.cos_theta_t;
        let den = (eta2 * c + q).norm_sqr();
        if den > T::zero() {
            T::lit(4.0) * c * (eta2.conj() * q).re.max(T::zero()) / den
        } else {
            T::one()
        }
    }

    /// The reflection Jones matrix `diag(r_s, r_p)` in the s/p bases (x̂ = ŝ, ŷ = p̂).
    ///
    /// # Examples
    /// ```
    /// use gmueller::fresnel::coefficients;
    /// use num_complex::Complex;
    /// let f = coefficients(1.0_f64, Complex::new(1.5, 0.0));
    /// let j = f.reflection_jones().matrix();
    /// assert!((j[(0, 0)].re + 0.2).abs() < 1e-15 && (j[(1, 1)].re - 0.2).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn reflection_jones(&self) -> JonesMatrix<T> {
        let z = Complex::new(T::zero(), T::zero());
        JonesMatrix(Matrix2::new(self.rs, z, z, self.rp))
    }

    /// The power-normalised transmission Jones matrix (see [`transmission`]).
    ///
    /// # Formula
    /// ```text
    /// diag( t_s √(Re(η cos θ_t)/cos θ_i),  t_p √(Re(η* cos θ_t)/cos θ_i) )
    ///    = diag( 2√(c Re q)/(c + q),  2 (η/|η|) √(c Re(η*² q))/(η² c + q) )
    /// ```
    ///
    /// # Examples
    /// ```
    /// use gmueller::fresnel::coefficients;
    /// use num_complex::Complex;
    /// let f = coefficients(0.7_f64, Complex::new(1.5, 0.0));
    /// let j = f.transmission_jones().matrix();
    /// assert!((j[(0, 0)].norm_sqr() - f.transmittance_s()).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn transmission_jones(&self) -> JonesMatrix<T> {
        let z = Complex::new(T::zero(), T::zero());
        // The power factors are applied to the phases of t_s, t_p: |entry|² = T_s, T_p.
        let phase = |t: Complex<T>| {
            let n = t.norm_sqr().sqrt();
            if n > T::zero() {
                t / n
            } else {
                Complex::new(T::one(), T::zero())
            }
        };
        let s = phase(self.ts) * self.transmittance_s().sqrt();
        let p = phase(self.tp) * self.transmittance_p().sqrt();
        JonesMatrix(Matrix2::new(s, z, z, p))
    }
}

/// The Fresnel coefficients for incidence with `cos θ_i = cos_theta_i` on an interface of relative
/// index `eta` (`η = n₂/n₁`).
///
/// # Formula
/// See [`FresnelCoefficients`]; `cos θ_t` on the branch of the [module docs](self).
///
/// # Domain
/// `cos_theta_i` is clamped into `[0, 1]` (light arriving from the front side; values just outside
/// from rounding are harmless). `eta` must satisfy `Re η > 0`, `Im η ≥ 0`; this hot-path function
/// does not check it (use [`try_coefficients`] to validate). NaN inputs give NaN outputs; it never
/// panics. At grazing incidence with `η = 1` (no interface, `0/0`) it returns `r = 0`, `t = 1`.
///
/// # Examples
/// ```
/// use gmueller::fresnel::coefficients;
/// use num_complex::Complex;
/// // Normal incidence on glass: r_s = (1 − η)/(1 + η) = −0.2, r_p = −r_s.
/// let f = coefficients(1.0_f64, Complex::new(1.5, 0.0));
/// assert!((f.rs.re + 0.2).abs() < 1e-15 && (f.rp.re - 0.2).abs() < 1e-15);
/// ```
// Inlined so that callers needing only r_s, r_p (e.g. `reflection`) drop the transmission
// divisions.
#[inline]
#[must_use]
pub fn coefficients<T: Real>(cos_theta_i: T, eta: Complex<T>) -> FresnelCoefficients<T> {
    // Clamp into [0, 1]; NaN falls through both comparisons and propagates.
    let c = if cos_theta_i > T::one() {
        T::one()
    } else if cos_theta_i < T::zero() {
        T::zero()
    } else {
        cos_theta_i
    };
    let eta2 = eta * eta;
    // q = η cos θ_t = √(η² − sin²θ_i), principal branch: Re q ≥ 0, Im q ≥ 0, formed as
    // (η² − 1) + cos²θ_i: at η = 1 that is cos²θ_i exactly and √(cos²θ_i) = cos θ_i, so r = 0
    // exactly (no interface); η² − (1 − cos²θ_i) rounded 1 − cos²θ_i first and left
    // r_s ≈ 8e-30 (f64), 2e-12 (f32). The form of Walter et al. 2007 (eq. 22) and of Cycles.
    let q = principal_sqrt(Complex::new((eta2.re - T::one()) + c * c, eta2.im));
    let cc = Complex::new(c, T::zero());
    let zero = Complex::new(T::zero(), T::zero());
    let one = Complex::new(T::one(), T::zero());
    let ds = cc + q;
    let dp = eta2 * c + q;
    if ds == zero || dp == zero {
        // Only c = 0 with η² = 1: no interface (the limit η → 1 at fixed angle).
        return FresnelCoefficients {
            rs: zero,
            rp: zero,
            ts: one,
            tp: one,
            cos_theta_t: zero,
            cos_theta_i: c,
            eta,
        };
    }
    let two_c = c + c;
    FresnelCoefficients {
        rs: (cc - q) / ds,
        rp: (eta2 * c - q) / dp,
        ts: Complex::new(two_c, T::zero()) / ds,
        tp: eta * two_c / dp,
        cos_theta_t: q / eta,
        cos_theta_i: c,
        eta,
    }
}

/// [`coefficients`] with its inputs validated.
///
/// # Errors
/// - [`Error::NonFinite`] if `cos_theta_i` or a part of `eta` is NaN or infinite;
/// - [`Error::OutOfRange`] if `cos_theta_i ∉ [0, 1]`, `Re η ≤ 0` or `Im η < 0` (gain, or the
///   `n − iκ` convention of `e^{+iωt}` libraries: conjugate such an η first).
///
/// # Examples
/// ```
/// use gmueller::fresnel::try_coefficients;
/// use num_complex::Complex;
/// assert!(try_coefficients(0.5_f64, Complex::new(0.2, 3.0)).is_ok());
/// assert!(try_coefficients(0.5_f64, Complex::new(0.2, -3.0)).is_err());
/// assert!(try_coefficients(1.5_f64, Complex::new(1.5, 0.0)).is_err());
/// ```
pub fn try_coefficients<T: Real>(
    cos_theta_i: T,
    eta: Complex<T>,
) -> Result<FresnelCoefficients<T>, Error> {
    if !cos_theta_i.is_finite() {
        return Err(Error::NonFinite { what: "cos θ_i" });
    }
    if !complex_is_finite(eta) {
        return Err(Error::NonFinite {
            what: "relative index η",
        });
    }
    if cos_theta_i < T::zero() || cos_theta_i > T::one() {
        return Err(Error::OutOfRange {
            what: "cos θ_i",
            value: cos_theta_i.to_f64(),
            expected: "[0, 1]",
        });
    }
    if eta.re <= T::zero() {
        return Err(Error::OutOfRange {
            what: "Re η",
            value: eta.re.to_f64(),
            expected: "> 0",
        });
    }
    if eta.im < T::zero() {
        return Err(Error::OutOfRange {
            what: "Im η (κ)",
            value: eta.im.to_f64(),
            expected: "≥ 0 (absorbing, e^{−iωt})",
        });
    }
    Ok(coefficients(cos_theta_i, eta))
}

/// The reflection Jones matrix `diag(r_s, r_p)` of an interface, with x̂ = ŝ and ŷ = p̂.
///
/// # Formula
/// ```text
/// J_r = ⎡ r_s   0  ⎤,   r_s = (cos θ_i − η cos θ_t)/(cos θ_i + η cos θ_t)
///       ⎣  0   r_p ⎦    r_p = (η cos θ_i − cos θ_t)/(η cos θ_i + cos θ_t)
/// ```
/// Bases, the sign of `r_p` (a mirror at normal incidence: `r_p = −r_s`) and the branch of
/// `cos θ_t` are in the [module docs](self). Under total internal reflection `|r_s| = |r_p| = 1`
/// with `arg r_s = −2 atan(√(sin²θ_i − η²)/cos θ_i)` and
/// `arg r_p = −2 atan(√(sin²θ_i − η²)/(η² cos θ_i))` (negative phases: `e^{−iωt}`).
/// Domain and NaN behaviour as [`coefficients`]; infallible and allocation-free.
///
/// # Examples
/// ```
/// use gmueller::{fresnel::reflection, mueller::Mueller};
/// use num_complex::Complex;
/// // Gold at 633 nm, 45°: metallic, |r| ≤ 1, s reflects more than p.
/// let m = Mueller::from_jones(&reflection(0.5_f64.sqrt(), Complex::new(0.18, 3.0))).matrix();
/// assert!(m[(0, 0)] > 0.9 && m[(0, 0)] <= 1.0 && m[(0, 1)] > 0.0);
/// ```
#[must_use]
pub fn reflection<T: Real>(cos_theta_i: T, eta: Complex<T>) -> JonesMatrix<T> {
    coefficients(cos_theta_i, eta).reflection_jones()
}

/// The power-normalised transmission Jones matrix of an interface, with x̂ = ŝ and ŷ = p̂ (the
/// transmitted beam's own basis, `p̂ = k̂_t × ŝ`).
///
/// # Formula
/// ```text
/// J_t = ⎡ t_s √(Re(η cos θ_t)/cos θ_i)                0               ⎤
///       ⎣             0                 t_p √(Re(η* cos θ_t)/cos θ_i) ⎦
/// ```
/// The factors turn field amplitudes into power-flux amplitudes, so `|J_t,ss|² = T_s`,
/// `|J_t,pp|² = T_p` and the Mueller matrix of `J_t` has `M₀₀ = (T_s + T_p)/2`, the transmitted
/// power fraction of unpolarized light: `reflection` and `transmission` together conserve energy
/// for lossless media. The phases are those of `t_s`, `t_p`. (For a real index the factors are
/// `√(η cos θ_t / cos θ_i)`, the usual beam-area and impedance correction.) Under total internal
/// reflection the matrix is zero. Domain and NaN behaviour as [`coefficients`].
///
/// # Examples
/// ```
/// use gmueller::{fresnel::{reflection, transmission}, mueller::Mueller};
/// use num_complex::Complex;
/// let (c, eta) = (0.4_f64, Complex::new(1.5, 0.0));
/// let r = Mueller::from_jones(&reflection(c, eta)).matrix()[(0, 0)];
/// let t = Mueller::from_jones(&transmission(c, eta)).matrix()[(0, 0)];
/// assert!((r + t - 1.0).abs() < 1e-15);
/// ```
#[must_use]
pub fn transmission<T: Real>(cos_theta_i: T, eta: Complex<T>) -> JonesMatrix<T> {
    coefficients(cos_theta_i, eta).transmission_jones()
}
