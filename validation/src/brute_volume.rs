//! The volumetric brute-force reference: first-Born vector scattering of a partially coherent
//! Gaussian Schell-model beam (finite longitudinal coherence `σ_zz`) by a random permittivity
//! field, summed explicitly over voxels and averaged over realizations. Like [`crate::brute`]
//! it uses no gmueller physics — only `std`, `rustfft` and the kit's seeded generator (through
//! [`crate::brute::Rng`]) — so that it can serve as an independent reference for the n = 3
//! kernel (`crate::kernel_side_volume`).
//!
//! # Model (SI, non-magnetic, background index 1, `e^{−iωt}`)
//! ```text
//! ε(r)      = 1 + δε(r),   ⟨δε(r₁) δε(r₂)⟩ = R(r₁ − r₂)                      (stationary, zero mean)
//! E_in(r)   = W(r) [x̂ a_x(r) + ŷ a_y(r)] e^{i k d̂·r}                          (packet frame x̂, ŷ, d̂)
//! ⟨a_α(r₁) a_β*(r₂)⟩ = C_αβ exp(−½ ξᵀ Ξ_αβ ξ),   ξ = r₁ − r₂,   Ξ_αβ = Q Θ_αβ⁻¹ Qᵀ
//! Θ_xx = Θ_x, Θ_yy = Θ_y, Θ_xy = Θ_yx = Θ_½ = (Θ_x + Θ_y)/2,   Θ_α = blockdiag(θ_α, σ_zz²),  Q = [x̂ ŷ d̂]
//! C = [[S_x, (S2 − iS3)/2], [(S2 + iS3)/2, S_y]],   S_{x,y} = (S0 ± S1)/2           (S0 = 1: unit irradiance)
//! E_s(r r̂)  = (k²/4π) (e^{ikr}/r) (I − r̂r̂ᵀ) ∫ δε(r') E_in(r') e^{−ik r̂·r'} d³r'          (first Born)
//! β(r̂)      = r² ⟨E_s E_s†⟩ / V,   V = ∫ W² d³r       (Stokes of β in the exit frame below)
//! ```
//! β is the radiant intensity scattered per unit lit volume per unit incident irradiance (a
//! differential scattering coefficient, 1/(length·sr)); its Stokes vector is taken in the exit
//! frame `(ŝ_o, p̂_o, r̂)`, `ŝ_o = (r̂ × ẑ)/|r̂ × ẑ|`, `p̂_o = r̂ × ŝ_o` (gmueller's `Frame::sp(r̂, ẑ)`),
//! with `S0 = C_uu + C_vv`, `S1 = C_uu − C_vv`, `S2 = 2 Re C_uv`, `S3 = −2 Im C_uv`
//! (`C_uv = ⟨E_u E_v*⟩`, so `S3 = 2 Im⟨E_u* E_v⟩` and the Jones vector `(1, i)/√2` has `S3 = +1`).
//! The packet frame is `(ŝ, d̂ × ŝ, d̂)` with `ŝ = (d̂ × ẑ)/|d̂ × ẑ|` (`Frame::sp(d̂, ẑ)`), the light
//! travels along `d̂ = (sin θ_i, 0, −cos θ_i)`.
//!
//! # Derivation, from first principles
//! - **First Born.** With `ε = 1 + δε` the field obeys `∇×∇×E − k² E = k² δε E`: the scattered
//!   field is radiated by the polarization density `ε₀ δε E`. To first order in δε the source is
//!   `ε₀ δε E_in`, and the far field of a dipole `p` at `r'` is
//!   `(k²/4πε₀) (e^{ik|r−r'|}/|r−r'|) (r̂ × p) × r̂` (Jackson, *Classical Electrodynamics*, 3rd ed.,
//!   §9.2), with `(r̂ × p) × r̂ = (I − r̂r̂ᵀ) p = −r̂ × (r̂ × p)` and
//!   `|r − r'| ≈ r − r̂·r'`: the line `E_s` above. A small sphere of volume `v` and contrast
//!   `δε ≪ 1` then scatters the cross-section `k⁴ v² δε²/(6π)`, Rayleigh's
//!   `(8π/3) k⁴ a⁶ ((ε − 1)/(ε + 2))²` to first order (`tests::single_voxel_is_a_rayleigh_dipole`
//!   integrates the brute force's β over the sphere for one voxel and checks this).
//! - **Radiometry.** The time-averaged intensity of a field `E` in vacuum is `|E|²/(2Z₀)`, so
//!   `dP/dΩ = r² |E_s|²/(2Z₀)` and the incident irradiance is `S0/(2Z₀)` with `S0 = tr C = 1`:
//!   per unit irradiance the `2Z₀` cancel, as in the surface brute force.
//! - **The average.** With `f = δε W` and `h = k(r̂ − d̂) = k(r̂ + ŝ)` (ŝ = −d̂ toward the source),
//!   `r² ⟨E_s E_s†⟩ = (k²/4π)² Σ_αβ C_αβ P e_α e_βᵀ P ∫∫ W₁W₂ R(ξ) e^{−½ξᵀΞ_αβξ} e^{−ih·ξ} d³r₁ d³r₂`
//!   (`P = I − r̂r̂ᵀ`, e = x̂, ŷ). Writing `∫ W(r₂ + ξ) W(r₂) d³r₂ = V B(ξ)`, the stationary medium
//!   gives `β = (k²/4π)² Σ_αβ C_αβ P e_α e_βᵀ P ∫ R(ξ) e^{−½ξᵀΞ_αβξ} B(ξ) e^{−ih·ξ} d³ξ`; the
//!   kernel's prediction is this with `B = 1` (an unbounded lit region):
//!   `∫ R e^{−½ξᵀΞξ} e^{−ih·ξ} d³ξ = |Θ|^{1/2} ∫ p(q) g^Ξ(h − q) d³q`, the crate's `K³`.
//! - **Beam compensation.** For a Gaussian window `W = exp(−|r|²/(2w_b²))`,
//!   `B(ξ) = exp(−|ξ|²/(4w_b²))` exactly. The light is therefore synthesised with the precision
//!   `Ξ − I/(2w_b²)` (the axes the window covers), so that light × B is exactly the target
//!   coherence: the finite window then weighs pairs of points as an unbounded medium does.
//!   For `θ_x ≠ θ_y` the compensated cross-spectral matrix is not positive semidefinite in its
//!   far tails (`Θ ↦ (Θ⁻¹ − cI)⁻¹` is convex, so the compensated `Θ_½` falls below the mean of
//!   the compensated `Θ_x`, `Θ_y` and Bochner's bound fails at large q): the compensated source
//!   is then not a realizable random field. The light average is linear in the cross-spectra,
//!   so it still gives the double sum with the target coherence exactly; the explicit-field
//!   test below runs uncompensated.
//!
//! # Numerics
//! - A periodic grid of `n_x × n_y × n_z` voxels of sides `d` (centred at index `n/2`). δε is
//!   synthesised by circulant embedding of the sampled `R` (exact covariance at the grid
//!   points), two realizations per complex FFT. The sum over voxels is the rectangle rule of
//!   the integral; its error is the aliasing `Σ_{m≠0} F{R c}(h + 2πm/d)`, below 10⁻⁹ relative for
//!   a Gaussian R with `d ≤ ℓ/2` at `|h| ≤ 2k ≤ 2.6/ℓ` (the configurations' range).
//! - The light is averaged exactly, as in [`crate::brute`]: it is a sum of grid modes
//!   `e^{iq·r}` with independent random amplitudes of power `λ_q/N` (`λ_q` the circulant
//!   eigenvalues of the sampled coherence, one set per channel xx, yy, xy), so
//!   `⟨E_s E_s†⟩_light ∝ Σ_αβ C_αβ P e_α e_βᵀ P Σ_q (λ^{αβ}_q/N) |G(h − q)|²`,
//!   `G(κ) = Σ_r f(r) e^{−iκ·r} d³r`. The light enters only through three scalar sums per
//!   direction ([`ChannelSums`]), from which any incident Stokes vector is evaluated
//!   ([`VolumeEstimate::stokes`]); `tests::light_average_is_the_mean_over_random_fields` checks
//!   this against explicit random vector fields pushed through the literal `(I − r̂r̂ᵀ)` sum.
//! - Exit directions are arbitrary: `G(h − q) = FFT(f e^{−ih·r})` at `−q` (one 3-D FFT per
//!   direction and realization, pruned to the block of x- and y-indices the modes use).
//! - Statistics: the matter is sampled; per realization the Stokes vector of every input;
//!   standard errors are the sample standard deviation over realizations divided by √K, and the
//!   degree of polarization's by the jackknife.
//!
//! # Thin slab ([`Region::ThinSlab`])
//! One layer (`n_z = 1`) of thickness `t = d_z` at z = 0, `δε(x, y, z) = δε₂(x, y)` for `|z| < t/2`
//! (fully correlated across the thickness) with `R₂(ξ_t) = R(ξ_t, 0)`, and a transverse Gaussian
//! window. Then `∫∫ dz₁ dz₂ e^{−½ξᵀΞξ} e^{−ih_z(z₁−z₂)} = t² e^{−½ξ_tᵀ Ξ_tt ξ_t} (1 + O((h_z t)², t²Ξ_zz))`:
//! the one-layer sum is the `t → 0` limit (at fixed `t δε₂`), where the light is sectioned by
//! the plane (`Ξ_tt`, the tangent block of the 3-D precision) and `h_z` drops out.

