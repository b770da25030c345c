//! `summary.json`: every figure of a session, machine-readable.
//!
//! In deterministic mode every field except the measured times is
//! bit-identical across runs: `wall_clock_s`, `compute_ns`, `stages_ns` and
//! `slow_loop.step_ns` are read from the monotonic clock (real compute time,
//! see `session::timing`); the scheduler's own timing fields follow the mock
//! clock and are functions of the tick count.

pub use super::limits::{DeviceLimits, Replay, ReplayDevice};
use crate::session::{SessionOutcome, Stage, StageTimes};
use haptloop_rt::probe::Percentiles;
use haptloop_rt::schedule::MissCounts;
use haptloop_rt::thread::Granted;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Largest and RMS value of a quantity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MaxRms {
    /// Largest value.
    #[serde(with = "super::figure")]
    pub max: f64,
    /// Root mean square.
    #[serde(with = "super::figure")]
    pub rms: f64,
}

/// Constraint violation over the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Violation {
    /// Largest length-row violation of any tick, m.
    #[serde(with = "super::figure")]
    pub max: f64,
    /// RMS over ticks and length rows, m.
    #[serde(with = "super::figure")]
    pub rms: f64,
    /// Largest angle-row violation of any tick, rad.
    #[serde(with = "super::figure")]
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

/// What the clock of the run measures (deterministic or real time).
fn clock_note(deterministic: bool) -> String {
    if deterministic {
        "deterministic: the scheduler ran on a mock clock, which never wakes late and \
         takes no time between a device read and a force write, so lateness_ns and \
         read_to_write_ns are null and period_ns is exactly the period; compute_ns, \
         stages_ns, slow_loop.step_ns and wall_clock_s are measured on the monotonic clock"
            .into()
    } else {
        "real time: every timing figure is measured on the monotonic clock".into()
    }
}

/// The fingers' tracking error over the run, m (NaN without samples).
fn tracking(o: &SessionOutcome) -> MaxRms {
    let s = &o.stats;
    let n: u64 = s.fingers.iter().map(|f| f.tracking_n).sum();
    let (max, rms) = if n == 0 {
        (f64::NAN, f64::NAN)
    } else {
        (
            s.fingers.iter().map(|f| f.tracking_max).fold(0.0, f64::max),
            (s.fingers.iter().map(|f| f.tracking_sumsq).sum::<f64>() / n as f64).sqrt(),
        )
    };
    MaxRms { max, rms }
}

/// Each finger's force over the run, by name.
fn finger_forces(o: &SessionOutcome) -> BTreeMap<String, FingerForce> {
    let s = &o.stats;
    (0..s.fingers.len())
        .map(|i| {
            let f = &s.fingers[i];
            (
                o.fingers[i].clone(),
                FingerForce {
                    mean: f.force_mean(),
                    max: f.force_max,
                    commanded_max: f.commanded_max,
                },
            )
        })
        .collect()
}

/// Each objective's value over the run, with its kind and weight.
fn objectives(o: &SessionOutcome) -> BTreeMap<String, ObjectiveFigure> {
    o.design
        .objectives
        .iter()
        .map(|(n, kind, weight, r)| {
            (
                n.clone(),
                ObjectiveFigure {
                    kind: kind.clone(),
                    weight: *weight,
                    value: (*r).into(),
                },
            )
        })
        .collect()
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

/// One finger's force, rendered by its device (scene frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FingerForce {
    /// Mean |F|, N.
    #[serde(with = "super::figure")]
    pub mean: f64,
    /// Largest |F|, N.
    #[serde(with = "super::figure")]
    pub max: f64,
    /// Largest |F| the solver asked for before the safety layer, N.
    #[serde(with = "super::figure")]
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

/// The initial assembly (Newton-KKT placement) before the clock started.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Assembly {
    /// Newton iterations used.
    pub iterations: u32,
    /// Constraint residual after assembly (2-norm over length rows), m.
    #[serde(with = "super::figure")]
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
    #[serde(with = "super::figure")]
    pub max_seen_violation_m: f64,
    /// Wall time of one slow-loop step (about every 5 ms), monotonic clock.
    pub step_ns: Percentiles,
}

