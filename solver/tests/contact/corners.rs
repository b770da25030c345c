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

use nalgebra::{Quaternion, Rotation3, UnitQuaternion, Vector3};

use crate::common::{at, cuboid};

const H: f64 = 0.02;
const SHIFT: f64 = 0.0005;

fn set() -> ActiveSet {
    set_with(ContactSettings::default())
}

fn set_with(settings: ContactSettings) -> ActiveSet {
    let body = || {
        Some(ContactBody {
            collider: cuboid([H, H, H]).collider().unwrap(),
            fixed: false,
            fingertip: false,
            friction: 0.0,
        })
    };
    ActiveSet::new(vec![body(), body()], Vec::new(), settings)
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

/// A pose from a position and a unit quaternion [w, x, y, z].
fn pose(r: [f64; 3], q: [f64; 4]) -> Pose3 {
    let q = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
    Pose3 {
        r: Vector3::from(r),
        rot: q.to_rotation_matrix().into_inner(),
    }
}

/// The bottom and middle boxes of `stack` at tick 704 of `run stack
/// --deterministic --stall 0.65:20 --stall 1.15:20 …` (35 ms after a
/// 20-period stall; the snapshot whose witness table threw the top box off
/// the table at 75d705a): the middle box yawed 1.4 mrad against the bottom
/// one and tilted 1.3 mrad, standing on it 15 µm apart in plan, so its
/// (+x, −y) bottom corner and the bottom box's (+x, −y) top corner are
/// within microns of each other and neither is held by a vertex–face row.
/// The bodies touch along z, so no row that reads a penetration (a
/// negative value: the rows that push) may read a sideways slide of the
/// middle box (5 µm in +x and in +y): a slide over a face keeps every
/// vertex's height over it and the crossing of two top/bottom edges at the
/// same height (closed form, to 2 % of the slide for the tilt). At
/// 75d705a the bottom box's +x top edge (along y) and the middle box's
/// (+x, −y) side edge (vertical) had their closest approach inside both,
/// and their Eq. 3 row (a vertical separating plane at 45° between +x and
/// −y) read the plan offset, −11.5 µm, and moved by −3.5 µm with a 5 µm
/// slide in +x: the next tick it tipped the bottom box 0.7° and the column
/// threw its top box off the table (BENCHMARKS.md, issue 23, "the throws").
/// The test is `ContactSettings::edge_cones`, off by default; with it off
/// this fails as at 75d705a.
#[test]
fn stacked_corners_get_no_row_that_reads_a_slide() {
    let mut s = set_with(ContactSettings {
        edge_cones: true,
        ..ContactSettings::default()
    });
    let lower = pose(
        [
            0.008527006523355887,
            -9.115728774887861e-6,
            0.01999999996001733,
        ],
        [
            0.9999975759318555,
            -3.318594099306401e-10,
            -2.5679200932001743e-10,
            0.0022018565051537303,
        ],
    );
    let up = pose(
        [
            0.008532959305569363,
            1.269771042660653e-6,
            0.0599999924271513,
        ],
        [
            0.9999955397532702,
            -0.0004578453187206679,
            0.0004557823336813718,
            0.00291606760786894,
        ],
    );
    s.update(&[lower, up]);
    let rows = s.witnesses([0, 1]).to_vec();
    let pushing = rows
        .iter()
        .filter(|w| value_at(w, &lower, &up).0 < 0.0)
        .count();
    assert!(pushing >= 2, "{pushing} rows read the contact: {rows:?}");
    let slide = 5e-6;
    for dir in [Vector3::x(), Vector3::y()] {
        let slid = Pose3 {
            r: up.r + dir * slide,
            rot: up.rot,
        };
        for w in &rows {
            let before = value_at(w, &lower, &up).0;
            if before >= 0.0 {
                continue;
            }
            let after = value_at(w, &lower, &slid).0;
            assert!(
                (after - before).abs() < 0.02 * slide,
                "a row reads the slide along {dir:?}: {before} m → {after} m ({w:?})"
            );
        }
    }
}
