//! Locally-stationary matter (S2.7–S2.9), its angular spectrum (S2.14) and its pBSDF as the
//! region average of the mean Mueller field (S2.19); and a generator of its random realizations.
//!
//! # The model
//! ```text
//! S2.7:  ρ_JJ(p₁, p₂) = ⟨𝓜(p₁, p₂)⟩,   𝓜(p₁, p₂) = A_mül [J(p₂)* ⊗ J(p₁)] A_mül⁻¹   (S1.7)
//! S2.8:  ρ_JJ(p₁, p₂) = m̄((p₁ + p₂)/2) R_JJ(p₁ − p₂)                     locally stationary
//! S2.9:  S_P(p₁ − p₂) = ρ_JJ(p₁, p₂) S_i(p₁ − p₂)                         the interaction
//! S2.14: M̃(q) = ∫ e^{−iq·ζ} m̄(ζ) dᴺζ = (2π)^{N/2} F{m̄}(q)                  angular spectrum
//! S2.19: M = (1/|P|) ∫_P m̄ = M̃(0)/|P|                                      the pBSDF
//! ```
//! `J(p)` is the random Jones matrix of the matter at `p` (its scattering potential), `⟨·⟩` the
//! average over realizations of the matter. A [`LocallyStationary`] holds the two factors of
//! S2.8: the **mean Mueller field** `m̄` (a [`MeanField`]: where the matter is and what it does
//! to polarization) and the **stationary autocorrelation** (a [`StationaryCorrelation`]: how the
//! perturbations correlate over a separation ξ). The crate takes `R_JJ(ξ) = R(ξ) I` — a scalar
//! correlation, the form whose Fourier transform is the scalar PSD `p` of S2.20. (S2.7 defines
//! `m̄(ζ) = ⟨𝓜(ζ, ζ)⟩`, which makes `R(0) = 1`; like the crate's surface materials, which put
//! the variance σ² into `p`, the two factors may share the strength in any proportion: only
//! the product `ρ_JJ = m̄ R` is physical.)
//!
//! # Exact realizations
//! [`StationaryField`] draws Gaussian random fields on a periodic grid whose covariance is a
//! given autocorrelation exactly (circulant embedding), and [`JonesFieldGenerator`] multiplies
//! them by slowly varying mean Jones fields, `J(p) = Σ_t J̄_t(p) u_t(p)`. Then
//! `⟨𝓜(p₁, p₂)⟩ = c(p₁ − p₂) Σ_t 𝓜[J̄_t(p₁), J̄_t(p₂)]`, and S2.8 holds *exactly* for
//! Gaussian windows `J̄_t(p) = e^{−¼(p−c_t)ᵀW⁻¹(p−c_t)} J_t` of one shape W (Silverman's
//! construction, [`JonesFieldGenerator`]): `m̄(ζ) = Σ_t g^W(ζ − c_t) Mueller(J_t)` and
//! `R(ξ) = c(ξ) e^{−⅛ ξᵀW⁻¹ξ}`. `tests/matter/locally_stationary.rs` estimates `⟨𝓜⟩` from such
//! realizations by Monte Carlo and compares it with S2.8 within standard errors.

mod field;
mod window;

pub use field::{Fluctuation, JonesFieldGenerator, StationaryField};
pub use window::{BoxRegion, GaussianWindow};

use nalgebra::{Matrix4, SVector};
use num_complex::Complex;

use crate::mueller::{GeneralizedMueller, Mueller};
use crate::psd::{GaussianPsd, Psd};
use crate::real::Real;
use crate::stokes::GeneralizedStokes;

/// The mean Mueller field `m̄(ζ)` of locally-stationary matter (S2.8), with its angular
/// spectrum (S2.14) and its region average (S2.19).
///
/// `m̄` vanishes outside the scattering region P (the seed's convention after S2.10: the
/// restriction to the region is carried by `m̄`). It is a *window* `w(ζ) ≥ 0` times a local
/// Mueller matrix, and [`MeanField::measure`] is `|P| = ∫ w dᴺζ`, the region's volume (area for
/// `N = 2`), or the effective volume of a soft window.
///
/// Implemented by [`GaussianWindow`], [`BoxRegion`], and by `Vec` of any mean field (their sum,
/// e.g. several kinds of particles in overlapping regions).
pub trait MeanField<T: Real, const N: usize> {
    /// `m̄(ζ)`, the ensemble-averaged local Mueller matrix at `ζ`.
    #[must_use]
    fn mueller(&self, zeta: &SVector<T, N>) -> Mueller<T>;

    /// The angular spectrum of S2.14, `M̃(q) = ∫ e^{−iq·ζ} m̄(ζ) dᴺζ = (2π)^{N/2} F{m̄}(q)`, a
    /// complex 4×4 matrix (real for a window symmetric about the origin).
    #[must_use]
    fn angular_spectrum(&self, q: &SVector<T, N>) -> Matrix4<Complex<T>>;

