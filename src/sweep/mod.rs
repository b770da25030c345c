//! `haptloop sweep`: the speed/accuracy trade of a scene, measured.
//!
//! ```text
//!  Grid (iterations × update × gain × rate × velocity filter) ──► Knobs per point
//!  1. accuracy, in parallel (one deterministic session per point, mock clock,
//!     reference sampled every `reference_every`): violation, force error
//!     against the converged reference, penetration, tracking, failed ticks
//!  2. timing, afterwards, one point at a time on the calling thread
//!     (session::timing::time_ticks: the same deterministic session with
//!     `haptloop bench`'s per-stage timing on the monotonic clock; the tick
//!     without the simulated devices' stages): p50, p99, ticks over the period
//!  3. pareto.rs: the front of CPU load against force error (else
//!     violation, else penetration), and the cheapest point that meets
//!     every criterion
//! ```
//!
//! Timing is kept honest by running it alone: no accuracy run shares the
//! machine with it (they all finished first), the points are timed one
//! after the other on one thread, and every point's session is the very one
//! whose accuracy was measured (same inputs, reference sampling off).
//! Results other than the times are deterministic: two sweeps of the same
//! grid agree bit for bit on them, whatever the thread count.

mod pareto;

pub use pareto::{Axis, Criteria, Verdict};

use crate::scenes::Scene;
use crate::session::timing::{TickTiming, time_ticks};
use crate::session::{self, Plan, SessionOptions, SessionOutcome};
use anyhow::Result;
use haptloop_devices::{Grip, PhantomModel};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::UpdateRule;
use std::collections::BTreeMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// The values of each knob to sweep; the grid is their product.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// Update iterations per tick.
    pub iterations: Vec<u32>,
    /// Update rules.
    pub update: Vec<UpdateRule>,
    /// Constraint gains K.
    pub gain: Vec<f64>,
    /// Loop rates, Hz.
    pub rate_hz: Vec<u32>,
    /// Velocity filter time constants, ms.
    pub velocity_filter_ms: Vec<f64>,
}

/// One point of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knobs {
    /// Update iterations per tick.
    pub iterations: u32,
    /// Update rule.
    pub update: UpdateRule,
    /// Constraint gain K.
    pub gain: f64,
    /// Loop rate, Hz.
    pub rate_hz: u32,
    /// Velocity filter time constant, ms.
    pub velocity_filter_ms: f64,
}

impl Grid {
    /// Every combination, rate slowest, then rule, iterations, gain, filter.
    pub fn points(&self) -> Vec<Knobs> {
        let mut out = Vec::new();
        for &rate_hz in &self.rate_hz {
            for &update in &self.update {
                for &iterations in &self.iterations {
                    for &gain in &self.gain {
                        for &velocity_filter_ms in &self.velocity_filter_ms {
                            out.push(Knobs {
                                iterations,
                                update,
                                gain,
                                rate_hz,
                                velocity_filter_ms,
                            });
                        }
                    }
                }
            }
        }
        out
    }
}

/// Largest and RMS value of a figure (NaN: not measured).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaxRms {
    /// Largest.
    pub max: f64,
    /// Root mean square.
    pub rms: f64,
}

impl MaxRms {
    const NAN: MaxRms = MaxRms {
        max: f64::NAN,
        rms: f64::NAN,
    };
}

/// What one point's deterministic session measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Accuracy {
    /// Translational joint-row violation over the ticks that succeeded, m
    /// (NaN: the scene has no joint rows, or no tick succeeded).
    pub violation_m: MaxRms,
    /// |F − F*| against the converged reference, N (NaN: not measured).
    pub force_error_n: MaxRms,
    /// Largest |F*| of the reference, N.
    pub force_max_n: f64,
    /// Finger tracking error, m.
    pub tracking_m: MaxRms,
    /// Ticks whose solve failed.
    pub failed_ticks: u64,
    /// Failed ticks by kind.
    pub failure_kinds: BTreeMap<String, u64>,
    /// Samples compared with the reference.
    pub reference_samples: u64,
    /// Why the force error is not measured, if it is not.
    pub reference_missing: Option<String>,
    /// Largest penetration of a shaped body, m (NaN: no contact machinery).
    pub penetration_m: f64,
}

