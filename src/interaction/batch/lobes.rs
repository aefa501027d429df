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
use crate::interaction::RoughSurface;
use crate::interaction::pbsdf::Pbsdf;
use crate::interaction::polarization::KernelOutput;
use crate::interaction::{CoherenceModel, CoherenceWeights, Geometry, Kernel, PolarizationModel};
use crate::packet::WavePacket;
use crate::psd::Psd;
use crate::real::Real;
use nalgebra::Vector3;

impl<Pol: PolarizationModel, Coh: CoherenceModel> Kernel<Pol, Coh> {
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
    /// polarization, be it the packet's (`tests/lobe_batch.rs`: a bound in `L` alone failed by
    /// 13× in f64) or the one the coherence channels give an unpolarized packet of two shapes
    /// (the specular lobe far from the mirror direction near Brewster's angle, where
    /// `K_x ≫ K_y`: a bound with the packet's polarization alone failed by 4.3× in f32). For a
    /// non-polarizing pBSDF `L̂ ≤ (1 + √3) L`. In such a cancellation the per-direction kernel's
    /// own `f32` error is of the same order (4.5e-5 relative to `f64` in that case).
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
    pub fn evaluate_batch<T, P, Sp, Sc>(
        &self,
        material: &RoughSurface<P, Sp, Sc>,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
        interface: Option<T>,
        exits: DirectionsSoa<'_, T>,
        out: &mut LobesSoa<'_, T>,
        mut frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>
    where
        T: Real,
        P: Psd<T, 2> + 'static,
        Coh: CoherenceWeights<T, P> + 'static,
        Sp: Pbsdf<T> + 'static,
        Sc: Pbsdf<T> + 'static,
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

#[cfg(test)]
mod tests {
    use super::super::StokesSoa;
    use super::*;
    use crate::interaction::{
        Full, Incoherent, Intensity, OneShape, Partial, PlaneWave, RoughConductor, RoughDielectric,
    };
    use crate::packet::CoherenceShape;
    use crate::psd::{GaussianMixturePsd, GaussianPsd};
    use crate::stokes::Stokes;
    use num_complex::Complex;

    /// Exits above and below the surface, at normal, oblique, grazing and φ ≠ 0.
    fn exits<T: Real>(below: bool) -> [Vec<T>; 3] {
        let mut d: [Vec<T>; 3] = Default::default();
        for (i, theta) in [0.0_f64, 0.2, 0.7, 1.2, 1.55].iter().enumerate() {
            for phi in [0.0_f64, 0.4, 2.5, -1.9] {
                let sign = if below && i % 2 == 1 { -1.0 } else { 1.0 };
                let v = [
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    sign * theta.cos(),
                ];
                for c in 0..3 {
                    d[c].push(T::lit(v[c]));
                }
            }
        }
        d
    }

    fn packet<T: Real>(two_shapes: bool) -> WavePacket<T> {
        let travel = Vector3::new(T::lit(0.4), T::lit(0.1), -T::lit(0.91)).normalize();
        let frame = Frame::sp(travel, Vector3::z()).unwrap();
        let s = Stokes::new(T::one(), T::lit(0.3), -T::lit(0.2), T::lit(0.5)).unwrap();
        if two_shapes {
            WavePacket::new(
                s,
                CoherenceShape::isotropic(T::lit(6.0)).unwrap(),
                CoherenceShape::isotropic(T::lit(7.2)).unwrap(),
                frame,
                T::lit(0.55),
            )
            .unwrap()
        } else {
            WavePacket::from_stokes(
                s,
                CoherenceShape::isotropic(T::lit(6.0)).unwrap(),
                frame,
                T::lit(0.55),
            )
            .unwrap()
        }
    }

    /// The batch against `Kernel::evaluate` one direction at a time, both lobes, every Stokes
    /// parameter the level computes, the exit frame, within `tol` of each lobe's `S0`.
    fn check<T, Pol, Coh, P, Sp, Sc>(
        kernel: Kernel<Pol, Coh>,
        material: &RoughSurface<P, Sp, Sc>,
        interface: Option<T>,
        two_shapes: bool,
        tol: f64,
    ) -> usize
    where
        T: Real,
        Pol: PolarizationModel,
        Coh: CoherenceModel + CoherenceWeights<T, P> + 'static,
        P: Psd<T, 2> + 'static,
        Sp: Pbsdf<T> + 'static,
        Sc: Pbsdf<T> + 'static,
    {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let packet = packet::<T>(two_shapes);
        let d = exits::<T>(interface.is_some());
        let n = d[0].len();
        let mut buf = vec![vec![T::lit(-7.0); n]; 11];
        let [a, b, c, e, f, g, h, i, sx, sy, sz] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, c, e] },
            scattered: StokesSoa { s: [f, g, h, i] },
        };
        let mut frames = ExitFramesSoa { s: [sx, sy, sz] };
        let dirs = DirectionsSoa {
            x: &d[0],
            y: &d[1],
            z: &d[2],
        };
        let lanes = lane_path(&kernel, material, interface);
        kernel
            .evaluate_batch(
                material,
                &packet,
                &surface,
                interface,
                dirs,
                &mut out,
                Some(&mut frames),
            )
            .unwrap();
        let mut lit = 0;
        for j in 0..n {
            let exit = Vector3::new(d[0][j], d[1][j], d[2][j]);
            let geo = match interface {
                Some(eta) => Geometry::for_packet_at_interface(&packet, &surface, eta, exit),
                None => Geometry::for_packet(&packet, &surface, exit),
            }
            .unwrap();
            let r = kernel.evaluate(material, &packet, &geo);
            let lobes = [
                (r.specular_intensity(), &out.specular, 0),
                (r.scattered_intensity(), &out.scattered, 1),
            ];
            for (s0, soa, lobe) in lobes {
                let bound = if lanes {
                    // The documented bound of the lane path: 4 ε (4 + |E|) S0, E = ln S0 of
                    // the lobe (the packet's S0 is 1), plus the smallest normal number.
                    let e = if s0 == T::zero() {
                        0.0
                    } else {
                        s0.to_f64().abs().ln().abs()
                    };
                    let rel = 4.0 * T::EPSILON.to_f64() * (4.0 + e);
                    rel.max(tol) * s0.to_f64().abs() + T::MIN_POSITIVE.to_f64()
                } else {
                    tol * s0.to_f64().abs() + f64::MIN_POSITIVE
                };
                let want: [T; 4] = match r.stokes() {
                    Some(st) => [st.0, st.1][lobe].0.into(),
                    None => [s0, T::lit(-7.0), T::lit(-7.0), T::lit(-7.0)],
                };
                for (c, (col, w)) in soa.s.iter().zip(want).enumerate() {
                    let got = col[j].to_f64();
                    assert!(
                        (got - w.to_f64()).abs() <= bound,
                        "exit {j} lobe {lobe} S{c}: batch {got:e}, one at a time {:e}",
                        w.to_f64()
                    );
                }
                if s0 > T::zero() {
                    lit += 1;
                }
            }
            for (c, col) in frames.s.iter().enumerate() {
                assert_eq!(col[j], geo.exit_sp().x()[c], "exit {j} frame axis {c}");
            }
        }
        lit
    }

    /// Whether `evaluate_batch` takes the lane path (`super::super::partial`) for these.
    fn lane_path<T, Pol, Coh, P, Sp, Sc>(
        kernel: &Kernel<Pol, Coh>,
        material: &RoughSurface<P, Sp, Sc>,
        interface: Option<T>,
    ) -> bool
    where
        T: Real,
        Pol: PolarizationModel,
        Coh: CoherenceModel + 'static,
        P: 'static,
        Sp: 'static,
        Sc: 'static,
    {
        use crate::interaction::polarization::PolarizationLevel as L;
        let any: &dyn core::any::Any = material;
        let coh: &dyn core::any::Any = kernel.coherence();
        let conductor = any.is::<RoughConductor<T, GaussianPsd<T, 2>>>()
            || any
                .downcast_ref::<RoughConductor<T, GaussianMixturePsd<T, 2>>>()
                .is_some_and(|m| m.psd.components().len() <= 8);
        let dielectric = any.is::<RoughDielectric<T, GaussianPsd<T, 2>>>()
            || any
                .downcast_ref::<RoughDielectric<T, GaussianMixturePsd<T, 2>>>()
                .is_some_and(|m| m.psd.components().len() <= 8);
        matches!(Pol::LEVEL, L::Full | L::OneShape | L::Intensity)
            && (coh.is::<Partial>() || coh.is::<Incoherent>())
            && (dielectric || (conductor && interface.is_none()))
    }

    macro_rules! every_level {
        ($t:ty, $material:expr, $interface:expr, $two:expr, $tol:expr) => {{
            let m = $material;
            let mut lit = 0;
            every_level!(@each $t, m, $interface, $two, $tol, lit;
                (Intensity, PlaneWave) (Intensity, Partial) (Intensity, Incoherent)
                (OneShape, PlaneWave) (OneShape, Partial) (OneShape, Incoherent)
                (Full, PlaneWave) (Full, Partial) (Full, Incoherent));
            lit
        }};
        (@each $t:ty, $m:ident, $interface:expr, $two:expr, $tol:expr, $lit:ident;
            $(($pol:ty, $coh:ty))*) => {
            $(
                $lit += check::<$t, _, _, _, _, _>(
                    Kernel::<$pol, $coh>::default(),
                    &$m,
                    $interface,
                    $two,
                    $tol,
                );
            )*
        };
    }

    #[test]
    fn conductor_batch_equals_one_at_a_time_at_every_level() {
        for two in [false, true] {
            let gold = || {
                RoughConductor::new(
                    GaussianPsd::<f64, 2>::isotropic(0.02, 1.5).unwrap(),
                    Complex::new(0.2, 3.4),
                )
                .unwrap()
            };
            let lit = every_level!(f64, gold(), None, two, 1e-14);
            assert!(lit > 100, "only {lit} lit lobes checked");
            let gold32 = RoughConductor::new(
                GaussianPsd::<f32, 2>::isotropic(0.02, 1.5).unwrap(),
                Complex::new(0.2, 3.4),
            )
            .unwrap();
            let lit = every_level!(f32, gold32, None, two, 1e-6);
            assert!(lit > 60, "only {lit} lit lobes checked (f32)");
        }
    }

    /// A rough conductor with a three-component Gaussian-mixture PSD (the lane path at the
    /// `Partial` and `Incoherent` levels) and with a nine-component one (one at a time).
    #[test]
    fn mixture_batch_equals_one_at_a_time_at_every_level() {
        fn mixture<T: Real>(m: usize) -> RoughConductor<T, GaussianMixturePsd<T, 2>> {
            let comps = (0..m)
                .map(|j| {
                    let f = j as f64;
                    GaussianPsd::<T, 2>::isotropic(T::lit(0.02 / (1.0 + f)), T::lit(0.6 + 0.8 * f))
                        .unwrap()
                })
                .collect();
            RoughConductor::new(
                GaussianMixturePsd::new(comps).unwrap(),
                Complex::new(T::lit(0.2), T::lit(3.4)),
            )
            .unwrap()
        }
        for two in [false, true] {
            for m in [3, 9] {
                let lit = every_level!(f64, mixture::<f64>(m), None, two, 1e-14);
                assert!(lit > 100, "{m} components: only {lit} lit lobes checked");
                let lit = every_level!(f32, mixture::<f32>(m), None, two, 1e-6);
                assert!(
                    lit > 60,
                    "{m} components: only {lit} lit lobes checked (f32)"
                );
            }
        }
    }

    #[test]
    fn dielectric_batch_reflects_and_transmits_at_every_level() {
        for two in [false, true] {
            let glass =
                RoughDielectric::new(GaussianPsd::<f64, 2>::isotropic(0.02, 1.5).unwrap(), 1.5)
                    .unwrap();
            let lit = every_level!(f64, glass, Some(1.5), two, 1e-14);
            assert!(lit > 100, "only {lit} lit lobes checked");
            let glass32 =
                RoughDielectric::new(GaussianPsd::<f32, 2>::isotropic(0.02, 1.5).unwrap(), 1.5)
                    .unwrap();
            let lit = every_level!(f32, glass32, Some(1.5_f32), two, 1e-6);
            assert!(lit > 60, "only {lit} lit lobes checked (f32)");
        }
    }

    #[test]
    fn short_output_is_rejected_before_anything_is_written() {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let glass = RoughDielectric::new(GaussianPsd::<f64, 2>::isotropic(0.02, 1.5).unwrap(), 1.5)
            .unwrap();
        let packet = packet::<f64>(false);
        let d = exits::<f64>(false);
        let n = d[0].len();
        let mut buf = vec![vec![-7.0; n]; 8];
        buf[7].pop();
        let [a, b, c, e, f, g, h, i] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, c, e] },
            scattered: StokesSoa { s: [f, g, h, i] },
        };
        let dirs = DirectionsSoa {
            x: &d[0],
            y: &d[1],
            z: &d[2],
        };
        let r = Kernel::<Full, Partial>::default()
            .evaluate_batch(&glass, &packet, &surface, None, dirs, &mut out, None);
        assert!(matches!(r, Err(Error::OutOfRange { .. })), "{r:?}");
        assert!(
            buf.iter().flatten().all(|&v| v == -7.0),
            "something was written"
        );
    }

    #[test]
    fn a_rejected_exit_is_reported() {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let gold = RoughConductor::new(
            GaussianPsd::<f64, 2>::isotropic(0.02, 1.5).unwrap(),
            Complex::new(0.2, 3.4),
        )
        .unwrap();
        let packet = packet::<f64>(false);
        let (x, y, z) = ([0.1, 0.0], [0.0, 0.0], [0.99, 0.0]);
        let mut buf = [[-7.0; 2]; 8];
        let [a, b, c, e, f, g, h, i] = &mut buf;
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, c, e] },
            scattered: StokesSoa { s: [f, g, h, i] },
        };
        let dirs = DirectionsSoa {
            x: &x,
            y: &y,
            z: &z,
        };
        // The lane path (Full·Partial on a conductor) and the exit-by-exit one (Incoherent).
        let lanes = Kernel::<Full, Partial>::default()
            .evaluate_batch(&gold, &packet, &surface, None, dirs, &mut out, None);
        let by_exit = Kernel::<Full, Incoherent>::default()
            .evaluate_batch(&gold, &packet, &surface, None, dirs, &mut out, None);
        let want = Geometry::for_packet(&packet, &surface, Vector3::zeros()).unwrap_err();
        assert_eq!(lanes.unwrap_err(), want);
        assert_eq!(by_exit.unwrap_err(), want);
    }
}

