//! `haptloop run`: a scene on simulated devices, with a report.

mod args;
mod files;

pub use args::RunArgs;
use files::write_files;

use super::output::{RunDir, utc_stamp};
use crate::report::{session as text, summary::Summary};
use crate::scenes::{Scene, check_loaded, resolve};
use crate::session::{self, Plan, SessionOptions};
use crate::view::{self, SceneInfo, live::LiveServer};
use anyhow::Result;
use haptloop_rt::schedule::StopFlag;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
        eprintln!("haptloop: fast-loop coordinates: {}", outcome.coordinates);
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
pub(super) fn session_options(args: &RunArgs, live: Option<session::LiveHook>) -> SessionOptions {
    let mut options = SessionOptions {
        seconds: args.seconds,
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
        ..SessionOptions::default()
    };
    args.solver.apply(&mut options);
    options
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