    /// `|P| = ∫ w dᴺζ`, the window's weight (volume for `N = 3`, area for `N = 2`).
    #[must_use]
    fn measure(&self) -> T;

    /// The classical pBSDF of S2.19, the region average of `m̄`.
    ///
    /// # Formula
    /// ```text
    /// S2.19:  M = (1/|P|) ∫_P m̄(ζ) dᴺζ = M̃(0)/|P|
    /// ```
    /// The default is `Re M̃(0) / |P|` (`M̃(0)` is real: it integrates a real field).
    #[must_use]
    fn pbsdf(&self) -> Mueller<T> {
        let m0 = self.angular_spectrum(&SVector::zeros());
        Mueller(m0.map(|z| z.re) / self.measure())
    }
}

impl<T: Real, const N: usize, W: MeanField<T, N>> MeanField<T, N> for Vec<W> {
    /// `Σ m̄ₖ(ζ)`.
    fn mueller(&self, zeta: &SVector<T, N>) -> Mueller<T> {
        Mueller(self.iter().map(|w| w.mueller(zeta).0).sum())
    }
    /// `Σ M̃ₖ(q)`.
    fn angular_spectrum(&self, q: &SVector<T, N>) -> Matrix4<Complex<T>> {
        self.iter().map(|w| w.angular_spectrum(q)).sum()
    }
    /// `Σ |Pₖ|`: the weights add where windows overlap, as the fields do.
    fn measure(&self) -> T {
        self.iter().fold(T::zero(), |acc, w| acc + w.measure())
    }
}

/// The stationary autocorrelation `R(ξ)` of S2.8 (`R_JJ = R I`), a real even function of the
/// separation `ξ = p₁ − p₂` whose Fourier transform `p = F{R}` is the matter's PSD.
///
/// Implemented for [`GaussianPsd`] (`R(ξ) = σ² g^Λ(ξ)`, the transform back from its PSD) and for
/// every closure `Fn(&SVector<T, N>) -> T`.
pub trait StationaryCorrelation<T: Real, const N: usize> {
    /// `R(ξ)`.
    #[must_use]
    fn correlation(&self, xi: &SVector<T, N>) -> T;
}

impl<T: Real, const N: usize> StationaryCorrelation<T, N> for GaussianPsd<T, N> {
    /// `R(ξ) = σ² exp(−½ ξᵀΛ⁻¹ξ)`, `Λ⁻¹` the PSD's spectral covariance.
    fn correlation(&self, xi: &SVector<T, N>) -> T {
        self.variance() * self.spectral_shape().log_value_of_inverse(xi).exp()
    }
}

impl<T: Real, const N: usize, F: Fn(&SVector<T, N>) -> T> StationaryCorrelation<T, N> for F {
    fn correlation(&self, xi: &SVector<T, N>) -> T {
        self(xi)
    }
}

/// Locally-stationary matter (S2.7–S2.8): a mean Mueller field `m̄` and a stationary
/// autocorrelation `R`, with the interaction formula S2.9, the angular spectrum S2.14 and the
/// pBSDF S2.19.
///
/// # Formula
/// ```text
/// S2.8:  ρ_JJ(p₁, p₂) = m̄((p₁ + p₂)/2) R(p₁ − p₂)
/// S2.9:  S_P = ρ_JJ(p₁, p₂) S_i(p₁ − p₂)
/// ```
/// `N = 3` for a volume, `N = 2` for a surface (coordinates in its tangent plane). Lengths in
/// any consistent unit (µm in the docs).
///
/// # Examples
/// A Gaussian region of half-wave plates with Gaussian-correlated perturbations:
/// ```
/// use gmueller::jones::JonesMatrix;
/// use gmueller::matter::{GaussianWindow, LocallyStationary, MeanField};
/// use gmueller::mueller::Mueller;
/// use gmueller::psd::GaussianPsd;
/// use gmueller::stokes::Stokes;
/// use nalgebra::{Matrix3, Vector3};
///
/// let plate = Mueller::from_jones(&JonesMatrix::linear_retarder(0.0, core::f64::consts::PI));
/// let window = GaussianWindow::new(Vector3::zeros(), Matrix3::identity() * 4.0, plate)?;
/// let matter = LocallyStationary::new(window, GaussianPsd::<f64, 3>::isotropic(1.0, 0.2)?);
/// // S2.8 at the centre, zero separation: m̄(0) R(0) = M₀ · 1.
/// let rho = matter.autocorrelation(&Vector3::zeros(), &Vector3::zeros());
/// assert!((rho.matrix() - plate.matrix()).norm() < 1e-15);
/// // Separated by one correlation length: R = e^{−1/2}.
/// let rho = matter.autocorrelation(&Vector3::new(0.1, 0.0, 0.0), &Vector3::new(-0.1, 0.0, 0.0));
/// assert!((rho.matrix() - plate.matrix() * (-0.5f64).exp()).norm() < 1e-15);
/// // S2.9: circular light comes out with the other handedness (S3 → −S3) where ρ = M₀.
/// let s = Stokes::new(1.0, 0.0, 0.0, 1.0)?.to_generalized();
/// let out = matter.interact(&Vector3::zeros(), &Vector3::zeros(), &s);
/// assert!((out.vector()[3].re + 1.0).abs() < 1e-15);
/// // S2.19: the pBSDF is the region average of m̄, here M₀.
/// assert!((matter.mean().pbsdf().matrix() - plate.matrix()).norm() < 1e-14);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocallyStationary<M, R> {
    mean: M,
    correlation: R,
}