#[cfg(test)]
mod lane_tests {
    //! The lane path (`super::super::partial`) on batches of every length and at extreme
    //! scales of the packet.
    use super::super::StokesSoa;
    use super::*;
    use crate::interaction::{
        FresnelInterface, FresnelReflection, Full, Incoherent, Intensity, OneShape, Partial,
        RayleighRice, RoughConductor, RoughDielectric,
    };
    use crate::packet::CoherenceShape;
    use crate::psd::GaussianPsd;
    use crate::stokes::Stokes;
    use num_complex::Complex;

    /// 41 exits: around the mirror direction, near and at the normal, grazing.
    fn exits<T: Real>() -> [Vec<T>; 3] {
        let mut d: [Vec<T>; 3] = Default::default();
        for i in 0..41 {
            let t = i as f64 / 40.0;
            let theta = [0.0, 1e-9, 0.3 + 0.3 * t, 1.2 + 0.37 * t, 0.0][i % 5];
            let phi = -2.0 + 5.0 * t;
            let mut v = [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ];
            if i % 5 == 4 {
                // Within ~0.005 rad of the mirror direction of `packet`'s incidence.
                v = [0.4 + 0.008 * (t - 0.5), 0.1 + 0.006 * (0.5 - t), 0.91];
            }
            for c in 0..3 {
                d[c].push(T::lit(v[c]));
            }
        }
        d
    }