/// The fast loop's force against the converged reference: the same tick,
/// from the same state, replayed to convergence (`session::reference`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// One tick in this many was sampled.
    pub every_ticks: u64,
    /// Ticks sampled.
    pub samples: u64,
    /// Samples compared (the figures cover these only).
    pub compared: u64,
    /// Why nothing was compared, when nothing was (the figures are then
    /// `"NaN"`).
    pub missing: Option<String>,
    /// |F − F*| per finger and sample, N: the force the solver asked for
    /// (before the safety layer) against the reference's.
    pub force_error_n: MaxRms,
    /// The same over the reference force: max error / max |F*|, RMS error /
    /// RMS |F*|.
    pub force_error_relative: MaxRms,
    /// Largest and RMS |F*|, N.
    pub force_n: MaxRms,
    /// Largest distance of a body origin from the reference configuration
    /// per sample, m: max and RMS over samples.
    pub configuration_error_m: MaxRms,
    /// Samples not compared, by why: the fast tick failed, the reference's
    /// solve failed, it did not converge, a newer sample replaced it.
    pub not_compared: BTreeMap<String, u64>,
    /// Compared samples whose reference stopped at round-off above the
    /// 1e-12 m tolerance (included; `last_step_max_m` says how far).
    pub round_off: u64,
    /// Most iterations a reference took.
    pub iterations_max: u32,
    /// Largest last step of a compared reference, m.
    #[serde(with = "super::figure")]
    pub last_step_max_m: f64,
}

impl Reference {
    fn of(o: &SessionOutcome) -> Reference {
        let r = &o.slow.reference;
        let nan = MaxRms {
            max: f64::NAN,
            rms: f64::NAN,
        };
        let missing = if let Some(why) = o.slow.reference_unsupported {
            Some(format!("not measured: {why}"))
        } else if o.fingers.is_empty() {
            Some("not measured: the scene has no fingers, so no force to compare".to_string())
        } else if r.compared > 0 {
            None
        } else if r.captured == 0 {
            Some("not measured: no tick was sampled".to_string())
        } else {
            Some(format!(
                "not measured: none of the {} sampled ticks could be compared",
                r.captured
            ))
        };
        let measured = missing.is_none();
        let pick = |m: MaxRms| if measured { m } else { nan };
        let not_compared = [
            ("fast_tick_failed", r.fast_failed),
            ("reference_failed", r.reference_failed),
            ("not_converged", r.not_converged),
            ("overwritten", r.overwritten),
        ]
        .into_iter()
        .filter(|(_, n)| *n > 0)
        .map(|(k, n)| (k.to_string(), n))
        .collect();
        Reference {
            every_ticks: o.plan.reference_every_ticks,
            samples: r.captured,
            compared: r.compared,
            missing,
            force_error_n: pick(MaxRms {
                max: r.force_error_max_n,
                rms: r.force_error_rms_n(),
            }),
            force_error_relative: pick(MaxRms {
                max: r.force_error_max_n / r.force_max_n,
                rms: r.force_error_rms_n() / r.force_rms_n(),
            }),
            force_n: pick(MaxRms {
                max: r.force_max_n,
                rms: r.force_rms_n(),
            }),
            configuration_error_m: pick(MaxRms {
                max: r.q_error_max_m,
                rms: r.q_error_rms_m(),
            }),
            not_compared,
            round_off: r.round_off,
            iterations_max: r.iterations_max,
            last_step_max_m: if measured {
                r.last_step_max_m
            } else {
                f64::NAN
            },
        }
    }
}

/// The tick's time per stage (`session::timing`), monotonic clock, ns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stages {
    /// The whole tick.
    pub tick: Percentiles,
    /// The tick without the device stages (device read, safety + write).
    pub tick_without_device: Percentiles,
    /// Mean of `tick_without_device`.
    pub tick_without_device_mean: f64,
    /// Per stage, by its key (`handover`, `device_read`, `update`,
    /// `evaluation`, `force`, `safety_write`, `bookkeeping`).
    pub stages: BTreeMap<String, Percentiles>,
}

