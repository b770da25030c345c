//! Inequalities: the projected multiplier of a limit held at its bound is
//! positive, an inactive limit contributes nothing, and a limit only ever
//! pushes in the force computation.
//!
//! The pendulum hangs at θ₀ = 1 rad; its hinge angle is −(θ − θ₀) (the
//! revolute axis is +y and θ grows towards +x), limited to ±0.2 rad.

use haptloop_solver::{FingerTarget, Program, SolverSettings};

use crate::common::*;

const THETA0: f64 = 1.0;
const STOP: f64 = 0.2;

fn limited() -> Program {
    program(
        pendulum(THETA0, Some((-STOP, STOP))),
        SolverSettings::default(),
    )
}

fn tip_target(theta: f64) -> [FingerTarget; 1] {
    [FingerTarget::at(arm_dir(theta) * L_F)]
}

/// The arm's angle θ from the finger point (the tip is L_F from the pivot).
fn angle(p: &Program) -> f64 {
    let tip = p.finger_outputs()[0].attachment_m;
    tip.x.atan2(-tip.z)
}

/// Rows of the hinge's limits: [x − lo ≥ 0, hi − x ≥ 0].
fn limit_rows(p: &Program) -> std::ops::Range<usize> {
    let id = p
        .model()
        .constraint_id("hinge.limits")
        .expect("limits exist");
    p.model().constraints()[id.index()].rows.clone()
}

#[test]
fn a_limit_held_at_its_bound_has_a_positive_multiplier_and_carries_the_load() {
    // Pull the arm down towards θ = 0.5: gravity and finger both press it
    // into the stop at θ₀ − 0.2 (hinge angle +0.2, the `hi` row).
    let mut p = limited();
    hold(&mut p, &tip_target(0.5), 3000);
    let rows = limit_rows(&p);
    let (lo_row, hi_row) = (rows.start, rows.start + 1);
    assert!(
        (angle(&p) - (THETA0 - STOP)).abs() < 1e-6,
        "stopped at {}",
        angle(&p)
    );
    assert!(p.lambda()[hi_row] > 0.0, "ν = {}", p.lambda()[hi_row]);
    assert_eq!(p.lambda()[lo_row], 0.0);
    let o = p.finger_outputs()[0];
    // The stop carries gravity and the push: no constraint load on the finger;
    // the user feels the stop through the coupling, k × penetration.
    assert!(
        o.constraint_force_n.norm() < 1e-9,
        "{}",
        o.constraint_force_n
    );
    let k = p.settings().coupling_stiffness_n_per_m;
    let expected = (o.attachment_m - o.target_m) * k;
    assert!((o.coupling_force_n - expected).norm() < 1e-6 * expected.norm());
    // 0.3 rad past the stop at 15 cm: a chord of 2 × 0.15 × sin 0.15 = 4.5 cm.
    assert!(
        (o.tracking_error_m - 0.3 * (0.15f64).sin()).abs() < 1e-4,
        "{}",
        o.tracking_error_m
    );
}

#[test]
fn a_limit_never_pulls_the_arm_up_against_gravity() {
    // Push the arm up towards θ = 1.5 into the stop at θ₀ + 0.2 (the `lo`
    // row): gravity pulls away from the stop, so the stop cannot hold the
    // weight; the finger does, exactly as a pendulum held at that angle.
    let mut p = limited();
    hold(&mut p, &tip_target(1.5), 3000);
    let lo_row = limit_rows(&p).start;
    let theta = THETA0 + STOP;
    assert!((angle(&p) - theta).abs() < 1e-6, "stopped at {}", angle(&p));
    assert!(p.lambda()[lo_row] > 0.0);
    let f = p.finger_outputs()[0].constraint_force_n;
    let expected = ARM_KG * 9.81 * L_C * theta.sin() / L_F;
    assert!(
        (f.norm() - expected).abs() < 1e-6 * expected,
        "{} vs {expected}",
        f.norm()
    );
    // It holds the arm up: the finger is pulled down and outwards.
    assert!(f.z < 0.0);
}

#[test]
fn an_inactive_limit_contributes_nothing() {
    let theta = THETA0 + 0.1;
    let mut with = limited();
    let mut without = program(pendulum(THETA0, None), SolverSettings::default());
    for p in [&mut with, &mut without] {
        hold(p, &tip_target(theta), 2000);
    }
    assert!(limit_rows(&with).all(|r| with.lambda()[r] == 0.0));
    let (a, b) = (with.finger_outputs()[0], without.finger_outputs()[0]);
    assert!((angle(&with) - theta).abs() < 1e-9 && (angle(&without) - theta).abs() < 1e-9);
    assert!(rel(&a.constraint_force_n, &b.constraint_force_n) < 1e-9);
    assert!((a.force_n - b.force_n).norm() < 1e-9 * b.force_n.norm());
}

/// Held against the stop, the mechanism has no free motion left, so the
/// finger's Schur complement cancels to round-off: its rank must come out 0
/// on every tick (a round-off rank 1 turned noise into kilonewton spikes of
/// constraint force on some ticks and not others).
#[test]
fn the_finger_load_at_a_stop_is_zero_on_every_tick() {
    let mut p = limited();
    let mut worst: f64 = 0.0;
    for k in 0..3000 {
        let r = p.tick(&tip_target(0.5), DT);
        assert_eq!(r.status, haptloop_solver::TickOutcome::Ok, "tick {k}");
        if k >= 5 {
            worst = worst.max(p.finger_outputs()[0].constraint_force_n.norm());
        }
    }
    assert!(worst < 1e-9, "largest finger load at the stop: {worst} N");
}
