//! `Plan::new`'s solver settings: the scene's keys over the session's
//! defaults, the flags over the scene's, and the flags' range errors.

use super::*;
use crate::scenes::resolve;
use haptloop_solver::scene::SceneSettings;
use haptloop_solver::{Coordinates, RedundancyCheck};

/// The four-bar (no shapes) with every `[solver]` key set to a value
/// no default has.
fn four_bar_with_every_key() -> Scene {
    let mut scene = resolve("four-bar").unwrap();
    scene.compiled.settings = SceneSettings {
        iterations: Some(7),
        step: Some(0.7),
        gain: Some(123.0),
        multiplier_gain: Some(45.0),
        coupling_stiffness: Some(321.0),
        coupling_damping: Some(0.07),
        velocity_filter: Some(0.004),
        dynamics: Some(true),
        coordinates: Some(Coordinates::Joint),
        ..scene.compiled.settings
    };
    scene
}

/// Every field of the plan's solver settings, written out: the scene's
/// keys over the defaults, then every flag over the scene's.
#[test]
fn flags_override_the_scene_which_overrides_the_defaults() {
    let scene = four_bar_with_every_key();
    let plan = Plan::new(&scene, &SessionOptions::default()).unwrap();
    let from_scene = SolverSettings {
        update: UpdateRule::Projected,
        iterations: 7,
        step: 0.7,
        gain: 123.0,
        multiplier_gain: 45.0,
        finger_pull_limit_m: 1e-2,
        contact_step_m: f64::INFINITY,
        finger_weight: 1.0,
        length_scale_m: None,
        coupling_stiffness_n_per_m: 321.0,
        coupling_damping_n_s_per_m: 0.07,
        coupling_angular_stiffness_nm_per_rad: 0.0,
        velocity_filter: Duration::from_millis(4),
        force_solver: ForceSolver::Cholesky,
        force_regularization: 0.0,
        dynamics: true,
        redundancy: RedundancyCheck::Auto,
        norm_rows_out: false,
        coordinates: Coordinates::Joint,
    };
    assert_eq!(plan.solver, from_scene);
    let flags = SessionOptions {
        iterations: Some(9),
        update: Some(UpdateRule::Gradient),
        force_solver: Some(ForceSolver::MATVEC),
        gain: Some(77.0),
        coordinates: Some(Coordinates::Augmented),
        velocity_filter: Some(Duration::from_millis(2)),
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &flags).unwrap();
    let flagged = SolverSettings {
        iterations: 9,
        update: UpdateRule::Gradient,
        force_solver: ForceSolver::MATVEC,
        gain: 77.0,
        coordinates: Coordinates::Augmented,
        velocity_filter: Duration::from_millis(2),
        ..from_scene
    };
    assert_eq!(plan.solver, flagged);
}

/// A silent scene gets the session's defaults: inertial motion where
/// shaped bodies move under gravity (the cluttered table, its
/// `dynamics = false` taken out), none on the four-bar, the 10 ms
/// velocity filter.
#[test]
fn a_silent_scene_gets_the_session_defaults() {
    let mut cluttered = resolve("cluttered").unwrap();
    assert_eq!(cluttered.compiled.settings.dynamics, Some(false));
    let plan = Plan::new(&cluttered, &SessionOptions::default()).unwrap();
    assert!(!plan.solver.dynamics);
    cluttered.compiled.settings.dynamics = None;
    let plan = Plan::new(&cluttered, &SessionOptions::default()).unwrap();
    assert!(plan.solver.dynamics);
    assert_eq!(plan.solver.velocity_filter, DEFAULT_VELOCITY_FILTER);
    let four_bar = resolve("four-bar").unwrap();
    let plan = Plan::new(&four_bar, &SessionOptions::default()).unwrap();
    assert!(!plan.solver.dynamics);
    assert_eq!(
        (plan.solver.step, plan.solver.iterations),
        (1.0, 2),
        "the four-bar's [solver]"
    );
}

/// Out-of-range values name the flag, whether a flag or (past the
/// scene's own validation) the scene gave them.
#[test]
fn out_of_range_iterations_and_gain_name_the_flag() {
    let err = |scene: &Scene, o: SessionOptions| Plan::new(scene, &o).unwrap_err().to_string();
    let scene = four_bar_with_every_key();
    let o = SessionOptions {
        iterations: Some(0),
        ..SessionOptions::default()
    };
    assert_eq!(err(&scene, o), "--iterations must be 1–10000, got 0");
    let o = SessionOptions {
        gain: Some(-1.0),
        ..SessionOptions::default()
    };
    assert_eq!(err(&scene, o), "--gain must be a finite number > 0, got -1");
    let mut bad = four_bar_with_every_key();
    bad.compiled.settings.iterations = Some(20_000);
    assert_eq!(
        err(&bad, SessionOptions::default()),
        "--iterations must be 1–10000, got 20000"
    );
}
