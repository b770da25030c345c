//! Choi & Cremer §3.2.1, step by step on the pyramid of Fig. 6: a square
//! pyramid on its apex on a table is tilted by hand-made poses (no solver),
//! with the pre-emptive guards off so nothing but the nearest features has a
//! row. The apex touches (vertex–face); a tilt puts a base corner 1 mm
//! through the table while the apex stays on it: the monitor expands the
//! witness to the edge apex–corner (edge–face, `expansions` = 1); a roll
//! about that edge puts the next corner through: face–face (`expansions` =
//! 1 again). Every primitive's value is checked against the vertex's height
//! above the table, computed here from the pose. With the guards on, the
//! corner has a row before it touches and no expansion is needed.

use haptloop_solver::constraint::witness::{Witness, WitnessType};
use haptloop_solver::geometry::primitives::value_at;
use haptloop_solver::geometry::{ActiveSet, ContactBody, ContactSettings, Cycle, Pose3, Shape};
use nalgebra::{Rotation3, Unit, Vector3};

use crate::common::{at, cuboid};

/// Body-frame points of the pyramid (4 cm base, 4 cm tall, apex down), as
/// in `scenes/pyramid-tilt.toml`.
const APEX: [f64; 3] = [0.0, 0.0, -0.03];
const C1: [f64; 3] = [0.02, 0.02, 0.01];
const C2: [f64; 3] = [-0.02, 0.02, 0.01];
const C4: [f64; 3] = [0.02, -0.02, 0.01];

fn pyramid() -> Shape {
    Shape::Convex {
        points_m: vec![
            [0.02, 0.02, 0.01],
            [-0.02, 0.02, 0.01],
            [-0.02, -0.02, 0.01],
            [0.02, -0.02, 0.01],
            APEX,
        ],
    }
}

fn set(guards: bool) -> ActiveSet {
    let body = |shape: Shape, fixed: bool| {
        Some(ContactBody {
            collider: shape.collider().unwrap(),
            fixed,
            fingertip: false,
            friction: 0.0,
        })
    };
    ActiveSet::new(
        vec![
            body(cuboid([0.15, 0.15, 0.02]), true),
            body(pyramid(), false),
        ],
        Vec::new(),
        ContactSettings {
            guards,
            ..ContactSettings::default()
        },
    )
}

fn table() -> Pose3 {
    at([0.0, 0.0, -0.02])
}

/// The pyramid rotated by `rot` about its apex, the apex at height `z`.
fn about_apex(rot: Rotation3<f64>, z: f64) -> Pose3 {
    let apex = rot * Vector3::from(APEX);
    Pose3 {
        r: Vector3::new(0.0, 0.0, z) - apex,
        rot: rot.into_inner(),
    }
}

/// Height of a body-frame point above the table top at `pose`.
fn height(pose: &Pose3, p: [f64; 3]) -> f64 {
    pose.point(&Vector3::from(p)).z
}

/// The tilt about the horizontal axis perpendicular to the apex → C1
/// direction that brings C1 to `depth` below the table (apex on it).
fn tilt_c1(depth: f64) -> Rotation3<f64> {
    let axis = Unit::new_normalize(Vector3::new(-1.0, 1.0, 0.0));
    let rel = Vector3::from(C1) - Vector3::from(APEX);
    let phi = rel.z.atan2(rel.xy().norm());
    let theta = phi + (depth / rel.norm()).asin();
    Rotation3::from_axis_angle(&axis, theta)
}

/// `rot` (C1 on the table) rolled about the edge apex–C1 until C2 is
/// `depth` below the table.
fn roll_c2(rot: Rotation3<f64>, depth: f64) -> Rotation3<f64> {
    let edge = Unit::new_normalize(rot * (Vector3::from(C1) - Vector3::from(APEX)));
    let rel = rot * (Vector3::from(C2) - Vector3::from(APEX));
    // C2's offset from the edge line, and the roll that takes it to −depth.
    let off = rel - edge.into_inner() * rel.dot(&edge);
    let (r, h) = (off.norm(), off.z);
    let mut best = (f64::INFINITY, 0.0);
    // The sign of the roll that lowers C2: try both, keep the one that fits.
    for sign in [1.0, -1.0] {
        let start = (h / r).asin();
        let target = (-depth / r).asin();
        let psi = sign * (start - target);
        let z = (Rotation3::from_axis_angle(&edge, psi) * off).z;
        if (z + depth).abs() < best.0 {
            best = ((z + depth).abs(), psi);
        }
    }
    Rotation3::from_axis_angle(&edge, best.1) * rot
}

/// The pyramid's primitives (table = end 0, pyramid = end 1).
fn witnesses(s: &ActiveSet) -> Vec<Witness> {
    s.witnesses([0, 1]).to_vec()
}

