//! The coherence one Monte Carlo sample of light carries: rules and helpers for a sample of a
//! distant source, an area light, a sky, and indirect light.
//!
//! # The rule
//! An incoherent source is a sum of mutually incoherent plane waves, so a sample of it may
//! carry **any** coherence between two limits, each exact in expectation for a different
//! question:
//! - `w → ∞` (a plane wave per sample): exact for every source, but the coherent specular lobe
//!   is then a Dirac delta that only a direction drawn from the lobe itself can see;
//! - the coherence of the part of the source the sample stands for (van Cittert–Zernike:
//!   `Θ⊥ = λ²/(π Ω) I` for a disk of solid angle `Ω`): the specular lobe is then the (Gaussian)
//!   image of that part of the source — one sample per source gives its whole blurred
//!   reflection with no variance, but the image of a disk is replaced by a Gaussian of the
//!   same second moment.
//!
//! Between them, a finite width **blurs** mirror images by `1/(k w)` in the projected-disk
//! coordinates (a bias: the image of the source convolved with that Gaussian) and in exchange
//! **lowers the variance** of light sampling, whose directions can hit a lobe of finite width.
//! The helpers below implement one rule per kind of light; `docs/renderer.md` gives the
//! trade-off measured on one scene for each.
//!
//! | light | sample carries | helper |
//! |---|---|---|
//! | distant source (sun) | the whole disk's coherence, one packet along its centre | [`distant_disk`] |
//! | area light | the coherence of the light's projected area at its distance | [`area_light`] |
//! | sky, environment | a chosen width `w` on the surface ([`SurfaceCoherence`]) | [`SurfaceCoherence::packet`] |
//! | indirect, backward | the same assumed width as the sky (what the BSDF sampler draws for) | [`SurfaceCoherence`] |
//! | indirect, forward | the exitant packet of the previous vertex | [`crate::interaction::exitant::exitant_packet`] |
//!
//! # Surface-isotropic coherence
//! Coherence that is isotropic **on the surface** (width `σ` along every tangent) is, seen
//! across a beam arriving at `θ_i`, shorter in the plane of incidence by `cos θ_i`:
//! ```text
//! Θ⊥ = diag(σ², σ² cos²θ_i)      in the incident s/p frame (x̂ = ŝ_perp, ŷ = p̂)
//! Ξ  = Aᵀ Θ⊥⁻¹ A = I/σ²          (A the projection of the tangents on the beam's transverse plane)
//! ```
//! Passing `σ² I` instead gives `Ξ = diag(1/σ², cos²θ_i/σ²)` (s, in-plane tangent): a footprint
//! stretched by `1/cos θ_i` in the plane of incidence (an independent brute-force comparison found the lobe
//! width off by 53 standard errors at `θ_i = 30°`, σ = 0.5 µm, ℓ = 2 µm).

use nalgebra::{Matrix2, Vector3};

use crate::error::Error;
use crate::frame::Frame;
use crate::packet::{CoherenceShape, WavePacket};
use crate::real::Real;
use crate::stokes::Stokes;

