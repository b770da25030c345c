//! `coordinates = Joint`: a `Program` ticking in joint coordinates
//! against one ticking the augmented system on the same targets, its
//! failure path, its resync, its report against an independent evaluation,
//! zero allocation, and what `Auto` and `Joint` refuse.

use std::sync::Arc;
use std::time::Duration;

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::{
    Coordinates, EvalError, FingerTarget, Model, Program, RowUnit, Sense, SolverSettings,
    TickOutcome,
};
use nalgebra::Vector3;

const DT: Duration = Duration::from_millis(1);

/// The scene's model and its `[solver]` step and iterations over the
/// defaults, with `coordinates`.
pub fn scene(name: &str, coordinates: Coordinates) -> (Arc<Model>, SolverSettings) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.toml"));
    let compiled = haptloop_solver::scene::load(&path)
        .unwrap()
        .compile()
        .unwrap();
    let settings = super::common::step_and_iterations(&compiled.settings, coordinates);
    (Arc::new(compiled.model), settings)
}

/// Both programs of a scene from its q0.
pub fn pair(name: &str) -> (Program, Program) {
    let (model, s) = scene(name, Coordinates::Augmented);
    let aug = Program::new(model.clone(), s).unwrap();
    let joint = Program::new(
        model,
        SolverSettings {
            coordinates: Coordinates::Joint,
            ..s
        },
    )
    .unwrap();
    assert!(!aug.coordinates().joint);
    assert!(joint.coordinates().joint, "{name}: {}", joint.coordinates());
    (aug, joint)
}

/// The hand on a circle of `radius` in the xy plane, 500 ticks a turn.
pub fn hand(t0: &[FingerTarget], k: usize, radius: f64) -> Vec<FingerTarget> {
    let a = 2.0 * std::f64::consts::PI * k as f64 / 500.0;
    let mut t = t0.to_vec();
    for (t, t0) in t.iter_mut().zip(t0) {
        t.position_m = t0.position_m + Vector3::new(a.cos() - 1.0, a.sin(), 0.0) * radius;
    }
    t
}

fn radius(name: &str) -> f64 {
    if name == "peaucellier" { 0.004 } else { 0.002 }
}

/// Largest |r_a − r_b| over the moving bodies, metres.
pub fn body_gap(model: &Model, a: &[f64], b: &[f64]) -> f64 {
    model
        .layout()
        .moving_bodies()
        .map(|(_, o)| {
            (Vector3::from_column_slice(&a[o..o + 3]) - Vector3::from_column_slice(&b[o..o + 3]))
                .norm()
        })
        .fold(0.0, f64::max)
}

/// Largest |C| of the mechanism's equality rows of `unit` at q (finger rows
/// left out), from a fresh evaluation: what the report's
/// `max_violation_m` (`max_violation_rad`) claims.
fn true_violation(model: &Model, q: &[f64], targets: &[FingerTarget], unit: RowUnit) -> f64 {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, targets).unwrap();
    let finger_rows: Vec<usize> = model
        .fingers()
        .iter()
        .flat_map(|f| model.constraints()[f.constraint.index()].rows.clone())
        .collect();
    model
        .rows()
        .iter()
        .enumerate()
        .filter(|(i, r)| r.sense == Sense::Equality && r.unit == unit && !finger_rows.contains(i))
        .map(|(i, _)| ev.values()[i].abs())
        .fold(0.0, f64::max)
}