    /// The packet at scale `s0`, travelling down (`up = false`) or up (lit from inside the
    /// glass of [`GlassFromBelow`]).
    fn packet<T: Real>(s0: f64, up: bool) -> WavePacket<T> {
        let z = if up { T::lit(0.91) } else { -T::lit(0.91) };
        let travel = Vector3::new(T::lit(0.4), T::lit(0.1), z).normalize();
        let frame = Frame::sp(travel, Vector3::z()).unwrap();
        let s = Stokes::new(1.0, 0.3, -0.2, 0.5).unwrap().vector() * s0;
        WavePacket::new(
            Stokes::new(T::lit(s[0]), T::lit(s[1]), T::lit(s[2]), T::lit(s[3])).unwrap(),
            CoherenceShape::isotropic(T::lit(6.0)).unwrap(),
            CoherenceShape::isotropic(T::lit(7.2)).unwrap(),
            frame,
            T::lit(0.55),
        )
        .unwrap()
    }

    /// A rough surface of the lane path: gold with a Gaussian PSD ([`Gold`]) or a
    /// three-component mixture ([`GoldMixture`]) in reflection, or glass at its interface lit
    /// from inside ([`GlassFromBelow`]: reflection and transmission, Elson's factors, the
    /// reversed frame).
    trait Surface<T: Real> {
        type P: Psd<T, 2> + 'static;
        type Sp: Pbsdf<T> + 'static;
        type Sc: Pbsdf<T> + 'static;
        /// `Some(η)` at an interface lit from inside (the packet travels up; exits alternate
        /// between the two sides).
        const INTERFACE: Option<f64> = None;
        fn make() -> RoughSurface<Self::P, Self::Sp, Self::Sc>;
    }

