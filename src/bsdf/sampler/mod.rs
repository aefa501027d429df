//! The lobe-mixture sampler: one direction from three uniforms, in either tracing direction,
//! with a density that is the sampler's own exactly.
//!
//! # Formula
//! Both directions point away from the surface; the known one (`d_a`, wavenumber `k_a` of its
//! medium) is the direction to the source when tracing forward (sampling the exit r̂) and the
//! exit direction when tracing backward (sampling the direction to the source ŝ):
//! ```text
//! h_t = k_a u_a + k_b u_b          (u = the tangential components, in the frame the kernel uses)
//! u_b = (h_t − k_a u_a)/k_b,       p_ω(d_b) = p_h(h_t) · k_b² |cos θ_b|          (d²h_t = k_b² cos θ_b dω_b)
//! p_h = Σ_parts P_part · p_part(h_t)                                           (the lobes of `lobes.rs`)
//! ```
//! `k_b = k_a` on the known side (reflection) and the other medium's wavenumber across an
//! interface (transmission). A draw whose `|u_b| ≥ 1` (evanescent) is rejected, and so is one
//! within `cos θ_b ≤ √ε` of the horizon (ε the machine epsilon of the scalar type; 3.5·10⁻⁴
//! in `f32`, 89.98°), where a direction is not on a definite side of the surface in that type
//! (its dot product with the normal is rounding): `pdf` is 0 there, and every direction
//! `sample` returns has a finite, positive `pdf` (in `f32` at 89.99° the angle chart below drew
//! a direction 1.3·10⁻⁸ from the plane, whose weight was refused); Dirac lobes
//! (the specular lobe of a plane wave, grating orders of a plane wave) are drawn with their
//! probability and excluded from the density, as pbrt and Mitsuba do.
//!
//! # Grazing specular lobes (backward)
//! As a function of ŝ the kernel's coherent specular lobe goes as `g(h_t) cos θ_o`, while the
//! projected-disk density above goes as `g(h_t) cos θ_i`: where the lobe reaches the horizon,
//! `M/p ∝ cos θ_o/cos θ_i` is unbounded and its variance diverges (logarithmically). So when
//! tracing backward, a specular lobe whose centre lies within 4 of its standard deviations of
//! the horizon (in the projected disk) is drawn half of the time in the **angle chart**
//! `x = θ ê` (θ from the normal, ê the tangential direction; `d²x = (θ/sin θ) dω`, bounded
//! at the horizon) from a Gaussian about the lobe's centre whose widths are the lobe's image
//! there (radially `(asin(u_c + σ) − asin(u_c − σ))/2`, tangentially `σ θ_c/u_c`) widened by
//! 1.5:
//! ```text
//! p_ω(ŝ) += P_spec · ½ · 𝒩(x(ŝ); x_c, Σ_x) · θ/sin θ        (the h_t term of the part halved)
//! ```
//! (measured: at 85° and 20 µm of coherence the largest of 200 000 weights fell from 320× to
//! 9× the mean, `tests/bsdf/sampling.rs`).
//!
//! # Part probabilities
//! ```text
//! E = [R α_r,  R (1 − α_r),  T α_t,  T (1 − α_t)]      (reflected/transmitted × specular/scattered)
//! R = Fresnel reflectance at the known angle,  T = 1 − R (0 for a conductor, and for the specular
//! part where no Snell partner exists),  α = exp(−(vσ)²) at the specular direction of the side
//! P_j = max(E_j, ε ΣE) / Σ_k max(E_k, ε ΣE)      over the parts that exist,  ε = 10⁻³
//! ```
//! (the Kirchhoff estimate of each part's energy, which the first-order kernel follows to
//! `(vσ)²`; under total internal reflection, where `T = 0` at the known angle, the scattered
//! transmission is estimated as `(1 − R₀)(1 − exp(−(k_a σ cos θ_a)²))` with `R₀` the
//! normal-incidence reflectance; for grating orders the scattered estimate is the sum over the
//! propagating orders of `(η_m/σ²)(1 − exp(−(v_m σ)²))`, `v_m` each order's phase factor). The
//! floor keeps every existing part drawable whatever its estimate,
//! and leaves the parts above it exactly proportional to their estimates: where one lobe carries
//! almost everything (sunlit glass), a uniform floor of 1/50 had made the furnace estimate five
//! times noisier than the best mixture (`tests/bsdf/furnace.rs`).

use nalgebra::{Matrix2, Vector2, Vector3};

use super::lobes::{GaussLobe, PowerLobe};
use super::orders::{DISK_SHARE, OrderLobes, disk_point};
use crate::frame::Frame;
use crate::interaction::Side;
use crate::interaction::coherence::CoherenceLevel;
use crate::psd::{GaussianPsd, Shape};
use crate::real::Real;

mod batch;

pub use batch::{NO_LOBE, SamplesSoa, UniformsSoa};

