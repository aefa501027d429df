//! A structure-of-arrays batch path for the plane-wave polarized kernel: one packet, many exit
//! directions, with explicit SIMD chosen at run time.
//!
//! [`plane_wave_rayleigh_rice`] evaluates what
//! `Kernel::<Full, PlaneWave, ClosedForm>::evaluate(..).scattered` returns — the classical
//! Rayleigh–Rice Mueller BRDF applied to the packet's Stokes vector, with a Gaussian PSD — for
//! every direction of a [`DirectionsSoa`], writing the four Stokes parameters into a
//! [`StokesSoa`]. The per-packet work (incident s/p frame, the rotation `T`, `q_i`, the PSD's
//! Cholesky factor) is done once; the per-exit work runs 4 (`f64`) or 8 (`f32`) directions per
//! instruction under AVX2 + FMA through [`pulp`] (run-time detection, no `unsafe`, no
//! `RUSTFLAGS`), with a vector exponential and a branch-free principal complex square root.
//! Lay a batch out with [`crate::mueller::batch::padded_stride`].

use nalgebra::{Vector2, Vector3, Vector4};
use num_complex::Complex;
use pulp::{Simd, WithSimd};

use super::geometry::{self, Geometry};
use super::{ConstantMueller, Full, Kernel, PlaneWave, RayleighRice, RoughSurface};
use crate::error::Error;
use crate::frame::{Frame, frame_change_mueller};
use crate::mueller::Mueller;
use crate::mueller::batch::{strided, strided_mut};
use crate::numerics::{HYPOT_PLAIN, principal_sqrt};
use crate::packet::WavePacket;
use crate::psd::{GaussianPsd, Psd};
use crate::real::Real;

mod lanes;
use lanes::*;

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
        let [x, y, z] = strided(buf, n, stride)?;
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
            s: strided_mut(buf, n, stride)?,
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
/// This is `Kernel::<Full, PlaneWave, ClosedForm>::evaluate(&material, packet, &g).scattered`
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
/// the same order as the scalar kernel (no fused multiply–adds there), so they are the scalar
/// values bit for bit — which keeps the azimuth, whose condition number is `1/sin θ_o`, identical
/// next to the normal. What differs is the exponential (a polynomial within 1 ulp measured, 2
/// documented, instead of the C library's), its argument (the exponents `E` of the PSD, the
/// Debye–Waller factor and the constant prefactor summed before one exponential; `exp` turns
/// their rounding into a relative error `≈ ε |E|`), and the Mueller–Stokes product (fused
/// multiply–adds, another order). Against the scalar kernel, per Stokes parameter: within
/// `4 ε (4 + |E|) S0` (measured ≤ `0.7 ε (1 + |E|) S0`: ≤ 1e-13 relative in f64 over the whole
/// range, ≤ 5e-6 in f32 near the lobe), plus the smallest normal number times the output scale
/// where the scalar path rounds through subnormal numbers; exactly 0 where the PSD underflows
/// (`tests/interaction_batch.rs`).
///
/// Speed (AMD EPYC, AVX2 + FMA, 1024 exits within 15° of specular, `benches/kernel.rs` group
/// `kernel_batch`, one run): 23 ns per exit in `f64` and 11 ns in `f32`; 29 and 13 ns at normal
/// incidence, where every exit lies in the re-orthogonalised band of `Frame::sp`. The same exits
/// through `Geometry::for_packet` + [`Kernel::evaluate`] took 255 and 219 ns each.
///
/// Instruction sets: for `f32` and `f64` the CPU is detected at run time ([`pulp::Arch`]); with
/// AVX2 + FMA the loop handles 4 (`f64`) or 8 (`f32`) directions per instruction, elsewhere a
/// scalar instantiation of the same loop runs. Other [`Real`] types, and indices so extreme
/// that the scalar `hypot` would leave its fast branch (`0 < |Im ε| < 10⁻¹⁸` or
/// `|ε| > 10¹⁸`), go through the scalar kernel per direction. No heap allocation.
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
/// use gmueller::interaction::{FresnelReflection, Full, Geometry, Kernel, PlaneWave,
///     RayleighRice, RoughSurface};
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
    if prep.vectorizable
        && let Some(result) = T::plane_wave_rayleigh_rice_kernel(&prep, exits, out)
    {
        return result;
    }
    portable(psd, scatter, packet, surface, exits, out)
}

