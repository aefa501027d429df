//! What the polarization levels return per exit direction: the kernel's Stokes radiances
//! ([`Response`], [`IntensityResponse`], [`LevelResponse`]) and its BSDF form, the same
//! interaction as a Mueller matrix (or, at the intensity level, a scalar) per unit incident
//! irradiance ([`MuellerResponse`], [`Throughput`]).

use core::fmt::Debug;

use nalgebra::Matrix4;

use super::super::geometry::Side;
use crate::mueller::Mueller;
use crate::real::Real;
use crate::stokes::Stokes;

#[cfg(doc)]
use super::{Full, Intensity, OneShape};
#[cfg(doc)]
use crate::interaction::Geometry;

/// What a kernel returns for one exit direction, at any level: the intensities, and the
/// Stokes vectors where the level computes them.
pub trait KernelOutput<T: Real>: Copy + Debug + PartialEq {
    /// `S0` of the coherent specular (direct) lobe, attenuation included.
    #[must_use]
    fn specular_intensity(&self) -> T;
    /// `S0` of the scattered part, attenuation included.
    #[must_use]
    fn scattered_intensity(&self) -> T;
    /// The roughness (Debye–Waller) attenuation `α` applied to both parts.
    #[must_use]
    fn attenuation(&self) -> T;
    /// The side the light left on: reflection or transmission ([`Geometry::side`]).
    #[must_use]
    fn side(&self) -> Side;
    /// `(specular, scattered)` Stokes radiances in the exit s/p frame; `None` at the
    /// [`Intensity`] level, which does not compute them (it is not "unpolarized").
    #[must_use]
    fn stokes(&self) -> Option<(Stokes<T>, Stokes<T>)>;
    /// `specular + scattered` intensity.
    #[inline]
    #[must_use]
    fn total_intensity(&self) -> T {
        self.specular_intensity() + self.scattered_intensity()
    }
    /// The output as a [`LevelResponse`] (so that one type holds the output of any level).
    #[must_use]
    fn into_level_response(self) -> LevelResponse<T>;
    /// Every radiance multiplied by `factor` (the attenuation unchanged), e.g. `1/pdf`.
    #[must_use]
    fn scaled(&self, factor: T) -> Self;
    /// The coherent specular lobe multiplied by `factor`, the scattered part unchanged (the
    /// renderer layer's normalisation of the lobe near the horizon, `crate::bsdf`).
    #[must_use]
    fn specular_scaled(&self, factor: T) -> Self;
}

/// What a kernel of a run-time [`crate::interaction::Level`] returns: the level's own output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LevelResponse<T: Real> {
    /// From the [`Intensity`] level.
    Intensity(IntensityResponse<T>),
    /// From the [`OneShape`] or [`Full`] level.
    Stokes(Response<T>),
}

impl<T: Real> KernelOutput<T> for LevelResponse<T> {
    #[inline]
    fn specular_intensity(&self) -> T {
        match self {
            Self::Intensity(r) => r.specular,
            Self::Stokes(r) => r.specular.s0(),
        }
    }
    #[inline]
    fn scattered_intensity(&self) -> T {
        match self {
            Self::Intensity(r) => r.scattered,
            Self::Stokes(r) => r.scattered.s0(),
        }
    }
    #[inline]
    fn attenuation(&self) -> T {
        match self {
            Self::Intensity(r) => r.attenuation,
            Self::Stokes(r) => r.attenuation,
        }
    }
    #[inline]
    fn side(&self) -> Side {
        match self {
            Self::Intensity(r) => r.side,
            Self::Stokes(r) => r.side,
        }
    }
    #[inline]
    fn stokes(&self) -> Option<(Stokes<T>, Stokes<T>)> {
        match self {
            Self::Intensity(_) => None,
            Self::Stokes(r) => Some((r.specular, r.scattered)),
        }
    }
    #[inline]
    fn into_level_response(self) -> LevelResponse<T> {
        self
    }
    #[inline]
    fn scaled(&self, factor: T) -> Self {
        match self {
            Self::Intensity(r) => Self::Intensity(r.scaled(factor)),
            Self::Stokes(r) => Self::Stokes(r.scaled(factor)),
        }
    }
    #[inline]
    fn specular_scaled(&self, factor: T) -> Self {
        match self {
            Self::Intensity(r) => Self::Intensity(r.specular_scaled(factor)),
            Self::Stokes(r) => Self::Stokes(r.specular_scaled(factor)),
        }
    }
}

