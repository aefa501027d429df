//! Variants (model level × blur method × precision × API), their dispatch to monomorphised
//! kernels, and the timing loop.

use std::cell::RefCell;
use std::hint::black_box;
use std::time::{Duration, Instant};

use gmueller::Real;
use gmueller::gaussian::Gaussian;
use gmueller::interaction::batch::{DirectionsSoa, LobesSoa, StokesSoa, plane_wave_rayleigh_rice};
use gmueller::interaction::coherence::{CoherenceLevel, CoherenceModel, CoherenceWeights};
use gmueller::interaction::level::LevelVisitor;
use gmueller::interaction::pbsdf::{Pbsdf, RayleighRice};
use gmueller::interaction::polarization::{KernelOutput, PolarizationLevel, PolarizationModel};
use gmueller::interaction::{
    Full, Geometry, Intensity, Kernel, Level, OneShape, Partial, RoughSurface,
};
use gmueller::psd::{Adaptive, BlurMethod, ClosedForm, GaussHermite, GaussianPsd, Psd};
use nalgebra::{Matrix2, Vector2};

use super::scenes::{MIXTURES, Material, SceneData};

/// Polarization level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pol {
    Intensity,
    OneShape,
    Full,
}
/// Coherence level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coh {
    PlaneWave,
    Incoherent,
    Partial,
}
/// Blur method (only the partially coherent level blurs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Blur {
    /// Not used (plane-wave and incoherent limits evaluate `p(h)` or `∫p` only).
    None,
    /// Exact closed form (Gaussian PSDs, the grating).
    Exact,
    /// Gaussian-mixture fit of the K-correlation with m components, then closed form.
    Mixture(usize),
    /// Gauss–Hermite of the given order (continuous PSDs).
    GaussHermite(usize),
    /// Adaptive Gauss–Kronrod to the given relative tolerance (continuous PSDs).
    Adaptive(f64),
}
/// Precision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prec {
    F32,
    F64,
}

/// How a variant calls the library.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Api {
    /// `Kernel::prepare` once per pass, then `Kernel::evaluate_prepared` per exit direction on
    /// the scene's precomputed geometries.
    PerDirection,
    /// One batch call per pass for every exit direction of the scene (geometries built inside
    /// the call): `Kernel::evaluate_batch` at the partially coherent level,
    /// `interaction::batch::plane_wave_rayleigh_rice` at the plane-wave level.
    Batch,
}

/// One model variant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variant {
    pub pol: Pol,
    pub coh: Coh,
    pub blur: Blur,
    pub prec: Prec,
    pub api: Api,
}

impl Variant {
    /// Human-readable label, e.g. `Full·Partial·GH8·f64`, or `Full·Partial·exact·f64 batch`
    /// for a batch row.
    pub fn label(&self) -> String {
        format!(
            "{}·{}·{}·{}{}",
            match self.pol {
                Pol::Intensity => "Intensity",
                Pol::OneShape => "OneShape",
                Pol::Full => "Full",
            },
            match self.coh {
                Coh::PlaneWave => "PlaneWave",
                Coh::Incoherent => "Incoherent",
                Coh::Partial => "Partial",
            },
            self.blur_label(),
            match self.prec {
                Prec::F32 => "f32",
                Prec::F64 => "f64",
            },
            match self.api {
                Api::PerDirection => "",
                Api::Batch => " batch",
            }
        )
    }

    /// The per-direction variant of the same model (itself for a per-direction variant).
    pub fn per_direction(&self) -> Self {
        Self {
            api: Api::PerDirection,
            ..*self
        }
    }

    /// The blur part of the label.
    pub fn blur_label(&self) -> String {
        match self.blur {
            Blur::None => "—".into(),
            Blur::Exact => "exact".into(),
            Blur::Mixture(m) => format!("mix{m}"),
            Blur::GaussHermite(n) => format!("GH{n}"),
            Blur::Adaptive(t) => format!("adapt{t:.0e}"),
        }
    }

