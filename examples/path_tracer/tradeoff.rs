//! `--tradeoff`: what the coherence one sample of light carries trades, measured on this scene
//! (160×100, 64 spp, one wavelength: 0.55 µm, so that the noise is the sampling's alone; the
//! references at 128 spp). Two rules of `gmueller::bsdf::sources`:
//! - **the sun** (a distant disk; the same rule as an area light sampled by pieces): one packet
//!   along the centre with the whole disk's coherence, or the disk split into `N` random
//!   packets of `Ω/N` each (wider coherence, sharper lobes, random positions);
//! - **sky and indirect light**: the surface coherence width `w` of every BSDF-sampled
//!   direction (`SurfaceCoherence`); `w → ∞` is the plane-wave limit of an incoherent source.
//!
//! For each setting: the time, the noise (Σ standard errors of the pixels' Y / Σ Y), and the
//! difference from the reference setting rendered with another seed (`Σ |Y − Y_ref| / Σ Y_ref`,
//! noise of both included), over the whole image and over the glints (the 2 % brightest pixels
//! of the reference).

use std::fmt::Write as _;
use std::path::Path;

use super::{Options, Render, render};
use crate::scene::Scene;

struct Row {
    label: String,
    seconds: f64,
    noise: [f64; 2],
    diff: [f64; 2],
}

fn measure(label: String, r: &Render, reference: &Render, glints: &[bool]) -> Row {
    let mut noise = [0.0; 4];
    let mut diff = [0.0; 4];
    for ((p, q), &g) in r.pixels.iter().zip(&reference.pixels).zip(glints) {
        for (k, on) in [true, g].into_iter().enumerate() {
            if on {
                noise[k] += p.std_error(1);
                noise[k + 2] += p.mean(1);
                diff[k] += (p.mean(1) - q.mean(1)).abs();
                diff[k + 2] += q.mean(1);
            }
        }
    }
    Row {
        label,
        seconds: r.seconds,
        noise: [noise[0] / noise[2], noise[1] / noise[3]],
        diff: [diff[0] / diff[2], diff[1] / diff[3]],
    }
}

fn table(title: &str, rows: &[Row]) -> String {
    let mut s = format!(
        "\n{title}\n\n| setting | time (s) | noise, image | noise, glints | difference, image | difference, glints |\n|---|---|---|---|---|---|\n"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.4} | {:.4} | {:.4} | {:.4} |",
            r.label, r.seconds, r.noise[0], r.noise[1], r.diff[0], r.diff[1]
        );
    }
    s
}

fn glint_mask(reference: &Render) -> Vec<bool> {
    let mut y: Vec<f64> = reference.pixels.iter().map(|p| p.mean(1)).collect();
    y.sort_by(f64::total_cmp);
    let cut = y[y.len() * 98 / 100];
    reference.pixels.iter().map(|p| p.mean(1) >= cut).collect()
}

pub(crate) fn run(scene: &Scene, out: &Path) {
    let base = Options {
        width: 160,
        height: 100,
        spp: 64,
        wavelengths: 1,
        lambda: Some(0.55),
        progress: false,
        ..Options::default()
    };
    let reseed = |o: &Options| Options {
        seed: 7,
        spp: 128,
        ..o.clone()
    };
    let mut report = String::from(
        "Coherence per sample, measured on the path tracer's scene (160×100, 64 spp, λ = 0.55 µm, f32 Full·Partial; references at 128 spp).\n",
    );

    // One sweep: each setting against the last one rendered with another seed and 128 spp.
    let sweep = |title: &str, settings: Vec<(String, Options)>| {
        let reference = render(scene, &reseed(&settings[settings.len() - 1].1));
        let glints = glint_mask(&reference);
        let rows: Vec<Row> = settings
            .into_iter()
            .map(|(label, o)| measure(label, &render(scene, &o), &reference, &glints))
            .collect();
        table(title, &rows)
    };
    report += &sweep(
        "Sun: one packet with the disk's coherence, or N packets of Ω/N (reference N = 64, another seed, 128 spp)",
        [1, 4, 16, 64]
            .map(|n| {
                (
                    format!("sun in N = {n}"),
                    Options {
                        sun_split: n,
                        ..base.clone()
                    },
                )
            })
            .into(),
    );
    report += &sweep(
        "Sky and indirect light: surface coherence width w (reference w = 250 µm, another seed, 128 spp)",
        [2.0f32, 10.0, 50.0, 250.0]
            .map(|w| {
                (
                    format!("sky w = {w} µm"),
                    Options {
                        sky_coherence: w,
                        ..base.clone()
                    },
                )
            })
            .into(),
    );

    print!("{report}");
    std::fs::create_dir_all(out).expect("output directory");
    std::fs::write(out.join("tradeoff.md"), report).expect("write tradeoff.md");
}
