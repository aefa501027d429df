//! The geometry of one interaction: directions, angles, `h`, and the s/p frames.

use nalgebra::{Vector2, Vector3};

use crate::error::Error;
use crate::frame::Frame;
use crate::packet::WavePacket;
use crate::real::Real;

/// The side of the interface the light leaves on. The geometry owns it, so that the pBSDFs,
/// the roughness attenuation, the sampler and the exitant packet read the side-dependent
/// quantities (the exit hemisphere, `h`, the phase factor, the specular direction) from
/// [`Geometry`] rather than assuming reflection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Side {
    /// Back into the medium of incidence: `r̂ · n̂ > 0`, `h = k (r̂ + ŝ)`.
    Reflection,
}

/// Everything about the directions of one interaction that the kernel and the pBSDFs need.
///
/// Built only by [`Geometry::new`] (or [`Geometry::for_packet`]), which validates every input;
/// the fields are read through accessors, so the invariants below cannot be bypassed.
///
/// The surface frame is a [`Frame`] whose k̂ is the surface normal n̂ and whose (x̂, ŷ) = (t̂₁, t̂₂)
/// span the tangent plane; light arrives from and leaves into the side n̂ points to.
///
/// # Formula
/// ```text
/// ŝ = −k̂_packet      (from the surface toward the source; crate docs, "Errata", item 4)
/// h = k (r̂ + ŝ),     h_t = (h·t̂₁, h·t̂₂)          (h_t = 0 at the specular direction)
/// cos θ_i = ŝ·n̂,     cos θ_o = r̂·n̂
/// ```
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
    /// `cos θ_o = r̂·n̂` (> 0).
    pub(crate) cos_o: T,
    /// The tangential part of `h = k(r̂ + ŝ)` in (t̂₁, t̂₂), rad/length.
    pub(crate) h_t: Vector2<T>,
    /// The incident beam's s/p frame ([`Frame::sp`] of the propagation direction −ŝ).
    pub(crate) incident_sp: Frame<T>,
    /// The exit beam's s/p frame ([`Frame::sp`] of r̂): the frame of the kernel's output.
    pub(crate) exit_sp: Frame<T>,
}

impl<T: Real> Geometry<T> {
    /// The geometry of light arriving from `to_source` (ŝ) and leaving along `exit` (r̂) at a
    /// surface with frame `surface` (k̂ = n̂), at wavenumber `k`. Both directions are normalised.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless `k` is finite, positive and not subnormal (a wavelength
    /// whose `2π/λ` is a normal number); [`Error::NonFinite`] or [`Error::InvalidBasis`] for
    /// zero or non-finite directions; [`Error::OutOfRange`] when either direction is not
    /// strictly above the surface (`cos θ ≤ 0`): the surface kernel describes reflection only.
    pub fn new(
        k: T,
        surface: &Frame<T>,
        to_source: Vector3<T>,
        exit: Vector3<T>,
    ) -> Result<Self, Error> {
        if !(k.is_finite() && k >= T::MIN_POSITIVE) {
            return Err(Error::OutOfRange {
                what: "wavenumber k",
                value: k.to_f64(),
                expected: "finite and ≥ the smallest normal number",
            });
        }
        let s = unit(to_source, "direction to the source")?;
        let r = unit(exit, "exit direction")?;
        let n = surface.k();
        let (cos_i, incident_sp) = incidence(&s, surface)?;
        let cos_o = r.dot(&n);
        if cos_o <= T::zero() {
            return Err(Error::OutOfRange {
                what: "cos θ_o (exit direction below the surface)",
                value: cos_o.to_f64(),
                expected: "> 0",
            });
        }
        let h = (r + s) * k;
        let h_t = Vector2::new(h.dot(&surface.x()), h.dot(&surface.y()));
        // r̂ is a unit vector, and so is n̂ (of a validated frame).
        let exit_sp = Frame::sp_unit(r, n);
        Ok(Self {
            k,
            surface: *surface,
            to_source: s,
            exit: r,
            cos_i,
            cos_o,
            h_t,
            incident_sp,
            exit_sp,
        })
    }

    /// The wavenumber `k = 2π/λ` (rad/length).
    #[inline]
    #[must_use]
    pub fn k(&self) -> T {
        self.k
    }

    /// The surface frame (t̂₁, t̂₂, n̂).
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

    /// `cos θ_o = r̂·n̂` (> 0).
    #[inline]
    #[must_use]
    pub fn cos_o(&self) -> T {
        self.cos_o
    }

    /// The tangential part of `h = k(r̂ + ŝ)` in (t̂₁, t̂₂), rad/length (0 at the specular
    /// direction).
    #[inline]
    #[must_use]
    pub fn h_t(&self) -> Vector2<T> {
        self.h_t
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

    /// The side of the interface the light leaves on (today always [`Side::Reflection`]).
    #[inline]
    #[must_use]
    pub fn side(&self) -> Side {
        Side::Reflection
    }

    /// The phase factor `v` of the interface: a height `z` changes the exit light's phase by
    /// `v z`.
    ///
    /// # Formula
    /// ```text
    /// reflection:  v = k (cos θ_i + cos θ_o)      (the normal part of h = k(r̂ + ŝ))
    /// ```
    /// It sets the Debye–Waller attenuation `exp(−(vσ)²)`
    /// ([`super::roughness_attenuation`]) and the phase-screen scattering `|r|² v²`.
    #[inline]
    #[must_use]
    pub fn phase_factor(&self) -> T {
        self.k * (self.cos_i + self.cos_o)
    }

    /// The s/p frame of the specular direction `r_spec = −ŝ + 2 cos θ_i n̂`
    /// ([`Frame::sp`] without re-normalising its inputs: ŝ and n̂ are unit, so `r_spec` is unit
    /// to rounding): the frame in which a mirror's Jones matrix leaves the light.
    #[inline]
    #[must_use]
    pub fn specular_sp(&self) -> Frame<T> {
        let n = self.surface.k();
        let r_spec = n * (self.cos_i + self.cos_i) - self.to_source;
        Frame::sp_unit(r_spec, n)
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

    /// `sin θ_o` (≥ 0).
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
    /// incidence and normal exitance, where the azimuth of r̂ itself is not.
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

/// `v/|v|`, rescaled by the largest component first: `|v|` itself over- or underflows for
/// components beyond ~1e±154 (f64) or ~1e±19 (f32), which rejected valid directions as zero.
pub(crate) fn unit<T: Real>(v: Vector3<T>, what: &'static str) -> Result<Vector3<T>, Error> {
    crate::error::ensure_finite(what, v.iter().copied())?;
    let m = v.amax();
    if m == T::zero() {
        return Err(Error::InvalidBasis {
            reason: "zero direction vector",
        });
    }
    let u = v / m;
    Ok(u / u.norm())
}
