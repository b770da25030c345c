//! Resolving what a session will do: command-line flags override the scene's
//! `[solver]` table, which overrides the solver's defaults.

use crate::scenes::Scene;
use anyhow::{Result, bail};
use haptloop_rt::schedule::{MAX_RATE_HZ, MIN_RATE_HZ, ScheduleConfig};
use haptloop_rt::thread::ThreadConfig;
use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::scene::SemanticMode;
use haptloop_solver::{ForceSolver, SolverSettings, UpdateRule};
use std::path::PathBuf;
use std::time::Duration;

/// Default time constant of the velocity low-pass filter in sessions: 10 ms.
///
/// The solver's own default is 0 (exact inputs need none), but a session reads
/// quantised encoders: a 0.03 mm count at 1 kHz is a 30 m/s² step in the
/// finite-difference acceleration, so the Eq. 7 inertial force of a 0.08 kg
/// coupler buzzes by about 2.4 N per count. Measured on the default scene
/// (BENCHMARKS.md, sessions): tick-to-tick force change p99 7.0 N unfiltered,
/// 1.4 N at 2 ms, 0.66 N at 5 ms, 0.33 N at 10 ms; the accelerations' own
/// τ/4 stage (`ACCELERATION_FILTER_FRACTION` in the solver) then cut the
/// remaining buzz about 5× (BENCHMARKS.md, issue 11). 10 ms delays only the
/// inertial part of the force (gravity and coupling are undelayed), and is in
/// line with the 15–20 ms velocity windows CHAI3D and Force Dimension use.
pub const DEFAULT_VELOCITY_FILTER: Duration = Duration::from_millis(10);

/// What the user asked for (typed flags of `haptloop run`).
#[derive(Debug, Clone)]
pub struct SessionOptions {
    /// Session length, s.
    pub seconds: f64,
    /// Loop rate override, Hz.
    pub rate_hz: Option<u32>,
    /// AL iterations per tick override.
    pub iterations: Option<u32>,
    /// Update rule override (projected or Nelson & Cohen's gradient step).
    pub update: Option<UpdateRule>,
    /// Eq. 7 solver override (the Cholesky, or the matvec-only tick).
    pub force_solver: Option<ForceSolver>,
    /// Constraint gain K override.
    pub gain: Option<f64>,
    /// The fast loop's coordinates override (`--coordinates`).
    pub coordinates: Option<haptloop_solver::Coordinates>,
    /// Velocity low-pass time constant override (zero: off).
    pub velocity_filter: Option<Duration>,
    /// Mock clock, as fast as possible, bit-identical across runs.
    pub deterministic: bool,
    /// Assemble the scene with Newton-KKT placement before the clock starts
    /// (default); false starts from the file's configuration as written.
    pub assemble: bool,
    /// Where to write summary.json, histograms, trace.csv and plots.
    pub out_dir: Option<PathBuf>,
    /// Record each device's trace into this directory (`<device>.trace`).
    pub record: Option<PathBuf>,
    /// Replay each device from `<device>.trace` in this directory.
    pub replay: Option<PathBuf>,
    /// Spin window before each deadline.
    pub spin: Duration,
    /// The fast thread's core, priority and memory-locking requests.
    pub thread: ThreadConfig,
    /// Compare one tick in this many with the converged reference (`None`:
    /// [`DEFAULT_REFERENCE_EVERY`]; zero: every tick).
    pub reference_every: Option<Duration>,
    /// Stream the run to a live viewer (`--live`): called with the viewer's
    /// ends of the exchange when the loops start.
    pub live: Option<super::LiveHook>,
    /// The interaction mode at the start (`--semantic-mode`; `None`:
    /// constrained), for scenes with semantic areas (§6).
    pub semantic_mode: Option<SemanticMode>,
}

