//! The lobe-mixture sampler over SIMD lanes: [`LobeSampler::sample_batch`] draws one direction
//! per element of a batch of uniforms, each lane its own draw from the same sampler (one shading
//! point and tracing direction), with its exact density.
//!
//! # Lanes and fallback
//! The draws of a sampler whose lobes are Gaussians in `h_t` — the specular lobe (a Dirac delta,
//! or one or two channel Gaussians) and one scattered Gaussian (a Gaussian PSD at first order,
//! blurred by the coherence or in the incoherent limit) or the Kirchhoff series' mixture of at
//! most six order lobes per side (`bsdf::orders`: the lobe chosen per lane from `u_lobe`'s
//! remainder as `OrderLobes::sample` does, the density `Σ_j P_j 𝒩_j` of the side holding the
//! direction), without the angle chart of a grazing backward specular lobe — run in lanes, 8 (`f64`) or 16 (`f32`) per instruction under
//! AVX-512, 4 or 8 under AVX2 + FMA: the part from `u_lobe`, a Box–Muller point from `u`
//! (the vector logarithm and sine/cosine of [`crate::simd`]), the direction of its `h_t`, and the
//! density of that direction recomputed from it as [`LobeSampler::pdf`] does. Every other
//! sampler (mixture PSDs, grating orders, the power lobe, the disk lobe, the angle chart) draws
//! each element with [`LobeSampler::sample`].
//!
//! # Agreement with `sample`
//! Lane `i` is `sample(u_lobe[i], [u0[i], u1[i]])` computed with the same operations in the same
//! order, except the logarithm, sine and cosine (within 1 ulp of the standard library's, in
//! place of the standard library's). Divisions stay divisions: multiplying by reciprocals
//! instead (of `k_b`, of the norm of the direction) moved the weights at 89.99° by up to
//! 9·10⁻⁸ relative in `f64`, where `cos θ = √(1 − |u|²)` and the lobe's `h_t` magnify an ulp,
//! and gained nothing measurable. The part chosen, the lobe and whether a draw is rejected
//! are the same unless `u` lies within a few ulp of a boundary; the directions and densities
//! agree to a few ulp (asserted over 2·10⁴ draws per case, with the lanes where the choice of
//! lobe differs counted, at most 1 in 10⁴: `f64` within 10⁻¹² relative; `f32` the direction
//! within 64 ε and the density within 2⁻¹² relative, `tests/bsdf/sample_batch.rs`).

use pulp::{Simd, WithSimd};

use super::{LobeSampler, Part, SampledLobe, Scatter, SideMap, Specular};
use crate::bsdf::lobes::GaussLobe;
use crate::bsdf::orders::ORDER_LOBES;
use crate::error::Error;
use crate::interaction::Side;
use crate::interaction::batch::DirectionsSoa;
use crate::real::Real;
use crate::simd::driver::{self, LaneMap};

/// A batch of uniforms for [`LobeSampler::sample_batch`]: three slices of equal length, element
/// `i` the arguments `(lobe[i], [u0[i], u1[i]])` of [`LobeSampler::sample`].
#[derive(Debug, Clone, Copy)]
pub struct UniformsSoa<'a, T> {
    /// `u_lobe`, which chooses the part (and the channel).
    pub lobe: &'a [T],
    /// The first uniform of the point in the lobe.
    pub u0: &'a [T],
    /// The second uniform of the point in the lobe.
    pub u1: &'a [T],
}

/// The output of [`LobeSampler::sample_batch`]: one drawn direction per element, as the fields
/// of [`super::DirectionSample`] in slices of equal length (at least the batch's).
///
/// An element with no direction (an evanescent or rejected draw: `sample` returned `None`) has
/// `pdf = 0`, the direction and `delta_weight` 0 and `lobe = NO_LOBE`.
#[derive(Debug)]
pub struct SamplesSoa<'a, T> {
    /// The direction's x components (unit, pointing away from the surface).
    pub x: &'a mut [T],
    /// y components.
    pub y: &'a mut [T],
    /// z components.
    pub z: &'a mut [T],
    /// The density per unit solid angle (for a delta lobe, the probability of having chosen it);
    /// 0 for no direction.
    pub pdf: &'a mut [T],
    /// [`super::DirectionSample::delta_weight`].
    pub delta_weight: &'a mut [T],
    /// The lobe drawn, as [`SampledLobe::code`] ([`SampledLobe::from_code`] gives it back);
    /// [`NO_LOBE`] for no direction.
    pub lobe: &'a mut [u8],
}