#![allow(dead_code)]

use std::f64::consts::{PI, TAU};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use rustfft::num_complex::Complex64 as C;

use crate::brute::{Rng, inverse2, sandwich};

mod fft3;
pub use fft3::{Fft3, circulant_spectrum};

/// A 3-vector (world coordinates, ẑ the slab normal).
pub type V3 = [f64; 3];
type M3 = [[f64; 3]; 3];

/// The random permittivity perturbation δε (dimensionless), stationary with a known 3-D
/// autocorrelation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Permittivity {
    /// `R(r) = σ² exp(−|r|²/(2ℓ²))`.
    Gaussian {
        /// rms perturbation σ.
        sigma: f64,
        /// correlation length ℓ.
        ell: f64,
    },
    /// `R(r) = σ² exp(−|r|/ℓ)` (PSD `∝ (1 + ℓ²q²)⁻²` in 3-D: the K-correlation with `γ = 3`,
    /// `T = ℓ²`).
    Exponential {
        /// rms perturbation σ.
        sigma: f64,
        /// correlation length ℓ.
        ell: f64,
    },
}

impl Permittivity {
    /// The autocorrelation at separation `r`.
    #[must_use]
    pub fn correlation(&self, r: V3) -> f64 {
        let r2 = dot(r, r);
        match *self {
            Self::Gaussian { sigma, ell } => sigma * sigma * (-0.5 * r2 / (ell * ell)).exp(),
            Self::Exponential { sigma, ell } => sigma * sigma * (-r2.sqrt() / ell).exp(),
        }
    }

