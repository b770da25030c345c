//! `front.svg`: every point that ran cleanly (CPU load against the
//! accuracy axis, log-log), the front joined, the recommendation ringed.

use super::rule;
use crate::sweep::Sweep;
use anyhow::{Result, anyhow};
use plotters::prelude::*;
use std::path::Path;

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plotting: {e}")
}

/// The chart: log-log.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// A plotted point: load %, accuracy, on the front, recommended, the
/// table's row number.
type Plotted = (f64, f64, bool, bool, usize);

/// `front.svg`: every point that ran cleanly (CPU load against the
/// accuracy axis, log-log), the front joined, the recommendation ringed.
pub fn front_svg(path: &Path, s: &Sweep) -> Result<()> {
    let pts = plotted(s);
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let ((x0, x1), (y0, y1)) = ranges(&pts);
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}: cost against accuracy ({} points)",
                s.scene,
                s.points.len()
            ),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("CPU load, % of a core (tick p50 × rate)")
        .y_desc(s.axis.as_str())
        .x_label_formatter(&|v| format!("{v}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(err)?;
    draw_points(&mut chart, &pts, s)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

/// The points that ran cleanly with a positive load and a finite accuracy.
fn plotted(s: &Sweep) -> Vec<Plotted> {
    s.points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let (x, y) = (p.load(), s.axis.value(p));
            let clean = matches!(&p.accuracy, Ok(a) if a.failed_ticks == 0);
            (clean && x > 0.0 && y.is_finite()).then_some((
                100.0 * x,
                y.max(1e-15),
                p.pareto,
                s.recommended == Some(i),
                i,
            ))
        })
        .collect()
}

/// The axes' ranges: the points with margins, and headroom above them for
/// the legend (upper right), so it never covers one.
fn ranges(pts: &[Plotted]) -> ((f64, f64), (f64, f64)) {
    let (x0, x1) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let (y0, y1) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.1), b.max(p.1))
    });
    let x = if pts.is_empty() {
        (0.01, 100.0)
    } else {
        (x0 / 2.0, x1 * 2.0)
    };
    let y = if pts.is_empty() {
        (1e-9, 1.0)
    } else {
        (y0 / 3.0, y1 * 30.0)
    };
    (x, y)
}

/// The measured points in grey, the front joined in blue with each of its
/// points named by its row in the printed table and its knobs, the
/// recommendation ringed in red.
fn draw_points(chart: &mut Chart, pts: &[Plotted], s: &Sweep) -> Result<()> {
    let grey = RGBColor(150, 150, 150);
    let blue = RGBColor(31, 119, 180);
    let red = RGBColor(214, 39, 40);
    chart
        .draw_series(
            pts.iter()
                .filter(|p| !p.2)
                .map(|p| Circle::new((p.0, p.1), 3, grey.filled())),
        )
        .map_err(err)?
        .label("measured")
        .legend(move |(x, y)| Circle::new((x + 10, y), 3, grey.filled()));
    let mut front: Vec<(f64, f64)> = pts.iter().filter(|p| p.2).map(|p| (p.0, p.1)).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front.clone(), blue.stroke_width(2)))
        .map_err(err)?
        .label("Pareto front")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(2)));
    chart
        .draw_series(front.iter().map(|&p| Circle::new(p, 4, blue.filled())))
        .map_err(err)?;
    chart
        .draw_series(pts.iter().filter(|p| p.2).map(|p| {
            let k = &s.points[p.4].knobs;
            Text::new(
                format!(
                    "#{} {} ×{} {} Hz",
                    p.4,
                    rule(k.update),
                    k.iterations,
                    k.rate_hz
                ),
                (p.0 * 1.06, p.1 * 1.15),
                ("sans-serif", 12).into_font().color(&blue),
            )
        }))
        .map_err(err)?;
    if let Some(p) = pts.iter().find(|p| p.3) {
        chart
            .draw_series(std::iter::once(Circle::new(
                (p.0, p.1),
                9,
                red.stroke_width(2),
            )))
            .map_err(err)?
            .label("recommended")
            .legend(move |(x, y)| Circle::new((x + 10, y), 6, red.stroke_width(2)));
    }
    Ok(())
}
