//! Random media: a region of locally-stationary matter whose single-scattering kernel is S2.20
//! with n = 3, in first-Born form with its absolute constant, as a volume path tracer needs it —
//! a scattering coefficient and a Mueller phase matrix for the incident packet's coherence,
//! with sampling and its exact pdf.
//!
//! # Formula
//! ```text
//! dI/dV(r̂) = (k⁴/16π²) · m̄(cos Θ) · T · Σ_α K³_α(h) S_α                (Stokes radiant intensity per unit volume)
//! K³_α     = |Θ_α|^{1/2} ∫ p(q) g^{Ξ_α}(h − q) d³q = (2π)^{3/2} ∫ p(q) 𝒩_{Ξ_α}(h − q) d³q   (S2.17, n = 3)
//! Ξ_α      = Q Θ_α⁻¹ Qᵀ,  Θ_α = blockdiag(Θ⊥_α, σ_zz²)                       (S2.18, 3-D)
//! h        = k(r̂ + ŝ) = k(r̂ − d̂),   cos Θ = r̂·d̂
//! σ_s      = (1/S0) ∫ [dI/dV]₀ dΩ,     F = (dI/dV)/(σ_s S0) as a Mueller matrix,  ∫ [F S]₀ dΩ = S0
//! ```
//! `p` is the 3-D PSD of the relative permittivity fluctuation `δε` (unitary transform,
//! `∫ p = (2π)^{3/2} ⟨δε²⟩`, [`crate::psd`]; see *Conventions* below), `m̄` the mean scattering matrix ([`Scatterer`]:
//! [`Dipole`] for the Born medium), `T` the rotation (S2.4) from the packet frame to the incident
//! scattering-plane frame, `S_α` the packet's channels (S2.16) and `Θ_α` its 3-D shapes
//! ([`WavePacket::with_longitudinal_coherence`] sets `σ_zz`). The coherence levels give `K³`
//! as in [`VolumeCoherence`]; the polarization levels keep `m̄₀₀ K³_½ S0` (`Intensity`),
//! `m̄ T K³_½ S` (`OneShape`) or the sum above (`Full`).
//!
//! # Derivation (first Born, SI, non-magnetic, background index 1)
//! With `ε(r) = 1 + δε(r)`, `⟨δε⟩ = 0`, the field obeys `∇×∇×E − k²E = k² δε E`; to first order
//! the far field is
//! ```text
//! E_s(r r̂) = (k²/4π) (e^{ikr}/r) (I − r̂r̂ᵀ) ∫ δε(p) E(p) e^{−ik r̂·p} d³p
//! r² ⟨E_s E_s†⟩ = (k⁴/16π²) ∫∫ R(p₁ − p₂) (I − r̂r̂ᵀ) ⟨E(p₁) E(p₂)†⟩ (I − r̂r̂ᵀ) e^{−ik r̂·(p₁−p₂)} d³p₁ d³p₂
//! ```
//! the double integral of S2.10 with the locally-stationary `⟨δε(p₁)δε(p₂)⟩ = m̄ R(p₁ − p₂)`
//! (S2.8, `m̄` the region's indicator times the dipole projection). For the packet
//! `⟨E(p₁)E(p₂)†⟩ = e^{ik d̂·ξ} Σ_α g^{Θ_α}(Qᵀξ) C_α` (ξ = p₁ − p₂) the ζ = (p₁ + p₂)/2 integral
//! gives the volume `V` (S2.14, `M̃(0)`), and the ξ integral is `∫ R(ξ) g^{Θ_α}(Qᵀξ) e^{−ih·ξ} d³ξ
//! = (2π)^{3/2} F{R g}(h) = K³_α` (convolution theorem, Lemma S2.1 with `B = Qᵀ`). Per unit
//! volume: `dI/dV = (k⁴/16π²) Σ_α K³_α · (I − r̂r̂ᵀ) C_α (I − r̂r̂ᵀ)`, which in Stokes form is the
//! formula above with `m̄ = ` [`Dipole`]. For a plane wave `K³ → (2π)^{3/2} p(h)` and the
//! differential scattering cross-section per unit volume is `(k⁴/16π²)(2π)^{3/2} p(h) |ê_o·ê_i|²`.
//! The seed's S2.20 prefactor `cos θ_o/(λ²(2π)^{3/2})` is the surface (aperture) one; the
//! volume's is `k⁴/16π² = π²/λ⁴` per unit volume, with `K³` carrying the corrected `(2π)^{3/2}`
//! of S2.17 (errata).
//!
//! **Rayleigh limit.** For correlation lengths `≪ λ`, `p(h) ≈ p(0) = (2π)^{−3/2} ⟨δε²⟩ V_c`
//! (`V_c = ∫R/R(0)` the correlation volume) and
//! `σ_s = (k⁴/16π²) ⟨δε²⟩ V_c ∫ (1 + cos²Θ)/2 dΩ = (k⁴/6π) ⟨δε²⟩ V_c`, with the Rayleigh phase
//! matrix `F = (3/8π) m̄_dipole`; a dilute medium of small spheres (`⟨δε²⟩V_c = N δε² V²`)
//! gives `N` times the textbook Rayleigh cross-section `(8π/3) k⁴ a⁶ (δε/3)²` of one sphere.
//! For a Gaussian `R = σ² exp(−|ξ|²/2ℓ²)`, plane wave, unpolarized, exactly:
//! `σ_s = (k⁴/16π²)(2π)^{3/2} σ² ℓ³ · π ∫₋₁¹ e^{−k²ℓ²(1−μ)} (1 + μ²) dμ`.
//!
//! **Background index.** In a background of index `n` (`ε = n²(1 + δε)`, `δε` the relative
//! fluctuation) the same formulas hold with `k = n k₀` and `λ = λ₀/n`, the wavenumber and
//! wavelength in the medium, which is what the packet must carry; for the PSD of an absolute
//! fluctuation `Δε = n² δε`, divide it by `n⁴`.
//!
//! **Longitudinal coherence.** S2.20 enters `σ_zz` as a blur of the PSD along d̂
//! (`Ξ_zz = 1/σ_zz²`, from the single-frequency propagation of a packet with a longitudinal
//! envelope). Light whose equal-time coherence has that length has a bandwidth `Δk = 1/σ_zz`, and
//! its frequencies scatter independently, each with its own `h = k'(r̂ − d̂)`: no blur forward, a
//! blur of `2/σ_zz` backward. The two differ (`tests/medium/spectrum.rs`,
//! `longitudinal_coherence_against_bandwidth`: forward, the packet gives `(1 + ℓ²/σ_zz²)^{−1/2}`
//! of the plane wave, 0.71 at `ℓ = σ_zz`, bandwidth `E[(k'/k)⁴] ≈ 1`). A spectral renderer, whose
//! packets carry one wavelength each, should leave `σ_zz` unbounded: the `Partial` level takes
//! that as its limit (the `Incoherent` level, which needs every coherence length below the
//! correlation lengths, refuses it).
//!
//! **Validity.** Single scattering in the first Born approximation: `|δε| ≪ 1` and a phase error
//! `k L |δε| ≪ 1` over the scattering region; multiple scattering is the path tracer's job
//! (`σ_s` and `F` per event).
//!
//! # Conventions (read before building a medium)
//! - **The PSD is of the relative permittivity `δε`, not of the index.** For index
//!   fluctuations `δn` in a background of index `n`, `ε = (n + δn)² = n²(1 + δε)` gives
//!   `δε = 2δn/n + (δn/n)²`, so `p_δε ≈ (4/n²) p_δn` — in air or vacuum `δε ≈ 2δn` and
//!   `p_δε = 4 p_δn`: a `δn` spectrum passed in unchanged understates `σ_s` (and `dI/dV`) by a
//!   factor 4 (`tests/medium/conventions.rs`: against the classical `2πk⁴Φ_n sin²χ` of index
//!   fluctuations, to 1e-12). [`RandomMedium::new`] has the formula.
//! - **`GaussianPsd::isotropic(σ, ℓ)` is the correlation `σ² e^{−r²/2ℓ²}`** (its PSD
//!   `σ²ℓ³ e^{−ℓ²|q|²/2}`, the unitary transform, checked by radial quadrature). Much of the
//!   literature (SCATMECH, the surface-scattering texts) writes `σ² e^{−r²/ℓ'²}`: its `ℓ'` is
//!   `√2 ℓ`.
//! - **`h = k(r̂ + ŝ)` with ŝ pointing toward the source** (`ŝ = −d̂`, d̂ the travel direction):
//!   `h = 0` forward, `h = 2kŝ` straight back toward the source
//!   ([`ScatteringGeometry::scattering_vector`]).
//!
//! # The packet is paraxial
//! The packet's coherence `e^{ik d̂·ξ} g^{Θ}(ξ)` puts its plane waves on the plane tangent to the
//! sphere `|K| = k` at `k d̂`; a real beam's lie on the sphere, `κ⊥²/2k` behind the plane. Against
//! an exact sum of plane waves (a Gaussian Schell-model beam in a Gaussian medium, each plane
//! wave scattered by the exact first-Born formula; `tests/medium/paraxial.rs`) the packet is low
//! by `e = I_exact/I_packet − 1 ≈ 2(ℓ/w)²(1 − cos Θ)/2` (`ℓ` this crate's correlation length, `w`
//! the coherence width; exactly `2ℓ²/(w² − ℓ²)` backward for a scalar scatterer), more off axis
//! where `kℓ²/w` is not small, plus `O((ℓ/w)² sin²Θ + 1/(kw)²)` from the dipole factor taken at
//! d̂. Measured: backward 16.5 % at `w = 2 λ`, `kℓ = 3.54` (the `kℓ' = 5` of a correlation
//! `σ²e^{−r²/ℓ'²}`), 1.5e-3 at `w = 20 λ`, 2.4e-4 at `w = 50 λ`; 10° from forward at most
//! 3.3e-3 at `w = 5 λ` and 2.2e-4 at `w = 20 λ` (dipole, `kℓ ≤ 10`). Asserted over
//! `w = 2–50 λ`, `kℓ = 0.5–10` (`ℓ ≤ w/2`), `Θ = 10°–180°`:
//! ```text
//! |e| ≤ 2.02 [a² ((1 − cos Θ)/2 · (1 + (kℓ²/w)² sin²Θ) + D sin²Θ) + D/(kw)²],   a² = ℓ²/(w² − ℓ²)
//! ```
//! (`D` = 1 for [`Dipole`], 0 for [`Scalar`]; measured constant 2.011 and 1.971). A renderer
//! whose coherence widths are a few wavelengths and whose media are correlated over more than
//! a tenth of them should expect percent-level errors away from forward.
//!
//! # When `σ_s` is 0 or not representable
//! - `F`, the pdf and the sample weight are computed from `ln σ_s`
//!   ([`VolumeIncident::ln_scattering_coefficient`]): a `σ_s` that underflows the type
//!   ([`VolumeIncident::scattering_coefficient`] 0) or overflows it (∞) leaves them finite and exact
//!   (`tests/medium/f32.rs`: `σ_s` 5e-49 and 1e40 in `f32`, `F` within 1e-5 of `f64`).
//! - A medium that does not scatter (`δε = 0`, `ln σ_s = −∞`): `σ_s = 0`, `F = 0`, `dI/dV = 0`,
//!   sample weights 0, and the sampler still draws with a finite positive pdf.
//! - `σ_s` that did not resolve the phase function's lobe — a PSD whose form names a lobe
//!   far wider than its PSD's, so that every quadrature node misses it — is refused:
//!   [`PhaseFunction::prepare`] returns [`crate::Error::Unrealizable`] when `F` forward exceeds
//!   `64 c max(k²/2πs², 1/4π)` (`s` the lobe's finest named scale, `c = 2ν` for a power lobe, 1
//!   otherwise), rather than hand out an `F` of ~10⁸⁶ (∞ in `f32`). Every lobe a crate PSD names
//!   peaks forward, where the check looks, so for them `F` and the weights are finite for every
//!   prepared packet.
//! - `σ_s = 0` at the `Partial` level from a PSD of positive variance is refused too
//!   ([`crate::Error::Unrealizable`]): the blurred PSD is positive everywhere, so 0 means that
//!   the blur's quadrature missed it at every node — seen with a band-limited
//!   [`crate::psd::PowerLaw`] far narrower than the blur under Gauss–Hermite
//!   (`tests/medium/f32.rs`, `a_band_the_blur_misses_is_refused`). At the plane-wave level
//!   `σ_s = 0` is exact where the PSD vanishes on the sphere `|q| ≤ 2k` (a band beyond `2k`).
//!
//! # Peers
//! A polarized Rayleigh phase function is still "not implemented" in Mitsuba 3 (its
//! `src/phase/rayleigh.cpp` warns so in polarized variants and falls back to the scalar
//! `(3/16π)(1 + cos²Θ)`, which is this module's `F₀₀` for unpolarized light in the Rayleigh
//! limit), and no renderer or scattering library we know makes a phase function
//! coherence-aware: the coherence levels here have no peer to compare with; they are tested
//! against the Born integral itself (`tests/medium/born.rs`).
//!
//! # Numerics
//! The weights are logarithms combined with `ln S0` and `ln(k⁴/16π²)` before anything is
//! exponentiated (as the surface kernel, [`crate::interaction`]); the Full level caps `K³_½` at
//! the Cauchy–Schwarz bound of the channel weights; outputs are valid Stokes vectors. `σ_s` is a
//! fixed quadrature over the sphere in Lambert coordinates adapted to the lobe
//! ([`PhaseFunction::prepare`], cost in `benches/medium.rs`).
//!
//! **Each channel in its own axes.** `Ξ_α`'s variances span `(w/σ_zz)²` — 10⁸ for a 2.7·10³ λ
//! width beside a 0.27 λ `σ_zz` — and a 3-D matrix in world axes cannot hold more than `1/ε` of
//! span in `T`: rounded to `f32`, its transverse block was noise, the `σ_s` quadrature missed the
//! lobe and `σ_s` came out 0 (issue 36; `tests/medium/f32.rs`). `Ξ_α` is diagonal in the basis
//! of the channel's transverse eigenvectors and d̂, formed in `f64`; there the `Incoherent`
//! weight, and the `Partial` weight of a Gaussian PSD whose blur is exact for Gaussians, are
//! Gaussian lobes `c − ½|L⁻¹Bᵀh|²` whose rows are formed in `f64`, and an isotropic mixture
//! with a closed-form blur is blurred with the diagonal `Ξ_α` at `Bᵀh`
//! ([`crate::psd::Form::is_exact`], [`VolumeCoherence::closed_form_for_gaussians`]). Quadrature
//! blurs and PSDs not known to be Gaussian or isotropic get `Ξ_α` in world axes (factored in
//! `f64`, rounded to `T`). The lobe that places the quadrature's nodes is the 3-D lobe restricted
//! to the sphere (the slice at `h·d̂ = 0`, narrowed where `h·d̂ = −|h|²/2k` limits it: a long
//! `σ_zz` at the `Incoherent` level), and `h` at the nodes is formed from the Lambert point, not
//! from a rounded exit direction.

