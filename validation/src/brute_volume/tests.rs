//! Tests of the volumetric brute force: the Born constant and the dipole pattern against
//! Rayleigh's cross-section, and the exact light average against explicit random vector fields
//! summed literally.

use super::*;
use gmueller::verify::quadrature::gauss_legendre;

fn light(theta_x: [[f64; 2]; 2], theta_y: [[f64; 2]; 2], sigma_zz: f64) -> Light {
    Light {
        wavelength: 0.5,
        theta_i: 30f64.to_radians(),
        theta_x,
        theta_y,
        sigma_zz,
    }
}

/// The Born constant and the dipole pattern against Rayleigh's cross-section: one voxel of
/// volume v = d³ and contrast δε lit by a coherent plane wave (one light mode, q = 0)
/// scatters, integrated over the sphere (Gauss–Legendre in cos θ × 64 azimuths),
/// `σ = k⁴ v² δε²/(6π)` — Rayleigh's `(8π/3) k⁴ a⁶ ((ε − 1)/(ε + 2))²` for a sphere of the
/// same volume to first order in δε (Jackson 3rd ed. §10.1) — for unpolarized, linear and
/// circular input alike; and the pattern of x̂-polarized light is `sin²γ`, γ from x̂.
#[test]
fn single_voxel_is_a_rayleigh_dipole() {
    let l = light([[1.0, 0.0], [0.0, 1.0]], [[1.0, 0.0], [0.0, 1.0]], 1.0);
    let grid = VolumeGrid {
        n: [4, 4, 4],
        d: [0.02; 3],
        beam_compensation: false,
    };
    let gl = gauss_legendre(48);
    let naz = 64;
    let mut exits = Vec::new();
    let mut weights = Vec::new();
    for (&u, &wu) in gl.nodes.iter().zip(&gl.weights) {
        for j in 0..naz {
            let phi = TAU * (j as f64 + 0.5) / naz as f64;
            exits.push(direction(u.acos(), phi));
            weights.push(wu * TAU / naz as f64);
        }
    }
    let k = l.k();
    let phases = demodulation(&l, &grid, &exits);
    let born = k * k / (4.0 * PI);
    let p = Plan {
        grid,
        window: vec![1.0; grid.len()],
        matter_amp: vec![0.0; grid.len()],
        modes: vec![(0, [1.0; 3])],
        mode_xs: vec![0],
        mode_ys: vec![0],
        phases,
        constant: born * born,
    };
    let deps = 1e-3;
    let mut f = vec![0.0; grid.len()];
    f[(2 * 4 + 1) * 4 + 3] = deps; // off-centre: the phases must not matter
    let sums = Worker::new(&p).sums(&p, &f);
    let est = VolumeEstimate {
        exits: exits.clone(),
        sums: vec![sums],
        light_modes: 1,
        light: l,
    };
    let v = grid.d[0].powi(3);
    let want = k.powi(4) * v * v * deps * deps / (6.0 * PI);
    for input in [
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0],
        [1.0, 0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0, 1.0],
    ] {
        let s = est.stokes(input);
        let total: f64 = s.iter().zip(&weights).map(|(e, w)| e.mean[0] * w).sum();
        println!("input {input:?}: σ = {total:e}, Rayleigh {want:e}");
        assert!(
            (total / want - 1.0).abs() < 1e-10,
            "{input:?}: {total:e} vs {want:e}"
        );
    }
    let x = l.packet_frame()[0];
    for (e, r) in est.stokes([1.0, 1.0, 0.0, 0.0]).iter().zip(&exits) {
        let cos_g = dot(*r, x);
        let pattern = k.powi(4) * v * v * deps * deps / (16.0 * PI * PI) * (1.0 - cos_g * cos_g);
        assert!(
            (e.mean[0] - pattern).abs() < 1e-12 * want,
            "pattern at {r:?}"
        );
        // Fully polarized in, fully polarized out.
        assert!(e.dop > 1.0 - 1e-9 || e.mean[0] < 1e-9 * want);
    }
}