/// [`SamplesSoa::lobe`] of an element with no direction.
pub const NO_LOBE: u8 = 0xff;

impl SampledLobe {
    /// The lobe as one byte: bit 0 transmission, bit 1 scattered, bit 2 delta.
    ///
    /// # Examples
    /// ```
    /// use gmueller::bsdf::{Part, SampledLobe};
    /// use gmueller::interaction::Side;
    /// let l = SampledLobe { side: Side::Transmission, part: Part::Specular, delta: true };
    /// assert_eq!(l.code(), 0b101);
    /// assert_eq!(SampledLobe::from_code(l.code()), Some(l));
    /// ```
    #[must_use]
    pub fn code(&self) -> u8 {
        u8::from(self.side == Side::Transmission)
            | (u8::from(self.part == Part::Scattered) << 1)
            | (u8::from(self.delta) << 2)
    }

    /// The lobe of a [`SampledLobe::code`]; `None` for a byte above 7 ([`NO_LOBE`]).
    #[must_use]
    pub fn from_code(code: u8) -> Option<Self> {
        (code < 8).then_some(Self {
            side: if code & 1 == 0 {
                Side::Reflection
            } else {
                Side::Transmission
            },
            part: if code & 2 == 0 {
                Part::Specular
            } else {
                Part::Scattered
            },
            delta: code & 4 != 0,
        })
    }
}

/// A Gaussian lobe's constants in lanes' terms.
#[derive(Debug, Clone, Copy)]
struct Gauss<T> {
    c: [T; 2],
    l: [T; 3],
    norm: T,
}

impl<T: Real> Gauss<T> {
    /// `[c₀, c₁, l₀₀, l₁₀, l₁₁]`.
    #[inline(always)]
    fn flat(&self) -> [T; 5] {
        [self.c[0], self.c[1], self.l[0], self.l[1], self.l[2]]
    }

    fn of(g: &GaussLobe<T>) -> Self {
        Self {
            c: [g.centre.x, g.centre.y],
            l: g.l,
            norm: g.norm,
        }
    }
}

/// One side's map ([`SideMap`]) in lanes' terms.
#[derive(Debug, Clone, Copy)]
struct Map<T> {
    t1: [T; 3],
    t2: [T; 3],
    n: [T; 3],
    known_h: [T; 2],
    k: T,
    mirror: bool,
}

impl<T: Real> Map<T> {
    /// `[t̂₁, t̂₂, n̂, k_a u_a, k_b]` flattened (12 numbers).
    #[inline(always)]
    fn flat(&self) -> [T; 12] {
        let (a, b, n, h) = (self.t1, self.t2, self.n, self.known_h);
        [
            a[0], a[1], a[2], b[0], b[1], b[2], n[0], n[1], n[2], h[0], h[1], self.k,
        ]
    }

    fn of(m: &SideMap<T>) -> Self {
        Self {
            t1: [m.t1.x, m.t1.y, m.t1.z],
            t2: [m.t2.x, m.t2.y, m.t2.z],
            n: [m.n.x, m.n.y, m.n.z],
            known_h: [m.known_h.x, m.known_h.y],
            k: m.k,
            mirror: m.mirror,
        }
    }
}

/// The specular lobe in lanes' terms.
#[derive(Debug, Clone, Copy)]
enum Spec<T> {
    /// No specular lobe (its parts have probability 0).
    None,
    /// A Dirac delta at `h_t = 0`.
    Delta,
    /// `count` channel Gaussians `(weight, lobe)`.
    Gauss([(T, Gauss<T>); 2], usize),
}

/// One side's order lobes: `(P_j, lobe)` and their count.
type OrderLanes<T> = ([(T, Gauss<T>); ORDER_LOBES], usize);

/// The scattered lobes in lanes' terms.
#[derive(Debug, Clone, Copy)]
enum Scat<T> {
    /// No scattered lobe.
    None,
    /// One Gaussian on both sides.
    One(Gauss<T>),
    /// The Kirchhoff series' orders per side (reflected, transmitted): `count` lobes
    /// `(P_j, lobe)` each (`bsdf::orders`).
    Series([OrderLanes<T>; 2]),
}

/// A sampler the lanes can draw from (module docs): its constants.
#[derive(Debug, Clone, Copy)]
struct LaneSampler<T> {
    probs: [T; 4],
    maps: [Map<T>; 2],
    transmits: bool,
    spec: Spec<T>,
    scat: Scat<T>,
}

