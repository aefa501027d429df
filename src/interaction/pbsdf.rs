//! Polarimetric BSDFs (S2.19): the classical Mueller matrix `M` of the interaction, from the
//! incident beam's s/p frame to the exit beam's s/p frame.

use nalgebra::Matrix2;
use num_complex::Complex;

use super::geometry::Geometry;
use crate::error::Error;
use crate::frame::{Frame, frame_change_mueller};
use crate::fresnel::{self, principal_sqrt};
use crate::jones::JonesMatrix;
use crate::mueller::Mueller;
use crate::real::Real;

/// A pBSDF: the Mueller matrix `M(ŝ → r̂)` of S2.19, from the incident s/p frame
/// ([`Geometry::incident_sp`]) to the exit s/p frame ([`Geometry::exit_sp`]).
///
/// `M` is dimensionless here: the kernel supplies the `cos θ_o / λ²` of S2.20.
pub trait Pbsdf<T: Real> {
    /// The Mueller matrix for this geometry.
    #[must_use]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T>;

    /// `M₀₀` alone (what the scalar model level needs); override when cheaper than
    /// [`Pbsdf::mueller`].
    #[inline]
    #[must_use]
    fn m00(&self, g: &Geometry<T>) -> T {
        self.mueller(g).0[(0, 0)]
    }
}

/// A constant Mueller matrix, the same for every geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantMueller<T: Real>(pub Mueller<T>);

impl<T: Real> Pbsdf<T> for ConstantMueller<T> {
    #[inline]
    fn mueller(&self, _g: &Geometry<T>) -> Mueller<T> {
        self.0
    }
}

/// Specular reflection by a planar interface of relative index `η = n + iκ` (dielectric or
/// conductor): the Mueller matrix of [`fresnel::reflection`] at `cos θ_i`, in s/p frames.
///
/// # Formula
/// ```text
/// M = T(F_spec → F_exit) · A_mül (J* ⊗ J) A_mül⁻¹,   J = fresnel::reflection(cos θ_i, η)
/// F_spec = Frame::sp(r_spec, n̂),  r_spec = −ŝ + 2 cos θ_i n̂     (shares ŝ with the incident frame)
/// ```
/// `J` maps the incident s/p frame to the s/p frame of the *specular* direction; the coherent
/// lobe's exit directions `r̂ ≠ r_spec` (finite coherence) receive it by the minimal rotation
/// `r_spec → r̂` ([`crate::frame::frame_change_mueller`], the identity at `r̂ = r_spec`). Without
/// that transport the output depended on the arbitrary choice of ŝ at normal incidence (a jump
/// of the Stokes vector across the `Frame::sp` normal-incidence switch; `tests/extremes.rs`,
/// `normal_incidence_switch_is_invisible_in_a_fixed_frame`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FresnelReflection<T: Real> {
    eta: Complex<T>,
}

impl<T: Real> FresnelReflection<T> {
    /// A Fresnel reflector.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::OutOfRange`] unless `Re η > 0`, `Im η ≥ 0`, finite.
    pub fn new(eta: Complex<T>) -> Result<Self, Error> {
        validate_eta(eta)?;
        Ok(Self { eta })
    }
}

impl<T: Real> Pbsdf<T> for FresnelReflection<T> {
    #[inline]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        let m = Mueller::from_jones(&fresnel::reflection(g.cos_i, self.eta));
        frame_change_mueller(&specular_sp(g), &g.exit_sp) * m
    }
    /// `M₀₀` (the frame transport leaves it unchanged).
    #[inline]
    fn m00(&self, g: &Geometry<T>) -> T {
        let c = fresnel::coefficients(g.cos_i, self.eta);
        (c.reflectance_s() + c.reflectance_p()) * T::lit(0.5)
    }
}

/// The s/p frame of the specular direction `r_spec = −ŝ + 2 cos θ_i n̂` ([`Frame::sp`] without
/// re-normalising its inputs: ŝ and n̂ are unit, so `r_spec` is unit to rounding).
#[inline]
fn specular_sp<T: Real>(g: &Geometry<T>) -> Frame<T> {
    let n = g.surface.k();
    let r_spec = n * (g.cos_i + g.cos_i) - g.to_source;
    Frame::sp_unit(r_spec, n)
}

