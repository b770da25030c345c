//! A joint tick that fails (here injected: `Program::fail_next_joint_tick`,
//! as a force solve not positive would) runs the augmented tick for the same
//! call: against an augmented-only program brought to the same q at rest,
//! the fallback tick's q, outputs and report bit for bit; the next tick in
//! joint coordinates again; a fallback that fails too leaves q unchanged and
//! every output zero.

use std::sync::Arc;
use std::time::Duration;

use haptloop_solver::{
    Coordinates, FingerOutput, FingerTarget, Program, SolverSettings, TickOutcome,
};

use super::joint_coordinates::{body_gap, hand, pair};

const DT: Duration = Duration::from_millis(1);

/// An augmented-only program of `joint`'s model and settings, at `joint`'s q
/// at rest (`set_q`), its multipliers at their initial value as the joint
/// program's (which joint ticks never update).
fn augmented_at(joint: &Program) -> Program {
    let settings = SolverSettings {
        coordinates: Coordinates::Augmented,
        ..*joint.settings()
    };
    let mut p = Program::new(Arc::clone(joint.model_arc()), settings).unwrap();
    p.set_q(joint.q()).unwrap();
    p
}

fn bits(o: &[FingerOutput]) -> Vec<u64> {
    o.iter()
        .flat_map(|o| {
            let v = [
                o.force_n,
                o.torque_nm,
                o.constraint_force_n,
                o.coupling_force_n,
                o.attachment_m,
                o.target_m,
            ];
            let mut b: Vec<u64> = v
                .iter()
                .flat_map(|x| x.iter().map(|c| c.to_bits()))
                .collect();
            b.push(o.tracking_error_m.to_bits());
            b
        })
        .collect()
}

/// On each mechanism after 20 joint ticks of the hand circle: the injected
/// failure's tick is Ok and equals, bit for bit (q, outputs, report), the
/// tick of an augmented-only program set to the same q; one fallback is
/// counted; the next tick is a joint tick (the counter unchanged) that
/// agrees with the augmented program set to the same q at rest (the joint
/// tick is resynced at rest) as the lockstep tests do: bodies within 1 µm,
/// force within 1e-4 of the largest.
#[test]
fn a_failed_joint_tick_runs_the_augmented_tick() {
    for name in ["four-bar", "bennett", "peaucellier"] {
        let (_, mut joint) = pair(name);
        let model = joint.model_arc().clone();
        let t0 = model.initial_targets();
        for k in 0..20 {
            assert_eq!(joint.tick(&hand(&t0, k, 0.002), DT).status, TickOutcome::Ok);
        }
        assert_eq!(joint.joint_fallbacks(), 0);
        let mut aug = augmented_at(&joint);
        let t = hand(&t0, 20, 0.002);
        assert!(joint.fail_next_joint_tick(false));
        let (rj, ra) = (joint.tick(&t, DT), aug.tick(&t, DT));
        assert_eq!(rj.status, TickOutcome::Ok, "{name}: {rj:?}");
        assert_eq!(joint.joint_fallbacks(), 1, "{name}");
        assert_eq!(rj, ra, "{name}: the fallback's report");
        let q_bits = |p: &Program| p.q().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(q_bits(&joint), q_bits(&aug), "{name}: q");
        assert_eq!(
            bits(joint.finger_outputs()),
            bits(aug.finger_outputs()),
            "{name}: outputs"
        );
        assert!(
            aug.finger_outputs().iter().any(|o| o.force_n.norm() > 1e-3),
            "{name}: the load is not trivially zero"
        );
        // The next tick: joint coordinates again, from q at rest.
        aug.set_q(joint.q()).unwrap();
        let t = hand(&t0, 21, 0.002);
        let (rj, ra) = (joint.tick(&t, DT), aug.tick(&t, DT));
        assert_eq!((rj.status, ra.status), (TickOutcome::Ok, TickOutcome::Ok));
        assert_eq!(
            joint.joint_fallbacks(),
            1,
            "{name}: the next tick fell back"
        );
        let dr = body_gap(&model, aug.q(), joint.q());
        let (mut df, mut fmax) = (0.0f64, 0.0f64);
        for (a, b) in aug.finger_outputs().iter().zip(joint.finger_outputs()) {
            df = df.max((a.force_n - b.force_n).norm());
            fmax = fmax.max(a.force_n.norm());
        }
        println!("{name} after a fallback: |Δr| {dr:.2e} m, |ΔF| {df:.2e} of {fmax:.2e} N");
        assert!(dr < 1e-6, "{name}: |Δr| {dr:.2e} m");
        assert!(df < 1e-4 * fmax, "{name}: |ΔF| {df:.2e} N");
    }
}

/// A fallback that fails too (injected as a failed refresh at q): the
/// failure stands (`ForceSolve`), q unchanged to the bit, every output
/// exactly zero, one fallback counted; the next tick succeeds in joint
/// coordinates. A program in augmented coordinates takes no injection.
#[test]
fn a_failed_fallback_fails_the_tick() {
    let (mut aug, mut joint) = pair("bennett");
    let t0 = joint.model().initial_targets();
    for k in 0..20 {
        assert_eq!(joint.tick(&hand(&t0, k, 0.002), DT).status, TickOutcome::Ok);
    }
    let q = joint.q().to_vec();
    assert!(joint.fail_next_joint_tick(true));
    let r = joint.tick(&hand(&t0, 20, 0.002), DT);
    assert_eq!(r.status, TickOutcome::ForceSolve, "{r:?}");
    assert!(joint.q() == &q[..], "q moved on a failed tick");
    assert!(
        joint
            .finger_outputs()
            .iter()
            .all(|o| *o == FingerOutput::default())
    );
    assert_eq!(joint.joint_fallbacks(), 1);
    let r = joint.tick(&hand(&t0, 21, 0.002), DT);
    assert_eq!(r.status, TickOutcome::Ok);
    assert_eq!(joint.joint_fallbacks(), 1, "the next tick fell back");
    assert!(!aug.fail_next_joint_tick(false));
    assert_eq!(aug.tick(&t0, DT).status, TickOutcome::Ok);
    assert_eq!(aug.joint_fallbacks(), 0);
}