/// The narrowest Gaussian lobe a sampler accepts, in machine epsilons of the scalar type
/// (standard deviation in the projected disk).
const MIN_WIDTH_ULPS: f64 = 8.0;
/// The floor `ε` of the part probabilities (module docs).
const PART_FLOOR: f64 = 1e-3;
/// The weight of a blurred grating order whose centre lies beyond the propagating directions
/// (by more than three blur widths), relative to its efficiency.
const HIDDEN_ORDER_WEIGHT: f64 = 1e-3;

/// Backward specular lobes whose centre lies within this many standard deviations (in the
/// projected disk) of the horizon are also drawn in the angle chart (module docs).
const HORIZON_REACH: f64 = 4.0;
/// The share of the angle chart in such a specular part.
const HORIZON_SHARE: f64 = 0.5;
/// The widening of the angle-chart lobe over the linearised image of the specular lobe.
const HORIZON_WIDEN: f64 = 1.5;

/// Which part of the kernel a sample was drawn from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Part {
    /// The coherent specular lobe (mirror or Snell direction, widened by the coherence).
    Specular,
    /// The scattered part (the PSD's lobes, grating orders).
    Scattered,
}

/// The lobe a sample came from: side, part, and whether it is a Dirac delta.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SampledLobe {
    /// Reflection or transmission.
    pub side: Side,
    /// Specular or scattered.
    pub part: Part,
    /// A Dirac delta (the specular lobe, or a grating order, at the plane-wave level): the
    /// sample's `pdf` is then the probability of choosing it, and its value is not in `eval`.
    pub delta: bool,
}

/// One direction drawn by the sampler.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionSample<T: Real> {
    /// The drawn unit direction, pointing away from the surface (the exit r̂ when tracing
    /// forward, the direction to the source ŝ when tracing backward).
    pub direction: Vector3<T>,
    /// Its density per unit solid angle, equal to the sampler's `pdf(direction)`; for a delta
    /// lobe the probability of having chosen it.
    pub pdf: T,
    /// The lobe it was drawn from.
    pub lobe: SampledLobe,
    /// For a delta lobe, its weight in the PSD: `η_m` of a grating order, `R(0)` of a smooth
    /// PSD's order, 1 for the specular delta; 0 otherwise.
    pub delta_weight: T,
}

/// The map between `h_t` and the unknown direction on one side.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SideMap<T: Real> {
    t1: Vector3<T>,
    t2: Vector3<T>,
    /// The normal of the unknown direction's half-space.
    n: Vector3<T>,
    /// `k_a u_a` in this side's tangent frame.
    known_h: Vector2<T>,
    /// `k_b`.
    k: T,
    /// This side's tangent frame is the caller's with t̂₂ negated: a PSD (given in the
    /// caller's frame) sees `h_t` mirrored, `(h₁, −h₂)`.
    mirror: bool,
}

impl<T: Real> SideMap<T> {
    /// `h` between this side's tangent frame and the caller's (where the PSD lives): `(h₁, −h₂)`
    /// on a mirrored side (its own inverse).
    #[inline]
    fn flip(&self, h: &Vector2<T>) -> Vector2<T> {
        if self.mirror {
            Vector2::new(h.x, -h.y)
        } else {
            *h
        }
    }

    /// `h_t` of an unknown direction `d` (unit) on this side, `None` if `d` is not in its
    /// half-space.
    #[inline]
    fn h_of(&self, d: &Vector3<T>) -> Option<(Vector2<T>, T)> {
        let c = d.dot(&self.n);
        // Below half the draws' margin from the horizon no lobe draws (module docs).
        (c > T::EPSILON.sqrt() * T::lit(0.5)).then(|| {
            (
                self.known_h + Vector2::new(d.dot(&self.t1), d.dot(&self.t2)) * self.k,
                c,
            )
        })
    }

    /// The unknown direction of `h_t`, `None` where it is evanescent.
    #[inline]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN must fail the test too"
    )]
    fn direction(&self, h: &Vector2<T>) -> Option<Vector3<T>> {
        let u = (h - self.known_h) / self.k;
        let r2 = u.norm_squared();
        // r2 < 1 − ε keeps cos θ_b a normal number (no density 0 at the horizon).
        if !(r2 < T::one() - T::EPSILON) {
            return None;
        }
        let c = (T::one() - r2).sqrt();
        Some(self.t1 * u.x + self.t2 * u.y + self.n * c)
    }
}

impl<T: Real> SideMap<T> {
    /// The direction of the angle-chart point `x = θ ê` (θ the polar angle from this side's
    /// normal, ê the unit tangential direction), `None` at or beyond the horizon.
    #[inline]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN must fail the test too"
    )]
    fn direction_of_angle(&self, x: &Vector2<T>) -> Option<Vector3<T>> {
        let theta = x.norm();
        if !(theta < T::frac_pi_2()) {
            return None;
        }
        let (s, c) = theta.sin_cos();
        // The same margin from the horizon as `direction` (cos θ > √ε): a direction closer to
        // the plane of the surface is not on a definite side in `T`.
        if !(c > T::EPSILON.sqrt()) {
            return None;
        }
        let u = if theta > T::zero() {
            x * (s / theta)
        } else {
            Vector2::zeros()
        };
        Some(self.t1 * u.x + self.t2 * u.y + self.n * c)
    }

    /// The angle-chart point of a unit direction `d` in this side's half-space and the density
    /// factor `θ/sin θ` (`d²x = (θ/sin θ) dω`).
    #[inline]
    fn angle_of(&self, d: &Vector3<T>) -> (Vector2<T>, T) {
        let u = Vector2::new(d.dot(&self.t1), d.dot(&self.t2));
        let s = u.norm();
        let theta = s.atan2(d.dot(&self.n));
        if s > T::zero() {
            (u * (theta / s), theta / s)
        } else {
            (Vector2::zeros(), T::one())
        }
    }
}