mod basis;
mod coefficient;
mod coherence;
mod geometry;
mod lobes;
mod phase;
mod sampler;
mod scatterer;
mod scattering;
mod spectrum;

pub use coherence::VolumeCoherence;
pub use geometry::ScatteringGeometry;
pub use phase::{
    LevelLight, PhaseFunction, PhaseSample, PhaseValue, ScatteredLight, VolumeIncident,
};
pub use scatterer::{Dipole, Scalar, Scatterer};

#[cfg(doc)]
use crate::packet::WavePacket;

/// A random medium: a region of stationary random permittivity `δε` with PSD `psd`, whose
/// volume elements scatter with the mean matrix `scatterer` ([module docs](self)).
///
/// A renderer builds one per region (its bounds are the renderer's); slowly varying
/// (locally-stationary) matter is a different medium per region.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomMedium<P, M = Dipole> {
    /// The 3-D PSD of `δε` (rad/length in, length³ out; read through its
    /// [`crate::psd::Psd::form`]).
    pub psd: P,
    /// The mean scattering matrix `m̄` ([`Scatterer`]).
    pub scatterer: M,
}

impl<P, M> RandomMedium<P, M> {
    /// A medium from its PSD and mean scattering matrix.
    ///
    /// # Formula
    /// ```text
    /// ε(r) = n² (1 + δε(r)),   p = F{⟨δε(x) δε(x + ξ)⟩}   (3-D, unitary)
    /// index fluctuations δn:   δε = 2δn/n + (δn/n)²  ⇒  p_δε ≈ (4/n²) p_δn
    /// ```
    /// `psd` is the PSD of the **relative permittivity** fluctuation `δε`, in rad/length in and
    /// length³ out, with the packet's wavelength the one in the background of index `n`. For a
    /// medium described by its refractive-index fluctuations `δn` (rms `σ_n`), pass the `δε`
    /// spectrum: `4/n²` times the `δn` spectrum (`GaussianPsd::isotropic(2σ_n/n, ℓ)` for a
    /// Gaussian one); passed in unchanged, a `δn` spectrum in air understates `σ_s` and `dI/dV`
    /// by a factor 4 (`tests/medium/conventions.rs`, against the classical cross-section
    /// `2πk⁴Φ_n sin²χ` of index fluctuations). `GaussianPsd::isotropic(σ, ℓ)` is the correlation
    /// `σ² e^{−r²/2ℓ²}` ([module docs](self)).
    ///
    /// # Examples
    /// ```
    /// use gmueller::medium::{Dipole, RandomMedium};
    /// use gmueller::psd::GaussianPsd;
    /// // Index fluctuations of rms 5e-4 in air (n = 1), correlated over 0.3 µm.
    /// let (sigma_n, ell) = (5e-4_f64, 0.3);
    /// let medium = RandomMedium::new(GaussianPsd::<f64, 3>::isotropic(2.0 * sigma_n, ell)?, Dipole);
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    #[must_use]
    pub fn new(psd: P, scatterer: M) -> Self {
        Self { psd, scatterer }
    }
}