impl Accuracy {
    /// The figures of a finished session.
    pub fn of(o: &SessionOutcome) -> Accuracy {
        let s = &o.stats;
        let solved = s.solved_ticks();
        let violation_m = if o.joint_rows == 0 || solved == 0 {
            MaxRms::NAN
        } else {
            MaxRms {
                max: s.violation_max_m,
                rms: s.violation_rms_m(),
            }
        };
        let n: u64 = s.fingers.iter().map(|f| f.tracking_n).sum();
        let tracking_m = if n == 0 {
            MaxRms::NAN
        } else {
            MaxRms {
                max: s.fingers.iter().map(|f| f.tracking_max).fold(0.0, f64::max),
                rms: (s.fingers.iter().map(|f| f.tracking_sumsq).sum::<f64>() / n as f64).sqrt(),
            }
        };
        let r = &o.slow.reference;
        let reference_missing = match o.slow.reference_unsupported {
            Some(why) => Some(why.to_string()),
            None if o.fingers.is_empty() => {
                Some("the scene has no fingers, so no force to compare".to_string())
            }
            None if r.compared == 0 => Some(format!(
                "none of the {} sampled ticks could be compared",
                r.captured
            )),
            None => None,
        };
        let (force_error_n, force_max_n) = if reference_missing.is_some() {
            (MaxRms::NAN, f64::NAN)
        } else {
            (
                MaxRms {
                    max: r.force_error_max_n,
                    rms: r.force_error_rms_n(),
                },
                r.force_max_n,
            )
        };
        Accuracy {
            violation_m,
            force_error_n,
            force_max_n,
            tracking_m,
            failed_ticks: s.solver_failures,
            failure_kinds: session::FailureKind::ALL
                .iter()
                .zip(&s.failure_kinds)
                .filter(|(_, n)| **n > 0)
                .map(|(k, n)| (k.as_str().to_string(), *n))
                .collect(),
            reference_samples: r.compared,
            reference_missing,
            penetration_m: o.slow.contact.map_or(f64::NAN, |c| {
                c.max_penetration_m.max(s.contact.max_penetration_m)
            }),
        }
    }
}

/// One measured point.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Its settings.
    pub knobs: Knobs,
    /// Its accuracy, or why its session could not run (unstable gains …).
    pub accuracy: Result<Accuracy, String>,
    /// Its tick cost (points whose session ran).
    pub timing: Option<TickTiming>,
    /// The virtual coupling is passive at this rate for a relaxed grip
    /// (Colgate: k T/2 + B < b_arm + b_grip).
    pub passive: bool,
    /// On the Pareto front of CPU load against the accuracy axis.
    pub pareto: bool,
    /// Whether it meets every criterion, or the first it misses.
    pub verdict: Verdict,
}

impl Point {
    /// Fraction of one core the fast loop takes at this rate (median tick
    /// × rate); NaN without a timing.
    pub fn load(&self) -> f64 {
        self.timing.map_or(f64::NAN, |t| {
            t.p50_ns as f64 * f64::from(self.knobs.rate_hz) / 1e9
        })
    }
}

/// Everything a sweep measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// Scene name.
    pub scene: String,
    /// The scene's violation tolerance, m.
    pub tolerance_m: Option<f64>,
    /// Session length per point, s.
    pub seconds: f64,
    /// Ticks between reference samples, per point's rate (0 = every tick
    /// is given as the duration zero).
    pub reference_every: Duration,
    /// The criteria of the recommendation.
    pub criteria: Criteria,
    /// What the front is drawn against.
    pub axis: Axis,
    /// Every point, grid order.
    pub points: Vec<Point>,
    /// Index of the cheapest point meeting every criterion.
    pub recommended: Option<usize>,
    /// The sweep was stopped (a signal) before every point was measured and
    /// timed.
    pub stopped_early: bool,
}

/// How a sweep runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Session length per point, s.
    pub seconds: f64,
    /// Compare one tick in this many with the reference (zero: every tick).
    pub reference_every: Duration,
    /// Threads for the accuracy runs.
    pub threads: usize,
    /// Largest force error accepted, as a fraction of the largest reference
    /// force.
    pub force_tolerance: f64,
}

/// What the sweep is doing, for a progress display.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// An accuracy run finished (point index).
    Accuracy(usize),
    /// A timing run finished (point index).
    Timing(usize),
}

