//! The interaction modes of Choi & Cremer §4.3 (`haptloop_solver::place`) on
//! a two-link arm whose reach has a closed form: an upper link of length
//! L1 on a ball joint at the origin, a hand link on a ball joint at the
//! upper link's end, the hand's origin L2 from that joint. Its origin can
//! reach exactly the shell L1 − L2 ≤ |p| ≤ L1 + L2, and a pose (p, R) exactly
//! when |p − R·(0, L2, 0)| = L1. Every check compares the placed
//! configuration with those closed forms and evaluates the mechanism's joint
//! rows independently (the builder's joints-only model).

use haptloop_solver::place::{Goal, Mode, PlaceError, PlaceOptions, Placed, place, pose};
use haptloop_solver::{BodySpec, Evaluation, JointKind, JointSpec, ModelBuilder};
use nalgebra::{UnitQuaternion, Vector3};

const L1: f64 = 0.1;
const L2: f64 = 0.08;

/// The arm bent at a right angle: upper along x, hand along y.
fn arm() -> ModelBuilder {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    let link = |name: &str, at: [f64; 3]| {
        BodySpec::new(name)
            .at(at)
            .mass(0.1)
            .inertia([1e-4, 1e-4, 1e-4])
    };
    b.body(link("upper", [L1 / 2.0, 0.0, 0.0]));
    b.body(link("hand", [L1, L2, 0.0]));
    b.joint(
        JointSpec::new(JointKind::Spherical, "ground", "upper")
            .anchors([0.0; 3], [-L1 / 2.0, 0.0, 0.0]),
    );
    b.joint(
        JointSpec::new(JointKind::Spherical, "upper", "hand")
            .anchors([L1 / 2.0, 0.0, 0.0], [0.0, -L2, 0.0]),
    );
    b
}