/// The [`OneShape`] and [`Full`] levels' answer for one exit direction: Stokes radiances in the
/// exit s/p frame ([`Geometry::exit_sp`]), in the exit medium.
///
/// The four lobes of an interface are told apart by the side and the part: reflected or
/// transmitted ([`Response::side`]), coherent specular (the mirror or Snell lobe, widened by the
/// coherence) or scattered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Response<T: Real> {
    /// The coherent specular (direct) lobe, attenuation included.
    pub specular: Stokes<T>,
    /// The scattered (diffuse) part, attenuation included.
    pub scattered: Stokes<T>,
    /// The roughness (Debye–Waller) attenuation `α` applied to both parts.
    pub attenuation: T,
    /// The side the light left on (the geometry's [`Geometry::side`]).
    pub side: Side,
}

impl<T: Real> Response<T> {
    /// `specular + scattered`.
    #[must_use]
    pub fn total(&self) -> Stokes<T> {
        Stokes(self.specular.0 + self.scattered.0)
    }
}

impl<T: Real> KernelOutput<T> for Response<T> {
    #[inline]
    fn specular_intensity(&self) -> T {
        self.specular.s0()
    }
    #[inline]
    fn scattered_intensity(&self) -> T {
        self.scattered.s0()
    }
    #[inline]
    fn attenuation(&self) -> T {
        self.attenuation
    }
    #[inline]
    fn side(&self) -> Side {
        self.side
    }
    #[inline]
    fn stokes(&self) -> Option<(Stokes<T>, Stokes<T>)> {
        Some((self.specular, self.scattered))
    }
    #[inline]
    fn into_level_response(self) -> LevelResponse<T> {
        LevelResponse::Stokes(self)
    }
    /// Each lobe times `factor`, a result whose `S0` falls into the subnormal range moved back
    /// into the cone (`prepared::subnormal_onto_cone`: the entries round on their own there).
    #[inline]
    fn scaled(&self, factor: T) -> Self {
        let scale = |s: &Stokes<T>| {
            Stokes(crate::interaction::prepared::subnormal_onto_cone(
                s.0 * factor,
            ))
        };
        Self {
            specular: scale(&self.specular),
            scattered: scale(&self.scattered),
            attenuation: self.attenuation,
            side: self.side,
        }
    }
    #[inline]
    fn specular_scaled(&self, factor: T) -> Self {
        Self {
            specular: Stokes(crate::interaction::prepared::subnormal_onto_cone(
                self.specular.0 * factor,
            )),
            ..*self
        }
    }
}

/// The [`Intensity`] level's answer for one exit direction: radiances `L₀` only (in the exit
/// medium).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntensityResponse<T: Real> {
    /// `L₀` of the coherent specular (direct) lobe, attenuation included.
    pub specular: T,
    /// `L₀` of the scattered (diffuse) part, attenuation included.
    pub scattered: T,
    /// The roughness (Debye–Waller) attenuation `α` applied to both parts.
    pub attenuation: T,
    /// The side the light left on (the geometry's [`Geometry::side`]).
    pub side: Side,
}

impl<T: Real> IntensityResponse<T> {
    /// `specular + scattered`.
    #[must_use]
    pub fn total(&self) -> T {
        self.specular + self.scattered
    }
}