    /// Whether the variant applies to a material (quadrature needs a continuous PSD, the
    /// mixture fit a K-correlation, the exact blur a closed form; the plane-wave batch
    /// `plane_wave_rayleigh_rice` a Gaussian PSD in reflection).
    pub fn applies(&self, m: &super::scenes::MaterialSpec) -> bool {
        use super::scenes::MaterialSpec as M;
        if self.api == Api::Batch && self.coh == Coh::PlaneWave {
            return matches!(m, M::Gaussian { .. } | M::Brushed { .. });
        }
        match self.blur {
            Blur::None => true,
            Blur::Exact => !matches!(m, super::scenes::MaterialSpec::KCorr { .. }),
            Blur::Mixture(_) => matches!(m, super::scenes::MaterialSpec::KCorr { .. }),
            Blur::GaussHermite(_) | Blur::Adaptive(_) => m.continuous(),
        }
    }
}

/// Every variant of the harness.
pub fn all_variants() -> Vec<Variant> {
    let mut v = Vec::new();
    for prec in [Prec::F64, Prec::F32] {
        for pol in [Pol::Full, Pol::OneShape, Pol::Intensity] {
            for coh in [Coh::PlaneWave, Coh::Incoherent] {
                v.push(Variant {
                    pol,
                    coh,
                    blur: Blur::None,
                    prec,
                    api: Api::PerDirection,
                });
            }
            let mut blurs = vec![Blur::Exact];
            blurs.extend(MIXTURES.iter().map(|&m| Blur::Mixture(m)));
            blurs.extend([4, 8, 16].map(Blur::GaussHermite));
            if pol == Pol::Full && prec == Prec::F64 {
                // Slow (milliseconds per evaluation): full level, f64, 45° scenes only.
                blurs.push(Blur::Adaptive(1e-4));
            }
            for blur in blurs {
                v.push(Variant {
                    pol,
                    coh: Coh::Partial,
                    blur,
                    prec,
                    api: Api::PerDirection,
                });
            }
        }
    }
    // The batch rows (after their per-direction twins, which are measured first on each scene):
    // `Kernel::evaluate_batch` at Full, OneShape and Intensity · Partial · exact, Full · Partial
    // on the K-correlation's mixture fits, Full · Incoherent, and the plane-wave batch
    // `plane_wave_rayleigh_rice` (= Full·PlaneWave), both precisions.
    for prec in [Prec::F64, Prec::F32] {
        for (pol, coh, blur) in [
            (Pol::Full, Coh::Partial, Blur::Exact),
            (Pol::OneShape, Coh::Partial, Blur::Exact),
            (Pol::Intensity, Coh::Partial, Blur::Exact),
            (Pol::Full, Coh::Partial, Blur::Mixture(MIXTURES[0])),
            (Pol::Full, Coh::Partial, Blur::Mixture(MIXTURES[1])),
            (Pol::Full, Coh::Incoherent, Blur::None),
            (Pol::Full, Coh::PlaneWave, Blur::None),
        ] {
            v.push(Variant {
                pol,
                coh,
                blur,
                prec,
                api: Api::Batch,
            });
        }
    }
    v
}

/// Output of one variant on one scene: total Stokes per exit direction, and the median time per
/// evaluation (ns).
pub struct Measured {
    pub stokes: Vec<[f64; 4]>,
    pub ns: f64,
}

/// Timing policy: at least `min_batches` batches (each = every exit direction of the scene once),
/// more while the elapsed time is below `budget`, at most `max_batches`.
#[derive(Debug, Clone, Copy)]
pub struct Timing {
    pub budget: Duration,
    pub min_batches: usize,
    pub max_batches: usize,
}

/// The timing policy applied to a scene whose first (recording) pass took `first`: repeated
/// passes of `pass`, each over `n` evaluations; the median time per evaluation (ns).
fn timed(first: Duration, n: f64, timing: Timing, mut pass: impl FnMut()) -> f64 {
    let mut times = Vec::new();
    let min = if first > timing.budget {
        times.push(first.as_secs_f64() * 1e9 / n);
        0
    } else {
        timing.min_batches
    };
    let start = Instant::now();
    while times.len() < min || (start.elapsed() < timing.budget && times.len() < timing.max_batches)
    {
        let t = Instant::now();
        pass();
        times.push(t.elapsed().as_secs_f64() * 1e9 / n);
    }
    median(&mut times)
}

