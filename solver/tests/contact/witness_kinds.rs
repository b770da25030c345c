//! Each of Choi & Cremer's six witness kinds (§3.1), built by the active set
//! on hand-made geometry whose distance is known exactly: the features it
//! names, the primitives it reduces them to, and that every primitive's
//! value is that distance. Then degenerate geometry (parallel edges,
//! coplanar faces, coincident vertices, touching at a vertex, coincident
//! sphere centres): never a NaN in a value or a gradient.

use haptloop_solver::constraint::witness::{Witness, WitnessType};
use haptloop_solver::geometry::primitives::value_at;
use haptloop_solver::geometry::{ActiveSet, ContactBody, ContactSettings, Pose3, Shape};
use haptloop_solver::{BodySpec, ModelBuilder};
use nalgebra::{Rotation3, Vector3};

use crate::common::{at, cuboid};

const H: f64 = 0.05;
const GAP: f64 = 0.003;

fn body(shape: Shape, fixed: bool) -> Option<ContactBody> {
    Some(ContactBody {
        collider: shape.collider().unwrap(),
        fixed,
        fingertip: false,
        friction: 0.0,
    })
}

/// The witnesses the active set builds for shape `a` at `pa` against fixed
/// shape `b` at `pb`.
fn witnesses(a: Shape, pa: Pose3, b: Shape, pb: Pose3) -> Vec<Witness> {
    let mut set = ActiveSet::new(
        vec![body(b, true), body(a, false)],
        Vec::new(),
        ContactSettings::default(),
    );
    let cycle = set.update(&[pb, pa]);
    assert_eq!(cycle.tracked, 1, "the pair is within the contact distance");
    set.witnesses([0, 1]).to_vec()
}

/// Values of `w` (pair order: end 0 the fixed `b`, end 1 `a`).
fn values(w: &[Witness], pa: &Pose3, pb: &Pose3) -> Vec<f64> {
    w.iter().map(|w| value_at(w, pb, pa).0).collect()
}

fn kinds(w: &[Witness]) -> Vec<WitnessType> {
    w.iter().filter_map(|w| w.origin()).collect()
}

/// A cube of half size H rotated so that its vertex (1, 1, 1) points along −z.
fn vertex_down() -> Rotation3<f64> {
    Rotation3::rotation_between(&Vector3::new(1.0, 1.0, 1.0), &-Vector3::z()).unwrap()
}

fn rot_pose(r: Vector3<f64>, rot: Rotation3<f64>) -> Pose3 {
    Pose3 {
        r,
        rot: rot.into_inner(),
    }
}

fn corner_depth() -> f64 {
    H * 3f64.sqrt()
}

#[test]
fn vertex_face() {
    let cube = cuboid([H; 3]);
    let pb = at([0.0, 0.0, 0.0]);
    let pa = rot_pose(
        Vector3::new(0.01, -0.02, H + GAP + corner_depth()),
        vertex_down(),
    );
    let w = witnesses(cube.clone(), pa, cube, pb);
    assert!(
        kinds(&w).contains(&WitnessType::VertexFace),
        "{:?}",
        kinds(&w)
    );
    // The vertex–face row itself holds exactly the gap; pre-emptive
    // neighbours (§3.2.1) are farther.
    let v = values(&w, &pa, &pb);
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    assert!((min - GAP).abs() < 1e-12, "{v:?}");
}

#[test]
fn vertex_edge_is_held_by_the_separating_plane_through_the_edge() {
    let cube = cuboid([H; 3]);
    // B: an edge along y on top (rotated 45° about y).
    let rb = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_4);
    let pb = rot_pose(Vector3::zeros(), rb);
    let top = H * 2f64.sqrt();
    let pa = rot_pose(
        Vector3::new(0.0, 0.01, top + GAP + corner_depth()),
        vertex_down(),
    );
    let w = witnesses(cube.clone(), pa, cube, pb);
    assert_eq!(kinds(&w)[0], WitnessType::VertexEdge, "{:?}", kinds(&w));
    // The plane through the edge with the mean of its faces' normals (+z):
    // the vertex straight above is GAP from it.
    assert!((values(&w, &pa, &pb)[0] - GAP).abs() < 1e-12);
}

#[test]
fn vertex_vertex_is_held_by_the_separating_plane_through_the_vertex() {
    let cube = cuboid([H; 3]);
    let up = Rotation3::rotation_between(&Vector3::new(1.0, 1.0, 1.0), &Vector3::z()).unwrap();
    let pb = rot_pose(Vector3::zeros(), up);
    let pa = rot_pose(
        Vector3::new(0.0, 0.0, 2.0 * corner_depth() + GAP),
        vertex_down(),
    );
    let w = witnesses(cube.clone(), pa, cube, pb);
    assert_eq!(kinds(&w)[0], WitnessType::VertexVertex, "{:?}", kinds(&w));
    assert!((values(&w, &pa, &pb)[0] - GAP).abs() < 1e-12);
}

