//! The planar lattice's update settings (`scenes/lattice.toml`: two full
//! Gauss–Newton steps a tick) against the solver's defaults (four steps of
//! 0.9), both judged by the converged reference on the same hand path:
//! the cheaper setting must render the same force and hold the joints at
//! least as tightly (BENCHMARKS.md, "Issue 23 — the lattice's tick").

use haptloop::report::summary::Summary;
use haptloop::scenes::resolve;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::schedule::StopFlag;
use std::time::Duration;

const LATTICE: &str = include_str!("../../scenes/lattice.toml");

fn summary(path: &str) -> Summary {
    let scene = resolve(path).unwrap();
    let options = SessionOptions {
        seconds: 0.5,
        deterministic: true,
        reference_every: Some(Duration::from_millis(10)),
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &options).unwrap();
    let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    Summary::of(&o)
}

#[test]
fn two_full_steps_render_the_four_damped_steps_force_with_tighter_joints() {
    let chosen = "step = 1.0\niterations = 2\n";
    assert!(
        LATTICE.contains(chosen),
        "the scene's update settings moved"
    );
    let dir = tempfile::tempdir().unwrap();
    let defaults = dir.path().join("lattice-defaults.toml");
    std::fs::write(&defaults, LATTICE.replace(chosen, "")).unwrap();
    let scene = summary("lattice");
    let default = summary(defaults.to_str().unwrap());
    assert_eq!((scene.iterations, default.iterations), (2, 4));
    for s in [&scene, &default] {
        assert_eq!(s.safety.solver_failures, 0);
        assert_eq!(s.violation.ticks_failed, 0);
        let r = &s.reference;
        assert_eq!(r.missing, None);
        assert_eq!(r.compared, 50, "{r:?}");
        assert!(
            r.force_n.max > 0.1 && r.force_error_n.max.is_finite(),
            "{r:?}"
        );
    }
    let (a, b) = (&scene.reference, &default.reference);
    // Measured: 1.07e-3 N both (largest force 0.4 N): the same to 1 %.
    assert!(
        a.force_error_n.max <= 1.01 * b.force_error_n.max
            && a.force_error_n.rms <= 1.01 * b.force_error_n.rms,
        "two full steps {:?} vs four of 0.9 {:?}",
        a.force_error_n,
        b.force_error_n
    );
    assert!(a.force_error_n.max <= 0.01 * a.force_n.max);
    // Measured: 4.0e-11 m against 1.5e-10 m.
    assert!(
        scene.violation.max <= default.violation.max,
        "two full steps {:e} m vs four of 0.9 {:e} m",
        scene.violation.max,
        default.violation.max
    );
}