impl<M, R> LocallyStationary<M, R> {
    /// Matter from its mean Mueller field and its stationary autocorrelation (each validated by
    /// its own constructor).
    pub fn new(mean: M, correlation: R) -> Self {
        Self { mean, correlation }
    }

    /// The mean Mueller field `m̄`.
    #[must_use]
    pub fn mean(&self) -> &M {
        &self.mean
    }

    /// The stationary autocorrelation `R`.
    #[must_use]
    pub fn correlation(&self) -> &R {
        &self.correlation
    }

    /// The autocorrelation of the Jones field, S2.8: `ρ_JJ(p₁, p₂) = m̄((p₁ + p₂)/2) R(p₁ − p₂)`,
    /// a real (classical) Mueller matrix.
    ///
    /// # Formula
    /// ```text
    /// S2.7–S2.8:  ⟨𝓜(p₁, p₂)⟩ = ρ_JJ(p₁, p₂) = m̄(ζ) R(ξ),   ζ = (p₁ + p₂)/2,  ξ = p₁ − p₂
    /// ```
    /// NaN inputs give NaN entries.
    #[must_use]
    pub fn autocorrelation<T: Real, const N: usize>(
        &self,
        p1: &SVector<T, N>,
        p2: &SVector<T, N>,
    ) -> Mueller<T>
    where
        M: MeanField<T, N>,
        R: StationaryCorrelation<T, N>,
    {
        let zeta = (p1 + p2) * T::lit(0.5);
        Mueller(self.mean.mueller(&zeta).0 * self.correlation.correlation(&(p1 - p2)))
    }

    /// The interaction formula S2.9: the generalized Stokes parameters of the light at the
    /// matter after interaction, before propagation, from those of the incident light at the
    /// same separation.
    ///
    /// # Formula
    /// ```text
    /// S2.9:  S_P(p₁ − p₂) = ρ_JJ(p₁, p₂) S_i(p₁ − p₂)
    /// ```
    /// `incident` is `S_i` at the separation `p₁ − p₂` (a two-point quantity: it is complex
    /// away from `ξ = 0`). This is the ensemble average over the matter of S1.6,
    /// `𝓜(p₁, p₂) S_i`, i.e. of `J(p₁) C_i J(p₂)†` (S1.4).
    #[must_use]
    pub fn interact<T: Real, const N: usize>(
        &self,
        p1: &SVector<T, N>,
        p2: &SVector<T, N>,
        incident: &GeneralizedStokes<T>,
    ) -> GeneralizedStokes<T>
    where
        M: MeanField<T, N>,
        R: StationaryCorrelation<T, N>,
    {
        GeneralizedMueller::from_mueller(&self.autocorrelation(p1, p2)) * *incident
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    #[test]
    fn vec_of_windows_sums_fields_spectra_and_weights() {
        let a = GaussianWindow::<f64, 2>::new(
            Vector2::new(1.0, 0.0),
            Matrix2::identity(),
            Mueller::identity(),
        )
        .unwrap();
        let half = Mueller(Matrix4::identity() * 0.5);
        let b =
            GaussianWindow::new(Vector2::new(-1.0, 0.5), Matrix2::identity() * 2.0, half).unwrap();
        let both = vec![a, b];
        let z = Vector2::new(0.3, -0.2);
        let sum = a.mueller(&z).0 + b.mueller(&z).0;
        assert!((both.mueller(&z).0 - sum).norm() < 1e-15);
        assert!((both.measure() - a.measure() - b.measure()).abs() < 1e-14);
        // S2.19 of the sum: the weight-averaged Mueller matrix.
        let avg = (Matrix4::identity() * a.measure() + half.0 * b.measure()) / both.measure();
        assert!((both.pbsdf().0 - avg).norm() < 1e-14);
    }
}
