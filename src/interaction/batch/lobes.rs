//! The kernel at any level for a batch of exit directions: both lobes and the exit frames.
//!
//! [`Kernel::evaluate_batch`] is the structure-of-arrays form of
//! [`Kernel::evaluate_prepared`] for every polarization and coherence level, every material
//! (reflection or, with `interface = Some(η)`, reflection and transmission at a dielectric
//! interface) and every PSD and blur: the per-packet work once, then the exits — 8 (`f64`) or
//! 16 (`f32`) per instruction under AVX-512 (4 or 8 under AVX2 + FMA) for the partially coherent (closed-form blur) and incoherent
//! Gaussian- or Gaussian-mixture-PSD rough conductor in reflection, and rough dielectric in
//! reflection and at its interface lit from either side, at every polarization level
//! (`super::partial`), one at a time otherwise — with no heap allocation. For several
//! wavelengths of one path, `Kernel::evaluate_batch_spectral` (`super::spectral`) shares the
//! exit geometry between them.

use super::DirectionsSoa;
use super::outputs::{ExitFramesSoa, LobesSoa, check_lengths};
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::coherence::{CoherenceModel, CoherenceWeights};
use crate::interaction::polarization::KernelOutput;
use crate::interaction::polarization::PolarizationModel;
use crate::interaction::roughness::{RoughnessModel, RoughnessWeights};
use crate::interaction::{Geometry, Kernel, Surface};
use crate::packet::WavePacket;
use crate::real::Real;
use nalgebra::Vector3;