impl<T: Real> KernelOutput<T> for IntensityResponse<T> {
    #[inline]
    fn specular_intensity(&self) -> T {
        self.specular
    }
    #[inline]
    fn scattered_intensity(&self) -> T {
        self.scattered
    }
    #[inline]
    fn attenuation(&self) -> T {
        self.attenuation
    }
    #[inline]
    fn side(&self) -> Side {
        self.side
    }
    #[inline]
    fn stokes(&self) -> Option<(Stokes<T>, Stokes<T>)> {
        None
    }
    #[inline]
    fn into_level_response(self) -> LevelResponse<T> {
        LevelResponse::Intensity(self)
    }
    #[inline]
    fn scaled(&self, factor: T) -> Self {
        Self {
            specular: self.specular * factor,
            scattered: self.scattered * factor,
            attenuation: self.attenuation,
            side: self.side,
        }
    }
    #[inline]
    fn specular_scaled(&self, factor: T) -> Self {
        Self {
            specular: self.specular * factor,
            ..*self
        }
    }
}

pub(crate) mod sealed {
    pub trait Sealed {}
}

/// One lobe of the kernel in BSDF form, and the light it acts on: a [`Mueller`] matrix acting
/// on a [`Stokes`] vector at the Stokes levels ([`OneShape`], [`Full`]), a scalar acting on an
/// intensity `S0` at the [`Intensity`] level (the kernel's `M₀₀` part: the intensity level does
/// not compute polarization, so its scalar is not the throughput of unpolarized light through
/// a polarizing surface but the level's own answer).
///
/// A renderer generic over the polarization level keeps its path throughput as a
/// `Throughput`, composes with [`Throughput::then`] (light meets `self` first, so a camera
/// path is built as `vertex.then(&path)`) and re-expresses between frames with
/// [`Throughput::frame_change`] (the identity for scalars).
pub trait Throughput<T: Real>: Copy + Debug + PartialEq + sealed::Sealed {
    /// The light a throughput acts on: a [`Stokes`] vector, or an intensity `S0`.
    type Light: Copy + Debug + PartialEq;

    /// The zero throughput: no light passes.
    #[must_use]
    fn zero() -> Self;
    /// The identity: all light passes unchanged.
    #[must_use]
    fn identity() -> Self;
    /// `M₀₀`, the intensity throughput of unpolarized light.
    #[must_use]
    fn m00(&self) -> T;
    /// The throughput applied to `light`.
    #[must_use]
    fn apply(&self, light: &Self::Light) -> Self::Light;
    /// `next · self`: the light meets `self` first, then `next`.
    #[must_use]
    fn then(&self, next: &Self) -> Self;
    /// `self + other`.
    #[must_use]
    fn plus(&self, other: &Self) -> Self;
    /// `factor · self`.
    #[must_use]
    fn scaled(&self, factor: T) -> Self;
    /// `self` under the rule for small entries of every throughput the kernel's BSDF form and
    /// [`crate::bsdf`] return: 0 when every entry is below the smallest normal number
    /// (`MIN_POSITIVE`); the entries below it set to 0 when the largest entry is at least
    /// `MIN_POSITIVE/ε` (f32: 9.9e-32, f64: 1.0e-292; the change is below `11 ε` of the
    /// largest entry, within the rounding of `M S`); unchanged in between, where a subnormal
    /// entry may carry the polarization of its row and is exact to `ε MIN_POSITIVE/2`. So a
    /// subnormal entry occurs only beside a largest entry in `[MIN_POSITIVE, MIN_POSITIVE/ε)`.
    #[must_use]
    fn flushed(&self) -> Self;
    /// `true` when every entry is finite.
    #[must_use]
    fn is_finite(&self) -> bool;
    /// The sixteen entries of the Mueller matrix in row-major order (`[4 k + l]` holds
    /// `M_kl`); for a scalar, `M₀₀` followed by fifteen zeros.
    #[must_use]
    fn entries(&self) -> [T; 16];
    /// The re-expression of light given in frame `from` in frame `to` (the same beam):
    /// [`crate::frame::frame_change_mueller`] for Mueller matrices, `1` for scalars.
    #[must_use]
    fn frame_change(from: &crate::frame::Frame<T>, to: &crate::frame::Frame<T>) -> Self;
    /// The intensity `S0` of a light.
    #[must_use]
    fn intensity(light: &Self::Light) -> T;
    /// The throughput of a Mueller matrix at this level: the matrix itself, or its `M₀₀`.
    #[must_use]
    fn from_mueller(m: &Mueller<T>) -> Self;
    /// The throughput as a Mueller matrix: the matrix itself, or `M₀₀` alone in the corner
    /// (the intensity level acts on `S0` and leaves the light unpolarized). The inverse of
    /// [`Throughput::from_mueller`] on this level's throughputs.
    #[must_use]
    fn to_mueller(&self) -> Mueller<T>;
    /// A light of this level from a Stokes vector: the vector itself, or its `S0`.
    #[must_use]
    fn light(s: &Stokes<T>) -> Self::Light;
    /// The Stokes vector of a light, `None` at the intensity level (which has none).
    #[must_use]
    fn light_stokes(light: &Self::Light) -> Option<Stokes<T>>;
}

