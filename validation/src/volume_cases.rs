//! The volumetric configurations of the wave tracer and their comparison with the kernel's
//! prediction: the brute force ([`crate::brute_volume`]) against
//! [`crate::kernel_side_volume::predict`], direction by direction and for several incident
//! polarizations, with the acceptance (within 3 standard errors or 2 %) and wrong
//! predictions that the same comparison must reject.
//!
//! The configurations (λ = 0.5 µm, δε with σ = 0.01, Gaussian with ℓ = 0.1 µm unless stated):
//! - `volume_cube`: a bulk region (Gaussian window `w_b = 0.6 µm`), `θ_i = 30°`, anisotropic GSM
//!   light with `θ_x ≠ θ_y` (so the three light channels differ) and `σ_zz = 0.2 µm`; exits
//!   from 15° to 165° of scattering angle, in the plane of incidence on both sides and out of
//!   it; unpolarized, x̂, ŷ and partially 45°-linear and circular input (at 95 % of the
//!   Bochner bound). Wrong predictions: the opposite S3 handedness, S2 mirrored.
//! - `volume_backscatter`: a bulk region, `σ_zz = 0.15 µm`: at and around the backscatter
//!   direction `h = 2kŝ` lies along the packet's axis, where `σ_zz` blurs the PSD; the
//!   prediction with `σ_zz → ∞` (10³ µm) must be rejected there.
//! - `volume_exponential`: a second R, exponential (`R = σ² e^{−r/ℓ}`, ℓ = 0.15 µm, the 3-D
//!   K-correlation with γ = 3; the kernel blurs its Gaussian-mixture fit); a Gaussian R of the
//!   same σ and ℓ must be rejected.
//! - `volume_thin_slab`: one layer of thickness 5 nm, δε fully correlated across it
//!   (the thin-slab limit), `θ_i` = 40°, `θ_x ≠ θ_y`, `σ_zz = 0.25 µm` (which enters the section
//!   of the coherence by the slab); exits above and below. The prediction is the 2-D surface
//!   term `surface_coherence_term` times t (`kernel_side_volume`, "Thin slab"); with
//!   `σ_zz → ∞` it must be rejected.

use crate::brute_volume::{
    self, Light, Permittivity, Region, StokesEstimate, V3, VolumeEstimate, VolumeGrid, VolumeScene,
    dop, scattered,
};
use crate::kernel_side_volume::predict;

/// How large a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Size {
    /// The main job's default.
    Full,
    /// `--quick`: a quarter of the realizations.
    Quick,
    /// The validation test: smaller windows, fewer directions and realizations.
    Test,
}

/// A wrong prediction the comparison must reject.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Wrong {
    /// The kernel with the given scene change: `σ_zz` replaced.
    SigmaZz(f64),
    /// S3 of the prediction negated (the opposite circular handedness).
    FlipS3,
    /// S2 of the prediction negated (a mirrored frame).
    FlipS2,
    /// The kernel with a Gaussian R of the same variance and ℓ (the wrong PSD shape).
    GaussianR,
}

impl Wrong {
    /// A short description.
    #[must_use]
    pub fn name(&self) -> String {
        match *self {
            Self::SigmaZz(s) => format!("σ_zz → {s:.0e} µm (∞)"),
            Self::FlipS3 => "S3 negated (handedness)".into(),
            Self::FlipS2 => "S2 negated (mirrored frame)".into(),
            Self::GaussianR => "Gaussian R of the same σ, ℓ".into(),
        }
    }
}