impl<F: Real> LaneSampler<F> {
    /// The lanes' constants of `s`, `None` when its lobes are not all Gaussians in `h_t`.
    fn of(s: &LobeSampler<'_, F>) -> Option<Self> {
        if s.disk != F::zero() || s.chart(0).is_some() || (s.transmits && s.chart(1).is_some()) {
            return None;
        }
        let spec = match s.specular {
            None => Spec::None,
            Some(Specular::Delta) => Spec::Delta,
            Some(Specular::Gauss(lobes, count)) => Spec::Gauss(
                [
                    (lobes[0].0, Gauss::of(&lobes[0].1)),
                    (lobes[1].0, Gauss::of(&lobes[1].1)),
                ],
                count,
            ),
        };
        let scat = match s.scatter {
            Scatter::None => Scat::None,
            Scatter::One(l) => Scat::One(Gauss::of(&l)),
            Scatter::Series(sides) => Scat::Series(sides.map(|o| {
                let lobes = o.lobes.map(|(w, l)| (w, Gauss::of(&l)));
                (lobes, o.count)
            })),
            _ => return None,
        };
        Some(Self {
            probs: s.probs,
            maps: [Map::of(&s.sides[0]), Map::of(&s.sides[1])],
            transmits: s.transmits,
            spec,
            scat,
        })
    }
}

impl<'a, T: Real> LobeSampler<'a, T> {
    /// Draws one direction per element of `u` into `out` ([`LobeSampler::sample`] of each
    /// element, in SIMD lanes where the sampler's lobes allow: module docs of
    /// `bsdf::sampler::batch`); allocates nothing.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when the slices of `u` differ in length or a slice of `out` is
    /// shorter than them.
    ///
    /// # Examples
    /// ```
    /// use gmueller::bsdf::{Bsdf, SampledLobe, SamplesSoa, SurfaceCoherence, UniformsSoa};
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::{Full, Kernel, Partial, RoughConductor};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::spectral::Metal;
    /// use nalgebra::Vector3;
    ///
    /// let gold = RoughConductor::new(GaussianPsd::isotropic(0.02, 1.0)?, Metal::Au.index(0.55_f64))?;
    /// let frame = Frame::from_normal(Vector3::z())?;
    /// let bsdf = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), frame, 0.55)?;
    /// let exit = Vector3::new(0.3, 0.0, 0.95).normalize();
    /// let sampler = bsdf.incident_sampler(exit, &SurfaceCoherence::new(5.0)?)?;
    /// let (lobe, u0, u1) = ([0.1, 0.7, 0.9], [0.2, 0.5, 0.8], [0.3, 0.6, 0.1]);
    /// let [mut x, mut y, mut z, mut pdf, mut dw] = [[0.0_f64; 3]; 5];
    /// let mut code = [0_u8; 3];
    /// sampler.sample_batch(
    ///     UniformsSoa { lobe: &lobe, u0: &u0, u1: &u1 },
    ///     SamplesSoa { x: &mut x, y: &mut y, z: &mut z, pdf: &mut pdf,
    ///                  delta_weight: &mut dw, lobe: &mut code },
    /// )?;
    /// for i in 0..3 {
    ///     let one = sampler.sample(lobe[i], [u0[i], u1[i]]).unwrap();
    ///     assert!((pdf[i] - one.pdf).abs() <= 1e-12 * one.pdf);
    ///     assert_eq!(SampledLobe::from_code(code[i]), Some(one.lobe));
    /// }
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn sample_batch(&self, u: UniformsSoa<'_, T>, out: SamplesSoa<'_, T>) -> Result<(), Error> {
        let n = u.lobe.len();
        if u.u0.len() != n || u.u1.len() != n {
            return Err(Error::OutOfRange {
                what: "batch slice length",
                value: n as f64,
                expected: "uniform slices lobe, u0 and u1 of one common length",
            });
        }
        let short = [
            out.x.len(),
            out.y.len(),
            out.z.len(),
            out.pdf.len(),
            out.delta_weight.len(),
        ]
        .into_iter()
        .any(|l| l < n)
            || out.lobe.len() < n;
        if short {
            return Err(Error::OutOfRange {
                what: "batch slice length",
                value: n as f64,
                expected: "output slices at least as long as the uniforms",
            });
        }
        match LaneSampler::of(self) {
            Some(c) => crate::simd::dispatch(Batch { c: &c, u, out }),
            None => self.sample_each(u, out),
        }
        Ok(())
    }