    struct Gold;
    struct GoldMixture;
    struct GlassFromBelow;

    fn gold<T: Real, P: Psd<T, 2>>(psd: P) -> RoughConductor<T, P> {
        RoughConductor::new(psd, Complex::new(T::lit(0.2), T::lit(3.4))).unwrap()
    }

    fn gaussian<T: Real>(h: f64, l: f64) -> GaussianPsd<T, 2> {
        GaussianPsd::<T, 2>::isotropic(T::lit(h), T::lit(l)).unwrap()
    }

    impl<T: Real> Surface<T> for Gold {
        type P = GaussianPsd<T, 2>;
        type Sp = FresnelReflection<T>;
        type Sc = RayleighRice<T>;
        fn make() -> RoughConductor<T, Self::P> {
            gold(gaussian(0.02, 1.5))
        }
    }

    impl<T: Real> Surface<T> for GoldMixture {
        type P = crate::psd::GaussianMixturePsd<T, 2>;
        type Sp = FresnelReflection<T>;
        type Sc = RayleighRice<T>;
        fn make() -> RoughConductor<T, Self::P> {
            let c = vec![
                gaussian(0.02, 1.5),
                gaussian(0.012, 0.6),
                gaussian(0.006, 4.0),
            ];
            gold(crate::psd::GaussianMixturePsd::new(c).unwrap())
        }
    }