    /// The correlation length ℓ.
    #[must_use]
    pub fn ell(&self) -> f64 {
        match *self {
            Self::Gaussian { ell, .. } | Self::Exponential { ell, .. } => ell,
        }
    }
}

/// The Gaussian Schell-model light: a packet of wavelength λ travelling along
/// `d̂ = (sin θ_i, 0, −cos θ_i)` with transverse shapes `θ_x`, `θ_y` (length², in the packet
/// frame) and longitudinal coherence `σ_zz`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Wavelength λ (length).
    pub wavelength: f64,
    /// Angle of `−d̂` from ẑ (radians).
    pub theta_i: f64,
    /// Transverse coherence covariance of the x̂ component.
    pub theta_x: [[f64; 2]; 2],
    /// Transverse coherence covariance of the ŷ component.
    pub theta_y: [[f64; 2]; 2],
    /// Longitudinal coherence length `σ_zz` (`f64::INFINITY`: unbounded, thin slabs only).
    pub sigma_zz: f64,
}

impl Light {
    /// `k = 2π/λ`.
    #[must_use]
    pub fn k(&self) -> f64 {
        TAU / self.wavelength
    }

    /// The propagation direction d̂.
    #[must_use]
    pub fn travel(&self) -> V3 {
        [self.theta_i.sin(), 0.0, -self.theta_i.cos()]
    }