/// How often a session compares the fast loop's force with the converged
/// reference: every 100 ms (a replay costs a few factorisations of the
/// force matrix on the slow thread: 2–5 ms on the sphere toy).
pub const DEFAULT_REFERENCE_EVERY: Duration = Duration::from_millis(100);

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            seconds: 10.0,
            rate_hz: None,
            iterations: None,
            update: None,
            force_solver: None,
            gain: None,
            coordinates: None,
            velocity_filter: None,
            deterministic: false,
            assemble: true,
            out_dir: None,
            record: None,
            replay: None,
            spin: Duration::ZERO,
            thread: ThreadConfig::default(),
            reference_every: None,
            live: None,
            semantic_mode: None,
        }
    }
}

/// A resolved session plan.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Scene name.
    pub scene: String,
    /// Session length, s.
    pub seconds: f64,
    /// Loop rate, Hz.
    pub rate_hz: u32,
    /// Fast-loop solver settings.
    pub solver: SolverSettings,
    /// Violation the initial assembly must reach, m.
    pub assembly_tolerance_m: f64,
    /// Violation the scene promises to stay under while running, m.
    pub violation_tolerance_m: Option<f64>,
    /// Mock clock?
    pub deterministic: bool,
    /// Assemble with placement before the clock starts?
    pub assemble: bool,
    /// Output directory.
    pub out_dir: Option<PathBuf>,
    /// Device-trace recording directory.
    pub record: Option<PathBuf>,
    /// Device-trace replay directory.
    pub replay: Option<PathBuf>,
    /// Spin window before each deadline.
    pub spin: Duration,
    /// The fast thread's core, priority and memory-locking requests.
    pub thread: ThreadConfig,
    /// The contact active set's knobs (scenes with shapes).
    pub contact: ContactSettings,
    /// Ticks between comparisons with the converged reference (1: every
    /// tick; 0: none).
    pub reference_every_ticks: u64,
    /// Translational joint rows (violation is measured on these; 0: the
    /// status line and report say there is nothing to violate).
    pub joint_rows: usize,
    /// The live viewer's hook (`--live`).
    pub live: Option<super::LiveHook>,
    /// The semantic interaction mode at the start.
    pub semantic_mode: SemanticMode,
    /// Host stalls injected on the mock clock (deterministic runs only;
    /// `run --stall`).
    pub stalls: Vec<super::stall::Stall>,
    /// Slow-loop stalls injected in the lockstep (deterministic runs only;
    /// `run --slow-stall`): no slow step for that many periods.
    pub slow_stalls: Vec<super::stall::Stall>,
}

