//! The Pareto plot: median time per evaluation vs max S0 relative error, log–log, one point per
//! variant; the Pareto front is joined and labelled.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use super::measure::Coh;

static FONT: Once = Once::new();

fn ensure_font() {
    FONT.call_once(|| {
        // DejaVu Sans (Bitstream Vera licence), shipped by the `dejavu` crate.
        let _ = register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

/// One variant on the plot.
pub struct ParetoPoint {
    pub label: String,
    pub ns: f64,
    pub s0_max: f64,
    pub s0_rms: f64,
    pub f32: bool,
    pub coh: Coh,
    /// A batch row (drawn as a triangle).
    pub batch: bool,
}

/// Errors below this are drawn at it (the exact variants have error 0 or ~1e-16).
const ERR_FLOOR: f64 = 1e-12;

/// Draws the plot to `path`.
pub fn pareto(
    path: &Path,
    pts: &[ParetoPoint],
    title: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    ensure_font();
    let root = BitMapBackend::new(path, (1400, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let e = |p: &ParetoPoint| p.s0_max.max(ERR_FLOOR);
    let (t0, t1) = pts.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), p| {
        (a.min(p.ns), b.max(p.ns))
    });
    let (e0, e1) = pts.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), p| {
        (a.min(e(p)), b.max(e(p)))
    });
    let mut chart = ChartBuilder::on(&root)
        .margin(16)
        .caption(title, ("sans-serif", 20))
        .x_label_area_size(55)
        .y_label_area_size(90)
        .build_cartesian_2d(
            (t0 / 1.5..t1 * 3.0).log_scale(),
            (e0 / 5.0..(e1 * 5.0).max(2.0)).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("median time per evaluation (ns, log)")
        .y_desc(format!(
            "max relative error of S0 vs reference (log; exact drawn at {ERR_FLOOR:.0e})"
        ))
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()?;

    // 1 % line.
    chart
        .draw_series(LineSeries::new(
            [(t0 / 1.5, 0.01), (t1 * 3.0, 0.01)],
            BLACK.mix(0.6).stroke_width(2),
        ))?
        .label("1 % error")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.4)));

    // Pareto front: sorted by time, keep points with strictly lower error than all faster ones.
    let mut idx: Vec<usize> = (0..pts.len()).collect();
    idx.sort_by(|&a, &b| pts[a].ns.total_cmp(&pts[b].ns));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for &i in &idx {
        if e(&pts[i]) < best {
            best = e(&pts[i]);
            front.push(i);
        }
    }
    chart
        .draw_series(LineSeries::new(
            front.iter().map(|&i| (pts[i].ns, e(&pts[i]))),
            RGBColor(120, 120, 120).stroke_width(2),
        ))?
        .label("Pareto front")
        .legend(|(x, y)| {
            PathElement::new(
                vec![(x, y), (x + 20, y)],
                RGBColor(120, 120, 120).stroke_width(2),
            )
        });

    let colour = |c: Coh| match c {
        Coh::PlaneWave => RGBColor(31, 119, 180),
        Coh::Incoherent => RGBColor(214, 39, 40),
        Coh::Partial => RGBColor(44, 160, 44),
    };
    for (coh, name) in [
        (Coh::PlaneWave, "PlaneWave"),
        (Coh::Incoherent, "Incoherent"),
        (Coh::Partial, "Partial"),
    ] {
        let c = colour(coh);
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.coh == coh && !p.f32 && !p.batch)
                    .map(|p| Circle::new((p.ns, e(p)), 5, c.filled())),
            )?
            .label(format!("{name} · f64 (filled)"))
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.coh == coh && p.f32 && !p.batch)
                    .map(|p| Circle::new((p.ns, e(p)), 5, c.stroke_width(2))),
            )?
            .label(format!("{name} · f32 (open)"))
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.stroke_width(2)));
        // Batch rows: triangles, filled f64, open f32.
        chart.draw_series(pts.iter().filter(|p| p.coh == coh && p.batch).map(|p| {
            let style = if p.f32 { c.stroke_width(2) } else { c.filled() };
            TriangleMarker::new((p.ns, e(p)), 7, style)
        }))?;
    }
    chart
        .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
        .label("batch rows (triangles)")
        .legend(|(x, y)| TriangleMarker::new((x + 10, y), 7, BLACK.stroke_width(2)));
    // RMS as small grey dots under each point.
    chart.draw_series(
        pts.iter()
            .map(|p| Circle::new((p.ns, p.s0_rms.max(ERR_FLOOR)), 2, BLACK.mix(0.35).filled())),
    )?;
    // Labels on the front.
    for &i in &front {
        let p = &pts[i];
        chart.draw_series(std::iter::once(Text::new(
            p.label.clone(),
            (p.ns * 1.08, e(p) * 1.25),
            ("sans-serif", 13).into_font(),
        )))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    root.draw(&Text::new(
        "small grey dots: RMS S0 error of the same variant; labels: variants on the Pareto front",
        (110, 880),
        ("sans-serif", 13).into_font(),
    ))?;
    root.present()?;
    Ok(())
}