/// The largest |C| of the rows joint ticks never evaluate (tree joints,
/// quaternion norms), from a fresh evaluation of the model at q (angles
/// and norms times L): the residue joint ticks would freeze.
fn tree_residue(model: &haptloop_solver::Model, q: &[f64], t: &[FingerTarget]) -> f64 {
    let tree = haptloop_solver::reduced::JointTree::new(model).unwrap();
    let mut ev = model.evaluation();
    ev.evaluate(model, q, t).unwrap();
    let ell = model.characteristic_length_m();
    let of = |rows: &[usize], s: f64| {
        rows.iter()
            .map(|&r| ev.values()[r].abs() * s)
            .fold(0.0, f64::max)
    };
    let tree_m = tree
        .tree_rows()
        .iter()
        .map(|&r| {
            let s = match model.rows()[r].unit {
                haptloop_solver::RowUnit::Length => 1.0,
                _ => ell,
            };
            ev.values()[r].abs() * s
        })
        .fold(0.0, f64::max);
    tree_m.max(of(tree.norm_rows(), ell))
}

/// A fallback on a tick whose hand target jumps by 3 cm leaves the tree
/// joints and the quaternion norms open (four-bar 9.3e-6, Bennett 1.3e-2,
/// Peaucellier 5.9e-10; the augmented tick closes them over later ticks:
/// Bennett's were still 1.8e-8 after 30 more augmented ticks), and joint
/// ticks never evaluate them: before the projection they stayed so.
/// Compared with a fresh evaluation of the model at the program's q (m,
/// angles and norms times L): 60 ticks after the fallback (recovery ticks,
/// if any, then joint ticks, the first of which projects q onto the tree)
/// the tree rows and norms are within 1e-11 and 100× below the fallback's,
/// the loop rows closed again (within 1e-9 m), and no further fallback.
#[test]
fn a_fallback_s_open_tree_rows_are_closed_by_the_next_joint_tick() {
    for name in ["four-bar", "bennett", "peaucellier"] {
        let (_, mut joint) = pair(name);
        let model = joint.model_arc().clone();
        let t0 = model.initial_targets();
        for k in 0..20 {
            assert_eq!(joint.tick(&hand(&t0, k, 0.002), DT).status, TickOutcome::Ok);
        }
        let mut t = hand(&t0, 20, 0.002);
        t[0].position_m.x += 0.03;
        assert!(joint.fail_next_joint_tick(false));
        assert_eq!(joint.tick(&t, DT).status, TickOutcome::Ok);
        let after = tree_residue(&model, joint.q(), &t);
        for _ in 0..60 {
            assert_eq!(joint.tick(&t, DT).status, TickOutcome::Ok, "{name}");
        }
        let end = tree_residue(&model, joint.q(), &t);
        let loops = joint.last_report().max_violation_m;
        let rec = joint.joint_recovery_ticks();
        println!(
            "{name}: tree rows and norms {after:.2e} after the fallback, {end:.2e} 60 ticks \
             later ({rec} of them augmented); loop rows then {loops:.2e} m"
        );
        assert_eq!(joint.joint_fallbacks(), 1, "{name}");
        assert!(rec < 25, "{name}: {rec} recovery ticks");
        assert!(
            end <= 1e-11 && 100.0 * end <= after,
            "{name}: {end:.2e} of {after:.2e}"
        );
        assert!(loops <= 1e-9, "{name}: loops {loops:.2e} m");
    }
}

/// `set_q` to q0 with every coordinate moved by up to 1e-4 (a fixed
/// pseudo-random pattern) on scenes with every kind of tree joint
/// (revolute, spherical: four-bar, Bennett, Peaucellier; prismatic and
/// universal: Stewart, the chain; weld: stewart-3rsu): the tree rows and
/// norms, from a fresh evaluation of the model, are open beyond 1e-6 before
/// the next tick and within 1e-10 after it (the joint tick after a resync
/// that finds them open projects q onto the tree; the 64-link chain's
/// round-off 1.6e-11, the others' ≤ 6e-13), the tick Ok.
#[test]
fn an_off_tree_set_q_is_projected_onto_the_tree() {
    for name in [
        "four-bar",
        "bennett",
        "peaucellier",
        "stewart",
        "chain",
        "stewart-3rsu",
    ] {
        let (model, s) = super::joint_coordinates::scene(name, Coordinates::Joint);
        let mut joint = Program::new(model.clone(), s).unwrap();
        assert!(joint.coordinates().joint, "{name}: {}", joint.coordinates());
        let mut seed = 7u64;
        let q: Vec<f64> = model
            .q0()
            .iter()
            .map(|v| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                v + 1e-4 * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
            })
            .collect();
        joint.set_q(&q).unwrap();
        let t = model.initial_targets();
        let before = tree_residue(&model, joint.q(), &t);
        let r = joint.tick(&t, DT);
        let after = tree_residue(&model, joint.q(), &t);
        println!("{name}: tree rows and norms {before:.2e} at the set q, {after:.2e} after a tick");
        assert_eq!(r.status, TickOutcome::Ok, "{name}: {r:?}");
        assert!(before > 1e-6, "{name}: {before:.2e}");
        assert!(after <= 1e-10, "{name}: {after:.2e}");
    }
}