    /// [`LobeSampler::pdf`] of every direction of `d` into `out` (directions need not be unit;
    /// 0 for a zero or non-finite one), in SIMD lanes where [`LobeSampler::sample_batch`] draws
    /// in lanes (within the same bounds of `pdf` as its draws' densities), one at a time
    /// otherwise. Allocates nothing.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] when the slices of `d` differ in length or `out` is shorter.
    ///
    /// # Examples
    /// ```
    /// use gmueller::bsdf::{Bsdf, SurfaceCoherence};
    /// use gmueller::frame::Frame;
    /// use gmueller::interaction::batch::DirectionsSoa;
    /// use gmueller::interaction::{Full, Kernel, Partial, RoughConductor};
    /// use gmueller::psd::GaussianPsd;
    /// use gmueller::spectral::Metal;
    /// use nalgebra::Vector3;
    ///
    /// let gold = RoughConductor::new(GaussianPsd::isotropic(0.02, 1.0)?, Metal::Au.index(0.55_f64))?;
    /// let bsdf = Bsdf::new(&gold, Kernel::<Full, Partial>::default(), Frame::from_normal(Vector3::z())?, 0.55)?;
    /// let sampler = bsdf.incident_sampler(Vector3::new(0.3, 0.0, 0.95), &SurfaceCoherence::new(5.0)?)?;
    /// let (x, y, z) = ([-0.3, 0.0, 0.5], [0.0, 0.1, 0.0], [0.95, 1.0, -0.8]);
    /// let mut pdf = [0.0; 3];
    /// sampler.pdf_batch(DirectionsSoa { x: &x, y: &y, z: &z }, &mut pdf)?;
    /// for i in 0..3 {
    ///     let one = sampler.pdf(&Vector3::new(x[i], y[i], z[i]));
    ///     assert!((pdf[i] - one).abs() <= 1e-12 * one);
    /// }
    /// assert_eq!(pdf[2], 0.0); // below an opaque surface
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn pdf_batch(&self, d: DirectionsSoa<'_, T>, out: &mut [T]) -> Result<(), Error> {
        let n = d.x.len();
        if d.y.len() != n || d.z.len() != n || out.len() < n {
            return Err(Error::OutOfRange {
                what: "batch slice length",
                value: n as f64,
                expected: "direction slices of one common length and an output at least as long",
            });
        }
        let out = &mut out[..n];
        match LaneSampler::of(self) {
            Some(c) => crate::simd::dispatch(PdfBatch { c: &c, d, out }),
            None => {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = self.pdf(&nalgebra::Vector3::new(d.x[i], d.y[i], d.z[i]));
                }
            }
        }
        Ok(())
    }

    /// [`LobeSampler::sample_batch`] one element at a time.
    fn sample_each(&self, u: UniformsSoa<'_, T>, out: SamplesSoa<'_, T>) {
        for i in 0..u.lobe.len() {
            let (d, pdf, dw, code) = match self.sample(u.lobe[i], [u.u0[i], u.u1[i]]) {
                Some(d) => (d.direction, d.pdf, d.delta_weight, d.lobe.code()),
                None => (nalgebra::Vector3::zeros(), T::zero(), T::zero(), NO_LOBE),
            };
            (out.x[i], out.y[i], out.z[i]) = (d.x, d.y, d.z);
            (out.pdf[i], out.delta_weight[i], out.lobe[i]) = (pdf, dw, code);
        }
    }
}

/// [`pdf_lanes`] as a lane map (x, y, z → pdf).
struct PdfLanes<'a, T>(&'a LaneSampler<T>);

impl<F: Real> LaneMap<F, 3, 1> for PdfLanes<'_, F> {
    #[inline(always)]
    fn eval<S: Simd>(&self, s: S, x: [F::V<S>; 3]) -> [F::V<S>; 1] {
        [pdf_lanes::<S, F>(s, self.0, x)]
    }
}

/// The SIMD loop of [`LobeSampler::pdf_batch`].
struct PdfBatch<'a, 'd, 'o, T> {
    c: &'a LaneSampler<T>,
    d: DirectionsSoa<'d, T>,
    out: &'o mut [T],
}

impl<T: Real> WithSimd for PdfBatch<'_, '_, '_, T> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) {
        let Self { c, d, out } = self;
        let n = d.x.len();
        let (x, y, z) = (
            T::vsplit::<S>(&d.x[..n]).0,
            T::vsplit::<S>(&d.y[..n]).0,
            T::vsplit::<S>(&d.z[..n]).0,
        );
        let nv = x.len();
        let (x, y, z) = (&x[..nv], &y[..nv], &z[..nv]);
        {
            let o = &mut T::vsplit_mut::<S>(&mut out[..n]).0[..nv];
            for i in 0..nv {
                o[i] = pdf_lanes::<S, T>(s, c, [x[i], y[i], z[i]]);
            }
        }
        driver::remainder::<S, T, PdfLanes<'_, T>, 3, 1>(
            s,
            &PdfLanes(c),
            [d.x, d.y, d.z],
            &mut [out],
            n,
            nv,
        );
    }
}

