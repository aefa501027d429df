//! The kernel for a batch of (incident, exit) pairs: [`Kernel::evaluate_pairs`], every lane
//! its own direction to the source, its own exit and its own coherence width — what a
//! wavefront renderer's lanes are (each path at its own vertex), for the light its backward
//! weights and its next-event estimation evaluate: unpolarized, of unit `S0`, with the
//! isotropic section `Ξ = I/w²` on the surface ([`crate::bsdf::SurfaceCoherence`]'s packet, in
//! the closed form of `PreparedPacket::unpolarized_isotropic`).
//!
//! # Lanes
//! Per vector of pairs, the per-packet constants that depend on each pair's direction (its
//! [`super::prep::LobePrep`]'s incidence, Fresnel matrix, specular frame and exponent) are
//! built in lanes (`consts`), with the scalar operations in the scalar order, so bit for bit
//! the scalar constants, and so are those of each pair's width (the `½` channel's weights).
//! Where a lane's direction is within `√ε` of the normal (or a constant would not be the
//! scalar one), that vector's constants are built one pair at a time from the closed-form
//! preparation and gathered
//! ([`super::per_lane::Gathered`]). Then the lobe stages of `super::partial` run on the vector,
//! with the same operations as the batch over exits of one packet. A lane is therefore
//! bit for bit what [`Kernel::evaluate_batch`]'s lanes give for that pair's prepared packet
//! and exit (the `pairs_equal_the_batch_lanes_bit_for_bit` test), and within the bound of
//! [`Kernel::evaluate_batch`] of the per-direction kernel. The lanes cover the partially coherent
//! (closed-form blur) and incoherent first-order kernel at every polarization level, on a
//! [`super::super::RoughConductor`] or a [`super::super::RoughDielectric`] in reflection, with
//! a [`crate::psd::GaussianPsd`]; any other case (a mixture PSD, the Kirchhoff series, a
//! quadrature blur, a plane wave) goes pair by pair through the per-direction kernel, as do
//! the lanes the batch over exits redoes (within `√ε` of the normal, a scale outside the
//! normal range).

use nalgebra::Vector3;
use pulp::{Simd, WithSimd};

use super::DirectionsSoa;
use super::outputs::{ExitFramesSoa, LobesSoa, MuellerLobesSoa, check_lengths};
use super::partial::{
    ScalarExit, as_written, exit_lanes, lane_prep_at, load, lobe_lanes, mueller_lanes, redo_lanes,
    row_maker, store, write_scalar,
};
use super::per_lane::{Gathered, MAX_LANES};
use super::prep::{LANE_FIELDS, LobePrep};
use super::stages::validity::clearly_valid_lanes_about;
use crate::error::Error;
use crate::frame::Frame;
use crate::interaction::coherence::{CoherenceModel, CoherenceWeights};
use crate::interaction::polarization::{PolarizationModel, Throughput};
use crate::interaction::roughness::{RoughnessModel, RoughnessWeights};
use crate::interaction::{Geometry, Kernel, Surface};
use crate::mueller::batch::MuellerSoa;
use crate::real::Real;

mod consts;

/// A batch of pairs for [`Kernel::evaluate_pairs`], three views of equal length: element `i`
/// is unpolarized light of unit `S0` arriving from `to_source[i]` (any length) with the
/// isotropic coherence section `I/wᵢ²` on the surface, `inverse_width[i] = 1/wᵢ` (µm⁻¹),
/// leaving along `exit[i]` (any length).
#[derive(Debug, Clone, Copy)]
pub struct PairsSoa<'a, T> {
    /// The directions to the source (`−k̂`), world coordinates.
    pub to_source: DirectionsSoa<'a, T>,
    /// The exit directions, world coordinates.
    pub exit: DirectionsSoa<'a, T>,
    /// `1/w` of each pair's coherence width `w` on the surface (µm⁻¹).
    pub inverse_width: &'a [T],
}

