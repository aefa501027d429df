//! `--energy`: the total reflected fraction of the phase-screen model at grazing incidence, by
//! brute force, beside the model's own analytic total and the kernel's, all summed over the same
//! grid of exit directions.
//!
//! # What is measured
//! ```text
//! fraction = ∫ L cos θ_o dω / cos θ_i = Σ_m cos θ_o |E(h_m)|² Δh² / (4π² |P| cos θ_i)
//!            (m over the propagating DFT directions, Δh = 2π/(N dx), |P| = Σ |A|² dx²)
//! ```
//! for a *coherent* Gaussian beam `A = exp(−|x|²/(2W²))` (`ψ ≡ 1`, so no light average is
//! needed) on a lossless Gaussian surface (`R = σ² exp(−r²/(2ℓ²))`), `E` as in `brute.rs` with
//! the exact direction dependence of `v = k (cos θ_i + cos θ_o)` (Taylor series, one FFT per
//! term). The sum over DFT orders is the exact power balance of the periodic problem.
//!
//! Beside it, on the same directions:
//! - *smooth*: the same with `h ≡ 0` — what a mirror reflects of this finite beam (the beam's
//!   angular spread makes `⟨cos θ_o⟩ ≠ cos θ_i` near grazing; the incident power on the surface is
//!   the same `⟨cos θ⟩`, so `fraction / smooth` is the beam-independent reflected fraction);
//! - *model, all orders*: `⟨|E|²⟩/|P| = Σ_n α (v²σ²)ⁿ/n! · 2π s_n² exp(−|h|² s_n²/2)`,
//!   `1/s_n² = 1/(2W²) + n/ℓ²` (the beam's autocorrelation `exp(−|ξ|²/(4W²))` times
//!   `exp(−v²(σ² − R))` expanded in `R`, Fourier transformed term by term);
//! - *model, first order*: the same with `n ≤ 1` — the model the kernel implements;
//! - *kernel*: `Kernel::<Intensity, Partial, ClosedForm>` + `PhaseScreen` with the packet shape
//!   `Θ = 2W² diag(1, cos²θ_i)`, whose surface section is the beam's `Ξ = I/(2W²)`, so that its
//!   specular lobe and blur are those of this beam: `Σ_m L Δh² / (k² cos θ_i)`.
//!
//! The brute force uses no gmueller code and no formula of the model beyond its definition; the
//! standard error is the sample standard deviation over height realizations divided by √K.

use std::f64::consts::{PI, TAU};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use rustfft::num_complex::Complex64 as C;

use gmueller_validation::brute::{self, Fft2, Grid, Matter, Rng, Scene};
use gmueller_validation::kernel_side;

/// The propagating directions of the DFT grid.
struct Dirs {
    /// Row-major grid index.
    idx: Vec<usize>,
    /// `h_t` (rad/µm).
    h: Vec<[f64; 2]>,
    /// `cos θ_o`.
    cos_o: Vec<f64>,
    /// `v = k (cos θ_i + cos θ_o)`.
    v: Vec<f64>,
    /// `Δh² / (4π² |P| cos θ_i)`.
    norm: f64,
}

fn directions(scene: &Scene, grid: &Grid, area: f64) -> Dirs {
    let n = grid.n;
    let dh = grid.dh();
    let (k, cos_i) = (scene.k(), scene.theta_i.cos());
    let mut d = Dirs {
        idx: Vec::new(),
        h: Vec::new(),
        cos_o: Vec::new(),
        v: Vec::new(),
        norm: dh * dh / (4.0 * PI * PI * area * cos_i),
    };
    for iy in 0..n {
        for ix in 0..n {
            let h = [
                brute::signed(ix, n) as f64 * dh,
                brute::signed(iy, n) as f64 * dh,
            ];
            if let Some(r) = scene.exit_for(h) {
                d.idx.push(iy * n + ix);
                d.h.push(h);
                d.cos_o.push(r[2]);
                d.v.push(k * (cos_i + r[2]));
            }
        }
    }
    d
}