/// The scalar kernel per direction: validate every exit, then evaluate each.
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

/// The per-packet constants of [`plane_wave_rayleigh_rice`] (not public API: it appears in the
/// signature of a hidden method of [`Real`]).
#[doc(hidden)]
#[derive(Debug, Clone, Copy)]
pub struct PlaneWavePrep<T: Real> {
    /// Whether the SIMD loop reproduces the scalar kernel for these parameters.
    vectorizable: bool,
    surface: Frame<T>,
    /// `−k̂` of the packet as given (for the exact error of an ambiguous direction).
    to_source_raw: Vector3<T>,
    /// ŝ (unit).
    s: Vector3<T>,
    n: Vector3<T>,
    t1: Vector3<T>,
    t2: Vector3<T>,
    /// `n̂ × ŝ_in` and `n̂ × (n̂ × ŝ_in)`: the azimuth axes of [`Geometry::exit_azimuth`].
    u_az: Vector3<T>,
    v_az: Vector3<T>,
    k: T,
    cos_i: T,
    si2: T,
    e: Complex<T>,
    em1: Complex<T>,
    neg_em1: Complex<T>,
    qi: Complex<T>,
    d1: Complex<T>,
    d3: Complex<T>,
    neg_em1_qi: Complex<T>,
    /// `Im ε = 0`: the modulus in `q_o` is `|Re(ε) − sin²θ_o|`.
    real_eps: bool,
    /// `(Im ε)²` and `(Im ε)/2`.
    eim2: T,
    eim_half: T,
    /// `ln(σ²|Λ|^{1/2}) + ln(2π (2k cos θ_i)² / λ²) + ln S0`.
    log_scale: T,
    variance: T,
    l00: T,
    l10: T,
    l11: T,
    /// `T S/S0` as `(S0 + S1)/2, (S0 − S1)/2, S2, S3` (the Full level's effective vector,
    /// normalised; `S0` is in `log_scale`).
    stokes: [T; 4],
    /// `√ε` of the type: below it `Frame::sp` falls back to a tangent of n̂.
    parallel_tol: T,
}

impl<T: Real> PlaneWavePrep<T> {
    fn new(
        psd: &GaussianPsd<T, 2>,
        epsilon: Complex<T>,
        packet: &WavePacket<T>,
        surface: &Frame<T>,
    ) -> Result<Self, Error> {
        let s = geometry::unit(-packet.direction(), "direction to the source")?;
        let n = surface.k();
        // The incident s/p frame, T and the effective Stokes vector exactly as the Full level.
        let (cos_i, incident_sp) = geometry::incidence(&s, surface)?;
        let t = frame_change_mueller(packet.frame(), &incident_sp).0;
        // S/S0, with ln S0 folded into the exponent of the weight: the weight alone (K, tiny in
        // a far tail) underflowed before it was scaled by a bright S0 (f32: 0 for S0 = 1e25
        // where the answer is 3e-22).
        let st = packet.stokes().0;
        let (st, ln_s0) = if st[0] > T::zero() {
            (st / st[0], st[0].ln())
        } else {
            (Vector4::zeros(), T::zero())
        };
        let half = T::lit(0.5);
        let (sx, sy) = ((st[0] + st[1]) * half, (st[0] - st[1]) * half);
        let ts = t * Vector4::new(sx + sy, sx - sy, st[2], st[3]);
        let u_az = n.cross(&incident_sp.x());
        let v_az = n.cross(&u_az);
        // RayleighRice::factors' per-packet part, with the same operations.
        let e = epsilon;
        let one = Complex::new(T::one(), T::zero());
        let si2 = (T::one() - cos_i * cos_i).max(T::zero());
        let qi = principal_sqrt(e - one * si2);
        let em1 = e - one;
        let d1 = qi + cos_i;
        let d3 = e * cos_i + qi;
        let neg_em1_qi = -em1 * qi;
        // `hypot(Re ε − sin²θ_o, Im ε)` takes its plain branch for every θ_o when Im ε ≠ 0 lies
        // in [1e-18, 1e18] and |Re ε| + 1 ≤ 1e18; with Im ε = 0 it is |Re ε − sin²θ_o| exactly.
        let (lo, hi) = (T::lit(HYPOT_PLAIN.0), T::lit(HYPOT_PLAIN.1));
        let real_eps = e.im == T::zero();
        let plain = e.im.abs() >= lo && e.im.abs() <= hi && e.re.abs() + T::one() <= hi;
        let k = packet.wavenumber();
        let lambda = T::two_pi() / k;
        let jones_scale = T::lit(2.0) * k * cos_i;
        let log_prefactor = (T::two_pi() * jones_scale * jones_scale / (lambda * lambda)).ln();
        let log_amplitude = psd.log_value(&Vector2::zeros());
        let l = psd.spectral_shape().cholesky_factor();
        let vectorizable = (real_eps || plain) && log_prefactor.is_finite();
        Ok(Self {
            vectorizable,
            surface: *surface,
            to_source_raw: -packet.direction(),
            s,
            n,
            t1: surface.x(),
            t2: surface.y(),
            u_az,
            v_az,
            k,
            cos_i,
            si2,
            e,
            em1,
            neg_em1: -em1,
            qi,
            d1,
            d3,
            neg_em1_qi,
            real_eps,
            eim2: e.im * e.im,
            eim_half: e.im * T::lit(0.5),
            log_scale: log_amplitude + log_prefactor + ln_s0,
            variance: psd.variance(),
            l00: l[(0, 0)],
            l10: l[(1, 0)],
            l11: l[(1, 1)],
            stokes: [
                (ts[0] + ts[1]) * T::lit(0.5),
                (ts[0] - ts[1]) * T::lit(0.5),
                ts[2],
                ts[3],
            ],
            parallel_tol: T::EPSILON.sqrt(),
        })
    }

