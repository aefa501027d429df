//! Far-field propagation (S2.1–S2.6): the vector Smythe diffraction formula, and the
//! propagation of the CSD matrix, of the generalized Stokes parameters and of the generalized
//! radiance from a scattering region to a pair of far-field points.
//!
//! # The formulas
//! ```text
//! S2.1:  E′(r) = (i e^{ikr}/(λ r)) r̂ × ∫_P [n̂ × E(p)] e^{−ik r̂·p} d²p
//! S2.2:  C_o(r₁, r₂) = e^{ik r̂·(r₁−r₂)}/(λ² r²) ∫∫ e^{−ik(r̂₁·p₁ − r̂₂·p₂)} P C_P(p₁, p₂) Pᵀ
//! S2.5:  S_o = e^{ik r̂·(r₁−r₂)}/(λ² r²) ∫∫ e^{−ik(r̂₁·p₁ − r̂₂·p₂)} M_P S_P(p₁, p₂)
//! S2.6:  L_o = (r²/A) S_o,      A the projected area of P in direction r̂
//! ```
//! `P` is the 2×2 real **projection** that takes the field's components in the incident frame
//! (x̂, ŷ) to the far field's in the exit frame (x̂′, ŷ′), and `M_P = A_mül (P ⊗ P) A_mül⁻¹` its
//! Mueller matrix ([`projection_mueller`]). The seed prints `P = cos θ_o τ` (τ of S2.3), i.e.
//! `cos²θ_o τ C τᵀ` and `cos²θ_o T S` ([`seed_projection`]). That is the scalar
//! (Rayleigh–Sommerfeld) obliquity applied to a frame rotation; the vector formula S2.1 it is
//! derived from gives [`smythe_projection`], `P_ab = x̂′_a · (r̂ × (n̂ × b̂))`, which differs from
//! it for p-polarized light away from the normal (`tests/propagation.rs` decides this by Monte
//! Carlo; errata, item 10). A volume under the first Born approximation radiates the dipole
//! pattern `−r̂ × (r̂ × V)` of its source density, [`born_projection`], and has no `cos θ_o`.
//!
//! # Conventions
//! Time dependence `e^{−iωt}`; the CSD is `C(p₁, p₂) = ⟨E(p₁) E(p₂)†⟩` (first point
//! unconjugated); `r̂ⱼ = rⱼ/|rⱼ|`, `r̂` the unit bisector of `r̂₁, r̂₂` and `r² = |r₁||r₂|` (the
//! product of the two fields' `1/r`). The far-field approximation is `|p| ≪ r` and
//! `k|p|²/r ≪ 1`; the projection is evaluated once, at the mean direction (the seed's
//! `r̂ ≈ r̂₁ ≈ r̂₂`). The region is a quadrature: nodes `pⱼ` with weights `wⱼ` (area elements on an
//! aperture, volume elements in a volume).
//!
//! The double integrals are reference computations, `O(n²)` in the number of nodes, generic
//! over `T: Real` but meant for `f64` (in `f32` the sum's rounding grows with `n`, and the
//! propagator phase `kr` loses all digits beyond `r ≈ 10⁶ λ`). They allocate one vector of
//! phases per call.

use nalgebra::{Matrix2, Vector3};
use num_complex::Complex;

use crate::error::Error;
use crate::frame::{Frame, tau};
use crate::jones::JonesMatrix;
use crate::mueller::Mueller;
use crate::numerics::unit_direction;
use crate::real::Real;
use crate::stokes::GeneralizedStokes;

/// A sample of an aperture field for [`smythe_far_field`]: a point, the (complex, 3-vector)
/// electric field there, and the quadrature weight (area element).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApertureSample<T: Real> {
    /// The point `p` in the aperture plane.
    pub position: Vector3<T>,
    /// `E(p)`, world components.
    pub field: Vector3<Complex<T>>,
    /// The area element `d²p` of the quadrature.
    pub weight: T,
}