impl<Pol: PolarizationModel, Coh: CoherenceModel, Rough: RoughnessModel> Kernel<Pol, Coh, Rough> {
    /// Evaluates S2.20 for every pair of `pairs` at the wavenumber `k` (rad/µm, in the medium
    /// above `surface`), in reflection: both lobes into `out` and, when given, the exit s/p
    /// frames into `frames`, as [`Kernel::evaluate_batch`] writes them (at the
    /// [`super::super::Intensity`] level `S0` only).
    ///
    /// Entry `i` is the kernel for unpolarized light of unit `S0` arriving from
    /// `to_source[i]` whose coherence section on the surface is `I/wᵢ²` — the packet
    /// [`crate::bsdf::SurfaceCoherence::packet`] builds for the width `wᵢ` (shape
    /// `diag(w², w² cos²θ_i)` in the incident s/p frame), in the closed form of
    /// [`crate::bsdf::Bsdf::prepare_surface`], which equals that packet's preparation up to
    /// rounding — leaving along `exit[i]`, with the geometry of [`Geometry::new`]. A
    /// wavefront renderer's lanes are such pairs: each path at its own vertex, its light
    /// unpolarized (module docs of `interaction::batch::pairs`).
    ///
    /// # Lanes
    /// With the levels, coherence, PSD and materials of [`Kernel::evaluate_batch`]'s lanes at
    /// first order (a [`crate::psd::GaussianPsd`], not a mixture), the pairs run in SIMD lanes,
    /// each lane its own pair, with the same bound against the per-direction kernel as
    /// [`Kernel::evaluate_batch`] (a lane is bit for bit the batch's lane for that pair's
    /// prepared packet and exit); elsewhere pair by pair through the per-direction kernel.
    /// Allocates nothing.
    ///
    /// # Errors
    /// - [`Error::OutOfRange`] when a slice of `pairs`, `out` or `frames` is shorter than
    ///   `pairs.exit.x`, when `k` is not positive and finite, or when an inverse width is not
    ///   positive and finite (nothing is written).
    /// - The error of [`Geometry::new`] for the first pair it rejects (nothing is written: every
    ///   pair is validated first).
    ///
    /// # Examples
    /// ```
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::batch::{DirectionsSoa, LobesSoa, PairsSoa, StokesSoa};
    /// use gmueller::interaction::{Full, Geometry, Kernel, Partial, RoughConductor};
    /// use gmueller::bsdf::SurfaceCoherence;
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::stokes::Stokes;
    /// use nalgebra::Vector3;
    /// use num_complex::Complex;
    ///
    /// let gold = RoughConductor::new(GaussianPsd::<f64, 2>::isotropic(0.02, 1.0)?,
    ///     Complex::new(0.47, 2.4))?;
    /// let surface = Frame::from_normal(Vector3::z())?;
    /// let (lambda, w) = (0.55, 5.0);
    /// // Two pairs: each its own light direction and exit.
    /// let (sx, sy, sz) = ([0.4, -0.2], [0.0, 0.3], [0.9, 0.8]);
    /// let (rx, ry, rz) = ([-0.4, 0.1], [0.05, -0.3], [0.9, 0.9]);
    /// let inverse_width = [1.0 / w; 2];
    /// let pairs = PairsSoa {
    ///     to_source: DirectionsSoa { x: &sx, y: &sy, z: &sz },
    ///     exit: DirectionsSoa { x: &rx, y: &ry, z: &rz },
    ///     inverse_width: &inverse_width,
    /// };
    /// let mut buf = [[0.0; 2]; 8];
    /// let [a, b, c, d, e, f, g, h] = &mut buf;
    /// let mut out = LobesSoa {
    ///     specular: StokesSoa { s: [a, b, c, d] },
    ///     scattered: StokesSoa { s: [e, f, g, h] },
    /// };
    /// let kernel = Kernel::<Full, Partial>::default();
    /// let k = 2.0 * std::f64::consts::PI / lambda;
    /// kernel.evaluate_pairs(&gold, k, &surface, pairs, &mut out, None)?;
    /// // Pair 1 against its packet evaluated alone (the same light up to rounding).
    /// let to_source = Vector3::new(sx[1], sy[1], sz[1]);
    /// let packet = SurfaceCoherence::fixed(w)?
    ///     .packet(Stokes::unpolarized(1.0)?, to_source, &surface, lambda)?;
    /// let g = Geometry::new(k, &surface, to_source, Vector3::new(rx[1], ry[1], rz[1]))?;
    /// let one = kernel.evaluate(&gold, &packet, &g).scattered.vector();
    /// assert!((out.scattered.s[0][1] - one[0]).abs() <= 1e-12 * one[0]);
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn evaluate_pairs<T, S>(
        &self,
        material: &S,
        k: T,
        surface: &Frame<T>,
        pairs: PairsSoa<'_, T>,
        out: &mut LobesSoa<'_, T>,
        frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        check_lengths(&pairs.exit, core::slice::from_ref(out), frames.as_deref())?;
        self.pairs_into(material, k, surface, pairs, Sink::Stokes(out), frames)
    }

