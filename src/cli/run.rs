//! `haptloop run`: a scene on simulated devices, with a report.

use super::output::{RunDir, produce_atomic, write_atomic};
use super::rt_args::RtArgs;
use super::values;
use crate::report::{plots, scene_plot, session as text, summary::Summary};
use crate::scenes::{DEFAULT_SCENE, Scene, check_loaded, resolve};
use crate::session::{self, Plan, SessionOptions};
use crate::view::{self, SceneInfo, live::LiveServer};
use anyhow::Result;
use clap::Args;
use haptloop_rt::schedule::{MAX_RATE_HZ, MIN_RATE_HZ, StopFlag};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// Flags of `haptloop run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// A built-in scene (see `haptloop scenes`) or a scene file (TOML).
    #[arg(default_value = DEFAULT_SCENE)]
    pub scene: String,
    /// Session length in seconds, (0, 86400].
    #[arg(long, default_value_t = 10.0, value_parser = values::seconds)]
    pub seconds: f64,
    /// Fast-loop rate in Hz (100–20000); default: the scene's, else 1000.
    #[arg(long, value_parser = clap::value_parser!(u32).range(i64::from(MIN_RATE_HZ)..=i64::from(MAX_RATE_HZ)))]
    pub rate: Option<u32>,
    /// Augmented-Lagrangian iterations per tick (1–10000): more is more
    /// accurate and costs more per tick. Default: the scene's, else the
    /// solver's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub iterations: Option<u32>,
    /// Update rule of the fast loop: `projected` (Gauss–Newton with the
    /// force solve's factor; the default) or `gradient` (Nelson & Cohen
    /// Eq. 1–3).
    #[arg(long, value_name = "RULE", value_parser = values::update_rule)]
    pub update: Option<haptloop_solver::UpdateRule>,
    /// Eq. 7 solver: `cholesky` (a numeric factorisation a tick; the
    /// default) or `matvec` (experimental: no factorisation in the tick,
    /// conjugate gradients preconditioned by a factor the slow loop
    /// refreshes, a solve that reaches the cap redone with a factorisation;
    /// not for contact; measured slower than `cholesky` on every mechanism,
    /// BENCHMARKS.md), `matvec:N` to cap its iterations at N (default 64),
    /// `tree` (experimental: no full factor, conjugate gradients
    /// preconditioned by a spanning tree of the mechanism; not for contact;
    /// measured slower than `cholesky` on meshes, BENCHMARKS.md), `tree:N`
    /// to cap its iterations a solve at N (default 500), `multilevel` and
    /// `multilevel:N` (experimental: conjugate gradients preconditioned by
    /// an aggregation V-cycle; not for contact), `cg:N`
    /// (Jacobi-preconditioned, gradient update only).
    #[arg(long, value_name = "SOLVER", value_parser = values::force_solver)]
    pub force_solver: Option<haptloop_solver::ForceSolver>,
    /// Constraint gain K of the fast update (finite, > 0). Default: the
    /// scene's, else the solver's.
    #[arg(long, value_parser = values::positive)]
    pub gain: Option<f64>,
    /// Time constant of the low-pass filter on the velocities behind the
    /// Eq. 7 inertial force, ms (0 turns it off). Default: the scene's, else
    /// 10 ms: encoder quantisation makes unfiltered accelerations buzz.
    #[arg(long, value_name = "MS", value_parser = values::filter_ms)]
    pub velocity_filter_ms: Option<f64>,
    /// Run on a mock clock as fast as possible: bit-identical results across
    /// runs (every summary.json field but wall_clock_s), no real-time figures.
    #[arg(long)]
    pub deterministic: bool,
    /// Start from the scene file's configuration as written, without the
    /// Newton-KKT assembly (watch the fast loop and the slow loop pull it
    /// together).
    #[arg(long)]
    pub no_assembly: bool,
    /// Output directory (default `runs/<scene>-<UTC time>/`).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write no files; print the report only.
    #[arg(long, conflicts_with = "out")]
    pub no_files: bool,
    /// Record every device's trace into DIR (`<device>.trace`).
    #[arg(long, value_name = "DIR")]
    pub record: Option<PathBuf>,
    /// Replay every device from DIR (`<device>.trace`) instead of simulating.
    #[arg(long, value_name = "DIR")]
    pub replay: Option<PathBuf>,
    /// Real-time thread requests.
    #[command(flatten)]
    pub rt: RtArgs,
    /// No live status line.
    #[arg(long)]
    pub quiet: bool,
    /// Frees a design variable without editing the scene (repeatable):
    /// `<joint>.length`, `<joint>.anchor_i`, `<joint>.anchor_j` or
    /// `<fixed body>.position`.
    #[arg(long, value_name = "OWNER.VAR")]
    pub free: Vec<String>,
    /// Adds an objective (repeatable): `KIND` or `KIND:key=value,…` with the
    /// keys of `[[objective]]` (docs/scene-format.md); names need no quotes,
    /// e.g. `dexterity:chain=[base,upper,fore],point=[0.1,0,0],weight=0.01`.
    #[arg(long, value_name = "KIND:KEY=VALUE,…")]
    pub objective: Vec<String>,
    /// Switches a design variable off at a session time (repeatable):
    /// `NAME@SECONDS`, e.g. `rocker.anchor_j@2.5`; held where it is until
    /// switched on again (Nelson & Cohen's design flags; `[[design_flag]]`).
    #[arg(long, value_name = "NAME@SECONDS")]
    pub design_off: Vec<String>,
    /// Switches a design variable back on at a session time (repeatable):
    /// `NAME@SECONDS`.
    #[arg(long, value_name = "NAME@SECONDS")]
    pub design_on: Vec<String>,
    /// Serve a live 3-D view on http://127.0.0.1:PORT/ (never another
    /// interface) and stream the run to it; the run starts when the page
    /// connects. Virtual devices are dragged there with the mouse.
    #[arg(long, conflicts_with = "deterministic")]
    pub live: bool,
    /// The live view's port (0: any free one).
    #[arg(long, default_value_t = 8470, requires = "live")]
    pub port: u16,
    /// Replace every device of the scene with this model (`virtual`: moved
    /// by the mouse in the live view, its scripted hand dropped; or a
    /// PHANToM model).
    #[arg(long, value_name = "MODEL")]
    pub device: Option<String>,
    /// The semantic interaction mode at the start (Gösele & Stuerzlinger
    /// §6): `constrained` (the default: a held object's offer/binding
    /// constraints act) or `unconstrained` (they are off for the held
    /// object); `[[schedule]] mode` switches it during the run.
    #[arg(long, value_name = "MODE", value_parser = semantic_mode)]
    pub semantic_mode: Option<haptloop_solver::scene::SemanticMode>,
    /// Injects a host stall on the mock clock (repeatable, deterministic
    /// runs only): `SECONDS:PERIODS`, the tick at SECONDS is followed by the
    /// next one PERIODS periods later, as after a real stall (the scheduler
    /// skips the slots between).
    #[arg(long, value_name = "SECONDS:PERIODS", requires = "deterministic", value_parser = stall)]
    pub stall: Vec<session::Stall>,
    /// Stalls the slow loop in a deterministic run (repeatable):
    /// `SECONDS:PERIODS`, no slow-loop step (contact witnesses and
    /// programs, re-projection) for PERIODS periods after SECONDS, as when
    /// the slow thread is descheduled or a contact program takes long to
    /// build.
    #[arg(long, value_name = "SECONDS:PERIODS", requires = "deterministic", value_parser = slow_stall)]
    pub slow_stall: Vec<session::Stall>,
}

