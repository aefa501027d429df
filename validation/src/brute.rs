//! The brute-force reference: scalar Kirchhoff phase-screen reflection of a partially coherent
//! Gaussian Schell-model beam by random surfaces, summed explicitly on a grid and averaged over
//! realizations. Uses no gmueller code (only `rustfft` and `std`), so that it can serve as an
//! independent reference for the kernel.
//!
//! # Model
//! ```text
//! surface z = h(x), x = (x₁, x₂) in the tangent plane (t̂₁, t̂₂), normal n̂; perfect reflector
//! E_in(x)  = A(x) ψ(x) e^{i k d_t·x},        A(x) = exp(−|x|²/(2W²)),  |A(0)|² = S = 1
//! ⟨ψ(x₁) ψ*(x₂)⟩ = exp(−½ ξ⊥ᵀ Θ⁻¹ ξ⊥),      ξ⊥ = (x̂·ξ, ŷ·ξ),  ξ = x₁ − x₂   (packet frame x̂, ŷ)
//! E(r̂)     = ∫ E_in(x) e^{−i v h(x)} e^{−i k r̂_t·x} d²x = ∫ A ψ e^{−i v h} e^{−i h_t·x} d²x
//! v        = k (cos θ_i + cos θ_o),           h_t = k (r̂_t − d_t)   (0 at the specular direction)
//! dP/dΩ    = cos²θ_o / λ² · |E|²,             L = ⟨dP/dΩ⟩ / (|P| cos θ_o),  |P| = ∫ |A|²/S d²x
//! ```
//!
//! # Numerics
//! - The surface is an `N × N` periodic grid of spacing `dx`; heights are synthesised by
//!   circulant embedding of the sampled autocorrelation `R` (exact covariance at the grid
//!   points), the light likewise from its sampled coherence `c(ξ) = exp(−½ ξᵀ Ξ ξ)`,
//!   `Ξ = Aᵀ Θ⁻¹ A` with `A_ij = e_i·t̂_j` (the coherence seen at pairs of surface points).
//! - The light is a superposition of plane-wave modes `e^{i q·x}` with independent random
//!   phases and powers `λ_q = DFT(c)_q` (the circulant eigenvalues). The average over the light
//!   is done exactly: `⟨|E(h)|²⟩_ψ = N⁻² Σ_q λ_q |G(h − q)|²` with `G = dx² DFT(A e^{−i v h})`.
//!   Only the matter is sampled; the estimate's standard error is the sample standard
//!   deviation over height realizations divided by √K.
//! - Exit directions lie on the DFT grid, `h_t = 2π m/(N dx)`. The direction dependence of
//!   `v` is handled exactly by a Taylor series about a reference `v₀`:
//!   `e^{−i v h} = e^{−i v₀ h} Σ_n (−i (v − v₀))ⁿ hⁿ/n!`, one FFT per term, truncated at
//!   `10⁻¹³` relative.
//!
//! - The finite beam weighs a pair of surface points separated by ξ by the beam's normalised
//!   autocorrelation `B(ξ) = ∫A(x+ξ)A(x)d²x / ∫A² = exp(−|ξ|²/(4W²))`: the measured lobe is the
//!   stationary one blurred by a Gaussian of variance `1/(2W²)` in `h_t`, which inflates the
//!   far tails of a narrow lobe by `exp(h²/(4W²σ_h⁴))` (4 % at 5 lobe widths for W = 12 w).
//!   With [`Grid::beam_compensation`] (the default of [`auto_grid`]) the source coherence is
//!   `exp(−½ ξᵀ (Ξ − I/(2W²)) ξ)`, so that source coherence × `B` is exactly the target
//!   `exp(−½ ξᵀ Ξ ξ)`: the beam then averages point pairs exactly as a stationary field does.
//!
//! Remaining bias sources (small by construction): aliasing of the spectrum beyond the grid's
//! Nyquist frequency `π/dx`, and the periodic grid (box ≥ 6 W).