    /// [`Kernel::evaluate_pairs`] as Mueller matrices: for every pair of `pairs` at the
    /// wavenumber `k` (rad/µm, in the medium above `surface`), in reflection, both lobes'
    /// `M` into `out` and, when given, the exit s/p frames into `frames`. Entry `i` is
    /// [`Kernel::evaluate_mueller_prepared`] of the pair's packet (unpolarized light of unit
    /// irradiance from `to_source[i]` with the section `I/wᵢ²` on the surface, in the closed
    /// form of [`Kernel::evaluate_pairs`]) at the geometry [`Geometry::new`] of the pair: the
    /// matrix acts on Stokes vectors in the pair's incident s/p frame and gives them in its
    /// exit s/p frame, per unit incident irradiance. Its first column is what
    /// [`Kernel::evaluate_pairs`] writes (before that projects onto the cone of valid
    /// vectors). At the [`super::super::Intensity`] level `M₀₀` only (`m[0]`; the other
    /// slices are not written). This is the value a backward path tracer's weight needs at
    /// each lane's vertex: the throughput it carries is a Mueller matrix.
    ///
    /// # Lanes
    /// As [`Kernel::evaluate_pairs`]: column `j` of a lane is its Stokes assembly for the
    /// effective vector `e_j`, scaled like `M₀₀`. Against the per-direction kernel, every entry
    /// within the bound [`Kernel::evaluate_batch`] documents for a vector of `S0 = M₀₀`
    /// (`tests`: `mueller_pairs_equal_the_per_direction_kernel`). Allocates nothing.
    ///
    /// # Errors
    /// As [`Kernel::evaluate_pairs`] (a slice of `out` shorter than `pairs.exit.x`: every
    /// slice of both lobes is checked, at the `Intensity` level too).
    ///
    /// # Examples
    /// ```
    /// use gmueller::bsdf::{Bsdf, SurfaceCoherence};
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::batch::{DirectionsSoa, MuellerLobesSoa, MuellerSoa, PairsSoa};
    /// use gmueller::interaction::{Full, Geometry, Kernel, Partial, RoughConductor};
    /// use gmueller::psd::GaussianPsd;
    /// use nalgebra::Vector3;
    /// use num_complex::Complex;
    ///
    /// let gold = RoughConductor::new(GaussianPsd::<f64, 2>::isotropic(0.02, 1.0)?,
    ///     Complex::new(0.47, 2.4))?;
    /// let surface = Frame::from_normal(Vector3::z())?;
    /// let k = 2.0 * std::f64::consts::PI / 0.55;
    /// let (s, r, inverse_width) = ([0.4, 0.0, 0.9], [-0.4, 0.05, 0.9], [0.2]);
    /// let pairs = PairsSoa {
    ///     to_source: DirectionsSoa { x: &s[..1], y: &s[1..2], z: &s[2..] },
    ///     exit: DirectionsSoa { x: &r[..1], y: &r[1..2], z: &r[2..] },
    ///     inverse_width: &inverse_width,
    /// };
    /// let mut buf = [[0.0; 1]; 32];
    /// let [m0, m1, m2, m3, m4, m5, m6, m7, m8, m9, m10, m11, m12, m13, m14, m15,
    ///     n0, n1, n2, n3, n4, n5, n6, n7, n8, n9, n10, n11, n12, n13, n14, n15] = &mut buf;
    /// let mut out = MuellerLobesSoa {
    ///     specular: MuellerSoa { m: [m0, m1, m2, m3, m4, m5, m6, m7, m8, m9, m10, m11, m12,
    ///         m13, m14, m15] },
    ///     scattered: MuellerSoa { m: [n0, n1, n2, n3, n4, n5, n6, n7, n8, n9, n10, n11, n12,
    ///         n13, n14, n15] },
    /// };
    /// let kernel = Kernel::<Full, Partial>::default();
    /// kernel.evaluate_pairs_mueller(&gold, k, &surface, pairs, &mut out, None)?;
    /// // Against the pair's light prepared by the renderer layer (the same closed form), one
    /// // at a time.
    /// let bsdf = Bsdf::new(&gold, kernel, surface, 0.55)?;
    /// let light = bsdf.prepare_surface(Vector3::from(s), &SurfaceCoherence::fixed(5.0)?)?;
    /// let g = Geometry::new(k, &surface, Vector3::from(s), Vector3::from(r))?;
    /// let one = kernel.evaluate_mueller_prepared(&gold, light.prepared(), &g).scattered.matrix();
    /// for (i, m) in out.scattered.m.iter().enumerate() {
    ///     assert!((m[0] - one[(i / 4, i % 4)]).abs() <= 1e-12 * one[(0, 0)]);
    /// }
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn evaluate_pairs_mueller<T, S>(
        &self,
        material: &S,
        k: T,
        surface: &Frame<T>,
        pairs: PairsSoa<'_, T>,
        out: &mut MuellerLobesSoa<'_, T>,
        frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        let n = pairs.exit.len();
        let short = |m: &MuellerSoa<'_, T>| m.m.iter().any(|c| c.len() < n);
        if short(&out.specular) || short(&out.scattered) {
            return Err(Error::OutOfRange {
                what: "batch slice length",
                value: n as f64,
                expected: "every direction, lobe and frame slice at least as long as exits.x",
            });
        }
        check_lengths(&pairs.exit, &[], frames.as_deref())?;
        self.pairs_into(material, k, surface, pairs, Sink::Mueller(out), frames)
    }