/// The SIMD loop, instantiated by [`pulp::Arch::dispatch`] once per instruction set.
struct Batch<'a, 'u, 'o, T> {
    c: &'a LaneSampler<T>,
    u: UniformsSoa<'u, T>,
    out: SamplesSoa<'o, T>,
}

impl<T: Real> WithSimd for Batch<'_, '_, '_, T> {
    type Output = ();

    // `inline(always)`: the body must be compiled inside pulp's `#[target_feature]` function.
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) {
        let Self { c, u, out } = self;
        let n = u.lobe.len();
        let lanes = T::width::<S>();
        let mut code = [T::zero(); 16];
        let mut start = 0;
        while start < n {
            // The last vector overlaps the one before it (no masked store: slow on AMD); a
            // batch shorter than a vector goes through masked loads and stores.
            let (lo, full) = if start + lanes <= n {
                (start, true)
            } else if n >= lanes {
                (n - lanes, true)
            } else {
                (0, false)
            };
            let hi = if full { lo + lanes } else { n };
            let load = |x: &[T]| {
                if full {
                    T::vsplit::<S>(&x[lo..hi]).0[0]
                } else {
                    T::load_partial(s, &x[lo..hi])
                }
            };
            let v = lanes_of::<S, T>(s, c, load(u.lobe), load(u.u0), load(u.u1));
            let outs: [&mut [T]; 5] = [
                &mut out.x[lo..hi],
                &mut out.y[lo..hi],
                &mut out.z[lo..hi],
                &mut out.pdf[lo..hi],
                &mut out.delta_weight[lo..hi],
            ];
            for (o, vk) in outs.into_iter().zip(v) {
                if full {
                    T::vsplit_mut::<S>(o).0[0] = vk;
                } else {
                    T::store_partial(s, o, vk);
                }
            }
            T::store_partial(s, &mut code[..hi - lo], v[5]);
            for (b, c) in out.lobe[lo..hi].iter_mut().zip(&code[..hi - lo]) {
                *b = c.to_f64() as u8;
            }
            start = hi;
        }
    }
}

/// `clamp01` of the scalar sampler in lanes (NaN → 0).
#[inline(always)]
fn clamp01<S: Simd, F: Real>(s: S, v: F::V<S>) -> F::V<S> {
    let v = F::vselect(s, F::veq(s, v, v), v, F::vlit(s, 0.0));
    F::vmin(
        s,
        F::vmax(s, v, F::vlit(s, 0.0)),
        F::vsplat(s, F::one() - F::lit(0.5) * F::EPSILON),
    )
}

/// `a` where `m`, else `b`, for a scalar pair.
#[inline(always)]
fn pick<S: Simd, F: Real>(s: S, m: F::M<S>, a: F, b: F) -> F::V<S> {
    F::vselect(s, m, F::vsplat(s, a), F::vsplat(s, b))
}

/// Five constants on every lane.
#[inline(always)]
fn splat5<S: Simd, F: Real>(s: S, f: [F; 5]) -> [F::V<S>; 5] {
    [
        F::vsplat(s, f[0]),
        F::vsplat(s, f[1]),
        F::vsplat(s, f[2]),
        F::vsplat(s, f[3]),
        F::vsplat(s, f[4]),
    ]
}

/// `𝒩(h; c, L Lᵀ)` of one lobe on every lane (`GaussLobe::density`).
#[inline(always)]
fn density<S: Simd, F: Real>(s: S, g: &Gauss<F>, hx: F::V<S>, hy: F::V<S>) -> F::V<S> {
    density_lanes::<S, F>(s, splat5::<S, F>(s, g.flat()), F::vsplat(s, g.norm), hx, hy)
}

/// [`density`] with the lobe's constants `[c₀, c₁, l₀₀, l₁₀, l₁₁]` and `norm` per lane.
#[inline(always)]
fn density_lanes<S: Simd, F: Real>(
    s: S,
    [c0, c1, l00, l10, l11]: [F::V<S>; 5],
    norm: F::V<S>,
    hx: F::V<S>,
    hy: F::V<S>,
) -> F::V<S> {
    let z0 = F::vdiv(s, F::vsub(s, hx, c0), l00);
    let z1 = F::vdiv(s, F::vsub(s, F::vsub(s, hy, c1), F::vmul(s, l10, z0)), l11);
    let q = F::vadd(s, F::vmul(s, z0, z0), F::vmul(s, z1, z1));
    F::vmul(
        s,
        norm,
        crate::simd::exp::vexp::<S, F>(s, F::vmul(s, F::vlit(s, -0.5), q)),
    )
}

