//! What the batch lobe kernels write: the two lobes as Stokes radiances and the exit frames,
//! in structure-of-arrays form, and the check of their lengths (`Kernel::evaluate_batch`,
//! `evaluate_batch_spectral`).

use super::{DirectionsSoa, StokesSoa};
use crate::error::Error;
#[cfg(doc)]
use crate::frame::Frame;
#[cfg(doc)]
use crate::interaction::Geometry;
use crate::mueller::batch::MuellerSoa;

/// The two lobes of a batch: Stokes radiances in each direction's exit s/p frame
/// ([`Geometry::exit_sp`]), in the exit medium.
#[derive(Debug)]
pub struct LobesSoa<'a, T> {
    /// The coherent specular (direct) lobe, attenuation included.
    pub specular: StokesSoa<'a, T>,
    /// The scattered part, attenuation included.
    pub scattered: StokesSoa<'a, T>,
}

/// The two lobes of a batch of pairs as Mueller matrices ([`crate::interaction::Kernel::evaluate_pairs_mueller`]):
/// sixteen slices per lobe, row-major (`m[4 k + l]` holds `M_kl` of every pair), each matrix
/// acting on Stokes vectors in its pair's incident s/p frame and giving them in its exit s/p
/// frame ([`Geometry::exit_sp`]), per unit incident irradiance, in the exit medium.
#[derive(Debug)]
pub struct MuellerLobesSoa<'a, T> {
    /// The coherent specular (direct) lobe, attenuation included.
    pub specular: MuellerSoa<'a, T>,
    /// The scattered part, attenuation included.
    pub scattered: MuellerSoa<'a, T>,
}

/// The exit s/p frames of a batch, as the unit `ŝ` axis of each ([`Frame::x`] of
/// [`Geometry::exit_sp`]); the `p̂` axis is `ô × ŝ` with `ô` the unit exit direction.
#[derive(Debug)]
pub struct ExitFramesSoa<'a, T> {
    /// `x, y, z` components of `ŝ` (world coordinates).
    pub s: [&'a mut [T]; 3],
}

/// [`Error::OutOfRange`] unless every direction, lobe and frame slice is at least as long as
/// `exits.x`.
pub(crate) fn check_lengths<T>(
    exits: &DirectionsSoa<'_, T>,
    outs: &[LobesSoa<'_, T>],
    frames: Option<&ExitFramesSoa<'_, T>>,
) -> Result<(), Error> {
    let n = exits.len();
    let short = |len: usize| len < n;
    if short(exits.y.len())
        || short(exits.z.len())
        || outs.iter().any(|out| {
            out.specular.s.iter().any(|s| short(s.len()))
                || out.scattered.s.iter().any(|s| short(s.len()))
        })
        || frames.is_some_and(|f| f.s.iter().any(|s| short(s.len())))
    {
        return Err(Error::OutOfRange {
            what: "batch slice length",
            value: n as f64,
            expected: "every direction, lobe and frame slice at least as long as exits.x",
        });
    }
    Ok(())
}
