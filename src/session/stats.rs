//! What the fast loop counts and accumulates per tick, allocated up front.
//!
//! # Real-time
//! Every `record*` method is a handful of arithmetic operations on
//! preallocated fields: no allocation, no lock.

use super::timing::StageTimes;
use haptloop_rt::hist::LatencyHistogram;
use haptloop_solver::{Divergence, TickOutcome, TickReport};
use nalgebra::Vector3;

/// Per-finger accumulators.
#[derive(Debug, Clone, Default)]
pub struct FingerStats {
    /// Ticks recorded.
    pub n: u64,
    /// Σ |rendered force|, N.
    pub force_sum: f64,
    /// max |rendered force|, N.
    pub force_max: f64,
    /// max |force the solver asked for| (before the safety layer), N.
    pub commanded_max: f64,
    /// max |attachment point − target|, m.
    pub tracking_max: f64,
    /// Σ |attachment point − target|², m².
    pub tracking_sumsq: f64,
    /// Ticks with a tracking measurement (failed solves have none).
    pub tracking_n: u64,
}

impl FingerStats {
    /// Records one tick.
    #[inline]
    pub fn record(&mut self, commanded: &Vector3<f64>, rendered: &Vector3<f64>, tracking_m: f64) {
        let f = rendered.norm();
        self.n += 1;
        self.force_sum += f;
        self.force_max = self.force_max.max(f);
        self.commanded_max = self.commanded_max.max(commanded.norm());
        if tracking_m.is_finite() {
            self.tracking_max = self.tracking_max.max(tracking_m);
            self.tracking_sumsq += tracking_m * tracking_m;
            self.tracking_n += 1;
        }
    }

    /// Mean rendered force magnitude, N.
    pub fn force_mean(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            self.force_sum / self.n as f64
        }
    }

    /// RMS tracking error over the ticks that measured it, m (NaN if none).
    pub fn tracking_rms(&self) -> f64 {
        if self.tracking_n == 0 {
            f64::NAN
        } else {
            (self.tracking_sumsq / self.tracking_n as f64).sqrt()
        }
    }
}

/// Session-wide accumulators.
#[derive(Debug, Clone)]
pub struct RunStats {
    /// Device read → force write, ns.
    pub read_to_write: LatencyHistogram,
    /// Ticks recorded.
    pub ticks: u64,
    /// AL iterations run in all.
    pub iterations: u64,
    /// max over ticks of the largest length-row violation, m.
    pub violation_max_m: f64,
    /// max over ticks of the largest angle-row violation, rad.
    pub violation_max_rad: f64,
    /// Σ over ticks of (RMS length-row violation)², m².
    pub violation_sumsq: f64,
    /// One per model finger.
    pub fingers: Vec<FingerStats>,
    /// Ticks whose solve failed (zero force written).
    pub solver_failures: u64,
    /// Safety-hook calls for miss streaks.
    pub miss_streaks: u64,
    /// Safety-hook calls for faults.
    pub faults: u64,
    /// Times forces were cut for a safety event.
    pub force_cuts: u64,
    /// Programs swapped in from the slow loop.
    pub programs_swapped: u64,
    /// Contact figures of the fast loop.
    pub contact: ContactStats,
    /// Failed ticks by why they failed ([`FailureKind`] order).
    pub failure_kinds: [u64; FailureKind::ALL.len()],
    /// Time per stage of the tick, monotonic clock.
    pub stages: StageTimes,
    /// The bodies' energy (inertial motion).
    pub energy: super::energy::EnergyStats,
    /// Ticks after skipped grid slots and the periods the world did not
    /// simulate.
    pub stalls: StallStats,
}

/// Ticks that came after skipped grid slots (a host stall), and what the
/// fast loop did about them: each such tick simulates at most
/// `MAX_SIMULATED_PERIODS` periods, the rest are dropped.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StallStats {
    /// Ticks that came more than one period after the previous one.
    pub ticks_after_gap: u64,
    /// Longest gap between two ticks, periods.
    pub longest_gap_periods: u64,
    /// Periods not simulated, in all: the world's time is this many
    /// periods behind the session's (the devices') at the end.
    pub periods_dropped: u64,
    /// Ticks whose finger targets were still catching up with the devices
    /// after a stall (`session::catch_up`).
    pub catch_up_ticks: u64,
    /// The largest distance left between a device's target and the one
    /// the program was given, m.
    pub max_target_lag_m: f64,
}