/// A quadrature node of a scattering region: a point and its weight (area or volume element).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegionNode<T: Real> {
    /// The point `p`.
    pub position: Vector3<T>,
    /// The weight `d²p` or `d³p`.
    pub weight: T,
}

fn positive<T: Real>(what: &'static str, v: T) -> Result<T, Error> {
    if !v.is_finite() {
        return Err(Error::NonFinite { what });
    }
    if v > T::zero() {
        Ok(v)
    } else {
        Err(Error::OutOfRange {
            what,
            value: v.to_f64(),
            expected: "(0, ∞)",
        })
    }
}

/// `e^{iθ}`.
fn cis<T: Real>(theta: T) -> Complex<T> {
    let (s, c) = theta.sin_cos();
    Complex::new(c, s)
}

/// The integral of S2.1 without its propagator: `r̂ × Σⱼ wⱼ [n̂ × E(pⱼ)] e^{−ik r̂·pⱼ}`, so that
/// the far field is `E′(r) = (i e^{ikr}/(λ r)) · smythe_amplitude(…)`.
///
/// # Formula
/// ```text
/// S2.1:  F(r̂) = r̂ × ∫_P [n̂ × E(p)] e^{−ik r̂·p} d²p,     k = 2π/λ
/// ```
/// `normal` and `direction` are normalized here. Use this rather than [`smythe_far_field`] in
/// `f32` (no `e^{ikr}`).
///
/// # Errors
/// [`Error::OutOfRange`]/[`Error::NonFinite`] for a wavelength that is not finite and positive;
/// [`Error::NonFinite`]/[`Error::InvalidBasis`] for a non-finite or zero normal or direction.
pub fn smythe_amplitude<T: Real>(
    wavelength: T,
    normal: &Vector3<T>,
    direction: &Vector3<T>,
    aperture: &[ApertureSample<T>],
) -> Result<Vector3<Complex<T>>, Error> {
    let k = T::two_pi() / positive("wavelength", wavelength)?;
    let n = unit_direction(normal, "aperture normal")?.map(|x| Complex::new(x, T::zero()));
    let r = unit_direction(direction, "far-field direction")?;
    let mut sum = Vector3::<Complex<T>>::zeros();
    for s in aperture {
        let phase = cis(-k * r.dot(&s.position)) * s.weight;
        sum += n.cross(&s.field) * phase;
    }
    Ok(r.map(|x| Complex::new(x, T::zero())).cross(&sum))
}

/// The far-field Smythe diffraction formula S2.1: the field at distance `distance` in direction
/// `direction` from a planar aperture with normal `normal`, given samples of the field in it.
///
/// # Formula
/// ```text
/// S2.1:  E′(r) = (i e^{ikr}/(λ r)) r̂ × ∫_P [n̂ × E(p)] e^{−ik r̂·p} d²p
/// ```
/// `E` is the field in the aperture (only its tangential part `n̂ × E` matters), P centred near
/// the origin, the integral the quadrature of `aperture`. Valid in the far field
/// (`r ≫ |p|`, `k|p|²/(2r) ≪ 1`): `tests/propagation.rs` compares it with the exact Smythe
/// integral `(1/2π) ∫ ∇G × (n̂ × E) d²p`, `G = e^{ikR}/R`, whose difference falls as `1/r`.
/// E′ is transverse (`r̂ · E′ = 0`).
///
/// # Errors
/// As [`smythe_amplitude`]; [`Error::OutOfRange`]/[`Error::NonFinite`] for a distance that is
/// not finite and positive.
///
/// # Examples
/// A Gaussian aperture field `E₀ e^{−|p|²/(2w²)}` (x̂-polarized, normal incidence) sends
/// `|E′|² = (2π w² |E₀| / (λ r))²` straight ahead:
/// ```
/// use gmueller::propagation::{ApertureSample, smythe_far_field};
/// use nalgebra::Vector3;
/// use num_complex::Complex;
/// let (lambda, w, d) = (0.5_f64, 1.0, 0.1);
/// let mut aperture = Vec::new();
/// for i in -80..=80 {
///     for j in -80..=80 {
///         let p = Vector3::new(i as f64 * d, j as f64 * d, 0.0);
///         let e = (-0.5 * p.norm_squared() / (w * w)).exp();
///         aperture.push(ApertureSample { position: p, field: Vector3::new(e.into(), 0.0.into(), 0.0.into()), weight: d * d });
///     }
/// }
/// let r = 1e4;
/// let e = smythe_far_field(lambda, &Vector3::z(), &Vector3::z(), r, &aperture)?;
/// let expected = core::f64::consts::TAU * w * w / (lambda * r);
/// assert!((e.norm() - expected).abs() < 1e-12 * expected);
/// # Ok::<(), gmueller::Error>(())
/// ```
pub fn smythe_far_field<T: Real>(
    wavelength: T,
    normal: &Vector3<T>,
    direction: &Vector3<T>,
    distance: T,
    aperture: &[ApertureSample<T>],
) -> Result<Vector3<Complex<T>>, Error> {
    let r = positive("distance", distance)?;
    let amplitude = smythe_amplitude(wavelength, normal, direction, aperture)?;
    let k = T::two_pi() / wavelength;
    let prefactor = Complex::new(T::zero(), T::one()) * cis(k * r) / (wavelength * r);
    Ok(amplitude * prefactor)
}

