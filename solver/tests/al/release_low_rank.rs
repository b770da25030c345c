//! The release branch's second solve by a low-rank correction of the first
//! factor (`force::solve`'s `low_rank`) against solving afresh: a Stewart
//! platform lifted into its stroke limits (three limits pull and are
//! released on most held ticks), ticked in lockstep with a program whose
//! release branch assembles and factors every solve.
//!
//! Not bit for bit: the correction solves the masked system through the
//! first factor and a 3 × 3 W = (A_JJ⁻¹)_RR, the reference refactors it,
//! and the two round differently. What must hold:
//! - q and the steps' λ equal to the bit: the steps factor the first
//!   active set in both (the third solve), so only the release tick's
//!   finger output can differ;
//! - the finger's force and torque within 1e-9 relative of their size (or
//!   of 1 N / 1 N·m near zero). The round-off of either solve is about
//!   cond(A) · ε ≈ 1e-16 · 1e4 on this A (diagonal 1e-1..1e3 after the
//!   row scaling) times cond(W) ≤ 1e2 for the correction: 1e-10 relative
//!   at most; 1e-9 leaves a decade and fails on any real difference (a
//!   released row left in the solve changes the force by 0.8 N, the
//!   limits' pull).

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::mechanisms::stewart;
use haptloop_solver::{FingerTarget, SolverSettings, TickOutcome};

use super::release_spare::{lift, start_of};
use crate::common::*;
use crate::lockstep::{Agree, agree, lockstep, same_state};

#[test]
fn the_low_rank_release_agrees_with_solving_afresh_within_round_off() {
    let mut fast = program(stewart(), SolverSettings::default());
    let mut fresh = program(stewart(), SolverSettings::default());
    fresh.drop_release_spare();
    let first = [FingerTarget::at(fast.finger_outputs()[0].attachment_m)];
    let start = {
        let _ = (fast.tick(&first, DT), fresh.tick(&first, DT));
        start_of(&fast)
    };
    let ticks = if cfg!(debug_assertions) { 4600 } else { 6000 };
    let (mut worst_f, mut worst_t) = (0.0f64, 0.0f64);
    let pair = (&mut fast, &mut fresh);
    lockstep(
        "stewart",
        pair,
        1..ticks,
        |k| lift(&start, k),
        |k, a, b| {
            same_state(k, a, b);
            let (x, y) = (a.finger_outputs()[0], b.finger_outputs()[0]);
            let forces = [
                (x.force_n, y.force_n),
                (x.constraint_force_n, y.constraint_force_n),
            ];
            let torques = [
                (x.torque_nm, y.torque_nm),
                (x.constraint_torque_nm, y.constraint_torque_nm),
            ];
            worst_f = worst_f.max(agree(k, Agree::Relative(1e-9), &forces));
            worst_t = worst_t.max(agree(k, Agree::Relative(1e-9), &torques));
        },
    );
    eprintln!(
        "releases {} low-rank {} kept {}; worst relative difference force {worst_f:e}, torque {worst_t:e}",
        fast.force_releases(),
        fast.force_low_rank_releases(),
        fast.force_first_solves_kept()
    );
    let held = ticks - 4000;
    assert_eq!(fast.force_releases(), fresh.force_releases());
    assert!(
        fast.force_low_rank_releases() > held as u64 / 2,
        "{} of {} releases took the low-rank correction",
        fast.force_low_rank_releases(),
        fast.force_releases()
    );
    assert!(fast.force_first_solves_kept() >= fast.force_low_rank_releases());
    assert_eq!(fresh.force_low_rank_releases(), 0);
    // Held against the stops, the low-rank releases allocate nothing.
    let before = fast.force_low_rank_releases();
    let hold = lift(&start, ticks);
    let (ok, stats) = count(|| (0..200).all(|_| fast.tick(&hold, DT).status == TickOutcome::Ok));
    assert!(ok && is_installed());
    assert_eq!(stats.total(), 0, "the held ticks allocated: {stats:?}");
    assert!(
        fast.force_low_rank_releases() > before + 50,
        "the low-rank path did not run while counted"
    );
}