#![allow(dead_code)]

use std::f64::consts::TAU;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use rustfft::num_complex::Complex64 as C;
use rustfft::{Fft, FftPlanner};

/// A small deterministic generator (`SplitMix64`), so results do not depend on thread timing.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator for stream `stream` of run `seed`.
    #[must_use]
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self(seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
        r.next_u64();
        r
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
    }

    /// A circular complex normal variate with `E|Z|² = 1`.
    pub fn complex_normal(&mut self) -> C {
        let r = (-self.uniform().ln()).sqrt();
        C::from_polar(r, TAU * self.uniform())
    }
}

/// The random matter: a height field `z = h(x)` with a known autocorrelation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Matter {
    /// Gaussian correlation `R(r) = σ² exp(−r²/(2ℓ²))`.
    Gaussian {
        /// rms height σ (length).
        sigma: f64,
        /// correlation length ℓ (length).
        ell: f64,
    },
    /// Exponential correlation `R(r) = σ² exp(−r/ℓ)`: the K-correlation model with `γ = 2`,
    /// `T = ℓ²` (Matérn, smoothness ½).
    Exponential {
        /// rms height σ.
        sigma: f64,
        /// correlation length ℓ = √T.
        ell: f64,
    },
    /// A sinusoidal grating `h(x) = a sin(2π x₁/Λ + φ)` along t̂₁ with a uniformly random phase φ
    /// per realization: `R(ξ) = (a²/2) cos(2π ξ₁/Λ)`.
    Sinusoid {
        /// height amplitude a.
        amplitude: f64,
        /// period Λ.
        period: f64,
    },
}

impl Matter {
    /// The rms height `√R(0)`.
    #[must_use]
    pub fn rms(&self) -> f64 {
        match *self {
            Self::Gaussian { sigma, .. } | Self::Exponential { sigma, .. } => sigma,
            Self::Sinusoid { amplitude, .. } => amplitude / 2f64.sqrt(),
        }
    }

    /// The autocorrelation `R(ξ)` of a stationary random field (`None` for the grating, which
    /// is synthesised directly).
    fn correlation(&self, x: f64, y: f64) -> Option<f64> {
        let r2 = x * x + y * y;
        match *self {
            Self::Gaussian { sigma, ell } => Some(sigma * sigma * (-0.5 * r2 / (ell * ell)).exp()),
            Self::Exponential { sigma, ell } => Some(sigma * sigma * (-r2.sqrt() / ell).exp()),
            Self::Sinusoid { .. } => None,
        }
    }
}

/// The illumination and the surface, in surface coordinates (t̂₁, t̂₂, n̂) = (x, y, z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scene {
    /// Wavelength λ (length).
    pub wavelength: f64,
    /// Incidence angle `θ_i` (radians); the plane of incidence is `(t̂₁, n̂)` and the light travels
    /// along `d = (sin θ_i, 0, −cos θ_i)`.
    pub theta_i: f64,
    /// The transverse coherence covariance `Θ⊥` (length²) in the packet's s/p frame
    /// ([`Scene::packet_frame`]).
    pub theta: [[f64; 2]; 2],
    /// The height field.
    pub matter: Matter,
}

/// The sampling of the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Points per side.
    pub n: usize,
    /// Spacing (length).
    pub dx: f64,
    /// Beam envelope width W: `A = exp(−|x|²/(2W²))`.
    pub beam_width: f64,
    /// Divide the beam's autocorrelation `exp(−|ξ|²/(4W²))` out of the source coherence (see
    /// the module docs), so that the finite beam weighs point pairs exactly as the stationary
    /// field the kernel describes.
    pub beam_compensation: bool,
}

