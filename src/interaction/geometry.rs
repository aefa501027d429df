//! The geometry of one interaction: directions, angles, the side of the interface the light
//! leaves on, `h`, the phase factor, and the s/p frames.

use nalgebra::{Unit, Vector2, Vector3};

use crate::error::Error;
use crate::frame::Frame;
use crate::numerics::unit_direction;
use crate::packet::WavePacket;
use crate::real::Real;

/// The side of the interface the light leaves on. The geometry owns it, so that the pBSDFs,
/// the roughness attenuation and the exitant packet read the side-dependent quantities (the
/// exit hemisphere, `h`, the phase factor, the specular direction, the exit medium) from
/// [`Geometry`] rather than assuming reflection.
///
/// With n̂ the normal on the side of the source and `η = n_t/n_i` the index of the medium
/// across the interface relative to the medium of incidence:
/// ```text
/// Reflection:    r̂·n̂ > 0,   h = k (ŝ + r̂),     v = h·n̂ = k (cos θ_i + cos θ_o)
/// Transmission:  r̂·n̂ < 0,   h = k (ŝ + η r̂),   v = h·n̂ = k (cos θ_i − η cos θ_o)
/// ```
/// (`k` the wavenumber in the medium of incidence, so `η k` is the one in the exit medium).
/// SCATMECH's `Roughness_BRDF_Model` names the four cases of an interface between an ambient
/// medium (above) and a substrate: DOWNUP and UPDOWN are reflections, DOWNDOWN and UPUP
/// transmissions ([`Geometry::incident_from_below`] tells DOWN from UP).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Side {
    /// Back into the medium of incidence: `r̂ · n̂ > 0`, `h = k (ŝ + r̂)`.
    Reflection,
    /// Into the medium across the interface: `r̂ · n̂ < 0`, `h = k (ŝ + η r̂)`.
    Transmission,
}

/// Everything about the directions of one interaction that the kernel and the pBSDFs need.
///
/// Built only by [`Geometry::new`] (or [`Geometry::for_packet`]), which validates every input;
/// the fields are read through accessors, so the invariants below cannot be bypassed.
///
/// The surface frame is a [`Frame`] whose k̂ is the surface normal n̂ and whose (x̂, ŷ) = (t̂₁, t̂₂)
/// span the tangent plane. The geometry keeps it **oriented toward the source** (n̂·ŝ > 0): an
/// opaque surface ([`Geometry::new`]) is lit from the side n̂ points to; at an interface between
/// two media ([`Geometry::at_interface`]) light may come from either side, and the frame the
/// caller gives is reversed (`Frame::reversed`: t̂₂ and n̂ negated) when it comes from below.
/// Every angle, `h_t`, the azimuth and the s/p frames refer to that oriented frame
/// ([`Geometry::surface`]).
///
/// # Formula
/// ```text
/// ŝ = −k̂_packet      (from the surface toward the source; crate docs, "Errata", item 4)
/// h = k (ŝ + η r̂),   h_t = (h·t̂₁, h·t̂₂)          (η = 1 in reflection; h_t = 0 at the
///                                                  specular or Snell direction)
/// cos θ_i = ŝ·n̂,     cos θ_o = |r̂·n̂|             (θ_o measured from the normal of the exit side)
/// ```
/// `k` is the wavenumber in the medium of incidence and `η = n_t/n_i` the relative index of the
/// exit medium in transmission ([`Geometry::relative_index`]); the tangential part of `h` is
/// the phase matching of SCATMECH's `Bragg_Frequency`, `k (η sin θ_o (cos φ, sin φ) − sin θ_i (1, 0))`
/// in the plane-of-incidence coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry<T: Real> {
    /// Wavenumber `k = 2π/λ`.
    pub(crate) k: T,
    /// The surface frame (t̂₁, t̂₂, n̂).
    pub(crate) surface: Frame<T>,
    /// ŝ: unit vector from the surface toward the source.
    pub(crate) to_source: Vector3<T>,
    /// r̂: the exit direction (unit).
    pub(crate) exit: Vector3<T>,
    /// `cos θ_i = ŝ·n̂` (> 0).
    pub(crate) cos_i: T,
    /// `cos θ_o = |r̂·n̂|` (> 0).
    pub(crate) cos_o: T,
    /// The tangential part of `h = k(ŝ + η r̂)` in (t̂₁, t̂₂), rad/length.
    pub(crate) h_t: Vector2<T>,
    /// The incident beam's s/p frame ([`Frame::sp`] of the propagation direction −ŝ).
    pub(crate) incident_sp: Frame<T>,
    /// The exit beam's s/p frame ([`Frame::sp`] of r̂): the frame of the kernel's output.
    pub(crate) exit_sp: Frame<T>,
    /// Reflection or transmission.
    pub(crate) side: Side,
    /// `η = n_t/n_i` in transmission, 1 in reflection.
    pub(crate) eta: T,
    /// `ln η²` (0 in reflection): the radiance factor of the exit medium, in log form.
    pub(crate) ln_eta_sq: T,
    /// The caller's surface frame was reversed because the source is below it.
    pub(crate) from_below: bool,
}