fn run<T, Pol2, Coh2, P, Sp, Sc>(
    kernel: &Kernel<Pol2, Coh2>,
    m: &RoughSurface<P, Sp, Sc>,
    s: &SceneData<T>,
    timing: Timing,
) -> Measured
where
    T: Real,
    Pol2: PolarizationModel,
    Coh2: CoherenceWeights<T, P>,
    P: Psd<T, 2>,
    Sp: Pbsdf<T>,
    Sc: Pbsdf<T>,
{
    let n = s.geoms.len() as f64;
    // The first pass records the values (and counts as a batch if it is already slow).
    // One packet, a grid of exit directions: the per-packet work (`Kernel::prepare`) is done
    // once per pass and counted in the time per evaluation (amortised over the grid).
    let t0 = Instant::now();
    let prepared = kernel
        .prepare(&s.packet, s.geoms[0].surface())
        .expect("the scene's packet travels toward the surface");
    let stokes: Vec<[f64; 4]> = s
        .geoms
        .iter()
        .map(|g| {
            let r = kernel.evaluate_prepared(m, &prepared, g);
            // The Intensity level computes S0 only (the other components are not compared).
            r.stokes().map_or(
                [r.scattered_intensity().to_f64(), 0.0, 0.0, 0.0],
                |(_, scattered)| {
                    let v = scattered.vector();
                    [v[0].to_f64(), v[1].to_f64(), v[2].to_f64(), v[3].to_f64()]
                },
            )
        })
        .collect();
    let first = t0.elapsed();
    let ns = timed(first, n, timing, || {
        let prepared = kernel
            .prepare(black_box(&s.packet), s.geoms[0].surface())
            .expect("the scene's packet travels toward the surface");
        for g in &s.geoms {
            black_box(kernel.evaluate_prepared(black_box(m), black_box(&prepared), black_box(g)));
        }
    });
    Measured { stokes, ns }
}

/// The f64 Stokes vectors of a batch's scattered lobe (the Intensity level writes `S0` only; the
/// other columns stay at the buffers' initial 0, as the per-direction rows record them).
fn soa_stokes<T: Real>(s: &[&mut [T]; 4], n: usize) -> Vec<[f64; 4]> {
    (0..n)
        .map(|i| [0, 1, 2, 3].map(|c| s[c][i].to_f64()))
        .collect()
}

/// A batch row through `Kernel::evaluate_batch`: one call per pass for every exit direction of
/// the scene (the per-packet work and the geometries inside the call, as a renderer would use
/// it), the time per evaluation = call time / number of exits. The output buffers are
/// allocated once, outside the timed region; the frames are not requested.
fn run_batch<T, Pol2, Coh2, P, Sp, Sc>(
    kernel: &Kernel<Pol2, Coh2>,
    m: &RoughSurface<P, Sp, Sc>,
    s: &SceneData<T>,
    timing: Timing,
) -> Measured
where
    T: Real,
    Pol2: PolarizationModel,
    Coh2: CoherenceModel + CoherenceWeights<T, P> + 'static,
    P: Psd<T, 2> + 'static,
    Sp: Pbsdf<T> + 'static,
    Sc: Pbsdf<T> + 'static,
{
    let n = s.exits[0].len();
    let exits = DirectionsSoa {
        x: &s.exits[0],
        y: &s.exits[1],
        z: &s.exits[2],
    };
    let mut buf = vec![vec![T::zero(); n]; 8];
    let [a, b, c, d, e, f, g, h] = &mut buf[..] else {
        unreachable!("eight columns")
    };
    let mut out = LobesSoa {
        specular: StokesSoa { s: [a, b, c, d] },
        scattered: StokesSoa { s: [e, f, g, h] },
    };
    let call = |out: &mut LobesSoa<'_, T>| {
        kernel
            .evaluate_batch(
                black_box(m),
                black_box(&s.packet),
                black_box(&s.surface),
                black_box(s.interface),
                black_box(exits),
                out,
                None,
            )
            .expect("every exit of the scene is valid");
        black_box(&mut *out);
    };
    let t0 = Instant::now();
    call(&mut out);
    let first = t0.elapsed();
    let stokes = soa_stokes(&out.scattered.s, n);
    let ns = timed(first, n as f64, timing, || call(&mut out));
    Measured { stokes, ns }
}

