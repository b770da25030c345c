//! The fast loop's tick body: device → program → force, every period.
//!
//! ```text
//!  swap in a new program (if the slow loop sent one; the old one goes back)    handover
//!  read every device (scene frame) → finger targets                            device read
//!  Program::tick (AL iterations + Eq. 7–8 force + coupling)    update, evaluation, force
//!  write each finger's force through its device's safety layer                 safety + write
//!  record statistics; publish a snapshot; queue one trace row per finger       bookkeeping
//! ```
//!
//! Each stage on the right is timed on the monotonic clock (`timing`).
//!
//! # Real-time
//! `FastLoop::tick` allocates nothing, takes no lock and does no I/O: every
//! buffer (targets, snapshot, statistics, the trace queue) is allocated when
//! the session is built; the trace rows go to a lock-free queue that the
//! reporter drains (a full queue drops and counts rows). Its run time is
//! bounded by the program's fixed iteration count and the devices' sub-steps.

mod stages;

use super::messages::{Handover, RowsStamp, Snapshot};
use super::rig::Rig;
use super::stats::{FingerStats, RunStats};
use super::timing::{Stage, StageClock};
use crossbeam::queue::ArrayQueue;
use haptloop_devices::{FaultKind, Health, TraceRecorder, TraceRow};
use haptloop_rt::clock::Clock;
use haptloop_rt::exchange::{MailboxWriter, ProgramReceiver};
use haptloop_rt::schedule::{SafetyEvent, Tick, TickBody, TickStatus};
use haptloop_solver::{FingerTarget, Program, TickOutcome, TickReport};
use nalgebra::Vector3;
use std::sync::Arc;
use std::time::Duration;

/// One finger at one tick, for `trace.csv` and the plots.
#[derive(Debug, Clone, Copy, Default)]
pub struct TraceSample {
    /// Session time, s.
    pub t_s: f64,
    /// Model finger index.
    pub finger: u16,
    /// The finger target the program was given, m, scene frame: the device
    /// tip, or after a stall its catch-up (`catch_up`).
    pub target_m: [f64; 3],
    /// Finger attachment point on the mechanism, m, scene frame.
    pub position_m: [f64; 3],
    /// Force the device's motors produced, N, scene frame (after the safety
    /// layer and the motors' saturation and thermal limits).
    pub force_n: [f64; 3],
    /// Largest length-row violation this tick, m.
    pub violation_m: f64,
    /// The tick's solve failed (zero force commanded): its position and
    /// violation are not measurements.
    pub failed: bool,
}

/// Heap-free faults the tick reports to the scheduler's safety hook.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SessionFault {
    /// The solver produced a non-finite state or could not evaluate; zero force
    /// was written this tick.
    Solver,
    /// A device latched a fault (its safety layer cut its force).
    Device {
        /// Device index.
        device: u16,
        /// What went wrong.
        kind: FaultKind,
    },
}

/// Ticks during which force stays cut after a safety event; forces then come
/// back through each device's rate limiter. 50 ms: long enough for a stalled
/// host to settle, short enough not to feel like a dropout.
const CUT_SECONDS: f64 = 0.05;

/// Most periods one tick simulates, however many grid slots were skipped
/// before it (a host stall): the rest are dropped and counted
/// ([`RunStats::stalls`](super::stats::RunStats)). BENCHMARKS.md, "Contact:
/// missed ticks", measures the alternative (the gap in one step).
pub const MAX_SIMULATED_PERIODS: u64 = 1;

/// The fast loop's state. Built on the main thread, moved to the fast thread.
pub struct FastLoop<C: Clock> {
    pub(super) clock: C,
    pub(super) period: Duration,
    pub(super) program: Box<Handover>,
    pub(super) programs: ProgramReceiver<Handover>,
    /// Force factors the slow loop refreshed (the matvec-only tick).
    pub(super) refresh: Option<super::refresh::RefreshReceiver>,
    /// A tick whose violation exceeds this is treated as a failed solve
    /// (force cut, re-projection): the mechanism has come apart, m.
    pub(super) broken_m: f64,
    /// Likewise a witness row's penetration beyond this: the world has come
    /// apart, m (`contact::broken_penetration_m`; infinite without contact).
    pub(super) broken_penetration_m: f64,
    /// How far the bodies moved since the snapshot of the witness rows in
    /// use (scenes with contact): bounds the next ticks' motion.
    pub(super) witness_age: Option<super::witness_age::WitnessAge>,
    pub(super) rig: Rig,
    pub(super) targets: Vec<FingerTarget>,
    /// Bounds how fast the targets the program sees catch up after a stall.
    pub(super) catch_up: super::catch_up::TargetCatchUp,
    pub(super) snapshot: MailboxWriter<Snapshot>,
    pub(super) trace: Arc<ArrayQueue<TraceSample>>,
    pub(super) stats: RunStats,
    pub(super) last_index: Option<u64>,
    pub(super) cut_until: u64,
    /// [`Snapshot::peak_violation_m`] so far, m.
    pub(super) violation_peak_m: f64,
    pub(super) health: Vec<Health>,
    /// Encoder counts read this tick, per device.
    pub(super) counts: Vec<[i32; 3]>,
    /// Gimbal orientation read this tick, per device, `[w, x, y, z]`.
    pub(super) orientations: Vec<[f64; 4]>,
    /// One per device when recording (`--record`), else empty: rows go to a
    /// bounded queue the reporter drains.
    pub(super) recorders: Vec<TraceRecorder>,
    /// Witness tables from the slow loop (scenes with contact).
    pub(super) inbox: Option<super::contact::WitnessInbox>,
    /// Design variables' and objectives' figures and trace (scenes with any).
    pub(super) design: Option<super::design::DesignTracker>,
    /// Design variables switched on and off at their times.
    pub(super) switches: super::design::DesignSchedule,
    /// Samples ticks for the converged reference (scenes it supports).
    pub(super) reference: Option<super::reference::ReferenceCapture>,
    /// The last tick was sampled for the reference.
    pub(super) sampled: bool,
    /// Times the stages of the tick (monotonic clock, whatever `clock` is).
    pub(super) timer: StageClock,
    /// Per finger: the force its device's motors produced this tick, scene frame.
    pub(super) rendered: Vec<Vector3<f64>>,
    /// Per finger: the force commanded this tick, scene frame.
    pub(super) commanded: Vec<Vector3<f64>>,
}