impl Stages {
    /// Percentiles of `times`.
    pub fn of(times: &StageTimes) -> Stages {
        Stages {
            tick: times.tick.summary().into(),
            tick_without_device: times.tick_without_device.summary().into(),
            tick_without_device_mean: times.tick_without_device.summary().mean,
            stages: Stage::ALL
                .iter()
                .map(|&s| (s.key().to_string(), times.stage(s).summary().into()))
                .collect(),
        }
    }

    /// The percentiles of `stage`.
    pub fn get(&self, stage: Stage) -> Percentiles {
        self.stages[stage.key()]
    }
}

/// What the contact machinery saw and did (scenes whose shaped bodies can
/// touch; absent otherwise).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// Deepest penetration seen, m: the larger of the two below.
    #[serde(with = "super::figure")]
    pub max_penetration_m: f64,
    /// The penetration the scene tolerates (`penetration_tolerance`), m.
    pub tolerance_m: f64,
    /// `kept`, `EXCEEDED`, with the failed ticks counted as for the
    /// violation.
    pub verdict: String,
    /// Deepest penetration measured exactly (parry, separating axis) in the
    /// fast loop's snapshots, every slow-loop cycle, m.
    #[serde(with = "super::figure")]
    pub max_penetration_exact_m: f64,
    /// Deepest violation of a witness row in use at the end of a tick that
    /// succeeded, every tick, m.
    #[serde(with = "super::figure")]
    pub max_penetration_rows_m: f64,
    /// Most witness rows active (pushing) in one tick.
    pub max_active: u32,
    /// Primitive witnesses whose features changed inside tracked pairs.
    pub witness_changes: u64,
    /// Backups: a penetration beyond the tolerance (or a tunnel) seen in a
    /// snapshot, answered by reverting to the last clean configuration.
    pub backups: u64,
    /// Witnesses expanded to a higher-dimensional feature on penetration.
    pub expansions: u64,
    /// New programs because the set of tracked pairs changed.
    pub structure_changes: u64,
    /// Witness tables published for the running program.
    pub witness_tables: u64,
    /// Most pairs tracked at once.
    pub max_tracked_pairs: u32,
    /// In-tick activations (refactorisations for a contact a step would
    /// have violated).
    pub activations: u64,
    /// Ticks that ran out of activations.
    pub activation_limit_ticks: u64,
    /// Most fingertip contacts sticking (friction) at once.
    pub max_sticking: u32,
    /// Witness updates (tables and programs) the fast loop took over.
    pub updates: u64,
    /// Ticks from the snapshot an update was computed from to the tick that
    /// used it: mean.
    #[serde(with = "super::figure")]
    pub latency_ticks_mean: f64,
    /// Same, largest.
    pub latency_ticks_max: u64,
    /// One slow-loop contact cycle (broad + narrow phase, witnesses), µs:
    /// mean and largest.
    #[serde(with = "super::figure")]
    pub cycle_us_mean: f64,
    /// Same, largest.
    #[serde(with = "super::figure")]
    pub cycle_us_max: f64,
    /// Building a program for a new set of pairs (symbolic analysis
    /// included), µs: mean and largest.
    #[serde(with = "super::figure")]
    pub build_us_mean: f64,
    /// Same, largest.
    #[serde(with = "super::figure")]
    pub build_us_max: f64,
    /// Structure changes served from the cache by structure (a set of pairs
    /// seen before), and preparing one of those, µs: mean and largest
    /// (`"NaN"` when none was reused).
    pub reused: u64,
    /// Mean, µs.
    #[serde(with = "super::figure")]
    pub reuse_us_mean: f64,
    /// Largest, µs.
    #[serde(with = "super::figure")]
    pub reuse_us_max: f64,
    /// The contact speed limit, m/s: `contact_distance` per slow-loop
    /// cycle, the most a shaped body may move.
    #[serde(default)]
    pub speed_limit_m_per_s: f64,
    /// Ticks in which it held a shaped body back (a fingertip then lags its
    /// device).
    #[serde(default)]
    pub speed_limited_ticks: u64,
    /// The largest finger tracking error in such a tick, m.
    #[serde(default)]
    pub speed_limit_lag_max_m: f64,
    /// A penetration beyond this means the world came apart, m (the
    /// contact distance, at least ten times the tolerance).
    #[serde(default)]
    pub broken_penetration_m: f64,
    /// Slow-loop snapshots whose exact penetration was beyond it, and ticks
    /// whose witness rows were (failed: force cut). Either makes the
    /// verdict `BROKEN`.
    #[serde(default)]
    pub broken_snapshots: u64,
    /// Same, ticks.
    #[serde(default)]
    pub broken_ticks: u64,
    /// Slow-loop cycles that found a penetration beyond the tolerance and
    /// held it instead of backing it up: two backups in a row had not
    /// cleared it (the penetration stays, reported above).
    #[serde(default)]
    pub backups_held: u64,
    /// Ticks in which the witness rows were too old to move any body (the
    /// slow loop was late; the motion they are trusted for counts from
    /// their snapshot).
    #[serde(default)]
    pub stale_stopped_ticks: u64,
    /// The most motion since their snapshot the rows in use were asked to
    /// cover, in ticks at the contact speed limit (the budget is two
    /// slow-loop cycles).
    #[serde(default, with = "super::figure")]
    pub max_witness_age_ticks: f64,
}