/// First-order perturbation (Rayleigh–Rice) scattering by a rough interface of relative
/// permittivity `ε = η²`, as SCATMECH's `Microroughness_BRDF_Model` (Germer, Appl. Opt. 36,
/// 8798, 1997) defines its polarization factors.
///
/// # Formula
/// ```text
/// q_i = √(ε − sin²θ_i),   q_o = √(ε − sin²θ_o)           (principal branch)
/// ss =  (ε−1) cos φ / [(cos θ_i + q_i)(cos θ_o + q_o)]
/// pp =  (ε−1)(ε sin θ_i sin θ_o − q_o q_i cos φ) / [(ε cos θ_i + q_i)(ε cos θ_o + q_o)]
/// ps = −(ε−1) q_i sin φ / [(ε cos θ_i + q_i)(cos θ_o + q_o)]      (p in → s out)
/// sp = −(ε−1) q_o sin φ / [(cos θ_i + q_i)(ε cos θ_o + q_o)]      (s in → p out)
/// J  = 2k cos θ_i [[ss, ps], [sp, pp]],      M = A_mül (J* ⊗ J) A_mül⁻¹   (S1.7)
/// ```
/// φ is the exit azimuth from the forward plane of incidence ([`Geometry::exit_azimuth`]).
/// The factor `2k cos θ_i` makes the kernel's plane-wave limit `cos θ_o/λ² · M · 2π p(h_t)`
/// equal the Rayleigh–Rice BRDF `16π²/λ⁴ cos θ_i cos θ_o Q S(f)` times `cos θ_i`
/// (`p = S/(2π)` converts SCATMECH's PSD to ours): the kernel returns radiance per unit
/// incident irradiance *across the beam*, the BRDF is per unit irradiance *on the surface*.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayleighRice<T: Real> {
    epsilon: Complex<T>,
}

