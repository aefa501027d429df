//! The brute-force reference: scalar Kirchhoff phase-screen reflection (and transmission, see
//! below) of a partially coherent Gaussian Schell-model beam by random surfaces, summed
//! explicitly on a grid and averaged over realizations. Uses no gmueller code (only `rustfft`
//! and `std`), so that it can serve as an independent reference for the kernel.
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
//!
//! # Transmission ([`Scene::eta_t`] = `Some(η)`)
//! The surface is then the interface between the light's medium above (index `n_i`, where n̂
//! points) and a medium below (index `n_t`, `η = n_t/n_i`); `λ` and `k = 2π/λ = n_i k₀` stay the
//! packet's, in the medium of incidence, and the medium below has `k_t = η k`, `λ_t = λ/η`.
//! ```text
//! aperture  a(x) = E_in(x) e^{−i v h(x)}   on the mean plane z = 0, in medium t   (t = 1)
//! v         = k (cos θ_i − η cos θ_o) = k₀ (n_i cos θ_i − n_t cos θ_o)   (θ_o from −n̂, < 0 for η > 1 near Snell)
//! E(r̂)      = ∫ A ψ e^{−i v h} e^{−i h_t·x} d²x,       h_t = k_t r̂_t − k d_t  (0 at Snell's direction)
//! dP/dΩ     = (n_t/n_i) cos²θ_o / λ_t² · |E|²,          L = ⟨dP/dΩ⟩ / (|P| cos θ_o)   (radiance in medium t)
//! exits     h_t = 2π m/(N dx):  r̂_t = (h_t + k d_t)/k_t,  r̂_z = −√(1 − |r̂_t|²)
//! ```
//! Derivation, from first principles (scalar field, non-magnetic media, `e^{−iωt}`):
//! - **Phase screen.** Locally the interface at height `z = h` meets a plane wave
//!   `e^{i k (d_t·x − cos θ_i z)}` of the incident field; the transmitted wave of direction r̂
//!   (`r̂_z = −cos θ_o`, tangentially matched, `k_t r̂_t = k d_t`) leaves the point `(x', h)` with
//!   the incident phase and travels `h/cos θ_o` in medium t to reach the mean plane at
//!   `x = x' + r̂_t h/cos θ_o`. Its phase there is
//!   `k d_t·x' − k cos θ_i h + k_t h/cos θ_o = k d_t·x + h (k_t cos θ_o − k cos θ_i) = k d_t·x − v h`
//!   (using `k d_t·r̂_t = k_t |r̂_t|²`): the aperture field is the incident one times `e^{−i v h}`,
//!   the sign convention of this module in both cases (reflection: `v = k (cos θ_i + cos θ_o)`,
//!   the path `h cos θ_i` less on the way in and out). Only `v²` enters the average: the height
//!   statistics are symmetric (`h → −h`), and `⟨e^{−ivh}⟩ = e^{−v²σ²/2}` for Gaussian heights
//!   (the transmitted Debye–Waller factor `α_t = e^{−(vσ)²}` of the coherent part).
//! - **Far field in a medium.** The field below the plane is the angular spectrum of `a`,
//!   `U(x, z) = ∫ â(q) e^{i q·x − i √(k_t² − q²) z} d²q`, `â(q) = (2π)⁻² ∫ a e^{−i q·x} d²x`
//!   (`z < 0`, outgoing). Stationary phase at `R → ∞` along r̂ gives exactly
//!   `U ≈ −2πi k_t cos θ_o â(k_t r̂_t) e^{i k_t R}/R` (the Rayleigh–Sommerfeld far field), so
//!   `R² |U|² = k_t² cos²θ_o/(2π)² |∫ a e^{−i k_t r̂_t·x} d²x|² = cos²θ_o/λ_t² |E(r̂)|²`; the
//!   incident carrier `e^{i k d_t·x}` is absorbed in `h_t`.
//! - **Intensity in a medium.** The time-averaged Poynting flux of a (locally plane) wave of
//!   amplitude `U` in a medium of index n is `n |U|²/(2 Z₀)`: the power per solid angle is
//!   `n_t R² |U|²/(2 Z₀)`, and the incident irradiance across the beam is `n_i |A(0)|²/(2 Z₀)`
//!   (`= n_i/(2 Z₀)`, since `|A(0)|² = 1`). Per unit incident irradiance this is the line
//!   `dP/dΩ` above; `n_t = n_i` gives the reflection formula.
//! - **Radiance.** The lit patch of area `|P|` radiates `dP/dΩ = L cos θ_o |P|`, as in reflection;
//!   `L` is the radiance in medium t (it carries the `n²` law: a flat interface at normal
//!   incidence gives `L ∝ η · η²`, `η` from the aperture model's power and `η²` from the solid
//!   angle compressed by refraction).
//! - **Check: a flat interface** (`h = 0`, coherent light, a beam wide against λ). The incident
//!   power through the surface is `cos θ_i |P|`. With `dΩ = d²r̂_t/cos θ_o = d²h_t/(k_t² cos θ_o)`
//!   and Parseval, `∫ |E|² d²h_t = (2π)² |P|`, the transmitted power is
//!   `∫ η cos θ_o/(λ_t² k_t²) |E|² d²h_t = η cos θ_t |P|`: the fraction `η cos θ_t/cos θ_i`, the
//!   Fresnel transmittance `(n_t cos θ_t/n_i cos θ_i) |t|²` with `t = 1`
//!   (`tests::flat_interface_transmits_eta_cos_t_over_cos_i` sums it over the DFT directions).
//!
//! The numerics are those of reflection with `v`, the exit directions and the prefactor
//! `(n_t/n_i) cos θ_o/λ_t²` of the transmitted side; the section of the coherence by the surface
//! (the footprint) is the same. Reflection results are unchanged, bit for bit.