impl<C: Clock> FastLoop<C> {
    fn session_time(&self, tick: &Tick) -> Duration {
        // Grid time, not wake-up time: slot k is due (k + 1) periods after the
        // devices were registered at t = 0, so device physics and the solver's
        // differences see exact periods. A jittery wake-up changes when the
        // work happens, never what it computes.
        self.periods(tick.index + 1)
    }

    /// `n` loop periods as a duration (exact in nanoseconds).
    fn periods(&self, n: u64) -> Duration {
        Duration::from_nanos((self.period.as_nanos() as u64).saturating_mul(n))
    }

    fn cut_forces(&mut self, index: u64) {
        let ticks = (CUT_SECONDS / self.period.as_secs_f64()).ceil() as u64;
        self.cut_until = self.cut_until.max(index + ticks);
        self.stats.force_cuts += 1;
    }

    /// The statistics so far.
    pub fn stats(&self) -> &RunStats {
        &self.stats
    }

    /// The running program.
    pub fn program(&self) -> &Program {
        &self.program.program
    }

    /// True if the last tick was sampled for the converged reference.
    pub fn sampled(&self) -> bool {
        self.sampled
    }

    /// The devices.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// How the design variables and objectives moved so far (empty without
    /// any).
    pub fn design_stats(&self) -> super::design::DesignStats {
        self.design
            .as_ref()
            .map(|d| d.stats.clone())
            .unwrap_or_default()
    }
}

impl<C: Clock> TickBody for FastLoop<C> {
    type Fault = SessionFault;

    fn tick(&mut self, tick: &Tick) -> TickStatus<SessionFault> {
        self.timer.start();
        let now = self.session_time(tick);
        let read_start = self.clock.now();
        self.take_over(tick, now);
        self.timer.lap(Stage::Handover);

        self.read_devices(now);
        self.timer.lap(Stage::DeviceRead);
        let s = self.solve(tick);
        let cut = !s.solved || tick.index < self.cut_until;

        let t_s = now.as_secs_f64();
        if let Some(d) = &mut self.design {
            d.record(t_s, &self.program.program, s.solved);
        }
        let fault = self.write_forces(now, cut);
        self.stats
            .read_to_write
            .record((self.clock.now() - read_start).0);
        self.timer.lap(Stage::SafetyWrite);

        self.record_fingers(t_s, &s);
        self.stats.record_tick(&s.report, s.solved, s.apart);
        if let Some(r) = &mut self.reference {
            let p = &self.program.program;
            self.sampled = r.after(tick.index, p, &self.targets, s.dt.as_secs_f64(), s.solved);
        }
        self.publish(tick, now, &s);
        self.timer.lap(Stage::Bookkeeping);
        self.stats.stages.record(&self.timer);

        match (s.solved, fault) {
            (false, _) => TickStatus::Fault(SessionFault::Solver),
            (true, Some(f)) => TickStatus::Fault(f),
            (true, None) => TickStatus::Ok,
        }
    }

    fn on_safety(&mut self, event: SafetyEvent<SessionFault>) {
        let index = self.last_index.unwrap_or(0);
        match event {
            SafetyEvent::MissStreak { .. } => self.stats.miss_streaks += 1,
            SafetyEvent::Fault(_) => self.stats.faults += 1,
        }
        self.cut_forces(index);
    }

    fn on_stop(&mut self) {
        // Leave the hardware safe: zero force on every device on this very
        // write (decreasing force is never rate limited), then motors off.
        let now = self.periods(self.last_index.map_or(0, |i| i + 1));
        for dev in &mut self.rig.devices {
            dev.device.stop(now);
        }
    }
}