/// The projection of S2.2 as printed, `P = cos θ_o τ`: τ (S2.3) from `incident` to `exit`
/// times the obliquity `cos θ_o = |r̂ · n̂|`, `r̂` the exit frame's k̂.
///
/// # Formula
/// ```text
/// S2.2:  P C Pᵀ = cos²θ_o τ C τᵀ,     S2.5:  M_P = cos²θ_o T(φ)    (S2.4)
/// ```
/// The scalar obliquity: it agrees with [`smythe_projection`] at normal exit and for
/// s-polarized light, not for p-polarized light away from the normal (errata, item 10).
#[must_use]
pub fn seed_projection<T: Real>(
    incident: &Frame<T>,
    exit: &Frame<T>,
    normal: &Vector3<T>,
) -> Matrix2<T> {
    let cos_o = exit.k().dot(normal).abs() / normal.norm();
    tau(incident, exit) * cos_o
}

/// The projection that the vector Smythe formula S2.1 gives: the exit-frame components of
/// `r̂ × (n̂ × b̂)` for the incident basis vectors `b̂ ∈ {x̂, ŷ}`.
///
/// # Formula
/// ```text
/// S2.1 ⇒ S2.2:  P_ab = x̂′_a · (r̂ × (n̂ × b̂)),   a ∈ {x̂′, ŷ′} (exit),  b̂ ∈ {x̂, ŷ} (incident)
/// ```
/// E.g. at normal incidence with the exit in the x–z plane at `θ_o`: `P = −diag(1, cos θ_o)` for
/// x̂ → p̂′, ŷ → ŝ′ — the p-component keeps its amplitude, only the s-component has the
/// obliquity `cos θ_o` (`seed_projection` puts `cos θ_o` on both).
#[must_use]
pub fn smythe_projection<T: Real>(
    incident: &Frame<T>,
    exit: &Frame<T>,
    normal: &Vector3<T>,
) -> Matrix2<T> {
    let n = normal / normal.norm();
    let r = exit.k();
    let column = |b: Vector3<T>| {
        let v = r.cross(&n.cross(&b));
        (exit.x().dot(&v), exit.y().dot(&v))
    };
    let (a, c) = column(incident.x());
    let (b, d) = column(incident.y());
    Matrix2::new(a, b, c, d)
}