/// One volumetric configuration.
#[derive(Debug, Clone)]
pub struct Case {
    /// Short name (`--only`).
    pub name: &'static str,
    /// One-line description.
    pub title: String,
    /// The scene.
    pub scene: VolumeScene,
    /// Its grid.
    pub grid: VolumeGrid,
    /// Exit directions: (scattering angle ψ, azimuth a about d̂) in degrees, and r̂.
    pub exits: Vec<([f64; 2], V3)>,
    /// Incident Stokes vectors (packet frame), named.
    pub inputs: Vec<(&'static str, [f64; 4])>,
    /// Matter realizations.
    pub realizations: usize,
    /// Wrong predictions that must be rejected somewhere.
    pub wrong: Vec<Wrong>,
}

const LAMBDA: f64 = 0.5;
const MATTER: Permittivity = Permittivity::Gaussian {
    sigma: 0.01,
    ell: 0.1,
};

fn det(t: [[f64; 2]; 2]) -> f64 {
    t[0][0] * t[1][1] - t[0][1] * t[1][0]
}

/// Unpolarized, x̂, ŷ, and ±45° / circular at `frac` of the Bochner bound (`S1 = 0`, so
/// `|μ|² = S2² + S3²`).
fn inputs(light: &Light, frac: f64) -> Vec<(&'static str, [f64; 4])> {
    let bound = (det(light.shape(0)) * det(light.shape(1))).sqrt() / det(light.shape(2));
    let a = frac * bound.min(1.0).sqrt();
    vec![
        ("unpolarized", [1.0, 0.0, 0.0, 0.0]),
        ("x̂ (s)", [1.0, 1.0, 0.0, 0.0]),
        ("ŷ (p)", [1.0, -1.0, 0.0, 0.0]),
        ("+45°", [1.0, 0.0, a, 0.0]),
        ("circular", [1.0, 0.0, 0.0, a]),
    ]
}

fn exits(light: &Light, list: &[[f64; 2]]) -> Vec<([f64; 2], V3)> {
    list.iter()
        .map(|&[psi, a]| ([psi, a], scattered(light, psi.to_radians(), a.to_radians())))
        .collect()
}

/// The three configurations at `size` (module docs).
#[must_use]
pub fn cases(size: Size) -> Vec<Case> {
    let test = size == Size::Test;
    // Realizations: (full, test); quick is a quarter of full.
    let scale = |full: usize, test: usize| match size {
        Size::Full => full,
        Size::Quick => (full / 4).max(8),
        Size::Test => test,
    };
    let mut out = Vec::new();

    // 1. A bulk region, θ_x ≠ θ_y.
    let light = Light {
        wavelength: LAMBDA,
        theta_i: 30f64.to_radians(),
        theta_x: [[0.04, 0.01], [0.01, 0.0625]],
        theta_y: [[0.09, -0.005], [-0.005, 0.04]],
        sigma_zz: 0.2,
    };
    let scene = VolumeScene {
        light,
        matter: MATTER,
        region: Region::Bulk {
            window: if test { 0.45 } else { 0.6 },
        },
    };
    let list: &[[f64; 2]] = if test {
        &[
            [20.0, 0.0],
            [90.0, 0.0],
            [140.0, 180.0],
            [90.0, 90.0],
            [120.0, -60.0],
        ]
    } else {
        &[
            [15.0, 0.0],
            [40.0, 0.0],
            [70.0, 0.0],
            [90.0, 0.0],
            [110.0, 0.0],
            [140.0, 0.0],
            [165.0, 0.0],
            [40.0, 180.0],
            [90.0, 180.0],
            [140.0, 180.0],
            [30.0, 90.0],
            [90.0, 90.0],
            [150.0, 90.0],
            [60.0, -60.0],
            [120.0, -60.0],
        ]
    };
    out.push(Case {
        name: "volume_cube",
        title: "Bulk Gaussian δε (ℓ = 0.1 µm) in a Gaussian window; GSM light θ_i = 30°, \
                θ_x ≠ θ_y (0.2–0.3 µm), σ_zz = 0.2 µm; five input polarizations"
            .into(),
        grid: brute_volume::auto_grid(&scene, 2.0, 6.0),
        exits: exits(&light, list),
        inputs: inputs(&light, 0.95),
        scene,
        realizations: scale(256, 160),
        wrong: vec![Wrong::FlipS3, Wrong::FlipS2],
    });

    // 2. Backscatter from a thick region: σ_zz matters.
    let light = Light {
        wavelength: LAMBDA,
        theta_i: 30f64.to_radians(),
        theta_x: [[0.04, 0.0], [0.0, 0.04]],
        theta_y: [[0.04, 0.0], [0.0, 0.04]],
        sigma_zz: 0.15,
    };
    let scene = VolumeScene {
        light,
        region: Region::Bulk {
            window: if test { 0.45 } else { 0.6 },
        },
        matter: MATTER,
    };
    let list: &[[f64; 2]] = if test {
        &[[180.0, 0.0], [160.0, 90.0], [145.0, 0.0], [25.0, 0.0]]
    } else {
        &[
            [180.0, 0.0],
            [170.0, 0.0],
            [160.0, 0.0],
            [145.0, 0.0],
            [160.0, 180.0],
            [145.0, 180.0],
            [170.0, 90.0],
            [160.0, 90.0],
            [145.0, -90.0],
            [25.0, 0.0],
            [60.0, 90.0],
        ]
    };
    let all = inputs(&light, 1.0);
    out.push(Case {
        name: "volume_backscatter",
        title: "Backscatter from a thick region: bulk Gaussian δε (ℓ = 0.1 µm); GSM light \
                θ_i = 30°, w = 0.2 µm, σ_zz = 0.15 µm (h = 2kŝ along the packet axis)"
            .into(),
        grid: brute_volume::auto_grid(&scene, 2.0, 6.0),
        exits: exits(&light, list),
        inputs: vec![all[0], all[3], all[4]],
        scene,
        realizations: scale(192, 96),
        wrong: vec![Wrong::SigmaZz(1e3)],
    });

    // 3. A second R: exponential correlation (3-D K-correlation, γ = 3), ℓ = 0.15 µm sampled at
    // ℓ/4 (the cusp of R at 0 makes the aliasing of the voxel sum decay only as (ℓκ)⁻⁴: below
    // 0.3 % up to ψ = 140°, (1 + ℓ²h²)² · 6 (1 + (2πℓ/d)²)⁻²).
    let light = Light {
        wavelength: LAMBDA,
        theta_i: 30f64.to_radians(),
        theta_x: [[0.05, 0.01], [0.01, 0.04]],
        theta_y: [[0.05, 0.01], [0.01, 0.04]],
        sigma_zz: 0.2,
    };
    let scene = VolumeScene {
        light,
        matter: Permittivity::Exponential {
            sigma: 0.01,
            ell: 0.15,
        },
        region: Region::Bulk {
            window: if test { 0.45 } else { 0.6 },
        },
    };
    let list: &[[f64; 2]] = if test {
        &[[15.0, 0.0], [60.0, 90.0], [120.0, 180.0]]
    } else {
        &[
            [10.0, 0.0],
            [25.0, 0.0],
            [45.0, 0.0],
            [70.0, 0.0],
            [100.0, 0.0],
            [140.0, 0.0],
            [45.0, 180.0],
            [20.0, 90.0],
            [60.0, 90.0],
            [120.0, -90.0],
        ]
    };
    let all = inputs(&light, 1.0);
    out.push(Case {
        name: "volume_exponential",
        title:
            "A second R: bulk exponential δε (3-D K-correlation γ = 3, ℓ = 0.15 µm, voxels ℓ/4); \
                GSM light θ_i = 30°, σ_zz = 0.2 µm; kernel via the mixture fit"
                .into(),
        grid: brute_volume::auto_grid(&scene, 4.0, 6.0),
        exits: exits(&light, list),
        inputs: vec![all[0], all[1], all[4]],
        scene,
        realizations: scale(192, 96),
        wrong: vec![Wrong::GaussianR],
    });

    // 4. The thin-slab limit.
    let light = Light {
        wavelength: LAMBDA,
        theta_i: 40f64.to_radians(),
        theta_x: [[0.05, 0.012], [0.012, 0.08]],
        theta_y: [[0.1, 0.0], [0.0, 0.06]],
        sigma_zz: 0.25,
    };
    let scene = VolumeScene {
        light,
        region: Region::ThinSlab {
            window: if test { 1.2 } else { 2.0 },
            thickness: 0.005,
        },
        matter: MATTER,
    };
    let list: &[[f64; 2]] = if test {
        &[[30.0, 0.0], [100.0, 180.0], [135.0, 0.0], [60.0, 90.0]]
    } else {
        &[
            [20.0, 0.0],
            [45.0, 0.0],
            [70.0, 0.0],
            [45.0, 180.0],
            [100.0, 180.0],
            [135.0, 0.0],
            [160.0, 0.0],
            [120.0, 180.0],
            [60.0, 90.0],
            [120.0, -90.0],
            [150.0, 60.0],
        ]
    };
    out.push(Case {
        name: "volume_thin_slab",
        title: "Thin-slab limit: one 5 nm layer of Gaussian δε₂ (ℓ = 0.1 µm), θ_i = 40°, \
                θ_x ≠ θ_y, σ_zz = 0.25 µm; vs the 2-D surface_coherence_term × t"
            .into(),
        grid: brute_volume::auto_grid(&scene, 2.0, 6.0),
        exits: exits(&light, list),
        inputs: inputs(&light, 0.95),
        scene,
        realizations: scale(768, 384),
        wrong: vec![Wrong::SigmaZz(1e3)],
    });
    out
}

/// One (input, direction) comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Index into [`Case::inputs`].
    pub input: usize,
    /// Index into [`Case::exits`].
    pub exit: usize,
    /// The brute force.
    pub brute: StokesEstimate,
    /// The kernel's β.
    pub kernel: [f64; 4],
    /// The wrong predictions' β, in the order of [`Case::wrong`].
    pub wrong: Vec<[f64; 4]>,
}