/// Over 300 ticks of the hand circle, both programs from q0: bodies within
/// 1 µm, finger force within 1e-4 of the largest, the joint program's
/// reported violation no worse than 10 × the augmented one's worst (or
/// 1 nm), and its length and angle maxima equal, to 1e-12 (m, rad), to a
/// fresh evaluation of every row at its q (the tree rows it does not
/// evaluate included).
#[test]
fn the_joint_program_follows_the_augmented_program() {
    for name in ["four-bar", "bennett", "peaucellier"] {
        let (mut aug, mut joint) = pair(name);
        let model = aug.model_arc().clone();
        let t0 = model.initial_targets();
        let (mut dr, mut df, mut fmax) = (0.0f64, 0.0f64, 0.0f64);
        let (mut va, mut vj, mut gap) = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..300 {
            let t = hand(&t0, k, radius(name));
            let (ra, rj) = (aug.tick(&t, DT), joint.tick(&t, DT));
            assert_eq!(ra.status, TickOutcome::Ok, "{name} tick {k}");
            assert_eq!(rj.status, TickOutcome::Ok, "{name} tick {k}");
            assert!(rj.iterations >= 1 && rj.iterations <= joint.settings().iterations);
            dr = dr.max(body_gap(&model, aug.q(), joint.q()));
            for (a, b) in aug.finger_outputs().iter().zip(joint.finger_outputs()) {
                df = df.max((a.force_n - b.force_n).norm());
                fmax = fmax.max(a.force_n.norm());
            }
            va = va.max(ra.max_violation_m.max(ra.max_violation_rad));
            vj = vj.max(rj.max_violation_m.max(rj.max_violation_rad));
            if k % 50 == 49 {
                let v = true_violation(&model, joint.q(), &t, RowUnit::Length);
                let a = true_violation(&model, joint.q(), &t, RowUnit::Angle);
                gap = gap.max((v - rj.max_violation_m).abs());
                gap = gap.max((a - rj.max_violation_rad).abs());
            }
        }
        println!(
            "{name}: |Δr| {dr:.2e} m, |ΔF| {df:.2e} of {fmax:.2e} N, violation joint {vj:.2e} \
             augmented {va:.2e}, report against a fresh evaluation {gap:.2e} m"
        );
        assert!(fmax > 1e-3, "{name}: the load is not trivially zero");
        assert!(dr < 1e-6, "{name}: |Δr| {dr:.2e} m");
        assert!(df < 1e-4 * fmax, "{name}: |ΔF| {df:.2e} N");
        assert!(
            vj < (10.0 * va).max(1e-9),
            "{name}: {vj:.2e} against {va:.2e}"
        );
        assert!(
            gap < 1e-12,
            "{name}: report off a fresh evaluation by {gap:.2e} m"
        );
        assert!(
            body_gap(&model, model.q0(), joint.q()) > 1e-4,
            "{name}: it moved"
        );
    }
}

/// The largest |C| of `rows` at q (a fresh evaluation).
fn rows_at(model: &Model, q: &[f64], t: &[FingerTarget], rows: &[usize]) -> f64 {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, t).unwrap();
    rows.iter()
        .map(|&r| ev.values()[r].abs())
        .fold(0.0, f64::max)
}

/// The tree joints and quaternion norms hold by construction, so the report
/// takes them from the last resync: after 3000 ticks a fresh evaluation of
/// those rows at the joint program's q is within 1e-13 (m or rad) of its
/// value at the start (forward kinematics' round-off drift), and the norms
/// within 1e-13.
#[test]
fn the_tree_rows_drift_by_round_off_only() {
    for name in ["four-bar", "bennett", "peaucellier"] {
        let (_, mut joint) = pair(name);
        let model = joint.model_arc().clone();
        let tree = haptloop_solver::reduced::JointTree::new(&model).unwrap();
        let t0 = model.initial_targets();
        let start = rows_at(&model, joint.q(), &t0, tree.tree_rows());
        let (mut worst, mut norms) = (0.0f64, 0.0f64);
        for k in 0..3000 {
            let t = hand(&t0, k, radius(name));
            assert_eq!(
                joint.tick(&t, DT).status,
                TickOutcome::Ok,
                "{name} tick {k}"
            );
            if k % 500 == 499 {
                worst = worst.max(rows_at(&model, joint.q(), &t, tree.tree_rows()));
                norms = norms.max(rows_at(&model, joint.q(), &t, tree.norm_rows()));
            }
        }
        println!(
            "{name}: tree rows {start:.2e} at the start, at most {worst:.2e} over 3000 ticks; \
             norms at most {norms:.2e}"
        );
        assert!(
            worst < start + 1e-13,
            "{name}: {worst:.2e} from {start:.2e}"
        );
        assert!(norms < 1e-13, "{name}: norms {norms:.2e}");
    }
}

/// A NaN target fails the tick as the augmented program fails it: the same
/// outcome, q unchanged to the bit, every output exactly zero; the next
/// good tick succeeds and agrees with the augmented program's again.
#[test]
fn a_nan_target_fails_the_joint_tick_and_restores() {
    let (mut aug, mut joint) = pair("four-bar");
    let t0 = aug.model().initial_targets();
    for k in 0..20 {
        let t = hand(&t0, k, 0.002);
        assert_eq!(aug.tick(&t, DT).status, TickOutcome::Ok);
        assert_eq!(joint.tick(&t, DT).status, TickOutcome::Ok);
    }
    let q = joint.q().to_vec();
    let mut bad = hand(&t0, 20, 0.002);
    bad[0].position_m.x = f64::NAN;
    let (ra, rj) = (aug.tick(&bad, DT), joint.tick(&bad, DT));
    assert!(
        matches!(
            rj.status,
            TickOutcome::Eval(EvalError::NonFiniteTarget { .. })
        ),
        "{rj:?}"
    );
    assert_eq!(ra.status, rj.status);
    assert!(joint.q() == &q[..], "q moved on a failed tick");
    assert!(
        joint
            .finger_outputs()
            .iter()
            .all(|o| *o == Default::default())
    );
    let short = joint.tick(&bad[..0], DT).status;
    assert!(
        matches!(short, TickOutcome::Eval(EvalError::TargetCount { .. })),
        "{short:?}"
    );
    let t = hand(&t0, 21, 0.002);
    let (ra, rj) = (aug.tick(&t, DT), joint.tick(&t, DT));
    assert_eq!((ra.status, rj.status), (TickOutcome::Ok, TickOutcome::Ok));
    assert!(body_gap(aug.model(), aug.q(), joint.q()) < 1e-6);
    let zero = joint.tick(&t, Duration::ZERO);
    assert_eq!(zero.status, TickOutcome::ZeroDt);
}