/// How one design-variable component (m) or objective value moved over the
/// run: at the start (after assembly), at the end, and its extremes over the
/// ticks that succeeded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DesignFigure {
    /// At the start.
    #[serde(with = "super::figure")]
    pub start: f64,
    /// After the last tick that succeeded.
    #[serde(with = "super::figure")]
    pub end: f64,
    /// Smallest.
    #[serde(with = "super::figure")]
    pub min: f64,
    /// Largest.
    #[serde(with = "super::figure")]
    pub max: f64,
}

impl From<crate::session::Range4> for DesignFigure {
    fn from(r: crate::session::Range4) -> Self {
        Self {
            start: r.start,
            end: r.end,
            min: r.min,
            max: r.max,
        }
    }
}

/// One objective's reported value over the run (its unit depends on the
/// kind: see `docs/scene-format.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectiveFigure {
    /// The objective's kind.
    pub kind: String,
    /// Its weight.
    pub weight: f64,
    /// Start, end, min and max of its reported value.
    #[serde(flatten)]
    pub value: DesignFigure,
}

/// The whole summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// Requested length, s.
    pub seconds: f64,
    /// Loop rate, Hz.
    pub rate_hz: u32,
    /// Mock clock?
    pub deterministic: bool,
    /// AL iterations per tick.
    pub iterations: u32,
    /// Ticks run.
    pub ticks: u64,
    /// Missed deadlines (late + overrun + skipped).
    pub missed: u64,
    /// Missed deadlines by kind.
    pub misses: MissCounts,
    /// Wake-up lateness; `null` in deterministic mode, whose mock clock
    /// has none to measure (`clock_note` says so).
    pub lateness_ns: Option<Percentiles>,
    /// Tick compute time: the scheduler's in real time; in deterministic mode
    /// (whose scheduler runs on the mock clock) the monotonic clock's whole
    /// tick, `stages_ns.tick`.
    pub compute_ns: Percentiles,
    /// The tick's time per stage, monotonic clock.
    pub stages_ns: Stages,
    /// Start-to-start period.
    pub period_ns: Percentiles,
    /// First device read → last force write, per tick; `null` in
    /// deterministic mode (`clock_note` says why).
    pub read_to_write_ns: Option<Percentiles>,
    /// Which clock the timing figures come from, and why any is `null`.
    #[serde(default)]
    pub clock_note: String,
    /// Constraint violation.
    pub violation: Violation,
    /// Finger tracking error (attachment point vs device tip), m, all fingers.
    pub tracking_m: MaxRms,
    /// Force per finger.
    pub force_n: BTreeMap<String, FingerForce>,
    /// Faults reported to the safety hook (solver and device).
    pub faults: u64,
    /// Safety actions.
    pub safety: Safety,
    /// Host stalls: ticks after skipped slots and the periods dropped.
    #[serde(default)]
    pub stalls: Stalls,
    /// Initial assembly (null when skipped with `--no-assembly`).
    pub assembly: Option<Assembly>,
    /// The slow loop's re-projections.
    pub slow_loop: SlowLoop,
    /// The fast loop's force error against the converged reference.
    pub reference: Reference,
    /// Programs the slow loop handed over.
    pub programs_swapped: u64,
    /// Contact figures (absent for scenes without contact).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<Contact>,
    /// Semantic events and the grouping graph (absent for scenes without
    /// semantic areas or holds).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub semantic: Option<super::semantic::Semantic>,
    /// The moving bodies' energy (scenes with inertial motion; absent
    /// otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy: Option<super::energy::Energy>,
    /// What each virtual device did (`model = "virtual"`, `--device virtual`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub virtual_devices: Vec<crate::session::VirtualOutcome>,
    /// Trace samples dropped (queue full).
    pub trace_dropped: u64,
    /// What the OS granted the fast thread (real-time mode).
    pub granted: Option<Granted>,
    /// True if stopped early (Ctrl-C).
    pub stopped_early: bool,
    /// Per device: the ticks its own limits acted (workspace stops, peak
    /// clamp, motor saturation, thermal cut).
    #[serde(default)]
    pub device_limits: Vec<DeviceLimits>,
    /// A replay's comparison with its recording (absent when not
    /// replaying).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replay: Option<Replay>,
    /// What the user should know before trusting the figures: forces the
    /// device could not render, a replay that diverged. Empty when none.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Wall-clock seconds (not deterministic).
    pub wall_clock_s: f64,
    /// How each design-variable component moved, m: `"<joint>.<var>"` or
    /// `"<body>.position.x"` (absent without design variables).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub design: BTreeMap<String, DesignFigure>,
    /// Each objective's reported value over the run (absent without
    /// objectives).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub objectives: BTreeMap<String, ObjectiveFigure>,
    /// Each named joint's motor torque over the run (Nelson & Cohen §5.2;
    /// N·m, N on a prismatic joint; absent without `report_torque`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub joint_torques: BTreeMap<String, DesignFigure>,
}

