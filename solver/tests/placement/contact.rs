//! Placements that respect contact (`haptloop_solver::place` with the
//! geometry module's non-penetration inequalities): a seated pelvis with a
//! hinged thigh, both boxes, placed by its origin at a goal 1.8 cm inside a
//! fixed seat block. Where it stops has a closed form: resting on the
//! seat's top face (z = 0), its centre one half-height above it, under the
//! goal's x and y, level (the thigh lies flat on it beside the pelvis). Every
//! check computes the boxes' corners from the placed poses (an
//! independent measure of penetration, not the rows the solver held) and
//! evaluates the joint rows on the joints-only model.

use haptloop_solver::geometry::Shape;
use haptloop_solver::place::{Goal, Mode, PlaceOptions, Placed, place, pose};
use haptloop_solver::{BodySpec, Evaluation, JointKind, JointSpec, ModelBuilder};
use nalgebra::Vector3;

/// The pelvis's half extents; the thigh's are the same but 2.5 cm long.
const PELVIS: [f64; 3] = [0.015, 0.025, 0.008];
const THIGH: [f64; 3] = [0.025, 0.02, 0.008];
/// The goal: inside the seat, whose top face is z = 0.
const GOAL: [f64; 3] = [0.01, 0.005, -0.01];

fn boxed(half: [f64; 3]) -> Shape {
    Shape::Box {
        half_extents_m: half,
    }
}

/// The seat (fixed, 10 × 10 cm, top face z = 0), the pelvis 4.2 cm above
/// it and a thigh on a hip hinge about y at the pelvis's front edge
/// (limited to [−0.5, 0.1] rad: the seat, not the limit, keeps it flat).
fn seated() -> ModelBuilder {
    let mut b = ModelBuilder::new();
    b.body(
        BodySpec::fixed("seat")
            .at([0.0, 0.0, -0.025])
            .shape(boxed([0.05, 0.05, 0.025])),
    );
    b.body(
        BodySpec::new("pelvis")
            .at([0.0, 0.0, 0.05])
            .shape(boxed(PELVIS)),
    );
    b.body(
        BodySpec::new("thigh")
            .at([-0.04, 0.0, 0.05])
            .shape(boxed(THIGH)),
    );
    b.joint(
        JointSpec::new(JointKind::Revolute, "pelvis", "thigh")
            .anchors([-0.015, 0.0, 0.0], [0.025, 0.0, 0.0])
            .axes([0.0, 1.0, 0.0], [0.0, 1.0, 0.0])
            .limits(-0.5, 0.1),
    );
    b
}

/// Lowest corner of `body` (half extents `half`) at `q`, m above z = 0.
fn lowest_corner(p: &Placed, body: &str, half: [f64; 3]) -> f64 {
    let id = p.model.body_id(body).unwrap();
    let (c, r) = pose(&p.model, &p.q, id);
    let mut low = f64::MAX;
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                let corner = c + r * Vector3::new(sx * half[0], sy * half[1], sz * half[2]);
                low = low.min(corner.z);
            }
        }
    }
    low
}

/// Largest |C| of the equality rows and largest violation of the limit
/// rows of the joints-only model at the placed q.
fn joint_residual(p: &Placed) -> f64 {
    let model = seated().build_joints_only().unwrap();
    let mut e = Evaluation::new(&model);
    e.evaluate_values(&model, &p.q, &[]).unwrap();
    let v = e.values();
    let eq = v[model.equality_rows()]
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let ineq = v[model.inequality_rows()]
        .iter()
        .fold(0.0_f64, |m, v| m.max(-v));
    eq.max(ineq)
}

fn opts(mode: Mode, contact: bool) -> PlaceOptions {
    PlaceOptions {
        mode,
        contact,
        ..PlaceOptions::default()
    }
}

fn goal() -> Goal {
    Goal {
        position_m: Vector3::from(GOAL),
        orientation: None,
    }
}