#![allow(dead_code)]

use std::f64::consts::TAU;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use gmueller::verify::rng::SplitMix64;
use rustfft::num_complex::Complex64 as C;
use rustfft::{Fft, FftPlanner};

/// A small deterministic generator (the kit's `SplitMix64`, one stream per work item), so
/// results do not depend on thread timing.
#[derive(Debug, Clone)]
pub struct Rng(SplitMix64);

impl Rng {
    /// A generator for stream `stream` of run `seed`.
    #[must_use]
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self(SplitMix64(
            seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03),
        ));
        r.next_u64();
        r
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
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
    /// `None`: the surface is a perfect reflector and the light leaves above it (reflection).
    /// `Some(η)`: the surface is the interface to a medium below of relative index
    /// `η = n_t/n_i` (`n_i` that of the light's medium above), the aperture field is the incident
    /// field times the phase screen (`t = 1`), and the light leaves below it (transmission, see
    /// the module docs). `wavelength` is the one in the medium of incidence either way.
    pub eta_t: Option<f64>,
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

/// The inverse of a 2×2 matrix, by its adjugate.
#[must_use]
pub fn inverse2(t: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let det = t[0][0] * t[1][1] - t[0][1] * t[1][0];
    [
        [t[1][1] / det, -t[0][1] / det],
        [-t[1][0] / det, t[0][0] / det],
    ]
}

