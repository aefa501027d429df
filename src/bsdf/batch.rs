//! A forward bounce over a batch of draws: [`Bsdf::sample_exit_batch`] draws exit directions
//! for one light packet ([`LobeSampler::sample_batch`]) and weighs them with the kernel's batch
//! path ([`Kernel::evaluate_batch`](crate::interaction::Kernel::evaluate_batch)), both in SIMD lanes where they have them.
//!
//! # Formula
//! The weight of draw `i` is what [`Bsdf::sample_exit`] gives for the same uniforms, applied
//! to the packet's Stokes vector `S` (in the packet's frame; the result in the exit s/p frame of
//! `r̂ᵢ`, [`crate::interaction::Geometry::exit_sp`]):
//! ```text
//! Wᵢ = (M_spec(r̂ᵢ) S / E_side + M_scat(r̂ᵢ) S) · cos θ_o / (cos θ_i · pᵢ)
//! ```
//! `E_side` the coherent lobe's mass on the draw's side ([`super::Incident::specular_mass`]); a
//! Dirac lobe's weight is its integral ([`Bsdf::exit_weight`]) applied to `S`, per draw. At the
//! intensity levels only `S0` is written (the other three are set to 0). The weights come from
//! the kernel's batch evaluation at first order and with the Kirchhoff series (in lanes for a
//! Gaussian PSD, [`Kernel::evaluate_batch`](crate::interaction::Kernel::evaluate_batch)); at the other roughness levels (geometric,
//! quadrature) every draw is weighed by [`Bsdf::exit_weight`] (the draws are still batched).
//!
//! # Agreement
//! The lanes' weights equal `exit_weight(..).to_mueller() · S` of the scalar path to the batch
//! evaluation's bound and the lanes' pdf (`f64`: 10⁻¹⁰ relative of `W₀` is asserted; `f32`:
//! 2⁻¹⁰, `tests/bsdf/sample_batch.rs`); with the Kirchhoff series, plus the series' tolerance
//! (the batch and the scalar sums are each within half of it of the whole series).

use nalgebra::{Vector3, Vector4};

use super::SurfaceCoherence;
use crate::interaction::polarization::KernelOutput;

use super::model::BsdfSurface;
use super::sampler::{NO_LOBE, SampledLobe, SamplesSoa, UniformsSoa};
use super::{Bsdf, BsdfKernel, LobeSampler};
use crate::error::Error;
use crate::interaction::Side;
use crate::interaction::batch::check_lengths;
use crate::interaction::batch::clearly_valid_about;
use crate::interaction::batch::{DirectionsSoa, ExitFramesSoa, LobesSoa, StokesSoa};
use crate::interaction::polarization::{PolarizationLevel, PolarizationModel, Throughput};
use crate::interaction::roughness::{RoughnessLevel, RoughnessModel};
use crate::numerics::unit_direction;
use crate::packet::WavePacket;
use crate::real::Real;

/// Exits per call of the batch evaluation (its buffers live on the stack).
const CHUNK: usize = 128;