    /// `Ok` when the scalar kernel accepts `exit` (the error of [`Geometry::new`] otherwise).
    fn check_exact(&self, exit: Vector3<T>) -> Result<(), Error> {
        Geometry::new(self.k, &self.surface, self.to_source_raw, exit).map(|_| ())
    }

    /// `(cos φ, sin φ)` of [`Geometry::exit_azimuth`] for the unit exit `r` (the scalar code,
    /// for directions within `√ε` of the normal).
    fn azimuth_scalar(&self, r: Vector3<T>) -> (T, T) {
        let s_out = Frame::sp_unit(r, self.n).x();
        (-s_out.dot(&self.v_az), s_out.dot(&self.u_az))
    }
}

/// `true` when `(x, y, z)` is certainly an accepted exit direction: finite, of moderate size,
/// and with `r·n̂ > 64 ε max|r_i|`, far enough from 0 that the `cos θ_o` of the normalised
/// direction is positive whatever the rounding (ambiguous directions go to
/// [`PlaneWavePrep::check_exact`]).
#[inline]
fn clearly_valid<F: ExpLanes>(p: &PlaneWavePrep<F>, x: F, y: F, z: F) -> bool {
    let m = x.abs().max(y.abs()).max(z.abs());
    let d = x * p.n.x + y * p.n.y + z * p.n.z;
    x.is_finite()
        && y.is_finite()
        && z.is_finite()
        && m >= F::lit(F::MIN_SIZE)
        && m <= F::lit(F::MAX_SIZE)
        && d > F::lit(64.0) * F::EPSILON * m
}

/// The SIMD kernel for `f32` and `f64`: validates every direction, then evaluates.
/// Lengths must already be equal (checked by [`plane_wave_rayleigh_rice`]).
pub(crate) fn kernel_simd<F: ExpLanes>(
    prep: &PlaneWavePrep<F>,
    exits: &DirectionsSoa<'_, F>,
    out: &mut StokesSoa<'_, F>,
) -> Result<(), Error> {
    pulp::Arch::new().dispatch(Batch { prep, exits, out })
}