impl<T: Real> sealed::Sealed for Mueller<T> {}
impl<T: Real> sealed::Sealed for T {}

impl<T: Real> Throughput<T> for Mueller<T> {
    type Light = Stokes<T>;
    #[inline]
    fn entries(&self) -> [T; 16] {
        core::array::from_fn(|i| self.0[(i / 4, i % 4)])
    }
    #[inline]
    fn zero() -> Self {
        Mueller(Matrix4::zeros())
    }
    #[inline]
    fn identity() -> Self {
        Mueller(Matrix4::identity())
    }
    #[inline]
    fn m00(&self) -> T {
        self.0[(0, 0)]
    }
    #[inline]
    fn apply(&self, light: &Stokes<T>) -> Stokes<T> {
        Stokes(self.0 * light.0)
    }
    #[inline]
    fn then(&self, next: &Self) -> Self {
        Mueller(next.0 * self.0)
    }
    #[inline]
    fn plus(&self, other: &Self) -> Self {
        Mueller(self.0 + other.0)
    }
    #[inline]
    fn scaled(&self, factor: T) -> Self {
        Mueller(self.0 * factor)
    }
    #[inline]
    fn flushed(&self) -> Self {
        Mueller(crate::interaction::flush_to_normal(self.0))
    }
    #[inline]
    fn is_finite(&self) -> bool {
        self.0.iter().all(|x| x.is_finite())
    }
    #[inline]
    fn frame_change(from: &crate::frame::Frame<T>, to: &crate::frame::Frame<T>) -> Self {
        crate::frame::frame_change_mueller(from, to)
    }
    #[inline]
    fn intensity(light: &Stokes<T>) -> T {
        light.s0()
    }
    #[inline]
    fn to_mueller(&self) -> Mueller<T> {
        *self
    }
    #[inline]
    fn from_mueller(m: &Mueller<T>) -> Self {
        *m
    }
    #[inline]
    fn light(s: &Stokes<T>) -> Stokes<T> {
        *s
    }
    #[inline]
    fn light_stokes(light: &Stokes<T>) -> Option<Stokes<T>> {
        Some(*light)
    }
}

