//! Inertial ticks allocate nothing: contact with friction (sticking,
//! breaking loose, sliding; the block is pushed off its centre line, so its
//! patch's twist row holds and its twisting friction acts), restitution and the energy account, on every
//! program the slow loop hands over (counted from their first tick).

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::geometry::Shape;
use haptloop_solver::{BodySpec, FingerSpec, FingerTarget, ModelBuilder, TickOutcome};
use nalgebra::Vector3;

use crate::common::{G, cuboid, lockstep};

#[test]
fn inertial_ticks_allocate_nothing() {
    assert!(is_installed());
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -G]);
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(cuboid([0.3, 0.3, 0.02]))
            .friction(0.5),
    );
    b.body(
        BodySpec::new("block")
            .at([0.0, 0.0, 0.03])
            .shape(cuboid([0.03, 0.03, 0.03]))
            .mass(0.1)
            .friction(0.5),
    );
    b.body(
        BodySpec::new("ball")
            .at([0.1, 0.0, 0.05])
            .shape(Shape::Sphere { radius_m: 0.01 })
            .restitution(0.8),
    );
    b.finger(FingerSpec::contact(
        "index",
        [-0.04, 0.015, 0.03],
        0.008,
        0.0,
    ));
    let mut l = lockstep(b.build().unwrap(), 1000);
    let mut allocations = 0;
    let mut ticked = 0;
    for k in 0..1500 {
        let t = (k + 1) as f64 * 1e-3;
        let target = [FingerTarget::at(Vector3::new(
            -0.04 + 0.02 * t,
            0.015,
            0.03,
        ))];
        // The slow loop's cycles allocate (off the real-time thread): the
        // ticks that end in one go through the lockstep, every other tick
        // is counted.
        if (k + 1) % 5 == 0 {
            assert_eq!(l.tick(&target).status, TickOutcome::Ok);
            continue;
        }
        let (r, stats) = count(|| l.program.tick(&target, l.dt));
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        l.ticks += 1;
        allocations += stats.total();
        ticked += 1;
    }
    let (resolves, bounces) = l.program.transitions();
    println!(
        "alloc: {ticked} ticks counted, {resolves} re-solves, {bounces} bounces, {} slips",
        l.program.slips()
    );
    assert!(
        resolves > 0 && bounces > 0 && l.program.slips() > 0,
        "the path was not covered"
    );
    assert_eq!(allocations, 0);
}
