//! Mean Mueller fields with closed-form angular spectra (S2.14): a Gaussian window and a box.

use nalgebra::{Matrix4, SMatrix, SVector};
use num_complex::Complex;

use super::MeanField;
use crate::error::{Error, ensure_finite};
use crate::gaussian::Gaussian;
use crate::mueller::Mueller;
use crate::real::Real;

/// `e^{−i q·c}`.
fn shift_phase<T: Real, const N: usize>(q: &SVector<T, N>, center: &SVector<T, N>) -> Complex<T> {
    let (s, c) = q.dot(center).sin_cos();
    Complex::new(c, -s)
}

/// A Gaussian window of matter: `m̄(ζ) = g^W(ζ − c) M₀`, peak `M₀` at the centre `c`, covariance
/// `W` (its square root is the region's extent).
///
/// # Formula
/// ```text
/// m̄(ζ) = exp(−½ (ζ − c)ᵀ W⁻¹ (ζ − c)) M₀
/// S2.14:  M̃(q) = (2π)^{N/2} |W|^{1/2} e^{−½ qᵀWq} e^{−iq·c} M₀
/// |P| = ∫ g^W = (2π)^{N/2} |W|^{1/2},     S2.19:  M = M̃(0)/|P| = M₀
/// ```
/// `M̃(q) ≈ M̃(0)` (S2.14's approximation) costs the factor `e^{−½ qᵀWq}`: for
/// `q = k(r̂₁ − r̂₂)` with the directions `δ` apart and a window of width `s`, about
/// `½ (k δ s)²` — the approximation holds for directions closer than the region's diffraction
/// angle `1/(k s)`.
///
/// # Examples
/// ```
/// use gmueller::matter::{GaussianWindow, MeanField};
/// use gmueller::mueller::Mueller;
/// use nalgebra::{Matrix3, Vector3};
/// let w = GaussianWindow::new(Vector3::zeros(), Matrix3::identity() * 0.25, Mueller::<f64>::identity())?;
/// // |P| = (2π)^{3/2} · 0.5³
/// assert!((w.measure() - core::f64::consts::TAU.powf(1.5) * 0.125).abs() < 1e-14);
/// let q = Vector3::new(2.0, 0.0, 0.0);
/// let m = w.angular_spectrum(&q);
/// assert!((m[(0, 0)].re - w.measure() * (-0.5f64 * 4.0 * 0.25).exp()).abs() < 1e-14);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussianWindow<T: Real, const N: usize> {
    center: SVector<T, N>,
    window: Gaussian<T, N>,
    mueller: Mueller<T>,
}

impl<T: Real, const N: usize> GaussianWindow<T, N> {
    /// A Gaussian window at `center` with covariance `W` and peak Mueller matrix `M₀`.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite centre; as [`Gaussian::new`] for `W` (finite,
    /// symmetric, positive definite).
    pub fn new(
        center: SVector<T, N>,
        covariance: SMatrix<T, N, N>,
        mueller: Mueller<T>,
    ) -> Result<Self, Error> {
        ensure_finite("window centre", center.iter().copied())?;
        Ok(Self {
            center,
            window: Gaussian::new(covariance)?,
            mueller,
        })
    }

    /// The centre `c`.
    #[must_use]
    pub fn center(&self) -> &SVector<T, N> {
        &self.center
    }

    /// The window `g^W`.
    #[must_use]
    pub fn window(&self) -> &Gaussian<T, N> {
        &self.window
    }

    /// The peak Mueller matrix `M₀`.
    #[must_use]
    pub fn peak_mueller(&self) -> &Mueller<T> {
        &self.mueller
    }
}

impl<T: Real, const N: usize> MeanField<T, N> for GaussianWindow<T, N> {
    fn mueller(&self, zeta: &SVector<T, N>) -> Mueller<T> {
        Mueller(self.mueller.0 * self.window.value(&(zeta - self.center)))
    }