impl<T: Real> Throughput<T> for T {
    type Light = T;
    #[inline]
    fn entries(&self) -> [T; 16] {
        let mut m = [T::zero(); 16];
        m[0] = *self;
        m
    }
    #[inline]
    fn zero() -> Self {
        T::zero()
    }
    #[inline]
    fn identity() -> Self {
        T::one()
    }
    #[inline]
    fn m00(&self) -> T {
        *self
    }
    #[inline]
    fn apply(&self, light: &T) -> T {
        *self * *light
    }
    #[inline]
    fn then(&self, next: &Self) -> Self {
        *next * *self
    }
    #[inline]
    fn plus(&self, other: &Self) -> Self {
        *self + *other
    }
    #[inline]
    fn scaled(&self, factor: T) -> Self {
        *self * factor
    }
    #[inline]
    fn flushed(&self) -> Self {
        // One entry: the first rule alone.
        if self.abs() < T::MIN_POSITIVE {
            T::zero()
        } else {
            *self
        }
    }
    #[inline]
    fn is_finite(&self) -> bool {
        nalgebra::ComplexField::is_finite(self)
    }
    #[inline]
    fn frame_change(_from: &crate::frame::Frame<T>, _to: &crate::frame::Frame<T>) -> Self {
        T::one()
    }
    #[inline]
    fn intensity(light: &T) -> T {
        *light
    }
    #[inline]
    fn to_mueller(&self) -> Mueller<T> {
        let mut m = nalgebra::Matrix4::zeros();
        m[(0, 0)] = *self;
        Mueller(m)
    }
    #[inline]
    fn from_mueller(m: &Mueller<T>) -> Self {
        m.0[(0, 0)]
    }
    #[inline]
    fn light(s: &Stokes<T>) -> T {
        s.s0()
    }
    #[inline]
    fn light_stokes(_light: &T) -> Option<Stokes<T>> {
        None
    }
}

/// The kernel in BSDF form for one exit direction: the coherent specular lobe and the
/// scattered part as throughputs ([`Throughput`]: Mueller matrices at the Stokes levels,
/// scalars at the [`Intensity`] level) **per unit incident irradiance across the beam**, for the
/// incident coherence of the packet it was evaluated for.
///
/// # Formula
/// ```text
/// L_o = M S,     M = (cos θ_o/λ_t²) α · M_pbsdf T Σ_α K_α P_α          (one matrix per lobe)
/// P_x = ½ [[1,1],[1,1]] ⊕ 0,   P_y = ½ [[1,−1],[−1,1]] ⊕ 0,   P_½ = 0 ⊕ I₂
/// M = f · cos θ_i,   f = L_o/(S0 cos θ_i)                                    (the BSDF)
/// ```
/// `S` is a Stokes vector in the **packet's frame** ([`crate::packet::WavePacket::frame`]) and
/// `M S` the Stokes radiance in the **exit s/p frame** ([`Geometry::exit_sp`]), in the exit
/// medium: `M` includes the rotation `T` from the packet frame to the incident s/p frame. It is
/// the kernel's response, divided by nothing: `apply(packet.stokes())` equals the kernel's
/// Stokes output (`tests/bsdf/eval.rs`). For one coherence shape (`Θ_x = Θ_y`, every packet of
/// the source helpers and of [`crate::interaction::exitant::exitant_packet`]) `Σ_α K_α P_α = K I`:
/// the matrix is `K` times the pBSDF's Mueller matrix. With distinct shapes the block
/// `[[K_x+K_y, K_x−K_y],[K_x−K_y, K_x+K_y]]/2 ⊕ K_½ I₂` is valid on the Stokes vectors those
/// shapes admit (`|μ|² ≤ √(|Θ_x||Θ_y|)/|Θ_½|`, [`crate::packet`]): `K_½` is capped at
/// `√(K_x K_y)/|μ|_max`, the Cauchy–Schwarz bound that the exact weights satisfy.
///
/// Radiometry: `M` is `f · cos θ_i` in Mitsuba's convention for the light direction ŝ (its
/// `BSDF::eval` returns `f · |cos θ|` of the sampled direction), so a backward tracer's
/// throughput update for a light direction drawn with pdf `p(ŝ)` is `M/p(ŝ)`.
///
/// Small entries follow [`Throughput::flushed`]: a value whose entries are all below the
/// smallest normal number of `T` is 0 (a matrix cannot carry the log-space scale of
/// [`crate::interaction::Kernel::evaluate`], which keeps a far tail of a bright packet: for that
/// use the Stokes form), and a subnormal entry beside a largest entry of at least
/// `MIN_POSITIVE/ε` is 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MuellerResponse<T: Real, M> {
    /// The coherent specular (direct) lobe, attenuation included.
    pub specular: M,
    /// The scattered (diffuse) part, attenuation included.
    pub scattered: M,
    /// The roughness (Debye–Waller) attenuation `α` applied to both parts.
    pub attenuation: T,
    /// The side the light leaves on.
    pub side: Side,
}

