//! The low-rank release (`force::solve`'s `low_rank`) on contacts: the
//! released contact rows touch the finger's body, so the correction's
//! A_FJ term (S' = S + Hᵀ H) carries the change, which the Stewart test's
//! leg limits barely exercise. The box of `release_spare`, in lockstep
//! with a run whose programs solve every step afresh: q and the steps' λ
//! equal to the bit (the steps factor the first active set in both), the
//! finger's force within 1e-9 relative of its size or of 1 N (the
//! Stewart test's bound; the argument is the same: round-off of a factor
//! with cond ≈ 1e4, times cond(W)).

use haptloop_solver::TickOutcome;

use super::release_spare::{pushed_box, target};

#[test]
fn contact_releases_by_the_low_rank_correction_agree_with_solving_afresh() {
    let (mut fast, mut fresh) = (pushed_box(), pushed_box());
    let ticks = if cfg!(debug_assertions) { 800 } else { 1600 };
    // Programs are replaced as pairs come and go: their counters restart.
    let (mut low_rank, mut last, mut worst) = (0, 0, 0.0f64);
    for k in 0..ticks {
        fresh.program.drop_release_spare();
        let (a, b) = (fast.tick(&target(k)), fresh.tick(&target(k)));
        assert_eq!(a.status, b.status, "tick {k}");
        assert_eq!(a.status, TickOutcome::Ok, "tick {k}");
        assert!(fast.program.q() == fresh.program.q(), "tick {k}: q");
        assert!(
            fast.program.lambda() == fresh.program.lambda(),
            "tick {k}: λ"
        );
        let (x, y) = (
            fast.program.finger_outputs()[0],
            fresh.program.finger_outputs()[0],
        );
        for (u, v) in [
            (x.force_n, y.force_n),
            (x.constraint_force_n, y.constraint_force_n),
        ] {
            let rel = (u - v).norm() / v.norm().max(1.0);
            worst = worst.max(rel);
            assert!(rel <= 1e-9, "tick {k}: {u:?} against {v:?} ({rel:e})");
        }
        assert_eq!(
            fast.program.force_releases(),
            fresh.program.force_releases()
        );
        assert_eq!(fresh.program.force_low_rank_releases(), 0);
        let now = fast.program.force_low_rank_releases();
        if now < last {
            last = 0;
        }
        low_rank += now - last;
        last = now;
    }
    eprintln!("low-rank releases {low_rank}, worst relative force difference {worst:e}");
    assert!(
        low_rank > 10,
        "{low_rank} low-rank releases: the path was not exercised"
    );
}