#[test]
fn edge_edge_is_held_through_the_intersection_point() {
    let cube = cuboid([H; 3]);
    // B: edge along x on top; A: edge along y underneath, crossing it.
    let rb = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_4);
    let ra = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_4);
    let h = H * 2f64.sqrt();
    let pb = rot_pose(Vector3::zeros(), rb);
    let pa = rot_pose(Vector3::new(0.0, 0.0, 2.0 * h + GAP), ra);
    let w = witnesses(cube.clone(), pa, cube, pb);
    assert_eq!(kinds(&w)[0], WitnessType::EdgeEdge, "{:?}", kinds(&w));
    assert!(matches!(w[0], Witness::EdgeEdge(_)));
    // Eq. 3: (IP − Fp)·Spn = the gap along the separating normal.
    assert!((values(&w, &pa, &pb)[0] - GAP).abs() < 1e-12);
}

#[test]
fn edge_face_reduces_to_its_endpoints_and_a_crossing() {
    let cube = cuboid([H; 3]);
    let ra = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_4);
    let h = H * 2f64.sqrt();
    // A's bottom edge (along x) lies parallel over B's top face: both ends
    // inside the face's region: two vertex–face primitives.
    let pb = at([0.0, 0.0, 0.0]);
    let pa = rot_pose(Vector3::new(0.0, 0.0, H + h + GAP), ra);
    let w = witnesses(cube.clone(), pa, cube.clone(), pb);
    let held: Vec<_> = w
        .iter()
        .zip(values(&w, &pa, &pb))
        .filter(|(_, v)| (v - GAP).abs() < 1e-12)
        .map(|(w, _)| w.origin())
        .collect();
    assert_eq!(held.len(), 2, "{:?}", kinds(&w));
    assert!(held.iter().all(|k| *k == Some(WitnessType::EdgeFace)));
    // Shifted along x so one end leaves the face: one vertex–face and one
    // edge–edge with the face's boundary edge (§3.1.5). The edge–edge row is
    // the distance from B's separating plane through that boundary edge,
    // whose normal is the mean of the top and side faces' (45°): GAP/√2.
    let pa = rot_pose(Vector3::new(1.5 * H, 0.0, H + h + GAP), ra);
    let w = witnesses(cube.clone(), pa, cube, pb);
    let v = values(&w, &pa, &pb);
    let ee = w
        .iter()
        .zip(&v)
        .filter(|(w, v)| {
            matches!(w, Witness::EdgeEdge(_)) && (**v - GAP / 2f64.sqrt()).abs() < 1e-12
        })
        .count();
    let vf = w
        .iter()
        .zip(&v)
        .filter(|(w, v)| matches!(w, Witness::Plane(_)) && (**v - GAP).abs() < 1e-12)
        .count();
    assert_eq!((vf, ee), (1, 1), "{:?} {v:?}", kinds(&w));
}

#[test]
fn face_face_reduces_to_corners_and_crossings() {
    let (big, small) = (cuboid([H; 3]), cuboid([0.02, 0.02, 0.02]));
    // Small box over the big one's top face, entirely inside it: its four
    // bottom corners.
    let pb = at([0.0, 0.0, 0.0]);
    let pa = at([0.01, 0.0, H + 0.02 + GAP]);
    let w = witnesses(small.clone(), pa, big.clone(), pb);
    assert_eq!(w.len(), 4, "{:?}", kinds(&w));
    assert!(kinds(&w).iter().all(|k| *k == WitnessType::FaceFace));
    assert!(values(&w, &pa, &pb).iter().all(|v| (v - GAP).abs() < 1e-12));
    // Over the big face's corner: one of its corners inside, the big face's
    // corner inside it (both vertex–face, GAP), and the two loops crossing
    // twice (edge–edge against the big box's 45° separating planes:
    // GAP/√2).
    let pa = at([H, H, H + 0.02 + GAP]);
    let w = witnesses(small, pa, big, pb);
    let v = values(&w, &pa, &pb);
    let count = |plane: bool, want: f64| {
        w.iter()
            .zip(&v)
            .filter(|(w, v)| matches!(w, Witness::Plane(_)) == plane && (**v - want).abs() < 1e-12)
            .count()
    };
    assert_eq!(
        (count(true, GAP), count(false, GAP / 2f64.sqrt())),
        (2, 2),
        "{:?} {v:?}",
        kinds(&w)
    );
}