    /// Whether [`Kernel::evaluate_pairs`] and [`Kernel::evaluate_pairs_mueller`] run the pairs
    /// of `material` in SIMD lanes (else pair by pair through the per-direction kernel).
    pub(crate) fn pairs_in_lanes<T, S>(&self, material: &S) -> bool
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
    {
        row_maker(self, material).is_some()
    }

    /// The checks and the pass of [`Kernel::evaluate_pairs`] and
    /// [`Kernel::evaluate_pairs_mueller`] (the output slices' lengths checked by the caller).
    fn pairs_into<T, S>(
        &self,
        material: &S,
        k: T,
        surface: &Frame<T>,
        pairs: PairsSoa<'_, T>,
        sink: Sink<'_, '_, T>,
        frames: Option<&mut ExitFramesSoa<'_, T>>,
    ) -> Result<(), Error>
    where
        T: Real,
        S: Surface<T>,
        Coh: CoherenceWeights<T, S::Psd>,
        Rough: RoughnessWeights<T, S::Psd, Coh>,
    {
        let PairsSoa {
            to_source,
            exit,
            inverse_width,
        } = pairs;
        let n = exit.len();
        if to_source.x.len() < n
            || to_source.y.len() < n
            || to_source.z.len() < n
            || inverse_width.len() < n
        {
            return Err(Error::OutOfRange {
                what: "pairs slice length",
                value: n as f64,
                expected: "to_source and inverse_width at least as long as exit.x",
            });
        }
        if !(k > T::zero() && k.is_finite()) {
            return Err(Error::OutOfRange {
                what: "wavenumber k (rad/µm)",
                value: k.to_f64(),
                expected: "positive and finite",
            });
        }
        crate::simd::dispatch(Validate {
            pairs,
            n,
            k,
            surface,
        })?;
        let at = |d: &DirectionsSoa<'_, T>, i: usize| Vector3::new(d.x[i], d.y[i], d.z[i]);
        let prepared = |i: usize| self.prepare_unpolarized_isotropic(k, inverse_width[i]);
        // The constants every pair shares, from the first pair (of the first four) the lanes
        // take; each pair's own from its row.
        let maker = row_maker(self, material);
        let head = maker.as_ref().and_then(|_| {
            (0..n.min(4)).find_map(|i| {
                lane_prep_at(
                    self,
                    material,
                    &prepared(i),
                    at(&to_source, i),
                    surface,
                    None,
                )
            })
        });
        let mut row = |i: usize| {
            let m = maker.as_ref()?;
            let s = at(&to_source, i);
            LobePrep::lane_row_of(&prepared(i), m.psd, m.indices, s, surface, m.incoherent)
        };
        let shared = head
            .as_ref()
            .zip(maker.as_ref())
            .map(|(h, m)| consts::Shared::new(h, m));
        let mueller = matches!(sink, Sink::Mueller(_));
        let mut scalar = |i: usize| -> Result<ScalarPair<T>, Error> {
            #[cfg(test)]
            tests::PER_DIRECTION.with(|c| c.set(c.get() + 1));
            let g = Geometry::new(k, surface, at(&to_source, i), at(&exit, i))?;
            Ok(if mueller {
                let m = self.evaluate_mueller_prepared(material, &prepared(i), &g);
                let (sp, sc) = (m.specular.entries(), m.scattered.entries());
                ScalarPair::Mueller(sp, sc, g.exit_sp().x().into())
            } else {
                ScalarPair::Stokes(as_written(
                    &self.evaluate_prepared(material, &prepared(i), &g),
                    &g,
                ))
            })
        };
        crate::simd::dispatch(PairLobes {
            to_source,
            exits: exit,
            n,
            intensity: Pol::LEVEL == crate::interaction::polarization::PolarizationLevel::Intensity,
            sink,
            frames,
            head: head.as_ref(),
            shared: shared.as_ref(),
            inverse_width,
            row: &mut row,
            scalar: &mut scalar,
        })
    }
}

