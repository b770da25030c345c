//! The run's health in `summary.json`: violation, finger forces and
//! tracking, safety actions, host stalls, the initial assembly and the
//! slow loop.

use super::SessionOutcome;
use haptloop_rt::probe::Percentiles;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Largest and RMS value of a quantity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MaxRms {
    /// Largest value.
    #[serde(with = "crate::report::figure")]
    pub max: f64,
    /// Root mean square.
    #[serde(with = "crate::report::figure")]
    pub rms: f64,
}

/// Constraint violation over the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Violation {
    /// Largest length-row violation of any tick, m.
    #[serde(with = "crate::report::figure")]
    pub max: f64,
    /// RMS over ticks and length rows, m.
    #[serde(with = "crate::report::figure")]
    pub rms: f64,
    /// Largest angle-row violation of any tick, rad.
    #[serde(with = "crate::report::figure")]
    pub max_rad: f64,
    /// The scene's stated tolerance, m, if it states one.
    pub tolerance: Option<f64>,
    /// Translational joint rows measured (0: the scene has no joints; the
    /// figures are then `"NaN"`).
    pub rows: usize,
    /// Ticks the figures cover: those whose solve succeeded.
    pub ticks_measured: u64,
    /// Ticks whose solve failed (zero force written); not covered.
    pub ticks_failed: u64,
    /// What the figures show against the tolerance, in words: `kept`,
    /// `EXCEEDED`, `FAILED TICKS: …` (never `kept` when a tick failed), or
    /// why nothing was measured (the figures are then `"NaN"`).
    pub verdict: String,
}

impl Violation {
    fn verdict(
        max: f64,
        tolerance: Option<f64>,
        measured: u64,
        failed: u64,
        rows: usize,
    ) -> String {
        if rows == 0 {
            return "none: the scene has no joint rows to violate".into();
        }
        if measured == 0 {
            return if failed == 0 {
                "not measured: no tick ran".into()
            } else {
                format!("not measured: all {failed} ticks failed")
            };
        }
        if failed > 0 {
            // Never "kept" when ticks failed: those ticks wrote zero force
            // and their violation is not a measurement.
            let over = match tolerance {
                Some(t) if max <= t => "within the tolerance",
                Some(_) => "EXCEEDED",
                None => "no tolerance stated",
            };
            return format!(
                "FAILED TICKS: {failed} ticks failed and are not covered; over the {measured} that succeeded: {over}"
            );
        }
        match tolerance {
            Some(t) if max <= t => "kept".into(),
            Some(_) => "EXCEEDED".into(),
            None => "no tolerance stated".into(),
        }
    }
}

impl Violation {
    pub(super) fn of(o: &SessionOutcome) -> Violation {
        let s = &o.stats;
        let measured = s.solved_ticks();
        let (v_max, v_rad) = if measured == 0 || o.joint_rows == 0 {
            (f64::NAN, f64::NAN)
        } else {
            (s.violation_max_m, s.violation_max_rad)
        };
        Violation {
            max: v_max,
            rms: if o.joint_rows == 0 {
                f64::NAN
            } else {
                s.violation_rms_m()
            },
            max_rad: v_rad,
            tolerance: o.plan.violation_tolerance_m,
            rows: o.joint_rows,
            ticks_measured: measured,
            ticks_failed: s.solver_failures,
            verdict: Violation::verdict(
                v_max,
                o.plan.violation_tolerance_m,
                measured,
                s.solver_failures,
                o.joint_rows,
            ),
        }
    }
}

/// One finger's force, rendered by its device (scene frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FingerForce {
    /// Mean |F|, N.
    #[serde(with = "crate::report::figure")]
    pub mean: f64,
    /// Largest |F|, N.
    #[serde(with = "crate::report::figure")]
    pub max: f64,
    /// Largest |F| the solver asked for before the safety layer, N.
    #[serde(with = "crate::report::figure")]
    pub commanded_max: f64,
}

/// One device safety event kind and how often it happened.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeviceEvent {
    /// Device name.
    pub device: String,
    /// What happened (clamp, ramp, thermal, watchdog, NaN …).
    pub event: String,
    /// Times (ticks or episodes, per the event).
    pub count: u64,
}

