//! Batches over wavelengths as well as directions: [`Kernel::evaluate_batch_spectral`], for the
//! 4–8 wavelengths a hero-wavelength renderer carries along one path.
//!
//! The wavelengths share the path's direction, so they share the exit geometry: r̂, `cos θ_o`
//! and the exit s/p frame are computed once per vector of exits, then the lobes of each
//! wavelength (its index, wavenumber, Stokes vector and coherence shapes) from them. On the
//! lane path of [`Kernel::evaluate_batch`] (see there: first order, and the Kirchhoff series
//! of a Gaussian PSD with partial coherence, each wavelength with its own orders) that is one
//! pass over the exits for up to [`MAX_WAVELENGTHS`] wavelengths; elsewhere the wavelengths go
//! one [`Kernel::evaluate_batch`] after another.

use nalgebra::Vector3;

use super::DirectionsSoa;
use super::outputs::{ExitFramesSoa, LobesSoa, check_lengths};
use super::partial::{PartialLobes, lane_prep, scalar_exit, series_prep};
use super::prep::{LobePrep, SERIES_MIN_EXITS, SeriesPrep};
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::coherence::{CoherenceModel, CoherenceWeights};
use crate::interaction::polarization::PolarizationModel;
use crate::interaction::prepared::PreparedPacket;
use crate::interaction::roughness::{RoughnessModel, RoughnessWeights};
use crate::interaction::{Kernel, Surface};
use crate::packet::WavePacket;
use crate::real::Real;

/// At most this many wavelengths share one pass over the exits; more are taken this many at a
/// time.
pub const MAX_WAVELENGTHS: usize = 8;

/// One wavelength of a spectral batch: its material (the index at this wavelength), its packet
/// (wavelength, Stokes vector, coherence shapes; the direction of every wavelength's packet must
/// be the same) and, for a dielectric interface, its relative index.
#[derive(Debug)]
pub struct Wavelength<'a, T: Real, S> {
    /// The surface at this wavelength.
    pub material: &'a S,
    /// The incident packet at this wavelength.
    pub packet: &'a WavePacket<T>,
    /// `interface` of [`Kernel::evaluate_batch`]: `None` in reflection, `Some(η)` at a
    /// dielectric interface.
    pub interface: Option<T>,
}

impl<T: Real, S> Clone for Wavelength<'_, T, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T: Real, S> Copy for Wavelength<'_, T, S> {}