/// Builds the options of one point's session.
fn session_options(k: &Knobs, o: &Options) -> SessionOptions {
    SessionOptions {
        seconds: o.seconds,
        rate_hz: Some(k.rate_hz),
        iterations: Some(k.iterations),
        update: Some(k.update),
        gain: Some(k.gain),
        velocity_filter: Some(Duration::from_secs_f64(k.velocity_filter_ms / 1000.0)),
        deterministic: true,
        reference_every: Some(o.reference_every),
        ..SessionOptions::default()
    }
}

/// Runs one point's deterministic session.
fn accuracy(scene: &Scene, k: &Knobs, o: &Options, stop: &StopFlag) -> Result<Accuracy, String> {
    let plan = Plan::new(scene, &session_options(k, o)).map_err(|e| format!("{e:#}"))?;
    let outcome = session::run(scene, plan, stop, &mut |_| {}).map_err(|e| format!("{e:#}"))?;
    if outcome.stopped_early {
        return Err(STOPPED.into());
    }
    Ok(Accuracy::of(&outcome))
}

const STOPPED: &str = "the sweep was stopped";

/// Is the scene's coupling passive at `rate_hz` for a relaxed grip on every
/// device of the scene (the least damped arm decides)?
fn passive(scene: &Scene, plan_coupling: (f64, f64), rate_hz: u32) -> bool {
    let (k, b_virtual) = plan_coupling;
    let b = scene
        .compiled
        .devices
        .iter()
        .filter_map(|d| PhantomModel::by_name(&d.model).ok())
        .map(|m| m.arm_damping_n_s_per_m + Grip::light().damping_n_s_per_m)
        .fold(f64::INFINITY, f64::min);
    let bound = haptloop_devices::passivity::colgate_bound_n_per_m(
        b,
        b_virtual,
        Duration::from_secs_f64(1.0 / f64::from(rate_hz)),
    );
    k <= bound
}

/// Runs the sweep: accuracy in parallel, then timing alone (see the module
/// docs). `progress` is called after every run; `stop` ends it early (the
/// points not run report why).
pub fn run(
    scene: &Scene,
    grid: &Grid,
    options: &Options,
    stop: &StopFlag,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Sweep> {
    let knobs = grid.points();
    let results: Mutex<Vec<Option<Result<Accuracy, String>>>> = Mutex::new(vec![None; knobs.len()]);
    let next = AtomicUsize::new(0);
    let threads = options.threads.clamp(1, knobs.len().max(1));
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= knobs.len() || stop.is_requested() {
                        break;
                    }
                    let a = accuracy(scene, &knobs[i], options, stop);
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(a);
                    }
                    progress(Progress::Accuracy(i));
                }
            });
        }
    });
    let results = results
        .into_inner()
        .map_err(|_| anyhow::anyhow!("an accuracy run panicked"))?;
    let coupling = {
        let plan = Plan::new(scene, &session_options(&knobs[0], options))?;
        (
            plan.solver.coupling_stiffness_n_per_m,
            plan.solver.coupling_damping_n_s_per_m,
        )
    };
    let mut points = Vec::with_capacity(knobs.len());
    for (i, (k, a)) in knobs.iter().zip(results).enumerate() {
        let accuracy = a.unwrap_or_else(|| Err(STOPPED.into()));
        let timing = match (&accuracy, stop.is_requested()) {
            (Ok(_), false) => {
                let plan = Plan::new(scene, &session_options(k, options))?;
                let t = time_ticks(scene, &plan)?;
                progress(Progress::Timing(i));
                Some(t)
            }
            _ => None,
        };
        points.push(Point {
            knobs: *k,
            accuracy,
            timing,
            passive: passive(scene, coupling, k.rate_hz),
            pareto: false,
            verdict: Verdict::Recommendable,
        });
    }
    let criteria = Criteria {
        tolerance_m: scene.compiled.settings.violation_tolerance,
        force_tolerance: options.force_tolerance,
        penetration_tolerance_m: Plan::new(scene, &session_options(&knobs[0], options))?
            .contact
            .penetration_tolerance_m,
    };
    let axis = pareto::axis(&points);
    let recommended = pareto::mark(&mut points, axis, &criteria);
    Ok(Sweep {
        scene: scene.compiled.name.clone(),
        tolerance_m: criteria.tolerance_m,
        seconds: options.seconds,
        reference_every: options.reference_every,
        criteria,
        axis,
        points,
        recommended,
        stopped_early: stop.is_requested(),
    })
}