/// Whether `kernel` agrees with the brute force: S0 within max(3 s.e., 2 %), S1–S3 within
/// max(3 s.e., 2 % of S0), the degree of polarization within max(3 s.e., 2 % of the brute
/// force's, 0.002). Returns the number of failed checks (of 5).
///
/// At a dipole null (polarized input, exit along its field: `S0 ≤ floor`, a scale far below
/// every other direction's) both sides vanish up to rounding: the four components must then be
/// within `floor`, and the undefined degree of polarization counts as passed.
#[must_use]
pub fn failures(brute: &StokesEstimate, kernel: &[f64; 4], floor: f64) -> usize {
    checks(brute, kernel, floor)
        .iter()
        .filter(|c| !within(c.0, c.1))
        .count()
}

/// The checks of [`failures`] as `(kernel − brute, tolerance, s.e.)`: four components, and the
/// degree of polarization unless at a dipole null.
fn checks(brute: &StokesEstimate, kernel: &[f64; 4], floor: f64) -> Vec<(f64, f64, f64)> {
    let b = &brute.mean;
    if b[0] <= floor {
        return (0..4).map(|i| (kernel[i] - b[i], floor, 0.0)).collect();
    }
    let mut out: Vec<(f64, f64, f64)> = (0..4)
        .map(|i| {
            let tol = (3.0 * brute.se[i]).max(0.02 * b[0]);
            (kernel[i] - b[i], tol, brute.se[i])
        })
        .collect();
    let tol = (3.0 * brute.dop_se).max(0.02 * brute.dop).max(0.002);
    out.push((dop(kernel) - brute.dop, tol, brute.dop_se));
    out
}