impl Grid {
    /// The spacing of the exit-direction grid in `h_t`, `2π/(N dx)` (rad/length).
    #[must_use]
    pub fn dh(&self) -> f64 {
        TAU / (self.n as f64 * self.dx)
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

impl Scene {
    /// The wavenumber `k = 2π/λ`.
    #[must_use]
    pub fn k(&self) -> f64 {
        TAU / self.wavelength
    }

    /// The propagation direction `d = (sin θ_i, 0, −cos θ_i)`.
    #[must_use]
    pub fn travel(&self) -> [f64; 3] {
        [self.theta_i.sin(), 0.0, -self.theta_i.cos()]
    }

    /// The packet's s/p frame `(x̂, ŷ, k̂) = (ŝ, d × ŝ, d)` with `ŝ = d × n̂ / |d × n̂|`
    /// (`ŝ = t̂₂` at normal incidence).
    #[must_use]
    pub fn packet_frame(&self) -> [[f64; 3]; 3] {
        let d = self.travel();
        let s = cross(d, [0.0, 0.0, 1.0]);
        let s = if s.iter().map(|v| v * v).sum::<f64>() < 1e-24 {
            [0.0, 1.0, 0.0]
        } else {
            unit(s)
        };
        [s, cross(d, s), d]
    }

    /// The coherence precision seen on the surface, `Ξ = Aᵀ Θ⁻¹ A` with `A_ij = e_i·t̂_j`
    /// (e = x̂, ŷ of the packet frame): `⟨ψ(x₁)ψ*(x₂)⟩ = exp(−½ ξᵀ Ξ ξ)` for surface separations ξ.
    #[must_use]
    pub fn surface_precision(&self) -> [[f64; 2]; 2] {
        let f = self.packet_frame();
        let a = [[f[0][0], f[0][1]], [f[1][0], f[1][1]]];
        let t = self.theta;
        let det = t[0][0] * t[1][1] - t[0][1] * t[1][0];
        let inv = [
            [t[1][1] / det, -t[0][1] / det],
            [-t[1][0] / det, t[0][0] / det],
        ];
        let mut xi = [[0.0; 2]; 2];
        for (i, row) in xi.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                for p in 0..2 {
                    for q in 0..2 {
                        *v += a[p][i] * inv[p][q] * a[q][j];
                    }
                }
            }
        }
        xi
    }

    /// The exit direction r̂ whose `h_t = k(r̂_t − d_t)` is `h`, or `None` below the horizon.
    #[must_use]
    pub fn exit_for(&self, h: [f64; 2]) -> Option<[f64; 3]> {
        let d = self.travel();
        let k = self.k();
        let rt = [d[0] + h[0] / k, d[1] + h[1] / k];
        let s2 = rt[0] * rt[0] + rt[1] * rt[1];
        (s2 < 1.0).then(|| [rt[0], rt[1], (1.0 - s2).sqrt()])
    }

    /// `v σ` at the specular direction (the phase-screen roughness parameter).
    #[must_use]
    pub fn v_sigma_specular(&self) -> f64 {
        2.0 * self.k() * self.theta_i.cos() * self.matter.rms()
    }
}

/// The brute-force estimate per direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Mean radiance `L` per unit incident irradiance across the beam.
    pub mean: Vec<f64>,
    /// Standard error of the mean (sample std / √K).
    pub std_err: Vec<f64>,
    /// Number of matter realizations K.
    pub realizations: usize,
    /// Taylor terms used for the `v` dependence.
    pub taylor_terms: usize,
    /// Light modes kept in the exact light average.
    pub light_modes: usize,
}

/// In-place 2-D FFT of a row-major `n × n` array (forward: `e^{−2πi k·j/n}`, unnormalised).
pub struct Fft2 {
    fft: Arc<dyn Fft<f64>>,
    scratch: Vec<C>,
    n: usize,
}

impl Fft2 {
    /// A forward (or, with `inverse`, backward) transform of size `n × n`.
    #[must_use]
    pub fn new(n: usize, inverse: bool) -> Self {
        let mut planner = FftPlanner::new();
        let fft = if inverse {
            planner.plan_fft_inverse(n)
        } else {
            planner.plan_fft_forward(n)
        };
        let scratch = vec![C::new(0.0, 0.0); fft.get_inplace_scratch_len()];
        Self { fft, scratch, n }
    }

