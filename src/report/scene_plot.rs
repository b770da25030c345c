//! `contact.svg`: the shaped bodies of a contact scene drawn in two
//! projections (side x–z, top x–y, scene frame) at six instants of the run
//! (their times in the title), fixed bodies in grey, each moving body in its
//! own colour, later instants darker, every body named where it ended up;
//! fingertip paths as lines. A silhouette is the 2-D convex hull of
//! the shape's projected outline points.

use crate::session::BodyTrack;
use anyhow::{Result, anyhow};
use haptloop_solver::geometry::{Pose3, Shape};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
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

/// Draws `contact.svg` (see the module docs).
pub fn contact(path: &Path, scene: &str, t: &BodyTrack) -> Result<()> {
    // The shaped moving bodies: (index into the track's bodies, outline).
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
    let samples: Vec<(f64, &crate::session::TrackSample)> = t.samples.iter().collect();
    let n = samples.len();
    let picks: Vec<usize> = if n == 0 {
        Vec::new()
    } else {
        (0..INSTANTS)
            .map(|k| k * (n - 1) / (INSTANTS - 1).max(1))
            .collect()
    };
    let world = |k: usize, b: usize, o: &[Vector3<f64>]| -> Vec<Vector3<f64>> {
        let (r, q) = &samples[k].1.poses[b];
        let p = pose_of(r, q);
        o.iter().map(|v| p.point(v)).collect()
    };
    // Keep the moving bodies in view: a large table must not shrink them to
    // dots. The window covers the moving bodies with a 50 % margin.
    let moving: Vec<Vector3<f64>> = picks
        .iter()
        .flat_map(|&k| shaped.iter().flat_map(move |(b, o)| world(k, *b, o)))
        .collect();
    let all: Vec<Vector3<f64>> = fixed
        .iter()
        .flat_map(|(_, o, p)| o.iter().map(|v| p.point(v)).collect::<Vec<_>>())
        .collect();
    let focus = if moving.is_empty() { &all } else { &moving };
    let lo = focus
        .iter()
        .fold(Vector3::repeat(f64::INFINITY), |a, v| a.inf(v));
    let hi = focus
        .iter()
        .fold(Vector3::repeat(f64::NEG_INFINITY), |a, v| a.sup(v));
    let times: Vec<String> = picks
        .iter()
        .map(|&k| format!("{:.2}", samples[k].0))
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
        let (cx, cy) = ((lo[ax] + hi[ax]) / 2.0, (lo[ay] + hi[ay]) / 2.0);
        let half = ((hi[ax] - lo[ax]).max(hi[ay] - lo[ay]) * 0.75).max(1e-3);
        let title = if ay == 2 {
            "side (x–z)"
        } else {
            "top (x–y)"
        };
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
        let project = |v: &Vector3<f64>| (v[ax], v[ay]);
        let centre = |h: &[(f64, f64)]| {
            let k = h.len().max(1) as f64;
            (
                h.iter().map(|p| p.0).sum::<f64>() / k,
                h.iter().map(|p| p.1).sum::<f64>() / k,
            )
        };
        let inside = |p: (f64, f64)| (p.0 - cx).abs() < half && (p.1 - cy).abs() < half;
        let label = |name: &str, at: (f64, f64), c: RGBColor| {
            Text::new(
                name.to_string(),
                at,
                ("sans-serif", 13).into_font().color(&c),
            )
        };
        for (name, o, p) in &fixed {
            let h = hull(o.iter().map(|v| project(&p.point(v))).collect());
            // A fixed body's name at the upper left of the part of it in
            // view, clear of the moving bodies at the centre.
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
            if inside(at) {
                chart
                    .draw_series(std::iter::once(label(name, at, RGBColor(90, 90, 90))))
                    .map_err(err)?;
            }
        }
        for (step, &k) in picks.iter().enumerate() {
            let alpha = 0.15 + 0.6 * step as f64 / (INSTANTS - 1).max(1) as f64;
            for (b, o) in &shaped {
                let h = hull(world(k, *b, o).iter().map(&project).collect());
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
                // Names at the last instant, where the bodies ended up.
                if step + 1 == picks.len() {
                    chart
                        .draw_series(std::iter::once(label(&t.bodies[*b].name, at, BLACK)))
                        .map_err(err)?;
                }
            }
        }
        for (f, _) in shaped.iter().filter(|(b, _)| t.bodies[*b].fingertip) {
            let c = COLOURS[f % COLOURS.len()];
            let path: Vec<(f64, f64)> = samples
                .iter()
                .map(|s| project(&Vector3::from(s.1.poses[*f].0)))
                .collect();
            chart
                .draw_series(std::iter::once(PathElement::new(path, c.stroke_width(1))))
                .map_err(err)?;
        }
    }
    root.present().map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hull_of_a_square_and_its_centre_is_the_square() {
        let h = hull(vec![
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.5, 0.5),
        ]);
        assert_eq!(h.len(), 4);
        let area: f64 = (0..h.len())
            .map(|i| {
                let (a, b) = (h[i], h[(i + 1) % h.len()]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f64>()
            / 2.0;
        assert!((area - 1.0).abs() < 1e-12, "{area}");
    }
}
