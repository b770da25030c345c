//! Per-stage time of the fast loop's tick, on the monotonic clock.
//!
//! A tick is cut into [`Stage`]s; [`StageClock`] reads `rt::clock`'s
//! monotonic clock at the start and at the end of each stage (eight reads a
//! tick, about 22 ns each on the development VM; the whole of it, records
//! included, is the `stage_clock/tick` bench in `benches/session.rs`) and
//! [`StageTimes`] keeps one HDR histogram per stage,
//! plus the whole tick and the tick without the device stages (what a
//! simulator without a device, such as MuJoCo's step, would compare with).
//! The monotonic clock is used whatever clock drives the loop, so a
//! deterministic run on the mock clock still reports real compute time
//! (and only those figures differ between two deterministic runs).
//!
//! # Real-time
//! [`StageClock::lap`] is a clock read and a subtraction; [`StageTimes::record`]
//! records nine histogram values: no allocation, no lock, no syscall (the
//! clock reads go through the vDSO).
//!
//! [`time_ticks`] is what `haptloop sweep` times each grid point with: the
//! same deterministic session `haptloop bench` runs, its stage histograms
//! read back, so the two commands' figures are one measurement.

use super::{Plan, run};
use crate::scenes::Scene;
use anyhow::Result;
use haptloop_rt::clock::{Clock, MonotonicClock, Nanos};
use haptloop_rt::hist::LatencyHistogram;
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::program::{SolverStage, StageMarks};

/// The stages of a fast-loop tick, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Swapping in a program from the slow loop and applying witness tables
    /// (usually nothing; a swap refactors at the adopted state).
    Handover,
    /// Reading every device (simulated arm physics, encoders, safety checks)
    /// and forming the finger targets.
    DeviceRead,
    /// The solver's update iterations ([`SolverStage::Update`]).
    Update,
    /// C and C_q at the final q and the violation ([`SolverStage::Evaluation`]).
    Evaluation,
    /// The Eq. 7 force solve, Eq. 8 and the coupling ([`SolverStage::Force`]).
    Force,
    /// Every device's safety layer and motor write.
    SafetyWrite,
    /// Statistics, the trace queue and the snapshot for the slow loop.
    Bookkeeping,
}

impl Stage {
    /// Every stage, in order.
    pub const ALL: [Stage; 7] = [
        Stage::Handover,
        Stage::DeviceRead,
        Stage::Update,
        Stage::Evaluation,
        Stage::Force,
        Stage::SafetyWrite,
        Stage::Bookkeeping,
    ];

    /// Its key in JSON files (`summary.json`, `haptloop bench --json`).
    pub fn key(self) -> &'static str {
        match self {
            Stage::Handover => "handover",
            Stage::DeviceRead => "device_read",
            Stage::Update => "update",
            Stage::Evaluation => "evaluation",
            Stage::Force => "force",
            Stage::SafetyWrite => "safety_write",
            Stage::Bookkeeping => "bookkeeping",
        }
    }

    /// Its label in text reports.
    pub fn label(self) -> &'static str {
        match self {
            Stage::Handover => "handover",
            Stage::DeviceRead => "device read",
            Stage::Update => "update",
            Stage::Evaluation => "evaluation",
            Stage::Force => "force (Eq. 7)",
            Stage::SafetyWrite => "safety + write",
            Stage::Bookkeeping => "bookkeeping",
        }
    }

    /// True for the stages a simulator without a device does not have.
    pub fn is_device(self) -> bool {
        matches!(self, Stage::DeviceRead | Stage::SafetyWrite)
    }
}

/// The stopwatch of one tick: [`start`](Self::start), then one
/// [`lap`](Self::lap) per stage (the solver's stages through [`StageMarks`]).
#[derive(Debug, Clone, Default)]
pub struct StageClock {
    clock: MonotonicClock,
    start: Nanos,
    last: Nanos,
    /// This tick's time per stage, ns.
    ns: [u64; 7],
}

impl StageClock {
    /// Starts a tick.
    #[inline]
    pub fn start(&mut self) {
        self.start = self.clock.now();
        self.last = self.start;
        self.ns = [0; 7];
    }

    /// Ends `stage`: the time since the previous lap (or the start) is its.
    #[inline]
    pub fn lap(&mut self, stage: Stage) {
        let now = self.clock.now();
        self.ns[stage as usize] += (now - self.last).0;
        self.last = now;
    }

    /// The whole tick so far, ns.
    pub fn total_ns(&self) -> u64 {
        (self.last - self.start).0
    }
}

impl StageMarks for StageClock {
    #[inline]
    fn end(&mut self, stage: SolverStage) {
        self.lap(match stage {
            SolverStage::Update => Stage::Update,
            SolverStage::Evaluation => Stage::Evaluation,
            SolverStage::Force => Stage::Force,
        });
    }
}