/// The kernel on one vector of directions `(x, y, z)` (validated): the four Stokes parameters.
#[inline(always)]
fn stokes_lanes<S: Simd, F: ExpLanes>(
    s: S,
    p: &PlaneWavePrep<F>,
    x: F::V<S>,
    y: F::V<S>,
    z: F::V<S>,
) -> [F::V<S>; 4] {
    let c = |v: F| F::vsplat(s, v);
    let (add, sub, mul, div) = (F::vadd::<S>, F::vsub::<S>, F::vmul::<S>, F::vdiv::<S>);
    let zero = c(F::zero());
    let cx = Cx(s);
    let v3 = |v: Vector3<F>| [c(v.x), c(v.y), c(v.z)];
    let n = v3(p.n);
    // r̂ as `geometry::unit`: divided by the largest |component|, then by the norm.
    let m = F::vmax(s, F::vmax(s, F::vabs(s, x), F::vabs(s, y)), F::vabs(s, z));
    let u = [div(s, x, m), div(s, y, m), div(s, z, m)];
    let norm = F::vsqrt(s, dot3::<S, F>(s, u, u));
    let r = div3::<S, F>(s, u, norm);
    let cos_o = dot3::<S, F>(s, r, n);
    // The exit s vector as `Frame::sp_unit(r̂, n̂)`: c = r̂ × n̂ normalised when
    // |c|² ≥ 1/64, re-orthogonalised against r̂ when √ε ≤ |c| < 1/8, a tangent of n̂ below.
    let cr = [
        sub(s, mul(s, r[1], n[2]), mul(s, r[2], n[1])),
        sub(s, mul(s, r[2], n[0]), mul(s, r[0], n[2])),
        sub(s, mul(s, r[0], n[1]), mul(s, r[1], n[0])),
    ];
    let c2 = dot3::<S, F>(s, cr, cr);
    let rho = F::vsqrt(s, c2);
    let mut s_out = div3::<S, F>(s, cr, rho);
    let near = F::vlt(s, c2, c(F::lit(1.0 / 64.0)));
    if F::vany(s, near) {
        let o = orthogonalize::<S, F>(s, cr, r);
        for j in 0..3 {
            s_out[j] = F::vselect(s, near, o[j], s_out[j]);
        }
    }
    // Geometry::exit_azimuth.
    let mut cos_phi = sub(s, zero, dot3::<S, F>(s, s_out, v3(p.v_az)));
    let mut sin_phi = dot3::<S, F>(s, s_out, v3(p.u_az));
    let normal = F::vlt(s, rho, c(p.parallel_tol));
    if F::vany(s, normal) {
        // Within √ε of the normal: the scalar frame code, lane by lane.
        let lanes = F::lanes::<S>();
        let mut buf = [[F::zero(); 6]; 16];
        let mut lane = [F::zero(); 16];
        for (j, v) in [r[0], r[1], r[2], rho, cos_phi, sin_phi]
            .into_iter()
            .enumerate()
        {
            F::store_partial(s, &mut lane[..lanes], v);
            for (b, &x) in buf.iter_mut().zip(&lane[..lanes]) {
                b[j] = x;
            }
        }
        for b in &mut buf[..lanes] {
            if b[3] < p.parallel_tol {
                (b[4], b[5]) = p.azimuth_scalar(Vector3::new(b[0], b[1], b[2]));
            }
        }
        for (l, b) in lane.iter_mut().zip(&buf[..lanes]) {
            *l = b[4];
        }
        cos_phi = F::load_partial(s, &lane[..lanes]);
        for (l, b) in lane.iter_mut().zip(&buf[..lanes]) {
            *l = b[5];
        }
        sin_phi = F::load_partial(s, &lane[..lanes]);
    }
    // RayleighRice::factors, per-exit part.
    let one = c(F::one());
    let so2 = F::vmax(s, sub(s, one, mul(s, cos_o, cos_o)), zero);
    // q_o = principal_sqrt(ε − sin²θ_o) without branches (b = Im ε ≥ 0 always).
    let a = sub(s, c(p.e.re), so2);
    let abs_a = F::vabs(s, a);
    let modulus = if p.real_eps {
        abs_a
    } else {
        F::vsqrt(s, add(s, mul(s, a, a), c(p.eim2)))
    };
    let big = F::vsqrt(s, mul(s, add(s, modulus, abs_a), c(F::lit(0.5))));
    let small = F::vselect(s, F::vlt(s, zero, big), div(s, c(p.eim_half), big), zero);
    let nonneg = F::vle(s, zero, a);
    let qo = C {
        re: F::vselect(s, nonneg, big, small),
        im: F::vselect(s, nonneg, small, big),
    };
    let e = cx.splat::<F>(p.e);
    let (d1, d3) = (cx.splat::<F>(p.d1), cx.splat::<F>(p.d3));
    let d2 = C {
        re: add(s, qo.re, cos_o),
        im: qo.im,
    };
    let d4 = C {
        re: add(s, mul(s, c(p.e.re), cos_o), qo.re),
        im: add(s, mul(s, c(p.e.im), cos_o), qo.im),
    };
    let inv_ss = cx.recip::<F>(cx.mul::<F>(d1, d2));
    let inv_pp = cx.recip::<F>(cx.mul::<F>(d3, d4));
    let both = cx.mul::<F>(inv_ss, inv_pp);
    let em1 = cx.splat::<F>(p.em1);
    let ss = cx.scale::<F>(cx.mul::<F>(em1, inv_ss), cos_phi);
    let sq = F::vsqrt(s, mul(s, c(p.si2), so2));
    let qoqi = cx.scale::<F>(cx.mul::<F>(qo, cx.splat::<F>(p.qi)), cos_phi);
    let es = cx.scale::<F>(e, sq);
    let inner = C {
        re: sub(s, es.re, qoqi.re),
        im: sub(s, es.im, qoqi.im),
    };
    let pp = cx.mul::<F>(cx.mul::<F>(em1, inner), inv_pp);
    let ps = cx.scale::<F>(
        cx.mul::<F>(
            cx.splat::<F>(p.neg_em1_qi),
            cx.mul::<F>(cx.mul::<F>(d1, d4), both),
        ),
        sin_phi,
    );
    let sp = cx.scale::<F>(
        cx.mul::<F>(
            cx.mul::<F>(cx.splat::<F>(p.neg_em1), qo),
            cx.mul::<F>(cx.mul::<F>(d2, d3), both),
        ),
        sin_phi,
    );
    // The weight cos θ_o · exp(ln prefactor + ln p(h_t) + ln α).
    let sv = v3(p.s);
    let kk = c(p.k);
    let h = [
        mul(s, add(s, r[0], sv[0]), kk),
        mul(s, add(s, r[1], sv[1]), kk),
        mul(s, add(s, r[2], sv[2]), kk),
    ];
    let h0 = dot3::<S, F>(s, h, v3(p.t1));
    let h1 = dot3::<S, F>(s, h, v3(p.t2));
    let y0 = div(s, h0, c(p.l00));
    let y1 = div(s, sub(s, h1, mul(s, c(p.l10), y0)), c(p.l11));
    let maha = add(s, mul(s, y0, y0), mul(s, y1, y1));
    let log_p = add(s, c(p.log_scale), mul(s, c(F::lit(-0.5)), maha));
    let v = mul(s, kk, add(s, c(p.cos_i), cos_o));
    let log_alpha = F::vneg_mul_add(s, mul(s, v, v), c(p.variance), zero);
    let w = mul(s, cos_o, vexp::<S, F>(s, add(s, log_p, log_alpha)));
    // M′ (T S) from the Jones entries a = ss, b = ps, c = sp, d = pp (S1.7 written out, with
    // P = (S0 + S1)/2 and Q = (S0 − S1)/2 of T S); see `mueller::batch` for the entries.
    let fma = F::vmul_add::<S>;
    let (re, im) = (re_conj::<S, F>, im_conj::<S, F>);
    let [pw, qw, s2, s3] = [
        c(p.stokes[0]),
        c(p.stokes[1]),
        c(p.stokes[2]),
        c(p.stokes[3]),
    ];
    let (ja, jb, jc, jd) = (ss, ps, sp, pp);
    let aa = re(s, ja, ja);
    let bb = re(s, jb, jb);
    let cc = re(s, jc, jc);
    let dd = re(s, jd, jd);
    let (ab_r, ab_i) = (re(s, ja, jb), im(s, ja, jb));
    let (cd_r, cd_i) = (re(s, jc, jd), im(s, jc, jd));
    let (ac_r, nac_i) = (re(s, ja, jc), im(s, jc, ja));
    let (bd_r, bd_i) = (re(s, jb, jd), im(s, jb, jd));
    let (bc_r, nbc_i) = (re(s, jb, jc), im(s, jc, jb));
    let (ad_r, ad_i) = (re(s, ja, jd), im(s, ja, jd));
    let row_a = fma(
        s,
        aa,
        pw,
        fma(s, bb, qw, fma(s, ab_r, s2, mul(s, ab_i, s3))),
    );
    let row_b = fma(
        s,
        cc,
        pw,
        fma(s, dd, qw, fma(s, cd_r, s2, mul(s, cd_i, s3))),
    );
    let two = c(F::lit(2.0));
    let o2 = fma(
        s,
        two,
        fma(s, ac_r, pw, mul(s, bd_r, qw)),
        fma(s, add(s, bc_r, ad_r), s2, mul(s, add(s, ad_i, nbc_i), s3)),
    );
    let o3 = fma(
        s,
        two,
        F::vneg_mul_add(s, bd_i, qw, mul(s, nac_i, pw)),
        fma(s, sub(s, nbc_i, ad_i), s2, mul(s, sub(s, ad_r, bc_r), s3)),
    );
    [
        mul(s, add(s, row_a, row_b), w),
        mul(s, sub(s, row_a, row_b), w),
        mul(s, o2, w),
        mul(s, o3, w),
    ]
}

