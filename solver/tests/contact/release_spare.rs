//! The release branch's spare (`force::feedback`) on contacts: without
//! inertial motion a contact row that pulls is released and the solve runs
//! again, and a sticking pair whose friction load leaves the cone slips.
//! Here the released rows touch the finger's body (A_FJ), which the
//! Stewart test's leg limits do not. A box pushed, lifted at one edge and
//! dragged by a contact finger, ticked in lockstep with a run whose
//! programs solve every step afresh, agrees bit for bit.

use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::{
    BodySpec, FingerSpec, FingerTarget, ModelBuilder, SolverSettings, TickOutcome,
};
use nalgebra::Vector3;

use crate::common::{Lockstep, cuboid};

pub(crate) fn pushed_box() -> Lockstep {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(cuboid([0.3, 0.3, 0.02]))
            .friction(0.4),
    );
    b.body(
        BodySpec::new("box")
            .at([0.0, 0.0, 0.03])
            .shape(cuboid([0.03, 0.03, 0.03]))
            .density(500.0)
            .friction(0.4),
    );
    b.finger(FingerSpec::contact(
        "index",
        [-0.045, 0.0, 0.03],
        0.008,
        0.0,
    ));
    Lockstep::new(
        b.build().unwrap(),
        SolverSettings::default(),
        ContactSettings::default(),
    )
}

/// Pushes 3 cm along x while rising 2 cm and pressing down at the end.
pub(crate) fn target(k: usize) -> [FingerTarget; 1] {
    let t = (k + 1) as f64 * 1e-3;
    let x = -0.045 + (0.05 * t).min(0.03);
    let z = 0.03 + 0.02 * (t - 0.6).clamp(0.0, 0.6) - 0.03 * (t - 1.2).clamp(0.0, 0.4);
    [FingerTarget::at(Vector3::new(x, 0.0, z))]
}

#[test]
fn contact_releases_with_the_spare_are_bit_identical_to_solving_afresh() {
    let (mut fast, mut fresh) = (pushed_box(), pushed_box());
    let ticks = if cfg!(debug_assertions) { 800 } else { 1600 };
    // Programs are replaced as pairs come and go: their counters restart.
    let (mut releases, mut kept, mut last) = (0, 0, (0, 0));
    for k in 0..ticks {
        fresh.program.drop_release_spare();
        // The spare alone: the low-rank correction is compared within
        // round-off in `release_low_rank`.
        fast.program.drop_release_low_rank();
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
        assert!(
            x.force_n == y.force_n,
            "tick {k}: {:?} {:?}",
            x.force_n,
            y.force_n
        );
        assert_eq!(
            fast.program.force_releases(),
            fresh.program.force_releases()
        );
        assert_eq!(fresh.program.force_first_solves_kept(), 0);
        let now = (
            fast.program.force_releases(),
            fast.program.force_first_solves_kept(),
        );
        if now.0 < last.0 {
            last = (0, 0);
        }
        releases += now.0 - last.0;
        kept += now.1 - last.1;
        last = now;
    }
    eprintln!("releases {releases} kept {kept} programs {}", fast.programs);
    assert!(
        releases > 10,
        "{releases} releases: the branch was not exercised"
    );
}