/// A brute-force total: mean over realizations and its standard error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Total {
    /// Mean reflected fraction.
    pub mean: f64,
    /// Standard error of the mean.
    pub std_err: f64,
    /// Height realizations K.
    pub realizations: usize,
    /// Taylor terms in `v`.
    pub terms: usize,
}

/// The brute-force reflected fraction of a coherent beam (see the module docs).
///
/// # Panics
/// Unless the matter is a random field (Gaussian or exponential).
#[must_use]
pub fn brute_total(
    scene: &Scene,
    grid: &Grid,
    realizations: usize,
    seed: u64,
    threads: usize,
) -> Total {
    let (n, dx) = (grid.n, grid.dx);
    let nn = n * n;
    let (beam, area) = brute::beam_envelope(grid);
    let dirs = directions(scene, grid, area);
    let amp = brute::height_amplitudes(&mut Fft2::new(n, false), &scene.matter, dx)
        .expect("a random height field");
    let vmin = dirs.v.iter().copied().fold(f64::INFINITY, f64::min);
    let vmax = dirs.v.iter().copied().fold(0.0, f64::max);
    let v0 = 0.5 * (vmin + vmax);
    // Terms until (Δv_max · 7σ)ⁿ/n! < 1e-13.
    let x = 0.5 * (vmax - vmin) * 7.0 * scene.matter.rms();
    let (mut terms, mut term) = (1usize, 1.0);
    while terms < 60 && term >= 1e-13 {
        term *= x / terms as f64;
        terms += 1;
    }
    let items = realizations.div_ceil(2);
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<(usize, f64)>> = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| {
                let mut fwd = Fft2::new(n, false);
                let mut inv = Fft2::new(n, true);
                let mut buf = vec![C::new(0.0, 0.0); nn];
                let mut u = vec![C::new(0.0, 0.0); nn];
                let mut acc = vec![C::new(0.0, 0.0); dirs.idx.len()];
                let mut coef = vec![C::new(0.0, 0.0); dirs.idx.len()];
                loop {
                    let item = next.fetch_add(1, Ordering::Relaxed);
                    if item >= items {
                        break;
                    }
                    let mut rng = Rng::new(seed, item as u64);
                    let (a, b) = brute::random_heights(&mut inv, &mut buf, &amp, &mut rng);
                    for (j, h) in [a, b].iter().enumerate() {
                        let idx = 2 * item + j;
                        if idx >= realizations {
                            break;
                        }
                        for ((u, &a), &z) in u.iter_mut().zip(&beam).zip(h) {
                            *u = C::from_polar(a * dx * dx, -v0 * z);
                        }
                        acc.fill(C::new(0.0, 0.0));
                        coef.fill(C::new(1.0, 0.0));
                        for t in 0..terms {
                            // buf = A e^{−i v₀ h} hᵗ dx²; coef = (−i (v − v₀))ᵗ / t!.
                            buf.copy_from_slice(&u);
                            for (u, &z) in u.iter_mut().zip(h) {
                                *u *= z;
                            }
                            fwd.run(&mut buf);
                            let step = 1.0 / (t + 1) as f64;
                            for (j, &i) in dirs.idx.iter().enumerate() {
                                acc[j] += coef[j] * buf[i];
                                coef[j] *= C::new(0.0, -(dirs.v[j] - v0) * step);
                            }
                        }
                        let f: f64 = acc
                            .iter()
                            .zip(&dirs.cos_o)
                            .map(|(e, c)| c * e.norm_sqr())
                            .sum::<f64>()
                            * dirs.norm;
                        results.lock().expect("poisoned").push((idx, f));
                    }
                }
            });
        }
    });
    let mut r = results.into_inner().expect("poisoned");
    r.sort_by_key(|x| x.0);
    let k = r.len() as f64;
    let mean = r.iter().map(|x| x.1).sum::<f64>() / k;
    let var = r.iter().map(|x| (x.1 - mean).powi(2)).sum::<f64>() / (k - 1.0).max(1.0);
    Total {
        mean,
        std_err: (var / k).sqrt(),
        realizations: r.len(),
        terms,
    }
}

