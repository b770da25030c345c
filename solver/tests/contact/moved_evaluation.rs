//! Evaluations leave alone the contact rows whose bodies and witnesses are
//! unchanged since they were written (`evaluate::since`): a run with that
//! shortcut must hold the same C and C_q, bit for bit, as a run whose
//! evaluations write every row (`Program::set_full_evaluation`), tick for
//! tick, through the slow loop's tables and through tables handed over
//! mid-run that change rows of bodies that did not move (a margin nudged,
//! a zero's sign flipped: `==` would call those the same witness).

use haptloop_rt::alloc::count;
use haptloop_solver::constraint::witness::Witness;
use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::mechanisms::cluttered_builder;
use haptloop_solver::{FingerTarget, SolverSettings, TickOutcome};
use nalgebra::Vector3;

use crate::common::Lockstep;

/// Ticks of the drag (fewer in unoptimised builds).
fn ticks() -> usize {
    if cfg!(debug_assertions) { 120 } else { 600 }
}

/// A table handed over every this many ticks, besides the slow loop's.
const NUDGE_EVERY: usize = 37;

fn target(start: FingerTarget, k: usize) -> FingerTarget {
    FingerTarget {
        position_m: start.position_m + Vector3::new(0.0002 * k as f64, 0.0, 0.0),
        ..start
    }
}

/// The table in use with every used plane slot's margin nudged by `n` ×
/// 1e-12 m and the zeros of its normal's sign flipped: rows of resting
/// bodies change, some only in the sign of a zero.
fn nudged(table: &[Witness], n: usize) -> Vec<Witness> {
    let mut t = table.to_vec();
    for w in &mut t {
        if let Witness::Plane(p) = w {
            p.margin += (n % 3) as f64 * 1e-12;
            for v in p.normal.iter_mut() {
                if *v == 0.0 {
                    *v = -*v;
                }
            }
        }
    }
    t
}

/// Per tick: the bits of q, C, C_q's values and the finger force.
type Bits = (Vec<u64>, Vec<u64>, Vec<u64>, [u64; 3]);

struct Run {
    ticks: Vec<Bits>,
    skipped: u64,
    nudges: usize,
    tables: u64,
    allocations: u64,
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn run(full: bool, dynamics: bool) -> Run {
    let model = cluttered_builder(9).build().expect("model");
    let settings = SolverSettings {
        dynamics,
        ..SolverSettings::default()
    };
    let mut l = Lockstep::new(model, settings, ContactSettings::default());
    let start = l.program.model().initial_targets()[0];
    let (mut out, mut skipped, mut allocations, mut nudges) = (Vec::new(), 0, 0, 0);
    for k in 0..ticks() {
        // A program the slow loop replaces starts with the defaults.
        l.program.set_full_evaluation(full);
        if k % NUDGE_EVERY == NUDGE_EVERY - 1 {
            let table = nudged(l.program.witnesses(), k / NUDGE_EVERY);
            assert!(l.program.apply_witnesses(&table));
            nudges += 1;
        }
        let before = l.program.evaluation_contacts_skipped();
        let t = [target(start, k)];
        let (r, stats) = count(|| l.program.tick(&t, l.dt));
        allocations += stats.total();
        skipped += l.program.evaluation_contacts_skipped() - before;
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        let ev = l.program.evaluation();
        let f = l.program.finger_outputs()[0].force_n;
        out.push((
            bits(l.program.q()),
            bits(ev.values()),
            bits(ev.jacobian().values()),
            [f.x.to_bits(), f.y.to_bits(), f.z.to_bits()],
        ));
        l.cycle_after(r);
    }
    Run {
        ticks: out,
        skipped,
        nudges,
        tables: l.tables,
        allocations,
    }
}

/// `skips`: the shortcut must have left rows alone (kinematic: resting
/// bodies keep their coordinates bit for bit; under inertial motion every
/// body on the table creeps a few ulps a tick, so every row is written and
/// only the equality is checked).
fn compare(dynamics: bool, skips: bool) {
    let (cheap, full) = (run(false, dynamics), run(true, dynamics));
    println!(
        "dynamics {dynamics}: {} contact constraints left alone by the Jacobian evaluations, \
         {} slow-loop tables, {} nudged tables",
        cheap.skipped, cheap.tables, cheap.nudges
    );
    assert_eq!(full.skipped, 0, "the full run left rows alone");
    if skips {
        assert!(cheap.skipped > 0, "the cheap run wrote every row");
    }
    assert!(cheap.nudges > 0, "no nudged table handed over");
    // The slow loop's first table comes with the first new contact (~230
    // ticks in): the short unoptimised run has only the nudged ones.
    if !cfg!(debug_assertions) {
        assert!(cheap.tables > 0, "no slow-loop table handed over");
    }
    assert_eq!(cheap.allocations, 0, "the cheap evaluations allocated");
    for (k, (a, b)) in cheap.ticks.iter().zip(&full.ticks).enumerate() {
        assert!(a.0 == b.0, "tick {k}: q differs");
        assert!(a.1 == b.1, "tick {k}: C differs");
        assert!(a.2 == b.2, "tick {k}: C_q differs");
        assert_eq!(a.3, b.3, "tick {k}: finger force");
    }
}

#[test]
fn evaluations_over_the_moving_bodies_equal_evaluations_of_every_row_kinematic() {
    compare(false, true);
}

#[test]
fn evaluations_over_the_moving_bodies_equal_evaluations_of_every_row_inertial() {
    // Unoptimised, the kinematic case runs alone; the release suite checks both.
    if cfg!(debug_assertions) {
        return;
    }
    compare(true, false);
}
