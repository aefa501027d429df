//! A structure-of-arrays batch path for the plane-wave polarized kernel: one packet, many exit
//! directions, with explicit SIMD chosen at run time.
//!
//! [`plane_wave_rayleigh_rice`] evaluates what
//! `Kernel::<Full, PlaneWave>::evaluate(..).scattered` returns — the classical
//! Rayleigh–Rice Mueller BRDF applied to the packet's Stokes vector, with a Gaussian PSD — for
//! every direction of a [`DirectionsSoa`], writing the four Stokes parameters into a
//! [`StokesSoa`]. The per-packet work (incident s/p frame, the rotation `T`, `q_i`, the PSD's
//! Cholesky factor) is done once; the per-exit work runs 8 (`f64`) or 16 (`f32`) directions per
//! instruction under AVX-512, 4 or 8 under AVX2 + FMA, through [`pulp`] (run-time detection, no `unsafe`, no
//! `RUSTFLAGS`), with a vector exponential and a branch-free principal complex square root.
//! Lay a batch out with [`crate::mueller::batch::padded_stride`].
//!
//! [`Kernel::evaluate_batch`] is the batch form of the partially coherent kernel at every level
//! (both lobes and the exit frames, into [`LobesSoa`] and [`ExitFramesSoa`]), and
//! [`Kernel::evaluate_batch_spectral`] its form for several wavelengths of one path; at every
//! polarization level with `Partial` or `Incoherent` coherence, with a Gaussian or
//! Gaussian-mixture (≤ 8 components) PSD, on a [`super::RoughConductor`] (reflection) or a
//! [`super::RoughDielectric`] (reflection and transmission, lit from either side), they run the
//! same stages in lanes (`partial.rs`), elsewhere the per-direction kernel per exit.
//!
//! [`Kernel::evaluate_pairs`] is the form a wavefront renderer's lanes need: every lane its own
//! light direction, exit and coherence width ([`PairsSoa`]; the renderer's unpolarized light of
//! `SurfaceCoherence`), the same lobe stages with the incidence constants gathered per lane
//! (`per_lane.rs`, `pairs/`) on rough conductors and dielectrics in reflection at first order;
//! [`crate::bsdf::Bsdf::eval_stokes_pairs`] adds each light's coherent-lobe mass.

use nalgebra::Vector3;
use pulp::{Simd, WithSimd};

use super::geometry::Geometry;
use super::pbsdf::{ConstantMueller, RayleighRice};
use super::{Full, Kernel, PlaneWave, RoughSurface};
use crate::error::Error;
use crate::frame::Frame;
use crate::mueller::Mueller;
use crate::packet::WavePacket;
use crate::psd::GaussianPsd;
use crate::real::Real;
use crate::simd::driver::{self, LaneMap};
use crate::simd::{Soa, SoaMut};

mod lobes;
mod outputs;
mod pairs;
mod partial;
mod per_lane;
mod prep;
mod spectral;
mod stages;

pub use crate::mueller::batch::MuellerSoa;
pub(crate) use outputs::check_lengths;
pub use outputs::{ExitFramesSoa, LobesSoa, MuellerLobesSoa};
pub use pairs::PairsSoa;
pub(crate) use prep::PlaneWavePrep;
pub use spectral::{MAX_WAVELENGTHS, Wavelength};
pub(crate) use stages::validity::clearly_valid_about;
use stages::validity::{clearly_valid, clearly_valid_lanes};

/// A batch of directions as three slices of equal length (world coordinates; need not be unit).
#[derive(Debug, Clone, Copy)]
pub struct DirectionsSoa<'a, T> {
    /// x components.
    pub x: &'a [T],
    /// y components.
    pub y: &'a [T],
    /// z components.
    pub z: &'a [T],
}

/// The output of a batch of Stokes vectors: four slices of equal length, `s[k][i]` the parameter
/// `S_k` of vector `i`.
#[derive(Debug)]
pub struct StokesSoa<'a, T> {
    /// `S0, S1, S2, S3`.
    pub s: [&'a mut [T]; 4],
}