/// `|diff| ≤ tol`, false for NaN.
fn within(diff: f64, tol: f64) -> bool {
    diff.abs() <= tol
}

/// The dipole-null floor of a comparison: `1e-9 ×` the largest brute-force S0.
fn null_floor(rows: &[Row]) -> f64 {
    1e-9 * rows.iter().map(|r| r.brute.mean[0]).fold(0.0, f64::max)
}

/// A configuration's comparison.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Every (input, direction).
    pub rows: Vec<Row>,
    /// Per wrong prediction: its name, and how many (input, direction) pairs reject it.
    pub wrong: Vec<(String, usize)>,
    /// The dipole-null floor (see [`failures`]).
    pub floor: f64,
}

impl Comparison {
    /// Failed checks of the kernel's prediction in `row` (see [`failures`]).
    #[must_use]
    pub fn failures(&self, row: &Row) -> usize {
        failures(&row.brute, &row.kernel, self.floor)
    }

    /// Checks (5 per row) and how many passed.
    #[must_use]
    pub fn passed(&self) -> (usize, usize) {
        let fails: usize = self.rows.iter().map(|r| self.failures(r)).sum();
        (5 * self.rows.len() - fails, 5 * self.rows.len())
    }

    /// Median relative standard error of S0.
    #[must_use]
    pub fn median_rel_se(&self) -> f64 {
        let mut v: Vec<f64> = self
            .rows
            .iter()
            .map(|r| r.brute.se[0] / r.brute.mean[0])
            .collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    }