impl<T: Real> Geometry<T> {
    /// The geometry of light arriving from `to_source` (ŝ) and leaving along `exit` (r̂) at an
    /// opaque surface with frame `surface` (k̂ = n̂), at wavenumber `k`: reflection on the side n̂
    /// points to. Both directions are normalised.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `k` is finite, positive and not subnormal (a wavelength
    /// whose `2π/λ` is a normal number); [`Error::NonFinite`] or [`Error::InvalidBasis`] for
    /// zero or non-finite directions; [`Error::OutOfRange`] when either direction is not
    /// strictly above the surface (`cos θ ≤ 0`): an opaque surface reflects only (for an
    /// interface between two media, see [`Geometry::at_interface`]).
    pub fn new(
        k: T,
        surface: &Frame<T>,
        to_source: Vector3<T>,
        exit: Vector3<T>,
    ) -> Result<Self, Error> {
        check_wavenumber(k)?;
        let s = unit_direction(&to_source, "direction to the source")?;
        let r = unit_direction(&exit, "exit direction")?;
        Self::opaque_units(k, surface, &s, &r)
    }

    /// [`Geometry::new`] of unit directions (the crate's internal paths, which have
    /// normalised them already).
    ///
    /// # Errors
    /// As [`Geometry::new`] for `k` and the signs of `cos θ`.
    pub(crate) fn opaque_units(
        k: T,
        surface: &Frame<T>,
        s: &Unit<Vector3<T>>,
        r: &Unit<Vector3<T>>,
    ) -> Result<Self, Error> {
        check_wavenumber(k)?;
        let s = s.into_inner();
        let (cos_i, incident_sp) = incidence(&s, surface)?;
        let inc = Incidence {
            to_source: s,
            surface: *surface,
            cos_i,
            incident_sp,
            from_below: false,
        };
        Self::leaving(k, &inc, None, r)
    }

    /// The geometry of the incident side `inc` (of unit ŝ, validated: [`Incidence::of`])
    /// leaving along the unit `r`: at an opaque surface (`eta = None`, as
    /// [`Geometry::opaque_units`]) or at an interface of relative index `eta` (as
    /// [`Geometry::interface_units`]). Both constructors end here, so a geometry built from an
    /// [`Incidence`] kept for many exits (the renderer layer's `Incident`) is theirs bit for
    /// bit.
    ///
    /// # Errors
    /// As [`Geometry::opaque_units`] or [`Geometry::interface_units`] for `k`, `η` and the exit.
    #[inline]
    pub(crate) fn leaving(
        k: T,
        inc: &Incidence<T>,
        eta: Option<T>,
        r: &Unit<Vector3<T>>,
    ) -> Result<Self, Error> {
        let r = r.into_inner();
        let rn = r.dot(&inc.surface.k());
        let (side, eta_t) = match eta {
            None => {
                check_wavenumber(k)?;
                if rn <= T::zero() {
                    return Err(Error::OutOfRange {
                        what: "cos θ_o (exit direction below the surface)",
                        value: rn.to_f64(),
                        expected: "> 0",
                    });
                }
                (Side::Reflection, T::one())
            }
            Some(eta) => {
                check_interface(k, eta)?;
                if rn > T::zero() {
                    (Side::Reflection, T::one())
                } else if rn < T::zero() {
                    let eta_t = if inc.from_below { eta.recip() } else { eta };
                    (Side::Transmission, eta_t)
                } else {
                    return Err(Error::OutOfRange {
                        what: "cos θ_o (exit direction in the plane of the surface)",
                        value: 0.0,
                        expected: "≠ 0",
                    });
                }
            }
        };
        Ok(Self::build(
            k,
            &inc.surface,
            (inc.to_source, r),
            (inc.cos_i, rn.abs()),
            inc.incident_sp,
            (side, eta_t),
            inc.from_below,
        ))
    }

