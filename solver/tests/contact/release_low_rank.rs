//! The low-rank release (`force::solve`'s `low_rank`) on contacts: the
//! released contact rows touch the finger's body, so the correction's
//! A_FJ term (S' = S + Hᵀ H) carries the change, which the Stewart test's
//! leg limits barely exercise. The box of `release_spare`, in lockstep
//! with a run whose programs solve every step afresh: q and the steps' λ
//! equal to the bit (the steps factor the first active set in both), the
//! finger's force within 1e-9 relative of its size or of 1 N (the
//! Stewart test's bound; the argument is the same: round-off of a factor
//! with cond ≈ 1e4, times cond(W)).

use super::release_spare::{pushed_box, target};
use crate::lockstep::{Agree, Restarting, agree, lockstep, same_state};

#[test]
fn contact_releases_by_the_low_rank_correction_agree_with_solving_afresh() {
    let (mut fast, mut fresh) = (pushed_box(), pushed_box());
    let ticks = if cfg!(debug_assertions) { 800 } else { 1600 };
    // Programs are replaced as pairs come and go: their counters restart,
    // and each new reference program drops its spare again.
    let (mut low_rank, mut worst) = (Restarting::default(), 0.0f64);
    fresh.program.drop_release_spare();
    lockstep(
        "box",
        (&mut fast, &mut fresh),
        0..ticks,
        target,
        |k, fast, fresh| {
            let (a, b) = (&fast.program, &fresh.program);
            same_state(k, a, b);
            let (x, y) = (a.finger_outputs()[0], b.finger_outputs()[0]);
            let forces = [
                (x.force_n, y.force_n),
                (x.constraint_force_n, y.constraint_force_n),
            ];
            worst = worst.max(agree(k, Agree::Relative(1e-9), &forces));
            assert_eq!(a.force_releases(), b.force_releases());
            assert_eq!(b.force_low_rank_releases(), 0);
            low_rank.add(a.force_low_rank_releases());
            fresh.program.drop_release_spare();
        },
    );
    let low_rank = low_rank.total;
    eprintln!("low-rank releases {low_rank}, worst relative force difference {worst:e}");
    assert!(
        low_rank > 10,
        "{low_rank} low-rank releases: the path was not exercised"
    );
}
