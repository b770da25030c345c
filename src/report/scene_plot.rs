//! `contact.svg`: the shaped bodies of a contact scene drawn in two
//! projections (side x–z, top x–y, scene frame) at six instants of the run
//! (their times in the title), fixed bodies in grey, each moving body in its
//! own colour, later instants darker, every body named where it ended up;
//! fingertip paths as lines. A silhouette is the 2-D convex hull of
//! the shape's projected outline points.

use crate::session::{BodyTrack, TrackSample};
use anyhow::{Result, anyhow};
use haptloop_solver::geometry::{Pose3, Shape};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::Path;

const SIZE: (u32, u32) = (1100, 560);
const INSTANTS: usize = 6;
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

/// Points whose convex hull is the shape (curved shapes: a ring of points
/// on each sphere, dense enough that the silhouette looks round).
fn outline(shape: &Shape) -> Vec<Vector3<f64>> {
    let ball = |c: Vector3<f64>, r: f64, out: &mut Vec<Vector3<f64>>| {
        for i in 0..12 {
            let th = std::f64::consts::PI * (i as f64 + 0.5) / 12.0;
            for j in 0..24 {
                let ph = std::f64::consts::TAU * j as f64 / 24.0;
                out.push(c + r * Vector3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
            }
        }
        out.push(c + Vector3::new(0.0, 0.0, r));
        out.push(c - Vector3::new(0.0, 0.0, r));
    };
    let mut out = Vec::new();
    match shape {
        Shape::Box { half_extents_m: h } => {
            for sx in [-1.0, 1.0] {
                for sy in [-1.0, 1.0] {
                    for sz in [-1.0, 1.0] {
                        out.push(Vector3::new(sx * h[0], sy * h[1], sz * h[2]));
                    }
                }
            }
        }
        Shape::Sphere { radius_m } => ball(Vector3::zeros(), *radius_m, &mut out),
        Shape::Capsule {
            half_height_m,
            radius_m,
        } => {
            ball(Vector3::new(0.0, 0.0, *half_height_m), *radius_m, &mut out);
            ball(Vector3::new(0.0, 0.0, -*half_height_m), *radius_m, &mut out);
        }
        Shape::Convex { points_m } => out.extend(points_m.iter().map(|p| Vector3::from(*p))),
    }
    out
}

/// Andrew's monotone chain: the convex hull of 2-D points, counter-clockwise.
fn hull(mut p: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut h: Vec<(f64, f64)> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let it: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in it {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

fn pose_of(r: &[f64; 3], q: &[f64; 4]) -> Pose3 {
    let u = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
    Pose3 {
        r: Vector3::from(*r),
        rot: u.to_rotation_matrix().into_inner(),
    }
}

/// The chart of one panel.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// What `contact.svg` draws: the shapes' outlines and the sampled instants.
struct Shapes<'t> {
    /// The shaped moving bodies: (index into the track's bodies, outline).
    shaped: Vec<(usize, Vec<Vector3<f64>>)>,
    /// The shaped fixed bodies: name, outline, pose.
    fixed: Vec<(&'t str, Vec<Vector3<f64>>, Pose3)>,
    /// The track's samples: time, poses.
    samples: Vec<(f64, &'t TrackSample)>,
    /// The samples drawn (`INSTANTS` of them, evenly spread).
    picks: Vec<usize>,
}

impl<'t> Shapes<'t> {
    /// The shapes and instants of the track `t`.
    fn of(t: &'t BodyTrack) -> Self {
        let shaped: Vec<(usize, Vec<Vector3<f64>>)> = t
            .bodies
            .iter()
            .enumerate()
            .filter_map(|(k, b)| b.shape.as_ref().map(|s| (k, outline(s))))
            .collect();
        let fixed: Vec<(&str, Vec<Vector3<f64>>, Pose3)> = t
            .fixed
            .iter()
            .filter_map(|(n, s, p)| s.as_ref().map(|s| (n.as_str(), outline(s), *p)))
            .collect();
        let samples: Vec<(f64, &TrackSample)> = t.samples.iter().collect();
        let n = samples.len();
        let picks: Vec<usize> = if n == 0 {
            Vec::new()
        } else {
            (0..INSTANTS)
                .map(|k| k * (n - 1) / (INSTANTS - 1).max(1))
                .collect()
        };
        Self {
            shaped,
            fixed,
            samples,
            picks,
        }
    }

    /// The outline `o` of body `b` placed at sample `k`.
    fn world(&self, k: usize, b: usize, o: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let (r, q) = &self.samples[k].1.poses[b];
        let p = pose_of(r, q);
        o.iter().map(|v| p.point(v)).collect()
    }

    /// The box the panels show: the moving bodies at the picked instants
    /// (a large table must not shrink them to dots), else the fixed ones.
    fn bounds(&self) -> (Vector3<f64>, Vector3<f64>) {
        let moving: Vec<Vector3<f64>> = self
            .picks
            .iter()
            .flat_map(|&k| (self.shaped.iter()).flat_map(move |(b, o)| self.world(k, *b, o)))
            .collect();
        let all: Vec<Vector3<f64>> = (self.fixed.iter())
            .flat_map(|(_, o, p)| o.iter().map(|v| p.point(v)).collect::<Vec<_>>())
            .collect();
        let focus = if moving.is_empty() { &all } else { &moving };
        let lo = focus
            .iter()
            .fold(Vector3::repeat(f64::INFINITY), |a, v| a.inf(v));
        let hi = focus
            .iter()
            .fold(Vector3::repeat(f64::NEG_INFINITY), |a, v| a.sup(v));
        (lo, hi)
    }
}

/// One panel's projection and window.
struct View {
    /// The horizontal and vertical axes (0 x, 1 y, 2 z).
    ax: usize,
    ay: usize,
    /// The window's centre and half width, m.
    cx: f64,
    cy: f64,
    half: f64,
}

impl View {
    /// The projection on axes (`ax`, `ay`) of the box (`lo`, `hi`) with a
    /// 50 % margin.
    fn new(ax: usize, ay: usize, lo: &Vector3<f64>, hi: &Vector3<f64>) -> Self {
        let (cx, cy) = ((lo[ax] + hi[ax]) / 2.0, (lo[ay] + hi[ay]) / 2.0);
        let half = ((hi[ax] - lo[ax]).max(hi[ay] - lo[ay]) * 0.75).max(1e-3);
        Self {
            ax,
            ay,
            cx,
            cy,
            half,
        }
    }

    fn project(&self, v: &Vector3<f64>) -> (f64, f64) {
        (v[self.ax], v[self.ay])
    }

    fn inside(&self, p: (f64, f64)) -> bool {
        (p.0 - self.cx).abs() < self.half && (p.1 - self.cy).abs() < self.half
    }
}

/// The centre of a polygon's vertices.
fn centre(h: &[(f64, f64)]) -> (f64, f64) {
    let k = h.len().max(1) as f64;
    (
        h.iter().map(|p| p.0).sum::<f64>() / k,
        h.iter().map(|p| p.1).sum::<f64>() / k,
    )
}

/// A body's name at `at`, in colour `c`.
fn label(name: &str, at: (f64, f64), c: RGBColor) -> Text<'static, (f64, f64), String> {
    Text::new(
        name.to_string(),
        at,
        ("sans-serif", 13).into_font().color(&c),
    )
}

/// Draws `contact.svg` (see the module docs).
pub fn contact(path: &Path, scene: &str, t: &BodyTrack) -> Result<()> {
    let shapes = Shapes::of(t);
    let (lo, hi) = shapes.bounds();
    let times: Vec<String> = (shapes.picks.iter())
        .map(|&k| format!("{:.2}", shapes.samples[k].0))
        .collect();
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled(
            &format!(
                "{scene}: shaped bodies at t = {} s (lighter → darker)",
                times.join(", ")
            ),
            ("sans-serif", 18),
        )
        .map_err(err)?;
    let panels = root.split_evenly((1, 2));
    for (panel, (ax, ay, xl, yl)) in panels
        .iter()
        .zip([(0usize, 2usize, "x, m", "z, m"), (0, 1, "x, m", "y, m")])
    {
        let view = View::new(ax, ay, &lo, &hi);
        let title = if ay == 2 {
            "side (x–z)"
        } else {
            "top (x–y)"
        };
        let (cx, cy, half) = (view.cx, view.cy, view.half);
        let mut chart = ChartBuilder::on(panel)
            .caption(title, ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(cx - half..cx + half, cy - half..cy + half)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(xl)
            .y_desc(yl)
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.3}"))
            .draw()
            .map_err(err)?;
        draw_fixed(&mut chart, &shapes, &view)?;
        draw_moving(&mut chart, &shapes, &view, t)?;
        draw_fingertips(&mut chart, &shapes, &view, t)?;
    }
    root.present().map_err(err)
}

/// The fixed bodies in grey, each named at the upper left of the part of
/// it in view, clear of the moving bodies at the centre.
fn draw_fixed(chart: &mut Chart, shapes: &Shapes, view: &View) -> Result<()> {
    let (cx, cy, half) = (view.cx, view.cy, view.half);
    for (name, o, p) in &shapes.fixed {
        let h = hull(o.iter().map(|v| view.project(&p.point(v))).collect());
        let (x0, y1) = h
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.1))
            });
        let at = (
            x0.max(cx - half * 0.95),
            y1.min(cy + half * 0.95) - half * 0.06,
        );
        chart
            .draw_series(std::iter::once(Polygon::new(
                h,
                RGBColor(170, 170, 170).mix(0.5),
            )))
            .map_err(err)?;
        if view.inside(at) {
            chart
                .draw_series(std::iter::once(label(name, at, RGBColor(90, 90, 90))))
                .map_err(err)?;
        }
    }
    Ok(())
}