    /// The geometry of light arriving from `to_source` (ŝ) and leaving along `exit` (r̂) at an
    /// interface between two media, at wavenumber `k` **in the medium of incidence**. `eta` is
    /// the relative index of the medium below the surface frame (the side n̂ points away from)
    /// to the medium above: `η = n_below/n_above` (1.5 for glass in air with n̂ pointing out of
    /// the glass). Both directions may lie on either side; the geometry orients the frame toward
    /// the source (see the type docs) and tells the side from the exit direction.
    ///
    /// # Formula
    /// ```text
    /// from above (ŝ·n̂ > 0):  frame as given,  η_t = η
    /// from below (ŝ·n̂ < 0):  frame reversed,  η_t = 1/η
    /// r̂ on the source side: Reflection;  otherwise Transmission with η_t = n_t/n_i
    /// ```
    /// In transmission the exit medium's wavenumber is `η_t k` and its wavelength `λ/η_t`
    /// ([`Geometry::relative_index`]).
    ///
    /// # Errors
    /// As [`Geometry::new`] for `k` and the directions; [`Error::OutOfRange`] unless `eta` is
    /// finite and positive with `η k` and `k/η` normal numbers, and when either direction lies in
    /// the plane of the surface (`ŝ·n̂ = 0` or `r̂·n̂ = 0`).
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Geometry, Side};
    /// use nalgebra::Vector3;
    ///
    /// // Glass below the plane z = 0, light from the air at 30°, leaving along Snell's direction.
    /// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
    /// let (n, sin_i) = (1.5_f64, 0.5_f64);
    /// let to_source = Vector3::new(-sin_i, 0.0, (1.0 - sin_i * sin_i).sqrt());
    /// let sin_t = sin_i / n;
    /// let exit = Vector3::new(sin_t, 0.0, -(1.0 - sin_t * sin_t).sqrt());
    /// let g = Geometry::at_interface(4.0 * std::f64::consts::PI, &surface, n, to_source, exit).unwrap();
    /// assert_eq!(g.side(), Side::Transmission);
    /// assert!(g.h_t().norm() < 1e-12); // phase matched: the Snell direction
    /// assert!((g.relative_index() - n).abs() < 1e-15);
    /// ```
    pub fn at_interface(
        k: T,
        surface: &Frame<T>,
        eta: T,
        to_source: Vector3<T>,
        exit: Vector3<T>,
    ) -> Result<Self, Error> {
        // The wavenumber and the index first (the errors' order), then the directions.
        check_interface(k, eta)?;
        let s = unit_direction(&to_source, "direction to the source")?;
        let r = unit_direction(&exit, "exit direction")?;
        Self::interface_units(k, surface, eta, &s, &r)
    }

    /// [`Geometry::at_interface`] of unit directions (the crate's internal paths, which have
    /// normalised them already).
    ///
    /// # Errors
    /// As [`Geometry::at_interface`] for `k`, `η` and directions in the plane of the surface.
    pub(crate) fn interface_units(
        k: T,
        surface: &Frame<T>,
        eta: T,
        s: &Unit<Vector3<T>>,
        r: &Unit<Vector3<T>>,
    ) -> Result<Self, Error> {
        check_interface(k, eta)?;
        let s = s.into_inner();
        if s.dot(&surface.k()) == T::zero() {
            return Err(Error::OutOfRange {
                what: "cos θ_i (source in the plane of the surface)",
                value: 0.0,
                expected: "≠ 0",
            });
        }
        Self::leaving(k, &Incidence::of(&s, surface)?, Some(eta), r)
    }

    /// The geometry from validated parts (unit directions, `cos θ > 0`, the oriented frame).
    fn build(
        k: T,
        surface: &Frame<T>,
        (s, r): (Vector3<T>, Vector3<T>),
        (cos_i, cos_o): (T, T),
        incident_sp: Frame<T>,
        (side, eta): (Side, T),
        from_below: bool,
    ) -> Self {
        let n = surface.k();
        let (h, ln_eta_sq) = match side {
            Side::Reflection => ((r + s) * k, T::zero()),
            Side::Transmission => ((s + r * eta) * k, (eta * eta).ln()),
        };
        let h_t = Vector2::new(h.dot(&surface.x()), h.dot(&surface.y()));
        // r̂ is a unit vector, and so is n̂ (of a validated frame).
        let exit_sp = Frame::sp_unit(r, n);
        Self {
            k,
            surface: *surface,
            to_source: s,
            exit: r,
            cos_i,
            cos_o,
            h_t,
            incident_sp,
            exit_sp,
            side,
            eta,
            ln_eta_sq,
            from_below,
        }
    }

    /// The wavenumber `k = 2π/λ` (rad/length).
    #[inline]
    #[must_use]
    pub fn k(&self) -> T {
        self.k
    }

    /// The surface frame (t̂₁, t̂₂, n̂), oriented toward the source (reversed from the caller's
    /// when the light comes from below, [`Geometry::incident_from_below`]).
    #[inline]
    #[must_use]
    pub fn surface(&self) -> &Frame<T> {
        &self.surface
    }

    /// ŝ: the unit vector from the surface toward the source.
    #[inline]
    #[must_use]
    pub fn to_source(&self) -> Vector3<T> {
        self.to_source
    }

    /// r̂: the unit exit direction.
    #[inline]
    #[must_use]
    pub fn exit(&self) -> Vector3<T> {
        self.exit
    }

    /// `cos θ_i = ŝ·n̂` (> 0).
    #[inline]
    #[must_use]
    pub fn cos_i(&self) -> T {
        self.cos_i
    }

    /// `cos θ_o = |r̂·n̂|` (> 0), the exit angle from the normal of the exit side.
    #[inline]
    #[must_use]
    pub fn cos_o(&self) -> T {
        self.cos_o
    }

    /// The tangential part of `h = k(ŝ + η r̂)` in (t̂₁, t̂₂), rad/length (0 at the specular
    /// direction, and at Snell's direction in transmission).
    #[inline]
    #[must_use]
    pub fn h_t(&self) -> Vector2<T> {
        self.h_t
    }

    /// `h_t` in the caller's surface frame, where a height PSD is given: `(h₁, −h₂)` when the
    /// light comes from below (the oriented frame has t̂₂ negated), `h_t` otherwise.
    #[inline]
    #[must_use]
    pub(crate) fn psd_h(&self) -> Vector2<T> {
        if self.from_below {
            Vector2::new(self.h_t.x, -self.h_t.y)
        } else {
            self.h_t
        }
    }

    /// The incident beam's s/p frame ([`Frame::sp`] of the propagation direction −ŝ).
    #[inline]
    #[must_use]
    pub fn incident_sp(&self) -> &Frame<T> {
        &self.incident_sp
    }

    /// The exit beam's s/p frame ([`Frame::sp`] of r̂): the frame of the kernel's output.
    #[inline]
    #[must_use]
    pub fn exit_sp(&self) -> &Frame<T> {
        &self.exit_sp
    }

    /// The side of the interface the light leaves on.
    #[inline]
    #[must_use]
    pub fn side(&self) -> Side {
        self.side
    }

    /// `η = n_t/n_i`, the index of the exit medium relative to the medium of incidence: the
    /// interface's relative index (or its inverse from below) in transmission, 1 in reflection.
    #[inline]
    #[must_use]
    pub fn relative_index(&self) -> T {
        self.eta
    }

    /// The wavenumber in the exit medium, `η k`.
    #[inline]
    #[must_use]
    pub fn exit_wavenumber(&self) -> T {
        self.k * self.eta
    }

    /// `true` when the light arrives from below the surface frame the caller gave to
    /// [`Geometry::at_interface`] (SCATMECH's UPDOWN and UPUP), so that frame was reversed: a
    /// pBSDF of the interface then sees the relative index `1/η`.
    #[inline]
    #[must_use]
    pub fn incident_from_below(&self) -> bool {
        self.from_below
    }

    /// The phase factor `v` of the interface: a height `z` (along the oriented n̂) changes the
    /// exit light's phase by `v z`; `v = h·n̂`, the normal part of the scattering vector.
    ///
    /// # Formula
    /// ```text
    /// reflection:    v = k (cos θ_i + cos θ_o)
    /// transmission:  v = k (cos θ_i − η cos θ_o) = k₀ (n_i cos θ_i − n_t cos θ_t)
    /// ```
    /// Derivation (transmission): a plane wave of wavenumber `k` meets the interface raised by
    /// `z`; relative to the flat one, the incident wave travels `z cos θ_i` less in the medium
    /// of incidence (phase `−k cos θ_i z` at the surface), and the refracted wave travels
    /// `z cos θ_o` more in the exit medium before reaching the mean plane (phase
    /// `+η k cos θ_o z`): in all `−v z`. Only `v²` enters the results
    /// (`tests/interaction/transmission.rs` checks the phase against explicitly propagated plane
    /// waves). It sets the Debye–Waller attenuation `exp(−(vσ)²)`
    /// ([`super::roughness::roughness_attenuation`]) and the phase-screen scattering `τ v²`
    /// ([`super::pbsdf::PhaseScreen`]).
    #[inline]
    #[must_use]
    pub fn phase_factor(&self) -> T {
        match self.side {
            Side::Reflection => self.k * (self.cos_i + self.cos_o),
            Side::Transmission => self.k * (self.cos_i - self.eta * self.cos_o),
        }
    }

    /// The specular direction on this geometry's side: the mirror direction
    /// `−ŝ + 2 cos θ_i n̂` in reflection, Snell's direction in transmission, `None` under total
    /// internal reflection (`sin θ_i ≥ η`).
    ///
    /// # Formula
    /// ```text
    /// reflection:    r_spec = −ŝ + 2 cos θ_i n̂
    /// transmission:  r_spec = −ŝ/η + (cos θ_i/η − cos θ_t) n̂,   cos θ_t = √(1 − sin²θ_i/η²)
    /// ```
    #[must_use]
    pub fn specular_direction(&self) -> Option<Vector3<T>> {
        let n = self.surface.k();
        match self.side {
            Side::Reflection => Some(n * (self.cos_i + self.cos_i) - self.to_source),
            Side::Transmission => {
                let sin2_i = (T::one() - self.cos_i) * (T::one() + self.cos_i);
                let sin2_t = sin2_i / (self.eta * self.eta);
                if sin2_t >= T::one() {
                    return None;
                }
                let cos_t = ((T::one() - sin2_t).max(T::zero())).sqrt();
                Some(n * (self.cos_i / self.eta - cos_t) - self.to_source / self.eta)
            }
        }
    }

    /// The s/p frame of the specular direction ([`Geometry::specular_direction`]; in reflection
    /// [`Frame::sp`] without re-normalising its inputs: ŝ and n̂ are unit, so `r_spec` is unit to
    /// rounding): the frame in which a mirror's or a flat interface's Jones matrix leaves the
    /// light. Under total internal reflection (no transmitted beam) the frame of the direction
    /// along the surface in the plane of incidence.
    #[inline]
    #[must_use]
    pub fn specular_sp(&self) -> Frame<T> {
        let n = self.surface.k();
        if self.side == Side::Reflection {
            let r_spec = n * (self.cos_i + self.cos_i) - self.to_source;
            return Frame::sp_unit(r_spec, n);
        }
        match self.specular_direction() {
            Some(r_spec) => Frame::sp_unit(r_spec / r_spec.norm(), n),
            None => {
                let along = n * self.cos_i - self.to_source;
                Frame::sp_unit(along / along.norm(), n)
            }
        }
    }

    /// The wavelength `λ = 2π/k`.
    #[inline]
    #[must_use]
    pub fn wavelength(&self) -> T {
        T::two_pi() / self.k
    }

    /// `sin θ_i` (≥ 0).
    #[inline]
    #[must_use]
    pub fn sin_i(&self) -> T {
        (T::one() - self.cos_i * self.cos_i).max(T::zero()).sqrt()
    }

    /// `sin θ_o` (≥ 0), in the exit medium.
    #[inline]
    #[must_use]
    pub fn sin_o(&self) -> T {
        (T::one() - self.cos_o * self.cos_o).max(T::zero()).sqrt()
    }

    /// `(cos φ, sin φ)` of the exit azimuth φ measured from the forward half of the plane of
    /// incidence (φ = 0 at the specular direction), positive toward `n̂ × û`, where
    /// `û = n̂ × ŝ_in` is the forward tangent and `ŝ_in` the incident beam's s vector.
    ///
    /// Computed from the exit beam's s vector, `ŝ_out = (sin φ) û − (cos φ) v̂` with
    /// `v̂ = n̂ × û`, so it stays defined — and consistent with [`Geometry::exit_sp`] — at normal
    /// incidence and normal exitance, where the azimuth of r̂ itself is not. The same formula
    /// holds in transmission: a transmitted r̂ of azimuth φ has the s vector of the reflected r̂
    /// with the same tangential direction.
    #[must_use]
    pub fn exit_azimuth(&self) -> (T, T) {
        let n = self.surface.k();
        let u = n.cross(&self.incident_sp.x());
        let v = n.cross(&u);
        let s_out = self.exit_sp.x();
        (-s_out.dot(&v), s_out.dot(&u))
    }
}

