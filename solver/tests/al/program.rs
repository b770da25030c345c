//! `Program` as the fast loop uses it: no allocation, bad input reported and
//! contained, hand-over of state, bit-identical replays.

use std::sync::Arc;
use std::time::Duration;

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{
    EvalError, FingerId, FingerTarget, Model, PlaneOwner, PointPlaneSpec, Program, ProgramError,
    SolverSettings, TickOutcome,
};
use nalgebra::Vector3;

use crate::common::*;

/// Targets of tick `k`: every finger on a 5 mm, 1 Hz circle around its start.
fn moving(model: &Model, k: usize) -> Vec<FingerTarget> {
    let w = 2.0 * std::f64::consts::PI * k as f64 * 1e-3;
    let mut t = model.initial_targets();
    for f in &mut t {
        f.position_m += Vector3::new(w.cos() - 1.0, w.sin(), 0.0) * 5e-3;
    }
    t
}

fn assert_tick_allocates_nothing(model: Model) {
    assert!(is_installed());
    let all: Vec<Vec<FingerTarget>> = (0..30).map(|k| moving(&model, k)).collect();
    let model = Arc::new(model);
    let mut p = Program::new(model.clone(), SolverSettings::default()).unwrap();
    let spare = Program::new(model.clone(), SolverSettings::default()).unwrap();
    let q = p.q().to_vec();
    let mut bad = all[0].clone();
    bad[0].position_m.x = f64::NAN;
    let (statuses, stats) = count(|| {
        let mut s = [TickOutcome::Ok; 5];
        for t in &all {
            s[0] = p.tick(t, DT).status;
            if s[0] != TickOutcome::Ok {
                break;
            }
        }
        s[1] = p.iterate(&all[0], 2);
        s[2] = p.tick(&bad, DT).status;
        s[3] = p.tick(&all[0], Duration::ZERO).status;
        p.set_q(&q).unwrap();
        p.adopt_state(&spare);
        s[4] = p.tick(&all[1], DT).status;
        s
    });
    assert_eq!(stats.total(), 0, "allocations: {stats:?}");
    assert_eq!(statuses[0], TickOutcome::Ok);
    assert_eq!(statuses[1], TickOutcome::Ok);
    assert!(matches!(
        statuses[2],
        TickOutcome::Eval(EvalError::NonFiniteTarget { .. })
    ));
    assert_eq!(statuses[3], TickOutcome::ZeroDt);
    assert_eq!(statuses[4], TickOutcome::Ok);
}

#[test]
fn tick_allocates_nothing_four_bar() {
    assert_tick_allocates_nothing(four_bar());
}

#[test]
fn tick_allocates_nothing_stewart() {
    assert_tick_allocates_nothing(stewart());
}

#[test]
fn tick_allocates_nothing_sphere_toy() {
    assert_tick_allocates_nothing(sphere_toy());
}

/// The piston (gears, masked rows) with motor torques reported on its main
/// bearing and a bore (§5.2's extra solves every tick).
#[test]
fn tick_allocates_nothing_piston_with_joint_torques() {
    let src = haptloop_solver::mechanisms::piston_builder();
    let mut b = haptloop_solver::ModelBuilder::new();
    b.gravity(src.gravity_m_s2());
    for s in src.body_specs() {
        b.body(s.clone());
    }
    for j in src.joint_specs() {
        let named = matches!(j.name.as_deref(), Some("main" | "bore0"));
        b.joint(if named {
            j.clone().report_torque()
        } else {
            j.clone()
        });
    }
    for g in src.gear_specs() {
        b.gear(g.clone());
    }
    for f in src.finger_specs() {
        b.finger(f.clone());
    }
    let model = b.build().unwrap();
    assert_eq!(model.torque_joints().len(), 2);
    assert_tick_allocates_nothing(model);
}

fn no_nan(p: &Program) -> bool {
    p.q().iter().chain(p.lambda()).all(|v| v.is_finite())
        && p.finger_outputs().iter().all(|o| o.is_finite())
}

