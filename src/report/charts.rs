//! Error-versus-cost charts, one per view, drawn by `plotters` to SVG:
//! every competing preset as a point (frame × `none`, total mismatch, both
//! on log axes), the Pareto front joined and labelled.

use super::cells::Cell;
use super::pareto::competes;
use super::summary::Report;
use anyhow::{Result, anyhow};
use plotters::prelude::*;

/// Mismatch below this is drawn at it (a log axis has no zero).
const FLOOR_PCT: f64 = 0.001;

/// A point's colour by family.
fn colour(family: &str) -> RGBColor {
    match family {
        "planar" => RGBColor(0x2c, 0xa0, 0x2c),
        "projective" => RGBColor(0x94, 0x67, 0xbd),
        "shadow-volume" => RGBColor(0xff, 0x7f, 0x0e),
        _ => RGBColor(0x1f, 0x77, 0xb4),
    }
}

fn point(c: &Cell) -> (f64, f64) {
    (c.cost.ratio_to_none, c.quality.total_pct.max(FLOOR_PCT))
}

/// The chart of view `index` of `report` as an SVG document.
pub fn pareto_svg(report: &Report, index: usize) -> Result<String> {
    let (view, front) = &report.fronts[index];
    let cells: Vec<&Cell> = report
        .cells
        .iter()
        .filter(|c| c.view() == *view && competes(c))
        .collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 420)).into_drawing_area();
        let err =
            |e: DrawingAreaErrorKind<_>| anyhow!("drawing the chart of {}: {e:?}", view.label());
        root.fill(&WHITE).map_err(err)?;
        let (mut x0, mut x1, mut y0, mut y1) = (1.0f64, 1.0f64, FLOOR_PCT, 1.0f64);
        for c in &cells {
            let (x, y) = point(c);
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{}: error against cost", view.label()),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (x0 * 0.9..x1 * 1.15).log_scale(),
                (y0 * 0.7..y1 * 1.5).log_scale(),
            )
            .map_err(err)?;
        chart
            .configure_mesh()
            .light_line_style(RGBColor(0xf4, 0xf4, 0xf4))
            .x_desc("frame time × none (log)")
            .y_desc("mismatch, % of considered pixels (log)")
            .draw()
            .map_err(err)?;
        chart
            .draw_series(
                cells
                    .iter()
                    .map(|c| Circle::new(point(c), 4, colour(&c.family).mix(0.6).filled())),
            )
            .map_err(err)?;
        let front_points: Vec<(f64, f64)> =
            front.iter().map(|&i| point(&report.cells[i])).collect();
        chart
            .draw_series(LineSeries::new(front_points, RED.stroke_width(2)))
            .map_err(err)?;
        // Labels of front points that sit together are stacked upwards.
        let mut placed: Vec<(i32, i32)> = vec![];
        let labels: Vec<(usize, i32)> = front
            .iter()
            .map(|&i| {
                let (px, py) = chart.backend_coord(&point(&report.cells[i]));
                let crowd = placed
                    .iter()
                    .filter(|(x, y)| (x - px).abs() < 90 && (y - py).abs() < 14 * 4)
                    .count() as i32;
                placed.push((px, py));
                (i, -14 - 13 * crowd)
            })
            .collect();
        chart
            .draw_series(labels.into_iter().map(|(i, dy)| {
                let c = &report.cells[i];
                EmptyElement::at(point(c))
                    + Circle::new((0, 0), 5, RED.filled())
                    + Text::new(c.technique().to_string(), (7, dy), ("sans-serif", 12))
            }))
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}
