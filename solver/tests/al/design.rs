//! Design variables and objectives in the fast update: free design columns
//! move with the bodies (the projected rule's Woodbury step, the gradient
//! rule's plain columns), bounds hold as a box, objectives pull without
//! pulling a joint apart, and a tick with all of it allocates nothing.

use std::sync::Arc;

use haptloop_rt::alloc::count;
use haptloop_solver::{
    BodySpec, Bounds, DesignParam as P, FingerSpec, FingerTarget, JointKind as K, JointSpec, Model,
    ModelBuilder, ObjectiveSpec, Objectives, Program, SolverSettings, TickOutcome, UpdateRule,
    mechanisms::four_bar_builder,
};
use nalgebra::Vector3;

use crate::common::{DT, G};

/// A bob on a strut of free length 0.1 m from a fixed pivot, held by a
/// finger at its centre; `bounds` on the length.
fn strut(bounds: Option<[f64; 2]>) -> Model {
    let mut b = ModelBuilder::new();
    b.gravity(G);
    b.body(BodySpec::fixed("pivot"));
    b.body(BodySpec::new("bob").at([0.1, 0.0, 0.0]).mass(0.05));
    let mut j = JointSpec::new(K::Distance, "pivot", "bob")
        .named("strut")
        .free(&[P::Length]);
    if let Some(b) = bounds {
        j = j.bounds(Bounds::Scalar(b));
    }
    b.joint(j);
    b.finger(FingerSpec::point("index", "bob", [0.0; 3]));
    b.build().unwrap()
}

fn program(model: Model, update: UpdateRule) -> Program {
    let settings = SolverSettings {
        update,
        ..SolverSettings::default()
    };
    Program::new(Arc::new(model), settings).unwrap()
}

/// [`program`] carrying `specs` compiled against `model`.
fn designed(model: Model, specs: &[ObjectiveSpec], update: UpdateRule) -> Program {
    let settings = SolverSettings {
        update,
        ..SolverSettings::default()
    };
    let objectives = Arc::new(Objectives::compile(specs, &model).unwrap());
    Program::with_objectives(Arc::new(model), objectives, settings).unwrap()
}

/// The finger pulls the bob 3 cm outward: a fixed strut cannot follow, a
/// free length does (the projected rule's design step), within the bounds.
#[test]
fn a_free_length_follows_the_finger_within_its_bounds() {
    for (bounds, expected) in [(None, 0.13), (Some([0.09, 0.115]), 0.115)] {
        let model = strut(bounds);
        let length = model.layout().design_vars()[0].offset;
        let mut p = program(model, UpdateRule::Projected);
        let mut t = p.model().initial_targets();
        let mut top = 0.0f64;
        for k in 0..400 {
            t[0].position_m.x = 0.1 + 0.03 * (k as f64 / 200.0).min(1.0);
            let r = p.tick(&t, DT);
            assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
            assert!(
                r.max_violation_m < 1e-9,
                "tick {k}: violation {:e}",
                r.max_violation_m
            );
            top = top.max(p.q()[length]);
        }
        let l = p.q()[length];
        assert!((l - expected).abs() < 1e-6, "{bounds:?}: length {l}");
        if let Some([_, hi]) = bounds {
            assert!(top <= hi + 1e-12, "the bound was crossed: {top}");
            // The bound holds the bob 1.5 cm short of the finger.
            let r = p.last_report();
            assert!((r.max_tracking_error_m - 0.015).abs() < 1e-4, "{r:?}");
        } else {
            assert!(p.last_report().max_tracking_error_m < 1e-5);
        }
    }
}

