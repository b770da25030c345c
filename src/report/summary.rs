//! `summary.json`: every figure of a session, machine-readable.
//!
//! In deterministic mode every field except the measured times is
//! bit-identical across runs: `wall_clock_s`, `compute_ns`, `stages_ns` and
//! `slow_loop.step_ns` are read from the monotonic clock (real compute time,
//! see `session::timing`); the scheduler's own timing fields follow the mock
//! clock and are functions of the tick count.
//!
//! The figures by kind: `run` (violation, forces, safety, stalls, assembly,
//! slow loop), `reference`, `timing`, `contact` and `design`; this file
//! collects them into the [`Summary`].

mod contact;
mod design;
mod reference;
mod run;
mod timing;

pub use super::limits::{DeviceLimits, Replay, ReplayDevice};
pub use contact::Contact;
pub use design::{DesignFigure, ObjectiveFigure};
pub use reference::Reference;
pub use run::{Assembly, DeviceEvent, FingerForce, MaxRms, Safety, SlowLoop, Stalls, Violation};
pub use timing::Stages;

use crate::session::SessionOutcome;
use haptloop_rt::probe::Percentiles;
use haptloop_rt::schedule::MissCounts;
use haptloop_rt::thread::Granted;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

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
    /// Which coordinates the fast loop's tick ran in, and why
    /// (`Program::coordinates`).
    #[serde(default)]
    pub coordinates: String,
    /// Joint ticks of the final program that failed and ran as augmented
    /// ticks instead.
    #[serde(default)]
    pub joint_fallbacks: u64,
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
            coordinates: o.coordinates.clone(),
            joint_fallbacks: o.joint_fallbacks,
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