/// The projection of a volume's first-Born far field: the dipole pattern `−r̂ × (r̂ × V)` of a
/// source density `V` transverse to the incident direction, in the exit frame.
///
/// # Formula
/// ```text
/// E′(r) = (e^{ikr}/(λ r)) ∫ [V(p) − r̂ (r̂·V(p))] e^{−ik r̂·p} d³p,   V = (k/2)(ε − 1) E
/// ⇒ P_ab = x̂′_a · b̂     (S2.3's dot products, not normalized)
/// ```
/// (`E_scat = k²/(4π r) e^{ikr} ∫ (ε−1) E_⊥ e^{−ik r̂·p}` and `k²/4π = (1/λ)(k/2)`.) Its
/// determinant is `k̂ · r̂ = cos Θ`: scattered at angle Θ, the component in the scattering plane
/// is reduced by `cos Θ` (Rayleigh's `cos²Θ`); τ (S2.3) normalizes that away.
#[must_use]
pub fn born_projection<T: Real>(incident: &Frame<T>, exit: &Frame<T>) -> Matrix2<T> {
    let (x, y) = (incident.x(), incident.y());
    Matrix2::new(
        exit.x().dot(&x),
        exit.x().dot(&y),
        exit.y().dot(&x),
        exit.y().dot(&y),
    )
}

/// The Mueller matrix of a projection, `M_P = A_mül (P ⊗ P) A_mül⁻¹` (S1.7 for the real Jones
/// matrix P); for [`seed_projection`] it is `cos²θ_o T(φ)` (S2.4).
#[must_use]
pub fn projection_mueller<T: Real>(projection: &Matrix2<T>) -> Mueller<T> {
    Mueller::from_jones(&JonesMatrix(projection.map(|x| Complex::new(x, T::zero()))))
}

/// Two far-field points `r₁`, `r₂` (S2.2): their directions, mean direction and distances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FarFieldPair<T: Real> {
    r1: Vector3<T>,
    r2: Vector3<T>,
}

impl<T: Real> FarFieldPair<T> {
    /// Two observation points (from the region's origin).
    ///
    /// # Errors
    /// [`Error::NonFinite`] for non-finite points; [`Error::InvalidBasis`] for a point at the
    /// origin or two opposite directions (no mean direction).
    pub fn new(r1: Vector3<T>, r2: Vector3<T>) -> Result<Self, Error> {
        unit_direction(&r1, "far-field point")?;
        unit_direction(&r2, "far-field point")?;
        let pair = Self { r1, r2 };
        unit_direction(
            &(pair.direction(0) + pair.direction(1)),
            "mean far-field direction",
        )?;
        Ok(pair)
    }

    /// Both points at `distance` in the directions `d₁`, `d₂`.
    ///
    /// # Errors
    /// As [`FarFieldPair::new`], and for a distance that is not finite and positive.
    pub fn at_distance(distance: T, d1: &Vector3<T>, d2: &Vector3<T>) -> Result<Self, Error> {
        let r = positive("distance", distance)?;
        Self::new(
            unit_direction(d1, "far-field direction")?.into_inner() * r,
            unit_direction(d2, "far-field direction")?.into_inner() * r,
        )
    }

    /// `r̂₁` (`which = 0`) or `r̂₂` (otherwise).
    #[must_use]
    pub fn direction(&self, which: usize) -> Vector3<T> {
        let r = if which == 0 { &self.r1 } else { &self.r2 };
        r / r.norm()
    }

    /// `r̂`, the unit bisector of `r̂₁` and `r̂₂`.
    #[must_use]
    pub fn mean_direction(&self) -> Vector3<T> {
        let m = self.direction(0) + self.direction(1);
        m / m.norm()
    }

    /// `r² = |r₁| |r₂|`.
    #[must_use]
    pub fn distance_squared(&self) -> T {
        self.r1.norm() * self.r2.norm()
    }

    /// The propagator `e^{ik r̂·(r₁ − r₂)} / (λ² r²)` of S2.2.
    fn propagator(&self, wavelength: T) -> Complex<T> {
        let k = T::two_pi() / wavelength;
        cis(k * self.mean_direction().dot(&(self.r1 - self.r2)))
            / (wavelength * wavelength * self.distance_squared())
    }

