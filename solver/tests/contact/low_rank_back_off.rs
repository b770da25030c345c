//! The low-rank release's back-off (`force::solve`'s `BACK_OFF`): after a
//! refused correction the next 63 releases refactor at once. On the
//! cluttered table a dragged box's fourth contact corner is nearly redundant
//! with the other three, and the correction refuses most of its releases
//! (its inflation guard); without the back-off every refusal paid the k
//! solves that form U and then the factorisation.
//!
//! Run in lockstep with programs whose releases always refactor
//! (`Program::drop_release_low_rank`):
//! - the tally of every program holds the back-off's arithmetic: each
//!   refusal but the last is followed by exactly `BACK_OFF` skipped
//!   releases, the last by at most that many (the program may be replaced
//!   first), and no release is skipped without a refusal before it;
//! - the results: q and λ equal to the bit (the steps factor the first
//!   active set in both), the finger's force within 1e-9 relative of its
//!   size or of 1 N (the other low-rank tests' bound: round-off of a
//!   factor of cond ≈ 1e4 times the inflation guard's 1e2);
//! - the ticks, back-off included, allocate nothing.
//!
//! Measured (release build): 2670 releases over 309 programs (the contact
//! cycle replaces the program every few ticks, and a new program starts
//! without a back-off), 2170 attempts, 14 refusals, 500 releases skipped;
//! worst force difference 2.1e-10 relative.

use haptloop_rt::alloc::count;
use haptloop_solver::force::LowRankTally;
use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::mechanisms::cluttered_builder;
use haptloop_solver::{FingerTarget, SolverSettings, TickOutcome};
use nalgebra::Vector3;

use crate::common::Lockstep;

/// `force::solve::BACK_OFF` (crate-private): releases refactored at once
/// after a refusal.
const BACK_OFF: u64 = 63;

/// The hand's target at tick `k`: along +x into the clutter, 0.2 mm per
/// tick (as `moved_steps`'s drag), then back.
fn target(start: FingerTarget, k: usize) -> FingerTarget {
    let s = if k < 1200 { k } else { 2400 - k.min(2400) };
    FingerTarget {
        position_m: start.position_m + Vector3::new(0.0002 * s as f64, 0.0, 0.0),
        ..start
    }
}

/// One program's tally checked against the back-off's arithmetic.
fn check(t: LowRankTally) {
    let most = BACK_OFF * t.refusals;
    let least = BACK_OFF * t.refusals.saturating_sub(1);
    assert!(
        (least..=most).contains(&t.skipped),
        "{t:?}: {} refusals leave {least}..={most} skipped releases",
        t.refusals
    );
    assert!(t.refusals <= t.attempts, "{t:?}");
}

#[test]
fn a_refused_low_rank_release_backs_off_and_the_results_equal_refactoring() {
    let model = || cluttered_builder(9).build().expect("model");
    let settings = SolverSettings::default();
    let mut fast = Lockstep::new(model(), settings, ContactSettings::default());
    let mut slow = Lockstep::new(model(), settings, ContactSettings::default());
    // Each program's tally from its start: no recycled program's counts.
    fast.recycle = false;
    let start = fast.program.model().initial_targets()[0];
    let ticks = if cfg!(debug_assertions) { 1200 } else { 2400 };
    let (mut sum, mut last) = (LowRankTally::default(), LowRankTally::default());
    let (mut releases, mut last_releases, mut allocations, mut worst) = (0, 0, 0, 0.0f64);
    let mut programs = 1;
    for k in 0..ticks {
        slow.program.drop_release_low_rank();
        let t = [target(start, k)];
        let (a, stats) = count(|| fast.program.tick(&t, fast.dt));
        allocations += stats.total();
        let b = slow.program.tick(&t, slow.dt);
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
        for (u, v) in [
            (x.force_n, y.force_n),
            (x.constraint_force_n, y.constraint_force_n),
        ] {
            let rel = (u - v).norm() / v.norm().max(1.0);
            worst = worst.max(rel);
            assert!(rel <= 1e-9, "tick {k}: {u:?} against {v:?} ({rel:e})");
        }
        assert_eq!(slow.program.force_low_rank_tally(), LowRankTally::default());
        // The tally of the program that ticked, before a cycle replaces it.
        let now = fast.program.force_low_rank_tally();
        check(now);
        let (tally, r) = (now, fast.program.force_releases());
        let fresh = tally.attempts < last.attempts || r < last_releases;
        let base = if fresh { LowRankTally::default() } else { last };
        sum.attempts += tally.attempts - base.attempts;
        sum.refusals += tally.refusals - base.refusals;
        sum.skipped += tally.skipped - base.skipped;
        releases += r - if fresh { 0 } else { last_releases };
        programs += usize::from(fresh);
        (last, last_releases) = (tally, r);
        fast.cycle_after(a);
        slow.cycle_after(b);
    }
    eprintln!(
        "{releases} releases over {programs} programs: {sum:?}; worst relative force \
         difference {worst:e}"
    );
    assert_eq!(allocations, 0, "the ticks allocated");
    // The correction was tried and refused, and the back-off engaged.
    assert!(sum.refusals >= 2, "{sum:?}");
    assert!(sum.skipped >= BACK_OFF, "{sum:?}");
    assert!(
        sum.attempts + sum.skipped <= releases,
        "{sum:?}, {releases} releases"
    );
}