/// What a mirror (`h ≡ 0`) reflects of the beam, summed over the same directions.
#[must_use]
pub fn smooth_total(scene: &Scene, grid: &Grid) -> f64 {
    let (beam, area) = brute::beam_envelope(grid);
    let dirs = directions(scene, grid, area);
    let dx2 = grid.dx * grid.dx;
    let mut buf: Vec<C> = beam.iter().map(|a| C::new(a * dx2, 0.0)).collect();
    Fft2::new(grid.n, false).run(&mut buf);
    dirs.idx
        .iter()
        .zip(&dirs.cos_o)
        .map(|(&i, c)| c * buf[i].norm_sqr())
        .sum::<f64>()
        * dirs.norm
}

/// The model's analytic ensemble total for this beam, orders `0..=max_order` of `exp(v² R)`.
///
/// # Panics
/// Unless the matter is Gaussian.
#[must_use]
pub fn model_total(scene: &Scene, grid: &Grid, max_order: usize) -> f64 {
    let Matter::Gaussian { sigma, ell } = scene.matter else {
        panic!("the analytic total is for the Gaussian surface");
    };
    let (_, area) = brute::beam_envelope(grid);
    let dirs = directions(scene, grid, area);
    let w2 = grid.beam_width * grid.beam_width;
    let mut total = 0.0;
    for j in 0..dirs.idx.len() {
        let (h, v) = (dirs.h[j], dirs.v[j]);
        let h2 = h[0] * h[0] + h[1] * h[1];
        let g = (v * sigma).powi(2);
        let mut series = 0.0;
        let mut coeff = (-g).exp(); // α (v²σ²)ⁿ / n!
        for order in 0..=max_order {
            let s2 = 1.0 / (1.0 / (2.0 * w2) + order as f64 / (ell * ell));
            series += coeff * TAU * s2 * (-0.5 * h2 * s2).exp();
            coeff *= g / (order + 1) as f64;
        }
        total += dirs.cos_o[j] * area * series;
    }
    total * dirs.norm
}

/// The packet shape whose surface section is the beam's autocorrelation, `Ξ = I/(2W²)`.
fn beam_shape(scene: &Scene, grid: &Grid) -> Scene {
    let w2 = 2.0 * grid.beam_width * grid.beam_width;
    let c2 = scene.theta_i.cos().powi(2);
    let s = Scene {
        theta: [[w2, 0.0], [0.0, w2 * c2]],
        ..*scene
    };
    let xi = s.surface_precision();
    assert!(
        (xi[0][0] * w2 - 1.0).abs() < 1e-9
            && (xi[1][1] * w2 - 1.0).abs() < 1e-9
            && xi[0][1].abs() * w2 < 1e-9,
        "surface section {xi:?} is not I/(2W²)"
    );
    s
}

/// The kernel's reflected fraction for this beam, summed over the same directions.
#[must_use]
pub fn kernel_total(scene: &Scene, grid: &Grid) -> f64 {
    let (_, area) = brute::beam_envelope(grid);
    let dirs = directions(scene, grid, area);
    let ks = beam_shape(scene, grid);
    let exits: Vec<[f64; 3]> = dirs
        .h
        .iter()
        .map(|h| scene.exit_for(*h).expect("propagating"))
        .collect();
    let dh = grid.dh();
    let sum: f64 = kernel_side::predict(&ks, &exits)
        .iter()
        .map(kernel_side::Prediction::total)
        .sum();
    sum * dh * dh / (scene.k().powi(2) * scene.theta_i.cos())
}

/// One energy case.
struct Case {
    theta_i_deg: f64,
    k_sigma: f64,
    beam_width: f64,
    dx: f64,
    realizations: usize,
}