/// A capsule lying on a face: its axis (a segment core) against the face,
/// the radius as the margin.
#[test]
fn curved_shapes_act_through_their_exact_support_point() {
    let cube = cuboid([H; 3]);
    let capsule = Shape::Capsule {
        half_height_m: 0.02,
        radius_m: 0.01,
    };
    let lying = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
    let pb = at([0.0, 0.0, 0.0]);
    let pa = rot_pose(Vector3::new(0.0, 0.0, H + 0.01 + GAP), lying);
    let w = witnesses(capsule, pa, cube.clone(), pb);
    let v = values(&w, &pa, &pb);
    assert!(
        v.len() >= 2 && v.iter().all(|v| (v - GAP).abs() < 1e-12),
        "{v:?}"
    );
    // A sphere off a cube's corner: the exact distance to the corner.
    let ball = Shape::Sphere { radius_m: 0.01 };
    let dir = Vector3::new(1.0, 1.0, 1.0).normalize();
    let pa = at((Vector3::repeat(H) + dir * (0.01 + GAP)).into());
    let w = witnesses(ball, pa, cube, pb);
    assert!((values(&w, &pa, &pb)[0] - GAP).abs() < 1e-12);
}

/// Values and gradients stay finite on degenerate geometry: parallel edges
/// (Ve·Fpn → 0 in Eq. 2), coplanar faces of equal boxes, coincident
/// vertices, a vertex exactly on a face, two spheres with one centre.
#[test]
fn degenerate_geometry_never_gives_nan() {
    let cube = cuboid([H; 3]);
    let r45x = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_4);
    let h = H * 2f64.sqrt();
    let up = Rotation3::rotation_between(&Vector3::new(1.0, 1.0, 1.0), &Vector3::z()).unwrap();
    let ball = Shape::Sphere { radius_m: 0.01 };
    // (name, A, A's pose, B, B's pose); the last overlaps completely.
    let cases: Vec<(&str, Shape, Pose3, Shape, Pose3)> = vec![
        (
            "parallel edges",
            cube.clone(),
            rot_pose(Vector3::new(0.01, 0.0, 2.0 * h + GAP), r45x),
            cube.clone(),
            rot_pose(Vector3::zeros(), r45x),
        ),
        (
            "coplanar equal faces",
            cube.clone(),
            at([0.0, 0.0, 2.0 * H]),
            cube.clone(),
            at([0.0, 0.0, 0.0]),
        ),
        (
            "coincident vertices",
            cube.clone(),
            rot_pose(Vector3::new(0.0, 0.0, 2.0 * corner_depth()), vertex_down()),
            cube.clone(),
            rot_pose(Vector3::zeros(), up),
        ),
        (
            "a vertex on a face",
            cube.clone(),
            rot_pose(Vector3::new(0.0, 0.0, H + corner_depth()), vertex_down()),
            cube.clone(),
            at([0.0, 0.0, 0.0]),
        ),
        (
            "one centre",
            ball.clone(),
            at([0.0, 0.0, 0.0]),
            ball,
            at([0.0, 0.0, 0.0]),
        ),
    ];
    for (name, a, pa, b, pb) in cases {
        // Through a model, so the rows' Jacobians are evaluated too.
        let mut m = ModelBuilder::new();
        m.body(
            BodySpec::fixed("b")
                .at(pb.r.into())
                .oriented(quat(&pb))
                .shape(b.clone()),
        );
        m.body(
            BodySpec::new("a")
                .at(pa.r.into())
                .oriented(quat(&pa))
                .shape(a.clone()),
        );
        let base = m.build().unwrap();
        let w = witnesses(a, pa, b, pb);
        assert!(!w.is_empty(), "{name}: no witness");
        let model = base
            .with_contacts(&[haptloop_solver::geometry::PairSpec {
                bodies: [0, 1],
                slots: w.len() as u32,
                friction: false,
            }])
            .unwrap();
        let mut ev = model.evaluation();
        ev.witnesses_mut()[..w.len()].copy_from_slice(&w);
        ev.evaluate(&model, model.q0(), &[]).unwrap();
        assert!(
            ev.values().iter().all(|v| v.is_finite()),
            "{name}: {:?}",
            ev.values()
        );
        assert!(
            ev.jacobian().values().iter().all(|v| v.is_finite()),
            "{name}: a gradient is not finite"
        );
        // The touching cases overlap by round-off at most; coincident centres
        // report the full depth (two 1 cm spheres: 2 cm).
        let min = ev.values().iter().copied().fold(f64::INFINITY, f64::min);
        let depth = if name == "one centre" { 0.02 } else { 0.0 };
        assert!((min + depth).abs() < 1e-9 || min > -1e-9, "{name}: {min}");
    }
}

fn quat(p: &Pose3) -> [f64; 4] {
    let q = nalgebra::UnitQuaternion::from_matrix(&p.rot);
    [q.w, q.i, q.j, q.k]
}
