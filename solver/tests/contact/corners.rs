//! Two equal boxes stacked corner past corner: the upper one shifted by
//! 0.5 mm in −x and +y, so its (+x, +y) corner hangs over no face of the
//! lower box (beyond its +y edge) and the lower box's (+x, +y) corner over
//! no face of the upper one (beyond its +x edge). Neither corner has a
//! vertex guard; the two edges that meet there cross 1.25 % of their
//! length from those corners, where the edge guards used to defer to the
//! vertex guards. In `stack` after long host stalls that left the top box
//! sinking 2.66 mm through such a corner in one cycle without any row
//! (BENCHMARKS.md, issue 23, "edge guards at the corners").

use haptloop_solver::constraint::witness::Witness;
use haptloop_solver::geometry::primitives::value_at;
use haptloop_solver::geometry::{ActiveSet, ContactBody, ContactSettings, Pose3};

use nalgebra::{Rotation3, Vector3};

use crate::common::{at, cuboid};

const H: f64 = 0.02;
const SHIFT: f64 = 0.0005;

fn set() -> ActiveSet {
    let body = || {
        Some(ContactBody {
            collider: cuboid([H, H, H]).collider().unwrap(),
            fixed: false,
            fingertip: false,
            friction: 0.0,
        })
    };
    ActiveSet::new(vec![body(), body()], Vec::new(), ContactSettings::default())
}

/// The upper box `gap` above the lower one, shifted, and tilted 0.01 rad
/// about x (its −y side down): the nearest features are its −y bottom edge
/// and the lower box's top face (an edge–face pair), so no face–face
/// reduction makes the corners' crossing rows.
fn upper(gap: f64) -> Pose3 {
    Pose3 {
        r: Vector3::new(-SHIFT, SHIFT, 2.0 * H + gap),
        rot: Rotation3::from_axis_angle(&Vector3::x_axis(), 0.01).into_inner(),
    }
}

/// Eq. 3 of the lower box's +y top edge (along x) against the upper box's
/// +x bottom edge, from the poses: the edge's line meets the plane of the
/// upper box's +x face at ip; the value is ip's offset from the upper edge
/// along that edge's normal (+x and −z halved, upper frame).
fn crossing_value(up: &Pose3) -> f64 {
    let v = Vector3::new(-H, H, H);
    let e = Vector3::x();
    let n1 = up.rot * Vector3::x();
    let f = up.point(&Vector3::new(H, -H, -H));
    let sn = up.rot * Vector3::new(1.0, 0.0, -1.0).normalize();
    let ip = v + e * ((f - v).dot(&n1) / e.dot(&n1));
    (ip - f).dot(&sn)
}

/// The edge–edge rows of the pair and their values at the poses.
fn edge_rows(s: &ActiveSet, lower: &Pose3, up: &Pose3) -> Vec<f64> {
    s.witnesses([0, 1])
        .iter()
        .filter(|w| matches!(w, Witness::EdgeEdge(_)))
        .map(|w| value_at(w, lower, up).0)
        .collect()
}

/// The upper box 1 mm above and tilted: the lower box's +y top edge and
/// the upper box's +x bottom edge cross near (H − SHIFT, H) in plan, 1.25 %
/// of both edges from the hanging corners. Its guard reads what Eq. 3 gives
/// from the poses (0.844 mm). Before the change the pair had no
/// row there (the crossing within 5 % of both ends): the test fails on
/// 4a8f1a9 with only the edge–face crossing's row, 0.566 mm.
#[test]
fn the_corner_no_vertex_guard_holds_has_an_edge_row() {
    let mut s = set();
    let lower = at([0.0, 0.0, 0.0]);
    let up = upper(0.001);
    s.update(&[lower, up]);
    let rows = edge_rows(&s, &lower, &up);
    let expected = crossing_value(&up);
    assert!(expected > 0.001 / 2f64.sqrt(), "{expected}");
    assert!(
        rows.iter().any(|v| (v - expected).abs() < 1e-12),
        "no edge row reading {expected} m: {rows:?} ({:?})",
        s.witnesses([0, 1])
    );
}