/// `Aᵀ M A` for the 2×N matrix `A` with rows `rows` (`(Aᵀ M A)_ij = Σ_pq A_pi M_pq A_qj`): the
/// precision `M` of packet-frame coordinates seen in the N coordinates `A` maps from.
#[must_use]
pub fn sandwich<const N: usize>(rows: [[f64; N]; 2], m: [[f64; 2]; 2]) -> [[f64; N]; N] {
    let mut out = [[0.0; N]; N];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            for p in 0..2 {
                for q in 0..2 {
                    *v += rows[p][i] * m[p][q] * rows[q][j];
                }
            }
        }
    }
    out
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
        sandwich(
            [[f[0][0], f[0][1]], [f[1][0], f[1][1]]],
            inverse2(self.theta),
        )
    }

    /// The exit direction r̂ whose `h_t` is `h`, or `None` beyond the horizon: in reflection
    /// `h_t = k(r̂_t − d_t)` and `r̂_z > 0`; in transmission `h_t = η k r̂_t − k d_t` and `r̂_z < 0`.
    #[must_use]
    pub fn exit_for(&self, h: [f64; 2]) -> Option<[f64; 3]> {
        let d = self.travel();
        let k = self.k();
        match self.eta_t {
            None => {
                let rt = [d[0] + h[0] / k, d[1] + h[1] / k];
                let s2 = rt[0] * rt[0] + rt[1] * rt[1];
                (s2 < 1.0).then(|| [rt[0], rt[1], (1.0 - s2).sqrt()])
            }
            Some(eta) => {
                let kt = eta * k;
                let rt = [(h[0] + k * d[0]) / kt, (h[1] + k * d[1]) / kt];
                let s2 = rt[0] * rt[0] + rt[1] * rt[1];
                (s2 < 1.0).then(|| [rt[0], rt[1], -(1.0 - s2).sqrt()])
            }
        }
    }

    /// The phase factor `v` for an exit direction with `cos θ_o = |r̂_z|`: `k (cos θ_i + cos θ_o)`
    /// in reflection, `k (cos θ_i − η cos θ_o)` in transmission (module docs).
    #[must_use]
    pub fn phase_factor(&self, cos_o: f64) -> f64 {
        let (k, cos_i) = (self.k(), self.theta_i.cos());
        match self.eta_t {
            None => k * (cos_i + cos_o),
            Some(eta) => k * (cos_i - eta * cos_o),
        }
    }

    /// The specular direction of the exit side: the mirror direction, or Snell's (`h_t = 0`;
    /// `None` under total internal reflection).
    #[must_use]
    pub fn specular_exit(&self) -> Option<[f64; 3]> {
        self.exit_for([0.0, 0.0])
    }

    /// `|v| σ` at the specular direction (the phase-screen roughness parameter): `2kσ cos θ_i`
    /// in reflection, `kσ |cos θ_i − η cos θ_t|` in transmission (`cos θ_t = 0` beyond the
    /// critical angle).
    #[must_use]
    pub fn v_sigma_specular(&self) -> f64 {
        match self.eta_t {
            None => 2.0 * self.k() * self.theta_i.cos() * self.matter.rms(),
            Some(_) => {
                let cos_t = self.specular_exit().map_or(0.0, |r| -r[2]);
                self.phase_factor(cos_t).abs() * self.matter.rms()
            }
        }
    }

    /// The radiance prefactor `(n_t/n_i) cos θ_o/λ_t²` of the exit side (`cos θ_o/λ²` in
    /// reflection; module docs).
    #[must_use]
    pub fn radiance_prefactor(&self, cos_o: f64) -> f64 {
        let lambda = self.wavelength;
        match self.eta_t {
            None => cos_o / (lambda * lambda),
            Some(eta) => {
                let lambda_t = lambda / eta;
                eta * cos_o / (lambda_t * lambda_t)
            }
        }
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
    /// Per direction: DFT index `(m_x, m_y)`, Taylor coefficients `(−iΔv)ⁿ/n!`, the radiance
    /// prefactor over `|P|` (`cos θ_o/λ²/|P|` in reflection).
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
    let dh = grid.dh();
    let geo: Vec<(f64, f64)> = dirs
        .iter()
        .map(|m| {
            let r = scene
                .exit_for([m[0] as f64 * dh, m[1] as f64 * dh])
                .expect("exit direction beyond the horizon");
            // cos θ_o = |r̂_z| (r̂_z > 0 in reflection, so this is r̂_z there, as before).
            let cos_o = r[2].abs();
            (cos_o, scene.phase_factor(cos_o))
        })
        .collect();
    // v < 0 is possible in transmission (η > 1); in reflection v > 0 and these are the
    // previous bounds.
    let vmin = geo.iter().map(|g| g.1).fold(f64::INFINITY, f64::min);
    let vmax = geo.iter().map(|g| g.1).fold(f64::NEG_INFINITY, f64::max);
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
            (*m, c, scene.radiance_prefactor(cos_o) / area)
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
/// If a direction is beyond the horizon of the exit side or, for the grating, the box is not a
/// whole number of periods.
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The power a flat surface sends into the exit side, per unit incident power, summed over
    /// the DFT directions within 0.6 rad/µm of the specular one (10 lobe widths): with
    /// `L = dP/dΩ/(|P| cos θ_o)` and `dΩ = d²h_t/(k_o² cos θ_o)` (`k_o` the exit medium's
    /// wavenumber), `dP = L |P| d²h_t/k_o²`, over the incident power `cos θ_i |P|`. Nearly
    /// coherent light (w = 20 µm): the lobe is 0.06 rad/µm wide, so `cos θ_o` is `cos θ_t`
    /// across it to ~5e-5 (the curvature of `cos θ_o` grows toward grazing exits: 2.5e-4 at
    /// 61°, from the glass at 35°).
    fn flat_fraction(eta_t: Option<f64>, theta_i_deg: f64) -> f64 {
        let scene = Scene {
            wavelength: 0.5,
            theta_i: theta_i_deg.to_radians(),
            theta: [[400.0, 30.0], [30.0, 400.0]],
            matter: Matter::Gaussian {
                sigma: 0.0,
                ell: 4.0,
            },
            eta_t,
        };
        let grid = auto_grid(&scene, 2.0, 1.5);
        let dh = grid.dh();
        let reach = (0.6 / dh).ceil() as i64;
        let dirs: Vec<[i64; 2]> = (-reach..=reach)
            .flat_map(|my| (-reach..=reach).map(move |mx| [mx, my]))
            .collect();
        let est = run(&scene, &grid, &dirs, 1, 1, 2, &|| {});
        assert!(
            est.std_err.iter().all(|&s| s == 0.0),
            "a flat surface is not random"
        );
        let k_o = scene.k() * eta_t.unwrap_or(1.0);
        est.mean.iter().sum::<f64>() * dh * dh / (k_o * k_o) / scene.theta_i.cos()
    }

    #[test]
    fn flat_mirror_reflects_everything() {
        for theta_i in [0.0, 30.0, 60.0] {
            let f = flat_fraction(None, theta_i);
            println!("mirror, θ_i = {theta_i}°: {f:.7} ({:+.1e})", f - 1.0);
            assert!((f - 1.0).abs() < 1e-4, "θ_i = {theta_i}°: reflected {f}");
        }
    }

    /// The aperture model (`t = 1`) transmits `η cos θ_t/cos θ_i` (module docs): from the air
    /// into glass and from glass into the air (below the critical angle, 41.8°; the exit at
    /// 48.6° from the glass at 30°).
    #[test]
    fn flat_interface_transmits_eta_cos_t_over_cos_i() {
        for (eta, theta_i) in [
            (1.5, 0.0),
            (1.5, 30.0),
            (1.5, 70.0),
            (1.0 / 1.5, 20.0),
            (1.0 / 1.5, 30.0),
        ] {
            let f = flat_fraction(Some(eta), theta_i);
            let sin_t = theta_i.to_radians().sin() / eta;
            let want = eta * (1.0 - sin_t * sin_t).sqrt() / theta_i.to_radians().cos();
            println!(
                "η = {eta:.4}, θ_i = {theta_i}°: {f:.7} vs {want:.7} ({:+.1e})",
                f / want - 1.0
            );
            assert!(
                (f / want - 1.0).abs() < 1e-4,
                "η = {eta}, θ_i = {theta_i}°: transmitted {f}, expected {want}"
            );
        }
    }

    /// The sign convention, `e^{−i v h}` with `v = k (cos θ_i − η cos θ_o)` (`k (cos θ_i + cos θ_o)`
    /// in reflection), against Snell's law and the mirror law at a tilted facet: the screen of a
    /// planar surface `h = s·x` is the plane wave `e^{−i v s·x}`, which moves the lobe to
    /// `h_t = −v s`; the exactly refracted (reflected) direction at the facet of normal
    /// `(−s, 1)/√(1 + s²)` must have that `h_t` to first order in the slope `s`. Slopes along
    /// t̂₁ and t̂₂, several angles, both sides of the glass, and reflection.
    #[test]
    fn phase_screen_sign_matches_snell_at_a_tilted_facet() {
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for eta_t in [None, Some(1.5), Some(1.0 / 1.5)] {
            for theta_i in [0.0, 20.0, 35.0] {
                for slope in [[1e-5, 0.0], [0.0, 1e-5], [-7e-6, 4e-6]] {
                    let scene = Scene {
                        wavelength: 0.5,
                        theta_i: f64::to_radians(theta_i),
                        theta: [[1.0, 0.0], [0.0, 1.0]],
                        matter: Matter::Gaussian {
                            sigma: 0.0,
                            ell: 1.0,
                        },
                        eta_t,
                    };
                    let d = scene.travel();
                    let m = unit([-slope[0], -slope[1], 1.0]);
                    let c_i = -dot(d, m);
                    let eta = eta_t.unwrap_or(1.0);
                    // Exact exit direction at the facet: the mirror law, or Snell's (vector form).
                    let r = match eta_t {
                        None => [0, 1, 2].map(|j| d[j] + 2.0 * c_i * m[j]),
                        Some(eta) => {
                            let c_t = (1.0 - (1.0 - c_i * c_i) / (eta * eta)).sqrt();
                            [0, 1, 2].map(|j| d[j] / eta + (c_i / eta - c_t) * m[j])
                        }
                    };
                    let k = scene.k();
                    let h = [0, 1].map(|j| k * (eta * r[j] - d[j]));
                    let cos_o = scene.specular_exit().expect("no total reflection")[2].abs();
                    let v = scene.phase_factor(cos_o);
                    for j in 0..2 {
                        let want = -v * slope[j];
                        assert!(
                            (h[j] - want).abs() < 1e-4 * v.abs() * 1e-5,
                            "{eta_t:?}, θ_i = {theta_i}°, slope {slope:?}: h_t[{j}] = {:e}, −v s = {want:e}",
                            h[j]
                        );
                    }
                }
            }
        }
    }
}
