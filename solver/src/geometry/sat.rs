//! The separating-axis test of two convex polyhedra: the axis of largest
//! separation (smallest penetration) among both bodies' face normals and the
//! cross products of their edge directions, and its signed separation.
//!
//! For touching or overlapping polyhedra GJK's closest points, and with them
//! its direction, are round-off: a box resting on a table at a gap of 1e-15 m
//! may come back with the direction to one of the table's far corners, whose
//! support sets then name a vertex–vertex witness. The separating axis does
//! not degrade there — the best axis of a box on a table is the table's face
//! normal at separation 0 — and for convex polyhedra its separation is the
//! exact penetration depth (Gottschalk's theorem), so the narrow phase uses
//! it below a small gap and for every overlap. Positions and directions in
//! A's body frame unless said otherwise.

use nalgebra::{Matrix3, Vector3};

use super::polyhedron::Polyhedron;

/// The best separating axis of a pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Separation {
    /// Signed separation along `axis`, metres (negative: penetration depth).
    pub separation_m: f64,
    /// Unit axis from A toward B, A's frame.
    pub axis: Vector3<f64>,
}

/// Axes closer than this (sin of the angle) to an already tried one are
/// skipped, and edge pairs this close to parallel give no axis.
const PARALLEL_SIN: f64 = 1e-9;

/// Face axes win ties with edge axes up to this separation difference,
/// relative to the pair's size: a box on a table is face–face, not an edge
/// pair that happens to give the same separation.
const FACE_PREFERENCE: f64 = 1e-9;

/// The separating axis of A and B, with B's frame mapped into A's by
/// `rot_ba` (B → A rotation) and `t_ba` (B's origin in A's frame).
pub fn best_axis(
    a: &Polyhedron,
    b: &Polyhedron,
    rot_ba: &Matrix3<f64>,
    t_ba: &Vector3<f64>,
) -> Separation {
    let size = a.radius_m + b.radius_m;
    let tie = FACE_PREFERENCE * size;
    // Support extents along n (A's frame): max over A of a·n, min over B of b·n.
    let b_min = |n: &Vector3<f64>| {
        let nb = rot_ba.tr_mul(n);
        let base = t_ba.dot(n);
        b.vertices
            .iter()
            .map(|v| v.dot(&nb))
            .fold(f64::INFINITY, f64::min)
            + base
    };
    let a_max = |n: &Vector3<f64>| {
        a.vertices
            .iter()
            .map(|v| v.dot(n))
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let sep = |n: &Vector3<f64>| b_min(n) - a_max(n);
    let mut best = Separation {
        separation_m: f64::NEG_INFINITY,
        axis: Vector3::z(),
    };
    for f in &a.faces {
        let s = sep(&f.normal);
        if s > best.separation_m {
            best = Separation {
                separation_m: s,
                axis: f.normal,
            };
        }
    }
    for f in &b.faces {
        let n = -(rot_ba * f.normal);
        let s = sep(&n);
        if s > best.separation_m {
            best = Separation {
                separation_m: s,
                axis: n,
            };
        }
    }
    let face_best = best.separation_m;
    for da in &a.edge_directions {
        for db in &b.edge_directions {
            let db = rot_ba * db;
            let c = da.cross(&db);
            let len = c.norm();
            if len < PARALLEL_SIN {
                continue;
            }
            let n = c / len;
            for n in [n, -n] {
                let s = sep(&n);
                if s > best.separation_m && s > face_best + tie {
                    best = Separation {
                        separation_m: s,
                        axis: n,
                    };
                }
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    #[test]
    fn a_box_on_a_table_separates_along_the_table_normal() {
        let table = Polyhedron::cuboid([0.3, 0.3, 0.02]).unwrap();
        let b = Polyhedron::cuboid([0.03, 0.03, 0.03]).unwrap();
        // Table at the origin (A), box resting on it with a round-off gap.
        for gap in [-1e-15, 0.0, 1e-15, 1e-9, -2e-3] {
            let s = best_axis(
                &table,
                &b,
                &Matrix3::identity(),
                &Vector3::new(0.01, -0.02, 0.05 + gap),
            );
            assert!((s.separation_m - gap).abs() < 1e-15, "{gap}: {s:?}");
            assert!((s.axis - Vector3::z()).norm() < 1e-15, "{gap}: {s:?}");
        }
    }

    #[test]
    fn crossed_edges_separate_along_their_cross_product() {
        let c = Polyhedron::cuboid([0.1, 0.1, 0.1]).unwrap();
        let ra = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_4);
        let rb = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_4);
        let h = 0.1 * 2f64.sqrt();
        for gap in [0.004, -0.003] {
            // B relative to A: rotation A⁻¹ B, origin A⁻¹ (t).
            let rot_ba = ra.inverse() * rb;
            let t_ba = ra.inverse() * Vector3::new(0.0, 0.0, 2.0 * h + gap);
            let s = best_axis(&c, &c, rot_ba.matrix(), &t_ba);
            assert!((s.separation_m - gap).abs() < 1e-12, "{gap}: {s:?}");
            let world = ra * s.axis;
            assert!((world - Vector3::z()).norm() < 1e-9, "{world}");
        }
    }
}