impl<'m, T, S, K> Bsdf<'m, T, S, K>
where
    T: Real,
    S: BsdfSurface<T>,
    K: BsdfKernel<T, S::Psd>,
    K::Coh: Clone,
{
    /// A forward bounce for every element of `u`: the exit direction drawn for the light
    /// `packet` ([`Bsdf::exit_sampler`] of its [`Bsdf::prepare`], [`LobeSampler::sample_batch`])
    /// into `samples`, and its weight `W` applied to the packet's Stokes vector (module docs of
    /// `bsdf::batch`) into `weights`, in the exit s/p frame of each draw: the Stokes power
    /// fraction the draw carries, whose mean over draws is the packet's albedo. An element with
    /// no direction has weight 0. Allocates nothing (its buffers are on the stack).
    ///
    /// # Errors
    /// As [`Bsdf::prepare`], [`Bsdf::exit_sampler`] and [`LobeSampler::sample_batch`];
    /// [`Error::OutOfRange`] when a slice of `weights` is shorter than `u`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::bsdf::{Bsdf, SamplesSoa, SurfaceCoherence, UniformsSoa};
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::batch::StokesSoa;
    /// use gmueller::interaction::{Full, Kernel, Partial, RoughConductor};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::spectral::Metal;
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    ///
    /// let gold = RoughConductor::new(GaussianPsd::isotropic(0.02, 1.0)?, Metal::Au.index(0.55_f64))?;
    /// let bsdf = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), Frame::from_normal(Vector3::z())?, 0.55)?;
    /// let sky = SurfaceCoherence::new(5.0)?;
    /// let packet = bsdf.surface_packet(Stokes::unpolarized(1.0)?, Vector3::new(0.4, 0.0, 0.9), &sky)?;
    /// let (lobe, u0, u1) = ([0.1, 0.7], [0.2, 0.5], [0.3, 0.6]);
    /// let [mut x, mut y, mut z, mut pdf, mut dw] = [[0.0_f64; 2]; 5];
    /// let mut code = [0_u8; 2];
    /// let [mut s0, mut s1, mut s2, mut s3] = [[0.0_f64; 2]; 4];
    /// bsdf.sample_exit_batch(
    ///     &packet,
    ///     UniformsSoa { lobe: &lobe, u0: &u0, u1: &u1 },
    ///     SamplesSoa { x: &mut x, y: &mut y, z: &mut z, pdf: &mut pdf,
    ///                  delta_weight: &mut dw, lobe: &mut code },
    ///     StokesSoa { s: [&mut s0, &mut s1, &mut s2, &mut s3] },
    /// )?;
    /// let inc = bsdf.prepare(&packet)?;
    /// let one = bsdf.sample_exit(&inc, lobe[0], [u0[0], u1[0]])?.unwrap();
    /// let w = one.weight.apply(&packet.stokes());
    /// assert!((s0[0] - w.s0()).abs() <= 1e-10 * w.s0());
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    #[expect(
        clippy::needless_range_loop,
        reason = "element i of a chunk in six sample slices, 3 + 8 buffers and four weights"
    )]
    pub fn sample_exit_batch(
        &self,
        packet: &WavePacket<T>,
        u: UniformsSoa<'_, T>,
        samples: SamplesSoa<'_, T>,
        weights: StokesSoa<'_, T>,
    ) -> Result<(), Error> {
        let n = u.lobe.len();
        if weights.s.iter().any(|w| w.len() < n) {
            return Err(Error::OutOfRange {
                what: "batch slice length",
                value: n as f64,
                expected: "weight slices at least as long as the uniforms",
            });
        }
        let incident = self.prepare(packet)?;
        let sampler: LobeSampler<'_, T> = self.exit_sampler(&incident)?;
        let SamplesSoa {
            x,
            y,
            z,
            pdf,
            delta_weight,
            lobe,
        } = samples;
        sampler.sample_batch(
            u,
            SamplesSoa {
                x: &mut *x,
                y: &mut *y,
                z: &mut *z,
                pdf: &mut *pdf,
                delta_weight: &mut *delta_weight,
                lobe: &mut *lobe,
            },
        )?;
        let StokesSoa {
            s: [w0, w1, w2, w3],
        } = weights;
        let normal = self.surface.k();
        let cos_i = incident.to_source.dot(&normal).abs();
        let mass = [
            incident.specular_mass(Side::Reflection),
            incident.specular_mass(Side::Transmission),
        ];
        let light = packet.stokes();
        let intensity = K::Pol::LEVEL == PolarizationLevel::Intensity;
        // The batch evaluation at first order and for the Kirchhoff series (both in lanes
        // where `evaluate_batch` has them); at the other roughness levels every draw is
        // weighed by `exit_weight`.
        let first = matches!(
            <K::Rough as RoughnessModel>::LEVEL,
            RoughnessLevel::FirstOrder | RoughnessLevel::KirchhoffSeries
        )
        .then(|| self.kernel.kernel());
        // A direction the evaluation accepts, for the elements it must skip.
        let stand_in = incident.to_source;
        let mut start = 0;
        while start < n {
            let m = CHUNK.min(n - start);
            let mut dirs = [[T::zero(); CHUNK]; 3];
            let mut lobes = [[T::zero(); CHUNK]; 8];
            for i in 0..m {
                let j = start + i;
                let drawn = first.is_some() && lobe[j] != NO_LOBE && delta_weight[j] == T::zero();
                let d = if drawn {
                    Vector3::new(x[j], y[j], z[j])
                } else {
                    stand_in
                };
                (dirs[0][i], dirs[1][i], dirs[2][i]) = (d.x, d.y, d.z);
            }
            if let Some(kernel) = &first {
                let [dx, dy, dz] = &dirs;
                let [a0, a1, a2, a3, b0, b1, b2, b3] = &mut lobes;
                let mut out = LobesSoa {
                    specular: StokesSoa {
                        s: [&mut a0[..m], &mut a1[..m], &mut a2[..m], &mut a3[..m]],
                    },
                    scattered: StokesSoa {
                        s: [&mut b0[..m], &mut b1[..m], &mut b2[..m], &mut b3[..m]],
                    },
                };
                let exits = DirectionsSoa {
                    x: &dx[..m],
                    y: &dy[..m],
                    z: &dz[..m],
                };
                kernel.evaluate_batch(
                    self.material,
                    packet,
                    &self.surface,
                    self.eta,
                    exits,
                    &mut out,
                    None,
                )?;
            }
            for i in 0..m {
                let j = start + i;
                let w = match SampledLobe::from_code(lobe[j]) {
                    None => [T::zero(); 4],
                    Some(l) if l.delta || first.is_none() => {
                        let s = super::DirectionSample {
                            direction: Vector3::new(x[j], y[j], z[j]),
                            pdf: pdf[j],
                            lobe: l,
                            delta_weight: delta_weight[j],
                        };
                        let d = unit_direction(&s.direction, "sampled direction")?;
                        let (t, _) = self.exit_weight_at(&incident, &s, &d)?;
                        let v = t.to_mueller().apply(&light);
                        [v.s0(), v.s1(), v.s2(), v.s3()]
                    }
                    Some(l) => {
                        let e = mass[usize::from(l.side == Side::Transmission)];
                        let d = Vector3::new(x[j], y[j], z[j]);
                        let f = d.dot(&normal).abs() / (cos_i * pdf[j]);
                        core::array::from_fn(|c| (lobes[c][i] / e + lobes[4 + c][i]) * f)
                    }
                };
                w0[j] = w[0];
                (w1[j], w2[j], w3[j]) = if intensity {
                    (T::zero(), T::zero(), T::zero())
                } else {
                    (w[1], w[2], w[3])
                };
            }
            start += m;
        }
        Ok(())
    }

    /// The renderer's light for a batch of pairs: element `i` is
    /// `eval_stokes(&prepare_surface(to_source[i], coherence)?, exits[i])` — unpolarized light
    /// of unit irradiance arriving from `to_source[i]` with the surface coherence
    /// `coherence`, leaving along `exits[i]`, its coherent lobe divided by that light's mass
    /// `E` ([`Bsdf::prepare_surface`], [`super::Incident::specular_mass`]) — written into
    /// `out` (both lobes, Stokes radiances in each exit's s/p frame; at the intensity levels
    /// `S0` only) and, when given, the exit s vectors into `frames`. What a wavefront
    /// renderer's next-event estimation evaluates, every lane its own light direction and
    /// exit.
    ///
    /// On an opaque surface the pairs run through
    /// [`Kernel::evaluate_pairs`](crate::interaction::Kernel::evaluate_pairs) (in SIMD lanes
    /// where it has them, within its bound of the per-pair kernel), and each pair's `E` is then
    /// computed alone; at an interface pair by pair. Allocates nothing (its buffers are on the
    /// stack).
    ///
    /// # Errors
    /// As [`Bsdf::prepare_surface`] and [`Bsdf::eval_stokes`] for the first pair they reject
    /// (on an opaque surface nothing is written then);
    /// [`Error::OutOfRange`] when a slice of `exits`, `out` or `frames` is shorter than
    /// `to_source.x`, or one of `to_source` is.
    ///
    /// # Examples
    /// ```
    /// use gmueller::bsdf::{Bsdf, SurfaceCoherence};
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::batch::{DirectionsSoa, LobesSoa, StokesSoa};
    /// use gmueller::interaction::{Full, Kernel, Partial, RoughConductor};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::spectral::Metal;
    /// use nalgebra::Vector3;
    ///
    /// let gold = RoughConductor::new(GaussianPsd::isotropic(0.02, 1.0)?, Metal::Au.index(0.55_f64))?;
    /// let bsdf = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), Frame::from_normal(Vector3::z())?, 0.55)?;
    /// let sky = SurfaceCoherence::new(20.0)?;
    /// let (sx, sy, sz) = ([0.4, -0.2], [0.0, 0.3], [0.9, 0.8]);
    /// let (rx, ry, rz) = ([-0.4, 0.1], [0.05, -0.3], [0.9, 0.9]);
    /// let mut buf = [[0.0; 2]; 8];
    /// let [a, b, c, d, e, f, g, h] = &mut buf;
    /// let mut out = LobesSoa {
    ///     specular: StokesSoa { s: [a, b, c, d] },
    ///     scattered: StokesSoa { s: [e, f, g, h] },
    /// };
    /// bsdf.eval_stokes_pairs(
    ///     &sky,
    ///     DirectionsSoa { x: &sx, y: &sy, z: &sz },
    ///     DirectionsSoa { x: &rx, y: &ry, z: &rz },
    ///     &mut out,
    ///     None,
    /// )?;
    /// let light = bsdf.prepare_surface(Vector3::new(sx[1], sy[1], sz[1]), &sky)?;
    /// let one = bsdf.eval_stokes(&light, Vector3::new(rx[1], ry[1], rz[1]))?;
    /// assert!((out.scattered.s[0][1] - one.scattered.s0()).abs() <= 1e-12 * one.scattered.s0());
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn eval_stokes_pairs(
        &self,
        coherence: &SurfaceCoherence<T>,
        to_source: DirectionsSoa<'_, T>,
        exits: DirectionsSoa<'_, T>,
        out: &mut LobesSoa<'_, T>,
        mut frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error> {
        let n = to_source.len();
        if to_source.y.len() < n || to_source.z.len() < n {
            return Err(Error::OutOfRange {
                what: "batch slice length",
                value: n as f64,
                expected: "to_source.y and to_source.z at least as long as to_source.x",
            });
        }
        check_lengths(
            &DirectionsSoa {
                x: &to_source.x[..n],
                y: exits.y,
                z: exits.z,
            },
            core::slice::from_ref(out),
            frames.as_deref(),
        )?;
        if exits.x.len() < n {
            return Err(Error::OutOfRange {
                what: "batch slice length",
                value: n as f64,
                expected: "exits at least as long as to_source.x",
            });
        }
        let at = |d: &DirectionsSoa<'_, T>, i: usize| Vector3::new(d.x[i], d.y[i], d.z[i]);
        let intensity = K::Pol::LEVEL == PolarizationLevel::Intensity;
        let stokes_len = if intensity { 1 } else { 4 };
        if self.eta.is_some() {
            for i in 0..n {
                let light = self.prepare_surface(at(&to_source, i), coherence)?;
                let r = self.eval_stokes(&light, at(&exits, i))?;
                let z = T::zero();
                let (sp, sc) = match r.stokes() {
                    Some((sp, sc)) => (sp.vector(), sc.vector()),
                    None => (
                        Vector4::new(r.specular_intensity(), z, z, z),
                        Vector4::new(r.scattered_intensity(), z, z, z),
                    ),
                };
                for c in 0..stokes_len {
                    out.specular.s[c][i] = sp[c];
                    out.scattered.s[c][i] = sc[c];
                }
                if let Some(f) = frames.as_deref_mut() {
                    let g = self.geometry(at(&to_source, i), at(&exits, i))?;
                    for (col, v) in f.s.iter_mut().zip(g.exit_sp().x().iter()) {
                        col[i] = *v;
                    }
                }
            }
            return Ok(());
        }
        // Every pair validated before anything is written: the directions (as
        // `prepare_surface`) and the geometry (as `eval_stokes`), exactly only where the fast
        // test does not clear both directions (a cleared direction to the source is finite,
        // non-zero and above the surface, so those checks pass too).
        let normal = self.surface.k();
        for i in 0..n {
            let (s, r) = (at(&to_source, i), at(&exits, i));
            let clear = |v: Vector3<T>| clearly_valid_about(&normal, false, v.into());
            if !(clear(s) && clear(r)) {
                self.wavenumber(&unit_direction(&s, "direction to the source")?.into_inner())?;
                self.geometry(s, r)?;
            }
        }
        let kernel = self.kernel.kernel();
        let mut start = 0;
        while start < n {
            let m = CHUNK.min(n - start);
            let end = start + m;
            // Each pair's wavenumber and coherence width, as `prepare_surface` has them.
            let mut inv_w = [T::zero(); CHUNK];
            let mut k = T::zero();
            for (i, w) in inv_w[..m].iter_mut().enumerate() {
                let s = unit_direction(&at(&to_source, start + i), "direction to the source")?;
                k = self.wavenumber(&s)?;
                *w = self.width_of(&s, k, coherence).recip();
            }
            fn sub<'d, T>(
                d: &DirectionsSoa<'d, T>,
                r: core::ops::Range<usize>,
            ) -> DirectionsSoa<'d, T> {
                DirectionsSoa {
                    x: &d.x[r.clone()],
                    y: &d.y[r.clone()],
                    z: &d.z[r],
                }
            }
            let [a0, a1, a2, a3] = &mut out.specular.s;
            let [b0, b1, b2, b3] = &mut out.scattered.s;
            let mut chunk = LobesSoa {
                specular: StokesSoa {
                    s: [
                        &mut a0[start..end],
                        &mut a1[start..end],
                        &mut a2[start..end],
                        &mut a3[start..end],
                    ],
                },
                scattered: StokesSoa {
                    s: [
                        &mut b0[start..end],
                        &mut b1[start..end],
                        &mut b2[start..end],
                        &mut b3[start..end],
                    ],
                },
            };
            let mut chunk_frames = frames.as_deref_mut().map(|f| {
                let [fx, fy, fz] = &mut f.s;
                ExitFramesSoa {
                    s: [
                        &mut fx[start..end],
                        &mut fy[start..end],
                        &mut fz[start..end],
                    ],
                }
            });
            let pairs = crate::interaction::batch::PairsSoa {
                to_source: sub(&to_source, start..end),
                exit: sub(&exits, start..end),
                inverse_width: &inv_w[..m],
            };
            kernel.evaluate_pairs(
                self.material,
                k,
                &self.surface,
                pairs,
                &mut chunk,
                chunk_frames.as_mut(),
            )?;
            // The coherent lobe over its mass, as `eval_stokes`: where the lobe is not zero
            // (a zero stays zero, sign and all, under the positive finite `1/E`; the mass
            // costs a quadrature near grazing, and most pairs lie outside the narrow lobe).
            for (i, w) in inv_w[..m].iter().enumerate() {
                if chunk.specular.s[..stokes_len]
                    .iter()
                    .all(|c| c[i] == T::zero())
                {
                    continue;
                }
                let s = unit_direction(&at(&to_source, start + i), "direction to the source")?;
                let prepared = kernel.prepare_unpolarized_isotropic(k, *w);
                let facing = self.surface.facing(&s);
                let mass = self.specular_mass(&prepared, &s, &facing, false, [true, false])[0];
                if mass != T::one() {
                    let inv = mass.recip();
                    for c in chunk.specular.s.iter_mut().take(stokes_len) {
                        c[i] *= inv;
                    }
                }
            }
            start = end;
        }
        Ok(())
    }
}
