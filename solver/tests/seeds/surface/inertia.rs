//! Eq. 7 with surface contact: the static load of a ball on a bowl's slope
//! is its weight's tangential part (the bowl carries the normal part,
//! rolling or sliding); accelerated along a plane, a rolling ball loads the
//! finger with (m + I/R²) a = 7/5 m a, a sliding one with m a.

use haptloop_solver::{BodyId, FingerTarget, TickOutcome};
use nalgebra::Vector3;

use super::common::{DT, I, LEVEL, M, R, ball, bowl, plane, program};

#[test]
fn a_ball_held_on_a_bowls_slope_loads_the_finger_with_its_tangential_weight() {
    for rolling in [true, false] {
        let model = ball(bowl(), LEVEL, [0.05, -0.03], rolling, true);
        let mut p = program(model.clone());
        let t = model.initial_targets();
        for k in 0..400 {
            assert_eq!(p.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
        }
        let c = model.body_position(p.q(), BodyId(1)).unwrap();
        // The bowl's centre is 0.2 m above its lowest point: the normal at
        // the contact points from the contact to it.
        let n = (Vector3::new(0.0, 0.0, 0.2) - c).normalize();
        let g = Vector3::new(0.0, 0.0, -9.81 * M);
        let want = g - n * n.dot(&g);
        let f = p.finger_outputs()[0].constraint_force_n;
        assert!((f - want).norm() < 1e-9, "rolling {rolling}: {f} vs {want}");
    }
}

#[test]
fn accelerating_a_ball_loads_the_finger_with_its_rolling_or_sliding_inertia() {
    let a = 0.5; // m/s²
    for (rolling, mass) in [(true, M + I / (R * R)), (false, M)] {
        let model = ball(plane(), LEVEL, [0.0, 0.0], rolling, false);
        let mut p = program(model.clone());
        let start = model.initial_targets()[0].position_m;
        for k in 1..=400 {
            let t = k as f64 * DT.as_secs_f64();
            let target = start + Vector3::new(0.5 * a * t * t, 0.0, 0.0);
            assert_eq!(
                p.tick(&[FingerTarget::at(target)], DT).status,
                TickOutcome::Ok
            );
        }
        let f = p.finger_outputs()[0].constraint_force_n;
        let want = -mass * a;
        assert!(
            (f.x - want).abs() < 1e-6 * want.abs() && f.y.abs() < 1e-9,
            "rolling {rolling}: {f} vs {want}"
        );
    }
}