    impl<T: Real> Surface<T> for GlassFromBelow {
        type P = GaussianPsd<T, 2>;
        type Sp = FresnelInterface<T>;
        type Sc = RayleighRice<T>;
        const INTERFACE: Option<f64> = Some(1.5);
        fn make() -> RoughDielectric<T, Self::P> {
            RoughDielectric::new(gaussian(0.02, 1.5), T::lit(1.5)).unwrap()
        }
    }

    /// [`exits`], every other one mirrored below the surface when `M` is at an interface.
    fn exits_for<T: Real, M: Surface<T>>() -> [Vec<T>; 3] {
        let mut d = exits::<T>();
        if M::INTERFACE.is_some() {
            for (j, z) in d[2].iter_mut().enumerate() {
                if j % 2 == 1 {
                    *z = -*z;
                }
            }
        }
        d
    }

    /// The first `n` exits through `evaluate_batch`: `[specular S0..S3, scattered S0..S3,
    /// frame x, y, z]`, each `n` long.
    fn batch<T: Real, Pol: PolarizationModel, Coh, M: Surface<T>>(
        packet: &WavePacket<T>,
        n: usize,
    ) -> Vec<Vec<T>>
    where
        Coh: CoherenceWeights<T, M::P> + Default + 'static,
    {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let d = exits_for::<T, M>();
        let mut buf = vec![vec![T::lit(-7.0); n]; 11];
        let [a, b, c, e, f, g, h, i, sx, sy, sz] = &mut buf[..] else {
            unreachable!()
        };
        let mut out = LobesSoa {
            specular: StokesSoa { s: [a, b, c, e] },
            scattered: StokesSoa { s: [f, g, h, i] },
        };
        let mut frames = ExitFramesSoa { s: [sx, sy, sz] };
        let dirs = DirectionsSoa {
            x: &d[0][..n],
            y: &d[1][..n],
            z: &d[2][..n],
        };
        Kernel::<Pol, Coh>::default()
            .evaluate_batch(
                &M::make(),
                packet,
                &surface,
                M::INTERFACE.map(T::lit),
                dirs,
                &mut out,
                Some(&mut frames),
            )
            .unwrap();
        buf
    }