/// The angle-chart image of the specular lobes `lobes` (weights, `h_t` lobes centred at 0) on
/// side `map`, when their centre lies within `HORIZON_REACH` standard deviations of the
/// horizon (module docs, "Grazing specular lobes"); `None` otherwise.
fn horizon_lobe<T: Real>(map: &SideMap<T>, lobes: &[(T, GaussLobe<T>)]) -> Option<GaussLobe<T>> {
    let mut cov = Matrix2::zeros();
    for (w, l) in lobes {
        let [a, b, c] = l.l;
        cov += Matrix2::new(a * a, a * b, a * b, b * b + c * c) * *w;
    }
    let cov = cov / (map.k * map.k);
    let centre = -map.known_h / map.k;
    let r = centre.norm();
    if !(r > T::zero() && r.is_finite()) {
        return None;
    }
    let e = centre / r;
    let ep = Vector2::new(-e.y, e.x);
    let sr = e.dot(&(cov * e)).max(T::zero()).sqrt();
    let st = ep.dot(&(cov * ep)).max(T::zero()).sqrt();
    if T::one() - r >= T::lit(HORIZON_REACH) * sr {
        return None;
    }
    let asin = |x: T| x.max(T::zero()).min(T::one()).asin();
    let theta = asin(r);
    let widen = T::lit(HORIZON_WIDEN);
    let sig_r = (asin(r + sr) - asin(r - sr)) * T::lit(0.5) * widen;
    let sig_t = st * theta / r.min(T::one()) * widen;
    let rot = Matrix2::new(e.x, ep.x, e.y, ep.y);
    let c =
        rot * Matrix2::new(sig_r * sig_r, T::zero(), T::zero(), sig_t * sig_t) * rot.transpose();
    GaussLobe::new(e * theta, &c)
}

/// The specular lobe of a side.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Specular<T: Real> {
    /// A Dirac delta at `h_t = 0` (plane wave).
    Delta,
    /// One or two channel Gaussians `(weight, 𝒩(0, Ξ_α))`.
    Gauss([(T, GaussLobe<T>); 2], usize),
}

/// The scattered lobes, built once.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Scatter<'a, T: Real> {
    None,
    /// One Gaussian lobe (Gaussian PSD; a smooth PSD's order or the incoherent limit, blurred).
    One(GaussLobe<T>),
    /// Gaussian mixture components blurred by `Ξ` (`None`: plane wave), weights `σ_j²/Σσ²`.
    Mixture {
        comps: &'a [GaussianPsd<T, 2>],
        blur: Option<Matrix2<T>>,
        total: T,
    },
    /// Grating orders: blurred by the Gaussian `shape` (centred at 0), or Dirac deltas.
    Orders {
        orders: &'a [(Vector2<T>, T)],
        shape: Option<GaussLobe<T>>,
        reach: T,
        totals: [T; 2],
    },
    /// The K-correlation power lobe, mixed ½/½ with the blurred core where there is a blur.
    Power {
        power: PowerLobe<T>,
        core: Option<GaussLobe<T>>,
    },
    /// A Dirac order at `h_t = 0` (a smooth PSD of positive weight, plane wave).
    OriginDelta(T),
    /// Beyond first order, a Gaussian PSD: the series' orders per side (reflected,
    /// transmitted), `orders.rs`.
    Series([OrderLobes<T>; 2]),
}

/// What the sampler is built from (assembled by [`super::Bsdf`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Setup<'a, T: Real> {
    /// The known direction (unit, pointing away from the surface).
    pub known: Vector3<T>,
    /// The caller's surface frame oriented toward the known direction.
    pub facing: Frame<T>,
    /// `k_a`, the wavenumber of the known direction's medium.
    pub k_known: T,
    /// The wavenumber across the interface (`None`: opaque).
    pub k_across: Option<T>,
    /// Forward (the known direction is the source's): the kernel's frame is `facing` for both
    /// sides; backward: the transmitted side's is `facing.reversed()`.
    pub forward: bool,
    /// The Fresnel reflectance at the known angle, from its side.
    pub reflectance: T,
    /// The PSD's variance `σ²`.
    pub variance: T,
    /// The PSD's form (its shape names the scattered lobes).
    pub lobes: Shape<'a, T, 2>,
    /// The coherence level.
    pub level: CoherenceLevel,
    /// Whether the kernel has a specular lobe (no section of a partially coherent packet: none).
    pub specular: bool,
    /// The specular channels `(weight, Ξ_α)` (weights summing to 1) and their count (0 for a
    /// plane wave).
    pub channels: [(T, Matrix2<T>); 2],
    pub channel_count: usize,
    /// `Ξ`, the blur of the scattered lobes (`None` for a plane wave), in the caller's surface
    /// frame (the PSD's).
    pub blur: Option<Matrix2<T>>,
    /// Per side (reflected, transmitted), whether its tangent frame is the caller's with t̂₂
    /// negated (the PSD then sees `h_t` mirrored).
    pub mirror: [bool; 2],
    /// The kernel's roughness level is beyond first order: the scattered lobes are the
    /// series' (`orders.rs`), with the projected-disk lobe.
    pub rough: bool,
}