/// `true` for the lanes that are certainly valid directions (see [`clearly_valid`]).
#[inline(always)]
fn clearly_valid_lanes<S: Simd, F: ExpLanes>(
    s: S,
    p: &PlaneWavePrep<F>,
    x: F::V<S>,
    y: F::V<S>,
    z: F::V<S>,
) -> F::M<S> {
    let c = |v: F| F::vsplat(s, v);
    let zero = c(F::zero());
    let finite = |v: F::V<S>| F::veq(s, F::vsub(s, v, v), zero);
    let m = F::vmax(s, F::vmax(s, F::vabs(s, x), F::vabs(s, y)), F::vabs(s, z));
    let d = F::vadd(
        s,
        F::vadd(s, F::vmul(s, x, c(p.n.x)), F::vmul(s, y, c(p.n.y))),
        F::vmul(s, z, c(p.n.z)),
    );
    let and = F::vand::<S>;
    and(
        s,
        and(s, and(s, finite(x), finite(y)), finite(z)),
        and(
            s,
            and(
                s,
                F::vle(s, c(F::lit(F::MIN_SIZE)), m),
                F::vle(s, m, c(F::lit(F::MAX_SIZE))),
            ),
            F::vlt(s, F::vmul(s, c(F::lit(64.0) * F::EPSILON), m), d),
        ),
    )
}

