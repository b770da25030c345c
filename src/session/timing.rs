//! What the solver's tick costs on this machine, measured: `Program::tick`
//! (the update's iterations, the Eq. 7–8 force solve, the coupling) timed
//! with the monotonic clock (`haptloop_rt::clock`, the only reader of the
//! OS clock) around each tick of a deterministic session.
//!
//! ```text
//!  Plan ──► time_ticks: the session, built on the mock clock (the accuracy run's inputs)
//!             per tick: FastLoop::tick (devices, program, safety; untimed)
//!                       t0 = now · shadow Program::tick(same targets, same period) · t1 = now
//!                       slow loop in lockstep every 5 ms · trace drained (untimed)
//!        ──► TickTiming { p50, p99, max, over_period, replay_exact }
//! ```
//!
//! The shadow is a second copy of the session's program, built the same
//! way and fed the same targets: it repeats the session's solver ticks bit
//! for bit unless the slow loop hands the session a new program or contact
//! rows (`replay_exact` says whether it stayed identical). The simulated
//! devices are not timed: a real device's read and write are I/O, not this
//! simulation's physics sub-steps.
//!
//! This is the one function the sweep times with; `haptloop bench` (per
//! stage) can take its place behind the same boundary. The ticks run back to
//! back on the calling thread, so caches stay warm: the pinned real-time
//! thread, which sleeps between ticks, measured 1.4–2× these figures for a
//! whole tick (BENCHMARKS.md, sessions). Timing never changes a result: the
//! session is the deterministic one the accuracy runs use, without
//! reference sampling.

use super::{Plan, SLOW_PERIOD, build};
use crate::scenes::Scene;
use anyhow::Result;
use haptloop_rt::clock::{Clock, MockClock, MonotonicClock, Nanos};
use haptloop_rt::schedule::{SafetyEvent, Tick, TickBody, TickStatus};

/// The measured cost of the ticks of one session, ns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TickTiming {
    /// Ticks timed.
    pub ticks: u64,
    /// Median.
    pub p50_ns: u64,
    /// 99th percentile.
    pub p99_ns: u64,
    /// Largest.
    pub max_ns: u64,
    /// Ticks that took longer than the period: overruns the loop would have
    /// at this rate from the solver alone (device I/O, the host's wake-up
    /// lateness and stalls come on top; `haptloop probe` measures those).
    pub over_period: u64,
    /// The timed shadow program ended in exactly the session's state (no
    /// hand-over or contact update made them part).
    pub replay_exact: bool,
}

/// Runs `plan` (made deterministic, without reference sampling) on this
/// thread and times each solver tick. Allocates (builds the session twice
/// and a buffer of one duration per tick), but not inside the timed region.
pub fn time_ticks(scene: &Scene, plan: &Plan) -> Result<TickTiming> {
    let mut plan = plan.clone();
    plan.deterministic = true;
    plan.out_dir = None;
    plan.record = None;
    plan.reference_every_ticks = 0;
    let mut built = build(scene, &plan, MockClock::new(Nanos(0)))?;
    let mut shadow = build(scene, &plan, MockClock::new(Nanos(0)))?.fast.program;
    let ticks = plan.ticks();
    let period = plan.period().as_nanos() as u64;
    let slow_every = ((SLOW_PERIOD.as_secs_f64() * f64::from(plan.rate_hz)).round() as u64).max(1);
    let clock = MonotonicClock::new();
    let mut ns = Vec::with_capacity(ticks as usize);
    for k in 0..ticks {
        let t = Nanos((k + 1) * period);
        let tick = Tick {
            index: k,
            deadline: t,
            start: t,
        };
        // As the scheduler does: a faulted tick cuts the force.
        if let TickStatus::Fault(f) = built.fast.tick(&tick) {
            built.fast.on_safety(SafetyEvent::Fault(f));
        }
        let targets = &built.fast.targets;
        let t0 = clock.now();
        shadow.program.tick(targets, plan.period());
        let t1 = clock.now();
        ns.push(t1.saturating_sub(t0).as_u64());
        if k % slow_every == slow_every - 1 {
            built.slow.step();
        }
        while built.trace.pop().is_some() {}
    }
    let mut t = summarise(ns, period);
    t.replay_exact = shadow.program.q() == built.fast.program().q();
    Ok(t)
}

/// Percentiles (nearest rank) of `ns`, and how many exceed `period_ns`.
fn summarise(mut ns: Vec<u64>, period_ns: u64) -> TickTiming {
    ns.sort_unstable();
    let at = |p: f64| -> u64 {
        if ns.is_empty() {
            return 0;
        }
        let rank = ((p * ns.len() as f64).ceil() as usize).clamp(1, ns.len());
        ns[rank - 1]
    };
    TickTiming {
        ticks: ns.len() as u64,
        p50_ns: at(0.50),
        p99_ns: at(0.99),
        max_ns: ns.last().copied().unwrap_or(0),
        over_period: ns.iter().filter(|&&t| t > period_ns).count() as u64,
        replay_exact: true,
    }
}

#[cfg(test)]
mod tests {
    use super::summarise;

    #[test]
    fn percentiles_are_nearest_rank_and_overruns_are_counted() {
        let t = summarise((1..=100).rev().collect(), 97);
        assert_eq!((t.ticks, t.p50_ns, t.p99_ns, t.max_ns), (100, 50, 99, 100));
        assert_eq!(t.over_period, 3);
        let empty = summarise(Vec::new(), 1);
        assert_eq!((empty.p50_ns, empty.over_period), (0, 0));
    }
}