impl<T: Real, M: Throughput<T>> MuellerResponse<T, M> {
    /// `specular + scattered`, without subnormal entries ([`Throughput::flushed`]: the two
    /// lobes have none, but their sum can cancel into the subnormal range).
    #[must_use]
    pub fn total(&self) -> M {
        self.specular.plus(&self.scattered).flushed()
    }

    /// Both lobes multiplied by `factor` (the attenuation unchanged), e.g. `1/pdf`.
    #[must_use]
    pub fn scaled(&self, factor: T) -> Self {
        Self {
            specular: self.specular.scaled(factor),
            scattered: self.scattered.scaled(factor),
            attenuation: self.attenuation,
            side: self.side,
        }
    }

    /// The coherent specular lobe multiplied by `factor`, the scattered part unchanged.
    #[must_use]
    pub fn specular_scaled(&self, factor: T) -> Self {
        Self {
            specular: self.specular.scaled(factor),
            ..*self
        }
    }
}

impl<T: Real> MuellerResponse<T, Mueller<T>> {
    /// The Stokes radiances for the incident Stokes vector `s` (in the packet's frame): the
    /// kernel's [`Response`] for a packet with `s` and the coherence this was evaluated for,
    /// valid Stokes vectors (each product projected onto the cone where rounding left it
    /// outside, as the kernel's own).
    #[must_use]
    pub fn apply(&self, s: &Stokes<T>) -> Response<T> {
        let cone = |m: &Mueller<T>| Stokes(super::onto_cone(m.0 * s.0));
        Response {
            specular: cone(&self.specular),
            scattered: cone(&self.scattered),
            attenuation: self.attenuation,
            side: self.side,
        }
    }
}

impl<T: Real> MuellerResponse<T, T> {
    /// The radiances for the incident intensity `s0`: the kernel's [`IntensityResponse`].
    #[must_use]
    pub fn apply(&self, s0: T) -> IntensityResponse<T> {
        IntensityResponse {
            specular: self.specular * s0,
            scattered: self.scattered * s0,
            attenuation: self.attenuation,
            side: self.side,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector4;

    /// A response scaled into the subnormal range stays a valid Stokes vector: the f32 vector
    /// `(1, 0.998, 0.06, 0)` (valid) times `k δ` rounds entry by entry, e.g. to `(9, 9, 1, 0) δ`.
    #[test]
    fn a_response_scaled_to_subnormal_stays_valid() {
        let v = Vector4::new(1.0_f32, 0.998, 0.06, 0.0);
        assert!(v[1] * v[1] + v[2] * v[2] <= v[0] * v[0]);
        let r = Response {
            specular: Stokes(v),
            scattered: Stokes(v),
            attenuation: 1.0,
            side: Side::Reflection,
        };
        let d = f32::MIN_POSITIVE * f32::EPSILON;
        for k in 1..40 {
            let s = KernelOutput::scaled(&r, d * k as f32 * 1.02);
            for st in [s.specular.0, s.scattered.0] {
                // In units of δ (exact), where the squares do not underflow.
                let n = st / d;
                assert!(
                    n[0] >= 0.0 && n[1] * n[1] + n[2] * n[2] + n[3] * n[3] <= n[0] * n[0],
                    "{k}: {n:?} δ is not a valid Stokes vector"
                );
            }
        }
    }
}