/// The sampler of one shading point in one tracing direction (see the module docs). Built
/// by [`super::Bsdf::exit_sampler`] and [`super::Bsdf::incident_sampler`]; it borrows the
/// material's PSD and allocates nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LobeSampler<'a, T: Real> {
    sides: [SideMap<T>; 2],
    /// `[reflected specular, reflected scattered, transmitted specular, transmitted scattered]`.
    probs: [T; 4],
    specular: Option<Specular<T>>,
    /// Tracing backward: grazing specular lobes are also drawn in the angle chart (computed
    /// where needed, [`LobeSampler::chart`], to keep the sampler small).
    backward: bool,
    scatter: Scatter<'a, T>,
    transmits: bool,
    /// The share of the projected-disk lobe in the scattered parts (`orders.rs`: beyond first
    /// order for PSDs without a series lobe; 0 otherwise).
    disk: T,
}

/// A uniform clamped into `[0, 1⁻]` (NaN → 0).
#[inline]
fn clamp01<T: Real>(v: T) -> T {
    v.max(T::zero()).min(T::one() - T::lit(0.5) * T::EPSILON)
}

impl<'a, T: Real> LobeSampler<'a, T> {
    /// The sampler for `setup` (module docs), or why it cannot be built.
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN width must fail the test too"
    )]
    pub(crate) fn new(setup: &Setup<'a, T>) -> Result<Self, &'static str> {
        let s = Self::build(setup)
            .ok_or("sampling lobe covariance over- or underflows the scalar type")?;
        // Every Gaussian lobe must resolve on the float grid of the projected disk (spacing ≤ ε
        // there): a narrower one puts all its draws on a few representable directions, where
        // its density can underflow to 0.
        let k = s.sides[0].k.max(s.sides[1].k);
        if !(s.narrowest() / k >= T::lit(MIN_WIDTH_ULPS) * T::EPSILON) {
            return Err(
                "sampling lobe narrower than 8ε in the projected disk (not resolvable \
                        in the scalar type): a smaller coherence width, or f64",
            );
        }
        Ok(s)
    }

    /// The narrowest standard deviation (in `h_t`) of the lobes, `+∞` without Gaussian lobes.
    fn narrowest(&self) -> T {
        let mut w = T::MAX;
        if let Some(Specular::Gauss(lobes, count)) = self.specular {
            for (_, l) in &lobes[..count] {
                w = w.min(l.narrowest());
            }
        }
        match self.scatter {
            Scatter::One(l)
            | Scatter::Orders { shape: Some(l), .. }
            | Scatter::Power { core: Some(l), .. } => w = w.min(l.narrowest()),
            Scatter::Series(sides) => {
                w = w.min(sides[0].narrowest());
                if self.transmits {
                    w = w.min(sides[1].narrowest());
                }
            }
            Scatter::Mixture { comps, blur, .. } => {
                for c in comps {
                    w = w.min(mixture_lobe(c, blur.as_ref()).map_or(T::zero(), |l| l.narrowest()));
                }
            }
            _ => {}
        }
        w
    }

    /// The lobes, probabilities and maps of `setup`; `None` when a covariance over- or
    /// underflows.
    fn build(setup: &Setup<'a, T>) -> Option<Self> {
        let f = &setup.facing;
        let (t1, t2, n) = (f.x(), f.y(), f.k());
        let ka = setup.k_known;
        let d = setup.known;
        let ua = Vector2::new(d.dot(&t1), d.dot(&t2));
        let cos_a = d.dot(&n);
        let reflect = SideMap {
            t1,
            t2,
            n,
            known_h: ua * ka,
            k: ka,
            mirror: setup.mirror[0],
        };
        let kb = setup.k_across.unwrap_or(ka);
        // Backward transmission: the kernel's frame faces the (unknown) source below.
        let t2_b = if setup.forward { t2 } else { -t2 };
        let transmit = SideMap {
            t1,
            t2: t2_b,
            n: -n,
            known_h: Vector2::new(ua.x, if setup.forward { ua.y } else { -ua.y }) * ka,
            k: kb,
            mirror: setup.mirror[1],
        };
        let transmits = setup.k_across.is_some();
        let sigma2 = setup.variance;

        let specular = if !setup.specular {
            None
        } else if setup.level == CoherenceLevel::PlaneWave {
            Some(Specular::Delta)
        } else {
            let mut lobes = [(
                T::zero(),
                GaussLobe::new(Vector2::zeros(), &Matrix2::identity())?,
            ); 2];
            for (i, (w, xi)) in setup.channels.iter().take(setup.channel_count).enumerate() {
                lobes[i] = (*w, GaussLobe::new(Vector2::zeros(), xi)?);
            }
            Some(Specular::Gauss(lobes, setup.channel_count.max(1)))
        };

        let cos_b2 = T::one() - transmit.known_h.norm_squared() / (kb * kb);
        let cos_b = cos_b2.max(T::zero()).sqrt();
        // The phase factors at the specular directions, `v = k_a cos θ_a ± k_b cos θ_b`.
        let v_r = T::lit(2.0) * ka * cos_a;
        let v_t = ka * cos_a - kb * cos_b;
        let scatter = match (setup.rough, setup.lobes, setup.level) {
            (true, Shape::Gaussian(g), CoherenceLevel::PlaneWave | CoherenceLevel::Partial) => {
                let cp = *g.spectral_shape().covariance();
                let blur = setup.blur.as_ref();
                Scatter::Series([
                    OrderLobes::new(v_r * v_r * sigma2, &cp, blur, ka)?,
                    OrderLobes::new(v_t * v_t * sigma2, &cp, blur, kb)?,
                ])
            }
            _ => scatter_lobes(setup, &[reflect, transmit])?,
        };
        let has_scatter = sigma2 > T::zero()
            && match scatter {
                Scatter::None => false,
                Scatter::Orders { totals, .. } => totals[0] > T::zero() || totals[1] > T::zero(),
                _ => true,
            };

        // Energies (module docs).
        let r = setup.reflectance.max(T::zero()).min(T::one());
        let alpha_r = (-(v_r * v_r) * sigma2).exp();
        let snell = transmits && cos_b2 > T::zero();
        let alpha_t = (-(v_t * v_t) * sigma2).exp();
        let t = if transmits { T::one() - r } else { T::zero() };
        // Scattered transmission where no specular transmission exists (total internal
        // reflection: T = 0 at the known angle) is the roughness's coupling into the other
        // medium: estimated with the normal-incidence transmittance and the known side's phase.
        let t_scat = if transmits && !snell {
            let n_rel = kb / ka;
            let r0 = ((n_rel - T::one()) / (n_rel + T::one())).powi(2);
            (T::one() - r0) * (T::one() - (-(ka * cos_a).powi(2) * sigma2).exp())
        } else {
            t * (T::one() - alpha_t)
        };
        let scat_t = match scatter {
            Scatter::Orders { totals, .. } => totals[1] > T::zero(),
            _ => true,
        };
        let scat_r = match scatter {
            Scatter::Orders { totals, .. } => totals[0] > T::zero(),
            _ => true,
        };
        let present = [
            specular.is_some(),
            has_scatter && scat_r,
            snell && specular.is_some(),
            transmits && has_scatter && scat_t,
        ];
        // Grating orders: the Kirchhoff estimate per propagating order, with its own phase
        // factor `v_m` (the specular one misjudges orders far from the mirror direction).
        let (r_scat, t_scat) = match scatter {
            Scatter::Orders { orders, .. } if sigma2 > T::zero() => {
                let order_energy = |map: &SideMap<T>, v_of: &dyn Fn(T) -> T| {
                    orders.iter().fold(T::zero(), |acc, (z, e)| {
                        let u = (map.flip(z) - map.known_h) / map.k;
                        let c2 = T::one() - u.norm_squared();
                        if c2 > T::zero() {
                            let v = v_of(map.k * c2.sqrt());
                            acc - *e / sigma2 * (-(v * v) * sigma2).exp_m1()
                        } else {
                            acc
                        }
                    })
                };
                let kc = ka * cos_a;
                (
                    r * order_energy(&reflect, &|kcos| kc + kcos),
                    if transmits {
                        t * order_energy(&transmit, &|kcos| kc - kcos)
                    } else {
                        T::zero()
                    },
                )
            }
            _ => (r * (T::one() - alpha_r), t_scat),
        };
        let energy = [
            r * alpha_r,
            r_scat,
            if snell { t * alpha_t } else { T::zero() },
            t_scat,
        ];
        let count = T::lit(present.iter().filter(|&&p| p).count() as f64);
        let total: T = (0..4)
            .filter(|&i| present[i])
            .fold(T::zero(), |a, i| a + energy[i]);
        let mut probs = [T::zero(); 4];
        if total > T::zero() && total.is_finite() {
            // Proportional to the estimates, each floored at ε of the total.
            let floor = T::lit(PART_FLOOR) * total;
            let mut sum = T::zero();
            for i in 0..4 {
                if present[i] {
                    probs[i] = energy[i].max(floor);
                    sum += probs[i];
                }
            }
            probs = probs.map(|p| p / sum);
        } else {
            for i in 0..4 {
                if present[i] {
                    probs[i] = T::one() / count;
                }
            }
        }
        Some(Self {
            sides: [reflect, transmit],
            probs,
            specular,
            backward: !setup.forward,
            scatter,
            transmits,
            disk: if setup.rough && has_scatter && !matches!(scatter, Scatter::Series(_)) {
                T::lit(DISK_SHARE)
            } else {
                T::zero()
            },
        })
    }

    /// Backward, the angle-chart lobe of side `side`'s specular part where it reaches near the
    /// horizon (module docs, "Grazing specular lobes").
    #[inline]
    fn chart(&self, side: usize) -> Option<GaussLobe<T>> {
        if !self.backward || self.probs[2 * side] <= T::zero() {
            return None;
        }
        match self.specular {
            Some(Specular::Gauss(lobes, count)) => horizon_lobe(&self.sides[side], &lobes[..count]),
            _ => None,
        }
    }

    /// The part probabilities `[reflected specular, reflected scattered, transmitted specular,
    /// transmitted scattered]` (module docs).
    #[must_use]
    pub fn part_probabilities(&self) -> [T; 4] {
        self.probs
    }

    /// The same lobes with other part probabilities (each clamped to ≥ 0 and set to 0 for a part
    /// this sampler does not have, then normalised; all zero leaves the probabilities as they
    /// were): for tuning a mixture, or drawing from one part alone. `pdf` follows the new
    /// probabilities, so sampling stays exact.
    #[must_use]
    pub fn with_part_probabilities(&self, probs: [T; 4]) -> Self {
        let mut p = [T::zero(); 4];
        let mut total = T::zero();
        for i in 0..4 {
            if self.probs[i] > T::zero() && probs[i] > T::zero() && probs[i].is_finite() {
                p[i] = probs[i];
                total += probs[i];
            }
        }
        let mut out = *self;
        if total > T::zero() {
            out.probs = p.map(|x| x / total);
        }
        out
    }

    /// Draws a direction from three uniforms in `[0, 1)`: `u_lobe` chooses the part (and,
    /// rescaled, the component), `u` the point in the lobe. `None` when the draw is evanescent
    /// (its probability is the lobes' mass outside the propagating directions; the density of
    /// what is returned is [`LobeSampler::pdf`], which integrates to the rest).
    ///
    /// Every input is accepted without panic (uniforms are clamped into `[0, 1)`).
    #[must_use]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN must fail the test too"
    )]
    pub fn sample(&self, u_lobe: T, u: [T; 2]) -> Option<DirectionSample<T>> {
        let mut v = clamp01(u_lobe);
        let u = [clamp01(u[0]), clamp01(u[1])];
        let mut acc = T::zero();
        let mut part = 3;
        for (i, &p) in self.probs.iter().enumerate() {
            if p > T::zero() && (v < acc + p || i == 3) {
                part = i;
                v = clamp01((v - acc) / p);
                break;
            }
            acc += p;
        }
        if !(self.probs[part] > T::zero()) {
            return None;
        }
        let side_index = part / 2;
        let side = if side_index == 0 {
            Side::Reflection
        } else {
            Side::Transmission
        };
        let map = &self.sides[side_index];
        // `delta`: the Dirac lobe's weight in the PSD and its share among its part's lobes.
        let share = T::lit(HORIZON_SHARE);
        let chart = self.chart(side_index);
        let (direction, delta) = if part % 2 == 0 {
            match (self.specular?, chart) {
                (Specular::Delta, _) => (
                    map.direction(&Vector2::zeros())?,
                    Some((T::one(), T::one())),
                ),
                (Specular::Gauss(..), Some(chart)) if v < share => {
                    (map.direction_of_angle(&chart.sample(u))?, None)
                }
                (Specular::Gauss(lobes, count), chart) => {
                    if chart.is_some() {
                        v = clamp01((v - share) / (T::one() - share));
                    }
                    let lobe = if count == 2 && v >= lobes[0].0 {
                        &lobes[1].1
                    } else {
                        &lobes[0].1
                    };
                    (map.direction(&lobe.sample(u))?, None)
                }
            }
        } else if v < self.disk {
            // The projected-disk lobe, in this side's own frame.
            (map.direction(&(map.known_h + disk_point(u) * map.k))?, None)
        } else {
            let v = clamp01((v - self.disk) / (T::one() - self.disk));
            // The scattered lobes live in the caller's frame (the PSD's).
            let (h, delta) = self.sample_scatter(side_index, v, u)?;
            (map.direction(&map.flip(&h))?, delta)
        };
        let lobe = SampledLobe {
            side,
            part: if part % 2 == 0 {
                Part::Specular
            } else {
                Part::Scattered
            },
            delta: delta.is_some(),
        };
        let (pdf, delta_weight) = match delta {
            // A scattered-part delta is reached past the projected disk's share.
            Some((weight, share)) if part % 2 == 1 => {
                (self.probs[part] * (T::one() - self.disk) * share, weight)
            }
            Some((weight, share)) => (self.probs[part] * share, weight),
            None => (
                self.density(&direction, Some((side_index, chart))),
                T::zero(),
            ),
        };
        // Every direction returned has a finite, positive density (a draw the density does not
        // see is rejected, as an evanescent one).
        if !(pdf > T::zero() && pdf.is_finite()) {
            return None;
        }
        Some(DirectionSample {
            direction,
            pdf,
            lobe,
            delta_weight,
        })
    }

    /// A point of the scattered lobes of side `side`, with `(weight, share)` for a Dirac order.
    #[allow(clippy::type_complexity)]
    fn sample_scatter(&self, side: usize, v: T, u: [T; 2]) -> Option<(Vector2<T>, Option<(T, T)>)> {
        match self.scatter {
            Scatter::None => None,
            Scatter::One(lobe) => Some((lobe.sample(u), None)),
            Scatter::Mixture { comps, blur, total } => {
                let target = v * total;
                let mut acc = T::zero();
                let last = comps.len() - 1;
                for (j, c) in comps.iter().enumerate() {
                    acc += c.variance_of();
                    if target < acc || j == last {
                        let lobe = mixture_lobe(c, blur.as_ref())?;
                        return Some((lobe.sample(u), None));
                    }
                }
                None
            }
            Scatter::Orders {
                orders,
                shape,
                reach,
                totals,
            } => {
                let map = &self.sides[side];
                let target = v * totals[side];
                let mut acc = T::zero();
                let blurred = shape.is_some();
                let mut chosen = None;
                for (z, e) in orders {
                    let w = order_weight(map, z, *e, reach, blurred);
                    if w > T::zero() {
                        acc += w;
                        chosen = Some((*z, *e, w));
                        if target < acc {
                            break;
                        }
                    }
                }
                let (z, e, w) = chosen?;
                Some(match shape {
                    Some(lobe) => (z + lobe.sample(u), None),
                    None => (z, Some((e, w / totals[side]))),
                })
            }
            Scatter::Power { power, core } => match core {
                Some(core) if v >= T::lit(0.5) => Some((core.sample(u), None)),
                _ => Some((power.sample(u), None)),
            },
            Scatter::OriginDelta(w) => Some((Vector2::zeros(), Some((w, T::one())))),
            Scatter::Series(sides) => Some((sides[side].sample(v, u), None)),
        }
    }

    /// The density per unit solid angle of drawing `direction` (normalised here); 0 where no
    /// non-delta lobe reaches (the half-space of an opaque surface's other side included).
    ///
    /// # Formula
    /// ```text
    /// p_ω(d) = k_b² |cos θ_b| Σ_parts P_part p_part(h_t(d))          (delta lobes excluded)
    /// ```
    #[must_use]
    pub fn pdf(&self, direction: &Vector3<T>) -> T {
        self.density(direction, None)
    }

    /// [`LobeSampler::pdf`], with the angle-chart lobe of one side already computed
    /// (`known`: the side and its [`LobeSampler::chart`], as [`LobeSampler::sample`] has it).
    #[inline]
    fn density(&self, direction: &Vector3<T>, known: Option<(usize, Option<GaussLobe<T>>)>) -> T {
        let n = direction.norm();
        if !(n > T::zero() && n.is_finite()) {
            return T::zero();
        }
        let d = direction / n;
        for side in 0..2 {
            if side == 1 && !self.transmits {
                break;
            }
            let map = &self.sides[side];
            if let Some((h, cos)) = map.h_of(&d) {
                let chart = match known {
                    Some((known_side, chart)) if known_side == side => chart,
                    _ => self.chart(side),
                };
                let (h_share, chart) = match chart {
                    Some(chart) => {
                        let (x, jac) = map.angle_of(&d);
                        let share = T::lit(HORIZON_SHARE);
                        (
                            T::one() - share,
                            self.probs[2 * side] * share * chart.density(&x) * jac,
                        )
                    }
                    None => (T::one(), T::zero()),
                };
                let spec = self.probs[2 * side]
                    * h_share
                    * match self.specular {
                        Some(Specular::Gauss(lobes, count)) => lobes[..count]
                            .iter()
                            .fold(T::zero(), |a, (w, l)| a + *w * l.density(&h)),
                        _ => T::zero(),
                    };
                let scat = if self.probs[2 * side + 1] > T::zero() {
                    // The disk lobe's density in h_t is 1/(π k_b²) on the whole side.
                    let disk = self.disk / (T::pi() * map.k * map.k);
                    self.probs[2 * side + 1]
                        * ((T::one() - self.disk) * self.scatter_density(side, &map.flip(&h))
                            + disk)
                } else {
                    T::zero()
                };
                return (spec + scat) * (map.k * map.k) * cos + chart;
            }
        }
        T::zero()
    }

    /// The scattered lobes' density at `h` on side `side` (deltas excluded).
    fn scatter_density(&self, side: usize, h: &Vector2<T>) -> T {
        match self.scatter {
            Scatter::None | Scatter::OriginDelta(_) => T::zero(),
            Scatter::One(lobe) => lobe.density(h),
            Scatter::Mixture { comps, blur, total } => {
                comps.iter().fold(T::zero(), |a, c| {
                    a + mixture_lobe(c, blur.as_ref())
                        .map_or(T::zero(), |l| c.variance_of() * l.density(h))
                }) / total
            }
            Scatter::Orders {
                orders,
                shape,
                reach,
                totals,
            } => match shape {
                None => T::zero(),
                Some(lobe) => {
                    let map = &self.sides[side];
                    orders.iter().fold(T::zero(), |a, (z, e)| {
                        let w = order_weight(map, z, *e, reach, true);
                        if w > T::zero() {
                            a + w * lobe.density(&(h - z))
                        } else {
                            a
                        }
                    }) / totals[side]
                }
            },
            Scatter::Power { power, core } => match core {
                Some(core) => T::lit(0.5) * (power.log_density(h).exp() + core.density(h)),
                None => power.log_density(h).exp(),
            },
            Scatter::Series(sides) => sides[side].density(h),
        }
    }
}