    /// The packet frame `(x̂, ŷ, d̂) = (ŝ, d̂ × ŝ, d̂)`, `ŝ = (d̂ × ẑ)/|d̂ × ẑ|` (`ŝ = ŷ` at normal
    /// incidence).
    #[must_use]
    pub fn packet_frame(&self) -> [V3; 3] {
        let d = self.travel();
        let s = cross(d, [0.0, 0.0, 1.0]);
        let s = if dot(s, s) < 1e-24 {
            [0.0, 1.0, 0.0]
        } else {
            unit(s)
        };
        [s, cross(d, s), d]
    }

    /// The transverse shape of channel `c` (0: xx, 1: yy, 2: xy, the mean of the two).
    #[must_use]
    pub fn shape(&self, c: usize) -> [[f64; 2]; 2] {
        let (a, b) = (self.theta_x, self.theta_y);
        match c {
            0 => a,
            1 => b,
            _ => [
                [0.5 * (a[0][0] + b[0][0]), 0.5 * (a[0][1] + b[0][1])],
                [0.5 * (a[1][0] + b[1][0]), 0.5 * (a[1][1] + b[1][1])],
            ],
        }
    }

    /// The world precision `Ξ = Q Θ⁻¹ Qᵀ` of channel `c` (`Θ = blockdiag(θ_c, σ_zz²)`, Q the
    /// packet frame as columns): `⟨a(r₁)a*(r₂)⟩ ∝ exp(−½ ξᵀ Ξ ξ)`.
    #[must_use]
    pub fn precision(&self, c: usize) -> M3 {
        let f = self.packet_frame();
        let inv_zz = 1.0 / (self.sigma_zz * self.sigma_zz);
        let mut xi = sandwich([f[0], f[1]], inverse2(self.shape(c)));
        for (i, row) in xi.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v += f[2][i] * inv_zz * f[2][j];
            }
        }
        xi
    }

    /// `true` when `θ_x = θ_y` (one light channel describes every pair).
    #[must_use]
    pub fn single_shape(&self) -> bool {
        self.theta_x == self.theta_y
    }
}

/// The lit region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Region {
    /// δε fills space; the lit volume is the Gaussian window `exp(−|r|²/(2w_b²))` (the beam
    /// envelope and the region in one), `w_b = window`.
    Bulk {
        /// Window width `w_b` (length).
        window: f64,
    },
    /// One layer of thickness `t` at z = 0 (module docs), transverse window `exp(−ρ²/(2w_b²))`.
    ThinSlab {
        /// Transverse window width `w_b`.
        window: f64,
        /// Thickness t.
        thickness: f64,
    },
}

impl Region {
    /// The window width.
    #[must_use]
    pub fn window(&self) -> f64 {
        match *self {
            Self::Bulk { window } | Self::ThinSlab { window, .. } => window,
        }
    }
}

/// A volumetric scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeScene {
    /// The light.
    pub light: Light,
    /// The permittivity field.
    pub matter: Permittivity,
    /// The lit region.
    pub region: Region,
}

/// The sampling grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeGrid {
    /// Voxels per axis.
    pub n: [usize; 3],
    /// Voxel sides (length); `d[2]` is the slab thickness for a thin slab.
    pub d: [f64; 3],
    /// Synthesise the light with the window's autocorrelation divided out (module docs).
    pub beam_compensation: bool,
}

impl VolumeGrid {
    /// Total number of voxels.
    #[must_use]
    pub fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// `true` for an empty grid.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A grid for `scene`: spacing `ℓ/points_per_length`, a box of `box_windows` window widths per
/// lit axis rounded up to a 2ᵃ3ᵇ size; a thin slab gets one layer of its thickness.
#[must_use]
pub fn auto_grid(scene: &VolumeScene, points_per_length: f64, box_windows: f64) -> VolumeGrid {
    let dx = scene.matter.ell() / points_per_length;
    let n = crate::brute::fast_size((box_windows * scene.region.window() / dx).ceil() as usize);
    match scene.region {
        Region::Bulk { .. } => VolumeGrid {
            n: [n; 3],
            d: [dx; 3],
            beam_compensation: true,
        },
        Region::ThinSlab { thickness, .. } => VolumeGrid {
            n: [n, n, 1],
            d: [dx, dx, thickness],
            beam_compensation: true,
        },
    }
}

/// The three light-channel sums of one direction and realization, times `(k²/4π)²/V`:
/// `[xx, yy, xy]` (module docs); `β = Σ_αβ C_αβ sums_αβ P e_α e_βᵀ P`.
pub type ChannelSums = [f64; 3];

/// The brute force's result: channel sums per realization and direction.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeEstimate {
    /// Exit directions r̂.
    pub exits: Vec<V3>,
    /// `sums[realization][direction]`.
    pub sums: Vec<Vec<ChannelSums>>,
    /// Light modes kept in the exact light average.
    pub light_modes: usize,
    /// The light (for the frames).
    pub light: Light,
}