    fn transpose(buf: &mut [C], n: usize) {
        for i in 0..n {
            for j in (i + 1)..n {
                buf.swap(i * n + j, j * n + i);
            }
        }
    }

    /// Transforms `buf` (row-major, `n²` values) in place.
    pub fn run(&mut self, buf: &mut [C]) {
        let n = self.n;
        self.fft.process_with_scratch(buf, &mut self.scratch);
        Self::transpose(buf, n);
        self.fft.process_with_scratch(buf, &mut self.scratch);
        Self::transpose(buf, n);
    }
}

/// Signed frequency index of DFT bin `i` (`−n/2 < s ≤ n/2`).
#[must_use]
pub fn signed(i: usize, n: usize) -> i64 {
    if i <= n / 2 {
        i as i64
    } else {
        i as i64 - n as i64
    }
}

/// The per-run constants shared by every realization.
struct Plan {
    n: usize,
    dx: f64,
    beam: Vec<f64>,
    area: f64,
    /// sqrt of the height spectrum (circulant eigenvalues), for random fields.
    height_amp: Option<Vec<f64>>,
    /// Light modes `(q_x, q_y, λ_q / N²)`.
    modes: Vec<(i64, i64, f64)>,
    /// Per direction: DFT index `(m_x, m_y)`, Taylor coefficients `(−iΔv)ⁿ/n!`, `cos θ_o/λ²/|P|`.
    dirs: Vec<([i64; 2], Vec<C>, f64)>,
    v0: f64,
    terms: usize,
}

/// The beam envelope `A(x) = exp(−|x|²/(2W²))` on the grid (row-major, centred at index `n/2`)
/// and its area `|P| = Σ |A|² dx²`.
#[must_use]
pub fn beam_envelope(grid: &Grid) -> (Vec<f64>, f64) {
    let (n, dx) = (grid.n, grid.dx);
    let half = (n / 2) as f64;
    let coord = |i: usize| (i as f64 - half) * dx;
    let mut beam = vec![0.0; n * n];
    let w2 = grid.beam_width * grid.beam_width;
    for iy in 0..n {
        for ix in 0..n {
            let (x, y) = (coord(ix), coord(iy));
            beam[iy * n + ix] = (-(x * x + y * y) / (2.0 * w2)).exp();
        }
    }
    let area = beam.iter().map(|a| a * a).sum::<f64>() * dx * dx;
    (beam, area)
}