/// The weight of order `(z, e)` on a side: `e` if its centre (widened by `reach`, the blur's
/// width) maps to a propagating direction, otherwise `HIDDEN_ORDER_WEIGHT · e` for a blurred
/// order (its tail may still reach) and 0 for a Dirac order (it cannot).
#[inline]
fn order_weight<T: Real>(map: &SideMap<T>, z: &Vector2<T>, e: T, reach: T, blurred: bool) -> T {
    let r = (map.flip(z) - map.known_h).norm();
    if r < map.k + reach {
        e
    } else if blurred {
        e * T::lit(HIDDEN_ORDER_WEIGHT)
    } else {
        T::zero()
    }
}

/// The lobe of a mixture component, `𝒩(0, C_j + Ξ)`.
#[inline]
fn mixture_lobe<T: Real>(c: &GaussianPsd<T, 2>, blur: Option<&Matrix2<T>>) -> Option<GaussLobe<T>> {
    let cov = *c.spectral_shape().covariance();
    GaussLobe::new(Vector2::zeros(), &blur.map_or(cov, |b| cov + b))
}

/// Variance of a mixture component.
trait VarianceOf<T> {
    fn variance_of(&self) -> T;
}
impl<T: Real> VarianceOf<T> for GaussianPsd<T, 2> {
    #[inline]
    fn variance_of(&self) -> T {
        crate::psd::Psd::<T, 2>::variance(self)
    }
}