/// One direction's Stokes estimate for one incident Stokes vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StokesEstimate {
    /// Mean Stokes vector of β in the exit frame (1/(length·sr) per unit irradiance).
    pub mean: [f64; 4],
    /// Standard errors of the four components.
    pub se: [f64; 4],
    /// Degree of polarization of the mean.
    pub dop: f64,
    /// Its jackknife standard error.
    pub dop_se: f64,
}

/// The degree of polarization `√(S1² + S2² + S3²)/S0`.
#[must_use]
pub fn dop(s: &[f64; 4]) -> f64 {
    (s[1] * s[1] + s[2] * s[2] + s[3] * s[3]).sqrt() / s[0]
}

impl VolumeEstimate {
    /// The Stokes vector (exit frame) of β for the incident Stokes vector `input` (packet
    /// frame, `S0 = 1` is unit irradiance), per realization.
    #[must_use]
    pub fn stokes_samples(&self, input: [f64; 4], dir: usize) -> Vec<[f64; 4]> {
        let proj = projections(&self.light, self.exits[dir]);
        self.sums
            .iter()
            .map(|s| stokes_of(&proj, input, s[dir]))
            .collect()
    }

    /// Mean, standard errors and the degree of polarization per direction for `input`.
    #[must_use]
    pub fn stokes(&self, input: [f64; 4]) -> Vec<StokesEstimate> {
        (0..self.exits.len())
            .map(|d| summarize(&self.stokes_samples(input, d)))
            .collect()
    }
}

fn summarize(samples: &[[f64; 4]]) -> StokesEstimate {
    let k = samples.len() as f64;
    let mut mean = [0.0; 4];
    for s in samples {
        for i in 0..4 {
            mean[i] += s[i] / k;
        }
    }
    let mut se = [0.0; 4];
    for s in samples {
        for i in 0..4 {
            se[i] += (s[i] - mean[i]).powi(2) / (k - 1.0).max(1.0);
        }
    }
    let se = se.map(|v| (v / k).sqrt());
    // Jackknife of the DoP of the mean.
    let full = dop(&mean);
    let mut acc = 0.0;
    if samples.len() > 1 {
        for s in samples {
            let loo: [f64; 4] = std::array::from_fn(|i| (mean[i] * k - s[i]) / (k - 1.0));
            acc += (dop(&loo) - full).powi(2);
        }
    }
    StokesEstimate {
        mean,
        se,
        dop: full,
        dop_se: ((k - 1.0) / k * acc).sqrt(),
    }
}

/// The exit frame `(ŝ_o, p̂_o)` of r̂ (module docs).
///
/// # Panics
/// If r̂ is within 1e-9 of ±ẑ (the frame is undefined there).
#[must_use]
pub fn exit_frame(r: V3) -> [V3; 2] {
    let s = cross(r, [0.0, 0.0, 1.0]);
    assert!(
        dot(s, s) > 1e-18,
        "exit {r:?} along ±ẑ: exit frame undefined"
    );
    let s = unit(s);
    [s, cross(r, s)]
}

/// `A[o][α] = o · (I − r̂r̂ᵀ) e_α` for the exit axes `o = ŝ_o, p̂_o` and the packet axes `e = x̂, ŷ`.
fn projections(light: &Light, r: V3) -> [[f64; 2]; 2] {
    let f = light.packet_frame();
    let o = exit_frame(r);
    let proj = |e: V3| {
        let re = dot(r, e);
        [e[0] - re * r[0], e[1] - re * r[1], e[2] - re * r[2]]
    };
    let pe = [proj(f[0]), proj(f[1])];
    [
        [dot(o[0], pe[0]), dot(o[0], pe[1])],
        [dot(o[1], pe[0]), dot(o[1], pe[1])],
    ]
}