/// The plane-wave batch row: `plane_wave_rayleigh_rice` (the scattered lobe of
/// `Kernel::<Full, PlaneWave>`; its specular lobe is a delta, 0 off the exact specular
/// direction, so the scattered lobe is what the per-direction rows record too), one call per
/// pass, buffers allocated outside the timed region.
fn run_plane_wave_batch<T: Real, Sp>(
    m: &RoughSurface<GaussianPsd<T, 2>, Sp, RayleighRice<T>>,
    s: &SceneData<T>,
    timing: Timing,
) -> Measured {
    let n = s.exits[0].len();
    let exits = DirectionsSoa {
        x: &s.exits[0],
        y: &s.exits[1],
        z: &s.exits[2],
    };
    let mut buf = vec![vec![T::zero(); n]; 4];
    let [a, b, c, d] = &mut buf[..] else {
        unreachable!("four columns")
    };
    let mut out = StokesSoa { s: [a, b, c, d] };
    let call = |out: &mut StokesSoa<'_, T>| {
        plane_wave_rayleigh_rice(
            black_box(m),
            black_box(&s.packet),
            black_box(&s.surface),
            black_box(&exits),
            out,
        )
        .expect("every exit of the scene is valid");
        black_box(&mut *out);
    };
    let t0 = Instant::now();
    call(&mut out);
    let first = t0.elapsed();
    let stokes = soa_stokes(&out.s, n);
    let ns = timed(first, n as f64, timing, || call(&mut out));
    Measured { stokes, ns }
}

/// `Kernel::evaluate_batch` at polarization level `pol`, `Partial(ClosedForm)`.
fn batch_partial_exact<T, P, Sp, Sc>(
    pol: Pol,
    m: &RoughSurface<P, Sp, Sc>,
    s: &SceneData<T>,
    timing: Timing,
) -> Measured
where
    T: Real,
    Partial<ClosedForm>: CoherenceWeights<T, P>,
    P: Psd<T, 2> + 'static,
    Sp: Pbsdf<T> + 'static,
    Sc: Pbsdf<T> + 'static,
{
    let coh = Partial(ClosedForm);
    match pol {
        Pol::Full => run_batch(&Kernel::<Full, _>::new(coh), m, s, timing),
        Pol::OneShape => run_batch(&Kernel::<OneShape, _>::new(coh), m, s, timing),
        Pol::Intensity => run_batch(&Kernel::<Intensity, _>::new(coh), m, s, timing),
    }
}

/// Runs a batch variant; `None` where it does not apply (see [`Variant::applies`]).
fn measure_batch<T: Real>(
    v: &Variant,
    mat: &Material<T>,
    s: &SceneData<T>,
    timing: Timing,
) -> Option<Measured> {
    Some(match (v.coh, v.blur, mat) {
        (Coh::PlaneWave, Blur::None, Material::Gauss(m))
            if v.pol == Pol::Full && s.interface.is_none() =>
        {
            run_plane_wave_batch(m, s, timing)
        }
        (Coh::Partial, Blur::Exact, Material::Gauss(m)) => batch_partial_exact(v.pol, m, s, timing),
        (Coh::Partial, Blur::Exact, Material::Grating(m)) => {
            batch_partial_exact(v.pol, m, s, timing)
        }
        (Coh::Partial, Blur::Exact, Material::Interface(m)) => {
            batch_partial_exact(v.pol, m, s, timing)
        }
        (Coh::Partial, Blur::Mixture(n), Material::K { mixtures, .. }) => {
            let i = MIXTURES.iter().position(|&x| x == n)?;
            batch_partial_exact(v.pol, &mixtures[i], s, timing)
        }
        (Coh::Incoherent, Blur::None, mat) if v.pol == Pol::Full => {
            let k = Kernel::<Full, gmueller::interaction::Incoherent>::default();
            match mat {
                Material::Gauss(m) => run_batch(&k, m, s, timing),
                Material::K { exact, .. } => run_batch(&k, exact, s, timing),
                Material::Grating(m) => run_batch(&k, m, s, timing),
                Material::Interface(m) => run_batch(&k, m, s, timing),
            }
        }
        _ => return None,
    })
}

