//! Command-line parsing: flags become typed values here, then validated
//! configuration objects of the library crates.

mod bench;
mod check;
mod export;
mod output;
mod place;
mod preflight;
mod probe;
mod rt_args;
mod run;
mod scenes;
mod signals;
mod solver_args;
mod sweep;
mod values;
mod view;

pub use run::EXIT_FAILED_TICKS;
pub use signals::EXIT_SIGNAL;

use anyhow::Result;
use clap::{CommandFactory, Parser, Subcommand};
use std::process::ExitCode;

/// Writes `text` and a newline to stdout. A closed stdout (`haptloop run |
/// head`) is not an error: the run still writes its files, where `println!`
/// would panic halfway.
pub(crate) fn emit(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = out
        .write_all(text.as_bytes())
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush());
}

/// Real-time haptic interaction with constrained virtual mechanisms.
///
/// A pinned kilohertz loop keeps a virtual mechanism assembled around the
/// finger of a (simulated) PHANToM arm and renders the constraint force.
#[derive(Debug, Parser)]
#[command(name = "haptloop", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a scene on simulated PHANToM arms and report what happened.
    ///
    /// The fast loop (pinned, SCHED_FIFO when permitted) reads every device,
    /// keeps the mechanism assembled around each finger and writes the force
    /// through the safety layer; the slow loop watches it; a status line
    /// prints once a second. At the end: latency percentiles, misses,
    /// constraint violation, tracking error, force per finger, safety events.
    /// Files go to --out DIR (default runs/<scene>-<time>/).
    Run(run::RunArgs),
    /// Measure the speed/accuracy trade of a scene over a grid of settings.
    ///
    /// Runs one deterministic session per point of the grid (iterations ×
    /// update rule × gain × rate × velocity filter; in parallel across the
    /// cores), then, to keep timing honest, reruns each point alone on one
    /// thread with nothing else of the sweep running and times its ticks
    /// per stage as `haptloop bench` does (the tick without the simulated
    /// devices' stages; other processes on the machine still count). Per
    /// point: violation, force error against the converged reference,
    /// penetration (contact scenes), tracking error, µs per tick, ticks over
    /// the period, failed ticks. Prints a table with the Pareto front (CPU
    /// load against force error, else violation, else penetration) and the
    /// cheapest point within the scene's tolerances; writes sweep.csv,
    /// sweep.json and front.svg to --out DIR (default
    /// runs/sweep-<scene>-<time>/).
    Sweep(sweep::SweepArgs),
    /// Measure this machine's timer and the scheduler's added jitter.
    ///
    /// Runs the hard-rate scheduler with a synthetic tick load, alternating in
    /// one-second blocks with a bare absolute-sleep reference loop on the same
    /// core and priority, and prints both side by side.
    Probe(probe::ProbeArgs),
    /// Time a scene's fast-loop tick per stage, on the mock clock.
    ///
    /// Runs the session as `run --deterministic` does (same inputs every
    /// run, no sleeping, the slow loop in lockstep) and reports percentiles
    /// of each stage of the tick, measured on the monotonic clock: device
    /// read, update iterations, evaluation, the Eq. 7 force solve, safety +
    /// write, bookkeeping, the whole tick and the tick without the device
    /// stages; then the slow loop's step time and the constraint violation.
    Bench(bench::BenchArgs),
    /// Write RUN_DIR/view.html: a run in 3-D, one file that opens from disk.
    ///
    /// Orbit, pan and zoom; a timeline with play, pause and speed; the
    /// bodies (shapes, or links between joint anchors), fingers, force
    /// arrows, contact points and normals; force, violation and penetration
    /// plots; the semantic events on the timeline. `run` writes it too.
    View(view::ViewArgs),
    /// List the built-in scenes, one line each, grouped by the paper and
    /// figure they show.
    Scenes,
    /// Write a scene in another program's format: `export mjcf SCENE`.
    ///
    /// MJCF is MuJoCo's: the model `benches/peers/` steps beside haptloop.
    Export(export::ExportArgs),
    /// Validate a scene file (or built-in name) and print what it compiles to.
    ///
    /// Errors name the file, line and column and what was expected; the exit
    /// status is 1 when the scene is invalid. Then a preflight tries what
    /// `run` will meet (the assembly, the hand's path against the device's
    /// workspace, a short deterministic trial: failed ticks, forces above the
    /// device's peak or continuous rating) and prints each finding at the
    /// field to change; the exit status is 3 when it found any.
    Check {
        /// A scene file path or a built-in scene name.
        scene: String,
        /// Length of the preflight's deterministic trial of the session, s,
        /// (0, 86400].
        #[arg(long, default_value_t = check::DEFAULT_TRIAL_SECONDS, value_parser = values::seconds)]
        seconds: f64,
    },
    /// Place a body at a goal: pull to goal or solve for goal (Choi & Cremer §4.3).
    ///
    /// Assembles the scene's mechanism (its bodies and joints, the scene's
    /// fingers left out) with a goal on the body's origin, then moves the
    /// goal to --goal: in pull mode through intermediate goals every --step
    /// metres, in solve mode at once. A step at which Newton-KKT does not
    /// converge within --max-iterations is split in halves (subgoal
    /// subdivision). Writes the scene with its bodies at the placed
    /// configuration and reports Newton iterations per step; the exit
    /// status is 3 when the goal was not reached (the file then holds the
    /// last converged subgoal).
    Place(place::PlaceArgs),
}

/// Parses the command line and runs the chosen command.
pub fn run() -> Result<ExitCode> {
    let cli = Cli::parse();
    let rt = match &cli.command {
        Some(Command::Run(a)) => Some(&a.rt),
        Some(Command::Probe(a)) => Some(&a.rt),
        _ => None,
    };
    if let Some(Err(msg)) = rt.map(rt_args::RtArgs::check) {
        Cli::command()
            .error(clap::error::ErrorKind::InvalidValue, msg)
            .exit();
    }
    let stop = signals::install()?;
    match cli.command {
        Some(Command::Probe(args)) => probe::run(&args, &stop),
        Some(Command::Scenes) => scenes::run(),
        Some(Command::Check { scene, seconds }) => check::run(&scene, seconds, &stop),
        Some(Command::Bench(args)) => bench::run(&args, &stop),
        Some(Command::Export(args)) => export::run(&args),
        Some(Command::Run(args)) => run::run(&args, &stop),
        Some(Command::Sweep(args)) => sweep::run(&args, &stop),
        Some(Command::Place(args)) => place::run(&args),
        Some(Command::View(args)) => view::run(&args),
        // The main job: the default scene on a simulated PHANToM, with a report.
        None => run::run(&run::RunArgs::default(), &stop),
    }
}

/// Prints a usage error about a flag (`haptloop: error: …`) and gives the
/// usage-error exit status, 2.
pub(crate) fn usage_error(message: &str) -> ExitCode {
    eprintln!("haptloop: error: {message}");
    ExitCode::from(2)
}
