//! Bodies at rest on others under gravity (inertial motion on): they stay
//! put, pressed on their supports, without sinking or creeping.

use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::{BodySpec, ModelBuilder, SolverSettings, TickOutcome};

use crate::common::{Lockstep, cuboid};

fn dynamics() -> SolverSettings {
    SolverSettings {
        dynamics: true,
        ..SolverSettings::default()
    }
}

/// A 6 cm box resting on a fixed table stays where it is for 2 s.
#[test]
fn a_box_rests_on_a_table() {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(cuboid([0.3, 0.3, 0.02])),
    );
    b.body(
        BodySpec::new("box")
            .at([0.0, 0.0, 0.03])
            .shape(cuboid([0.03, 0.03, 0.03]))
            .density(500.0),
    );
    let model = b.build().unwrap();
    let mut l = Lockstep::new(model, dynamics(), ContactSettings::default());
    let mut worst: f64 = 0.0;
    for k in 0..2000 {
        let r = l.tick(&[]);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        // Resting on its corners: at least three rows carry the weight.
        assert!(
            r.active_contacts >= 3,
            "tick {k}: {} rows active",
            r.active_contacts
        );
        let p = l.position("box");
        worst = worst.max((p - nalgebra::Vector3::new(0.0, 0.0, 0.03)).norm());
    }
    // The pair stays tracked with the same features: no new program, no
    // backup, and no penetration beyond the contact rows' compliance (1e-6
    // of their scale: picometres under a 108 g box).
    assert_eq!((l.programs, l.backups), (0, 0));
    assert!(l.max_penetration_m < 1e-9, "{}", l.max_penetration_m);
    assert!(worst < 1e-9, "the box moved {worst} m");
}
