//! The release branch's spare (`force::feedback`) on contacts: without
//! inertial motion a contact row that pulls is released and the solve runs
//! again, and a sticking pair whose friction load leaves the cone slips.
//! Here the released rows touch the finger's body (A_FJ), which the
//! Stewart test's leg limits do not. A box pushed, lifted at one edge and
//! dragged by a contact finger, ticked in lockstep with a run whose
//! programs solve every step afresh, agrees bit for bit.

use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::{
    BodySpec, FingerSpec, FingerTarget, ModelBuilder, Program, SolverSettings, TickReport,
};
use nalgebra::Vector3;

use crate::common::{Lockstep, cuboid};
use crate::lockstep::{Agree, Restarting, Ticked, agree, lockstep, same_state};

/// A contact run ticks its program and then its contact cycle.
impl Ticked for Lockstep {
    fn step(&mut self, targets: &[FingerTarget]) -> TickReport {
        self.tick(targets)
    }
    fn program(&self) -> &Program {
        &self.program
    }
}

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
    // Programs are replaced as pairs come and go: their counters restart,
    // and each new program is told again what to drop.
    let (mut releases, mut kept) = (Restarting::default(), Restarting::default());
    let configure = |fast: &mut Lockstep, fresh: &mut Lockstep| {
        fresh.program.drop_release_spare();
        // The spare alone: the low-rank correction is compared within
        // round-off in `release_low_rank`.
        fast.program.drop_release_low_rank();
    };
    configure(&mut fast, &mut fresh);
    lockstep(
        "box",
        (&mut fast, &mut fresh),
        0..ticks,
        target,
        |k, fast, fresh| {
            let (a, b) = (&fast.program, &fresh.program);
            same_state(k, a, b);
            let (x, y) = (a.finger_outputs()[0], b.finger_outputs()[0]);
            agree(k, Agree::Bits, &[(x.force_n, y.force_n)]);
            assert_eq!(a.force_releases(), b.force_releases());
            assert_eq!(b.force_first_solves_kept(), 0);
            releases.add(a.force_releases());
            kept.add(a.force_first_solves_kept());
            configure(fast, fresh);
        },
    );
    let (releases, kept) = (releases.total, kept.total);
    eprintln!("releases {releases} kept {kept} programs {}", fast.programs);
    assert!(
        releases > 10,
        "{releases} releases: the branch was not exercised"
    );
}