/// `--slow-stall`'s values.
fn slow_stall(s: &str) -> Result<session::Stall, String> {
    session::Stall::parse_flag("--slow-stall", s).map_err(|e| e.to_string())
}

/// `--stall`'s values.
fn stall(s: &str) -> Result<session::Stall, String> {
    session::Stall::parse(s).map_err(|e| e.to_string())
}

/// `--semantic-mode`'s values.
fn semantic_mode(s: &str) -> Result<haptloop_solver::scene::SemanticMode, String> {
    use haptloop_solver::scene::SemanticMode;
    match s {
        "constrained" => Ok(SemanticMode::Constrained),
        "unconstrained" => Ok(SemanticMode::Unconstrained),
        _ => Err(format!("`{s}`: expected `constrained` or `unconstrained`")),
    }
}

impl Default for RunArgs {
    fn default() -> Self {
        RunArgs {
            scene: DEFAULT_SCENE.into(),
            seconds: 10.0,
            rate: None,
            iterations: None,
            update: None,
            force_solver: None,
            gain: None,
            velocity_filter_ms: None,
            deterministic: false,
            no_assembly: false,
            out: None,
            no_files: false,
            record: None,
            replay: None,
            rt: RtArgs::default(),
            quiet: false,
            free: Vec::new(),
            objective: Vec::new(),
            design_off: Vec::new(),
            design_on: Vec::new(),
            live: false,
            port: 8470,
            device: None,
            semantic_mode: None,
            stall: Vec::new(),
            slow_stall: Vec::new(),
        }
    }
}

