//! A target the mechanism cannot reach: the 1-DOF four-bar's finger pulled off
//! its coupler curve. Everything stays bounded and finite, the mechanism stays
//! assembled, and the user feels the virtual coupling, proportional to the
//! error.

use haptloop_solver::mechanisms::four_bar;
use haptloop_solver::{FingerTarget, Program, SolverSettings};
use nalgebra::Vector3;

use crate::common::*;

/// The coupler curve's unit tangent at q0, from the motion of a converged
/// nudge along x.
fn tangent() -> Vector3<f64> {
    let m = four_bar();
    let p0 = m.initial_targets()[0].position_m;
    let mut p = program(m, SolverSettings::default());
    let r = p.assemble(&[FingerTarget::at(p0 + Vector3::x() * 1e-4)], 20_000, 1e-12);
    assert!(r.converged, "{r:?}");
    let p1 = p
        .model()
        .finger_point(p.q(), haptloop_solver::FingerId(0))
        .unwrap();
    (p1 - p0).normalize()
}

struct Held {
    p: Program,
    max_lambda: [f64; 2],
    max_violation: f64,
}

/// Holds the target `offset` metres off the curve, normal to it, for 3000
/// ticks; records the largest |λ| over the second and the third thousand.
fn held_off(offset: f64, n: &Vector3<f64>) -> Held {
    let m = four_bar();
    let target = [FingerTarget::at(
        m.initial_targets()[0].position_m + n * offset,
    )];
    let mut h = Held {
        p: program(m, SolverSettings::default()),
        max_lambda: [0.0; 2],
        max_violation: 0.0,
    };
    for k in 0..3000 {
        let r = h.p.tick(&target, DT);
        assert_eq!(r.status, haptloop_solver::TickOutcome::Ok, "tick {k}");
        assert!(h.p.q().iter().chain(h.p.lambda()).all(|v| v.is_finite()));
        let lam = h.p.lambda().iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if k >= 1000 {
            let slot = if k < 2000 { 0 } else { 1 };
            h.max_lambda[slot] = h.max_lambda[slot].max(lam);
            h.max_violation = h.max_violation.max(r.max_violation_m);
        }
    }
    h
}

#[test]
fn an_unreachable_target_is_bounded_and_rendered_by_the_coupling() {
    let t = tangent();
    let n = t.cross(&Vector3::z()).normalize();
    let k = SolverSettings::default().coupling_stiffness_n_per_m;
    let mut coupling = Vec::new();
    for offset in [5e-3, 1e-2] {
        let h = held_off(offset, &n);
        // The multipliers settle at the opposing load instead of winding up.
        assert!(h.max_lambda[0] > 0.0);
        assert!(
            (h.max_lambda[1] - h.max_lambda[0]).abs() < 1e-6 * h.max_lambda[0],
            "{:?}",
            h.max_lambda
        );
        assert!(h.max_violation < 1e-8, "joints hold: {}", h.max_violation);
        let o = h.p.finger_outputs()[0];
        // The closest point of the curve is (to second order) where it was.
        assert!(
            (o.tracking_error_m - offset).abs() < 0.02 * offset,
            "{}",
            o.tracking_error_m
        );
        let spring = (o.attachment_m - o.target_m) * k;
        assert!((o.coupling_force_n - spring).norm() < 1e-9 * spring.norm());
        coupling.push(o.coupling_force_n.norm());
    }
    let ratio = coupling[1] / coupling[0];
    assert!(
        (ratio - 2.0).abs() < 0.04,
        "coupling ∝ error: ratio {ratio}"
    );
}
