//! The release branch without its repeated work (`force::feedback`'s
//! spare): against a stop an active limit pulls and is released every tick,
//! and the force solve ran three times (assembly, factorisation, finger
//! solve each). With the spare the second solve masks the first's A and the
//! third takes the first back. Both must be exact: a Stewart platform lifted
//! into its stroke limits, ticked in lockstep with a program that solves
//! every step afresh, agrees bit for bit on every tick.

use haptloop_solver::mechanisms::stewart;
use haptloop_solver::{FingerTarget, Program, SolverSettings};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::common::*;
use crate::lockstep::{Agree, agree, lockstep, same_state};

/// The finger's target `k` ticks in: 10 cm up over 4 s, then held, the
/// platform's start orientation kept.
pub(crate) fn lift(start: &FingerTarget, k: usize) -> [FingerTarget; 1] {
    let s = (k as f64 * DT.as_secs_f64() / 4.0).min(1.0);
    [FingerTarget {
        position_m: start.position_m + Vector3::new(0.0, 0.0, 0.10 * s),
        orientation: start.orientation,
    }]
}

pub(crate) fn start_of(p: &Program) -> FingerTarget {
    let m = p.model();
    let o = (m.layout())
        .body_offset(m.body_id("platform").expect("platform"))
        .expect("moving");
    let e = &p.q()[o + 3..o + 7];
    FingerTarget {
        position_m: p.finger_outputs()[0].attachment_m,
        orientation: UnitQuaternion::from_quaternion(Quaternion::new(e[0], e[1], e[2], e[3])),
    }
}

#[test]
fn the_release_branch_with_the_spare_is_bit_identical_to_solving_afresh() {
    let mut fast = program(stewart(), SolverSettings::default());
    let mut fresh = program(stewart(), SolverSettings::default());
    fresh.drop_release_spare();
    // The spare alone (the masked refactorisation): the low-rank
    // correction is compared within round-off in `release_low_rank`.
    fast.drop_release_low_rank();
    // One tick at the start pose places the finger.
    let first = [FingerTarget::at(fast.finger_outputs()[0].attachment_m)];
    let start = {
        let _ = (fast.tick(&first, DT), fresh.tick(&first, DT));
        start_of(&fast)
    };
    let ticks = if cfg!(debug_assertions) { 4600 } else { 6000 };
    let pair = (&mut fast, &mut fresh);
    lockstep(
        "stewart",
        pair,
        1..ticks,
        |k| lift(&start, k),
        |k, a, b| {
            same_state(k, a, b);
            let (x, y) = (a.finger_outputs()[0], b.finger_outputs()[0]);
            let outputs = [
                (x.force_n, y.force_n),
                (x.torque_nm, y.torque_nm),
                (x.constraint_force_n, y.constraint_force_n),
            ];
            agree(k, Agree::Bits, &outputs);
        },
    );
    eprintln!(
        "releases {} kept {}",
        fast.force_releases(),
        fast.force_first_solves_kept()
    );
    // The stops held on most of the held ticks, each a release, and the
    // spare served them; the reference never used it.
    let held = ticks - 4000;
    assert!(
        fast.force_releases() > held as u64 / 2,
        "{} releases",
        fast.force_releases()
    );
    assert_eq!(fast.force_releases(), fresh.force_releases());
    assert!(
        fast.force_first_solves_kept() > held as u64 / 2,
        "{} of {} releases kept the first solve",
        fast.force_first_solves_kept(),
        fast.force_releases()
    );
    assert_eq!(fresh.force_first_solves_kept(), 0);
    assert_eq!(fast.force_low_rank_releases(), 0);
}