/// The exit Stokes vector from the projections, the incident Stokes vector and the channel sums.
fn stokes_of(a: &[[f64; 2]; 2], s: [f64; 4], t: ChannelSums) -> [f64; 4] {
    // Incident CSD C_αβ (packet frame) weighted by the channel sums.
    let cxy = C::new(0.5 * s[2], -0.5 * s[3]) * t[2];
    let cin = [
        [C::new(0.5 * (s[0] + s[1]) * t[0], 0.0), cxy],
        [cxy.conj(), C::new(0.5 * (s[0] - s[1]) * t[1], 0.0)],
    ];
    // C_out = A C_in Aᵀ.
    let mut cout = [[C::new(0.0, 0.0); 2]; 2];
    for (i, row) in cout.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            for p in 0..2 {
                for q in 0..2 {
                    *v += cin[p][q] * (a[i][p] * a[j][q]);
                }
            }
        }
    }
    [
        cout[0][0].re + cout[1][1].re,
        cout[0][0].re - cout[1][1].re,
        2.0 * cout[0][1].re,
        -2.0 * cout[0][1].im,
    ]
}

/// Voxel-centre coordinates along `axis` (centred at index `n/2`).
fn coords(grid: &VolumeGrid, axis: usize) -> Vec<f64> {
    let n = grid.n[axis];
    let half = (n / 2) as f64;
    (0..n).map(|i| (i as f64 - half) * grid.d[axis]).collect()
}

/// The window `W` on the grid and `V = Σ W² d³r`.
#[must_use]
pub fn window(scene: &VolumeScene, grid: &VolumeGrid) -> (Vec<f64>, f64) {
    let c = [coords(grid, 0), coords(grid, 1), coords(grid, 2)];
    let w2 = scene.region.window().powi(2);
    let mut out = Vec::with_capacity(grid.len());
    for &z in &c[2] {
        for &y in &c[1] {
            for &x in &c[0] {
                let r2 = match scene.region {
                    Region::Bulk { .. } => x * x + y * y + z * z,
                    Region::ThinSlab { .. } => x * x + y * y,
                };
                out.push((-0.5 * r2 / w2).exp());
            }
        }
    }
    let dv = grid.d[0] * grid.d[1] * grid.d[2];
    let v = out.iter().map(|w| w * w).sum::<f64>() * dv;
    (out, v)
}

// ------------------------------------------------------------------ the run

/// Per-run constants.
struct Plan {
    grid: VolumeGrid,
    window: Vec<f64>,
    /// `√` of the circulant spectrum of R.
    matter_amp: Vec<f64>,
    /// Light modes: flat index of `−q` and the weights `λ_q/N` of the channels xx, yy, xy.
    modes: Vec<(usize, [f64; 3])>,
    /// The x- and y-indices of `−q` over the modes (the pruned FFT's outputs).
    mode_xs: Vec<usize>,
    mode_ys: Vec<usize>,
    /// Per direction: the demodulation phases `e^{−i h_a x_a} d_a` per axis.
    phases: Vec<[Vec<C>; 3]>,
    /// `(k²/4π)²/V`.
    constant: f64,
}