/// Coherence that is isotropic on the surface: width `σ` (length) along every tangent, widened
/// near the horizon by the horizon rule unless built with [`SurfaceCoherence::fixed`].
///
/// What a backward tracer assumes for light arriving from a direction it draws (sky samples and
/// indirect light), so that the BSDF sampler ([`super::Bsdf::incident_sampler`]) and light
/// sampling agree on the integrand (multiple importance sampling needs both to estimate the
/// same thing). At the plane-wave level the width is ignored.
///
/// # The horizon rule
/// ```text
/// σ(θ) = √(σ² + (Q / (k cos²θ))²),     Q = 16      (θ the light's angle from the normal,
///                                                  k its wavenumber in the medium it crosses)
/// ```
/// The coherent lobe of light with surface coherence `σ` is `1/(kσ)` wide in the projected
/// disk, and the horizon lies `≈ cos²θ/2` from its centre: the lobe fits only while
/// `q = kσ cos²θ` is large. Measured with [`super::Bsdf::sample_incident`] on a smooth mirror
/// at a **fixed** width (the white furnace, which must give 1), the backward estimate depends
/// on `q` alone from 60° to 89°: 0.63 at `q = 1`, 0.95 at 2, 1.15 at 4, 1.041 at 8, 1.015 at
/// 12, 1.008 at 16, 1.0035 at 24, 1.0019 at 32 — `1 + 2/q²` for large `q`
/// (`tests/bsdf/horizon.rs`). `Q = 16` keeps the excess below 1 % at every angle: under the
/// rule the furnace is 0.996–1.009 from 0° to 89° for σ = 2–100 µm, on a conductor and on glass
/// (`cargo run --release -p gmueller-validation --bin furnace`; `docs/renderer.md`). The width
/// grows toward the horizon, which sharpens grazing reflections toward the plane-wave limit
/// (the exact answer for an incoherent source) instead of blurring them; the root of the sum
/// of squares keeps it smooth in θ (a kinked `max` made the estimate 2–4 % low where the rule
/// takes over). [`super::Bsdf::surface_width`] applies the rule on both sides of an interface
/// (the Snell partner's lobe must fit its own horizon). The widening stops where the lobe would
/// be narrower than `32 ε` in the projected disk (`f32`: beyond about 89.5°).
///
/// # Examples
/// ```
/// use gmueller::bsdf::SurfaceCoherence;
/// use gmueller::interaction::coherence::surface_inverse_coherence;
/// use gmueller::frame::Frame;
/// use gmueller::packet::Channel;
/// use gmueller::stokes::Stokes;
/// use nalgebra::Vector3;
/// let c = SurfaceCoherence::new(2.0_f64)?;
/// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
/// let to_source = Vector3::new(-0.5, 0.3, 0.81).normalize();
/// let p = c.packet(Stokes::unpolarized(1.0)?, to_source, &surface, 0.5)?;
/// // On the surface the coherence is isotropic: Ξ = I/σ(θ)², where the rule gives
/// // σ(θ) = √(σ² + (16/(k cos²θ))²) = 2.80 µm at cos θ = 0.81, λ = 0.5 µm.
/// let k = 2.0 * std::f64::consts::PI / 0.5;
/// let w = (4.0 + (16.0 / (k * to_source.z.powi(2))).powi(2)).sqrt();
/// assert!((w - c.width_at(to_source.z, k)).abs() < 1e-12);
/// let xi = surface_inverse_coherence(&p, Channel::Half, &surface).unwrap();
/// assert!((xi.covariance() - nalgebra::Matrix2::identity() / (w * w)).norm() < 1e-12);
/// // Near the horizon the rule widens it: at 85°, 16/(k cos²θ) ≈ 167 µm.
/// let w = c.width_at(85_f64.to_radians().cos(), k);
/// let rule = 16.0 / (k * 85_f64.to_radians().cos().powi(2));
/// assert!((w - rule.hypot(2.0)).abs() < 1e-9 * w && w > 166.0);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceCoherence<T: Real> {
    width: T,
    horizon_rule: bool,
}

/// `Q` of the horizon rule ([`SurfaceCoherence`]).
pub const HORIZON_RULE_Q: f64 = 16.0;

impl<T: Real> SurfaceCoherence<T> {
    /// Coherence of width `σ` on the surface, widened near the horizon by the horizon rule.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `σ` is finite and positive with `1/σ²` and `σ²` normal
    /// numbers.
    pub fn new(width: T) -> Result<Self, Error> {
        let w2 = width * width;
        let ok = |x: T| x.is_finite() && x >= T::MIN_POSITIVE;
        if !(width > T::zero() && ok(w2) && ok(w2.recip())) {
            return Err(Error::OutOfRange {
                what: "surface coherence width",
                value: width.to_f64(),
                expected: "finite and > 0, with σ² and 1/σ² normal numbers",
            });
        }
        Ok(Self {
            width,
            horizon_rule: true,
        })
    }