/// The median time (ns) to build one exit geometry of the scene (`Geometry::for_packet` or
/// `Geometry::for_packet_at_interface`), which the per-direction rows take precomputed and the
/// batch calls build inside: for the batch section's like-for-like comparison.
pub fn geometry_ns<T: Real>(s: &SceneData<T>, timing: Timing) -> f64 {
    let n = s.exits[0].len();
    let pass = || {
        for i in 0..n {
            let e = nalgebra::Vector3::new(s.exits[0][i], s.exits[1][i], s.exits[2][i]);
            let (p, f) = (black_box(&s.packet), black_box(&s.surface));
            black_box(match s.interface {
                None => Geometry::for_packet(p, f, black_box(e)),
                Some(eta) => Geometry::for_packet_at_interface(p, f, eta, black_box(e)),
            })
            .expect("every exit of the scene is valid");
        }
    };
    let t0 = Instant::now();
    pass();
    timed(t0.elapsed(), n as f64, timing, pass)
}

/// Median (sorts in place); NaN for an empty slice.
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let k = v.len() / 2;
    if v.len() % 2 == 1 {
        v[k]
    } else {
        0.5 * (v[k - 1] + v[k])
    }
}

/// The harness's run as a [`LevelVisitor`]: the library's [`Level::dispatch`] picks the
/// monomorphised kernel.
struct Run<'a, T: Real, P, Sp, Sc> {
    material: &'a RoughSurface<P, Sp, Sc>,
    scene: &'a SceneData<T>,
    timing: Timing,
}

impl<T: Real, P: Psd<T, 2>, Sp: Pbsdf<T>, Sc: Pbsdf<T>> LevelVisitor<T, P>
    for Run<'_, T, P, Sp, Sc>
{
    type Output = Measured;
    fn visit<Pol2, Coh2>(self, _level: Level, kernel: Kernel<Pol2, Coh2>) -> Measured
    where
        Pol2: PolarizationModel,
        Coh2: CoherenceWeights<T, P>,
    {
        run(&kernel, self.material, self.scene, self.timing)
    }
}

/// The library's level of a harness variant.
fn level(pol: Pol, coh: Coh) -> Level {
    Level::new(
        match pol {
            Pol::Intensity => PolarizationLevel::Intensity,
            Pol::OneShape => PolarizationLevel::OneShape,
            Pol::Full => PolarizationLevel::Full,
        },
        match coh {
            Coh::PlaneWave => CoherenceLevel::PlaneWave,
            Coh::Incoherent => CoherenceLevel::Incoherent,
            Coh::Partial => CoherenceLevel::Partial,
        },
    )
}

macro_rules! levels {
    ($pol:expr, $coh:expr, $blur:expr, $mat:expr, $scene:expr, $timing:expr) => {
        level($pol, $coh).dispatch(
            $blur,
            Run {
                material: $mat,
                scene: $scene,
                timing: $timing,
            },
        )
    };
}

/// Runs variant `v` (its precision must be `T`'s) on a material and scene; `None` if it does not
/// apply to the material.
pub fn measure<T: Real>(
    v: &Variant,
    mat: &Material<T>,
    s: &SceneData<T>,
    timing: Timing,
) -> Option<Measured> {
    if v.api == Api::Batch {
        return measure_batch(v, mat, s, timing);
    }
    let gh = |n: usize| GaussHermite::<T>::new(n).expect("order in range");
    let ad = |t: f64| Adaptive::new(T::lit(t)).expect("tolerance in range");
    Some(match (mat, v.blur) {
        (Material::Gauss(m), Blur::None | Blur::Exact) => {
            levels!(v.pol, v.coh, ClosedForm, m, s, timing)
        }
        (Material::Gauss(m), Blur::GaussHermite(n)) => levels!(v.pol, v.coh, gh(n), m, s, timing),
        (Material::Gauss(m), Blur::Adaptive(t)) => levels!(v.pol, v.coh, ad(t), m, s, timing),
        // The limits never blur: any method type satisfies the bound; it is not called.
        (Material::K { exact, .. }, Blur::None) => levels!(v.pol, v.coh, gh(1), exact, s, timing),
        (Material::K { exact, .. }, Blur::GaussHermite(n)) => {
            levels!(v.pol, v.coh, gh(n), exact, s, timing)
        }
        (Material::K { exact, .. }, Blur::Adaptive(t)) => {
            levels!(v.pol, v.coh, ad(t), exact, s, timing)
        }
        (Material::K { mixtures, .. }, Blur::Mixture(m)) => {
            let i = MIXTURES.iter().position(|&x| x == m)?;
            levels!(v.pol, v.coh, ClosedForm, &mixtures[i], s, timing)
        }
        (Material::Grating(m), Blur::None | Blur::Exact) => {
            levels!(v.pol, v.coh, ClosedForm, m, s, timing)
        }
        (Material::Interface(m), Blur::None | Blur::Exact) => {
            levels!(v.pol, v.coh, ClosedForm, m, s, timing)
        }
        (Material::Interface(m), Blur::GaussHermite(n)) => {
            levels!(v.pol, v.coh, gh(n), m, s, timing)
        }
        (Material::Interface(m), Blur::Adaptive(t)) => levels!(v.pol, v.coh, ad(t), m, s, timing),
        _ => return None,
    })
}

