//! The lockstep harness: two programs (or two runs holding one each)
//! ticked on the same targets, compared tick by tick. Shared by the `al`
//! and `contact` test binaries (the latter includes this file by path).
#![allow(dead_code)] // shared by two binaries; not every one uses every helper

use std::ops::Range;

use haptloop_solver::{
    FingerTarget, ForceSolver, Model, Program, SolverSettings, TickOutcome, TickReport,
};
use nalgebra::Vector3;

/// 1 kHz.
const DT: std::time::Duration = std::time::Duration::from_millis(1);

/// What a lockstep run ticks: a program, or a run that holds one (the
/// contact tests' cycle, which replaces its program as pairs come and go).
pub trait Ticked {
    /// One tick on `targets`.
    fn step(&mut self, targets: &[FingerTarget]) -> TickReport;
    /// The program the last tick ran.
    fn program(&self) -> &Program;
}

impl Ticked for Program {
    fn step(&mut self, targets: &[FingerTarget]) -> TickReport {
        self.tick(targets, DT)
    }
    fn program(&self) -> &Program {
        self
    }
}

/// Ticks `a` then `b` on `targets(k)` for every `k` in `ticks`, asserts
/// both ticks Ok (`name` and `k` in the message), then calls `each(k, a,
/// b)`: the comparisons, and whatever must happen before the next tick.
pub fn lockstep<A: Ticked, B: Ticked, T: AsRef<[FingerTarget]>>(
    name: &str,
    (a, b): (&mut A, &mut B),
    ticks: Range<usize>,
    mut targets: impl FnMut(usize) -> T,
    mut each: impl FnMut(usize, &mut A, &mut B),
) {
    for k in ticks {
        let t = targets(k);
        let (ra, rb) = (a.step(t.as_ref()), b.step(t.as_ref()));
        assert_eq!(ra.status, TickOutcome::Ok, "{name} tick {k}: {ra:?}");
        assert_eq!(ra.status, rb.status, "{name} tick {k}");
        each(k, a, b);
    }
}

/// Asserts q and λ of the two programs equal to the bit.
pub fn same_state(k: usize, a: &Program, b: &Program) {
    assert!(a.q() == b.q(), "tick {k}: q differs");
    assert!(a.lambda() == b.lambda(), "tick {k}: λ differs");
}

/// How two vectors must agree.
#[derive(Clone, Copy, Debug)]
pub enum Agree {
    /// Equal to the bit.
    Bits,
    /// |u − v| ≤ tol · max(|v|, 1).
    Relative(f64),
}

/// Asserts each pair (u, v) agrees as `agree` says; returns the largest
/// relative difference |u − v| / max(|v|, 1).
pub fn agree(k: usize, agree: Agree, pairs: &[(Vector3<f64>, Vector3<f64>)]) -> f64 {
    let mut worst = 0.0f64;
    for &(u, v) in pairs {
        let rel = (u - v).norm() / v.norm().max(1.0);
        match agree {
            Agree::Bits => assert!(u == v, "tick {k}: {u:?} against {v:?}"),
            Agree::Relative(tol) => {
                assert!(rel <= tol, "tick {k}: {u:?} against {v:?} ({rel:e})")
            }
        }
        worst = worst.max(rel);
    }
    worst
}

/// Largest finger-force difference between two programs, and the largest
/// force (N).
pub fn force_gap(a: &Program, b: &Program) -> (f64, f64) {
    a.finger_outputs()
        .iter()
        .zip(b.finger_outputs())
        .fold((0.0, 0.0), |(gap, big), (x, y)| {
            let (fx, fy) = (x.constraint_force_n, y.constraint_force_n);
            (gap.max((fx - fy).norm()), big.max(fy.norm()))
        })
}

/// A counter summed over programs that replace each other (each new
/// program's counters restart at zero).
#[derive(Default, Debug)]
pub struct Restarting {
    /// The sum so far.
    pub total: u64,
    last: u64,
}

impl Restarting {
    /// Adds what the counter reading `now` grew by since the last reading.
    pub fn add(&mut self, now: u64) {
        if now < self.last {
            self.last = 0;
        }
        self.total += now - self.last;
        self.last = now;
    }
}

/// The iterative force solvers' comparison settings: full steps, three
/// iterations, `force_solver`.
pub fn settings(force_solver: ForceSolver) -> SolverSettings {
    SolverSettings {
        step: 1.0,
        iterations: 3,
        force_solver,
        ..SolverSettings::default()
    }
}

/// The model's targets moved `a` metres along a fixed direction.
pub fn moved(model: &Model, a: f64) -> Vec<FingerTarget> {
    model
        .initial_targets()
        .into_iter()
        .map(|t| FingerTarget::at(t.position_m + Vector3::new(0.6, -0.3, 0.2) * a))
        .collect()
}

/// The iterative tick's comparison with the Cholesky tick over a motion
/// (see [`follow`]).
#[derive(Debug, Default)]
pub struct Followed {
    /// Largest finger-force gap, N.
    pub worst: f64,
    /// Largest finger force, N.
    pub scale: f64,
    /// Largest violation of the iterative tick, m.
    pub viol: f64,
    /// Largest force-solve iteration count of the iterative tick.
    pub its: u32,
}

/// Ticks `iterative` and `exact` (a Cholesky tick), programs of `model`,
/// in lockstep over `ticks` ticks of a sinusoidal motion (`moved`, 3 mm), calling
/// `each(k, iterative, exact)` after each tick; returns the largest force
/// gap, force, violation and iteration count.
pub fn follow(
    name: &str,
    model: &Model,
    (iterative, exact): (&mut Program, &mut Program),
    ticks: usize,
    mut each: impl FnMut(usize, &Program, &Program),
) -> Followed {
    let mut f = Followed::default();
    let motion = |k: usize| moved(model, 0.003 * (k as f64 * 0.05).sin());
    lockstep(name, (iterative, exact), 0..ticks, motion, |k, it, ex| {
        f.viol = f.viol.max(it.last_report().max_violation_m);
        f.its = f.its.max(it.force_cg_iterations());
        let (gap, big) = force_gap(it, ex);
        f.worst = f.worst.max(gap);
        f.scale = f.scale.max(big);
        each(k, it, ex);
    });
    f
}

/// The comparison fails on a one-ulp difference when bits are asked for,
/// and on a difference just over the tolerance when a relative one is;
/// it passes equal vectors and returns the relative difference.
#[test]
fn the_comparison_fails_on_what_it_must() {
    let v = Vector3::new(2.0, -3.0, 0.5);
    let ulp = Vector3::new(f64::from_bits(2.0f64.to_bits() + 1), -3.0, 0.5);
    assert_eq!(agree(0, Agree::Bits, &[(v, v)]), 0.0);
    let bits = std::panic::catch_unwind(|| agree(0, Agree::Bits, &[(ulp, v)]));
    assert!(bits.is_err(), "a one-ulp difference passed as bit for bit");
    let rel = agree(0, Agree::Relative(1e-9), &[(ulp, v)]);
    assert!(rel > 0.0 && rel < 1e-15, "{rel:e}");
    let over = v + Vector3::new(2e-9 * v.norm(), 0.0, 0.0);
    let far = std::panic::catch_unwind(|| agree(0, Agree::Relative(1e-9), &[(over, v)]));
    assert!(far.is_err(), "a difference of 2e-9 passed a 1e-9 tolerance");
}