    /// Every lane is computed on its own: a batch of any length gives, bit for bit, the
    /// entries of the longest batch (whole vectors, overlapping tails, batches shorter than
    /// one vector padded).
    fn prefixes<T: Real, Pol: PolarizationModel>() {
        let p = packet::<T>(1.0, false);
        let all = batch::<T, Pol, Partial, Gold>(&p, 41);
        let mut lit = 0;
        for n in 0..=41 {
            let part = batch::<T, Pol, Partial, Gold>(&p, n);
            for (k, (a, b)) in part.iter().zip(&all).enumerate() {
                for j in 0..n {
                    assert_eq!(
                        a[j].to_f64().to_bits(),
                        b[j].to_f64().to_bits(),
                        "n {n} column {k} exit {j}"
                    );
                }
            }
            lit += part[4].iter().filter(|v| **v > T::zero()).count();
        }
        let specular = all[0].iter().filter(|v| **v > T::zero()).count();
        assert!(
            lit > 400 && specular >= 2,
            "only {lit} lit scattered, {specular} specular entries"
        );
    }

    #[test]
    fn a_batch_of_any_length_gives_the_same_entries() {
        prefixes::<f64, Full>();
        prefixes::<f32, Full>();
        prefixes::<f64, OneShape>();
        prefixes::<f32, OneShape>();
        prefixes::<f64, Intensity>();
        prefixes::<f32, Intensity>();
    }

    /// At packet `S0` from the smallest normal number to near the largest, the lane path
    /// against `Kernel::evaluate` within `4 ε (4 + |ln L| + 2 |ln S0|) L` (the documented bound
    /// with `L ≤ L̂` in place of `L̂`: stricter, no cancelling geometry among these exits)
    /// plus `MIN_POSITIVE` (`L` a lobe's `S0`; the exponent summed before the one exponential
    /// holds `ln S0` of the packet and the weight's logarithm, `ln L` minus `ln S0` and bounded
    /// terms), and valid Stokes vectors.
    fn scales<T: Real, Pol: PolarizationModel, Coh, M: Surface<T>>(exps: &[f64])
    where
        Coh: CoherenceWeights<T, M::P> + Default + 'static,
    {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let d = exits_for::<T, M>();
        let kernel = Kernel::<Pol, Coh>::default();
        let mut lit = 0;
        for &e in exps {
            let p = packet::<T>(10f64.powf(e), M::INTERFACE.is_some());
            let got = batch::<T, Pol, Coh, M>(&p, 41);
            for j in 0..41 {
                let exit = Vector3::new(d[0][j], d[1][j], d[2][j]);
                let g = match M::INTERFACE {
                    Some(eta) => Geometry::for_packet_at_interface(&p, &surface, T::lit(eta), exit),
                    None => Geometry::for_packet(&p, &surface, exit),
                }
                .unwrap();
                let r = kernel.evaluate(&M::make(), &p, &g);
                // Every Stokes parameter the level computes (S0 only at the Intensity level).
                let wants: [Vec<f64>; 2] = match r.stokes() {
                    Some((sp, sc)) => {
                        [sp, sc].map(|v| v.vector().iter().map(|w| w.to_f64()).collect())
                    }
                    None => [
                        vec![r.specular_intensity().to_f64()],
                        vec![r.scattered_intensity().to_f64()],
                    ],
                };
                for (lobe, want) in wants.iter().enumerate() {
                    let l = want[0];
                    let ln_s0 = p.stokes().s0().to_f64().ln().abs();
                    let rel = if l > 0.0 {
                        l.ln().abs() + 2.0 * ln_s0
                    } else {
                        0.0
                    };
                    let bound =
                        4.0 * T::EPSILON.to_f64() * (4.0 + rel) * l + T::MIN_POSITIVE.to_f64();
                    let v: Vec<f64> = (0..4).map(|k| got[4 * lobe + k][j].to_f64()).collect();
                    for (k, (&b, &w)) in v.iter().zip(want).enumerate() {
                        assert!(
                            (b - w).abs() <= bound || (w.is_infinite() && b == w),
                            "S0 1e{e} exit {j} lobe {lobe} S{k}: batch {b:e}, one at a time {w:e}"
                        );
                    }
                    if want.len() == 4 && v[0].is_infinite() {
                        // An overflow stays an overflow (the per-direction kernel's too).
                        assert!(v[0] > 0.0, "exit {j} lobe {lobe}: {v:?}");
                    } else if want.len() == 4 {
                        // As ratios to S0: the squares of entries near 1e-300 would underflow.
                        let (r, one) = if v[0] > 0.0 {
                            (v.iter().map(|x| x / v[0]).collect::<Vec<_>>(), 1.0)
                        } else {
                            (v.clone(), 0.0)
                        };
                        assert!(
                            v[0] >= 0.0
                                && r[1] * r[1] + r[2] * r[2] + r[3] * r[3]
                                    <= one * (1.0 + 8.0 * T::EPSILON.to_f64()),
                            "exit {j} lobe {lobe}: {v:?} not a valid Stokes vector"
                        );
                    } else {
                        assert!(
                            v[0] >= 0.0 && v[1..].iter().all(|&u| u == -7.0),
                            "exit {j} lobe {lobe}: {v:?}, S1..S3 written at the Intensity level"
                        );
                    }
                    if l > 0.0 {
                        lit += 1;
                    }
                }
            }
        }
        assert!(lit > 15 * exps.len(), "only {lit} lit lobes");
    }