    /// Coherence of width exactly `σ` on the surface from every direction (no horizon rule:
    /// near the horizon the backward estimate then exceeds the truth by `≈ 2/(kσ cos²θ)²`).
    ///
    /// # Errors
    /// As [`SurfaceCoherence::new`].
    pub fn fixed(width: T) -> Result<Self, Error> {
        Ok(Self {
            horizon_rule: false,
            ..Self::new(width)?
        })
    }

    /// The width `σ` (before the horizon rule).
    #[must_use]
    pub fn width(&self) -> T {
        self.width
    }

    /// The width for light arriving at `cos θ` in a medium of wavenumber `k`: the horizon
    /// rule's `√(σ² + (Q/(k cos²θ))²)` (type docs), or `σ` for [`SurfaceCoherence::fixed`]. Capped
    /// where its square would leave the normal numbers of `T` (only within ~10⁻⁹ rad of the
    /// horizon in `f32`).
    #[must_use]
    pub fn width_at(&self, cos_theta: T, k: T) -> T {
        self.combined(&[(cos_theta, k)])
    }

    /// `σ` combined with the horizon rule's width `Q/(k cos²θ)` of every `(cos θ, k)` in
    /// `sides` by the root of the sum of squares (`σ` alone for [`SurfaceCoherence::fixed`]).
    /// The rule's widening stops where the lobe would be narrower than `32 ε` in the projected
    /// disk of a side (`1/(k σ) ≥ 32 ε`, so that samplers can still resolve it: in `f32` beyond
    /// about 89.5°, never in `f64` within 89.99999°).
    pub(crate) fn combined(&self, sides: &[(T, T)]) -> T {
        if !self.horizon_rule {
            return self.width;
        }
        // The root of the sum of squares in f64 (`hypot` costs several times more; squares
        // of f32 values, or of f64 values up to 1e150, cannot overflow there; a larger f64
        // width gives +∞, and the cap below then keeps the width itself).
        let mut w2 = self.width.to_f64().powi(2);
        let mut k_max = T::zero();
        for &(cos_theta, k) in sides {
            w2 += (HORIZON_RULE_Q / (k * cos_theta * cos_theta).to_f64()).powi(2);
            k_max = k_max.max(k);
        }
        let w = T::lit(w2.sqrt());
        let cap = (T::lit(32.0) * T::EPSILON * k_max)
            .recip()
            .min(T::MAX.sqrt() * T::lit(1e-3));
        if w.is_finite() && w < cap {
            w
        } else {
            cap.max(self.width)
        }
    }

    /// `Ξ = I/σ²`, the inverse coherence on the surface of the width before the horizon rule
    /// (rad²/length², the covariance of the specular lobe in `h_t`).
    #[must_use]
    pub fn inverse_coherence(&self) -> Matrix2<T> {
        Matrix2::identity() * (self.width * self.width).recip()
    }

    /// `Ξ = I/σ(θ)²` for light arriving at `cos θ` in a medium of wavenumber `k`
    /// ([`SurfaceCoherence::width_at`]).
    #[must_use]
    pub fn inverse_coherence_at(&self, cos_theta: T, k: T) -> Matrix2<T> {
        let w = self.width_at(cos_theta, k);
        Matrix2::identity() * (w * w).recip()
    }

    /// The packet carrying `stokes` (in the incident s/p frame) from `to_source` (ŝ, toward the
    /// source; need not be unit) onto `surface` (either side), with this coherence on the
    /// surface: `Θ⊥ = diag(σ², σ² cos²θ_i)` in `Frame::sp(−ŝ, n̂)`, n̂ the normal facing the
    /// source, `σ = σ(θ_i)` of the horizon rule; `wavelength` is the light's in the medium it
    /// travels in.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when ŝ lies in the plane of the surface (`cos θ_i = 0`, or so
    /// small that `σ² cos²θ_i` underflows); as [`Frame::sp`] and [`WavePacket::new`].
    pub fn packet(
        &self,
        stokes: Stokes<T>,
        to_source: Vector3<T>,
        surface: &Frame<T>,
        wavelength: T,
    ) -> Result<WavePacket<T>, Error> {
        let (frame, cos_i) = incident_frame(to_source, surface)?;
        let w = self.width_at(cos_i, T::two_pi() / wavelength);
        let w2 = w * w;
        let shape =
            CoherenceShape::new(Matrix2::new(w2, T::zero(), T::zero(), w2 * cos_i * cos_i))?;
        WavePacket::from_stokes(stokes, shape, frame, wavelength)
    }
}