/// Safety actions taken during the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Safety {
    /// Times the session cut all forces (miss streaks, faults).
    pub force_cuts: u64,
    /// Miss streaks that reached the scheduler's limit.
    pub miss_streaks: u64,
    /// Ticks whose solve failed (zero force written).
    pub solver_failures: u64,
    /// The failed ticks by why they failed (kinds that happened only).
    #[serde(default)]
    pub failure_kinds: BTreeMap<String, u64>,
    /// Per-device safety-layer events.
    pub device_events: Vec<DeviceEvent>,
}

/// Ticks that came after skipped grid slots (host stalls) and what the fast
/// loop did: each stepped the world at most `max_simulated_periods`
/// periods; the rest were dropped, so the scene's time ended
/// `world_behind_s` behind the session's (the hand's).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Stalls {
    /// Ticks more than one period after the previous one.
    pub ticks_after_gap: u64,
    /// Longest gap between two ticks, periods (0: none ran).
    pub longest_gap_periods: u64,
    /// Most periods one tick simulates.
    pub max_simulated_periods: u64,
    /// Periods not simulated, in all.
    pub periods_dropped: u64,
    /// The scene's time behind the session's at the end, s.
    pub world_behind_s: f64,
    /// Ticks whose finger targets were still catching up with the devices
    /// after a gap (moved at most twice the hand's speed).
    #[serde(default)]
    pub catch_up_ticks: u64,
    /// The largest distance left between a device's target and the one the
    /// program was given, m.
    #[serde(default)]
    pub max_target_lag_m: f64,
}

impl Stalls {
    /// The report's line, or `None` when no tick came after a gap.
    pub fn line(&self) -> Option<String> {
        (self.ticks_after_gap > 0).then(|| {
            format!(
                "stalls: {} ticks came after skipped slots (longest gap {} periods); each stepped the world at most {} period(s): {} periods dropped, the scene's time ended {:.1} ms behind the hand's; the finger targets caught up over {} ticks (at most {:.3} mm behind the devices)",
                self.ticks_after_gap,
                self.longest_gap_periods,
                self.max_simulated_periods,
                self.periods_dropped,
                self.world_behind_s * 1e3,
                self.catch_up_ticks,
                self.max_target_lag_m * 1e3
            )
        })
    }
}

impl Stalls {
    pub(super) fn of(o: &SessionOutcome) -> Stalls {
        let s = &o.stats;
        Stalls {
            ticks_after_gap: s.stalls.ticks_after_gap,
            longest_gap_periods: s.stalls.longest_gap_periods,
            max_simulated_periods: crate::session::MAX_SIMULATED_PERIODS,
            periods_dropped: s.stalls.periods_dropped,
            world_behind_s: s.stalls.periods_dropped as f64 / f64::from(o.plan.rate_hz),
            catch_up_ticks: s.stalls.catch_up_ticks,
            max_target_lag_m: s.stalls.max_target_lag_m,
        }
    }
}

impl Safety {
    pub(super) fn of(o: &SessionOutcome) -> Safety {
        let s = &o.stats;
        Safety {
            force_cuts: s.force_cuts,
            miss_streaks: s.miss_streaks,
            solver_failures: s.solver_failures,
            failure_kinds: crate::session::FailureKind::ALL
                .iter()
                .zip(&s.failure_kinds)
                .filter(|(_, n)| **n > 0)
                .map(|(k, n)| (k.as_str().to_string(), *n))
                .collect(),
            device_events: o
                .device_events
                .iter()
                .map(|(d, e, c)| DeviceEvent {
                    device: d.clone(),
                    event: e.clone(),
                    count: *c,
                })
                .collect(),
        }
    }
}

/// The initial assembly (Newton-KKT placement) before the clock started.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Assembly {
    /// Newton iterations used.
    pub iterations: u32,
    /// Constraint residual after assembly (2-norm over length rows), m.
    #[serde(with = "crate::report::figure")]
    pub residual_m: f64,
    /// Converged | MaxIterations | Stalled | LeastSquares.
    pub status: String,
    /// True if it converged to the tolerance.
    pub converged: bool,
}

/// What the slow loop did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SlowLoop {
    /// Re-projections (violation over the threshold).
    pub reprojections: u64,
    /// Of which recoveries from a broken configuration.
    pub recoveries: u64,
    /// Placements that did not converge.
    pub placements_not_converged: u64,
    /// Largest violation the slow loop saw in a snapshot, m.
    #[serde(with = "crate::report::figure")]
    pub max_seen_violation_m: f64,
    /// Wall time of one slow-loop step (about every 5 ms), monotonic clock.
    pub step_ns: Percentiles,
}