impl Summary {
    /// Collects the summary of a finished session.
    pub fn of(o: &SessionOutcome) -> Summary {
        let s = &o.stats;
        Summary {
            scene: o.plan.scene.clone(),
            seconds: o.plan.seconds,
            rate_hz: o.plan.rate_hz,
            deterministic: o.plan.deterministic,
            iterations: o.plan.solver.iterations,
            ticks: o.report.ticks,
            missed: o.report.misses.total(),
            misses: o.report.misses,
            lateness_ns: (!o.plan.deterministic).then(|| o.report.lateness_ns.into()),
            compute_ns: if o.plan.deterministic {
                s.stages.tick.summary().into()
            } else {
                o.report.compute_ns.into()
            },
            stages_ns: Stages::of(&s.stages),
            period_ns: o.report.period_ns.into(),
            read_to_write_ns: (!o.plan.deterministic).then(|| s.read_to_write.summary().into()),
            clock_note: clock_note(o.plan.deterministic),
            violation: Violation::of(o),
            tracking_m: tracking(o),
            force_n: finger_forces(o),
            faults: s.faults,
            stalls: Stalls::of(o),
            safety: Safety::of(o),
            assembly: o.assembly.map(|a| Assembly {
                iterations: a.iterations,
                residual_m: a.residual_length_m,
                status: format!("{:?}", a.status),
                converged: a.status == haptloop_solver::SolveStatus::Converged,
            }),
            slow_loop: SlowLoop {
                reprojections: o.slow.reprojections,
                recoveries: o.slow.recoveries,
                placements_not_converged: o.slow.placements_not_converged,
                max_seen_violation_m: o.slow.max_seen_violation_m,
                step_ns: o.slow.step_ns.into(),
            },
            reference: Reference::of(o),
            programs_swapped: s.programs_swapped,
            contact: Contact::of(o),
            semantic: o.semantic.as_ref().map(Into::into),
            energy: super::energy::Energy::of(o),
            virtual_devices: o.virtual_devices.clone(),
            trace_dropped: o.trace_dropped,
            granted: o.granted.clone(),
            stopped_early: o.stopped_early,
            device_limits: o.device_limits.iter().map(DeviceLimits::from).collect(),
            replay: Replay::of(&o.device_limits),
            warnings: super::warnings::of(o),
            wall_clock_s: o.wall_clock_s,
            design: o
                .design
                .variables
                .iter()
                .map(|(n, r)| (n.clone(), (*r).into()))
                .collect(),
            objectives: objectives(o),
            joint_torques: o
                .design
                .torques
                .iter()
                .map(|(n, r)| (n.clone(), (*r).into()))
                .collect(),
        }
    }
}