impl<T: Real> Geometry<T> {
    /// The full scattering vector `h = k (ŝ + η r̂)` (rad/length; `η = 1` in reflection), whose
    /// tangential part is [`Geometry::h_t`] and normal part [`Geometry::phase_factor`].
    #[inline]
    #[must_use]
    pub fn scattering_vector(&self) -> Vector3<T> {
        (self.to_source + self.exit * self.eta) * self.k
    }

    /// The same directions at a facet of the surface whose normal is `normal` (unit, on the
    /// side of the source): the tangent plane of a rough surface, as
    /// [`super::pbsdf::TangentPlane`] uses it. The side, the relative index and whether the light
    /// came from below are kept; the angles, `h_t` and the s/p frames are those of the facet
    /// (the facet frame's tangents are [`Frame::from_normal`]'s). `None` unless the source is
    /// above the facet (`ŝ·m > 0`) and the exit direction is on the same side of the facet as
    /// of the surface (in front of it in reflection, behind it in transmission).
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::Geometry;
    /// use nalgebra::Vector3;
    /// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
    /// let g = Geometry::new(10.0_f64, &surface, Vector3::new(-0.5, 0.0, 0.866),
    ///     Vector3::new(0.2, 0.3, 0.93))?;
    /// // At the facet whose normal is the half vector, the exit is the mirror direction.
    /// let m = g.scattering_vector().normalize();
    /// let f = g.at_facet(m).unwrap();
    /// assert!(f.h_t().norm() < 1e-12 && (f.cos_i() - f.cos_o()).abs() < 1e-12);
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    #[must_use]
    pub fn at_facet(&self, normal: Vector3<T>) -> Option<Self> {
        let facet = Frame::from_normal(normal).ok()?;
        let m = facet.k();
        let cos_i = self.to_source.dot(&m);
        let rm = self.exit.dot(&m);
        let same_side = match self.side {
            Side::Reflection => rm > T::zero(),
            Side::Transmission => rm < T::zero(),
        };
        if !(cos_i > T::zero() && same_side) {
            return None;
        }
        // ŝ is unit and so is m.
        let incident_sp = Frame::sp_unit(-self.to_source, m);
        Some(Self::build(
            self.k,
            &facet,
            (self.to_source, self.exit),
            (cos_i, rm.abs()),
            incident_sp,
            (self.side, self.eta),
            self.from_below,
        ))
    }
}