/// Vector `chunk` of `n` pairs in vectors of `lanes`: `(start, count)`, whole vectors at 0,
/// `lanes`, 2 `lanes`, …; the tail as the last `lanes` pairs (overlapping the vector before
/// it), or, for a batch shorter than one vector, its `n` pairs (padded with pair 0).
fn span(chunk: usize, n: usize, lanes: usize) -> (usize, usize) {
    if n >= lanes {
        ((chunk * lanes).min(n - lanes), lanes)
    } else {
        (0, n)
    }
}

/// The validation of [`Kernel::evaluate_pairs`]'s pairs in lanes: every inverse width positive
/// and finite (else the error for the first that is not), then every pair whose directions
/// the fast test does not clear ([`clearly_valid_lanes_about`]) through [`Geometry::new`], in
/// order (its error for the first it rejects).
struct Validate<'a, F: Real> {
    pairs: PairsSoa<'a, F>,
    n: usize,
    k: F,
    surface: &'a Frame<F>,
}

impl<F: Real> WithSimd for Validate<'_, F> {
    type Output = Result<(), Error>;

    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> Result<(), Error> {
        let Self {
            pairs,
            n,
            k,
            surface,
        } = self;
        let lanes = F::width::<S>();
        let (zero, max) = (F::vsplat(s, F::zero()), F::vsplat(s, F::MAX));
        let widths = &pairs.inverse_width[..n];
        let (head, tail) = F::vsplit::<S>(widths);
        let good = |w: F| w > F::zero() && w.is_finite();
        let all_good = head.iter().all(|&w| {
            let ok = F::vand(s, F::vlt(s, zero, w), F::vle(s, w, max));
            !F::vany(s, F::vnot(s, ok))
        }) && tail.iter().all(|&w| good(w));
        if !all_good && let Some(w) = widths.iter().find(|w| !good(**w)) {
            return Err(Error::OutOfRange {
                what: "inverse coherence width 1/w (1/µm)",
                value: w.to_f64(),
                expected: "positive and finite",
            });
        }
        let normal = surface.k();
        let mut buf = [[F::zero(); MAX_LANES]; 6];
        let cols = [
            pairs.to_source.x,
            pairs.to_source.y,
            pairs.to_source.z,
            pairs.exit.x,
            pairs.exit.y,
            pairs.exit.z,
        ];
        for chunk in 0..n.div_ceil(lanes) {
            let (start, count) = span(chunk, n, lanes);
            let [b0, b1, b2, b3, b4, b5] = &mut buf;
            let v = [
                load::<S, F>(&cols[0][..n], b0, start, count),
                load::<S, F>(&cols[1][..n], b1, start, count),
                load::<S, F>(&cols[2][..n], b2, start, count),
                load::<S, F>(&cols[3][..n], b3, start, count),
                load::<S, F>(&cols[4][..n], b4, start, count),
                load::<S, F>(&cols[5][..n], b5, start, count),
            ];
            let clear = F::vand(
                s,
                clearly_valid_lanes_about::<S, F>(s, &normal, false, [v[0], v[1], v[2]]),
                clearly_valid_lanes_about::<S, F>(s, &normal, false, [v[3], v[4], v[5]]),
            );
            let unclear = F::vnot(s, clear);
            if F::vany(s, unclear) {
                for j in redo_lanes::<S, F>(s, unclear, count) {
                    let at = |c: usize| cols[c][start + j];
                    let to_source = Vector3::new(at(0), at(1), at(2));
                    Geometry::new(k, surface, to_source, Vector3::new(at(3), at(4), at(5)))?;
                }
            }
        }
        Ok(())
    }
}

