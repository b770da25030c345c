//! SVG plots of a session (plotters): the latency percentile distribution, and
//! force, constraint violation and (scenes with any) design variables and
//! objectives over time.

use crate::session::{Series, SessionOutcome};
use anyhow::{Result, anyhow};
use haptloop_rt::hist::LatencyHistogram;
use plotters::prelude::*;
use std::path::Path;

const SIZE: (u32, u32) = (900, 480);
const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plotting: {e}")
}

/// (1/(1−p), µs) points of a histogram's percentile distribution.
fn percentile_points(h: &LatencyHistogram) -> Vec<(f64, f64)> {
    if h.count() == 0 {
        return Vec::new();
    }
    h.inner()
        .iter_quantiles(5)
        .map(|v| {
            (
                v.quantile_iterated_to(),
                v.value_iterated_to().min(h.max()) as f64 / 1e3,
            )
        })
        .filter(|(q, _)| *q < 1.0)
        .map(|(q, us)| (1.0 / (1.0 - q), us.max(0.01)))
        .collect()
}

/// Lateness, compute and read → write time against percentile, log-log:
/// the usual HdrHistogram percentile plot.
///
/// In deterministic mode the scheduler runs on the mock clock, which has no
/// lateness and no compute time to show: the plot then shows the whole tick
/// and the tick without the device read, both on the monotonic clock.
pub fn latency(path: &Path, o: &SessionOutcome) -> Result<()> {
    let series: Vec<(&str, Vec<(f64, f64)>)> = if o.plan.deterministic {
        vec![
            (
                "whole tick (monotonic clock)",
                percentile_points(&o.stats.stages.tick),
            ),
            (
                "tick without device read",
                percentile_points(&o.stats.stages.tick_without_device),
            ),
        ]
    } else {
        vec![
            (
                "wake-up lateness",
                percentile_points(&o.histograms.lateness),
            ),
            ("compute", percentile_points(&o.histograms.compute)),
            (
                "device read → force write",
                percentile_points(&o.stats.read_to_write),
            ),
        ]
    };
    let xmax = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|x| x.0))
        .fold(10.0, f64::max);
    let ymax = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|x| x.1))
        .fold(1.0, f64::max);
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}: latency percentiles at {} Hz",
                o.plan.scene, o.plan.rate_hz
            ),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (1.0..xmax * 1.5).log_scale(),
            (0.01..ymax * 30.0).log_scale(),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("1/(1 − percentile): 10 = p90, 100 = p99, 1000 = p99.9")
        .y_desc("µs")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v}"))
        .draw()
        .map_err(err)?;
    for (k, (name, pts)) in series.into_iter().enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(pts, c.stroke_width(2)))
            .map_err(err)?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

/// Series over time, with optional horizontal limit lines (name, value,
/// colour). The y axis leaves headroom above the data for the legend, which
/// sits in the upper right: it never covers a curve.
fn time_plot(
    path: &Path,
    title: &str,
    y_desc: &str,
    series: &[(String, &Series, RGBColor, u32)],
    limits: &[(String, f64, RGBColor)],
    log_y: bool,
) -> Result<()> {
    let tmax = series
        .iter()
        .flat_map(|(_, s, ..)| s.points.iter().map(|p| p.0))
        .fold(1e-3, f64::max);
    let ymax = series
        .iter()
        .flat_map(|(_, s, ..)| s.points.iter().map(|p| p.1))
        .chain(limits.iter().map(|l| l.1))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70);
    // Log axis: start a decade below the smallest positive value (zeros are
    // drawn on the floor).
    let floor = series
        .iter()
        .flat_map(|(_, s, ..)| s.points.iter().map(|p| p.1))
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min)
        .min(ymax)
        / 10.0;
    let floor = if floor.is_finite() && floor > 0.0 {
        floor
    } else {
        1e-16
    };
    macro_rules! draw {
        ($chart:expr, $map:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc("session time, s")
                .y_desc(y_desc)
                .y_label_formatter(&|v| {
                    if log_y {
                        format!("{v:.0e}")
                    } else {
                        format!("{v:.2}")
                    }
                })
                .draw()
                .map_err(err)?;
            for (name, s, c, w) in series.iter() {
                let (c, w) = (*c, *w);
                chart
                    .draw_series(LineSeries::new(
                        s.points.iter().map($map),
                        c.stroke_width(w),
                    ))
                    .map_err(err)?
                    .label(name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w + 1))
                    });
            }
            for (name, v, c) in limits.iter() {
                let c = *c;
                chart
                    .draw_series(DashedLineSeries::new(
                        [(0.0, *v), (tmax, *v)].iter().map($map),
                        6,
                        4,
                        c.stroke_width(1),
                    ))
                    .map_err(err)?
                    .label(name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(1))
                    });
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.9))
                .border_style(BLACK)
                .draw()
                .map_err(err)?;
        }};
    }
    if log_y {
        let chart = builder
            .build_cartesian_2d(
                0.0..tmax,
                (floor..(ymax * 1e3).max(floor * 1e4)).log_scale(),
            )
            .map_err(err)?;
        draw!(chart, |&(t, v): &(f64, f64)| (t, v.max(floor)));
    } else {
        let chart = builder
            .build_cartesian_2d(0.0..tmax, 0.0..(ymax * 1.6).max(1e-3))
            .map_err(err)?;
        draw!(chart, |&(t, v): &(f64, f64)| (t, v));
    }
    root.present().map_err(err)
}