impl<Pol: PolarizationModel, Coh: CoherenceModel, Rough: RoughnessModel> Kernel<Pol, Coh, Rough> {
    /// [`Kernel::evaluate_batch`] for several wavelengths along one path: `outs[w]` receives
    /// the lobes of `wavelengths[w]` for every exit of `exits`, and `frames` (when given) the
    /// exit s/p frames, which do not depend on the wavelength.
    ///
    /// Entry `i` of `outs[w]` equals, bit for bit, entry `i` of
    /// `kernel.evaluate_batch(w.material, w.packet, surface, w.interface, exits, ..)`: the
    /// same stages on the same inputs, with the exit geometry computed once for all the
    /// wavelengths of a pass (lane path) — so the documented bound of `evaluate_batch` against
    /// the per-direction kernel holds for each wavelength. That holds at every roughness level:
    /// with the Kirchhoff series in lanes each wavelength has its own series constants (its
    /// `vσ`, orders and sections), and the pass groups the exits into the same vectors as
    /// `evaluate_batch`.
    ///
    /// # Errors
    /// - [`Error::OutOfRange`] when `outs` and `wavelengths` differ in length, when a slice of
    ///   an output is shorter than `exits` (nothing is written then), or when the packets do
    ///   not all travel in the same direction (they share the exit geometry).
    /// - Every error of [`Kernel::evaluate_batch`], for the first wavelength that reports one.
    ///   Treat `outs` as unspecified after an error.
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::batch::{DirectionsSoa, LobesSoa, StokesSoa, Wavelength};
    /// use gmueller::interaction::{Full, Kernel, Partial, RoughConductor};
    /// use gmueller::packet::{CoherenceShape, WavePacket};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    /// use num_complex::Complex;
    ///
    /// let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z())?;
    /// let psd = GaussianPsd::<f32, 2>::isotropic(0.01, 2.0)?;
    /// let travel = Vector3::new(0.5, 0.0, -(0.75_f32).sqrt());
    /// // Gold at two wavelengths (µm), the same path.
    /// let gold = [
    ///     RoughConductor::new(psd, Complex::new(0.47, 2.4))?,
    ///     RoughConductor::new(psd, Complex::new(0.16, 3.8))?,
    /// ];
    /// let packets = [0.5_f32, 0.65].map(|lambda| {
    ///     WavePacket::from_stokes(Stokes::unpolarized(1.0).unwrap(),
    ///         CoherenceShape::isotropic(10.0).unwrap(),
    ///         Frame::sp(travel, Vector3::z()).unwrap(), lambda).unwrap()
    /// });
    /// let wavelengths = [0, 1].map(|w| Wavelength {
    ///     material: &gold[w], packet: &packets[w], interface: None });
    /// let (x, y, z) = ([0.5, 0.3], [0.0, 0.1], [0.87, 0.95]);
    /// let exits = DirectionsSoa { x: &x, y: &y, z: &z };
    /// let mut buf = [[0.0_f32; 2]; 16];
    /// let (first, second) = buf.split_at_mut(8);
    /// fn soa(b: &mut [[f32; 2]]) -> LobesSoa<'_, f32> {
    ///     let [a, b, c, d, e, f, g, h] = b else { unreachable!() };
    ///     LobesSoa { specular: StokesSoa { s: [a, b, c, d] },
    ///                scattered: StokesSoa { s: [e, f, g, h] } }
    /// }
    /// let mut outs = [soa(first), soa(second)];
    /// Kernel::<Full, Partial>::default()
    ///     .evaluate_batch_spectral(&wavelengths, &surface, exits, &mut outs, None)?;
    /// assert!(outs[1].scattered.s[0][0] > 0.0);
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn evaluate_batch_spectral<T, S>(
        &self,
        wavelengths: &[Wavelength<'_, T, S>],
        surface: &Frame<T>,
        exits: DirectionsSoa<'_, T>,
        outs: &mut [LobesSoa<'_, T>],
        mut frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        if outs.len() != wavelengths.len() {
            return Err(Error::OutOfRange {
                what: "number of spectral outputs",
                value: outs.len() as f64,
                expected: "one LobesSoa per wavelength",
            });
        }
        check_lengths(&exits, outs, frames.as_deref())?;
        let Some(first) = wavelengths.first() else {
            return Ok(());
        };
        let direction = first.packet.direction();
        if let Some(w) = wavelengths
            .iter()
            .position(|w| w.packet.direction() != direction)
        {
            return Err(Error::OutOfRange {
                what: "wavelength whose packet direction differs from the first's",
                value: w as f64,
                expected: "the same direction for every wavelength",
            });
        }
        for (chunk, (ws, os)) in wavelengths
            .chunks(MAX_WAVELENGTHS)
            .zip(outs.chunks_mut(MAX_WAVELENGTHS))
            .enumerate()
        {
            // The exit frames once, with the first pass.
            let frames = if chunk == 0 {
                frames.as_deref_mut()
            } else {
                None
            };
            self.spectral_pass(ws, surface, exits, os, frames)?;
        }
        Ok(())
    }

    /// One pass over the exits for at most [`MAX_WAVELENGTHS`] wavelengths of one direction.
    fn spectral_pass<T, S>(
        &self,
        ws: &[Wavelength<'_, T, S>],
        surface: &Frame<T>,
        exits: DirectionsSoa<'_, T>,
        outs: &mut [LobesSoa<'_, T>],
        frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        let mut prepared = [const { None }; MAX_WAVELENGTHS];
        let mut preps: [Option<LobePrep<T>>; MAX_WAVELENGTHS] = [None; MAX_WAVELENGTHS];
        let mut lanes = true;
        for (w, wl) in ws.iter().enumerate() {
            let facing = match wl.interface {
                Some(_) => surface.facing(&-wl.packet.direction()),
                None => *surface,
            };
            let p = self.prepare(wl.packet, &facing)?;
            preps[w] = lane_prep(self, wl.material, &p, wl.packet, surface, wl.interface);
            prepared[w] = Some(p);
            // One pass validates the exits once for all: the same side rule (every wavelength
            // at an interface, or none).
            lanes &= wl.interface.is_some() == ws[0].interface.is_some() && preps[w].is_some();
        }
        let pass = Pass {
            ws,
            prepared: &prepared,
            preps: &preps,
            surface,
            exits,
        };
        let with_series = self.roughness().lane_series().is_some();
        // A call of fewer than `SERIES_MIN_EXITS` exits takes the series one exit at a time.
        lanes &= !with_series || exits.len() >= SERIES_MIN_EXITS;
        if lanes && with_series {
            // The series' constants of every wavelength (up to 62 KB in f64: built only for
            // the series).
            let mut series = [const { None }; MAX_WAVELENGTHS];
            for (w, sp) in series.iter_mut().enumerate().take(ws.len()) {
                let (Some(p), Some(prep)) = (&prepared[w], &preps[w]) else {
                    unreachable!("every wavelength has lane constants")
                };
                match series_prep(self, ws[w].material, p, prep) {
                    Some(Some(c)) => *sp = Some(c),
                    _ => lanes = false,
                }
            }
            if lanes {
                return self.lanes_pass(&pass, &series[..ws.len()], outs, frames);
            }
        }
        if !lanes {
            let mut frames = frames;
            for (w, (wl, out)) in ws.iter().zip(outs.iter_mut()).enumerate() {
                let f = if w == 0 { frames.as_deref_mut() } else { None };
                self.evaluate_batch(wl.material, wl.packet, surface, wl.interface, exits, out, f)?;
            }
            return Ok(());
        }
        self.lanes_pass(&pass, &[], outs, frames)
    }

    /// The lane path of one pass: every wavelength has its lane constants (and, with the
    /// series, `series[w]`).
    fn lanes_pass<T, S>(
        &self,
        pass: &Pass<'_, '_, '_, T, S, Pol, Coh>,
        series: &[Option<SeriesPrep<T>>],
        outs: &mut [LobesSoa<'_, T>],
        frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        let Pass {
            ws,
            prepared,
            preps,
            surface,
            exits,
        } = *pass;
        // Every wavelength has its constants: gather them contiguously.
        let Some(Some(p0)) = preps.first().copied() else {
            return Ok(());
        };
        let mut gathered = [p0; MAX_WAVELENGTHS];
        for (g, p) in gathered.iter_mut().zip(preps.iter().take(ws.len())) {
            if let Some(p) = p {
                *g = *p;
            }
        }
        let mut scalar = |w: usize, i: usize| {
            let exit = Vector3::new(exits.x[i], exits.y[i], exits.z[i]);
            let p = prepared[w].as_ref().ok_or(Error::OutOfRange {
                what: "wavelength index",
                value: w as f64,
                expected: "a prepared wavelength",
            })?;
            let wl = &ws[w];
            scalar_exit(
                self,
                wl.material,
                p,
                wl.packet,
                (surface, wl.interface),
                exit,
            )
        };
        crate::simd::dispatch(PartialLobes {
            series,
            preps: &gathered[..ws.len()],
            exits,
            outs,
            frames,
            scalar: &mut scalar,
        })
    }
}

/// What a lane pass of [`Kernel::evaluate_batch_spectral`] reads: the wavelengths, their
/// prepared packets and lane constants, the surface and the exits.
struct Pass<'p, 'w, 'e, T: Real, S, Pol: PolarizationModel, Coh: CoherenceModel> {
    ws: &'p [Wavelength<'w, T, S>],
    prepared: &'p [Option<PreparedPacket<T, Pol, Coh>>; MAX_WAVELENGTHS],
    preps: &'p [Option<LobePrep<T>>; MAX_WAVELENGTHS],
    surface: &'p Frame<T>,
    exits: DirectionsSoa<'e, T>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interaction::batch::StokesSoa;
    use crate::interaction::pbsdf::Pbsdf;
    use crate::interaction::{
        Full, Incoherent, Intensity, OneShape, Partial, PlaneWave, RoughConductor, RoughDielectric,
        RoughSurface,
    };
    use crate::packet::CoherenceShape;
    use crate::psd::{GaussianPsd, Psd};
    use crate::stokes::Stokes;
    use num_complex::Complex;

    /// 37 exits: around the mirror direction, at and near the normal (redone by the
    /// per-direction kernel), grazing, φ ≠ 0; mirrored below the surface when `below`.
    fn exits<T: Real>(below: bool) -> [Vec<T>; 3] {
        let mut d: [Vec<T>; 3] = Default::default();
        for i in 0..37 {
            let (theta, phi) = match i {
                0 => (0.0, 0.0),
                1 => (1e-9, 0.3),
                2 => (1.5607, -2.0),
                _ => (0.2 + 0.03 * f64::from(i), 0.05 * f64::from(i) - 0.9),
            };
            let z = if below && i % 2 == 1 {
                -theta.cos()
            } else {
                theta.cos()
            };
            let v = [theta.sin() * phi.cos(), theta.sin() * phi.sin(), z];
            for (c, v) in d.iter_mut().zip(v) {
                c.push(T::lit(v));
            }
        }
        d
    }

    /// `w` wavelengths of one path: each its own λ, Stokes vector and shapes.
    fn packets<T: Real>(w: usize) -> Vec<WavePacket<T>> {
        let travel = Vector3::new(T::lit(0.45), T::lit(0.12), -T::lit(0.88)).normalize();
        let frame = Frame::sp(travel, Vector3::z()).unwrap();
        (0..w)
            .map(|j| {
                let f = T::lit(j as f64);
                let s = Stokes::new(
                    T::one() + f,
                    T::lit(0.3),
                    -T::lit(0.2) * f / T::lit(8.0),
                    T::lit(0.4),
                )
                .unwrap();
                let sx = CoherenceShape::isotropic(T::lit(5.0) + f).unwrap();
                let sy = CoherenceShape::isotropic(T::lit(6.5) + f * T::lit(0.5)).unwrap();
                let lambda = T::lit(0.4) + T::lit(0.04) * f;
                if j % 3 == 2 {
                    WavePacket::from_stokes(s, sx, frame, lambda).unwrap()
                } else {
                    WavePacket::new(s, sx, sy, frame, lambda).unwrap()
                }
            })
            .collect()
    }

    type Columns<T> = Vec<Vec<T>>;

    /// `n` wavelengths' lobes (8 columns each) and one set of frames (3 columns).
    fn buffers<T: Real>(w: usize, n: usize) -> (Vec<Columns<T>>, Columns<T>) {
        (
            vec![vec![vec![T::lit(-7.0); n]; 8]; w],
            vec![vec![T::lit(-7.0); n]; 3],
        )
    }

    fn soa<T>(cols: &mut [Vec<T>]) -> LobesSoa<'_, T> {
        let [a, b, c, d, e, f, g, h] = cols else {
            unreachable!()
        };
        LobesSoa {
            specular: StokesSoa { s: [a, b, c, d] },
            scattered: StokesSoa { s: [e, f, g, h] },
        }
    }

    fn frames<T>(cols: &mut [Vec<T>]) -> ExitFramesSoa<'_, T> {
        let [a, b, c] = cols else { unreachable!() };
        ExitFramesSoa { s: [a, b, c] }
    }

    /// The spectral batch equals `evaluate_batch` per wavelength bit for bit, lobes and frames,
    /// for `counts` wavelengths; returns the number of lit scattered entries and of wavelengths
    /// with lane constants (`lane_prep`).
    fn same_as_one_by_one<T, Pol, Coh, P, Sp, Sc>(
        materials: &[RoughSurface<P, Sp, Sc>],
        interface: Option<T>,
        counts: &[usize],
    ) -> (usize, usize)
    where
        T: Real,
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P> + CoherenceModel + Default,
        P: Psd<T, 2>,
        Sp: Pbsdf<T>,
        Sc: Pbsdf<T>,
    {
        same_with(Kernel::<Pol, Coh>::default(), materials, interface, counts)
    }

    /// [`same_as_one_by_one`] for `kernel` at any roughness level; a wavelength counts as in
    /// the lanes when it has lane constants and, for the series, the series' constants.
    fn same_with<T, Pol, Coh, Rough, P, Sp, Sc>(
        kernel: Kernel<Pol, Coh, Rough>,
        materials: &[RoughSurface<P, Sp, Sc>],
        interface: Option<T>,
        counts: &[usize],
    ) -> (usize, usize)
    where
        T: Real,
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P> + CoherenceModel,
        Rough: RoughnessWeights<T, P, Coh>,
        P: Psd<T, 2>,
        Sp: Pbsdf<T>,
        Sc: Pbsdf<T>,
    {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let d = exits::<T>(interface.is_some());
        let n = d[0].len();
        let dirs = DirectionsSoa {
            x: &d[0],
            y: &d[1],
            z: &d[2],
        };
        let (mut lit, mut lanes_taken) = (0, 0);
        for &count in counts {
            let ps = packets::<T>(count);
            let ws: Vec<_> = ps
                .iter()
                .enumerate()
                .map(|(j, p)| Wavelength {
                    material: &materials[j % materials.len()],
                    packet: p,
                    interface,
                })
                .collect();
            let (mut lobes, mut fr) = buffers::<T>(count, n);
            let mut outs: Vec<_> = lobes.iter_mut().map(|c| soa(c)).collect();
            kernel
                .evaluate_batch_spectral(&ws, &surface, dirs, &mut outs, Some(&mut frames(&mut fr)))
                .unwrap();
            drop(outs);
            for (j, w) in ws.iter().enumerate() {
                // Whether this wavelength has lane constants (else the pass loops).
                {
                    let facing = match interface {
                        Some(_) => surface.facing(&-w.packet.direction()),
                        None => surface,
                    };
                    let prepared = kernel.prepare(w.packet, &facing).unwrap();
                    let prep = super::lane_prep(
                        &kernel, w.material, &prepared, w.packet, &surface, interface,
                    );
                    let lanes = prep.is_some_and(|p| {
                        !matches!(series_prep(&kernel, w.material, &prepared, &p), Some(None))
                    });
                    lanes_taken += usize::from(lanes);
                }
                let (mut one, mut fr1) = buffers::<T>(1, n);
                kernel
                    .evaluate_batch(
                        w.material,
                        w.packet,
                        &surface,
                        interface,
                        dirs,
                        &mut soa(&mut one[0]),
                        Some(&mut frames(&mut fr1)),
                    )
                    .unwrap();
                for (k, (a, b)) in lobes[j].iter().zip(&one[0]).enumerate() {
                    for i in 0..n {
                        assert_eq!(
                            a[i].to_f64().to_bits(),
                            b[i].to_f64().to_bits(),
                            "{count} wavelengths: wavelength {j} column {k} exit {i}"
                        );
                    }
                }
                assert_eq!(fr, fr1, "{count} wavelengths: frames");
                lit += lobes[j][4].iter().filter(|v| **v > T::zero()).count();
            }
        }
        (lit, lanes_taken)
    }

    fn conductors<T: Real>() -> Vec<RoughConductor<T, GaussianPsd<T, 2>>> {
        [(0.47, 2.4), (0.16, 3.8), (1.2, 7.0)]
            .iter()
            .zip([0.02, 0.015, 0.03])
            .map(|(&(re, im), h)| {
                RoughConductor::new(
                    GaussianPsd::<T, 2>::isotropic(T::lit(h), T::lit(1.8)).unwrap(),
                    Complex::new(T::lit(re), T::lit(im)),
                )
                .unwrap()
            })
            .collect()
    }

    /// The lit entries at every lane level; every wavelength must have lane constants.
    macro_rules! every_lane_level {
        ($t:ty, $m:expr, $counts:expr) => {{
            let m = $m;
            let all: usize = $counts.iter().sum();
            let runs = [
                same_as_one_by_one::<$t, Full, Partial, _, _, _>(&m, None, $counts),
                same_as_one_by_one::<$t, Full, Incoherent, _, _, _>(&m, None, $counts),
                same_as_one_by_one::<$t, OneShape, Partial, _, _, _>(&m, None, $counts),
                same_as_one_by_one::<$t, OneShape, Incoherent, _, _, _>(&m, None, $counts),
                same_as_one_by_one::<$t, Intensity, Partial, _, _, _>(&m, None, $counts),
                same_as_one_by_one::<$t, Intensity, Incoherent, _, _, _>(&m, None, $counts),
            ];
            for (level, (_, lanes)) in runs.iter().enumerate() {
                assert_eq!(*lanes, all, "level {level}: wavelengths outside the lanes");
            }
            runs.iter().map(|r| r.0).sum::<usize>()
        }};
    }

    #[test]
    fn the_lane_path_equals_one_wavelength_at_a_time_bit_for_bit() {
        let counts = [1, 3, 8, 11];
        let lit = every_lane_level!(f64, conductors::<f64>(), &counts);
        assert!(lit > 3000, "only {lit} lit entries");
        // f32: more of the far tails underflow to 0 (of 5106 entries per type).
        let lit = every_lane_level!(f32, conductors::<f32>(), &counts);
        assert!(lit > 2000, "only {lit} lit entries (f32)");
    }

    #[test]
    fn other_levels_and_interfaces_equal_one_wavelength_at_a_time() {
        let counts = [2, 9];
        let glass = |eta: f64| {
            RoughDielectric::new(GaussianPsd::<f64, 2>::isotropic(0.02, 1.5).unwrap(), eta).unwrap()
        };
        let g = [glass(1.5), glass(1.52)];
        let lit = same_as_one_by_one::<f64, Full, Partial, _, _, _>(&g, Some(1.5), &counts).0
            + same_as_one_by_one::<f64, Intensity, Incoherent, _, _, _>(&g, Some(1.5), &counts).0;
        assert!(lit > 100, "only {lit} lit entries");
        let (lit, lanes) = same_as_one_by_one::<f64, Full, PlaneWave, _, _, _>(
            &conductors::<f64>(),
            None,
            &counts,
        );
        assert_eq!(lanes, 0, "the plane wave has no lane path");
        assert!(lit > 100, "only {lit} lit entries (plane wave)");
    }

    /// The Kirchhoff series in lanes (a Gaussian PSD, partially coherent): rough gold, copper
    /// and tungsten at `vσ` ≈ 1.6–3 and glass lit from above, three levels, 1–11 wavelengths.
    #[test]
    fn the_series_lanes_equal_one_wavelength_at_a_time_bit_for_bit() {
        use crate::interaction::roughness::KirchhoffSeries;
        fn rough<T: Real>(
            m: &RoughConductor<T, GaussianPsd<T, 2>>,
        ) -> RoughConductor<T, GaussianPsd<T, 2>> {
            let psd =
                GaussianPsd::<T, 2>::isotropic(m.psd.variance().sqrt() * T::lit(3.0), T::lit(1.8));
            RoughSurface {
                psd: psd.unwrap(),
                ..*m
            }
        }
        fn run<T: Real>(tol: f64) -> usize {
            let metals: Vec<_> = conductors::<T>().iter().map(rough).collect();
            let glass: Vec<_> = [1.5, 1.52]
                .map(|eta| {
                    let psd = GaussianPsd::<T, 2>::isotropic(T::lit(0.06), T::lit(1.5)).unwrap();
                    RoughDielectric::new(psd, T::lit(eta)).unwrap()
                })
                .to_vec();
            let series = KirchhoffSeries::new(tol).unwrap();
            let counts = [1, 3, 8, 11];
            let all: usize = counts.iter().sum();
            let runs = [
                same_with(
                    Kernel::<Full, Partial>::default().with_roughness(series),
                    &metals,
                    None,
                    &counts,
                ),
                same_with(
                    Kernel::<OneShape, Partial>::default().with_roughness(series),
                    &metals,
                    None,
                    &counts,
                ),
                same_with(
                    Kernel::<Intensity, Partial>::default().with_roughness(series),
                    &metals,
                    None,
                    &counts,
                ),
                same_with(
                    Kernel::<Full, Partial>::default().with_roughness(series),
                    &glass,
                    Some(T::lit(1.5)),
                    &counts,
                ),
            ];
            for (level, (_, lanes)) in runs.iter().enumerate() {
                assert_eq!(
                    *lanes, all,
                    "run {level}: wavelengths outside the series lanes"
                );
            }
            runs.iter().map(|r| r.0).sum()
        }
        let lit = run::<f64>(1e-10);
        assert!(lit > 2000, "only {lit} lit entries");
        let lit = run::<f32>(1e-6);
        assert!(lit > 1500, "only {lit} lit entries (f32)");
    }

    #[test]
    fn bad_spectral_batches_are_rejected() {
        let kernel = Kernel::<Full, Partial>::default();
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let m = conductors::<f64>();
        let d = exits::<f64>(false);
        let n = d[0].len();
        let dirs = DirectionsSoa {
            x: &d[0],
            y: &d[1],
            z: &d[2],
        };
        let mut ps = packets::<f64>(3);
        fn wavelengths<'a, T: Real, P, Sp, Sc>(
            m: &'a RoughSurface<P, Sp, Sc>,
            ps: &'a [WavePacket<T>],
        ) -> Vec<Wavelength<'a, T, RoughSurface<P, Sp, Sc>>> {
            ps.iter()
                .map(|p| Wavelength {
                    material: m,
                    packet: p,
                    interface: None,
                })
                .collect()
        }

