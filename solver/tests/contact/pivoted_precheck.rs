//! The pivoted finger shortcut's precheck (`force::pivoted`) on the
//! cluttered table: the hand's rigid grasp of a box gives a 6 × 6 finger
//! block of full rank whose smallest eigenvalue, about 1e-6 of the largest,
//! lies between the eigensolve's rank threshold and the full-rank
//! shortcut's bound. No eigenvalue can be dropped there, so the pivoted
//! factor's certificate must refuse it, and the full-rank shortcut's
//! ‖S⁻¹‖₁ shows that in advance: every block the pivoted shortcut is
//! offered on this drag is refused by the precheck, none after factor work,
//! none served.
//!
//! Checked in lockstep with programs whose finger solves all run the
//! eigensolve (`force::eigensolve_only`): with nothing served, q, λ and the
//! finger outputs are equal to the bit on every tick; the tally's counts;
//! no allocation.

use haptloop_rt::alloc::count;
use haptloop_solver::force::{PivotedTally, eigensolve_only, pivoted_tally};
use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::mechanisms::cluttered_builder;
use haptloop_solver::{FingerTarget, SolverSettings, TickOutcome};
use nalgebra::Vector3;

use crate::common::Lockstep;

/// The hand's target at tick `k`: 0.2 mm a tick along +x into the clutter
/// for 1200 ticks, then back.
fn target(start: FingerTarget, k: usize) -> FingerTarget {
    let s = if k < 1200 { k } else { 2400 - k.min(2400) };
    FingerTarget {
        position_m: start.position_m + Vector3::new(0.0002 * s as f64, 0.0, 0.0),
        ..start
    }
}

#[test]
fn the_cluttered_grasp_is_refused_by_the_precheck_and_equals_the_eigensolve() {
    let model = || cluttered_builder(9).build().expect("model");
    let settings = SolverSettings::default();
    let mut fast = Lockstep::new(model(), settings, ContactSettings::default());
    let mut slow = Lockstep::new(model(), settings, ContactSettings::default());
    let start = fast.program.model().initial_targets()[0];
    let ticks = if cfg!(debug_assertions) { 1200 } else { 2400 };
    let (before, mut allocations) = (pivoted_tally(), 0);
    for k in 0..ticks {
        let t = [target(start, k)];
        let (a, stats) = count(|| fast.program.tick(&t, fast.dt));
        allocations += stats.total();
        let b = eigensolve_only(|| slow.program.tick(&t, slow.dt));
        assert_eq!(a.status, TickOutcome::Ok, "tick {k}");
        assert_eq!(a.status, b.status, "tick {k}");
        assert!(fast.program.q() == slow.program.q(), "tick {k}: q");
        assert!(
            fast.program.lambda() == slow.program.lambda(),
            "tick {k}: λ"
        );
        let (x, y) = (
            fast.program.finger_outputs()[0],
            slow.program.finger_outputs()[0],
        );
        assert!(
            x.force_n == y.force_n && x.constraint_force_n == y.constraint_force_n,
            "tick {k}: {x:?} against {y:?}"
        );
        fast.cycle_after(a);
        eigensolve_only(|| slow.cycle_after(b));
    }
    let after = pivoted_tally();
    let tally = PivotedTally {
        prechecked: after.prechecked - before.prechecked,
        refused: after.refused - before.refused,
        served: after.served - before.served,
    };
    eprintln!("cluttered drag, {ticks} ticks: {tally:?}");
    assert_eq!(allocations, 0, "the ticks allocated");
    // Offered at least once a tick on most ticks, and every one refused in
    // advance.
    assert!(tally.prechecked as usize >= ticks / 2, "{tally:?}");
    assert_eq!((tally.refused, tally.served), (0, 0), "{tally:?}");
}