/// The exact light average against explicit random vector fields: for one fixed δε on a
/// small grid, the light (`θ_x ≠ θ_y`, partially polarized and correlated, finite `σ_zz`) is
/// drawn 3000 times as a sum of grid modes with the 2×2 cross-spectral matrix of each mode
/// (Cholesky), and the field is summed literally, `E = (I − r̂r̂ᵀ) Σ_r δε E_in e^{−ik r̂·r} d³r`
/// with the 3-D vectors `E_in = W (x̂ a_x + ŷ a_y) e^{ik d̂·r}`; its Stokes vector in the exit
/// frame, averaged, must match [`VolumeEstimate::stokes`] from the channel sums within 4
/// standard errors of the Monte Carlo mean (each component; S0 also within 4 %).
#[test]
fn light_average_is_the_mean_over_random_fields() {
    let l = light(
        [[0.004, 0.001], [0.001, 0.006]],
        [[0.008, -0.001], [-0.001, 0.005]],
        0.07,
    );
    let scene = VolumeScene {
        light: l,
        matter: Permittivity::Gaussian {
            sigma: 0.01,
            ell: 0.1,
        },
        region: Region::Bulk { window: 0.06 },
    };
    // Without beam compensation: the compensated cross-spectral matrix of θ_x ≠ θ_y light
    // can fail Bochner's condition in its tails (module docs); the identity tested here
    // does not depend on it.
    // A box of 12 coherence widths, so that the circulant spectra are the Gaussian ones.
    let (n, dx) = (30, 0.036);
    let grid = VolumeGrid {
        n: [n; 3],
        d: [dx; 3],
        beam_compensation: false,
    };
    let exits = [
        scattered(&l, 0.3, 0.0),
        scattered(&l, 1.4, 0.7),
        scattered(&l, 2.6, -2.0),
        scattered(&l, 3.0, 2.5),
    ];
    let p = plan(&scene, &grid, &exits);
    let mut w = Worker::new(&p);
    let mut rng = Rng::new(3, 0);
    let eps = w.fields(&p, &mut rng)[0].clone();
    let f: Vec<f64> = eps.iter().zip(&p.window).map(|(e, w)| e * w).collect();
    let est = VolumeEstimate {
        exits: exits.to_vec(),
        sums: vec![w.sums(&p, &f)],
        light_modes: p.modes.len(),
        light: l,
    };
    // Bochner: |μ|² ≤ √(|Θx||Θy|)/|Θ½|; use 0.8 of it.
    let det = |t: [[f64; 2]; 2]| t[0][0] * t[1][1] - t[0][1] * t[1][0];
    let bound = (det(l.shape(0)) * det(l.shape(1))).sqrt() / det(l.shape(2));
    let mu = 0.8 * bound.sqrt();
    let (s1, phase) = (0.3_f64, 0.9_f64);
    let sxsy = 0.25 * (1.0 - s1 * s1);
    let input = [
        1.0,
        s1,
        2.0 * mu * sxsy.sqrt() * phase.cos(),
        2.0 * mu * sxsy.sqrt() * phase.sin(),
    ];
    let exact = est.stokes(input);

    // The same light as random fields: per mode q the cross-spectral matrix
    // [[S_x λx, C_xy λ½], [C_yx λ½, S_y λy]]/N of (A_x, A_y).
    let nn = grid.len();
    let spectra: Vec<Vec<f64>> = (0..3)
        .map(|c| {
            let xi = l.precision(c);
            circulant_spectrum(&grid, &|r| {
                let q: f64 = (0..3)
                    .map(|i| (0..3).map(|j| r[i] * xi[i][j] * r[j]).sum::<f64>())
                    .sum();
                (-0.5 * q).exp()
            })
        })
        .collect();
    let (sx, sy) = (0.5 * (1.0 + s1), 0.5 * (1.0 - s1));
    let cxy = C::new(0.5 * input[2], -0.5 * input[3]);
    // Where the discrete spectra break the continuous Bochner bound (far tails of the small
    // periodic grid), the yy-entry is raised to |C_xy|²/S_xx; the total raise is asserted
    // to be negligible.
    let mut deficit = 0.0;
    let mut total = 0.0;
    let chol: Vec<[C; 3]> = (0..nn)
        .map(|i| {
            let a = sx * spectra[0][i] / nn as f64;
            let b = sy * spectra[1][i] / nn as f64;
            let c = cxy * spectra[2][i] / nn as f64;
            if a <= 0.0 {
                return [
                    C::new(0.0, 0.0),
                    C::new(0.0, 0.0),
                    C::new(b.max(0.0).sqrt(), 0.0),
                ];
            }
            let l11 = a.sqrt();
            let l21 = c.conj() / l11;
            let rest = b - l21.norm_sqr();
            deficit += (-rest).max(0.0);
            total += b;
            [C::new(l11, 0.0), l21, C::new(rest.max(0.0).sqrt(), 0.0)]
        })
        .collect();
    println!("raised yy spectrum by {:.1e} of its total", deficit / total);
    assert!(
        deficit < 1e-6 * total,
        "cross-spectrum far from PSD: {deficit:e} of {total:e}"
    );
    let frame = l.packet_frame();
    let (k, d) = (l.k(), l.travel());
    let c = [coords(&grid, 0), coords(&grid, 1), coords(&grid, 2)];
    let pos = |i: usize| {
        let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
        [c[0][x], c[1][y], c[2][z]]
    };
    let mut inv = Fft3::new(grid.n, true);
    let draws = 3000;
    // The literal sum runs over the voxels the window lights (W > 1e-9).
    let lit: Vec<usize> = (0..nn).filter(|&i| p.window[i] > 1e-9).collect();
    let phases: Vec<Vec<C>> = exits
        .iter()
        .map(|r| {
            lit.iter()
                .map(|&i| {
                    let x = pos(i);
                    C::from_polar(f[i] * dx.powi(3), k * (dot(d, x) - dot(*r, x)))
                })
                .collect()
        })
        .collect();
    let mut acc = vec![[0.0; 4]; exits.len()];
    let mut acc2 = vec![[0.0; 4]; exits.len()];
    let mut light_rng = Rng::new(11, 0);
    let (mut ax, mut ay) = (vec![C::new(0.0, 0.0); nn], vec![C::new(0.0, 0.0); nn]);
    for _ in 0..draws {
        for i in 0..nn {
            let (z1, z2) = (light_rng.complex_normal(), light_rng.complex_normal());
            ax[i] = chol[i][0] * z1;
            ay[i] = chol[i][1] * z1 + chol[i][2] * z2;
        }
        inv.run(&mut ax);
        inv.run(&mut ay);
        for (di, r) in exits.iter().enumerate() {
            let mut e = [C::new(0.0, 0.0); 3];
            for (&i, ph) in lit.iter().zip(&phases[di]) {
                let (px, py) = (ph * ax[i], ph * ay[i]);
                for a in 0..3 {
                    e[a] += px * frame[0][a] + py * frame[1][a];
                }
            }
            // (I − r̂r̂ᵀ) E, then the exit frame.
            let re: C = (0..3).map(|a| e[a] * r[a]).sum();
            let e: [C; 3] = std::array::from_fn(|a| e[a] - re * r[a]);
            let [u, v] = exit_frame(*r);
            let eu: C = (0..3).map(|a| e[a] * u[a]).sum();
            let ev: C = (0..3).map(|a| e[a] * v[a]).sum();
            let s = [
                eu.norm_sqr() + ev.norm_sqr(),
                eu.norm_sqr() - ev.norm_sqr(),
                2.0 * (eu * ev.conj()).re,
                2.0 * (eu.conj() * ev).im,
            ]
            .map(|v| v * p.constant);
            for j in 0..4 {
                acc[di][j] += s[j];
                acc2[di][j] += s[j] * s[j];
            }
        }
    }
    let m = draws as f64;
    for (di, ex) in exact.iter().enumerate() {
        for j in 0..4 {
            let mean = acc[di][j] / m;
            let se = ((acc2[di][j] / m - mean * mean) / (m - 1.0)).sqrt();
            println!(
                "dir {di} S{j}: random fields {mean:.5e} ± {se:.1e}, exact {:.5e} ({:+.2} s.e.)",
                ex.mean[j],
                (mean - ex.mean[j]) / se
            );
            assert!(
                (mean - ex.mean[j]).abs() < 4.0 * se,
                "dir {di} S{j}: {mean:e} ± {se:e} vs {:e}",
                ex.mean[j]
            );
        }
        assert!((acc[di][0] / m / ex.mean[0] - 1.0).abs() < 0.04);
        assert!(ex.dop > 0.05, "dir {di}: the case must be polarized");
    }
}