/// `a·b` of a lane vector and a constant vector (`a.x b.x + a.y b.y + a.z b.z`).
#[inline(always)]
fn dot<S: Simd, F: Real>(s: S, a: &[F::V<S>; 3], b: &[F; 3]) -> F::V<S> {
    let c = |v: F| F::vsplat(s, v);
    F::vadd(
        s,
        F::vadd(s, F::vmul(s, a[0], c(b[0])), F::vmul(s, a[1], c(b[1]))),
        F::vmul(s, a[2], c(b[2])),
    )
}

/// One vector of draws: `[x, y, z, pdf, delta_weight, code]` (module docs).
#[inline(always)]
#[expect(
    clippy::too_many_lines,
    reason = "one draw, in the order of LobeSampler::sample"
)]
fn lanes_of<S: Simd, F: Real>(
    s: S,
    c: &LaneSampler<F>,
    u_lobe: F::V<S>,
    u0: F::V<S>,
    u1: F::V<S>,
) -> [F::V<S>; 6] {
    let k = |v: F| F::vsplat(s, v);
    let zero = F::vlit(s, 0.0);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);

    // The part: the first with `v < acc + p` (the last part takes what rounding leaves).
    let v = clamp01::<S, F>(s, u_lobe);
    let mut chosen = F::vlt(s, zero, zero);
    let mut part = zero;
    let mut w = v;
    let mut acc = F::zero();
    for (i, &p) in c.probs.iter().enumerate() {
        if p > F::zero() {
            let m = if i == 3 {
                F::veq(s, zero, zero)
            } else {
                F::vlt(s, v, k(acc + p))
            };
            let new = F::vand(s, m, F::vnot(s, chosen));
            w = F::vselect(
                s,
                new,
                clamp01::<S, F>(s, F::vdiv(s, sub(s, v, k(acc)), k(p))),
                w,
            );
            part = F::vselect(s, new, F::vlit(s, i as f64), part);
            chosen = F::vor(s, chosen, new);
        }
        acc += p;
    }
    let transmitted = F::vle(s, F::vlit(s, 2.0), part);
    let scattered = F::vor(
        s,
        F::veq(s, part, F::vlit(s, 1.0)),
        F::veq(s, part, F::vlit(s, 3.0)),
    );
    let delta = match c.spec {
        Spec::Delta => F::vnot(s, scattered),
        _ => F::vlt(s, zero, zero),
    };

    // The lobe's constants on every lane: the scattered lobe, or the specular channel `w`
    // chooses (`v ≥ w₀`: the second).
    let unit = Gauss {
        c: [F::zero(); 2],
        l: [F::one(), F::zero(), F::one()],
        norm: F::one(),
    };
    let (spec0, spec1, two) = match c.spec {
        Spec::Gauss(l, count) => (l[0], l[1], count == 2),
        _ => ((F::one(), unit), (F::zero(), unit), false),
    };
    let second = if two {
        F::vle(s, k(spec0.0), w)
    } else {
        F::vlt(s, zero, zero)
    };
    let (g0, g1) = (spec0.1.flat(), spec1.1.flat());
    let mut g = [zero; 5];
    for j in 0..5 {
        g[j] = pick::<S, F>(s, second, g1[j], g0[j]);
    }
    // The scattered lobe: the one Gaussian, or the series' order lobe `w` chooses on the
    // part's side (`OrderLobes::sample`: the first `j` with `w < Σ_{i≤j} P_i`, the last
    // taking the rest).
    let g_scat = match c.scat {
        Scat::None => splat5::<S, F>(s, unit.flat()),
        Scat::One(l) => splat5::<S, F>(s, l.flat()),
        Scat::Series(sides) => {
            let mut out = [zero; 5];
            for (side, (lobes, count)) in sides.iter().enumerate() {
                let mut sel = splat5::<S, F>(s, lobes[count - 1].1.flat());
                let mut acc = [F::zero(); ORDER_LOBES];
                let mut a = F::zero();
                for j in 0..count - 1 {
                    a += lobes[j].0;
                    acc[j] = a;
                }
                for j in (0..count - 1).rev() {
                    let m = F::vlt(s, w, k(acc[j]));
                    let f = lobes[j].1.flat();
                    for i in 0..5 {
                        sel[i] = F::vselect(s, m, k(f[i]), sel[i]);
                    }
                }
                if side == 0 {
                    out = sel;
                } else {
                    for i in 0..5 {
                        out[i] = F::vselect(s, transmitted, sel[i], out[i]);
                    }
                }
            }
            out
        }
    };
    let mut lobe = [zero; 5];
    for j in 0..5 {
        lobe[j] = F::vselect(s, scattered, g_scat[j], g[j]);
    }
    let [cx, cy, l00, l10, l11] = lobe;

    // Box–Muller (`GaussLobe::sample`): r = √(−2 ln(1 − u₀)), (sin, cos) of 2π u₁.
    let open = sub(s, F::vlit(s, 1.0), clamp01::<S, F>(s, u0));
    let r = F::vsqrt(
        s,
        mul(s, F::vlit(s, -2.0), crate::simd::ln::vln::<S, F>(s, open)),
    );
    let (sn, cs) =
        crate::simd::sin_cos::vsin_cos::<S, F>(s, mul(s, k(F::two_pi()), clamp01::<S, F>(s, u1)));
    let (z0, z1) = (mul(s, r, cs), mul(s, r, sn));
    let hx = add(s, cx, mul(s, l00, z0));
    let hy = add(s, cy, add(s, mul(s, l10, z0), mul(s, l11, z1)));
    // A delta lobe is at h_t = 0; a scattered point is mirrored on a mirrored side.
    let hx = F::vselect(s, delta, zero, hx);
    let hy = F::vselect(s, delta, zero, hy);
    let [m0, m1] = c.maps;
    let flip = match (m0.mirror, m1.mirror) {
        (false, false) => F::vlt(s, zero, zero),
        (true, true) => scattered,
        (true, false) => F::vand(s, scattered, F::vnot(s, transmitted)),
        (false, true) => F::vand(s, scattered, transmitted),
    };
    let hy = F::vselect(s, flip, sub(s, zero, hy), hy);

    // The direction of h_t on the part's side (`SideMap::direction`).
    let (f0, f1) = (m0.flat(), m1.flat());
    let side: [F::V<S>; 12] = core::array::from_fn(|j| pick::<S, F>(s, transmitted, f1[j], f0[j]));
    let kb = side[11];
    let ux = F::vdiv(s, sub(s, hx, side[9]), kb);
    let uy = F::vdiv(s, sub(s, hy, side[10]), kb);
    let r2 = add(s, mul(s, ux, ux), mul(s, uy, uy));
    let propagating = F::vlt(s, r2, k(F::one() - F::EPSILON));
    let cz = F::vsqrt(s, F::vmax(s, sub(s, F::vlit(s, 1.0), r2), zero));
    let d: [F::V<S>; 3] = core::array::from_fn(|j| {
        add(
            s,
            add(s, mul(s, side[j], ux), mul(s, side[3 + j], uy)),
            mul(s, side[6 + j], cz),
        )
    });

    // The density of the direction, recomputed from it as `LobeSampler::pdf` does.
    let density = pdf_lanes::<S, F>(s, c, d);

    // A delta's pdf is its part's probability; every direction returned has a finite,
    // positive pdf.
    let p_part = {
        let mut p = k(c.probs[0]);
        for i in 1..4 {
            p = F::vselect(s, F::veq(s, part, F::vlit(s, i as f64)), k(c.probs[i]), p);
        }
        p
    };
    let pdf = F::vselect(s, delta, p_part, density);
    let valid = F::vand(
        s,
        F::vand(s, chosen, propagating),
        F::vand(s, F::vlt(s, zero, pdf), F::vle(s, pdf, k(F::MAX))),
    );
    let code = add(
        s,
        add(
            s,
            F::vselect(s, transmitted, F::vlit(s, 1.0), zero),
            F::vselect(s, scattered, F::vlit(s, 2.0), zero),
        ),
        F::vselect(s, delta, F::vlit(s, 4.0), zero),
    );
    let keep = |x: F::V<S>| F::vselect(s, valid, x, zero);
    [
        keep(d[0]),
        keep(d[1]),
        keep(d[2]),
        keep(pdf),
        F::vselect(s, F::vand(s, valid, delta), F::vlit(s, 1.0), zero),
        F::vselect(s, valid, code, F::vlit(s, f64::from(NO_LOBE))),
    ]
}

