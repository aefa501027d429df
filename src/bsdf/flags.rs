//! Which lobes a BSDF has, as flags (the shape of pbrt's `BxDFFlags` and Mitsuba's
//! `BSDFFlags`).

use core::ops::BitOr;

/// A set of lobe kinds ([`crate::bsdf::Bsdf::flags`]).
///
/// # Examples
/// ```
/// use gmueller::bsdf::LobeFlags;
/// let f = LobeFlags::REFLECTION | LobeFlags::DELTA;
/// assert!(f.contains(LobeFlags::DELTA) && !f.contains(LobeFlags::TRANSMISSION));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct LobeFlags(u8);

impl LobeFlags {
    /// No lobe.
    pub const NONE: Self = Self(0);
    /// Light leaves on the side it arrived from.
    pub const REFLECTION: Self = Self(1);
    /// Light crosses the interface.
    pub const TRANSMISSION: Self = Self(2);
    /// A coherent specular lobe of finite width (the mirror or Snell lobe widened by the
    /// coherence): evaluated by `eval`, drawn by the samplers.
    pub const COHERENT_SPECULAR: Self = Self(4);
    /// A scattered part of finite width (the PSD's lobes, blurred grating orders).
    pub const SCATTERED: Self = Self(8);
    /// A Dirac delta (the specular lobe, or grating orders, of a plane wave): not in `eval`,
    /// drawn only by the samplers with its probability and throughput.
    pub const DELTA: Self = Self(16);

    /// `true` when every flag of `other` is set.
    #[must_use]
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// `true` when any flag of `other` is set.
    #[must_use]
    pub const fn intersects(self, other: Self) -> bool {
        self.0 & other.0 != 0
    }

    /// The raw bits.
    #[must_use]
    pub const fn bits(self) -> u8 {
        self.0
    }
}

impl BitOr for LobeFlags {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}