impl<Pol: PolarizationModel, Coh: CoherenceModel, Rough: RoughnessModel> Kernel<Pol, Coh, Rough> {
    /// Evaluates S2.20 for `packet` leaving along every direction of `exits`, writing both lobes
    /// into `out` and, when given, the exit s/p frames into `frames`.
    ///
    /// Entry `i` equals `kernel.evaluate(material, packet, &g)` with `g` the geometry of exit
    /// `i`: [`Geometry::for_packet`] when `interface` is `None` (reflection), and
    /// [`Geometry::for_packet_at_interface`] with relative index `η` when it is `Some(η)`
    /// (reflection or transmission, by the side of the exit). At the [`super::super::Intensity`]
    /// level only `S0` (`s[0]`) of each lobe is written: the level does not compute `S1..S3`.
    ///
    /// # Lanes
    /// With the [`super::super::Full`], [`super::super::OneShape`] or
    /// [`super::super::Intensity`] level (the last as `OneShape` on the effective vector
    /// `(1, 0, 0, 0)`, `S0` written),
    /// [`super::super::Partial`]`<`[`crate::psd::ClosedForm`]`>` or
    /// [`super::super::Incoherent`] coherence and a [`crate::psd::GaussianPsd`] or a
    /// [`crate::psd::GaussianMixturePsd`] of at most 8 components, on a
    /// [`super::super::RoughConductor`] with `interface = None` (Fresnel specular reflection
    /// and Rayleigh–Rice scattering, `Complex` index) or a [`super::super::RoughDielectric`]
    /// (either `interface`; at one, lit from either side, with a real Rayleigh–Rice
    /// permittivity: Fresnel reflection and transmission, Germer's and Elson's factors, each
    /// exit on its side; a vector of lanes with exits on both sides computes both), the exits
    /// run through the SIMD stages of `interaction::batch::stages`, 8 (`f64`) or 16 (`f32`)
    /// per instruction under AVX-512, 4 or 8 under AVX2 + FMA (pulp's run-time detection;
    /// elsewhere a scalar instantiation of the same loop). Exits within `√ε` of the normal, and
    /// lit parts whose final scale is not a normal number, are redone by the per-direction
    /// kernel, except a part whose `S0` is below `MIN_POSITIVE/2`, written as 0 (within the
    /// bound's absolute term below). The geometry, the exit frames (bit for bit), `q_o` and the Rayleigh–Rice factors are those of the per-direction
    /// kernel; the exponentials (a polynomial), the sums of the exponents and the matrix
    /// products (fused multiply–adds, another order) differ. Against the per-direction kernel,
    /// per Stokes parameter of a lobe of `S0 = L`:
    /// `|Δ| ≤ 4 ε (4 + |ln L| + 2 |ln S0|) L̂ + MIN_POSITIVE` with `S0` the packet's and
    /// `L̂ = max(L, (1 + √3) L₀)`, `L₀` the lobe's `S0` were its pBSDF non-polarizing (its
    /// Mueller matrix replaced by `M₀₀ I`): every exponent is summed before one exponential, so
    /// the rounding of the sum, relative to its terms, becomes a relative error of the result
    /// (`tests` of `batch::lobes`); and the output is a sum of products `M_kj u_j` of the
    /// pBSDF's matrix and the effective incident vector `u` (the coherence channels mixed, a
    /// valid Stokes vector: `Σ|u_j| ≤ (1 + √3) u₀`, and `|M_kj| ≤ M₀₀`), whose rounding is
    /// relative to `L̂` — far above `L` where the pBSDF's diattenuation cancels `u`'s
    /// polarization, be it the packet's (`tests/interaction/batch/lobes.rs`: a bound in `L` alone
    /// failed by 13× in f64) or the one the coherence channels give an unpolarized packet of two
    /// shapes (the specular lobe far from the mirror direction near Brewster's angle, where
    /// `K_x ≫ K_y`: a bound with the packet's polarization alone failed by 4.3× in f32). For a
    /// non-polarizing pBSDF `L̂ ≤ (1 + √3) L`. In such a cancellation the per-direction kernel's
    /// own `f32` error is of the same order (4.5e-5 relative to `f64` in that case).
    ///
    /// **Roughness levels.** The lanes run at first order and, for a
    /// [`crate::psd::GaussianPsd`] with `Partial<ClosedForm>` coherence, with the Kirchhoff
    /// series ([`crate::interaction::roughness::KirchhoffSeries`]: every order's weight in
    /// closed form, summed per lane until a falling term is below `tol/2` of the largest,
    /// `interaction::batch::stages::series`); the bound above then gains `tol · L`, the two
    /// sums' truncations (measured: at most `0.43 tol L` in f64). Lanes with `g = (vσ)²` at or
    /// above 64 (`f64`) or 16 (`f32`) or the series' switch to the geometric limit, and lanes
    /// whose sum needs more orders than the call builds (`ĝ + 12√ĝ + 24` for the largest `g`
    /// its exits can have, at most 160: far tails), are redone by the per-direction kernel. A
    /// call of fewer than 3 exits takes the per-direction series for all of them (building the
    /// series' constants costs more than 2 exits one at a time). Every other roughness level
    /// (and the incoherent series, a mixture PSD with the series) goes exit by exit, bit for
    /// bit [`Kernel::evaluate_prepared`].
    /// pulp's AVX-512 back-end (x86-64-v4: 8 `f64` or 16 `f32` lanes) is on and is what
    /// dispatch picks on a CPU that has it; the stage tests run it where the machine has it
    /// (2026-12-04: an AMD EPYC with AVX-512), besides the scalar back-ends of 1–8 lanes and
    /// AVX2. The NEON back-end has never run on real hardware here.
    ///
    /// # Errors
    /// - [`Error::OutOfRange`] when a slice of `out` or `frames` is shorter than `exits` (nothing
    ///   is written), or when the packet does not travel toward the surface (as
    ///   [`Kernel::prepare`]).
    /// - The error of the geometry constructor for the first exit direction it rejects (e.g. a
    ///   zero or non-finite direction, or, in reflection, one below the surface). On the lane
    ///   path nothing is written then (every exit is validated first); one exit at a time, the
    ///   entries before it are written. Treat `out` as unspecified after an error.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::batch::{DirectionsSoa, LobesSoa, StokesSoa};
    /// use gmueller::interaction::{Full, Geometry, Kernel, Partial, RoughDielectric};
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    ///
    /// let glass = RoughDielectric::new(GaussianPsd::<f64, 2>::isotropic(0.01, 2.0)?, 1.5)?;
    /// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
    /// let travel = Vector3::new(0.5, 0.0, -(0.75_f64).sqrt());
    /// // Unpolarized, one shape: the effective incident vector is (S0, 0, 0, 0), so L₀ = L.
    /// let packet = WavePacket::from_stokes(Stokes::new(1.0, 0.0, 0.0, 0.0)?,
    ///     CoherenceShape::isotropic(10.0)?, Frame::sp(travel, Vector3::z())?, 0.5)?;
    /// // One exit above (reflection), one below (transmission).
    /// let (x, y, z) = ([0.5, 0.3], [0.0, 0.1], [0.87, -0.95]);
    /// let exits = DirectionsSoa { x: &x, y: &y, z: &z };
    /// let mut buf = [[0.0; 2]; 8];
    /// let [a, b, c, d, e, f, g, h] = &mut buf;
    /// let mut out = LobesSoa {
    ///     specular: StokesSoa { s: [a, b, c, d] },
    ///     scattered: StokesSoa { s: [e, f, g, h] },
    /// };
    /// let kernel = Kernel::<Full, Partial>::default();
    /// kernel.evaluate_batch(&glass, &packet, &surface, Some(1.5), exits, &mut out, None)?;
    /// let g = glass.geometry_for_packet(&packet, &surface, Vector3::new(0.3, 0.1, -0.95))?;
    /// let one = kernel.evaluate(&glass, &packet, &g).scattered.vector();
    /// // The lanes against one exit at a time, within the bound above (packet S0 = 1, so
    /// // ln S0 = 0; L̂ = (1 + √3) L₀ = (1 + √3) L).
    /// let l = one[0];
    /// let bound = 4.0 * f64::EPSILON * (4.0 + l.ln().abs()) * (1.0 + 3f64.sqrt()) * l;
    /// for k in 0..4 {
    ///     assert!((out.scattered.s[k][1] - one[k]).abs() <= bound + f64::MIN_POSITIVE);
    /// }
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    #[expect(
        clippy::too_many_arguments,
        reason = "the material, the packet, the surface, the interface, the exits and two outputs"
    )]
    pub fn evaluate_batch<T, S>(
        &self,
        material: &S,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
        interface: Option<T>,
        exits: DirectionsSoa<'_, T>,
        out: &mut LobesSoa<'_, T>,
        mut frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        let n = exits.len();
        check_lengths(&exits, core::slice::from_ref(out), frames.as_deref())?;
        let facing = match interface {
            Some(_) => surface.facing(&-packet.direction()),
            None => *surface,
        };
        let prepared = self.prepare(packet, &facing)?;
        if let Some(done) = super::partial::try_evaluate(
            self,
            material,
            &prepared,
            packet,
            (surface, interface),
            exits,
            out,
            frames.as_deref_mut(),
        ) {
            return done;
        }
        for i in 0..n {
            let exit = Vector3::new(exits.x[i], exits.y[i], exits.z[i]);
            let g = match interface {
                Some(eta) => Geometry::for_packet_at_interface(packet, surface, eta, exit)?,
                None => Geometry::for_packet(packet, surface, exit)?,
            };
            let r = self.evaluate_prepared(material, &prepared, &g);
            match r.stokes() {
                Some((sp, sc)) => {
                    for c in 0..4 {
                        out.specular.s[c][i] = sp.0[c];
                        out.scattered.s[c][i] = sc.0[c];
                    }
                }
                None => {
                    out.specular.s[0][i] = r.specular_intensity();
                    out.scattered.s[0][i] = r.scattered_intensity();
                }
            }
            if let Some(f) = frames.as_deref_mut() {
                let s = g.exit_sp().x();
                for c in 0..3 {
                    f.s[c][i] = s[c];
                }
            }
        }
        Ok(())
    }
}