/// The scattered lobes of `setup` (module docs of `lobes.rs`).
fn scatter_lobes<'a, T: Real>(
    setup: &Setup<'a, T>,
    sides: &[SideMap<T>; 2],
) -> Option<Scatter<'a, T>> {
    let blur = setup.blur;
    if setup.level == CoherenceLevel::Incoherent {
        // K ∝ g^Ξ(h_t) ∫p: the lobe is the coherence's alone.
        return Some(match (setup.lobes, blur) {
            (Shape::Zero, _) => Scatter::None,
            (_, Some(b)) => Scatter::One(GaussLobe::new(Vector2::zeros(), &b)?),
            (_, None) => Scatter::None,
        });
    }
    Some(match setup.lobes {
        Shape::Zero => Scatter::None,
        Shape::Origin => match blur {
            Some(b) => Scatter::One(GaussLobe::new(Vector2::zeros(), &b)?),
            None => Scatter::OriginDelta(setup.variance),
        },
        Shape::Gaussian(g) => {
            let cp = *g.spectral_shape().covariance();
            Scatter::One(GaussLobe::new(
                Vector2::zeros(),
                &blur.map_or(cp, |b| cp + b),
            )?)
        }
        Shape::Mixture(comps) => {
            if comps.is_empty() {
                Scatter::None
            } else {
                let total = comps.iter().fold(T::zero(), |a, c| a + c.variance_of());
                Scatter::Mixture { comps, blur, total }
            }
        }
        Shape::Orders(orders) => {
            let (shape, reach) = match blur {
                Some(b) => (
                    Some(GaussLobe::new(Vector2::zeros(), &b)?),
                    T::lit(3.0) * (b[(0, 0)] + b[(1, 1)]).sqrt(),
                ),
                None => (None, T::zero()),
            };
            let blurred = shape.is_some();
            let mut totals = [T::zero(); 2];
            for (s, total) in totals.iter_mut().enumerate() {
                *total = orders.iter().fold(T::zero(), |a, (z, e)| {
                    a + order_weight(&sides[s], z, *e, reach, blurred)
                });
            }
            Scatter::Orders {
                orders,
                shape,
                reach,
                totals,
            }
        }
        Shape::KCorrelation { t, gamma } => {
            let core = match blur {
                Some(b) => {
                    let c = T::one() / ((gamma + T::one()) * t);
                    Some(GaussLobe::new(
                        Vector2::zeros(),
                        &(Matrix2::identity() * c + b),
                    )?)
                }
                None => None,
            };
            Scatter::Power {
                power: PowerLobe::new(t, gamma),
                core,
            }
        }
    })
}