/// Largest |C| of the arm's joint (and quaternion-norm) rows at `q`.
fn joint_residual(q: &[f64]) -> f64 {
    let model = arm().build_joints_only().expect("arm");
    let mut e = Evaluation::new(&model);
    e.evaluate_values(&model, q, &[]).expect("finite");
    e.values().iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// What a placement did, without its model.
fn brief(p: &Placed) -> String {
    format!(
        "reached {} splits {} last {:?} assembly {} steps {:?}",
        p.reached, p.splits, p.last_status, p.assembly_iterations, p.steps
    )
}

fn hand_at(p: [f64; 3]) -> Goal {
    Goal {
        position_m: Vector3::from(p),
        orientation: None,
    }
}

fn opts(mode: Mode) -> PlaceOptions {
    PlaceOptions {
        mode,
        ..PlaceOptions::default()
    }
}

#[test]
fn both_modes_place_a_reachable_goal_and_pull_needs_fewer_iterations_a_step() {
    let goal = [0.05, 0.1, 0.06];
    let r = Vector3::from(goal).norm();
    assert!(r > L1 - L2 && r < L1 + L2, "reachable by the closed form");
    let mut per_step = Vec::new();
    for mode in [Mode::Pull, Mode::Solve] {
        let placed = place(&arm(), "hand", &hand_at(goal), &opts(mode)).expect("places");
        assert!(placed.at_goal(), "{mode:?}: {}", brief(&placed));
        let id = placed.model.body_id("hand").unwrap();
        let (p, _) = pose(&placed.model, &placed.q, id);
        assert!((p - Vector3::from(goal)).norm() < 1e-9, "{mode:?}: {p}");
        assert!(joint_residual(&placed.q) < 1e-9, "{mode:?}");
        assert_eq!(placed.steps.last().unwrap().t, 1.0);
        if mode == Mode::Pull {
            // Closely spaced goals, one every 5 mm, none split.
            let n = (Vector3::from(goal) - Vector3::new(L1, L2, 0.0)).norm() / 0.005;
            assert_eq!(placed.steps.len(), n.ceil() as usize, "{}", brief(&placed));
            assert_eq!(placed.splits, 0);
        }
        per_step.push(placed.max_iterations());
    }
    // Close intermediate goals are good starting points (§5): every pull
    // step takes fewer Newton iterations than the jump to the goal.
    assert!(per_step[0] < per_step[1], "pull {per_step:?} against solve");
}

#[test]
fn a_goal_newton_cannot_reach_in_the_cap_is_subdivided() {
    let goal = [-0.02, 0.12, -0.09];
    let mut o = opts(Mode::Solve);
    // Three iterations a step, every goal (the final one too) to 1 µm.
    o.placement.max_iterations = 3;
    o.placement.tolerance = 1e-6;
    o.placement.step_tolerance = 1e-6;
    let placed = place(&arm(), "hand", &hand_at(goal), &o).expect("places");
    assert!(placed.splits > 0, "{}", brief(&placed));
    assert!(placed.at_goal(), "{}", brief(&placed));
    assert!(placed.steps.iter().all(|s| s.iterations <= 3));
    assert!(placed.steps.iter().any(|s| s.depth > 0));
    // The steps cover the path in order, each starting where the last ended.
    assert!(placed.steps.windows(2).all(|w| w[0].t < w[1].t));
    let id = placed.model.body_id("hand").unwrap();
    let (p, _) = pose(&placed.model, &placed.q, id);
    assert!((p - Vector3::from(goal)).norm() < 1e-6);
    assert!(joint_residual(&placed.q) < 1e-6);
    // With the default cap (8) the same jump needs fewer halvings.
    let wider = place(&arm(), "hand", &hand_at(goal), &opts(Mode::Solve)).expect("places");
    assert!(wider.at_goal(), "{}", brief(&wider));
    assert!(
        wider.splits < placed.splits,
        "{} against {}",
        brief(&wider),
        brief(&placed)
    );
    assert!(wider.steps.iter().all(|s| s.iterations <= 8));
}

#[test]
fn an_unreachable_goal_stops_at_the_reach_with_the_joints_held() {
    let goal = Vector3::new(0.0, 0.3, 0.0);
    let placed = place(&arm(), "hand", &hand_at(goal.into()), &opts(Mode::Pull)).expect("runs");
    assert!(!placed.at_goal());
    assert_ne!(placed.last_status, haptloop_solver::SolveStatus::Converged);
    // Where the straight path leaves the reach: |p0 + t (g − p0)| = L1 + L2.
    let p0 = Vector3::new(L1, L2, 0.0);
    let d = goal - p0;
    let (a, b, c) = (
        d.norm_squared(),
        2.0 * p0.dot(&d),
        p0.norm_squared() - (L1 + L2).powi(2),
    );
    let t_out = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    assert!(placed.reached <= t_out, "{} beyond {t_out}", placed.reached);
    let id = placed.model.body_id("hand").unwrap();
    let (p, _) = pose(&placed.model, &placed.q, id);
    // The hand is where the path put it, near the edge of the reach.
    assert!((p - (p0 + d * placed.reached)).norm() < 1e-9);
    assert!(
        p.norm() > L1 + L2 - 0.002,
        "stopped early at |p| = {}",
        p.norm()
    );
    assert!(joint_residual(&placed.q) < 1e-9);
}

/// A three-link arm (ball joints at the origin, at (L1, 0, 0) and at
/// (L1, 0, LF)), whose hand can take a pose anywhere in an open set: every
/// pose on the straight path to a reachable one is reachable.
fn arm3() -> ModelBuilder {
    const LF: f64 = 0.08;
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    let link = |name: &str, at: [f64; 3]| {
        BodySpec::new(name)
            .at(at)
            .mass(0.1)
            .inertia([1e-4, 1e-4, 1e-4])
    };
    b.body(link("upper", [L1 / 2.0, 0.0, 0.0]));
    b.body(link("fore", [L1, 0.0, LF / 2.0]));
    b.body(link("hand", [L1, L2, LF]));
    let ball = |i: &str, j: &str, ki: [f64; 3], kj: [f64; 3]| {
        JointSpec::new(JointKind::Spherical, i, j).anchors(ki, kj)
    };
    b.joint(ball("ground", "upper", [0.0; 3], [-L1 / 2.0, 0.0, 0.0]));
    b.joint(ball(
        "upper",
        "fore",
        [L1 / 2.0, 0.0, 0.0],
        [0.0, 0.0, -LF / 2.0],
    ));
    b.joint(ball("fore", "hand", [0.0, 0.0, LF / 2.0], [0.0, -L2, 0.0]));
    b
}

#[test]
fn a_rigid_goal_places_the_hand_pose() {
    // A configuration by forward kinematics: the joints at distances L1 and
    // LF, the hand's origin L2 along its own y from the last joint.
    let rot = UnitQuaternion::from_euler_angles(0.3, -0.2, 0.5);
    let j2 = Vector3::new(0.6_f64.cos(), 0.6_f64.sin(), 0.3).normalize() * L1;
    let j3 = j2 + Vector3::new(-0.2, 0.3, 1.0).normalize() * 0.08;
    let p = j3 + rot * Vector3::new(0.0, L2, 0.0);
    let goal = Goal {
        position_m: p,
        orientation: Some(rot),
    };
    let placed = place(&arm3(), "hand", &goal, &opts(Mode::Pull)).expect("places");
    assert!(placed.at_goal(), "{}", brief(&placed));
    let id = placed.model.body_id("hand").unwrap();
    let (got_p, got_r) = pose(&placed.model, &placed.q, id);
    assert!((got_p - p).norm() < 1e-9);
    assert!(got_r.angle_to(&rot) < 1e-8);
    let model = arm3().build_joints_only().expect("arm");
    let mut e = Evaluation::new(&model);
    e.evaluate_values(&model, &placed.q, &[]).expect("finite");
    assert!(e.values().iter().all(|v| v.abs() < 1e-9));
}

#[test]
fn a_fixed_or_unknown_body_is_named_in_the_error() {
    for name in ["ground", "foot"] {
        let e = place(&arm(), name, &hand_at([0.1, 0.0, 0.0]), &opts(Mode::Pull)).unwrap_err();
        assert!(matches!(e, PlaceError::Body(..)));
        let msg = e.to_string();
        assert!(msg.contains(name) && msg.contains("upper, hand"), "{msg}");
    }
    let bad = hand_at([f64::NAN, 0.0, 0.0]);
    assert!(matches!(
        place(&arm(), "hand", &bad, &opts(Mode::Pull)),
        Err(PlaceError::Invalid(_))
    ));
}