impl StallStats {
    /// Records one tick `gap` periods after the previous one, of which
    /// `dropped` were not simulated.
    #[inline]
    pub fn record(&mut self, gap: u64, dropped: u64) {
        if gap > 1 {
            self.ticks_after_gap += 1;
            self.longest_gap_periods = self.longest_gap_periods.max(gap);
        }
        self.periods_dropped += dropped;
    }

    /// Records the tick's largest target lag, m (0: none lagged).
    #[inline]
    pub fn record_lag(&mut self, lag_m: f64) {
        if lag_m > 0.0 {
            self.catch_up_ticks += 1;
            self.max_target_lag_m = self.max_target_lag_m.max(lag_m);
        }
    }
}

/// Why a tick counted as failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FailureKind {
    /// The solve succeeded but the mechanism came apart (violation beyond the
    /// session's broken threshold).
    ViolationBeyondBroken,
    /// A NaN or infinity.
    NonFinite,
    /// The targets or q could not be evaluated.
    Eval,
    /// The Eq. 7 multiplier solve failed.
    ForceSolve,
    /// A zero period.
    ZeroDt,
    /// A step beyond the divergence limit.
    DivergedStep,
    /// A multiplier beyond the divergence limit.
    DivergedMultiplier,
    /// A violation beyond the model's length scale.
    DivergedViolation,
    /// The solve succeeded but bodies came apart: a witness row's
    /// penetration beyond the session's bound for a broken world.
    PenetrationBeyondBroken,
}

impl FailureKind {
    /// Every kind, in counting order.
    pub const ALL: [FailureKind; 9] = [
        FailureKind::ViolationBeyondBroken,
        FailureKind::NonFinite,
        FailureKind::Eval,
        FailureKind::ForceSolve,
        FailureKind::ZeroDt,
        FailureKind::DivergedStep,
        FailureKind::DivergedMultiplier,
        FailureKind::DivergedViolation,
        FailureKind::PenetrationBeyondBroken,
    ];

    /// Name in reports and `summary.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            FailureKind::ViolationBeyondBroken => "violation_beyond_broken",
            FailureKind::NonFinite => "non_finite",
            FailureKind::Eval => "eval",
            FailureKind::ForceSolve => "force_solve",
            FailureKind::ZeroDt => "zero_dt",
            FailureKind::DivergedStep => "diverged_step",
            FailureKind::DivergedMultiplier => "diverged_multiplier",
            FailureKind::DivergedViolation => "diverged_violation",
            FailureKind::PenetrationBeyondBroken => "penetration_beyond_broken",
        }
    }
}

/// What the fast loop saw of contact.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactStats {
    /// Deepest penetration of a witness row at a tick's end, m (ticks that
    /// succeeded).
    pub max_penetration_m: f64,
    /// Most witness rows active (pushing) in one tick.
    pub max_active: u32,
    /// Refactorisations for in-tick activation, in all.
    pub activations: u64,
    /// Ticks that used all `MAX_ACTIVATIONS` refactorisations.
    pub activation_limit_ticks: u64,
    /// Witness tables and contact programs taken over from the slow loop.
    pub updates: u64,
    /// Largest and summed latency of those, ticks from the snapshot they
    /// were computed from to the tick that used them.
    pub latency_max_ticks: u64,
    /// Sum of the latencies, ticks (mean = this / updates).
    pub latency_sum_ticks: u64,
    /// Contact programs taken over with the factor the slow loop prepared
    /// (`Program::prepare_handover`): no refactorisation on the fast loop.
    pub prepared_programs: u64,
    /// Most friction pairs sticking at once.
    pub max_sticking: u32,
    /// Ticks in which the contact speed limit held a shaped body back.
    pub speed_limited_ticks: u64,
    /// The largest finger tracking error of such a tick, m: how far the
    /// limit left a fingertip behind its device.
    pub speed_limit_lag_max_m: f64,
    /// Backups the slow loop sent because the world came apart (force cut
    /// when taken over).
    pub broken_handovers: u64,
    /// Ticks in which the witness rows in use were too old to move the
    /// bodies at all (`witness_age`: the slow loop was late).
    pub stale_stopped_ticks: u64,
    /// The most motion since their snapshot the rows in use were asked to
    /// cover, ticks' worth of the contact speed limit.
    pub max_witness_age: f64,
}