/// The moving bodies at each picked instant, later ones darker, named at
/// the last instant, where they ended up.
fn draw_moving(chart: &mut Chart, shapes: &Shapes, view: &View, t: &BodyTrack) -> Result<()> {
    let picks = &shapes.picks;
    for (step, &k) in picks.iter().enumerate() {
        let alpha = 0.15 + 0.6 * step as f64 / (INSTANTS - 1).max(1) as f64;
        for (b, o) in &shapes.shaped {
            let h = hull(
                shapes
                    .world(k, *b, o)
                    .iter()
                    .map(|v| view.project(v))
                    .collect(),
            );
            let c = COLOURS[b % COLOURS.len()];
            let mut closed = h.clone();
            if let Some(f) = h.first() {
                closed.push(*f);
            }
            let at = centre(&h);
            chart
                .draw_series(std::iter::once(Polygon::new(h, c.mix(alpha * 0.5))))
                .map_err(err)?;
            chart
                .draw_series(std::iter::once(PathElement::new(closed, c.mix(alpha))))
                .map_err(err)?;
            if step + 1 == picks.len() {
                chart
                    .draw_series(std::iter::once(label(&t.bodies[*b].name, at, BLACK)))
                    .map_err(err)?;
            }
        }
    }
    Ok(())
}

/// The fingertips' paths over every sample.
fn draw_fingertips(chart: &mut Chart, shapes: &Shapes, view: &View, t: &BodyTrack) -> Result<()> {
    for (f, _) in (shapes.shaped.iter()).filter(|(b, _)| t.bodies[*b].fingertip) {
        let c = COLOURS[f % COLOURS.len()];
        let path: Vec<(f64, f64)> = (shapes.samples.iter())
            .map(|s| view.project(&Vector3::from(s.1.poses[*f].0)))
            .collect();
        chart
            .draw_series(std::iter::once(PathElement::new(path, c.stroke_width(1))))
            .map_err(err)?;
    }
    Ok(())
}