fn plan(scene: &Scene, grid: &Grid, dirs: &[[i64; 2]]) -> Plan {
    let (n, dx) = (grid.n, grid.dx);
    let nn = n * n;
    let (beam, area) = beam_envelope(grid);
    let w2 = grid.beam_width * grid.beam_width;

    let mut fwd = Fft2::new(n, false);
    let mut spectrum = |cov: &dyn Fn(f64, f64) -> f64| circulant_spectrum(&mut fwd, dx, cov);

    let mut xi = scene.surface_precision();
    if grid.beam_compensation {
        let d = 1.0 / (2.0 * w2);
        xi[0][0] -= d;
        xi[1][1] -= d;
    }
    let lam = spectrum(&|x, y| {
        (-0.5 * (xi[0][0] * x * x + (xi[0][1] + xi[1][0]) * x * y + xi[1][1] * y * y)).exp()
    });
    let lmax = lam.iter().copied().fold(0.0, f64::max);
    let mut modes = Vec::new();
    for iy in 0..n {
        for ix in 0..n {
            let l = lam[iy * n + ix];
            if l > 1e-13 * lmax {
                modes.push((signed(ix, n), signed(iy, n), l / nn as f64));
            }
        }
    }

    let height_amp = height_amplitudes(&mut fwd, &scene.matter, dx);

    // Directions, v, and the Taylor order.
    let k = scene.k();
    let cos_i = scene.theta_i.cos();
    let dh = grid.dh();
    let geo: Vec<(f64, f64)> = dirs
        .iter()
        .map(|m| {
            let r = scene
                .exit_for([m[0] as f64 * dh, m[1] as f64 * dh])
                .expect("exit direction below the horizon");
            (r[2], k * (cos_i + r[2]))
        })
        .collect();
    let vmin = geo.iter().map(|g| g.1).fold(f64::INFINITY, f64::min);
    let vmax = geo.iter().map(|g| g.1).fold(0.0, f64::max);
    let v0 = 0.5 * (vmin + vmax);
    let hmax = match scene.matter {
        Matter::Sinusoid { amplitude, .. } => amplitude,
        m => 7.0 * m.rms(),
    };
    let x = 0.5 * (vmax - vmin) * hmax;
    let mut terms = 1;
    let mut term = 1.0;
    while terms < 60 {
        term *= x / terms as f64;
        terms += 1;
        if term < 1e-13 {
            break;
        }
    }
    let lambda = scene.wavelength;
    let plan_dirs = dirs
        .iter()
        .zip(&geo)
        .map(|(m, &(cos_o, v))| {
            let dv = v - v0;
            let mut c = Vec::with_capacity(terms);
            let mut cur = C::new(1.0, 0.0);
            for t in 0..terms {
                if t > 0 {
                    cur = cur * C::new(0.0, -dv) / t as f64;
                }
                c.push(cur);
            }
            (*m, c, cos_o / (lambda * lambda) / area)
        })
        .collect();
    Plan {
        n,
        dx,
        beam,
        area,
        height_amp,
        modes,
        dirs: plan_dirs,
        v0,
        terms,
    }
}

/// Circulant eigenvalues of a sampled stationary covariance `cov(x, y)` on the `n × n` grid of
/// spacing `dx` (`n` from `fwd`; min-image separations), clamped at 0.
pub fn circulant_spectrum(fwd: &mut Fft2, dx: f64, cov: &dyn Fn(f64, f64) -> f64) -> Vec<f64> {
    let n = fwd.n;
    let mut buf = vec![C::new(0.0, 0.0); n * n];
    for iy in 0..n {
        for ix in 0..n {
            let (x, y) = (signed(ix, n) as f64 * dx, signed(iy, n) as f64 * dx);
            buf[iy * n + ix] = C::new(cov(x, y), 0.0);
        }
    }
    fwd.run(&mut buf);
    buf.iter().map(|c| c.re.max(0.0)).collect()
}

/// The square roots of the height spectrum (circulant eigenvalues of `R`) on the grid of `fwd`
/// with spacing `dx`, or `None` for the grating (synthesised directly).
pub fn height_amplitudes(fwd: &mut Fft2, matter: &Matter, dx: f64) -> Option<Vec<f64>> {
    matter.correlation(0.0, 0.0)?;
    let m = *matter;
    let mu = circulant_spectrum(fwd, dx, &|x, y| m.correlation(x, y).unwrap_or(0.0));
    Some(mu.into_iter().map(f64::sqrt).collect())
}

/// Two independent random height fields with spectrum `amp²` (the real and imaginary parts of
/// one complex field), using `inv` (a backward [`Fft2`]) and the scratch `buf` (`n²` values).
pub fn random_heights(
    inv: &mut Fft2,
    buf: &mut [C],
    amp: &[f64],
    rng: &mut Rng,
) -> (Vec<f64>, Vec<f64>) {
    for (b, a) in buf.iter_mut().zip(amp) {
        *b = rng.complex_normal() * *a;
    }
    inv.run(buf);
    let s = 2f64.sqrt() / inv.n as f64;
    (
        buf.iter().map(|c| c.re * s).collect(),
        buf.iter().map(|c| c.im * s).collect(),
    )
}