/// `set_q` and `shift_q` move the joint tick with the program: after a
/// jump to q0 (at rest there) and a shift back, both programs tick on in
/// lockstep as before (bodies within 1 µm, force within 1e-4 of the
/// largest).
#[test]
fn set_q_and_shift_q_resync_the_joint_tick() {
    let (mut aug, mut joint) = pair("bennett");
    let model = aug.model_arc().clone();
    let t0 = model.initial_targets();
    let (mut dr, mut df, mut fmax) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..150 {
        if k == 50 {
            aug.set_q(model.q0()).unwrap();
            joint.set_q(model.q0()).unwrap();
            assert!(
                joint
                    .finger_outputs()
                    .iter()
                    .all(|o| *o == Default::default())
            );
        }
        if k == 100 {
            let mut dq = vec![0.0; model.n_coords()];
            dq[0] = 1e-7;
            let before = joint.q()[0];
            aug.shift_q(&dq).unwrap();
            joint.shift_q(&dq).unwrap();
            assert_eq!(joint.q()[0], before + 1e-7, "the shift moved q");
        }
        let t = hand(&t0, k, 0.002);
        assert_eq!(aug.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
        assert_eq!(joint.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
        dr = dr.max(body_gap(&model, aug.q(), joint.q()));
        for (a, b) in aug.finger_outputs().iter().zip(joint.finger_outputs()) {
            df = df.max((a.force_n - b.force_n).norm());
            fmax = fmax.max(a.force_n.norm());
        }
    }
    println!("bennett with set_q and shift_q: |Δr| {dr:.2e} m, |ΔF| {df:.2e} of {fmax:.2e} N");
    assert!(dr < 1e-6, "|Δr| {dr:.2e}");
    assert!(df < 1e-4 * fmax, "|ΔF| {df:.2e}");
}

/// `Program::tick`, `set_q` and `shift_q` in joint coordinates allocate
/// nothing (counting global allocator), 200 ticks on each mechanism, three
/// of them falling back to the augmented tick (one of whose fallback fails,
/// one on a 3 cm jump of the target, followed by recovery ticks and the
/// joint tick's projection onto the tree).
#[test]
fn the_joint_program_allocates_nothing() {
    assert!(is_installed());
    for name in ["four-bar", "bennett", "peaucellier"] {
        let (_, mut joint) = pair(name);
        let t0 = joint.model().initial_targets();
        let targets: Vec<Vec<FingerTarget>> =
            (0..200).map(|k| hand(&t0, k, radius(name))).collect();
        let q0 = joint.model().q0().to_vec();
        let dq = vec![0.0; q0.len()];
        let mut bad = targets[0].clone();
        bad[0].position_m.y = f64::NAN;
        let mut far = targets[170].clone();
        far[0].position_m.x += 0.03;
        let (ok, stats) = count(|| {
            let mut ok = true;
            for (k, t) in targets.iter().enumerate() {
                ok &= joint.tick(t, DT).status == TickOutcome::Ok;
                if k == 100 {
                    ok &= joint.set_q(&q0).is_ok() && joint.shift_q(&dq).is_ok();
                    ok &= joint.tick(&bad, DT).status != TickOutcome::Ok;
                }
                // The next tick falls back to the augmented tick (which
                // succeeds), then one whose fallback fails too.
                if k == 150 || k == 160 {
                    ok &= joint.fail_next_joint_tick(k == 160);
                }
                if k == 160 {
                    ok &= joint.tick(t, DT).status == TickOutcome::ForceSolve;
                }
                // A fallback on a 3 cm jump: augmented recovery ticks, then
                // a joint tick that projects q onto the tree.
                if k == 170 {
                    ok &= joint.fail_next_joint_tick(false);
                    for _ in 0..10 {
                        ok &= joint.tick(&far, DT).status == TickOutcome::Ok;
                    }
                }
            }
            ok
        });
        assert!(ok, "{name}: a tick failed");
        assert_eq!(stats.total(), 0, "{name}: allocations {stats:?}");
        let (f, r) = (joint.joint_fallbacks(), joint.joint_recovery_ticks());
        println!("{name}: {f} fallbacks, {r} recovery ticks");
        assert!(f >= 3, "{name}: {f} fallback ticks");
    }
}