/// `YYYYMMDD-HHMMSS` in UTC, for default run directories.
pub(super) fn utc_stamp() -> String {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Days since 1970-01-01 → civil date (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}{m:02}{d:02}-{:02}{:02}{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// Exit status of a run that finished but had failed ticks, or whose replay
/// did not reproduce its recording (README, "Exit status").
pub const EXIT_FAILED_TICKS: u8 = 3;

/// Runs a session and prints (and writes) its report.
pub fn run(args: &RunArgs, stop: &StopFlag) -> Result<ExitCode> {
    let scene = match prepared_scene(args) {
        Ok(s) => s,
        Err(code) => return Ok(code),
    };
    // The live view listens before anything is claimed or built: a port in
    // use is said at once.
    let server = if args.live {
        Some(LiveServer::bind(args.port)?)
    } else {
        None
    };
    let live = match &server {
        Some(s) => Some(s.hook(SceneInfo::of(&scene))?),
        None => None,
    };
    let options = session_options(args, live);
    if args.semantic_mode.is_some() && scene.compiled.semantic.is_none() {
        return Ok(super::usage_error(&format!(
            "--semantic-mode: scene `{}` has no semantic areas (offer and binding areas)",
            scene.compiled.name
        )));
    }
    // Everything a flag can get wrong is said before the output directory
    // is claimed.
    let mut plan = Plan::new(&scene, &options)?;
    plan.stalls = args.stall.clone();
    plan.slow_stalls = args.slow_stall.clone();
    if let Err(msg) = args.rt.check_spin(plan.rate_hz) {
        return Ok(super::usage_error(&msg));
    }
    if let Err(msg) = check_record(args, &plan) {
        return Ok(super::usage_error(&msg));
    }
    let run_dir = claim_run_dir(args, &scene)?;
    plan.out_dir = run_dir.as_ref().map(|d| d.path().to_path_buf());
    announce(server.as_ref(), &scene, &plan);
    let outcome = run_with_progress(args, &scene, plan, stop);
    if let Some(s) = server {
        report_live(&s.finish());
    }
    let outcome = outcome?;
    let summary = Summary::of(&outcome);
    let fingers: Vec<(String, String)> = outcome
        .fingers
        .iter()
        .cloned()
        .zip(outcome.finger_devices.iter().cloned())
        .collect();
    if !super::signals::aborting() {
        super::emit(&text::render(&summary, &fingers));
    }
    if let Some(dir) = run_dir {
        write_files(dir.path(), &scene, &outcome, &summary)?;
        dir.release()?;
    }
    Ok(exit_status(&summary))
}

/// The scene `args` names with its design flags, switches and device model
/// applied; on a bad one, the error is printed and its exit status returned
/// (1: no such scene, 2: a flag it cannot take).
fn prepared_scene(args: &RunArgs) -> Result<Scene, ExitCode> {
    let scene = resolve(&args.scene).map_err(|e| {
        eprintln!("{e}");
        ExitCode::from(1)
    })?;
    let scene = with_design_flags(scene, &args.free, &args.objective)
        .and_then(|s| with_design_switches(s, &args.design_on, &args.design_off))
        .map_err(|e| {
            eprintln!("{e}");
            ExitCode::from(2)
        })?;
    match &args.device {
        Some(model) => scene.with_device_model(model).map_err(|e| {
            eprintln!("haptloop: {e}");
            ExitCode::from(2)
        }),
        None => Ok(scene),
    }
}

/// The session's options from the flags (`live`: the live view's hook).
fn session_options(args: &RunArgs, live: Option<session::LiveHook>) -> SessionOptions {
    SessionOptions {
        seconds: args.seconds,
        rate_hz: args.rate,
        iterations: args.iterations,
        update: args.update,
        force_solver: args.force_solver,
        gain: args.gain,
        velocity_filter: args
            .velocity_filter_ms
            .map(|ms| Duration::from_secs_f64(ms / 1000.0)),
        deterministic: args.deterministic,
        assemble: !args.no_assembly,
        out_dir: None,
        record: args.record.clone(),
        replay: args.replay.clone(),
        spin: args.rt.spin(),
        thread: args.rt.thread(),
        reference_every: None,
        live,
        semantic_mode: args.semantic_mode,
    }
}

/// The run's output directory (none with `--no-files`), claimed before
/// anything runs: a non-empty --out is refused, and the lock keeps a second
/// run out while this one writes. Every exit from here on gives it back
/// (RunDir's drop) unless the run completes.
fn claim_run_dir(args: &RunArgs, scene: &Scene) -> Result<Option<RunDir>> {
    Ok(match (&args.out, args.no_files) {
        (_, true) => None,
        (Some(d), false) => Some(RunDir::claim(d)?),
        (None, false) => Some(RunDir::claim_fresh(&Path::new("runs").join(format!(
            "{}-{}",
            scene.compiled.name,
            utc_stamp()
        )))?),
    })
}

/// Says on stderr what is about to run: the live view's address (or that
/// nothing moves the virtual devices without it), the scene, length and rate.
fn announce(server: Option<&LiveServer>, scene: &Scene, plan: &Plan) {
    let virtuals = scene
        .compiled
        .devices
        .iter()
        .filter(|d| d.model == haptloop_devices::VIRTUAL_MODEL)
        .count();
    if let Some(s) = server {
        eprintln!(
            "haptloop: live view at {} : open it in a browser; the run starts when it connects",
            s.url()
        );
    } else if virtuals > 0 {
        eprintln!(
            "haptloop: {virtuals} virtual device(s) and no --live: nothing will move them (pass --live to drag them)"
        );
    }
    eprintln!(
        "haptloop: running `{}` for {:.1} s at {} Hz{}; Ctrl-C stops cleanly",
        plan.scene,
        plan.seconds,
        plan.rate_hz,
        if plan.deterministic {
            " (deterministic)"
        } else {
            ""
        }
    );
}

/// Runs the session, its status lines on a spinner when stderr is a terminal
/// (else printed, unless `--quiet`).
fn run_with_progress(
    args: &RunArgs,
    scene: &Scene,
    plan: Plan,
    stop: &StopFlag,
) -> Result<session::SessionOutcome> {
    let bar = (!args.quiet && std::io::stderr().is_terminal()).then(|| {
        let b = ProgressBar::new_spinner();
        b.set_style(ProgressStyle::with_template("{spinner} {msg}").expect("valid template"));
        b
    });
    let quiet = args.quiet;
    let mut status = |line: &str| match &bar {
        Some(b) => b.set_message(line.to_string()),
        None if !quiet => eprintln!("{line}"),
        None => {}
    };
    let outcome = session::run(scene, plan, stop, &mut status);
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    outcome
}

/// Says on stderr what the live view served.
fn report_live(st: &view::live::LiveStats) {
    let moves: Vec<String> = st
        .pointer_moves
        .iter()
        .map(|(d, n)| format!("{d} {n}"))
        .collect();
    eprintln!(
        "haptloop: live view: {} page(s) served, {} viewer(s), {} frames sent{}{}",
        st.pages,
        st.viewers,
        st.frames,
        if moves.is_empty() {
            String::new()
        } else {
            format!("; pointer moves: {}", moves.join(", "))
        },
        if st.bad_messages > 0 {
            format!("; {} messages not understood (ignored)", st.bad_messages)
        } else {
            String::new()
        }
    );
}

/// 0 when every planned tick ran and succeeded; [`EXIT_FAILED_TICKS`] when
/// ticks failed or a replay diverged from its recording; 130 when a signal
/// stopped the run (its files are written all the same).
fn exit_status(s: &Summary) -> ExitCode {
    if s.stopped_early || super::signals::aborting() {
        eprintln!(
            "haptloop: stopped by a signal after {} ticks (exit status {})",
            s.ticks,
            super::signals::EXIT_SIGNAL
        );
        return ExitCode::from(super::signals::EXIT_SIGNAL);
    }
    let diverged = s.replay.as_ref().is_some_and(|r| r.diverged());
    if s.safety.solver_failures > 0 || diverged {
        let mut why = Vec::new();
        if s.safety.solver_failures > 0 {
            why.push(format!("{} ticks failed", s.safety.solver_failures));
        }
        if diverged {
            why.push("the replay diverged from its recording".to_string());
        }
        eprintln!(
            "haptloop: {} (exit status {EXIT_FAILED_TICKS})",
            why.join("; ")
        );
        return ExitCode::from(EXIT_FAILED_TICKS);
    }
    ExitCode::SUCCESS
}

/// `--record` must not write over the traces `--replay` reads, and must fit
/// what a replay can read back.
fn check_record(args: &RunArgs, plan: &Plan) -> Result<(), String> {
    let Some(record) = &args.record else {
        return Ok(());
    };
    if record.exists() && !record.is_dir() {
        return Err(format!(
            "--record {}: that is a file; --record takes a directory (one trace per device is \
             written into it)",
            record.display()
        ));
    }
    if let Some(replay) = &args.replay
        && same_directory(record, replay)
    {
        return Err(format!(
            "--record {}: that is the --replay directory; recording there would overwrite the \
             traces being replayed (record into another directory)",
            record.display()
        ));
    }
    let rows = plan.ticks() + 1;
    let most = haptloop_devices::MAX_TRACE_ROWS as u64;
    if rows > most {
        return Err(format!(
            "--record: this run would record {rows} rows per device; a replay reads at most {most} \
             (pass --seconds {} or less at {} Hz)",
            (most - 1) / u64::from(plan.rate_hz),
            plan.rate_hz
        ));
    }
    Ok(())
}

/// True when `a` and `b` name the same directory (either may not exist yet).
fn same_directory(a: &Path, b: &Path) -> bool {
    let resolve = |p: &Path| -> PathBuf {
        if let Ok(c) = p.canonicalize() {
            return c;
        }
        match (p.parent(), p.file_name()) {
            (Some(parent), Some(name)) => {
                let parent = if parent.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    parent
                };
                parent
                    .canonicalize()
                    .map_or_else(|_| p.to_path_buf(), |c| c.join(name))
            }
            _ => p.to_path_buf(),
        }
    };
    resolve(a) == resolve(b)
}

/// The scene with `--free` and `--objective` applied (unchanged without
/// them). An error about a flag names the flag (exit status 2).
fn with_design_flags(
    scene: Scene,
    free: &[String],
    objectives: &[String],
) -> Result<Scene, haptloop_solver::scene::SceneError> {
    if free.is_empty() && objectives.is_empty() {
        return Ok(scene);
    }
    let flagged = scene.loaded.with_flags(free, objectives)?;
    check_loaded(flagged.loaded.clone()).map_err(|e| flagged.attribute(e))
}

/// The scene with `--design-on` / `--design-off` switches added to its
/// `[[design_flag]]` schedule. An error names the flag (exit status 2).
pub fn with_design_switches(
    mut scene: Scene,
    on: &[String],
    off: &[String],
) -> Result<Scene, haptloop_solver::scene::SceneError> {
    use haptloop_solver::scene::{design_switch, with_switches};
    let model = &scene.compiled.model;
    let switches = off
        .iter()
        .map(|v| design_switch(v, false, model))
        .chain(on.iter().map(|v| design_switch(v, true, model)))
        .collect::<Result<Vec<_>, _>>()?;
    scene.compiled.design_flags = with_switches(&scene.compiled.design_flags, switches);
    Ok(scene)
}

fn write_files(
    dir: &Path,
    scene: &Scene,
    o: &session::SessionOutcome,
    summary: &Summary,
) -> Result<()> {
    let write = |name: &str, text: String| write_atomic(&dir.join(name), text.as_bytes());
    write(
        "summary.json",
        serde_json::to_string_pretty(summary)? + "\n",
    )?;
    if super::signals::aborting() {
        super::emit(&format!(
            "wrote {}/: summary.json, trace.csv (aborted: nothing else)",
            dir.display()
        ));
        return Ok(());
    }
    // On the mock clock (deterministic mode) there is no lateness and no
    // device-to-motor time to record: those files are not written, and
    // compute.hgrm holds the monotonic clock's whole tick instead.
    let timing_files = if o.plan.deterministic {
        write(
            "compute.hgrm",
            o.stats.stages.tick.percentile_distribution(1000.0),
        )?;
        "compute.hgrm (µs, monotonic clock)"
    } else {
        write(
            "lateness.hgrm",
            o.histograms.lateness.percentile_distribution(1000.0),
        )?;
        write(
            "compute.hgrm",
            o.histograms.compute.percentile_distribution(1000.0),
        )?;
        write(
            "read-to-write.hgrm",
            o.stats.read_to_write.percentile_distribution(1000.0),
        )?;
        "lateness.hgrm, compute.hgrm, read-to-write.hgrm (µs)"
    };
    produce_atomic(&dir.join("latency.svg"), |p| plots::latency(p, o))?;
    produce_atomic(&dir.join("force.svg"), |p| plots::force(p, o))?;
    let mut extra = String::new();
    // No empty plots: a scene without joint rows has no violation to draw.
    if o.joint_rows > 0 {
        produce_atomic(&dir.join("violation.svg"), |p| plots::violation(p, o))?;
        extra += ", violation.svg";
    }
    if o.track.bodies.iter().any(|b| b.shape.is_some()) {
        produce_atomic(&dir.join("contact.svg"), |p| {
            scene_plot::contact(p, &o.plan.scene, &o.track)
        })?;
        extra += ", contact.svg";
    }
    // Joint torques alone (the last columns) are not plotted.
    if o.recorder.design_names.len() > o.recorder.design_torques {
        produce_atomic(&dir.join("design.svg"), |p| plots::design(p, o))?;
        extra += ", design.svg";
    }
    for (name, text) in view::files::contents(&SceneInfo::of(scene), o)? {
        write(name, text)?;
    }
    view::write_page(dir, write_atomic)?;
    extra += ", scene.json, bodies.csv, fingers.csv, contacts.csv, view.html";
    super::emit(&format!(
        "wrote {}/: summary.json, trace.csv, {timing_files}, latency.svg, force.svg{extra}",
        dir.display()
    ));
    Ok(())
}