impl<'a, T> DirectionsSoa<'a, T> {
    /// The three component slices of `n` directions in one buffer, `stride` elements apart:
    /// `x, y, z` start at `0, stride, 2 stride`.
    ///
    /// Use [`crate::mueller::batch::padded_stride`] for `stride`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when `stride < n` or `buf.len() < 2 stride + n`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::interaction::batch::DirectionsSoa;
    /// use gmueller::mueller::batch::padded_stride;
    /// let (n, s) = (3, padded_stride::<f64>(3));
    /// let buf = vec![1.0_f64; 3 * s];
    /// assert_eq!(DirectionsSoa::from_strided(&buf, n, s).unwrap().len(), 3);
    /// ```
    pub fn from_strided(buf: &'a [T], n: usize, stride: usize) -> Result<Self, Error> {
        let [x, y, z] = Soa::<T, 3>::from_strided(buf, n, stride)?.c;
        Ok(Self { x, y, z })
    }

    /// The number of directions (the length of `x`).
    #[must_use]
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// `true` when the batch holds no direction.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
}

impl<'a, T> StokesSoa<'a, T> {
    /// The four parameter slices of `n` Stokes vectors in one buffer, `stride` elements apart:
    /// `S_k` of vector `i` lands at `buf[k stride + i]`.
    ///
    /// Use [`crate::mueller::batch::padded_stride`] for `stride`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when `stride < n` or `buf.len() < 3 stride + n`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::interaction::batch::StokesSoa;
    /// use gmueller::mueller::batch::padded_stride;
    /// let (n, s) = (3, padded_stride::<f64>(3));
    /// let mut buf = vec![0.0_f64; 4 * s];
    /// assert_eq!(StokesSoa::from_strided(&mut buf, n, s).unwrap().len(), 3);
    /// ```
    pub fn from_strided(buf: &'a mut [T], n: usize, stride: usize) -> Result<Self, Error> {
        Ok(Self {
            s: SoaMut::<T, 4>::from_strided(buf, n, stride)?.c,
        })
    }

    /// The number of Stokes vectors (the length of `s[0]`).
    #[must_use]
    pub fn len(&self) -> usize {
        self.s[0].len()
    }

