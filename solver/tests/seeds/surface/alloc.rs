//! Ticks of a rolling ball allocate nothing (counting allocator).

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::{FingerTarget, TickOutcome};
use nalgebra::Vector3;

use super::common::{DT, LEVEL, ball, bowl, program};

#[test]
fn rolling_ticks_allocate_nothing() {
    assert!(is_installed());
    let model = ball(bowl(), LEVEL, [0.02, 0.01], true, true);
    let mut p = program(model.clone());
    let start = model.initial_targets()[0].position_m;
    let mut state = p.tick_state();
    p.tick(&[FingerTarget::at(start)], DT);
    let (_, stats) = count(|| {
        for k in 1..60 {
            let t = [FingerTarget::at(
                start + Vector3::new(1e-4, 5e-5, 0.0) * k as f64,
            )];
            assert_eq!(p.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
            p.save_state(&mut state);
        }
    });
    assert_eq!(stats.total(), 0, "allocations in rolling ticks: {stats:?}");
}
