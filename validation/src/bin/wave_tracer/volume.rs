//! The volumetric configurations of the wave tracer (`gmueller_validation::volume_cases`): the
//! brute-force 3-D first-Born vector field sum (`gmueller_validation::brute_volume`) against
//! the n = 3 kernel (`gmueller_validation::kernel_side_volume`), with a table per
//! configuration, a verdict, a PNG per configuration (`volume_plot.rs`) and a CSV
//! (`wave_tracer_volume.csv`).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use gmueller_validation::volume_cases::{self, Case, Size};
use indicatif::{ProgressBar, ProgressStyle};

/// Runs the volumetric configurations (those named `only`, if given) and returns the report.
pub fn run(
    realizations: Option<usize>,
    quick: bool,
    threads: usize,
    seed: u64,
    only: Option<&str>,
    out: &Path,
) -> String {
    let size = if quick { Size::Quick } else { Size::Full };
    let mut cases = volume_cases::cases(size);
    cases.retain(|c| only.is_none_or(|o| o == c.name));
    if let Some(k) = realizations {
        for c in &mut cases {
            c.realizations = k.max(2);
        }
    }
    let mut report = String::new();
    if cases.is_empty() {
        return report;
    }
    let wall = Instant::now();
    let total: u64 = cases.iter().map(|c| c.realizations as u64).sum();
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} volume realizations {msg}",
        )
        .expect("template"),
    );
    let mut csv = String::from(
        "config,input,psi_deg,azimuth_deg,theta_o_deg,brute_S0,se_S0,brute_S1,se_S1,brute_S2,se_S2,\
         brute_S3,se_S3,brute_dop,se_dop,kernel_S0,kernel_S1,kernel_S2,kernel_S3,kernel_dop,failed_checks\n",
    );
    for case in &cases {
        bar.set_message(case.name);
        let t0 = Instant::now();
        let est = volume_cases::run(case, seed, threads, &|| bar.inc(1));
        let brute_time = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let cmp = volume_cases::compare(case, &est);
        let kernel_time =
            t1.elapsed().as_secs_f64() / (cmp.rows.len() * (1 + case.wrong.len())).max(1) as f64;
        for r in &cmp.rows {
            let (angles, exit) = case.exits[r.exit];
            let b = &r.brute;
            let _ = writeln!(
                csv,
                "{},{},{},{},{:.4},{:.8e},{:.4e},{:.8e},{:.4e},{:.8e},{:.4e},{:.8e},{:.4e},{:.6},{:.2e},{:.8e},{:.8e},{:.8e},{:.8e},{:.6},{}",
                case.name,
                case.inputs[r.input].0,
                angles[0],
                angles[1],
                exit[2].acos().to_degrees(),
                b.mean[0],
                b.se[0],
                b.mean[1],
                b.se[1],
                b.mean[2],
                b.se[2],
                b.mean[3],
                b.se[3],
                b.dop,
                b.dop_se,
                r.kernel[0],
                r.kernel[1],
                r.kernel[2],
                r.kernel[3],
                gmueller_validation::brute_volume::dop(&r.kernel),
                cmp.failures(r)
            );
        }
        let png = out.join(format!("{}.png", case.name));
        if let Err(e) = super::volume_plot::draw(&png, case, &cmp) {
            bar.println(format!("plot {} failed: {e}", png.display()));
        }
        let text = case_report(case, &est, &cmp, brute_time, kernel_time, threads);
        bar.println(&text);
        report += &text;
    }
    bar.finish_and_clear();
    let _ = writeln!(
        report,
        "\nvolumetric configurations: {:.1} s wall",
        wall.elapsed().as_secs_f64()
    );
    let path = out.join("wave_tracer_volume.csv");
    if let Err(e) = std::fs::write(&path, &csv) {
        eprintln!("cannot write {}: {e}", path.display());
    }
    report
}

fn case_report(
    case: &Case,
    est: &gmueller_validation::brute_volume::VolumeEstimate,
    cmp: &volume_cases::Comparison,
    brute_time: f64,
    kernel_time: f64,
    threads: usize,
) -> String {
    let mut s = String::new();
    let g = &case.grid;
    let _ = writeln!(s, "\n[{}] {}", case.name, case.title);
    let _ = writeln!(
        s,
        "  grid {}×{}×{} × ({:.3}, {:.3}, {:.4}) µm, window w_b = {:.2} µm, {} realizations, {} light modes, {} directions × {} inputs",
        g.n[0],
        g.n[1],
        g.n[2],
        g.d[0],
        g.d[1],
        g.d[2],
        case.scene.region.window(),
        est.sums.len(),
        est.light_modes,
        case.exits.len(),
        case.inputs.len()
    );
    let _ = writeln!(
        s,
        "  β = dP/dΩ per unit volume per unit irradiance (1/(µm·sr)), exit frame Frame::sp(r̂, ẑ); unpolarized input:"
    );
    // Wrong predictions that change S0 (σ_zz) get a column of their S0 difference.
    let s0_wrong: Vec<usize> = (0..case.wrong.len())
        .filter(|&w| matches!(case.wrong[w], volume_cases::Wrong::SigmaZz(_)))
        .collect();
    let _ = writeln!(
        s,
        "    {:>6} {:>6} {:>6}  {:>11} {:>8}  {:>11} {:>8}   {:>12} {:>12}{}",
        "ψ°",
        "a°",
        "θ_o°",
        "brute S0",
        "s.e.",
        "kernel S0",
        "diff",
        "DoP brute",
        "DoP kernel",
        s0_wrong
            .iter()
            .map(|_| format!(" {:>12}", "σ_zz=∞ diff"))
            .collect::<String>()
    );
    for r in cmp.rows.iter().filter(|r| r.input == 0) {
        let (angles, exit) = case.exits[r.exit];
        let b = &r.brute;
        let _ = writeln!(
            s,
            "    {:>6.0} {:>6.0} {:>6.1}  {:>11.4e} {:>7.2}%  {:>11.4e} {:>+7.2}%   {:>6.4}±{:<5.4} {:>12.4}{}{}",
            angles[0],
            angles[1],
            exit[2].acos().to_degrees(),
            b.mean[0],
            100.0 * b.se[0] / b.mean[0],
            r.kernel[0],
            100.0 * (r.kernel[0] / b.mean[0] - 1.0),
            b.dop,
            b.dop_se,
            gmueller_validation::brute_volume::dop(&r.kernel),
            s0_wrong
                .iter()
                .map(|&w| format!(" {:>+11.1}%", 100.0 * (r.wrong[w][0] / b.mean[0] - 1.0)))
                .collect::<String>(),
            if cmp.failures(r) > 0 { "  ✗" } else { "" }
        );
    }
    let _ = writeln!(
        s,
        "  all inputs ({}): max |S0 rel diff| {:.2} %, median s.e. {:.2} %; time per direction: brute force {:.2} s (wall, {threads} threads, all inputs), kernel side {:.1} µs (the medium built per call: its speed is in benches/medium.rs)",
        case.inputs
            .iter()
            .map(|i| i.0)
            .collect::<Vec<_>>()
            .join(", "),
        100.0 * cmp.max_rel_s0(),
        100.0 * cmp.median_rel_se(),
        brute_time / case.exits.len() as f64,
        kernel_time * 1e6
    );
    let _ = writeln!(s, "  verdict: {}", cmp.verdict());
    s
}