    /// `true` when the batch holds no vector.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Writes the scattered Stokes radiance of the plane-wave polarized kernel for every exit
/// direction of `exits` into `out`: the classical Rayleigh–Rice Mueller BRDF of `material` (a
/// Gaussian height PSD, a [`RayleighRice`] scatterer of permittivity ε = η²), applied to
/// `packet`.
///
/// # Formula
/// ```text
/// S2.20, plane-wave limit (K = 2π p(h_t), no specular part), one shape for every channel:
///   L_o = (cos θ_o / λ²) · α · 2π p(h_t) · M (T S)
///   α   = exp(−(k σ (cos θ_i + cos θ_o))²)                   Debye–Waller
///   p   = σ² |Λ|^{1/2} exp(−½ |L⁻¹ h_t|²),  L Lᵀ = Λ⁻¹        Gaussian PSD (unitary transform)
///   M   = A_mül (J* ⊗ J) A_mül⁻¹,  J = 2k cos θ_i [[ss, ps], [sp, pp]]   (S2.19, S1.7)
/// with ss, ps, sp, pp the Rayleigh–Rice factors of RayleighRice::factors at the exit azimuth
/// φ of Geometry::exit_azimuth, q_o = √(ε − sin²θ_o) (principal branch), ε = η², and T the
/// rotation (S2.4) from the packet frame to the incident s/p frame. Evaluated as
///   L_o = cos θ_o · exp(ln(2π (2k cos θ_i)²/λ²) + ln p(h_t) + ln α) · M′ (T S),
/// M′ the Mueller matrix of the unscaled factors, one exponential per direction.
/// ```
/// This is `Kernel::<Full, PlaneWave>::evaluate(&material, packet, &g).scattered`
/// (equal to the [`super::OneShape`] level) with `g = Geometry::for_packet(packet, surface, exit)`,
/// for each exit direction; the specular part of that kernel is a Dirac delta and not returned.
/// Stokes vectors are in the exit s/p frame ([`Geometry::exit_sp`]), per unit incident
/// irradiance across the beam; lengths in the units of the wavelength.
///
/// The material's specular pBSDF is not used: in the plane-wave limit the specular lobe is a
/// delta (the kernel's `specular` part, 0 off the exact specular direction).
///
/// Accuracy: the geometry (r̂, `cos θ_o`, the exit s vector, the azimuth, `h_t`), `q_o`, the
/// four Rayleigh–Rice factors and the PSD's exponent are computed with the same operations in
/// the same order as the per-direction kernel (no fused multiply–adds there), so they are its
/// values bit for bit — which keeps the azimuth, whose condition number is `1/sin θ_o`, identical
/// next to the normal. What differs is the exponential (a polynomial within 1 ulp measured, 2
/// documented, instead of the C library's), its argument (the exponents `E` of the PSD, the
/// Debye–Waller factor and the constant prefactor summed before one exponential; `exp` turns
/// their rounding into a relative error `≈ ε |E|`), and the Mueller–Stokes product (fused
/// multiply–adds, another order). Against the per-direction kernel, per Stokes parameter: within
/// `4 ε (4 + |E|) S0` (measured ≤ `0.7 ε (1 + |E|) S0`: ≤ 1e-13 relative in f64 over the whole
/// range, ≤ 5e-6 in f32 near the lobe), plus the smallest normal number times the output scale
/// where the per-direction path rounds through subnormal numbers; exactly 0 where the PSD underflows
/// (`tests/interaction/batch/plane_wave.rs`).
///
/// Speed (AMD EPYC, AVX2 + FMA, 1024 exits within 15° of specular, `benches/kernel.rs` group
/// `kernel_batch`, one run): 23 ns per exit in `f64` and 11 ns in `f32`; 29 and 13 ns at normal
/// incidence, where every exit lies in the re-orthogonalised band of `Frame::sp`. The same exits
/// through `Geometry::for_packet` + [`Kernel::evaluate`] took 255 and 219 ns each.
///
/// Instruction sets: for `f32` and `f64` the CPU is detected at run time ([`pulp::Arch`]); with
/// AVX-512 the loop handles 8 (`f64`) or 16 (`f32`) directions per instruction, with AVX2 +
/// FMA 4 or 8, elsewhere a
/// scalar instantiation of the same loop runs. Other [`Real`] types, and indices so extreme
/// that the scalar `hypot` would leave its fast branch (`0 < |Im ε| < 10⁻¹⁸` or
/// `|ε| > 10¹⁸`), go through the per-direction kernel per direction. No heap allocation.
///
/// # Errors
/// Nothing is written to `out` on error.
/// - [`Error::OutOfRange`] when the three direction slices and the four output slices do not all
///   have the same length (`value` is the length of `exits.x`), when the packet travels away
///   from the surface, or when an exit direction has `cos θ_o ≤ 0`;
/// - [`Error::NonFinite`] for a NaN or infinite component of an exit direction;
/// - [`Error::InvalidBasis`] for a zero exit direction;
///
/// The direction errors are those of [`Geometry::for_packet`] for the first offending exit.
///
/// # Examples
/// ```
/// use gmueller::frame::Frame;
/// use gmueller::interaction::batch::{DirectionsSoa, StokesSoa, plane_wave_rayleigh_rice};
/// use gmueller::interaction::{Full, Geometry, Kernel, PlaneWave, RoughSurface};
/// use gmueller::interaction::pbsdf::{FresnelReflection, RayleighRice};
/// use gmueller::packet::{CoherenceShape, WavePacket};
/// use gmueller::psd::{ClosedForm, GaussianPsd};
/// use gmueller::stokes::Stokes;
/// use nalgebra::Vector3;
/// use num_complex::Complex;
///
/// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
/// let travel = Vector3::new(0.5_f64, 0.0, -(0.75_f64).sqrt()); // 30° incidence
/// let packet = WavePacket::from_stokes(
///     Stokes::new(1.0, 0.3, 0.2, -0.1).unwrap(), CoherenceShape::isotropic(10.0).unwrap(),
///     Frame::sp(travel, Vector3::z()).unwrap(), 0.5).unwrap();
/// let eta = Complex::new(1.5, 0.0);
/// let psd = GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap();
/// let (x, y, z) = (vec![0.5, 0.4, 0.0], vec![0.0, 0.1, 0.2], vec![0.87, 0.9, 1.0]);
/// let exits = DirectionsSoa { x: &x, y: &y, z: &z };
/// let mut s = [vec![0.0; 3], vec![0.0; 3], vec![0.0; 3], vec![0.0; 3]];
/// let [s0, s1, s2, s3] = &mut s;
/// let mut out = StokesSoa { s: [s0, s1, s2, s3] };
/// let material = RoughSurface {
///     psd,
///     specular: FresnelReflection::new(eta).unwrap(),
///     scatter: RayleighRice::new(eta).unwrap(),
/// };
/// plane_wave_rayleigh_rice(&material, &packet, &surface, &exits, &mut out).unwrap();
///
/// let kernel = Kernel::<Full, PlaneWave>::default();
/// for i in 0..3 {
///     let g = Geometry::for_packet(&packet, &surface, Vector3::new(x[i], y[i], z[i])).unwrap();
///     let one = kernel.evaluate(&material, &packet, &g).scattered;
///     for k in 0..4 {
///         assert!((out.s[k][i] - one.vector()[k]).abs() <= 1e-12 * one.s0());
///     }
/// }
/// ```
pub fn plane_wave_rayleigh_rice<T: Real, Sp>(
    material: &RoughSurface<GaussianPsd<T, 2>, Sp, RayleighRice<T>>,
    packet: &WavePacket<T>,
    surface: &Frame<T>,
    exits: &DirectionsSoa<'_, T>,
    out: &mut StokesSoa<'_, T>,
) -> Result<(), Error> {
    let n = exits.x.len();
    let same = exits.y.len() == n && exits.z.len() == n && out.s.iter().all(|s| s.len() == n);
    if !same {
        return Err(Error::OutOfRange {
            what: "batch slice length",
            value: n as f64,
            expected: "3 direction slices and 4 Stokes slices of one common length",
        });
    }
    let (psd, scatter) = (&material.psd, material.scatter);
    let prep = PlaneWavePrep::new(psd, scatter.permittivity(), packet, surface)?;
    if prep.vectorizable {
        return kernel_simd(&prep, exits, out);
    }
    portable(psd, scatter, packet, surface, exits, out)
}

/// The per-direction kernel per direction: validate every exit, then evaluate each.
fn portable<T: Real>(
    psd: &GaussianPsd<T, 2>,
    scatter: RayleighRice<T>,
    packet: &WavePacket<T>,
    surface: &Frame<T>,
    exits: &DirectionsSoa<'_, T>,
    out: &mut StokesSoa<'_, T>,
) -> Result<(), Error> {
    let exit = |i: usize| Vector3::new(exits.x[i], exits.y[i], exits.z[i]);
    for i in 0..exits.len() {
        Geometry::for_packet(packet, surface, exit(i))?;
    }
    let material = RoughSurface {
        psd: *psd,
        specular: ConstantMueller(Mueller(nalgebra::Matrix4::zeros())),
        scatter,
    };
    let kernel = Kernel::<Full, PlaneWave>::new(PlaneWave);
    let prepared = kernel.prepare(packet, surface)?;
    for i in 0..exits.len() {
        let g = Geometry::for_packet(packet, surface, exit(i))?;
        let s = kernel
            .evaluate_prepared(&material, &prepared, &g)
            .scattered
            .0;
        for k in 0..4 {
            out.s[k][i] = s[k];
        }
    }
    Ok(())
}

/// The SIMD kernel: validates every direction, then evaluates. Lengths must already be equal
/// (checked by [`plane_wave_rayleigh_rice`]).
pub(crate) fn kernel_simd<F: Real>(
    prep: &PlaneWavePrep<F>,
    exits: &DirectionsSoa<'_, F>,
    out: &mut StokesSoa<'_, F>,
) -> Result<(), Error> {
    crate::simd::dispatch(Batch { prep, exits, out })
}

/// The kernel on one vector of (validated) directions `(x, y, z)`: the stages in order.
struct StokesLanes<'p, F: Real>(&'p PlaneWavePrep<F>);

