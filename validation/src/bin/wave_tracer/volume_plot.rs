//! PNG plots of the volumetric configurations: in the plane of incidence, the kernel's β (S0,
//! unpolarized input) and degree of polarization against the scattering angle, over the brute
//! force's points with ±1 s.e. bars.

use std::path::Path;

use gmueller_validation::brute_volume::{dop, scattered};
use gmueller_validation::kernel_side_volume::predict;
use gmueller_validation::volume_cases::{Case, Comparison, Wrong};
use plotters::prelude::*;

type Res = Result<(), Box<dyn std::error::Error>>;

/// A kernel curve: (signed scattering angle in degrees, β).
type Curve = Vec<(f64, [f64; 4])>;

/// The signed in-plane scattering angle of an exit (degrees): `+ψ` at azimuth 0, `−ψ` at 180°;
/// `None` out of the plane.
fn signed_psi(angles: [f64; 2]) -> Option<f64> {
    if angles[1] == 0.0 {
        Some(angles[0])
    } else if (angles[1].abs() - 180.0).abs() < 1e-9 {
        Some(-angles[0])
    } else {
        None
    }
}

/// Draws `case` (unpolarized input, exits in the plane of incidence) to `path`.
pub fn draw(path: &Path, case: &Case, cmp: &Comparison) -> Res {
    super::plot::ensure_font();
    let root = BitMapBackend::new(path, (1400, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(70);
    title.draw(&Text::new(
        format!("[{}] {}", case.name, case.title),
        (12, 8),
        ("sans-serif", 17).into_font(),
    ))?;
    title.draw(&Text::new(
        format!(
            "brute force ({} realizations, ±1 s.e.) vs the n = 3 kernel, unpolarized input, plane of incidence — {}",
            case.realizations,
            cmp.verdict()
        ),
        (12, 38),
        ("sans-serif", 14).into_font(),
    ))?;
    let (left, right) = body.split_horizontally(760);
    let unpolarized = [1.0, 0.0, 0.0, 0.0];
    let points: Vec<(f64, &gmueller_validation::volume_cases::Row)> = cmp
        .rows
        .iter()
        .filter(|r| r.input == 0)
        .filter_map(|r| signed_psi(case.exits[r.exit].0).map(|p| (p, r)))
        .collect();
    let light = &case.scene.light;
    let curve = |scene: &gmueller_validation::brute_volume::VolumeScene| -> Curve {
        (0..=360)
            .map(|i| {
                let psi = -180.0 + f64::from(i);
                let a = if psi >= 0.0 { 0.0 } else { 180f64.to_radians() };
                let r = scattered(light, psi.abs().to_radians(), a);
                (psi, predict(scene, unpolarized, r))
            })
            .collect()
    };
    let kernel = curve(&case.scene);
    let wrong: Vec<(String, Curve)> = case
        .wrong
        .iter()
        .filter_map(|w| match *w {
            Wrong::SigmaZz(s) => {
                let mut sc = case.scene;
                sc.light.sigma_zz = s;
                Some((w.name(), curve(&sc)))
            }
            _ => None,
        })
        .collect();
    let hi = kernel
        .iter()
        .map(|k| k.1[0])
        .chain(points.iter().map(|p| p.1.brute.mean[0]))
        .fold(0.0, f64::max)
        * 2.0;
    let lo = kernel
        .iter()
        .chain(wrong.iter().flat_map(|w| w.1.iter()))
        .map(|k| k.1[0])
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min)
        * 0.5;

    let mut chart = ChartBuilder::on(&left)
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .caption("β: S0 per unit volume and irradiance", ("sans-serif", 18))
        .build_cartesian_2d(-180.0..180.0, (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("scattering angle ψ from d̂ in the plane of incidence (deg; −: azimuth 180°)")
        .y_desc("β (1/(µm·sr))")
        .y_label_formatter(&|v| format!("{v:.1e}"))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 15))
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            kernel.iter().map(|(p, k)| (*p, k[0].max(lo))),
            BLUE.stroke_width(2),
        ))?
        .label("kernel (K³ × dipole × k⁴/16π²)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    for (name, c) in &wrong {
        chart
            .draw_series(
                c.iter()
                    .step_by(2)
                    .map(|(p, k)| Circle::new((*p, k[0].max(lo)), 1, BLACK.mix(0.5).filled())),
            )?
            .label(format!("kernel with {name}"))
            .legend(|(x, y)| Circle::new((x + 10, y), 2, BLACK.mix(0.5).filled()));
    }
    chart.draw_series(points.iter().map(|(p, r)| {
        let b = &r.brute;
        ErrorBar::new_vertical(
            *p,
            (b.mean[0] - b.se[0]).max(lo),
            b.mean[0],
            b.mean[0] + b.se[0],
            RED.filled(),
            6,
        )
    }))?;
    chart
        .draw_series(
            points
                .iter()
                .map(|(p, r)| Circle::new((*p, r.brute.mean[0]), 3, RED.filled())),
        )?
        .label("brute force")
        .legend(|(x, y)| Circle::new((x + 10, y), 3, RED.filled()));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::LowerRight)
        .draw()?;

    let mut chart = ChartBuilder::on(&right)
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .caption("degree of polarization", ("sans-serif", 18))
        .build_cartesian_2d(-180.0..180.0, 0.0..1.05)?;
    chart
        .configure_mesh()
        .x_desc("scattering angle ψ (deg)")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 15))
        .draw()?;
    chart.draw_series(LineSeries::new(
        kernel
            .iter()
            .filter(|(_, k)| k[0] > 0.0)
            .map(|(p, k)| (*p, dop(k))),
        BLUE.stroke_width(2),
    ))?;
    chart.draw_series(points.iter().map(|(p, r)| {
        let b = &r.brute;
        ErrorBar::new_vertical(
            *p,
            b.dop - b.dop_se,
            b.dop,
            b.dop + b.dop_se,
            RED.filled(),
            6,
        )
    }))?;
    chart.draw_series(
        points
            .iter()
            .map(|(p, r)| Circle::new((*p, r.brute.dop), 3, RED.filled())),
    )?;
    root.present()?;
    Ok(())
}