impl<T: Real> RayleighRice<T> {
    /// A Rayleigh–Rice scatterer with substrate index `η = n + iκ` (relative permittivity η²).
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::OutOfRange`] unless `Re η > 0`, `Im η ≥ 0`, finite.
    pub fn new(eta: Complex<T>) -> Result<Self, Error> {
        validate_eta(eta)?;
        Ok(Self { epsilon: eta * eta })
    }

    /// The substrate's relative permittivity `ε = η²`.
    #[inline]
    #[must_use]
    pub fn permittivity(&self) -> Complex<T> {
        self.epsilon
    }

    /// The polarization factors `[[ss, ps], [sp, pp]]` (without `2k cos θ_i`).
    #[must_use]
    pub fn factors(&self, g: &Geometry<T>) -> Matrix2<Complex<T>> {
        let e = self.epsilon;
        let one = Complex::new(T::one(), T::zero());
        let (ci, co) = (g.cos_i, g.cos_o);
        let sin2 = |c: T| (T::one() - c * c).max(T::zero());
        let (si2, so2) = (sin2(ci), sin2(co));
        let (cphi, sphi) = g.exit_azimuth();
        let qi = principal_sqrt(e - one * si2);
        let qo = principal_sqrt(e - one * so2);
        let em1 = e - one;
        // Denominators: s-type D₁ = cos θ_i + q_i, D₂ = cos θ_o + q_o; p-type D₃ = ε cos θ_i + q_i,
        // D₄ = ε cos θ_o + q_o. Two complex reciprocals (one real division each) give all four
        // pairings: 1/(D₃D₂) = D₁D₄/(D₁D₂·D₃D₄), 1/(D₁D₄) = D₂D₃/(D₁D₂·D₃D₄).
        let (d1, d2, d3, d4) = (qi + ci, qo + co, e * ci + qi, e * co + qo);
        let inv_ss = recip(d1 * d2);
        let inv_pp = recip(d3 * d4);
        let both = inv_ss * inv_pp;
        let ss = em1 * inv_ss * cphi;
        let pp = em1 * (e * (si2 * so2).sqrt() - qo * qi * cphi) * inv_pp;
        let ps = -em1 * qi * (d1 * d4 * both) * sphi;
        let sp = -em1 * qo * (d2 * d3 * both) * sphi;
        Matrix2::new(ss, ps, sp, pp)
    }

    /// The Jones matrix `2k cos θ_i [[ss, ps], [sp, pp]]`.
    #[must_use]
    pub fn jones(&self, g: &Geometry<T>) -> JonesMatrix<T> {
        JonesMatrix(self.factors(g) * Complex::new(T::lit(2.0) * g.k * g.cos_i, T::zero()))
    }
}

impl<T: Real> Pbsdf<T> for RayleighRice<T> {
    #[inline]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        Mueller::from_jones(&self.jones(g))
    }
    /// `M₀₀ = ½ Σ |J_ij|²` without the rest of the Mueller matrix.
    #[inline]
    fn m00(&self, g: &Geometry<T>) -> T {
        let scale = T::lit(2.0) * g.k * g.cos_i;
        let f = self.factors(g);
        T::lit(0.5) * scale * scale * f.iter().fold(T::zero(), |acc, z| acc + z.norm_sqr())
    }
}

/// `1/z = z̄/|z|²` with one real division (for the O(1)–O(|ε|²) denominator products of
/// [`RayleighRice::factors`]: `|z|²` stays finite for `|ε|` up to ~10⁷⁵ in f64, ~10⁹ in f32).
#[inline]
fn recip<T: Real>(z: Complex<T>) -> Complex<T> {
    let inv = T::one() / z.norm_sqr();
    Complex::new(z.re * inv, -z.im * inv)
}

/// A scalar phase-screen (Kirchhoff) scatterer: a height field `z(x)` on a reflector of
/// amplitude reflectance `r` imprints the phase `v z(x)`, `v = k (cos θ_i + cos θ_o)`, so the
/// first-order scattered field is `i v z(x) r` times the incident field and
/// ```text
/// M = |r|² v² I₄          (polarization-preserving)
/// ```
/// This is the model of the reference scalar tracer; with the kernel's roughness attenuation it
/// is the first term of the Beckmann–Kirchhoff series.
///
/// # Energy: not conserved near grazing incidence (a limit of the model)
/// On a lossless screen (`|r|² = 1`, mirror specular part) the plane-wave reflected fraction is
/// ```text
/// T = α_s + S,   α_s = exp(−(2kσ cos θ_i)²)                       (Debye–Waller, specular)
/// S = 1/cos θ_i ∫ cos²θ_o/λ² · α(v) v² · 2π p(h_t) dω               (first-order scattered)
///   = (1 − α_s) ρ,      T − 1 = (ρ − 1)(1 − α_s) ≈ (ρ − 1)(2kσ cos θ_i)²
/// ```
/// with ρ (Gaussian PSD, kσ = 0.1; `tests/interaction_energy.rs`, `energy_at_grazing_incidence`,
/// where the kernel's total equals this integral, computed independently, to 2e-12):
/// ```text
/// θ_i        0°     45°    60°    70°    75°    80°    85°
/// ℓ = 2λ   0.968  0.968  0.970  1.126  1.508  2.917  13.96
/// ℓ = 10λ  0.980  0.989  0.994  0.997  1.005  1.116  2.592
/// ```
/// (ρ falls slowly with kσ: 1.46 at 75°, 13.7 at 85° for ℓ = 2λ, kσ = 0.3). So at ℓ = 2λ the
/// screen reflects `T = 1.0052` at `θ_i = 75°`, kσ = 0.2 and `T = 1.0156` at 85°, inside the
/// first-order range `kσ (cos θ_i + 1) < 0.5`; at `θ_i ≤ 45°` it stays ≤ 1.
///
/// Why: the Debye–Waller factor takes `1 − α_s ≈ (v_s σ)²`, `v_s = 2k cos θ_i`, out of the
/// specular beam, while the first-order power scattered into the PSD component `p(h_t)` carries
/// `(cos θ_o/cos θ_i)(v/v_s)² = c (1 + c)²/4`, `c = cos θ_o/cos θ_i` — the far-field obliquity
/// (`cos²θ_o/λ²` over `dω = d²h_t/(k² cos θ_o)`, per `cos θ_i` of irradiance on the surface)
/// times the phase factor `v² = k² (cos θ_i + cos θ_o)²` — and nothing for evanescent `h_t`. The
/// two balance only where `c ≈ 1` across the PSD lobe, i.e. `kℓ cos²θ_i ≫ 1` (the lobe's width
/// `~1/(kℓ)` in `r̂_t` changes `c` by `~sin θ_i/(kℓ cos²θ_i)`). Near grazing the lobe reaches
/// from the horizon (`c = 0`, beyond it evanescent and lost) to `c` of several toward the
/// normal, and the cubic weight wins (`ρ > 1`); away from grazing most of the lobe has `c < 1`
/// (at normal incidence all of it) and `ρ < 1`.
///
/// The brute-force reference (`examples/scalar_tracer`, `--energy`), which builds the same model
/// from its definition with all orders of `e^{v²R}`, measures the same excess: a coherent
/// Gaussian beam on a lossless Gaussian surface (ℓ = 2λ, 128 realizations), normalised by what a
/// mirror reflects of the same beam, reflects 1.005480 ± 0.000017 at 75°, kσ = 0.2 (the model's
/// analytic total for that beam: 1.005474) and 1.015817 ± 0.000013 at 85° (1.015827).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseScreen<T: Real> {
    reflectance: T,
}