    /// Largest |relative difference| of S0 (dipole nulls excluded).
    #[must_use]
    pub fn max_rel_s0(&self) -> f64 {
        self.rows
            .iter()
            .filter(|r| r.brute.mean[0] > self.floor)
            .map(|r| (r.kernel[0] / r.brute.mean[0] - 1.0).abs())
            .fold(0.0, f64::max)
    }

    /// The printed verdict.
    #[must_use]
    pub fn verdict(&self) -> String {
        let (ok, all) = self.passed();
        let mut v = if ok == all {
            format!("agrees within 3σ/2 % ({ok}/{all} checks: S0, S1–S3, DoP)")
        } else {
            format!(
                "DISAGREES: {}/{all} checks beyond 3σ/2 %, the worst at {:.1} s.e. (at 3σ about \
                 1 in 370 independent checks fails by chance)",
                all - ok,
                self.worst_z()
            )
        };
        for (name, rejected) in &self.wrong {
            if *rejected > 0 {
                v += &format!("; wrong {name} rejected at {rejected}/{}", self.rows.len());
            } else {
                v += &format!("; wrong {name} NOT REJECTED");
            }
        }
        v
    }

    /// The largest `|kernel − brute|/s.e.` among the failed checks (0 if none).
    #[must_use]
    pub fn worst_z(&self) -> f64 {
        self.rows
            .iter()
            .flat_map(|r| checks(&r.brute, &r.kernel, self.floor))
            .filter(|c| !within(c.0, c.1) && c.2 > 0.0)
            .map(|c| c.0.abs() / c.2)
            .fold(0.0, f64::max)
    }

    /// `true` when every check passed and every wrong prediction was rejected somewhere.
    #[must_use]
    pub fn ok(&self) -> bool {
        let (ok, all) = self.passed();
        ok == all && self.wrong.iter().all(|w| w.1 > 0)
    }
}

/// Compares the brute force's estimate with the kernel (and the wrong predictions).
#[must_use]
pub fn compare(case: &Case, est: &VolumeEstimate) -> Comparison {
    let mut rows = Vec::new();
    for (ii, &(_, input)) in case.inputs.iter().enumerate() {
        let brute = est.stokes(input);
        for (di, &(_, exit)) in case.exits.iter().enumerate() {
            let k = predict(&case.scene, input, exit);
            let wrong = case
                .wrong
                .iter()
                .map(|w| match *w {
                    Wrong::SigmaZz(s) => {
                        let mut sc = case.scene;
                        sc.light.sigma_zz = s;
                        predict(&sc, input, exit)
                    }
                    Wrong::FlipS3 => [k[0], k[1], k[2], -k[3]],
                    Wrong::FlipS2 => [k[0], k[1], -k[2], k[3]],
                    Wrong::GaussianR => {
                        let mut sc = case.scene;
                        let (Permittivity::Gaussian { sigma, ell }
                        | Permittivity::Exponential { sigma, ell }) = sc.matter;
                        sc.matter = Permittivity::Gaussian { sigma, ell };
                        predict(&sc, input, exit)
                    }
                })
                .collect();
            rows.push(Row {
                input: ii,
                exit: di,
                brute: brute[di],
                kernel: k,
                wrong,
            });
        }
    }
    let floor = null_floor(&rows);
    let wrong = case
        .wrong
        .iter()
        .enumerate()
        .map(|(wi, w)| {
            let rejected = rows
                .iter()
                .filter(|r| failures(&r.brute, &r.wrong[wi], floor) > 0)
                .count();
            (w.name(), rejected)
        })
        .collect();
    Comparison { rows, wrong, floor }
}

/// Runs the brute force for `case`.
#[must_use]
pub fn run(case: &Case, seed: u64, threads: usize, progress: &(dyn Fn() + Sync)) -> VolumeEstimate {
    let exits: Vec<V3> = case.exits.iter().map(|e| e.1).collect();
    brute_volume::run(
        &case.scene,
        &case.grid,
        &exits,
        case.realizations,
        seed,
        threads,
        progress,
    )
}