        // Fewer outputs than wavelengths.
        let (mut lobes, _) = buffers::<f64>(2, n);
        let mut outs: Vec<_> = lobes.iter_mut().map(|c| soa(c)).collect();
        let r = kernel.evaluate_batch_spectral(
            &wavelengths(&m[0], &ps),
            &surface,
            dirs,
            &mut outs,
            None,
        );
        assert!(matches!(r, Err(Error::OutOfRange { .. })), "{r:?}");
        drop(outs);
        // A short slice in the last output: nothing written anywhere.
        let (mut lobes, _) = buffers::<f64>(3, n);
        lobes[2][5].pop();
        let mut outs: Vec<_> = lobes.iter_mut().map(|c| soa(c)).collect();
        let r = kernel.evaluate_batch_spectral(
            &wavelengths(&m[0], &ps),
            &surface,
            dirs,
            &mut outs,
            None,
        );
        assert!(matches!(r, Err(Error::OutOfRange { .. })), "{r:?}");
        drop(outs);
        assert!(lobes.iter().flatten().flatten().all(|&v| v == -7.0));
        // A packet in another direction.
        let travel = Vector3::new(0.4, 0.12, -0.88).normalize();
        ps[1] = WavePacket::from_stokes(
            Stokes::unpolarized(1.0).unwrap(),
            CoherenceShape::isotropic(5.0).unwrap(),
            Frame::sp(travel, Vector3::z()).unwrap(),
            0.5,
        )
        .unwrap();
        let (mut lobes, _) = buffers::<f64>(3, n);
        let mut outs: Vec<_> = lobes.iter_mut().map(|c| soa(c)).collect();
        let r = kernel.evaluate_batch_spectral(
            &wavelengths(&m[0], &ps),
            &surface,
            dirs,
            &mut outs,
            None,
        );
        assert!(
            matches!(r, Err(Error::OutOfRange { value, .. }) if value == 1.0),
            "{r:?}"
        );
        // No wavelengths: nothing to do.
        let r =
            kernel.evaluate_batch_spectral(&wavelengths(&m[0], &[]), &surface, dirs, &mut [], None);
        assert!(r.is_ok());
    }
}