/// The SIMD loop of [`Kernel::evaluate_pairs`] over vectors of (validated) pairs, one type
/// per float type (the material and kernel behind the two callbacks, as `PartialLobes`).
struct PairLobes<'r, 'e, 'o, 'f, F: Real> {
    to_source: DirectionsSoa<'e, F>,
    exits: DirectionsSoa<'e, F>,
    n: usize,
    intensity: bool,
    sink: Sink<'r, 'o, F>,
    frames: Option<&'r mut ExitFramesSoa<'f, F>>,
    /// The constants the pairs share (`None`: no pair in lanes).
    head: Option<&'r LobePrep<F>>,
    /// The constants the lanes of `consts` share (`None`: no pair in lanes).
    shared: Option<&'r consts::Shared<'r, F>>,
    /// `1/w` of each pair.
    inverse_width: &'e [F],
    /// Pair `i`'s own constants, `None` where the lanes do not reproduce its kernel.
    row: &'r mut dyn FnMut(usize) -> Option<[F; LANE_FIELDS]>,
    /// Pair `i` by the per-direction kernel.
    scalar: &'r mut dyn FnMut(usize) -> Result<ScalarPair<F>, Error>,
}

/// Where [`PairLobes`] writes: Stokes vectors ([`Kernel::evaluate_pairs`]) or Mueller
/// matrices ([`Kernel::evaluate_pairs_mueller`]).
enum Sink<'r, 'o, F> {
    Stokes(&'r mut LobesSoa<'o, F>),
    Mueller(&'r mut MuellerLobesSoa<'o, F>),
}

/// One pair by the per-direction kernel, as its [`Sink`] takes it.
enum ScalarPair<F> {
    Stokes(ScalarExit<F>),
    /// The specular and scattered matrices' entries (row-major) and the exit s vector.
    Mueller([F; 16], [F; 16], [F; 3]),
}

/// Writes pair `i` as the per-direction kernel gave it: its first `len` Stokes parameters or
/// matrix entries (`S0` or `M₀₀` alone at the `Intensity` level), and its exit s vector where
/// `frames` is given.
fn write_pair<F: Real>(
    i: usize,
    pair: ScalarPair<F>,
    sink: &mut Sink<'_, '_, F>,
    frames: Option<&mut ExitFramesSoa<'_, F>>,
    intensity: bool,
) {
    match (pair, sink) {
        (ScalarPair::Stokes(x), Sink::Stokes(out)) => {
            write_scalar(i, x, (out, frames), if intensity { 1 } else { 4 });
        }
        (ScalarPair::Mueller(sp, sc, so), Sink::Mueller(out)) => {
            let len = if intensity { 1 } else { 16 };
            for k in 0..len {
                out.specular.m[k][i] = sp[k];
                out.scattered.m[k][i] = sc[k];
            }
            if let Some(f) = frames {
                for (col, v) in f.s.iter_mut().zip(so) {
                    col[i] = v;
                }
            }
        }
        _ => unreachable!("the per-direction kernel answers in its sink's form"),
    }
}

