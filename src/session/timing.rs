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

use haptloop_rt::clock::{Clock, MonotonicClock, Nanos};
use haptloop_rt::hist::LatencyHistogram;
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
}