/// Histograms of the stage times over a run, ns.
#[derive(Debug, Clone)]
pub struct StageTimes {
    /// One per [`Stage`], in [`Stage::ALL`] order.
    pub stages: [LatencyHistogram; 7],
    /// The whole tick (first to last lap).
    pub tick: LatencyHistogram,
    /// The tick without [`Stage::DeviceRead`] and [`Stage::SafetyWrite`].
    pub tick_without_device: LatencyHistogram,
}

impl StageTimes {
    /// Empty histograms, every page touched (allocates about 1.8 MiB).
    pub fn new() -> Self {
        let fresh = || {
            let mut h = LatencyHistogram::new();
            h.reset();
            h
        };
        StageTimes {
            stages: std::array::from_fn(|_| fresh()),
            tick: fresh(),
            tick_without_device: fresh(),
        }
    }

    /// Records the tick `clock` timed.
    ///
    /// # Real-time
    /// Nine histogram records.
    #[inline]
    pub fn record(&mut self, clock: &StageClock) {
        let mut device = 0;
        for (k, stage) in Stage::ALL.iter().enumerate() {
            self.stages[k].record(clock.ns[k]);
            if stage.is_device() {
                device += clock.ns[k];
            }
        }
        let total = clock.total_ns();
        self.tick.record(total);
        self.tick_without_device
            .record(total.saturating_sub(device));
    }

    /// The histogram of `stage`.
    pub fn stage(&self, stage: Stage) -> &LatencyHistogram {
        &self.stages[stage as usize]
    }
}

impl Default for StageTimes {
    fn default() -> Self {
        Self::new()
    }
}

/// The measured cost of the ticks of one session, ns: the tick without the
/// simulated devices' stages (a real device's read and write are I/O, not
/// this simulation's physics sub-steps), from [`StageTimes`].
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
    /// Ticks that took longer than the period (to the histogram's 3
    /// significant digits): overruns the loop would have
    /// at this rate from its own compute alone (device I/O, the host's
    /// wake-up lateness and stalls come on top; `haptloop probe` measures
    /// those).
    pub over_period: u64,
}

impl TickTiming {
    /// The figures of `h`, with the ticks over `period_ns` counted.
    pub fn of(h: &LatencyHistogram, period_ns: u64) -> Self {
        let ticks = h.count();
        TickTiming {
            ticks,
            p50_ns: h.quantile(0.50),
            p99_ns: h.quantile(0.99),
            max_ns: h.max(),
            over_period: if ticks == 0 {
                0
            } else {
                // Values in buckets above the period's: the histogram's 3
                // significant digits (a tick within 0.1 % over the period
                // shares its bucket and is not counted).
                let above = h.inner().highest_equivalent(period_ns).saturating_add(1);
                h.inner().count_between(above, u64::MAX)
            },
        }
    }
}

/// Runs `plan` as `haptloop bench` does (deterministic, on this thread,
/// without reference sampling or output files) and returns the stage
/// timing of its ticks.
pub fn time_ticks(scene: &Scene, plan: &Plan) -> Result<TickTiming> {
    let mut plan = plan.clone();
    plan.deterministic = true;
    plan.out_dir = None;
    plan.record = None;
    plan.reference_every_ticks = 0;
    let period = plan.period().as_nanos() as u64;
    let outcome = run(scene, plan, &StopFlag::new(), &mut |_| {})?;
    Ok(TickTiming::of(
        &outcome.stats.stages.tick_without_device,
        period,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn laps_add_up_to_the_tick_and_device_stages_are_left_out() {
        let mut c = StageClock::default();
        c.start();
        for s in Stage::ALL {
            // Burn a little time in each stage.
            let t = c.clock.now();
            while (c.clock.now() - t).0 < 2_000 {}
            c.lap(s);
        }
        let sum: u64 = c.ns.iter().sum();
        assert_eq!(sum, c.total_ns());
        assert!(c.ns.iter().all(|&ns| ns >= 2_000), "{:?}", c.ns);
        let mut t = StageTimes::new();
        t.record(&c);
        let device = c.ns[Stage::DeviceRead as usize] + c.ns[Stage::SafetyWrite as usize];
        assert_eq!(t.tick.max(), c.total_ns());
        assert_eq!(t.tick_without_device.max(), c.total_ns() - device);
        assert_eq!(t.stage(Stage::Force).count(), 1);
    }

    #[test]
    fn tick_timing_counts_ticks_over_the_period() {
        let mut h = LatencyHistogram::new();
        for ns in 1..=100u64 {
            h.record(ns * 1000);
        }
        let t = TickTiming::of(&h, 97_000);
        assert_eq!(t.ticks, 100);
        assert_eq!(t.over_period, 3);
        assert!((49_000..=51_000).contains(&t.p50_ns), "{t:?}");
        assert!((98_000..=100_000).contains(&t.p99_ns), "{t:?}");
        let empty = TickTiming::of(&LatencyHistogram::new(), 1);
        assert_eq!((empty.ticks, empty.over_period), (0, 0));
    }
}