fn plan(scene: &VolumeScene, grid: &VolumeGrid, exits: &[V3]) -> Plan {
    let light = &scene.light;
    let bulk = matches!(scene.region, Region::Bulk { .. });
    assert!(
        !bulk || light.sigma_zz.is_finite(),
        "a bulk region needs a finite σ_zz"
    );
    let (window, volume) = window(scene, grid);
    let matter = scene.matter;
    let matter_amp = circulant_spectrum(grid, &|r| matter.correlation(r))
        .into_iter()
        .map(f64::sqrt)
        .collect();
    // The light's channels, compensated for the window's autocorrelation exp(−|ξ|²/(4w_b²)).
    let comp = if grid.beam_compensation {
        0.5 / scene.region.window().powi(2)
    } else {
        0.0
    };
    let channels = if light.single_shape() { 1 } else { 3 };
    let spectra: Vec<Vec<f64>> = (0..channels)
        .map(|c| {
            let mut xi = light.precision(c);
            xi[0][0] -= comp;
            xi[1][1] -= comp;
            if bulk {
                xi[2][2] -= comp;
            }
            check_positive_definite(&xi, bulk);
            circulant_spectrum(grid, &|r| {
                let mut q = 0.0;
                for i in 0..3 {
                    for j in 0..3 {
                        q += r[i] * xi[i][j] * r[j];
                    }
                }
                (-0.5 * q).exp()
            })
        })
        .collect();
    let nn = grid.len();
    let lmax = spectra
        .iter()
        .flat_map(|s| s.iter().copied())
        .fold(0.0, f64::max);
    let [nx, ny, nz] = grid.n;
    let mut modes = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let i = (z * ny + y) * nx + x;
                let w: [f64; 3] = std::array::from_fn(|c| spectra[c.min(channels - 1)][i]);
                if w.iter().any(|&l| l > 1e-13 * lmax) {
                    let neg = (((nz - z) % nz) * ny + (ny - y) % ny) * nx + (nx - x) % nx;
                    modes.push((neg, w.map(|l| l / nn as f64)));
                }
            }
        }
    }
    let mut mode_xs: Vec<usize> = modes.iter().map(|m| m.0 % nx).collect();
    let mut mode_ys: Vec<usize> = modes.iter().map(|m| (m.0 / nx) % ny).collect();
    for v in [&mut mode_xs, &mut mode_ys] {
        v.sort_unstable();
        v.dedup();
    }
    let phases = demodulation(light, grid, exits);
    let born = light.k().powi(2) / (4.0 * PI);
    Plan {
        grid: *grid,
        window,
        matter_amp,
        modes,
        mode_xs,
        mode_ys,
        phases,
        constant: born * born / volume,
    }
}

/// Per exit r̂, the per-axis demodulation factors `e^{−i h_a x_a} d_a`, `h = k(r̂ − d̂)`, whose
/// product over the axes times the source gives the sum `G(h − q) = Σ f e^{−i(h − q)·r} d³r`.
///
/// # Panics
/// If an exit is not a unit vector.
fn demodulation(light: &Light, grid: &VolumeGrid, exits: &[V3]) -> Vec<[Vec<C>; 3]> {
    let (k, d) = (light.k(), light.travel());
    let c = [coords(grid, 0), coords(grid, 1), coords(grid, 2)];
    exits
        .iter()
        .map(|r| {
            assert!(
                (dot(*r, *r) - 1.0).abs() < 1e-12,
                "exit {r:?} not a unit vector"
            );
            let h: V3 = std::array::from_fn(|a| k * (r[a] - d[a]));
            std::array::from_fn(|a| {
                c[a].iter()
                    .map(|&x| C::from_polar(grid.d[a], -h[a] * x))
                    .collect()
            })
        })
        .collect()
}

/// Panics unless the light's precision (the sampled block: 3×3 in bulk, the tangent 2×2 block
/// for a slab) is positive definite after the beam compensation.
fn check_positive_definite(xi: &M3, bulk: bool) {
    let m2 = xi[0][0] * xi[1][1] - xi[0][1] * xi[1][0];
    let m3 = xi[0][0] * (xi[1][1] * xi[2][2] - xi[1][2] * xi[2][1])
        - xi[0][1] * (xi[1][0] * xi[2][2] - xi[1][2] * xi[2][0])
        + xi[0][2] * (xi[1][0] * xi[2][1] - xi[1][1] * xi[2][0]);
    assert!(
        xi[0][0] > 0.0 && m2 > 0.0 && (!bulk || m3 > 0.0),
        "the window is too small for the light's coherence: compensated precision {xi:?}"
    );
}

/// Scratch space of one worker thread.
struct Worker {
    fwd: Fft3,
    inv: Fft3,
    buf: Vec<C>,
}

impl Worker {
    fn new(p: &Plan) -> Self {
        Self {
            fwd: Fft3::new(p.grid.n, false),
            inv: Fft3::new(p.grid.n, true),
            buf: vec![C::new(0.0, 0.0); p.grid.len()],
        }
    }

