//! A cluttered table (Choi & Cremer §1: "scenes cluttered with large
//! numbers of objects, many of them in contact"): `n` small convex bodies
//! standing on a fixed table, and a larger box held by a rigid finger that
//! is dragged through them.
//!
//! The objects sit on a jittered square grid 4 cm apart (so the density,
//! not the table, is fixed: a table of `n` objects has `n` grid cells), each
//! a box or a hexagonal prism of 12–20 mm with a random turn about the
//! vertical; all rest on the table (the active set tracks `n` resting
//! pairs). The dragged box starts outside the clutter, on the table, at the
//! middle row.

use super::GRAVITY_M_S2;
use crate::geometry::Shape;
use crate::{BodySpec, FingerSpec, ModelBuilder};

/// Spacing of the grid the objects stand on, metres.
pub const CLUTTER_SPACING_M: f64 = 0.04;

/// Half extent of the dragged box, metres.
pub const DRAGGED_HALF_M: f64 = 0.015;

/// A small deterministic generator (SplitMix64): the clutter is the same on
/// every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Grid cells per side for `n` objects.
pub fn clutter_side(n: usize) -> usize {
    (n as f64).sqrt().ceil() as usize
}

/// The cluttered table with `n` objects (see the module docs), kinematic
/// (no inertial motion is implied; the scene decides). The finger `hand`
/// holds the dragged box rigidly at its top.
pub fn cluttered_builder(n: usize) -> ModelBuilder {
    let mut b = ModelBuilder::new();
    b.gravity(GRAVITY_M_S2);
    let side = clutter_side(n).max(1);
    let extent = side as f64 * CLUTTER_SPACING_M;
    let half_table = extent / 2.0 + 0.1;
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(Shape::Box {
                half_extents_m: [half_table, half_table, 0.02],
            }),
    );
    let mut rng = Rng(0x5EED_C1A7);
    for k in 0..n {
        let (i, j) = (k % side, k / side);
        let x = (i as f64 + 0.5) * CLUTTER_SPACING_M - extent / 2.0
            + (rng.next() - 0.5) * 0.2 * CLUTTER_SPACING_M;
        let y = (j as f64 + 0.5) * CLUTTER_SPACING_M - extent / 2.0
            + (rng.next() - 0.5) * 0.2 * CLUTTER_SPACING_M;
        let half = 0.006 + 0.004 * rng.next();
        let height = 0.006 + 0.004 * rng.next();
        let turn = rng.next() * std::f64::consts::PI;
        let shape = if k % 2 == 0 {
            Shape::Box {
                half_extents_m: [half, half * (0.7 + 0.3 * rng.next()), height],
            }
        } else {
            let points = (0..12)
                .map(|m| {
                    let a = std::f64::consts::TAU * (m % 6) as f64 / 6.0;
                    let z = if m < 6 { -height } else { height };
                    [half * a.cos(), half * a.sin(), z]
                })
                .collect();
            Shape::Convex { points_m: points }
        };
        let (s, c) = (turn / 2.0).sin_cos();
        b.body(
            BodySpec::new(format!("object{k}"))
                .at([x, y, height])
                .oriented([c, 0.0, 0.0, s])
                .shape(shape)
                .density(600.0),
        );
    }
    let start = [-extent / 2.0 - 0.05, 0.0, DRAGGED_HALF_M];
    b.body(
        BodySpec::new("dragged")
            .at(start)
            .shape(Shape::Box {
                half_extents_m: [DRAGGED_HALF_M; 3],
            })
            .density(600.0),
    );
    b.finger(FingerSpec::rigid(
        "hand",
        "dragged",
        [0.0, 0.0, DRAGGED_HALF_M],
    ));
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clutter_has_n_objects_resting_on_the_table_without_overlap() {
        let m = cluttered_builder(100).build().unwrap();
        // table + 100 objects + dragged.
        assert_eq!(m.bodies().len(), 102);
        let colliders: Vec<_> = m.bodies()[1..]
            .iter()
            .map(|b| b.shape.as_ref().unwrap().collider().unwrap())
            .collect();
        for (k, b) in m.bodies()[1..].iter().enumerate() {
            // Resting on the table: the lowest point at z = 0.
            let shape = b.shape.as_ref().unwrap();
            let low = match shape {
                Shape::Box { half_extents_m } => b.position_m.z - half_extents_m[2],
                Shape::Convex { points_m } => {
                    b.position_m.z + points_m.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min)
                }
                _ => unreachable!(),
            };
            assert!(low.abs() < 1e-12, "body {k} bottom at {low}");
        }
        // No two objects overlap: their bounding circles in the table plane
        // are apart (jitter ±4 mm, radii ≤ 14 mm, grid 40 mm).
        let n = colliders.len();
        for a in 0..n {
            for c in a + 1..n {
                let (pa, pc) = (m.bodies()[1 + a].position_m, m.bodies()[1 + c].position_m);
                let d = ((pa.x - pc.x).powi(2) + (pa.y - pc.y).powi(2)).sqrt();
                let reach = |k: usize| match m.bodies()[1 + k].shape.as_ref().unwrap() {
                    Shape::Box { half_extents_m: h } => h[0].hypot(h[1]),
                    _ => colliders[k].radius_m,
                };
                assert!(d > reach(a) + reach(c), "objects {a} and {c} overlap");
            }
        }
    }
}