    /// `(wⱼ e^{−ik r̂₁·pⱼ}, wⱼ e^{−ik r̂₂·pⱼ})` for every node.
    fn phases(&self, wavelength: T, region: &[RegionNode<T>]) -> Vec<(Complex<T>, Complex<T>)> {
        let k = T::two_pi() / wavelength;
        let (d1, d2) = (self.direction(0), self.direction(1));
        region
            .iter()
            .map(|n| {
                (
                    cis(-k * d1.dot(&n.position)) * n.weight,
                    cis(-k * d2.dot(&n.position)) * n.weight,
                )
            })
            .collect()
    }
}

/// Far-field propagation of the CSD matrix, S2.2: the CSD of the far field at `r₁, r₂` from the
/// CSD `csd(p₁, p₂)` of the field at the region (components in the incident frame), with a
/// projection `P` ([`seed_projection`], [`smythe_projection`], [`born_projection`]).
///
/// # Formula
/// ```text
/// S2.2:  C_o(r₁, r₂) = e^{ik r̂·(r₁−r₂)}/(λ² r²) Σⱼ Σₗ wⱼ wₗ e^{−ik(r̂₁·pⱼ − r̂₂·pₗ)} P C_P(pⱼ, pₗ) Pᵀ
/// ```
/// the double (2-D or 3-D) Fourier transform of S2.2 as a quadrature over `region`. With
/// `P = seed_projection(…)` this is S2.2 as printed (`cos²θ_o τ C τᵀ`).
///
/// # Errors
/// [`Error::OutOfRange`]/[`Error::NonFinite`] for a wavelength that is not finite and positive.
///
/// # Examples
/// A fully coherent field, `C_P = E Eᵀ*`, gives the outer product of S2.1's far fields:
/// ```
/// use gmueller::frame::Frame;
/// use gmueller::propagation::{ApertureSample, FarFieldPair, RegionNode, propagate_csd,
///     smythe_far_field, smythe_projection};
/// use nalgebra::{Matrix2, Vector2, Vector3};
/// use num_complex::Complex;
/// let (lambda, d) = (0.5_f64, 0.1);
/// let incident = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
/// let jones = |p: &Vector3<f64>| Vector2::new(Complex::new((-p.norm_squared()).exp(), 0.0),
///     Complex::new(0.0, 0.5 * (-p.norm_squared()).exp()));
/// let nodes: Vec<_> = (-20..=20).flat_map(|i| (-20..=20).map(move |j|
///     RegionNode { position: Vector3::new(i as f64 * d, j as f64 * d, 0.0), weight: d * d })).collect();
/// let dir = Vector3::new(0.3, 0.1, 1.0).normalize();
/// let exit = Frame::sp(dir, Vector3::z())?;
/// let pair = FarFieldPair::at_distance(100.0, &dir, &dir)?;
/// let p = smythe_projection(&incident, &exit, &Vector3::z());
/// let c = propagate_csd(lambda, &pair, &p, &nodes, |a, b| jones(a) * jones(b).adjoint())?;
/// // The same from S2.1 (world-vector field → exit components).
/// let aperture: Vec<_> = nodes.iter().map(|n| { let e = jones(&n.position);
///     ApertureSample { position: n.position, weight: n.weight,
///         field: incident.x().map(Complex::from) * e[0] + incident.y().map(Complex::from) * e[1] } }).collect();
/// let f = smythe_far_field(lambda, &Vector3::z(), &dir, 100.0, &aperture)?;
/// let e = Vector2::new(exit.x().map(Complex::from).dot(&f), exit.y().map(Complex::from).dot(&f));
/// assert!((c - e * e.adjoint()).norm() < 1e-12 * c.norm());
/// # Ok::<(), gmueller::Error>(())
/// ```
pub fn propagate_csd<T: Real>(
    wavelength: T,
    points: &FarFieldPair<T>,
    projection: &Matrix2<T>,
    region: &[RegionNode<T>],
    csd: impl Fn(&Vector3<T>, &Vector3<T>) -> Matrix2<Complex<T>>,
) -> Result<Matrix2<Complex<T>>, Error> {
    let wavelength = positive("wavelength", wavelength)?;
    let phases = points.phases(wavelength, region);
    let mut sum = Matrix2::<Complex<T>>::zeros();
    for (nj, (aj, _)) in region.iter().zip(&phases) {
        for (nl, (_, bl)) in region.iter().zip(&phases) {
            // e^{−ik r̂₁·pⱼ} (e^{−ik r̂₂·pₗ})* = e^{−ik(r̂₁·pⱼ − r̂₂·pₗ)}
            sum += csd(&nj.position, &nl.position) * (aj * bl.conj());
        }
    }
    let p = projection.map(|x| Complex::new(x, T::zero()));
    Ok(p * sum * p.transpose() * points.propagator(wavelength))
}