impl<T: Real> PhaseScreen<T> {
    /// A phase screen on a reflector of power reflectance `|r|²` in `[0, 1]`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `0 ≤ |r|² ≤ 1`.
    pub fn new(reflectance: T) -> Result<Self, Error> {
        if !(reflectance >= T::zero() && reflectance <= T::one()) {
            return Err(Error::OutOfRange {
                what: "power reflectance",
                value: reflectance.to_f64(),
                expected: "[0, 1]",
            });
        }
        Ok(Self { reflectance })
    }
}

impl<T: Real> Pbsdf<T> for PhaseScreen<T> {
    #[inline]
    fn mueller(&self, g: &Geometry<T>) -> Mueller<T> {
        Mueller(nalgebra::Matrix4::identity() * self.m00(g))
    }
    #[inline]
    fn m00(&self, g: &Geometry<T>) -> T {
        let v = g.k * (g.cos_i + g.cos_o);
        self.reflectance * v * v
    }
}

/// An ideal depolarizer of albedo `a`: `M = a · diag(1, 0, 0, 0)` — every output unpolarized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdealDiffuse<T: Real> {
    albedo: T,
}

impl<T: Real> IdealDiffuse<T> {
    /// An ideal depolarizer.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `albedo ≥ 0` and finite.
    pub fn new(albedo: T) -> Result<Self, Error> {
        if !(albedo >= T::zero() && albedo.is_finite()) {
            return Err(Error::OutOfRange {
                what: "albedo",
                value: albedo.to_f64(),
                expected: "finite and ≥ 0",
            });
        }
        Ok(Self { albedo })
    }
}

impl<T: Real> Pbsdf<T> for IdealDiffuse<T> {
    #[inline]
    fn mueller(&self, _g: &Geometry<T>) -> Mueller<T> {
        let mut m = nalgebra::Matrix4::zeros();
        m[(0, 0)] = self.albedo;
        Mueller(m)
    }
    #[inline]
    fn m00(&self, _g: &Geometry<T>) -> T {
        self.albedo
    }
}

fn validate_eta<T: Real>(eta: Complex<T>) -> Result<(), Error> {
    crate::error::ensure_finite("refractive index", [eta.re, eta.im])?;
    if !(eta.re > T::zero() && eta.im >= T::zero()) {
        return Err(Error::OutOfRange {
            what: "refractive index η = n + iκ",
            value: eta.re.to_f64(),
            expected: "Re η > 0 and Im η ≥ 0",
        });
    }
    Ok(())
}
