//! A flexible program's tick allocates nothing (counting allocator).

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::{FingerTarget, SolverSettings, TickOutcome};
use nalgebra::Vector3;

use crate::flexible::common::{DT, belly, program};

#[test]
fn flexible_ticks_allocate_nothing() {
    assert!(is_installed());
    let model = belly(true);
    let mut p = program(model.clone(), SolverSettings::default());
    let start = model.initial_targets()[0].position_m;
    let mut t = [FingerTarget::at(start)];
    let r = p.assemble(&t, 500, 1e-10);
    assert!(r.converged, "{r:?}");
    let start = p
        .model()
        .finger_point(p.q(), haptloop_solver::FingerId(0))
        .unwrap();
    t[0].position_m = start;
    let mut state = p.tick_state();
    for k in 0..5 {
        t[0].position_m = start + Vector3::new(0.0, 1e-4 * k as f64, 0.0);
        p.tick(&t, DT);
    }
    let (_, stats) = count(|| {
        for k in 5..50 {
            t[0].position_m = start + Vector3::new(0.0, 1e-4 * k as f64, -5e-5 * k as f64);
            let r = p.tick(&t, DT);
            assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
            p.save_state(&mut state);
        }
    });
    assert_eq!(stats.total(), 0, "allocations in flexible ticks: {stats:?}");
    assert!(p.model().strain_energy_j(p.q()) > 0.0);
}