impl ContactStats {
    /// Records one update's latency.
    #[inline]
    pub fn record_latency(&mut self, ticks: u64) {
        self.updates += 1;
        self.latency_max_ticks = self.latency_max_ticks.max(ticks);
        self.latency_sum_ticks += ticks;
    }

    /// Records one tick.
    #[inline]
    pub fn record(&mut self, r: &TickReport) {
        self.max_penetration_m = self.max_penetration_m.max(r.max_penetration_m);
        self.max_active = self.max_active.max(r.active_contacts);
        self.activations += u64::from(r.activations);
        self.activation_limit_ticks +=
            u64::from(r.activations >= haptloop_solver::program::MAX_ACTIVATIONS);
        self.max_sticking = self.max_sticking.max(r.sticking);
        if r.speed_limited {
            self.speed_limited_ticks += 1;
            self.speed_limit_lag_max_m = self.speed_limit_lag_max_m.max(r.max_tracking_error_m);
        }
    }
}

impl RunStats {
    /// Empty statistics for `fingers` fingers (allocates the histogram).
    pub fn new(fingers: usize) -> Self {
        let mut read_to_write = LatencyHistogram::new();
        read_to_write.reset(); // make its pages resident before the loop
        RunStats {
            read_to_write,
            ticks: 0,
            iterations: 0,
            violation_max_m: 0.0,
            violation_max_rad: 0.0,
            violation_sumsq: 0.0,
            fingers: vec![FingerStats::default(); fingers],
            solver_failures: 0,
            miss_streaks: 0,
            faults: 0,
            force_cuts: 0,
            programs_swapped: 0,
            contact: ContactStats::default(),
            failure_kinds: [0; FailureKind::ALL.len()],
            stages: StageTimes::new(),
            energy: Default::default(),
            stalls: StallStats::default(),
        }
    }

    /// Records one tick's solver diagnostics.
    #[inline]
    /// `apart`: it failed on a penetration beyond the broken bound.
    pub fn record_tick(&mut self, r: &TickReport, solved: bool, apart: bool) {
        self.ticks += 1;
        self.iterations += u64::from(r.iterations);
        self.energy.record(&r.energy, solved);
        if solved {
            self.violation_max_m = self.violation_max_m.max(r.max_violation_m);
            self.violation_max_rad = self.violation_max_rad.max(r.max_violation_rad);
            self.violation_sumsq += r.rms_violation_m * r.rms_violation_m;
            self.contact.record(r);
        } else {
            self.solver_failures += 1;
            let k = match r.status {
                TickOutcome::Ok if apart => FailureKind::PenetrationBeyondBroken,
                TickOutcome::Ok => FailureKind::ViolationBeyondBroken,
                TickOutcome::NonFinite => FailureKind::NonFinite,
                TickOutcome::Eval(_) => FailureKind::Eval,
                TickOutcome::ForceSolve => FailureKind::ForceSolve,
                TickOutcome::ZeroDt => FailureKind::ZeroDt,
                TickOutcome::Diverged(Divergence::Step) => FailureKind::DivergedStep,
                TickOutcome::Diverged(Divergence::Multiplier) => FailureKind::DivergedMultiplier,
                TickOutcome::Diverged(Divergence::Violation) => FailureKind::DivergedViolation,
            };
            self.failure_kinds[k as usize] += 1;
        }
    }

    /// Ticks whose solve succeeded: the ones the violation figures cover.
    pub fn solved_ticks(&self) -> u64 {
        self.ticks - self.solver_failures
    }

    /// RMS length-row violation over the ticks that succeeded, m (NaN when
    /// none did: nothing was measured).
    pub fn violation_rms_m(&self) -> f64 {
        let n = self.solved_ticks();
        if n == 0 {
            f64::NAN
        } else {
            (self.violation_sumsq / n as f64).sqrt()
        }
    }
}