impl<T: Real> Geometry<T> {
    /// The geometry of `packet` (its wavenumber, ŝ = −k̂) leaving along `exit`.
    ///
    /// # Errors
    /// As [`Geometry::new`].
    pub fn for_packet(
        packet: &WavePacket<T>,
        surface: &Frame<T>,
        exit: Vector3<T>,
    ) -> Result<Self, Error> {
        Self::new(packet.wavenumber(), surface, -packet.direction(), exit)
    }

    /// The geometry of `packet` (its wavenumber in the medium of incidence, ŝ = −k̂) leaving
    /// along `exit` at an interface of relative index `eta` ([`Geometry::at_interface`]).
    ///
    /// # Errors
    /// As [`Geometry::at_interface`].
    pub fn for_packet_at_interface(
        packet: &WavePacket<T>,
        surface: &Frame<T>,
        eta: T,
        exit: Vector3<T>,
    ) -> Result<Self, Error> {
        Self::at_interface(packet.wavenumber(), surface, eta, -packet.direction(), exit)
    }
}

/// `Ok` for a wavenumber that is finite, positive and normal.
fn check_wavenumber<T: Real>(k: T) -> Result<(), Error> {
    if k.is_finite() && k >= T::MIN_POSITIVE {
        Ok(())
    } else {
        Err(Error::OutOfRange {
            what: "wavenumber k",
            value: k.to_f64(),
            expected: "finite and ≥ the smallest normal number",
        })
    }
}