    /// Two independent δε fields (real and imaginary parts of one complex field).
    fn fields(&mut self, p: &Plan, rng: &mut Rng) -> [Vec<f64>; 2] {
        for (b, a) in self.buf.iter_mut().zip(&p.matter_amp) {
            *b = rng.complex_normal() * *a;
        }
        self.inv.run(&mut self.buf);
        let s = 2f64.sqrt() / (p.grid.len() as f64).sqrt();
        [
            self.buf.iter().map(|c| c.re * s).collect(),
            self.buf.iter().map(|c| c.im * s).collect(),
        ]
    }

    /// The channel sums of every direction for the source `f = δε W` (real, on the grid).
    fn sums(&mut self, p: &Plan, f: &[f64]) -> Vec<ChannelSums> {
        let [nx, ny, _] = p.grid.n;
        p.phases
            .iter()
            .map(|[px, py, pz]| {
                for (z, pz) in pz.iter().enumerate() {
                    for (y, py) in py.iter().enumerate() {
                        let pyz = pz * py;
                        let row = (z * ny + y) * nx;
                        let out = &mut self.buf[row..row + nx];
                        for ((b, px), f) in out.iter_mut().zip(px).zip(&f[row..row + nx]) {
                            *b = pyz * px * *f;
                        }
                    }
                }
                self.fwd.run_pruned(&mut self.buf, &p.mode_xs, &p.mode_ys);
                let mut acc = [0.0; 3];
                for &(idx, w) in &p.modes {
                    let g2 = self.buf[idx].norm_sqr();
                    for c in 0..3 {
                        acc[c] += w[c] * g2;
                    }
                }
                acc.map(|a| a * p.constant)
            })
            .collect()
    }
}

/// Runs the brute force: `realizations` δε fields (seeded by `seed`, independent of the thread
/// count), `threads` workers, `progress` called once per finished realization.
///
/// # Panics
/// If an exit is not a unit vector or lies along ±ẑ, if a bulk region has unbounded `σ_zz`, or
/// if the window is too small for the beam compensation.
#[must_use]
pub fn run(
    scene: &VolumeScene,
    grid: &VolumeGrid,
    exits: &[V3],
    realizations: usize,
    seed: u64,
    threads: usize,
    progress: &(dyn Fn() + Sync),
) -> VolumeEstimate {
    for r in exits {
        let _ = exit_frame(*r);
    }
    let p = plan(scene, grid, exits);
    let items = realizations.div_ceil(2);
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<(usize, Vec<ChannelSums>)>> = Mutex::new(Vec::new());
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
                    let fields = w.fields(&p, &mut rng);
                    for (j, eps) in fields.iter().enumerate() {
                        let idx = 2 * item + j;
                        if idx >= realizations {
                            break;
                        }
                        let f: Vec<f64> = eps.iter().zip(&p.window).map(|(e, w)| e * w).collect();
                        let sums = w.sums(&p, &f);
                        results.lock().expect("poisoned").push((idx, sums));
                        progress();
                    }
                }
            });
        }
    });
    let mut results = results.into_inner().expect("poisoned");
    results.sort_by_key(|r| r.0);
    VolumeEstimate {
        exits: exits.to_vec(),
        sums: results.into_iter().map(|r| r.1).collect(),
        light_modes: p.modes.len(),
        light: scene.light,
    }
}

// ------------------------------------------------------------------ small vector algebra

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(a: V3) -> V3 {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

/// The unit vector at polar angle `theta` from ẑ and azimuth `phi`.
#[must_use]
pub fn direction(theta: f64, phi: f64) -> V3 {
    [
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    ]
}

/// The direction at scattering angle `psi` from d̂, turned by `azimuth` a about d̂:
/// `r̂ = cos ψ d̂ + sin ψ (cos a p̂ + sin a ŝ)` with (ŝ, p̂, d̂) the packet frame, so `a = 0` and
/// `a = π` stay in the plane of incidence.
#[must_use]
pub fn scattered(light: &Light, psi: f64, azimuth: f64) -> V3 {
    let [s, p, d] = light.packet_frame();
    let (sp, cp) = psi.sin_cos();
    let (sa, ca) = azimuth.sin_cos();
    std::array::from_fn(|i| cp * d[i] + sp * (ca * p[i] + sa * s[i]))
}

#[cfg(test)]
mod tests;
