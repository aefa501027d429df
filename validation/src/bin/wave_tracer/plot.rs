//! PNG plots of the lobes: the kernel's curve over the brute-force points with ±1 s.e. bars.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use super::{Config, Row, Summary, kernel_side, verdict};

static FONT: Once = Once::new();

/// Registers the plots' font once.
pub fn ensure_font() {
    FONT.call_once(|| {
        // DejaVu Sans (Bitstream Vera licence), shipped by the `dejavu` crate.
        let _ = register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

type Res = Result<(), Box<dyn std::error::Error>>;

/// Draws `rows` of configuration `c` (in-plane scan left, out-of-plane points right).
pub fn lobe(path: &Path, c: &Config, rows: &[Row], s: &Summary) -> Res {
    ensure_font();
    let root = BitMapBackend::new(path, (1400, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(70);
    title.draw(&Text::new(
        c.title.clone(),
        (12, 8),
        ("sans-serif", 20).into_font(),
    ))?;
    title.draw(&Text::new(
        format!(
            "brute force ({} realizations, ±1 s.e.) vs gmueller kernel [{}] — {}",
            c.realizations,
            kernel_side::method_name(&c.scene, c.order),
            verdict(s)
        ),
        (12, 38),
        ("sans-serif", 15).into_font(),
    ))?;
    let (left, right) = body.split_horizontally(900);
    let n_in = c.in_plane.len();
    let (inp, outp) = rows.split_at(n_in);

    let peak = rows
        .iter()
        .map(|r| r.brute.max(r.kernel.total()))
        .fold(0.0, f64::max);
    let floor = peak * 1e-6;

    // Dense kernel curves.
    let dh = c.grid.dh();
    let dense = |from: [f64; 2], to: [f64; 2]| -> Vec<(f64, [f64; 3], kernel_side::Prediction)> {
        let hs: Vec<[f64; 2]> = (0..=400)
            .map(|i| {
                let t = f64::from(i) / 400.0;
                [
                    from[0] + t * (to[0] - from[0]),
                    from[1] + t * (to[1] - from[1]),
                ]
            })
            .collect();
        let exits: Vec<[f64; 3]> = hs.iter().filter_map(|h| c.scene.exit_for(*h)).collect();
        let pred = kernel_side::predict_at(&c.scene, &exits, c.order);
        hs.iter()
            .zip(exits)
            .zip(pred)
            .map(|((h, e), p)| (h[1], e, p))
            .collect()
    };
    let hx0 = c.in_plane.first().map_or(0.0, |m| m[0] as f64 * dh);
    let hx1 = c.in_plane.last().map_or(0.0, |m| m[0] as f64 * dh);
    let curve = dense([hx0, 0.0], [hx1, 0.0]);
    let ang = super::in_plane_deg;
    let (a0, a1) = (ang(&curve[0].1), ang(&curve[curve.len() - 1].1));

    let snell = c.scene.eta_t.and(c.scene.specular_exit());
    let mut chart = ChartBuilder::on(&left)
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .caption("plane of incidence", ("sans-serif", 18))
        .build_cartesian_2d(a0..a1, (floor..peak * 2.0).log_scale())?;
    chart
        .configure_mesh()
        .x_desc(match c.scene.eta_t {
            None => "exit angle θ_o in the plane of incidence (deg; specular at +30)".to_string(),
            Some(_) => format!(
                "exit angle θ_o from −n̂ in the plane of incidence (deg; Snell at {:+.2}, dashed)",
                snell.map_or(f64::NAN, |r| ang(&r))
            ),
        })
        .y_desc("radiance per unit incident irradiance, L/S (1/sr)")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 15))
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            curve.iter().map(|(_, e, p)| (ang(e), p.total().max(floor))),
            BLUE.stroke_width(2),
        ))?
        .label("kernel: total")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(
            curve
                .iter()
                .map(|(_, e, p)| (ang(e), p.scattered.max(floor))),
            BLUE.mix(0.5).stroke_width(1),
        ))?
        .label("kernel: scattered part")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.mix(0.5)));
    if let Some(r) = snell {
        // Snell's direction (h_t = 0), dashed.
        let x = ang(&r);
        let (lo, hi) = (floor, peak * 2.0);
        let steps = 24;
        chart.draw_series((0..steps).step_by(2).map(|i| {
            let at = |j: i32| lo * (hi / lo).powf(f64::from(j) / f64::from(steps));
            PathElement::new(vec![(x, at(i)), (x, at(i + 1))], BLACK.mix(0.6))
        }))?;
    }
    draw_points(&mut chart, inp.iter().map(|r| (r.in_plane_deg(), r)), floor)?;
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;

    // Out of plane: h_y scan at h_x = 0.
    let hy0 = outp.iter().map(|r| r.h[1]).fold(0.0, f64::min);
    let hy1 = outp.iter().map(|r| r.h[1]).fold(0.0, f64::max);
    if hy1 > hy0 {
        let curve = dense([0.0, hy0], [0.0, hy1]);
        let mut chart = ChartBuilder::on(&right)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .caption("out of plane (h_x = 0)", ("sans-serif", 18))
            .build_cartesian_2d(hy0..hy1, (floor..peak * 2.0).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(if c.scene.eta_t.is_some() {
                "h_y, out-of-plane component of η k r - k d (rad/µm)"
            } else {
                "h_y, out-of-plane component of k(r - d) (rad/µm)"
            })
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .draw()?;
        chart.draw_series(LineSeries::new(
            curve.iter().map(|(hy, _, p)| (*hy, p.total().max(floor))),
            BLUE.stroke_width(2),
        ))?;
        draw_points(&mut chart, outp.iter().map(|r| (r.h[1], r)), floor)?;
    }
    root.present()?;
    Ok(())
}

fn draw_points<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<
        'a,
        DB,
        Cartesian2d<
            plotters::coord::types::RangedCoordf64,
            plotters::coord::combinators::LogCoord<f64>,
        >,
    >,
    pts: impl Iterator<Item = (f64, &'a Row)> + Clone,
    floor: f64,
) -> Result<(), String> {
    chart
        .draw_series(pts.clone().map(|(x, r)| {
            let lo = (r.brute - r.se).max(floor);
            let hi = (r.brute + r.se).max(floor);
            ErrorBar::new_vertical(x, lo, r.brute.max(floor), hi, RED.filled(), 6)
        }))
        .map_err(|e| e.to_string())?;
    chart
        .draw_series(pts.map(|(x, r)| {
            let color = if r.within() { RED } else { BLACK };
            Circle::new((x, r.brute.max(floor)), 3, color.filled())
        }))
        .map_err(|e| e.to_string())?
        .label("brute force (black: beyond 3σ/2 %)")
        .legend(|(x, y)| Circle::new((x + 10, y), 3, RED.filled()));
    Ok(())
}