/// Body-frame points held by the primitives of `origin`, and their values.
fn held(w: &[Witness], origin: WitnessType, pose: &Pose3) -> Vec<([f64; 3], f64)> {
    w.iter()
        .filter(|w| w.origin() == Some(origin))
        .filter_map(|w| match w {
            Witness::Plane(p) if p.point_end == 1 => Some((
                [p.point.x, p.point.y, p.point.z],
                value_at(w, &table(), pose).0,
            )),
            _ => None,
        })
        .collect()
}

fn holds(points: &[([f64; 3], f64)], p: [f64; 3], pose: &Pose3) -> bool {
    points.iter().any(|(q, v)| {
        let same = q.iter().zip(&p).all(|(a, b)| (a - b).abs() < 1e-12);
        // The primitive's value is the point's height above the table top.
        same && (v - height(pose, p)).abs() < 1e-12
    })
}

fn cycle(s: &mut ActiveSet, pose: Pose3) -> Cycle {
    s.update(&[table(), pose])
}

#[test]
fn a_tilted_pyramid_expands_vertex_face_to_edge_face_to_face_face() {
    let mut s = set(false);
    // 1. Upright, the apex 0.5 mm above the table: vertex–face on the apex.
    let upright = about_apex(Rotation3::identity(), 0.0005);
    let c = cycle(&mut s, upright);
    assert_eq!((c.tracked, c.expansions, c.backups.len()), (1, 0, 0));
    let w = witnesses(&s);
    let vf = held(&w, WitnessType::VertexFace, &upright);
    assert_eq!(vf.len(), 1, "{w:?}");
    assert!(holds(&vf, APEX, &upright));

    // 2. Tilted over the apex until C1 is 1 mm through the table: the
    // nearest features alone would hold C1 and forget the apex; the
    // expansion holds the edge apex–C1 (both its ends on the table face).
    let tilted = about_apex(tilt_c1(0.001), 0.0);
    assert!((height(&tilted, C1) + 0.001).abs() < 1e-12);
    for p in [C2, C4] {
        assert!(height(&tilted, p) > 0.01, "only C1 goes through");
    }
    let c = cycle(&mut s, tilted);
    assert_eq!(c.expansions, 1, "{c:?}");
    assert_eq!(c.tunnels, 0);
    assert_eq!(c.backups, vec![[0, 1]], "1 mm is past the 0.1 mm tolerance");
    assert!((c.max_penetration_m - 0.001).abs() < 1e-9, "{c:?}");
    let w = witnesses(&s);
    let ef = held(&w, WitnessType::EdgeFace, &tilted);
    assert_eq!(ef.len(), 2, "{w:?}");
    assert!(
        holds(&ef, APEX, &tilted) && holds(&ef, C1, &tilted),
        "{ef:?}"
    );

    // 3. Rolled about that edge until C2 is 1 mm through: the face apex–
    // C1–C2 on the table (face–face, three corners held).
    let on_edge = tilt_c1(0.0);
    let rolled = about_apex(roll_c2(on_edge, 0.001), 0.0);
    assert!((height(&rolled, C2) + 0.001).abs() < 1e-9);
    assert!(height(&rolled, C1).abs() < 1e-12);
    let c = cycle(&mut s, rolled);
    assert_eq!(c.expansions, 1, "{c:?}");
    let w = witnesses(&s);
    let ff = held(&w, WitnessType::FaceFace, &rolled);
    assert_eq!(ff.len(), 3, "{w:?}");
    for p in [APEX, C1, C2] {
        assert!(holds(&ff, p, &rolled), "{p:?} not held: {ff:?}");
    }

    // 4. Back to clean (the backup's retry, the edge 0.1 mm above the
    // table): the expanded primitives stay while they are near (C2, 2 cm
    // up, is past the window and dropped), and nothing expands again.
    let clean = about_apex(on_edge, 0.0001);
    let c = cycle(&mut s, clean);
    assert_eq!((c.expansions, c.backups.len()), (0, 0));
    let w = witnesses(&s);
    let kept = held(&w, WitnessType::FaceFace, &clean);
    assert!(
        holds(&kept, APEX, &clean) && holds(&kept, C1, &clean),
        "{w:?}"
    );
}

/// The same tilt with the guards on: C1 gets a row while it is still
/// 3 mm above the table, so when it goes through nothing needs expanding.
#[test]
fn with_the_guards_on_the_corner_is_held_before_it_touches() {
    let mut s = set(true);
    cycle(&mut s, about_apex(Rotation3::identity(), 0.0005));
    let near = about_apex(tilt_c1(-0.003), 0.0);
    cycle(&mut s, near);
    let w = witnesses(&s);
    let vf = held(&w, WitnessType::VertexFace, &near);
    assert!(holds(&vf, C1, &near), "C1 guarded at 3 mm: {w:?}");
    let c = cycle(&mut s, about_apex(tilt_c1(0.001), 0.0));
    assert_eq!(c.expansions, 0, "{c:?}");
}