/// The incident s/p frame `Frame::sp(−ŝ, n̂)` (n̂ facing the source) and `cos θ_i`.
#[expect(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "a NaN must fail the test too"
)]
fn incident_frame<T: Real>(
    to_source: Vector3<T>,
    surface: &Frame<T>,
) -> Result<(Frame<T>, T), Error> {
    crate::error::ensure_finite("direction to the source", to_source.iter().copied())?;
    let n = to_source.norm();
    if !(n > T::zero()) {
        return Err(Error::InvalidBasis {
            reason: "zero direction vector",
        });
    }
    let s = to_source / n;
    let facing = surface.facing(&s);
    let cos_i = s.dot(&facing.k());
    if !(cos_i > T::zero()) {
        return Err(Error::OutOfRange {
            what: "cos θ_i (source in the plane of the surface)",
            value: cos_i.to_f64(),
            expected: "> 0",
        });
    }
    Ok((Frame::sp(-s, facing.k())?, cos_i))
}

/// A sample of a distant, uniform disk source of solid angle `Ω` (sr; the sun: `6.8·10⁻⁵`)
/// seen along `to_source`: one packet along the source's centre with the whole disk's
/// coherence (van Cittert–Zernike, [`WavePacket::from_distant_disk_source`]:
/// `Θ⊥ = λ²/(π Ω) I`), its Stokes vector in the incident s/p frame of `surface`. `stokes` is
/// the source's irradiance across the beam (radiance × Ω for a uniform disk).
///
/// Trade-off: no variance from the source's extent (the lobe it lights is the Gaussian image
/// of the disk), at the price of the disk's profile (its image is a Gaussian of the same
/// second moment; at the lobe's 1/e² radius the disk's coherence differs by 4.9 %).
///
/// # Errors
/// As [`WavePacket::from_distant_disk_source`], and for a source in the plane of the surface.
pub fn distant_disk<T: Real>(
    stokes: Stokes<T>,
    solid_angle: T,
    to_source: Vector3<T>,
    surface: &Frame<T>,
    wavelength: T,
) -> Result<WavePacket<T>, Error> {
    let (frame, _) = incident_frame(to_source, surface)?;
    WavePacket::from_distant_disk_source(stokes, solid_angle, frame, wavelength)
}

/// A sample of a uniform area light of area `A` whose normal makes `cos θ_L` with the
/// direction to the shading point, at `distance`: a packet along `to_source` with the
/// coherence of the light's projected area seen from there, `Θ⊥ = λ² r²/(π A cos θ_L) I`
/// ([`WavePacket::from_area_source`]). For a light sampled by points, pass the area the sample
/// stands for (`A/N` for `N` stratified points): smaller areas carry wider coherence
/// (sharper reflections) and more variance.
///
/// # Errors
/// [`Error::OutOfRange`] unless `0 < cos θ_L ≤ 1`; as [`WavePacket::from_area_source`].
pub fn area_light<T: Real>(
    stokes: Stokes<T>,
    area: T,
    cos_light: T,
    distance: T,
    to_source: Vector3<T>,
    surface: &Frame<T>,
    wavelength: T,
) -> Result<WavePacket<T>, Error> {
    if !(cos_light > T::zero() && cos_light <= T::one()) {
        return Err(Error::OutOfRange {
            what: "cos θ_L of the area light",
            value: cos_light.to_f64(),
            expected: "(0, 1]",
        });
    }
    let (frame, _) = incident_frame(to_source, surface)?;
    WavePacket::from_area_source(stokes, area * cos_light, distance, frame, wavelength)
}