/// [`check_wavenumber`] and the relative index of an interface: finite and positive, with
/// `η k` and `k/η` normal numbers.
fn check_interface<T: Real>(k: T, eta: T) -> Result<(), Error> {
    check_wavenumber(k)?;
    let normal = |x: T| x.is_finite() && x >= T::MIN_POSITIVE;
    if normal(eta) && normal(eta * k) && normal(k / eta) {
        Ok(())
    } else {
        Err(Error::OutOfRange {
            what: "relative index η = n_below/n_above",
            value: eta.to_f64(),
            expected: "finite and > 0, with η k and k/η normal numbers",
        })
    }
}

/// The incident side of a geometry, which depends on ŝ and the surface frame alone: the frame
/// oriented toward the source, `cos θ_i` and the incident s/p frame. The renderer layer keeps
/// it with a prepared incident light and builds each exit's geometry from it
/// ([`Geometry::leaving`]) instead of again from ŝ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Incidence<T: Real> {
    to_source: Vector3<T>,
    surface: Frame<T>,
    cos_i: T,
    incident_sp: Frame<T>,
    from_below: bool,
}

impl<T: Real> Incidence<T> {
    /// The incident side of the unit `s` at the surface frame `surface` (of either side: the
    /// frame is reversed when `s` is below it, as [`Geometry::at_interface`] has it).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when `s` lies in the plane of the surface (`cos θ_i = 0`).
    pub(crate) fn of(s: &Vector3<T>, surface: &Frame<T>) -> Result<Self, Error> {
        let from_below = s.dot(&surface.k()) < T::zero();
        let oriented = if from_below {
            surface.reversed()
        } else {
            *surface
        };
        let (cos_i, incident_sp) = incidence(s, &oriented)?;
        Ok(Self {
            to_source: *s,
            surface: oriented,
            cos_i,
            incident_sp,
            from_below,
        })
    }
}

/// The incident side of every geometry for a unit ŝ: `cos θ_i = ŝ·n̂` and the incident beam's
/// s/p frame ([`Frame::sp`] of −ŝ); the kernel's per-packet work and the batch path build it
/// here too, so all of them agree bit for bit.
///
/// # Errors
/// [`Error::OutOfRange`] when `cos θ_i ≤ 0` (the source below the surface).
pub(crate) fn incidence<T: Real>(
    s: &Vector3<T>,
    surface: &Frame<T>,
) -> Result<(T, Frame<T>), Error> {
    let n = surface.k();
    let cos_i = s.dot(&n);
    if cos_i <= T::zero() {
        return Err(Error::OutOfRange {
            what: "cos θ_i (source below the surface)",
            value: cos_i.to_f64(),
            expected: "> 0",
        });
    }
    // ŝ is a unit vector, and so is n̂ (of a validated frame).
    Ok((cos_i, Frame::sp_unit(-*s, n)))
}