/// Scratch space of one worker thread.
struct Worker {
    fwd: Fft2,
    inv: Fft2,
    buf: Vec<C>,
    u: Vec<C>,
    /// Interleaved `G_t[idx]` at `g[idx * terms + t]`.
    g: Vec<C>,
}

impl Worker {
    fn new(p: &Plan) -> Self {
        let nn = p.n * p.n;
        Self {
            fwd: Fft2::new(p.n, false),
            inv: Fft2::new(p.n, true),
            buf: vec![C::new(0.0, 0.0); nn],
            u: vec![C::new(0.0, 0.0); nn],
            g: vec![C::new(0.0, 0.0); nn * p.terms],
        }
    }

    /// `L` at every direction for one height field, averaged exactly over the light.
    fn radiance(&mut self, p: &Plan, h: &[f64]) -> Vec<f64> {
        let (n, terms) = (p.n, p.terms);
        let dx2 = p.dx * p.dx;
        for ((u, &a), &z) in self.u.iter_mut().zip(&p.beam).zip(h) {
            *u = C::from_polar(a * dx2, -p.v0 * z);
        }
        for t in 0..terms {
            // buf = A e^{−i v₀ h} hᵗ dx², built by repeated multiplication.
            self.buf.copy_from_slice(&self.u);
            for (u, &z) in self.u.iter_mut().zip(h) {
                *u *= z;
            }
            self.fwd.run(&mut self.buf);
            for (i, b) in self.buf.iter().enumerate() {
                self.g[i * terms + t] = *b;
            }
        }
        let ni = n as i64;
        p.dirs
            .iter()
            .map(|(m, c, front)| {
                let mut acc = 0.0;
                for &(qx, qy, w) in &p.modes {
                    let ix = (m[0] - qx).rem_euclid(ni) as usize;
                    let iy = (m[1] - qy).rem_euclid(ni) as usize;
                    let g = &self.g[(iy * n + ix) * terms..][..terms];
                    let s: C = g.iter().zip(c).map(|(a, b)| a * b).sum();
                    acc += w * s.norm_sqr();
                }
                acc * front
            })
            .collect()
    }
}

/// Runs the brute force: `realizations` height fields (seeded by `seed`, independent of the
/// thread count), `threads` workers, `progress` called once per finished realization.
///
/// `dirs` are DFT indices `m`: `h_t = m · 2π/(N dx)`.
///
/// # Panics
/// If a direction is below the horizon or, for the grating, the box is not a whole number of
/// periods.
#[must_use]
pub fn run(
    scene: &Scene,
    grid: &Grid,
    dirs: &[[i64; 2]],
    realizations: usize,
    seed: u64,
    threads: usize,
    progress: &(dyn Fn() + Sync),
) -> Estimate {
    let p = plan(scene, grid, dirs);
    if let Matter::Sinusoid { period, .. } = scene.matter {
        let periods = grid.n as f64 * grid.dx / period;
        assert!(
            (periods - periods.round()).abs() < 1e-9,
            "grid box must hold a whole number of grating periods"
        );
    }
    // Work items: pairs of realizations for random fields, singles for the grating.
    let per_item = if p.height_amp.is_some() { 2 } else { 1 };
    let items = realizations.div_ceil(per_item);
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<(usize, Vec<f64>)>> = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| {
                let mut w = Worker::new(&p);
                loop {
                    let item = next.fetch_add(1, Ordering::Relaxed);
                    if item >= items {
                        break;
                    }
                    let mut rng = Rng::new(seed, item as u64);
                    let fields: Vec<Vec<f64>> = match (&p.height_amp, scene.matter) {
                        (Some(amp), _) => {
                            let (a, b) = random_heights(&mut w.inv, &mut w.buf, amp, &mut rng);
                            vec![a, b]
                        }
                        (None, Matter::Sinusoid { amplitude, period }) => {
                            let phase = TAU * rng.uniform();
                            let n = p.n;
                            let half = (n / 2) as f64;
                            let mut h = vec![0.0; n * n];
                            for iy in 0..n {
                                for ix in 0..n {
                                    let x = (ix as f64 - half) * p.dx;
                                    h[iy * n + ix] = amplitude * (TAU * x / period + phase).sin();
                                }
                            }
                            vec![h]
                        }
                        (None, _) => unreachable!("random fields carry a spectrum"),
                    };
                    for (j, h) in fields.iter().enumerate() {
                        let idx = item * per_item + j;
                        if idx >= realizations {
                            break;
                        }
                        let l = w.radiance(&p, h);
                        results.lock().expect("poisoned").push((idx, l));
                        progress();
                    }
                }
            });
        }
    });
    let mut results = results.into_inner().expect("poisoned");
    results.sort_by_key(|r| r.0);
    let k = results.len() as f64;
    let nd = dirs.len();
    let mut mean = vec![0.0; nd];
    for (_, l) in &results {
        for (m, v) in mean.iter_mut().zip(l) {
            *m += v / k;
        }
    }
    let mut var = vec![0.0; nd];
    for (_, l) in &results {
        for ((s, v), m) in var.iter_mut().zip(l).zip(&mean) {
            *s += (v - m) * (v - m) / (k - 1.0).max(1.0);
        }
    }
    Estimate {
        std_err: var.iter().map(|v| (v / k).sqrt()).collect(),
        mean,
        realizations: results.len(),
        taylor_terms: p.terms,
        light_modes: p.modes.len(),
    }
}

