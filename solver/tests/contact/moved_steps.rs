//! The projected steps evaluate and multiply only the contact rows of
//! bodies that move (`al::moved`), and an in-tick activation refactors
//! without a multiplier solve (`program::activation`); a run whose steps
//! evaluate every row (`Program::set_full_steps`) and whose activations
//! run the whole `force_active` (`Program::set_full_activation`) must move
//! and push exactly the same, tick for tick, including the in-tick
//! activations of contacts that arrive in the middle of a tick.

use haptloop_rt::alloc::count;
use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::mechanisms::cluttered_builder;
use haptloop_solver::{FingerTarget, SolverSettings, TickOutcome};
use nalgebra::Vector3;

use crate::common::Lockstep;

/// Ticks of the drag (fewer in unoptimised builds: the same contacts
/// arrive, the drag is only shorter).
fn ticks() -> usize {
    if cfg!(debug_assertions) { 260 } else { 700 }
}

/// The hand's target at tick `k`: along +x into the clutter, 0.2 mm per tick
/// (the dragged box meets the first column after ~230 ticks).
fn target(start: FingerTarget, k: usize) -> FingerTarget {
    FingerTarget {
        position_m: start.position_m + Vector3::new(0.0002 * k as f64, 0.0, 0.0),
        ..start
    }
}

struct Run {
    /// Per tick: q, the finger force, penetration, in-tick activations.
    ticks: Vec<(Vec<f64>, Vector3<f64>, f64, u32)>,
    skipped: u64,
    allocations: u64,
}

fn run(full: bool, dynamics: bool) -> Run {
    let model = cluttered_builder(9).build().expect("model");
    let settings = SolverSettings {
        dynamics,
        ..SolverSettings::default()
    };
    let mut l = Lockstep::new(model, settings, ContactSettings::default());
    let start = l.program.model().initial_targets()[0];
    let (mut out, mut skipped, mut allocations) = (Vec::new(), 0, 0);
    for k in 0..ticks() {
        // A program the slow loop replaces starts with the defaults.
        l.program.set_full_steps(full);
        l.program.set_full_activation(full);
        let before = l.program.step_contacts_skipped();
        let t = [target(start, k)];
        // The tick alone under the counter, then the contact cycle.
        let (r, stats) = count(|| l.program.tick(&t, l.dt));
        allocations += stats.total();
        skipped += l.program.step_contacts_skipped() - before;
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        let f = l.program.finger_outputs()[0].force_n;
        out.push((
            l.program.q().to_vec(),
            f,
            r.max_penetration_m,
            r.activations,
        ));
        l.cycle_after(r);
    }
    Run {
        ticks: out,
        skipped,
        allocations,
    }
}

fn compare(dynamics: bool) {
    let (cheap, full) = (run(false, dynamics), run(true, dynamics));
    let activations: u32 = cheap.ticks.iter().map(|t| t.3).sum();
    println!(
        "dynamics {dynamics}: {} contact constraints skipped, {activations} in-tick activations",
        cheap.skipped
    );
    assert_eq!(full.skipped, 0, "the full run skipped rows");
    assert!(cheap.skipped > 0, "the cheap run evaluated every row");
    assert!(activations > 0, "no contact arrived within a tick");
    assert_eq!(cheap.allocations, 0, "the cheap steps allocated");
    for (k, (a, b)) in cheap.ticks.iter().zip(&full.ticks).enumerate() {
        let dq =
            a.0.iter()
                .zip(&b.0)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
        assert!(dq <= 1e-12, "tick {k}: q differs by {dq:e}");
        assert!(
            (a.1 - b.1).norm() <= 1e-9,
            "tick {k}: force {} against {}",
            a.1,
            b.1
        );
        assert!((a.2 - b.2).abs() <= 1e-12, "tick {k}: penetration");
        assert_eq!(a.3, b.3, "tick {k}: in-tick activations");
    }
}

#[test]
fn steps_over_the_moving_bodies_equal_steps_over_every_row_kinematic() {
    compare(false);
}

#[test]
fn steps_over_the_moving_bodies_equal_steps_over_every_row_inertial() {
    // ~6 s unoptimised: the release suite checks it; the kinematic case
    // (most of the skipping and the activations) runs in both.
    if cfg!(debug_assertions) {
        return;
    }
    compare(true);
}