/// [`LobeSampler::pdf`] of one vector of directions `d` (need not be unit; 0 for a zero or
/// non-finite one), for a sampler the lanes draw from (`LobeSampler::density`, no chart and no
/// disk): the first side whose half-space holds the direction (beyond half the draws' margin
/// from the horizon).
#[inline(always)]
fn pdf_lanes<S: Simd, F: Real>(s: S, c: &LaneSampler<F>, d: [F::V<S>; 3]) -> F::V<S> {
    let k = |v: F| F::vsplat(s, v);
    let zero = F::vlit(s, 0.0);
    let (add, sub, mul) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>);
    let [m0, m1] = c.maps;
    let norm = F::vsqrt(
        s,
        add(
            s,
            add(s, mul(s, d[0], d[0]), mul(s, d[1], d[1])),
            mul(s, d[2], d[2]),
        ),
    );
    let dn: [F::V<S>; 3] = core::array::from_fn(|j| F::vdiv(s, d[j], norm));
    let margin = k(F::EPSILON.sqrt() * F::lit(0.5));
    let cos0 = dot::<S, F>(s, &dn, &m0.n);
    let in0 = F::vlt(s, margin, cos0);
    let (below, cos) = if c.transmits {
        let cos1 = dot::<S, F>(s, &dn, &m1.n);
        let in1 = F::vand(s, F::vnot(s, in0), F::vlt(s, margin, cos1));
        (in1, F::vselect(s, in1, cos1, cos0))
    } else {
        (F::vlt(s, zero, zero), cos0)
    };
    let inside = F::vor(s, in0, below);
    let kd = pick::<S, F>(s, below, m1.k, m0.k);
    // h_t = k_a u_a + k_b (d·t̂₁, d·t̂₂) on the side holding the direction (`SideMap::h_of`).
    let tangential = |j: usize, t1: &[F; 3], t0: &[F; 3]| {
        let d = F::vselect(s, below, dot::<S, F>(s, &dn, t1), dot::<S, F>(s, &dn, t0));
        add(
            s,
            pick::<S, F>(s, below, m1.known_h[j], m0.known_h[j]),
            mul(s, d, kd),
        )
    };
    let gx = tangential(0, &m1.t1, &m0.t1);
    let gy = tangential(1, &m1.t2, &m0.t2);
    let p_spec = pick::<S, F>(s, below, c.probs[2], c.probs[0]);
    let p_scat = pick::<S, F>(s, below, c.probs[3], c.probs[1]);
    let spec = match c.spec {
        Spec::Gauss(l, count) => {
            let mut a = mul(s, k(l[0].0), density::<S, F>(s, &l[0].1, gx, gy));
            a = add(s, zero, a);
            if count == 2 {
                a = add(s, a, mul(s, k(l[1].0), density::<S, F>(s, &l[1].1, gx, gy)));
            }
            mul(s, p_spec, a)
        }
        _ => zero,
    };
    let mirrored = match (m0.mirror, m1.mirror) {
        (false, false) => F::vlt(s, zero, zero),
        (true, true) => F::veq(s, zero, zero),
        (true, false) => F::vnot(s, below),
        (false, true) => below,
    };
    let fy = F::vselect(s, mirrored, sub(s, zero, gy), gy);
    let scat = match c.scat {
        Scat::One(g) => {
            let dens = density::<S, F>(s, &g, gx, fy);
            F::vselect(s, F::vlt(s, zero, p_scat), mul(s, p_scat, dens), zero)
        }
        Scat::Series(sides) => {
            // `OrderLobes::density` of the side holding the direction: `Σ_j P_j 𝒩_j(h)`, a
            // side with fewer lobes padded with weight 0 (`a + 0·𝒩 = a`).
            let [(l0, n0), (l1, n1)] = sides;
            let n1 = if c.transmits { n1 } else { 0 };
            let mut dens = zero;
            for j in 0..n0.max(n1) {
                let (w0, g0) = if j < n0 { l0[j] } else { (F::zero(), l0[0].1) };
                let (w1, g1) = if j < n1 { l1[j] } else { (F::zero(), l0[0].1) };
                let (f0, f1) = (g0.flat(), g1.flat());
                let mut g = [zero; 5];
                for i in 0..5 {
                    g[i] = pick::<S, F>(s, below, f1[i], f0[i]);
                }
                let dj =
                    density_lanes::<S, F>(s, g, pick::<S, F>(s, below, g1.norm, g0.norm), gx, fy);
                dens = add(s, dens, mul(s, pick::<S, F>(s, below, w1, w0), dj));
            }
            F::vselect(s, F::vlt(s, zero, p_scat), mul(s, p_scat, dens), zero)
        }
        Scat::None => zero,
    };
    let density = mul(s, mul(s, add(s, spec, scat), mul(s, kd, kd)), cos);
    F::vselect(s, inside, density, zero)
}