impl Violation {
    fn of(o: &SessionOutcome) -> Violation {
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

impl Stalls {
    fn of(o: &SessionOutcome) -> Stalls {
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
    fn of(o: &SessionOutcome) -> Safety {
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

impl Contact {
    fn of(o: &SessionOutcome) -> Option<Contact> {
        let s = &o.stats;
        let measured = s.solved_ticks();
        o.slow.contact.map(|c| {
            let f = &s.contact;
            let mean = |sum: u64, n: u64| {
                if n == 0 {
                    f64::NAN
                } else {
                    sum as f64 / n as f64
                }
            };
            let max_pen = c.max_penetration_m.max(f.max_penetration_m);
            let tol = o.plan.contact.penetration_tolerance_m;
            let failed = s.solver_failures;
            let within = max_pen <= tol;
            let bound = crate::session::broken_penetration_m(&o.plan.contact);
            let broken_ticks =
                s.failure_kinds[crate::session::FailureKind::PenetrationBeyondBroken as usize];
            let broken = c.broken + broken_ticks;
            Contact {
                max_penetration_m: max_pen,
                tolerance_m: tol,
                verdict: match (measured, failed, within) {
                    _ if broken > 0 || max_pen > bound => format!(
                        "BROKEN: bodies came apart ({} snapshots and {broken_ticks} ticks \
                         penetrated beyond {bound:.1e} m; force cut)",
                        c.broken
                    ),
                    (0, _, _) => "not measured: no tick succeeded".into(),
                    (_, 0, true) => "kept".into(),
                    (_, 0, false) => "EXCEEDED".into(),
                    (_, f, w) => format!(
                        "FAILED TICKS: {f} ticks failed and are not covered; over the {measured} that succeeded: {}",
                        if w { "within the tolerance" } else { "EXCEEDED" }
                    ),
                },
                max_penetration_exact_m: c.max_penetration_m,
                max_penetration_rows_m: f.max_penetration_m,
                max_active: f.max_active,
                witness_changes: c.witness_changes,
                backups: c.backups,
                expansions: c.expansions,
                structure_changes: c.structure_changes,
                witness_tables: c.frames,
                max_tracked_pairs: c.max_tracked,
                activations: f.activations,
                activation_limit_ticks: f.activation_limit_ticks,
                max_sticking: f.max_sticking,
                updates: f.updates,
                latency_ticks_mean: mean(f.latency_sum_ticks, f.updates),
                latency_ticks_max: f.latency_max_ticks,
                cycle_us_mean: mean(c.cycle_ns_sum, c.cycles) / 1e3,
                cycle_us_max: c.cycle_ns_max as f64 / 1e3,
                build_us_mean: mean(c.build_ns_sum, c.structure_changes - c.reused) / 1e3,
                build_us_max: c.build_ns_max as f64 / 1e3,
                reused: c.reused,
                reuse_us_mean: mean(c.reuse_ns_sum, c.reused) / 1e3,
                reuse_us_max: if c.reused == 0 {
                    f64::NAN
                } else {
                    c.reuse_ns_max as f64 / 1e3
                },
                speed_limit_m_per_s: o.plan.solver.contact_step_m * f64::from(o.plan.rate_hz),
                speed_limited_ticks: f.speed_limited_ticks,
                speed_limit_lag_max_m: f.speed_limit_lag_max_m,
                broken_penetration_m: bound,
                broken_snapshots: c.broken,
                broken_ticks,
                backups_held: c.held,
                stale_stopped_ticks: f.stale_stopped_ticks,
                max_witness_age_ticks: f.max_witness_age,
            }
        })
    }
}