    fn angular_spectrum(&self, q: &SVector<T, N>) -> Matrix4<Complex<T>> {
        // S2.14 for g^W: ∫ e^{−iq·ζ} g^W(ζ − c) dζ = e^{−iq·c} (2π)^{N/2}|W|^{1/2} g^{W⁻¹}(q),
        // in log form (|W|^{1/2} of a large region can exceed the range of f32).
        let scale = (self.window.log_integral() + self.window.log_value_of_inverse(q)).exp();
        let phase = shift_phase(q, &self.center) * scale;
        self.mueller.0.map(|m| phase * m)
    }

    fn measure(&self) -> T {
        self.window.log_integral().exp()
    }

    /// `M₀` exactly.
    fn pbsdf(&self) -> Mueller<T> {
        self.mueller
    }
}

/// A box of uniform matter: `m̄(ζ) = M₀` where `|ζₐ − cₐ| ≤ hₐ` on every axis, 0 outside.
///
/// # Formula
/// ```text
/// S2.14:  M̃(q) = e^{−iq·c} Πₐ 2 sin(qₐhₐ)/qₐ · M₀        (2hₐ where qₐ = 0)
/// |P| = Πₐ 2hₐ,     S2.19:  M = M₀
/// ```
/// `M̃(q) ≈ M̃(0)` costs `1 − Πₐ sinc(qₐhₐ) ≈ Σₐ (qₐhₐ)²/6`.
///
/// # Examples
/// ```
/// use gmueller::matter::{BoxRegion, MeanField};
/// use gmueller::mueller::Mueller;
/// use nalgebra::Vector2;
/// let b = BoxRegion::new(Vector2::zeros(), Vector2::new(1.0, 2.0), Mueller::<f64>::identity())?;
/// assert_eq!(b.measure(), 8.0);
/// // The first zero of the transform along x: q₁h₁ = π.
/// let m = b.angular_spectrum(&Vector2::new(core::f64::consts::PI, 0.0));
/// assert!(m[(0, 0)].norm() < 1e-14);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxRegion<T: Real, const N: usize> {
    center: SVector<T, N>,
    half_widths: SVector<T, N>,
    mueller: Mueller<T>,
}

impl<T: Real, const N: usize> BoxRegion<T, N> {
    /// A box at `center` with half-widths `hₐ > 0` and Mueller matrix `M₀` inside.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite centre or half-width; [`Error::OutOfRange`] for a
    /// half-width that is not positive.
    pub fn new(
        center: SVector<T, N>,
        half_widths: SVector<T, N>,
        mueller: Mueller<T>,
    ) -> Result<Self, Error> {
        ensure_finite("box centre", center.iter().copied())?;
        ensure_finite("box half-width", half_widths.iter().copied())?;
        if let Some(h) = half_widths.iter().find(|h| **h <= T::zero()) {
            return Err(Error::OutOfRange {
                what: "box half-width",
                value: h.to_f64(),
                expected: "(0, ∞)",
            });
        }
        Ok(Self {
            center,
            half_widths,
            mueller,
        })
    }
}

impl<T: Real, const N: usize> MeanField<T, N> for BoxRegion<T, N> {
    fn mueller(&self, zeta: &SVector<T, N>) -> Mueller<T> {
        let inside = (zeta - self.center)
            .iter()
            .zip(self.half_widths.iter())
            .all(|(d, h)| d.abs() <= *h);
        if inside {
            self.mueller
        } else {
            Mueller(Matrix4::zeros())
        }
    }

    fn angular_spectrum(&self, q: &SVector<T, N>) -> Matrix4<Complex<T>> {
        let two = T::lit(2.0);
        let mut scale = T::one();
        for (qa, h) in q.iter().zip(self.half_widths.iter()) {
            let x = *qa * *h;
            // ∫_{−h}^{h} e^{−iqx} dx = 2 sin(qh)/q = 2h sinc(qh); sin(x)/x loses no digits.
            scale *= if x == T::zero() {
                two * *h
            } else {
                two * *h * x.sin() / x
            };
        }
        let phase = shift_phase(q, &self.center) * scale;
        self.mueller.0.map(|m| phase * m)
    }

    fn measure(&self) -> T {
        self.half_widths
            .iter()
            .fold(T::one(), |acc, h| acc * T::lit(2.0) * *h)
    }

    fn pbsdf(&self) -> Mueller<T> {
        self.mueller
    }
}