/// A grid for `scene`: spacing at most `min(ℓ, w)/points_per_length` (w the smallest surface
/// coherence width), beam width `beam_factor` × the largest of ℓ and the surface coherence
/// widths, box ≥ 6 beam widths, `N` rounded up to a 2ᵃ3ᵇ size.
#[must_use]
pub fn auto_grid(scene: &Scene, points_per_length: f64, beam_factor: f64) -> Grid {
    let xi = scene.surface_precision();
    // Surface coherence widths: 1/√eigenvalues of Ξ.
    let tr = 0.5 * (xi[0][0] + xi[1][1]);
    let dd = (0.25 * (xi[0][0] - xi[1][1]).powi(2) + xi[0][1] * xi[1][0]).sqrt();
    let (wmin, wmax) = (1.0 / (tr + dd).sqrt(), 1.0 / (tr - dd).sqrt());
    let ell = match scene.matter {
        Matter::Gaussian { ell, .. } | Matter::Exponential { ell, .. } => ell,
        Matter::Sinusoid { period, .. } => period,
    };
    let mut dx = ell.min(wmin) / points_per_length;
    let beam_width = beam_factor * ell.max(wmax);
    let need = 6.0 * beam_width;
    let mut n = fast_size((need / dx).ceil() as usize);
    if let Matter::Sinusoid { period, .. } = scene.matter {
        // A whole number of periods in the box, 8 multiple-of-2 points per period at least.
        let per = (period / dx).ceil().max(8.0) as usize;
        let per = per.next_power_of_two();
        dx = period / per as f64;
        n = fast_size_multiple((need / dx).ceil() as usize, per);
    }
    Grid {
        n,
        dx,
        beam_width,
        beam_compensation: true,
    }
}

/// The smallest 2ᵃ3ᵇ ≥ m that is a multiple of the power of two `per`.
fn fast_size_multiple(m: usize, per: usize) -> usize {
    let mut n = fast_size(m);
    while !n.is_multiple_of(per) {
        n = fast_size(n + 1);
    }
    n
}

/// The smallest 2ᵃ3ᵇ ≥ m.
#[must_use]
pub fn fast_size(m: usize) -> usize {
    let mut best = usize::MAX;
    let mut p2 = 1usize;
    while p2 < 4 * m {
        let mut p = p2;
        while p < 4 * m {
            if p >= m && p < best {
                best = p;
            }
            p *= 3;
        }
        p2 *= 2;
    }
    best
}