impl Plan {
    /// Resolves `options` against `scene`. Rejects values no loop can run.
    pub fn new(scene: &Scene, options: &SessionOptions) -> Result<Plan> {
        let s = &scene.compiled.settings;
        if !(options.seconds.is_finite() && options.seconds > 0.0 && options.seconds <= 86_400.0) {
            bail!("--seconds must be in (0, 86400], got {}", options.seconds);
        }
        let rate_hz = options.rate_hz.or(s.rate_hz).unwrap_or(1000);
        if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz) {
            bail!("--rate must be {MIN_RATE_HZ}–{MAX_RATE_HZ} Hz, got {rate_hz}");
        }
        let mut solver = solver_settings(scene, options)?;
        let contact = s.contact_settings();
        // The contact speed limit, in scenes where things can touch: no body
        // moves farther in one slow-loop cycle than the contact distance (see
        // SolverSettings::contact_step_m).
        if scene.compiled.shaped_bodies >= 2 {
            let cycle_ticks = (super::SLOW_PERIOD.as_secs_f64() * f64::from(rate_hz)).max(1.0);
            solver.contact_step_m = contact.contact_distance_m / cycle_ticks;
        }
        if contact.release_distance_m < contact.contact_distance_m {
            bail!(
                "[solver] release_distance ({} m) must not be below contact_distance ({} m)",
                contact.release_distance_m,
                contact.contact_distance_m
            );
        }
        if options.semantic_mode.is_some() && scene.compiled.semantic.is_none() {
            bail!(
                "--semantic-mode: scene `{}` has no semantic areas (offer and binding areas)",
                scene.compiled.name
            );
        }
        Ok(Plan {
            scene: scene.compiled.name.clone(),
            seconds: options.seconds,
            rate_hz,
            solver,
            assembly_tolerance_m: s.placement_tolerance.unwrap_or(1e-9),
            violation_tolerance_m: s.violation_tolerance,
            deterministic: options.deterministic,
            assemble: options.assemble,
            out_dir: options.out_dir.clone(),
            record: options.record.clone(),
            replay: options.replay.clone(),
            spin: options.spin,
            thread: options.thread.clone(),
            contact,
            reference_every_ticks: (options
                .reference_every
                .unwrap_or(DEFAULT_REFERENCE_EVERY)
                .as_secs_f64()
                * f64::from(rate_hz))
            .round()
            .max(1.0) as u64,
            joint_rows: super::joint_length_rows(&scene.compiled.model),
            live: options.live.clone(),
            semantic_mode: options.semantic_mode.unwrap_or_default(),
            stalls: Vec::new(),
            slow_stalls: Vec::new(),
        })
    }

    /// The loop period.
    pub fn period(&self) -> Duration {
        Duration::from_nanos(1_000_000_000 / u64::from(self.rate_hz))
    }

    /// The session length.
    pub fn duration(&self) -> Duration {
        Duration::from_secs_f64(self.seconds)
    }

    /// Grid slots in the session.
    pub fn ticks(&self) -> u64 {
        (self.seconds * f64::from(self.rate_hz)).round() as u64
    }

    /// The scheduler configuration.
    pub fn schedule(&self) -> ScheduleConfig {
        ScheduleConfig {
            rate_hz: self.rate_hz,
            spin: self.spin,
            thread: self.thread.clone(),
            ..ScheduleConfig::default()
        }
    }
}

/// The fast loop's settings: the session's defaults (inertial motion for
/// shaped moving bodies under gravity, docs/scene-format.md; the velocity
/// filter), the scene's `[solver]` keys over them
/// (`SceneSettings::apply_to`), and the flags over those (iterations,
/// update rule, force solver, gain, coordinates, velocity filter).
fn solver_settings(scene: &Scene, options: &SessionOptions) -> Result<SolverSettings> {
    let mut solver = SolverSettings {
        dynamics: haptloop_solver::dynamics::inertial_by_default(&scene.compiled.model),
        velocity_filter: DEFAULT_VELOCITY_FILTER,
        ..SolverSettings::default()
    };
    scene.compiled.settings.apply_to(&mut solver);
    // The scene's values passed its own validation; the checks below see
    // them too, as before, but fail only for a flag's.
    solver.iterations = options.iterations.unwrap_or(solver.iterations);
    if !(1..=10_000).contains(&solver.iterations) {
        bail!("--iterations must be 1–10000, got {}", solver.iterations);
    }
    if let Some(u) = options.update {
        solver.update = u;
    }
    if let Some(f) = options.force_solver {
        if matches!(f, ForceSolver::Matvec { .. } | ForceSolver::Tree { .. })
            && scene.compiled.shaped_bodies > 0
        {
            bail!(
                "--force-solver {} does not cover contact: scene `{}` has shaped bodies",
                f.label(),
                scene.compiled.name
            );
        }
        solver.force_solver = f;
    }
    solver.gain = options.gain.unwrap_or(solver.gain);
    if !(solver.gain.is_finite() && solver.gain > 0.0) {
        bail!("--gain must be a finite number > 0, got {}", solver.gain);
    }
    solver.coordinates = options.coordinates.unwrap_or(solver.coordinates);
    solver.velocity_filter = options.velocity_filter.unwrap_or(solver.velocity_filter);
    Ok(solver)
}

#[cfg(test)]
mod tests;