/// The SIMD loop, instantiated by [`pulp::Arch::dispatch`] once per instruction set.
struct Batch<'r, 'e, 'o, F: Real> {
    prep: &'r PlaneWavePrep<F>,
    exits: &'r DirectionsSoa<'e, F>,
    out: &'r mut StokesSoa<'o, F>,
}

impl<F: ExpLanes> WithSimd for Batch<'_, '_, '_, F> {
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
        let lanes = F::lanes::<S>();
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
        let [o0, o1, o2, o3] = &mut out.s;
        let (o0, o1, o2, o3) = (&mut o0[..n], &mut o1[..n], &mut o2[..n], &mut o3[..n]);
        {
            let (v0, v1, v2, v3) = (
                &mut F::vsplit_mut::<S>(o0).0[..nv],
                &mut F::vsplit_mut::<S>(o1).0[..nv],
                &mut F::vsplit_mut::<S>(o2).0[..nv],
                &mut F::vsplit_mut::<S>(o3).0[..nv],
            );
            for i in 0..nv {
                let [a, b, c, d] = stokes_lanes::<S, F>(s, prep, hx[i], hy[i], hz[i]);
                v0[i] = a;
                v1[i] = b;
                v2[i] = c;
                v3[i] = d;
            }
        }
        if nv * lanes == n {
            return Ok(());
        }
        // The remainder, as `mueller::batch`: with at least one whole vector, recompute the last
        // whole vector `n − lanes .. n` (no masked store); shorter batches go through masked
        // loads and stores (the unused lanes compute on zeros and are discarded).
        let start = if nv > 0 { n - lanes } else { 0 };
        let load = |t: &[F]| {
            let t = &t[start..n];
            if nv > 0 {
                F::vsplit::<S>(t).0[0]
            } else {
                F::load_partial(s, t)
            }
        };
        let res = stokes_lanes::<S, F>(s, prep, load(xs), load(ys), load(zs));
        for (o, v) in [o0, o1, o2, o3].into_iter().zip(res) {
            let t = &mut o[start..n];
            if nv > 0 {
                F::vsplit_mut::<S>(t).0[0] = v;
            } else {
                F::store_partial(s, t, v);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