#[test]
fn non_finite_input_is_a_status_with_zero_outputs_and_state_kept() {
    let model = four_bar();
    let mut p = program(model.clone(), SolverSettings::default());
    for k in 0..50 {
        p.tick(&moving(&model, k), DT);
    }
    let (q, lambda) = (p.q().to_vec(), p.lambda().to_vec());
    let mut bad = moving(&model, 50);
    bad[0].position_m.y = f64::INFINITY;
    let r = p.tick(&bad, DT);
    assert_eq!(
        r.status,
        TickOutcome::Eval(EvalError::NonFiniteTarget {
            finger: FingerId(0)
        })
    );
    assert!(p.finger_outputs().iter().all(|o| *o == Default::default()));
    assert_eq!(p.q(), &q[..]);
    assert_eq!(p.lambda(), &lambda[..]);
    assert!(no_nan(&p));
    assert_eq!(
        p.tick(&[], DT).status,
        TickOutcome::Eval(EvalError::TargetCount {
            expected: 1,
            got: 0
        })
    );
    // A corrupted state that overflows: reported, contained, recoverable.
    let mut huge = q.clone();
    huge[0] = 1e300;
    p.set_q(&huge).unwrap();
    let r = p.tick(&moving(&model, 50), DT);
    assert_ne!(r.status, TickOutcome::Ok);
    assert!(
        no_nan(&p)
            && p.finger_outputs()
                .iter()
                .all(|o| o.force_n == Vector3::zeros())
    );
    p.set_q(&q).unwrap();
    assert_eq!(p.tick(&moving(&model, 51), DT).status, TickOutcome::Ok);
    assert!(no_nan(&p));
    // set_q refuses bad vectors.
    let mut nan = q.clone();
    nan[4] = f64::NAN;
    assert_eq!(p.set_q(&nan), Err(ProgramError::NonFinite { index: 4 }));
    assert!(matches!(p.set_q(&q[1..]), Err(ProgramError::Length { .. })));
}

/// Two identical runs give bit-identical q and forces.
#[test]
fn runs_are_bit_identical() {
    let run = || {
        let model = stewart();
        let mut p = program(model.clone(), SolverSettings::default());
        let mut trace = Vec::new();
        for k in 0..300 {
            p.tick(&moving(&model, k), DT);
            trace.extend(p.q().iter().map(|v| v.to_bits()));
            trace.extend(p.finger_outputs()[0].force_n.iter().map(|v| v.to_bits()));
            trace.extend(p.finger_outputs()[0].torque_nm.iter().map(|v| v.to_bits()));
        }
        trace
    };
    assert_eq!(run(), run());
}

/// A replacement built from the same model takes over mid-motion and then
/// ticks exactly as the original would have.
#[test]
fn adopt_state_continues_the_motion_exactly() {
    let model = Arc::new(four_bar());
    let mut a = Program::new(model.clone(), SolverSettings::default()).unwrap();
    for k in 0..200 {
        a.tick(&moving(&model, k), DT);
    }
    let mut b = Program::new(model.clone(), SolverSettings::default()).unwrap();
    b.adopt_state(&a);
    assert_eq!(a.q(), b.q());
    assert_eq!(a.lambda(), b.lambda());
    for k in 200..260 {
        let t = moving(&model, k);
        a.tick(&t, DT);
        b.tick(&t, DT);
        assert_eq!(a.q(), b.q(), "tick {k}");
        assert_eq!(a.finger_outputs(), b.finger_outputs(), "tick {k}");
    }
}

/// A model with one more (inactive) contact inequality: q and every
/// surviving multiplier are carried, the new row starts at zero, and the
/// forces continue smoothly.
#[test]
fn adopt_state_carries_surviving_multipliers_into_a_new_active_set() {
    let model = Arc::new(stewart());
    let mut a = Program::new(model.clone(), SolverSettings::default()).unwrap();
    for k in 0..200 {
        a.tick(&moving(&model, k), DT);
    }
    let platform = model.body_id("platform").unwrap();
    let floor = PointPlaneSpec {
        name: "floor".into(),
        body: platform,
        point_m: [0.0; 3],
        plane: PlaneOwner::World,
        plane_point_m: [0.0, 0.0, -1.0],
        normal: [0.0, 0.0, 1.0],
    };
    let extended = Arc::new(model.with_inequalities(&[floor]).unwrap());
    let mut b = Program::new(extended.clone(), SolverSettings::default()).unwrap();
    b.adopt_state(&a);
    assert_eq!(a.q(), b.q());
    assert_eq!(&b.lambda()[..a.lambda().len()], a.lambda());
    assert_eq!(b.lambda()[a.lambda().len()], 0.0);
    a.tick(&moving(&model, 200), DT);
    b.tick(&moving(&model, 200), DT);
    let (fa, fb) = (a.finger_outputs()[0].force_n, b.finger_outputs()[0].force_n);
    assert!(rel(&fb, &fa) < 1e-3, "{fa} vs {fb}");
}