/// Each finger's force over time: what the device rendered (after the
/// safety layer and its own limits; every tick) and what the solver asked
/// for (the slow loop's snapshots, 100 Hz), with each device model's peak
/// and continuous force as dashed lines.
pub fn force(path: &Path, o: &SessionOutcome) -> Result<()> {
    let asked: Vec<Series> = (0..o.fingers.len())
        .map(|i| {
            let mut s = Series::default();
            s.points = o
                .track
                .samples
                .iter()
                .filter_map(|(t, x)| x.asked_n.get(i).map(|f| (t, norm(f))))
                .collect();
            s
        })
        .collect();
    let mut series: Vec<(String, &Series, RGBColor, u32)> = Vec::new();
    for (i, name) in o.fingers.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        series.push((format!("{name}: rendered"), &o.recorder.force[i], c, 2));
        // The asked force in a lighter shade of the finger's colour.
        let light = RGBColor(c.0 / 2 + 127, c.1 / 2 + 127, c.2 / 2 + 127);
        series.push((format!("{name}: asked"), &asked[i], light, 1));
    }
    let mut limits = Vec::new();
    let mut models: Vec<&str> = o.finger_devices.iter().map(String::as_str).collect();
    models.dedup();
    for m in models {
        let (peak, continuous) = limits_of(m);
        limits.push((format!("{m} peak {peak} N"), peak, RGBColor(170, 40, 40)));
        if continuous < peak {
            limits.push((
                format!("{m} continuous {continuous} N"),
                continuous,
                RGBColor(200, 130, 0),
            ));
        }
    }
    time_plot(
        path,
        &format!("{}: force on each finger", o.plan.scene),
        "|F|, N",
        &series,
        &limits,
        false,
    )
}

fn norm(f: &[f64; 3]) -> f64 {
    (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
}

/// A device model's peak and continuous force, N.
fn limits_of(model: &str) -> (f64, f64) {
    if model == haptloop_devices::VIRTUAL_MODEL {
        let p = haptloop_devices::VirtualParams::default();
        return (p.peak_force_n, p.peak_force_n);
    }
    haptloop_devices::PhantomModel::by_name(model).map_or((f64::NAN, f64::NAN), |m| {
        (m.peak_force_n, m.continuous_force_n)
    })
}

/// The largest constraint violation over time, log scale.
pub fn violation(path: &Path, o: &SessionOutcome) -> Result<()> {
    time_plot(
        path,
        &format!("{}: largest constraint violation per tick", o.plan.scene),
        "violation, m",
        &[(
            "max |C| (length rows)".into(),
            &o.recorder.violation,
            COLOURS[0],
            1,
        )],
        &[],
        true,
    )
}

/// The design variables (top, m) and the objectives' values (bottom) over
/// time: the force plot's companion in scenes with design variables or
/// objectives. Each series is drawn on its own, so each panel's axis fits
/// all of its series.
pub fn design(path: &Path, o: &SessionOutcome) -> Result<()> {
    let r = &o.recorder;
    let (vars, objs) = r
        .design_series
        .split_at(r.design_variables.min(r.design_series.len()));
    // Joint torques (at the end) are in trace.csv and summary.json only.
    let objs = &objs[..objs.len().saturating_sub(r.design_torques)];
    let names = |from: usize, n: usize| -> Vec<&str> {
        r.design_names[from..from + n]
            .iter()
            .map(|s| s.trim_end_matches("_m").trim_start_matches("objective_"))
            .collect()
    };
    let root = SVGBackend::new(path, (SIZE.0, SIZE.1 * 2)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (top, bottom) = root.split_vertically(SIZE.1);
    for (area, series, labels, title, y) in [
        (
            &top,
            vars,
            names(0, vars.len()),
            format!("{}: design variables", o.plan.scene),
            "m",
        ),
        (
            &bottom,
            objs,
            names(vars.len(), objs.len()),
            format!("{}: objectives (reported values)", o.plan.scene),
            "value",
        ),
    ] {
        panel(area, series, &labels, &title, y)?;
    }
    root.present().map_err(err)
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    series: &[Series],
    labels: &[&str],
    title: &str,
    y_desc: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let finite = || {
        series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.1.is_finite())
    };
    let tmax = finite().map(|p| p.0).fold(1e-3, f64::max);
    let (lo, hi) = finite().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
        (a.min(p.1), b.max(p.1))
    });
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
    let pad = ((hi - lo) * 0.05).max(1e-9 * (1.0 + hi.abs()));
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..tmax, (lo - pad)..(hi + pad))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("session time, s")
        .y_desc(y_desc)
        .y_label_formatter(&|v| format!("{v:.4}"))
        .draw()
        .map_err(err)?;
    for (k, (s, name)) in series.iter().zip(labels).enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(
                s.points.iter().copied().filter(|p| p.1.is_finite()),
                c.stroke_width(1),
            ))
            .map_err(err)?
            .label(name.to_string())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    if !series.is_empty() {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }
    Ok(())
}