#[test]
fn a_pelvis_placed_inside_the_seat_stops_on_its_top_under_the_goal() {
    for mode in [Mode::Pull, Mode::Solve] {
        let p = place(&seated(), "pelvis", &goal(), &opts(mode, true)).expect("runs");
        let c = p.contact.expect("two shaped bodies: contact is on");
        let id = p.model.body_id("pelvis").unwrap();
        let (at, r) = pose(&p.model, &p.q, id);
        println!(
            "{mode:?}: pelvis at {at:?}, {} steps {:?}, contact {c:?}",
            p.steps.len(),
            p.steps.iter().map(|s| s.iterations).collect::<Vec<_>>()
        );
        assert_eq!(p.reached, 1.0, "{mode:?}: the whole path was solved");
        assert!(!p.at_goal() && p.steps.last().unwrap().blocked, "{mode:?}");
        assert!(c.blocked >= 1, "{mode:?}: {c:?}");
        // Closed form: centre one half-height above the top face, under the
        // goal, level; no corner of either box below the face.
        // (to 2 µm: a blocked final goal may end at the intermediate
        // tolerance, 1 µm, rather than the placement's 1 nm).
        assert!((at.z - PELVIS[2]).abs() < 2e-6, "{mode:?}: z = {}", at.z);
        assert!((at.x - GOAL[0]).abs() < 2e-6 && (at.y - GOAL[1]).abs() < 2e-6);
        // Level (its z axis vertical; a turn about z is free).
        let tilt = (r * Vector3::z()).z.clamp(-1.0, 1.0).acos();
        assert!(tilt < 1e-4, "{mode:?}: tilted {tilt} rad");
        assert!((p.goal_gap_m - (PELVIS[2] - GOAL[2])).abs() < 2e-6);
        for (body, half) in [("pelvis", PELVIS), ("thigh", THIGH)] {
            let low = lowest_corner(&p, body, half);
            assert!(low > -1e-6, "{mode:?}: {body} {low} m into the seat");
            assert!(
                low < 1e-6,
                "{mode:?}: {body} rests on the seat ({low} m above)"
            );
        }
        assert!(c.max_penetration_m <= 1e-6, "{c:?}");
        assert!(joint_residual(&p) < 1e-6, "{mode:?}");
    }
}

#[test]
fn without_contact_the_same_placement_ends_inside_the_seat() {
    let p = place(&seated(), "pelvis", &goal(), &opts(Mode::Pull, false)).expect("runs");
    assert!(
        p.at_goal() && p.contact.is_none(),
        "{:?} {:?}",
        p.steps,
        p.last_status
    );
    assert!(p.goal_gap_m < 1e-9);
    // The pelvis's centre is at the goal, 1.8 cm below the seat's top face
    // (its bottom deeper still): what contact prevents.
    let id = p.model.body_id("pelvis").unwrap();
    assert!((pose(&p.model, &p.q, id).0 - Vector3::from(GOAL)).norm() < 1e-9);
    let low = lowest_corner(&p, "pelvis", PELVIS);
    assert!(low < GOAL[2] - PELVIS[2] + 1e-3, "{low}");
    assert!(joint_residual(&p) < 1e-9);
}

#[test]
fn a_goal_above_the_seat_is_reached_with_contact_on() {
    // 1 mm above where the pelvis would touch: the rows are there (the
    // pair is within reach) but never active.
    let g = Goal {
        position_m: Vector3::new(0.01, 0.005, PELVIS[2] + 0.001),
        orientation: None,
    };
    let p = place(&seated(), "pelvis", &g, &opts(Mode::Pull, true)).expect("runs");
    let c = p.contact.unwrap();
    assert!(p.at_goal(), "{:?} {c:?}", p.steps);
    assert!(p.goal_gap_m < 1e-9);
    assert_eq!(c.blocked, 0);
    assert!(c.tracked_pairs >= 1, "the seat is tracked 1 mm away: {c:?}");
    // Its centre at the goal, no corner of either box in the seat (the
    // free steps tilt the pelvis a little: the thigh trails the drag).
    let id = p.model.body_id("pelvis").unwrap();
    assert!((pose(&p.model, &p.q, id).0 - g.position_m).norm() < 1e-9);
    for (body, half) in [("pelvis", PELVIS), ("thigh", THIGH)] {
        let low = lowest_corner(&p, body, half);
        assert!(low > 0.0 && low < 0.0011, "{body}: lowest corner {low} m");
    }
}