/// Eq. 3 moves design columns too (metric 1): the length follows, more
/// slowly, and the bound rows hold it as inequality rows.
#[test]
fn the_gradient_rule_moves_design_variables_too() {
    let model = strut(Some([0.09, 0.115]));
    let length = model.layout().design_vars()[0].offset;
    let mut p = program(model, UpdateRule::Gradient);
    let mut t = p.model().initial_targets();
    for k in 0..3000 {
        t[0].position_m.x = 0.1 + 0.03 * (k as f64 / 1000.0).min(1.0);
        assert_eq!(p.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
    }
    let l = p.q()[length];
    assert!((l - 0.115).abs() < 2e-4, "length {l}");
    assert!(p.last_report().max_violation_m < 2e-4);
}

/// The four-bar with a straight-line objective on the coupler's middle and a
/// feeble finger: the coupler moves toward the line along the linkage's one
/// free motion, and the joints stay assembled every tick.
#[test]
fn an_objective_moves_the_mechanism_without_pulling_a_joint_apart() {
    let b = four_bar_builder();
    let start = {
        let m = b.build().unwrap();
        m.finger_point(m.q0(), m.finger_id("index").unwrap())
            .unwrap()
    };
    let mut specs = vec![ObjectiveSpec::Finger { weight: 1e-6 }];
    specs.push(ObjectiveSpec::StraightLine {
        name: None,
        weight: 0.05,
        body: "coupler".into(),
        point_m: [0.0; 3],
        line_point_m: (start + Vector3::new(0.0, 0.01, 0.0)).into(),
        direction: [1.0, 0.0, 0.0],
    });
    let model = b.build().unwrap();
    let mut p = designed(model, &specs, UpdateRule::Projected);
    let t = p.model().initial_targets();
    let first = {
        p.tick(&t, DT);
        p.objective_reports()[0]
    };
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        let r = p.tick(&t, DT);
        assert_eq!(r.status, TickOutcome::Ok);
        worst = worst.max(r.max_violation_m);
        assert!(p.objective_step_m() <= haptloop_solver::program::OBJECTIVE_STEP_LIMIT_M + 1e-15);
    }
    let last = p.objective_reports()[0];
    assert!(worst < 1e-8, "violation {worst:e}");
    assert!(
        last < 0.5 * first,
        "distance from the line {first} → {last}"
    );
}

/// A tick with objectives, free design variables and bounds allocates
/// nothing (the crank's far anchor free and bounded, two objectives).
#[test]
fn a_tick_with_objectives_and_design_variables_allocates_nothing() {
    let mut b = four_bar_builder();
    let mut joints: Vec<JointSpec> = b.joint_specs().to_vec();
    joints[1] = joints[1]
        .clone()
        .free(&[P::AnchorI])
        .bounds(Bounds::Scalar([-0.05, 0.05]));
    let mut fresh = ModelBuilder::new();
    fresh.gravity(b.gravity_m_s2());
    for s in b.body_specs() {
        fresh.body(s.clone());
    }
    for j in joints {
        fresh.joint(j);
    }
    for f in b.finger_specs() {
        fresh.finger(f.clone());
    }
    b = fresh;
    let specs = vec![
        ObjectiveSpec::Dexterity {
            name: None,
            weight: 0.01,
            chain: ["ground", "crank", "coupler"].map(String::from).to_vec(),
            point_m: [0.0; 3],
            directions: Vec::new(),
            angular_directions: Vec::new(),
            closure: Vec::new(),
        },
        ObjectiveSpec::StraightLine {
            name: None,
            weight: 0.01,
            body: "coupler".into(),
            point_m: [0.0; 3],
            line_point_m: [0.06, 0.03, 0.06],
            direction: [1.0, 0.0, 0.0],
        },
        // Eq. 13's angular rows, a closed chain, Eq. 15 as written and App. D's
        // workspace volume: the objectives of issue 22.
        ObjectiveSpec::Dexterity {
            name: Some("angular".into()),
            weight: 0.01,
            chain: ["ground", "crank", "coupler"].map(String::from).to_vec(),
            point_m: [0.0; 3],
            directions: Vec::new(),
            angular_directions: vec![[0.0, 0.0, 1.0]],
            closure: Vec::new(),
        },
        ObjectiveSpec::Dexterity {
            name: Some("loop".into()),
            weight: 0.01,
            chain: ["ground", "crank", "coupler"].map(String::from).to_vec(),
            point_m: [0.0; 3],
            directions: vec![[0.0, 1.0, 0.0]],
            angular_directions: Vec::new(),
            closure: ["rocker", "ground"].map(String::from).to_vec(),
        },
        ObjectiveSpec::InverseDistance {
            name: None,
            weight: 0.001,
            points: vec![("coupler".into(), [0.0; 3])],
            obstacle: haptloop_solver::ObstacleSpec::World([0.1, 0.1, 0.1]),
        },
        ObjectiveSpec::WorkspaceVolume {
            name: None,
            weight: 0.01,
            chain: ["ground", "crank", "coupler"].map(String::from).to_vec(),
            point_m: [0.0; 3],
        },
    ];
    let model = b.build().unwrap();
    assert_eq!(model.layout().design_coords(), 3);
    for update in [UpdateRule::Projected, UpdateRule::Gradient] {
        let mut p = designed(model.clone(), &specs, update);
        let mut t: Vec<FingerTarget> = p.model().initial_targets();
        p.tick(&t, DT);
        let (statuses, stats) = count(|| {
            (0..500)
                .map(|k| {
                    t[0].position_m.y += 2e-5 * (k as f64 * 0.01).cos();
                    p.tick(&t, DT).status
                })
                .filter(|s| *s == TickOutcome::Ok)
                .count()
        });
        assert_eq!(statuses, 500, "{update:?}");
        assert_eq!(stats.total(), 0, "{update:?}: {stats:?}");
        assert!(p.objective_reports().iter().all(|v| v.is_finite()));
    }
}