/// Runs the energy cases and prints the table.
pub fn run(realizations: Option<usize>, quick: bool, threads: usize, seed: u64) {
    let (lambda, ell) = (0.5, 1.0);
    let k = TAU / lambda;
    let scale = |r: usize| {
        let r = realizations.unwrap_or(r);
        if quick { (r / 4).max(4) } else { r }
    };
    let mut cases = Vec::new();
    for (ti, w, dx, r) in [(75.0, 40.0, 0.25, 128), (85.0, 100.0, 0.5, 128)] {
        for ks in [0.1, 0.2, 0.3] {
            cases.push(Case {
                theta_i_deg: ti,
                k_sigma: ks,
                beam_width: w,
                dx,
                realizations: scale(r),
            });
        }
    }
    println!(
        "gmueller wave tracer — energy of the lossless phase screen (λ = 0.5 µm, ℓ = 1 µm, coherent Gaussian beam, box 8W)"
    );
    println!(
        "{:>4} {:>4} {:>6} {:>9} | {:>5} {:>5} {:>4} {:>3} {:>2} | {:>21} {:>9} {:>9} {:>9} {:>9} | {:>21} {:>9} {:>6}",
        "θi",
        "kσ",
        "v_sσ",
        "1 − α",
        "W µm",
        "N",
        "dx",
        "K",
        "T",
        "brute ± s.e.",
        "smooth",
        "model ∞",
        "model 1",
        "kernel",
        "brute/smooth ± s.e.",
        "∞/smooth",
        "z"
    );
    for c in &cases {
        let t0 = Instant::now();
        let ti = c.theta_i_deg.to_radians();
        let scene = Scene {
            wavelength: lambda,
            theta_i: ti,
            theta: [[1.0, 0.0], [0.0, 1.0]],
            matter: Matter::Gaussian {
                sigma: c.k_sigma / k,
                ell,
            },
            eta_t: None,
        };
        let n = brute::fast_size((8.0 * c.beam_width / c.dx).ceil() as usize);
        let grid = Grid {
            n,
            dx: c.dx,
            beam_width: c.beam_width,
            beam_compensation: false,
        };
        let vs = scene.v_sigma_specular();
        let b = brute_total(&scene, &grid, c.realizations, seed, threads);
        let smooth = smooth_total(&scene, &grid);
        // The analytic n = 0 term of a smooth surface must reproduce the FFT mirror (to the
        // box truncation of the beam, ~3e-7).
        let mirror = Scene {
            matter: Matter::Gaussian { sigma: 0.0, ell },
            ..scene
        };
        let smooth_model = model_total(&mirror, &grid, 0);
        assert!(
            (smooth_model / smooth - 1.0).abs() < 1e-6,
            "smooth: FFT {smooth} vs analytic {smooth_model}"
        );
        let all = model_total(&scene, &grid, 12);
        let first = model_total(&scene, &grid, 1);
        let kern = kernel_total(&scene, &grid);
        println!(
            "{:>4} {:>4} {:>6.4} {:>9.3e} | {:>5} {:>5} {:>4} {:>3} {:>2} | {:>10.6} ± {:>8.6} {:>9.6} {:>9.6} {:>9.6} {:>9.6} | {:>10.6} ± {:>8.6} {:>9.6} {:>+6.2}   ({:.0} s)",
            c.theta_i_deg,
            c.k_sigma,
            vs,
            1.0 - (-vs * vs).exp(),
            c.beam_width,
            n,
            c.dx,
            b.realizations,
            b.terms,
            b.mean,
            b.std_err,
            smooth,
            all,
            first,
            kern,
            b.mean / smooth,
            b.std_err / smooth,
            all / smooth,
            (b.mean - all) / b.std_err,
            t0.elapsed().as_secs_f64()
        );
    }
    println!(
        "columns: brute = Σ cos θ_o |E|² over the propagating DFT directions (module docs of energy.rs); smooth = the same for h ≡ 0;\n\
         model ∞ / model 1 = the model's analytic ensemble total on the same directions (all orders / first order);\n\
         kernel = the Intensity kernel (PhaseScreen, Partial, Θ matched to the beam) on the same directions; z = (brute − model ∞)/s.e."
    );
}