    #[test]
    fn the_lane_path_holds_its_bound_at_extreme_scales() {
        scales::<f64, Full, Partial, Gold>(&[-300.0, -150.0, 0.0, 150.0, 300.0]);
        scales::<f64, OneShape, Partial, Gold>(&[-300.0, 0.0, 300.0]);
        scales::<f32, Full, Partial, Gold>(&[-36.0, -20.0, 0.0, 20.0, 36.0]);
        scales::<f32, OneShape, Partial, Gold>(&[-36.0, 0.0, 36.0]);
        scales::<f64, Full, Incoherent, Gold>(&[-300.0, 0.0, 300.0]);
        scales::<f64, OneShape, Incoherent, Gold>(&[-300.0, 0.0, 300.0]);
        scales::<f32, Full, Incoherent, Gold>(&[-36.0, 0.0, 36.0]);
        scales::<f32, OneShape, Incoherent, Gold>(&[-36.0, 0.0, 36.0]);
        scales::<f64, Intensity, Partial, Gold>(&[-300.0, 0.0, 300.0]);
        scales::<f32, Intensity, Partial, Gold>(&[-36.0, 0.0, 36.0]);
        scales::<f64, Intensity, Incoherent, Gold>(&[-300.0, 0.0, 300.0]);
        scales::<f32, Intensity, Incoherent, Gold>(&[-36.0, 0.0, 36.0]);
        // A three-component mixture PSD (per channel ln Σⱼ Kⱼ in the lanes).
        scales::<f64, Full, Partial, GoldMixture>(&[-300.0, 0.0, 300.0]);
        scales::<f32, Full, Partial, GoldMixture>(&[-36.0, 0.0, 36.0]);
        scales::<f64, OneShape, Incoherent, GoldMixture>(&[-300.0, 0.0, 300.0]);
        scales::<f32, Intensity, Partial, GoldMixture>(&[-36.0, 0.0, 36.0]);
        // Glass lit from inside: both sides, Fresnel transmission and Elson's factors.
        scales::<f64, Full, Partial, GlassFromBelow>(&[-300.0, -150.0, 0.0, 150.0, 300.0]);
        scales::<f32, Full, Partial, GlassFromBelow>(&[-36.0, -20.0, 0.0, 20.0, 36.0]);
        scales::<f64, OneShape, Incoherent, GlassFromBelow>(&[-300.0, 0.0, 300.0]);
        scales::<f32, Intensity, Partial, GlassFromBelow>(&[-36.0, 0.0, 36.0]);
    }
}