impl<F: Real> WithSimd for PairLobes<'_, '_, '_, '_, F> {
    type Output = Result<(), Error>;

    // `inline(always)`: the body must be compiled inside pulp's `#[target_feature]` function.
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> Result<(), Error> {
        let Self {
            to_source,
            exits,
            n,
            intensity,
            mut sink,
            mut frames,
            head,
            shared,
            inverse_width,
            row,
            scalar,
        } = self;
        let lanes = F::width::<S>();
        let (xs, ys, zs) = (&exits.x[..n], &exits.y[..n], &exits.z[..n]);
        let (sxs, sys, szs) = (&to_source.x[..n], &to_source.y[..n], &to_source.z[..n]);
        let mut buf = [[F::zero(); MAX_LANES]; 3];
        let mut scratch = [[F::zero(); MAX_LANES]; 4];
        let mut cols = [[F::zero(); MAX_LANES]; LANE_FIELDS];
        for chunk in 0..n.div_ceil(lanes) {
            let (start, count) = span(chunk, n, lanes);
            // The tail vector's first lanes were written by the vector before it.
            let fresh = chunk * lanes;
            let Some(p) = head else {
                for i in fresh.max(start)..start + count {
                    write_pair(i, scalar(i)?, &mut sink, frames.as_deref_mut(), intensity);
                }
                continue;
            };
            // The constants in lanes (`consts`), or, where a lane is flagged, pair by pair.
            let in_lanes = match shared {
                Some(sh) => {
                    let pairs = ([sxs, sys, szs], &inverse_width[..n]);
                    consts::gather::<S, F>(s, sh, pairs, (start, count), &mut scratch)
                }
                None => None,
            };
            let g = match in_lanes {
                Some(g) => g,
                None => {
                    // Each pair's constants into lane j of every column (a short batch's
                    // other lanes repeat pair 0's).
                    let mut built = true;
                    for j in 0..count {
                        let Some(r) = row(start + j) else {
                            built = false;
                            break;
                        };
                        for (col, v) in cols.iter_mut().zip(r) {
                            col[j] = v;
                        }
                    }
                    if !built {
                        for i in fresh.max(start)..start + count {
                            write_pair(i, scalar(i)?, &mut sink, frames.as_deref_mut(), intensity);
                        }
                        continue;
                    }
                    for col in &mut cols {
                        let first = col[0];
                        col[count..lanes].fill(first);
                    }
                    Gathered::<S, F>::new(p, &cols)
                }
            };
            let [bx, by, bz] = &mut buf;
            let x = load::<S, F>(xs, bx, start, count);
            let y = load::<S, F>(ys, by, start, count);
            let z = load::<S, F>(zs, bz, start, count);
            let e = exit_lanes::<S, F, Gathered<S, F>>(s, (&p.inc, &g), x, y, z);
            let redo = match &mut sink {
                Sink::Stokes(out) => {
                    let l = lobe_lanes::<S, F, Gathered<S, F>>(s, (p, &g), None, &e, None);
                    for k in 0..if intensity { 1 } else { 4 } {
                        store::<S, F>(s, out.specular.s[k], l.specular[k], start, count);
                        store::<S, F>(s, out.scattered.s[k], l.scattered[k], start, count);
                    }
                    l.redo
                }
                Sink::Mueller(out) => {
                    let l = mueller_lanes::<S, F, Gathered<S, F>>(s, (p, &g), &e);
                    for k in 0..if intensity { 1 } else { 16 } {
                        let (row, col) = (k / 4, k % 4);
                        store::<S, F>(s, out.specular.m[k], l.specular[col][row], start, count);
                        store::<S, F>(s, out.scattered.m[k], l.scattered[col][row], start, count);
                    }
                    l.redo
                }
            };
            if let Some(f) = frames.as_deref_mut() {
                for k in 0..3 {
                    store::<S, F>(s, f.s[k], e.frame.s_out[k], start, count);
                }
            }
            if F::vany(s, redo) {
                // (The tail vector's lanes before `fresh` were stored again above: a lane to
                // redo there is redone again.)
                for j in redo_lanes::<S, F>(s, redo, count) {
                    let i = start + j;
                    write_pair(i, scalar(i)?, &mut sink, frames.as_deref_mut(), intensity);
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