impl<F: Real> LaneMap<F, 3, 4> for StokesLanes<'_, F> {
    #[inline(always)]
    fn eval<S: Simd>(&self, s: S, [x, y, z]: [F::V<S>; 3]) -> [F::V<S>; 4] {
        let p = self.0;
        let (r, cos_o) = stages::geometry::exit_direction::<S, F>(s, p, x, y, z);
        let azimuth = stages::azimuth::exit_azimuth::<S, F>(s, p, r);
        let (so2, qo) = stages::fresnel::exit_q::<S, F>(s, p, cos_o);
        let factors = stages::rayleigh_rice::factors::<S, F>(s, p, cos_o, so2, qo, azimuth);
        let w = stages::psd::weight::<S, F>(s, p, r, cos_o);
        stages::stokes::assemble::<S, F>(s, p, factors, w)
    }
}

/// The SIMD loop, instantiated by [`pulp::Arch::dispatch`] once per instruction set.
struct Batch<'r, 'e, 'o, F: Real> {
    prep: &'r PlaneWavePrep<F>,
    exits: &'r DirectionsSoa<'e, F>,
    out: &'r mut StokesSoa<'o, F>,
}

impl<F: Real> WithSimd for Batch<'_, '_, '_, F> {
    type Output = Result<(), Error>;

    // `inline(always)`: the body must be compiled inside pulp's `#[target_feature]` function.
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> Result<(), Error> {
        let Self { prep, exits, out } = self;
        let n = exits.x.len();
        let (xs, ys, zs) = (&exits.x[..n], &exits.y[..n], &exits.z[..n]);
        let (hx, ys_v, zs_v) = (
            F::vsplit::<S>(xs).0,
            F::vsplit::<S>(ys).0,
            F::vsplit::<S>(zs).0,
        );
        let nv = hx.len();
        let (hy, hz) = (&ys_v[..nv], &zs_v[..nv]);
        let lanes = F::width::<S>();
        let exit = |i: usize| Vector3::new(xs[i], ys[i], zs[i]);
        // Validate everything before writing anything.
        for i in 0..nv {
            let ok = clearly_valid_lanes::<S, F>(s, prep, hx[i], hy[i], hz[i]);
            if F::vany(s, F::vnot(s, ok)) {
                for j in i * lanes..(i + 1) * lanes {
                    prep.check_exact(exit(j))?;
                }
            }
        }
        for j in nv * lanes..n {
            if !clearly_valid(prep, xs[j], ys[j], zs[j]) {
                prep.check_exact(exit(j))?;
            }
        }
        let lanes_map = StokesLanes(prep);
        let [o0, o1, o2, o3] = &mut out.s;
        let (o0, o1, o2, o3) = (&mut o0[..n], &mut o1[..n], &mut o2[..n], &mut o3[..n]);
        {
            // The whole vectors, every slice bound to a local re-sliced to `nv` (no bounds
            // checks in the loop).
            let (v0, v1, v2, v3) = (
                &mut F::vsplit_mut::<S>(o0).0[..nv],
                &mut F::vsplit_mut::<S>(o1).0[..nv],
                &mut F::vsplit_mut::<S>(o2).0[..nv],
                &mut F::vsplit_mut::<S>(o3).0[..nv],
            );
            for i in 0..nv {
                let [a, b, c, d] = lanes_map.eval(s, [hx[i], hy[i], hz[i]]);
                v0[i] = a;
                v1[i] = b;
                v2[i] = c;
                v3[i] = d;
            }
        }
        driver::remainder::<S, F, StokesLanes<'_, F>, 3, 4>(
            s,
            &lanes_map,
            [xs, ys, zs],
            &mut [o0, o1, o2, o3],
            n,
            nv,
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests;