/// The reference: f64, full polarization, partial coherence; the exact closed form for Gaussian
/// PSDs and the grating, adaptive quadrature at 1e-10 for the K-correlation.
pub fn reference(mat: &Material<f64>, s: &SceneData<f64>) -> Measured {
    let timing = Timing {
        budget: Duration::ZERO,
        min_batches: 1,
        max_batches: 1,
    };
    match mat {
        Material::Gauss(m) => run(
            &Kernel::<Full, Partial<_>>::new(Partial(ClosedForm)),
            m,
            s,
            timing,
        ),
        Material::Grating(m) => run(
            &Kernel::<Full, Partial<_>>::new(Partial(ClosedForm)),
            m,
            s,
            timing,
        ),
        Material::Interface(m) => run(
            &Kernel::<Full, Partial<_>>::new(Partial(ClosedForm)),
            m,
            s,
            timing,
        ),
        Material::K { exact, .. } => run(
            &Kernel::<Full, Partial<_>>::new(Partial(Cached::new(
                Adaptive::new(1e-10).expect("valid"),
            ))),
            exact,
            s,
            timing,
        ),
    }
}

/// The last blur: covariance, `h` and the value.
type CacheEntry = (Matrix2<f64>, Vector2<f64>, f64);

/// A blur method that remembers its last answer: the full level blurs three channels, which for
/// a packet with one coherence shape are the same blur (saves 2/3 of the reference's cost).
#[derive(Debug, Clone)]
pub struct Cached<B> {
    inner: B,
    last: RefCell<Option<CacheEntry>>,
}

impl<B> Cached<B> {
    fn new(inner: B) -> Self {
        Self {
            inner,
            last: RefCell::new(None),
        }
    }
}

impl<P: Psd<f64, 2>, B: BlurMethod<f64, 2, P>> BlurMethod<f64, 2, P> for Cached<B> {
    fn blur(&self, psd: &P, cov: &Gaussian<f64, 2>, h: &Vector2<f64>) -> f64 {
        if let Some((c, hh, v)) = *self.last.borrow()
            && c == *cov.covariance()
            && hh == *h
        {
            return v;
        }
        let v = self.inner.blur(psd, cov, h);
        *self.last.borrow_mut() = Some((*cov.covariance(), *h, v));
        v
    }
}

/// The cross-check of the Gaussian reference: the same kernel with adaptive quadrature at 1e-10.
pub fn gaussian_adaptive(mat: &Material<f64>, s: &SceneData<f64>) -> Option<Vec<[f64; 4]>> {
    let timing = Timing {
        budget: Duration::MAX,
        min_batches: 0,
        max_batches: 0,
    };
    match mat {
        Material::Gauss(m) => Some(
            run(
                &Kernel::<Full, Partial<_>>::new(Partial(Adaptive::new(1e-10).expect("valid"))),
                m,
                s,
                timing,
            )
            .stokes,
        ),
        Material::Interface(m) => Some(
            run(
                &Kernel::<Full, Partial<_>>::new(Partial(Adaptive::new(1e-10).expect("valid"))),
                m,
                s,
                timing,
            )
            .stokes,
        ),
        _ => None,
    }
}
