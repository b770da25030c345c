//! The choices beyond Eq. 3: the projected update, the CG alternative for
//! Eq. 7, and the velocity filter.

use std::time::Duration;

use haptloop_solver::mechanisms::four_bar;
use haptloop_solver::{
    FingerId, FingerTarget, ForceSolver, Program, SolverSettings, TickOutcome, UpdateRule,
};
use nalgebra::Vector3;

use crate::common::*;

/// The four-bar's finger target moved 0.2 mm along the coupler curve's
/// tangent: after one tick the projected rule is where a converged assembly
/// is, up to the least-astonishment lag of a tick's fixed point (about
/// m/(K m̄) of the step, 0.2 %), while the gradient rule has not covered a
/// quarter of the step (it covers 15 %).
#[test]
fn projected_update_tracks_within_a_tick_where_eq3_lags() {
    let model = four_bar();
    let p0 = model.initial_targets()[0].position_m;
    let converged = |offset: Vector3<f64>| {
        let mut p = program(four_bar(), SolverSettings::default());
        let r = p.assemble(&[FingerTarget::at(p0 + offset)], 100, 1e-13);
        assert!(r.converged, "{r:?}");
        p.model().finger_point(p.q(), FingerId(0)).unwrap()
    };
    let t = (converged(Vector3::x() * 1e-4) - p0).normalize();
    let goal = converged(t * 2e-4);
    let after_one_tick = |update: UpdateRule| {
        let mut p = program(
            four_bar(),
            SolverSettings {
                update,
                ..Default::default()
            },
        );
        let r = p.tick(&[FingerTarget::at(p0 + t * 2e-4)], DT);
        assert_eq!(r.status, TickOutcome::Ok);
        (p.finger_outputs()[0].attachment_m - goal).norm()
    };
    let (projected, gradient) = (
        after_one_tick(UpdateRule::Projected),
        after_one_tick(UpdateRule::Gradient),
    );
    assert!(projected < 0.01 * 2e-4, "projected is {projected} m off");
    assert!(gradient > 0.75 * 2e-4, "gradient is {gradient} m off");
}

/// Warm-started CG with a generous cap gives the Cholesky's force; CG cannot
/// serve the projected update, which needs the factor.
#[test]
fn conjugate_gradients_agree_with_the_cholesky() {
    let model = four_bar();
    let targets = model.initial_targets();
    let force = |solver: ForceSolver| {
        let settings = SolverSettings {
            update: UpdateRule::Gradient,
            force_solver: solver,
            ..Default::default()
        };
        let mut p = program(model.clone(), settings);
        hold(&mut p, &targets, 3);
        p.finger_outputs()[0].constraint_force_n
    };
    let exact = force(ForceSolver::Cholesky);
    let cg = force(ForceSolver::ConjugateGradient {
        max_iterations: 200,
    });
    assert!(rel(&cg, &exact) < 1e-9, "{cg} vs {exact}");
    let bad = SolverSettings {
        force_solver: ForceSolver::ConjugateGradient { max_iterations: 50 },
        ..Default::default()
    };
    assert!(Program::new(std::sync::Arc::new(model), bad).is_err());
}

/// A body accelerated from rest at a constant a: unfiltered, the finger feels
/// m (g − a) from the second tick; with a velocity filter of time constant τ
/// the inertial part responds through two first-order stages, τ on the
/// velocity and τ_a = τ/4 on the acceleration (`force/motion.rs`):
/// 1 − (τ e^(−t/τ) − τ_a e^(−t/τ_a)) / (τ − τ_a), 0.516 at t = τ; and
/// `motion_delay` (the velocities' delay) says τ.
#[test]
fn velocity_filter_delays_the_inertial_force_by_its_time_constant() {
    let tau = Duration::from_millis(10);
    let model = free_body([0.0; 3], false);
    let x0 = model.initial_targets()[0].position_m;
    let (a, m) = (Vector3::new(2.0, 0.0, 0.0), 0.5);
    let g = Vector3::from(G);
    let run = |filter: Duration, ticks: usize| {
        let settings = SolverSettings {
            iterations: 16,
            velocity_filter: filter,
            ..Default::default()
        };
        let mut p = program(free_body([0.0; 3], false), settings);
        for k in 1..=ticks {
            let t = k as f64 * DT.as_secs_f64();
            assert_eq!(
                p.tick(&[FingerTarget::at(x0 + a * (0.5 * t * t))], DT)
                    .status,
                TickOutcome::Ok
            );
        }
        assert_eq!(p.motion_delay(DT), DT / 2 + filter);
        // Fraction of the inertial part m a that the finger feels.
        (g * m - p.finger_outputs()[0].constraint_force_n).dot(&a) / (m * a.norm_squared())
    };
    assert!((run(Duration::ZERO, 10) - 1.0).abs() < 0.02);
    let at_tau = run(tau, 10);
    let (t1, t2) = (1.0f64, 0.25f64); // τ and τ_a in units of τ, at t = τ
    let expected = 1.0 - (t1 * (-1.0 / t1).exp() - t2 * (-1.0 / t2).exp()) / (t1 - t2);
    assert!(
        (at_tau - expected).abs() < 0.06,
        "{at_tau} against {expected}"
    );
    // A single first-order stage would be 1 − e⁻¹ = 0.632 here.
    assert!(at_tau < 1.0 - (-1.0f64).exp() - 0.06, "{at_tau}");
    assert!((run(tau, 50) - 1.0).abs() < 0.02);
}