/// Nelson & Cohen §3's flags: the strut's free length switched off stays
/// exactly where it is while the finger pulls 3 cm outward (the bob stays on
/// its circle), and switched back on it follows the finger; under both
/// update rules. A hand-over and a saved tick state carry the flag.
#[test]
fn a_design_variable_switched_off_holds_and_switched_on_moves_again() {
    for update in [UpdateRule::Projected, UpdateRule::Gradient] {
        let model = strut(None);
        let col = model.layout().design_vars()[0].offset;
        let mut p = program(model.clone(), update);
        p.set_design_active(0, false).unwrap();
        assert!(!p.design_active(0));
        let mut t = p.model().initial_targets();
        for k in 0..300 {
            t[0].position_m.x = 0.1 + 0.03 * (k as f64 / 100.0).min(1.0);
            let r = p.tick(&t, DT);
            assert_eq!(r.status, TickOutcome::Ok, "{update:?}, tick {k}");
            assert_eq!(p.q()[col], 0.1, "{update:?}, tick {k}: the length moved");
            // Eq. 3 holds a strut the finger pulls on to its penalty's
            // balance (tens of µm); the projected step to round-off.
            let tol = if update == UpdateRule::Gradient {
                1e-4
            } else {
                1e-9
            };
            assert!(
                r.max_violation_m < tol,
                "{update:?}: {:e}",
                r.max_violation_m
            );
        }
        // A replacement program (a hand-over) and a replayed tick keep it off.
        let mut fresh = program(model.clone(), update);
        fresh.adopt_state(&p);
        assert!(!fresh.design_active(0));
        let before = p.tick_state();
        p.tick(&t, DT);
        let after = p.tick_state();
        let mut reference = program(model, UpdateRule::Projected);
        let c = reference
            .converged_tick(&before, &after, &t, DT.as_secs_f64(), 1e-12, 50)
            .unwrap();
        assert_eq!(c.status, TickOutcome::Ok);
        assert_eq!(reference.q()[col], 0.1, "{update:?}: the replay moved it");
        p.set_design_active(0, true).unwrap();
        for _ in 0..600 {
            p.tick(&t, DT);
        }
        let length = p.q()[col];
        assert!(
            (length - 0.13).abs() < 2e-3,
            "{update:?}: switched on, length {length}"
        );
    }
}
