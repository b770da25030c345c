//! The joint tick against the augmented `Program` ticking the same targets
//! from the same assembled q: two independent solvers of the same
//! constrained problem (one on 21–49 augmented coordinates with every
//! joint a set of rows, one on 3–7 joint coordinates with only the loop
//! and finger rows), compared tick by tick over a hand path.

use std::time::Duration;

use nalgebra::Vector3;

use super::JointTick;
use crate::{FingerTarget, Model, Program, TickOutcome};

/// The hand on a circle of `radius` metres in the xy plane, 500 ticks a turn.
pub(crate) fn hand(t0: &[FingerTarget], k: usize, radius: f64, out: &mut [FingerTarget]) {
    let a = 2.0 * std::f64::consts::PI * k as f64 / 500.0;
    for (t, t0) in out.iter_mut().zip(t0) {
        t.position_m = t0.position_m + Vector3::new(a.cos() - 1.0, a.sin(), 0.0) * radius;
    }
}

/// Largest |r_aug − r_joint| over the moving bodies, metres.
fn body_gap(model: &Model, a: &[f64], b: &[f64]) -> f64 {
    model
        .layout()
        .moving_bodies()
        .map(|(_, o)| {
            (0..3)
                .map(|c| (a[o + c] - b[o + c]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max)
}

/// Worst differences over `ticks` ticks of scene `name`: body position,
/// finger force, and the two violations (joint, augmented).
pub(crate) struct Gaps {
    pub position_m: f64,
    pub force_n: f64,
    pub largest_force_n: f64,
    pub joint_violation: f64,
    pub augmented_violation: f64,
}

pub(crate) fn compare(name: &str, ticks: usize, radius: f64) -> Gaps {
    let mut p: Program = super::tests::program_after(name, 0);
    let model = p.model_arc().clone();
    let t0 = model.initial_targets();
    let mut jt = JointTick::new(model.clone(), *p.settings(), p.q(), &t0).unwrap();
    let mut t = t0.clone();
    let mut g = Gaps {
        position_m: 0.0,
        force_n: 0.0,
        largest_force_n: 0.0,
        joint_violation: 0.0,
        augmented_violation: 0.0,
    };
    for k in 0..ticks {
        hand(&t0, k, radius, &mut t);
        let r = p.tick(&t, Duration::from_millis(1));
        assert_eq!(r.status, TickOutcome::Ok, "{name} tick {k}");
        jt.tick(&t, 1e-3).unwrap();
        g.position_m = g.position_m.max(body_gap(&model, p.q(), jt.q()));
        for (a, b) in p.finger_outputs().iter().zip(&jt.outputs) {
            g.force_n = g.force_n.max((a.force_n - b.force_n).norm());
            g.largest_force_n = g.largest_force_n.max(a.force_n.norm());
        }
        g.joint_violation = g.joint_violation.max(jt.max_violation);
        g.augmented_violation = g
            .augmented_violation
            .max(r.max_violation_m.max(r.max_violation_rad));
    }
    g
}

/// Over 200 ticks of a 2 mm hand circle (4 mm on Peaucellier): bodies
/// within 1 µm, finger force within 1e-4 of the largest, and the loop-closure violation no worse
/// than 10 × the augmented tick's worst or 1 nm (figures in BENCHMARKS.md).
#[test]
fn the_joint_tick_follows_the_augmented_tick() {
    for (name, radius) in [
        ("four-bar", 0.002),
        ("bennett", 0.002),
        ("peaucellier", 0.004),
    ] {
        let g = compare(name, 200, radius);
        println!(
            "{name}: |Δr| {:.2e} m, |ΔF| {:.2e} N of {:.2e} N, violation joint {:.2e} augmented {:.2e}",
            g.position_m, g.force_n, g.largest_force_n, g.joint_violation, g.augmented_violation
        );
        assert!(
            g.largest_force_n > 1e-3,
            "{name}: the load is not trivially zero"
        );
        assert!(g.position_m < 1e-6, "{name}: |Δr| {:.2e} m", g.position_m);
        assert!(
            g.force_n < 1e-4 * g.largest_force_n,
            "{name}: |ΔF| {:.2e} N",
            g.force_n
        );
        assert!(
            g.joint_violation < (10.0 * g.augmented_violation).max(1e-9),
            "{name}: violation {:.2e} against {:.2e}",
            g.joint_violation,
            g.augmented_violation
        );
    }
}

/// The joint tick's forward kinematics keeps the tree joints: every tree
/// row of the augmented evaluation at the joint tick's q stays at the
/// round-off of the assembled start after 200 ticks.
#[test]
fn the_tree_joints_hold_by_construction() {
    for name in ["four-bar", "bennett", "peaucellier"] {
        let p: Program = super::tests::program_after(name, 0);
        let model = p.model_arc().clone();
        let t0 = model.initial_targets();
        let mut jt = JointTick::new(model.clone(), *p.settings(), p.q(), &t0).unwrap();
        let start = super::tests::evaluation(&model, p.q());
        let tree = jt.space.tree.tree_rows().to_vec();
        let before = tree
            .iter()
            .map(|&r| start.values()[r].abs())
            .fold(0.0, f64::max);
        let mut t = t0.clone();
        for k in 0..200 {
            hand(&t0, k, 0.002, &mut t);
            jt.tick(&t, 1e-3).unwrap();
        }
        let ev = super::tests::evaluation(&model, jt.q());
        let after = tree
            .iter()
            .map(|&r| ev.values()[r].abs())
            .fold(0.0, f64::max);
        let norms = jt
            .space
            .tree
            .norm_rows()
            .iter()
            .map(|&r| ev.values()[r].abs())
            .fold(0.0, f64::max);
        // Rigid motions keep each joint's relative error: its components
        // in the world turn, so the largest may grow by at most √3.
        assert!(
            after < 2.0 * before + 1e-12,
            "{name}: tree rows {after:.2e} from {before:.2e}"
        );
        assert!(norms < 1e-12, "{name}: quaternion norms {norms:.2e}");
        assert!(body_gap(&model, p.q(), jt.q()) > 1e-4, "{name}: it moved");
    }
}

/// `cargo test --release -p haptloop-solver --lib
/// reduced::tick_tests::violation_with_one_more_step -- --ignored
/// --nocapture`: the worst loop-closure violation over the comparison's
/// 200 ticks, and its tick, for the joint tick with the scene's steps and
/// with one more, against the augmented tick with the scene's steps.
/// Prints; asserts only that the ticks succeed.
#[test]
#[ignore]
fn violation_with_one_more_step() {
    for (name, radius) in [
        ("four-bar", 0.002),
        ("bennett", 0.002),
        ("peaucellier", 0.004),
    ] {
        for extra in [0u32, 1] {
            let mut p: Program = super::tests::program_after(name, 0);
            let model = p.model_arc().clone();
            let t0 = model.initial_targets();
            let mut s = *p.settings();
            s.iterations += extra;
            let mut jt = JointTick::new(model.clone(), s, p.q(), &t0).unwrap();
            let mut t = t0.clone();
            let (mut wj, mut wa) = ((0.0f64, 0), (0.0f64, 0));
            for k in 0..200 {
                hand(&t0, k, radius, &mut t);
                let r = p.tick(&t, Duration::from_millis(1));
                assert_eq!(r.status, TickOutcome::Ok);
                jt.tick(&t, 1e-3).unwrap();
                let a = r.max_violation_m.max(r.max_violation_rad);
                if jt.max_violation > wj.0 {
                    wj = (jt.max_violation, k);
                }
                if a > wa.0 {
                    wa = (a, k);
                }
            }
            println!(
                "{name}: joint with {} steps {:.2e} (tick {}), augmented with {} {:.2e} (tick {})",
                s.iterations,
                wj.0,
                wj.1,
                p.settings().iterations,
                wa.0,
                wa.1
            );
        }
    }
}