/// Far-field propagation of the generalized Stokes parameters, S2.5: S2.2 under `A_mül`, with
/// the projection's Mueller matrix `M_P` ([`projection_mueller`]; `cos²θ_o T` as printed).
///
/// # Formula
/// ```text
/// S2.5:  S_o = e^{ik r̂·(r₁−r₂)}/(λ² r²) Σⱼ Σₗ wⱼ wₗ e^{−ik(r̂₁·pⱼ − r̂₂·pₗ)} M_P S_P(pⱼ, pₗ)
/// ```
/// `stokes(p₁, p₂)` is `S_P = A_mül vec(C_P(p₁, p₂))` (S1.2), a two-point (complex) vector.
///
/// # Errors
/// As [`propagate_csd`].
pub fn propagate_stokes<T: Real>(
    wavelength: T,
    points: &FarFieldPair<T>,
    mueller: &Mueller<T>,
    region: &[RegionNode<T>],
    stokes: impl Fn(&Vector3<T>, &Vector3<T>) -> GeneralizedStokes<T>,
) -> Result<GeneralizedStokes<T>, Error> {
    let wavelength = positive("wavelength", wavelength)?;
    let phases = points.phases(wavelength, region);
    let mut sum = nalgebra::Vector4::<Complex<T>>::zeros();
    for (nj, (aj, _)) in region.iter().zip(&phases) {
        for (nl, (_, bl)) in region.iter().zip(&phases) {
            sum += stokes(&nj.position, &nl.position).0 * (aj * bl.conj());
        }
    }
    let m = mueller.0.map(|x| Complex::new(x, T::zero()));
    Ok(GeneralizedStokes(m * sum * points.propagator(wavelength)))
}

/// Far-field propagation of the generalized radiance, S2.6: S2.5 times `r²/A`, `A` the
/// projected area of the region in the mean direction (`A = |P| cos θ_o` for a planar region
/// of area `|P|`).
///
/// # Formula
/// ```text
/// S2.6:  L_o = e^{ik r̂·(r₁−r₂)}/(λ² A) Σⱼ Σₗ wⱼ wₗ e^{−ik(r̂₁·pⱼ − r̂₂·pₗ)} M_P S_P(pⱼ, pₗ)
/// ```
/// Radiance is intensity (`r² S_o`, power per solid angle) per projected area of the source;
/// it does not depend on `r`.
///
/// # Errors
/// As [`propagate_stokes`]; [`Error::OutOfRange`]/[`Error::NonFinite`] for an area that is not
/// finite and positive.
pub fn propagate_radiance<T: Real>(
    wavelength: T,
    points: &FarFieldPair<T>,
    mueller: &Mueller<T>,
    projected_area: T,
    region: &[RegionNode<T>],
    stokes: impl Fn(&Vector3<T>, &Vector3<T>) -> GeneralizedStokes<T>,
) -> Result<GeneralizedStokes<T>, Error> {
    let area = positive("projected area", projected_area)?;
    let s = propagate_stokes(wavelength, points, mueller, region, stokes)?;
    Ok(s * (points.distance_squared() / area))
}
