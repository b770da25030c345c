//! Issue 23: a resting pile keeps its contact rows active. A pile of n
//! layers needs n in-tick activations to catch gravity's first step (each
//! held layer lets the next one fall into it), one more than a tick's
//! refactorisation budget from four layers up; rows activated in a tick that
//! ran out were dropped by its force solve (gap 0, no multiplier from a
//! step), so every tick started again with none active and stopped at the
//! limit without stepping: 21 ms a tick on 64 spheres, and a finger touching
//! nothing dragged 2 mm behind its device.

use haptloop::report::summary::Summary;
use haptloop::scenes::check_loaded;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::program::MAX_ACTIVATIONS;
use haptloop_solver::scene;
use std::fmt::Write;

/// A 2 × 2 × `layers` pile of touching 1 cm spheres on a table, dynamics on,
/// and a contact finger far away moving 1 cm in a second.
fn pile(layers: usize) -> String {
    let mut t = String::from(
        "[scene]\nname=\"pile\"\ngravity=[0,0,-9.81]\n[solver]\ndynamics=true\n\
         [[device]]\nname=\"right\"\nmodel=\"phantom-premium-1.5\"\n\
         hand={waypoints=[[0,0,0,0],[1,0.01,0,0]]}\n\
         [[finger]]\nname=\"f\"\ndevice=\"right\"\ngrasp=\"contact\"\nposition=[0.5,0.5,0.3]\n\
         [[body]]\nname=\"table\"\nfixed=true\nposition=[0,0,-0.02]\nshape={box=[1,1,0.02]}\n",
    );
    for k in 0..layers {
        for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let (x, y, z) = (0.02 * i as f64, 0.02 * j as f64, 0.01 + 0.02 * k as f64);
            write!(
                t,
                "[[body]]\nname=\"s{k}{i}{j}\"\nposition=[{x},{y},{z}]\nshape={{sphere=0.01}}\n"
            )
            .unwrap();
        }
    }
    t
}

fn run(layers: usize, seconds: f64) -> Summary {
    let loaded = scene::parse("pile.toml", &pile(layers), None).unwrap();
    let scene = check_loaded(loaded).unwrap();
    let options = SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &options).unwrap();
    let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    Summary::of(&o)
}

/// Five layers (one more than the budget + 1): the activations are the
/// first tick's, bounded by the budget, not one set a tick; every sphere
/// rests on one row (4 on the table, 4 per layer above: 4 × layers rows
/// active, the side contacts carry nothing), nothing penetrates and the
/// free finger tracks its device.
#[test]
fn a_resting_pile_keeps_its_rows_active() {
    let layers = MAX_ACTIVATIONS as usize + 2;
    let s = run(layers, 0.2);
    let c = s.contact.as_ref().expect("a contact scene reports contact");
    assert_eq!(s.safety.solver_failures, 0, "failed ticks");
    assert!(
        c.activations <= 2 * u64::from(MAX_ACTIVATIONS),
        "{} in-tick activations in 200 ticks ({} at the limit)",
        c.activations,
        c.activation_limit_ticks
    );
    assert!(c.activation_limit_ticks <= 1, "{c:?}");
    assert_eq!(c.max_active as usize, 4 * layers, "{c:?}");
    assert!(c.max_penetration_m <= c.tolerance_m, "{c:?}");
    assert!(s.tracking_m.max < 1e-4, "tracking {:?}", s.tracking_m);
}
