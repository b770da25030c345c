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

/// The upper box `gap` above the lower one, shifted.
fn upper(gap: f64) -> Pose3 {
    at([-SHIFT, SHIFT, 2.0 * H + gap])
}

/// The edge–edge rows of the pair and their values at the poses.
fn edge_rows(s: &ActiveSet, lower: &Pose3, up: &Pose3) -> Vec<f64> {
    s.witnesses([0, 1])
        .iter()
        .filter(|w| matches!(w, Witness::EdgeEdge(_)))
        .map(|w| value_at(w, lower, up).0)
        .collect()
}

/// The upper box 1 mm above: the lower box's +y top edge (along x) and the
/// upper box's +x bottom edge (along y) cross at (H − SHIFT, H) in plan, a
/// gap apart. The guard of that crossing (Eq. 3) measures the separation
/// along the upper edge's normal (−z and +x halved), so it reads gap / √2.
/// The opposite corners, (−x, −y), are the same crossing turned half a
/// turn. Before the change no edge–edge row was made at all (both crossings
/// within 5 % of an end).
#[test]
fn the_corner_no_vertex_guard_holds_has_an_edge_row() {
    let mut s = set();
    let lower = at([0.0, 0.0, 0.0]);
    let gap = 0.001;
    let up = upper(gap);
    s.update(&[lower, up]);
    let rows = edge_rows(&s, &lower, &up);
    let expected = gap / 2f64.sqrt();
    let held = rows
        .iter()
        .filter(|v| (*v - expected).abs() < 1e-12)
        .count();
    assert_eq!(
        held,
        2,
        "no edge row reading {expected} m: {rows:?} ({:?})",
        s.witnesses([0, 1])
    );
}
