//! `haptloop sweep`: the speed/accuracy trade of a scene over a grid of the
//! fast loop's knobs (see `crate::sweep`).

use super::output::{RunDir, produce_atomic, write_atomic};
use super::values;
use crate::report::sweep as report;
use crate::scenes::{Scene, resolve};
use crate::session::{Plan, SessionOptions};
use crate::sweep::{self, Grid, Options, Progress};
use anyhow::Result;
use clap::Args;
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::UpdateRule;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

/// Most points a sweep may have (the product of the lists).
pub const MAX_POINTS: usize = 10_000;

/// Flags of `haptloop sweep`. Every list is comma-separated; an empty
/// list, an empty item or a value out of range is a usage error (status 2).
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// A built-in scene (see `haptloop scenes`) or a scene file (TOML).
    pub scene: String,
    /// Update iterations per tick (each 1–10000).
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16", value_parser = values::iterations)]
    pub iterations: Vec<u32>,
    /// Update rules: `projected`, `gradient`.
    #[arg(long, value_delimiter = ',', default_value = "gradient,projected", value_parser = values::update_rule)]
    pub update: Vec<UpdateRule>,
    /// Eq. 7 solvers: `cholesky`, `matvec` (the matvec-only tick, each
    /// conjugate-gradient solve to its tolerance within a cap of 64
    /// iterations), `matvec:N`, `tree` (conjugate gradients preconditioned
    /// by a spanning tree, no full factor; cap 500), `tree:N`, `multilevel`
    /// (preconditioned by an aggregation V-cycle; cap 500), `multilevel:N`,
    /// `cg:N`
    /// (Jacobi-preconditioned, gradient update only).
    #[arg(long, value_delimiter = ',', default_value = "cholesky", value_parser = values::force_solver)]
    pub force_solver: Vec<haptloop_solver::ForceSolver>,
    /// Constraint gains K (each finite, > 0). Default: the scene's.
    #[arg(long, value_delimiter = ',', value_parser = values::positive)]
    pub gain: Vec<f64>,
    /// Loop rates, Hz (each 100–20000).
    #[arg(long, value_delimiter = ',', default_value = "250,500,1000,4000,10000", value_parser = values::rate)]
    pub rate: Vec<u32>,
    /// Velocity filter time constants, ms (each 0–1000). Default: the scene's.
    #[arg(long, value_name = "MS", value_delimiter = ',', value_parser = values::filter_ms)]
    pub velocity_filter_ms: Vec<f64>,
    /// Session length per point, seconds, (0, 86400].
    #[arg(long, default_value_t = 2.0, value_parser = values::seconds)]
    pub seconds: f64,
    /// Compare one tick every MS milliseconds with the converged reference
    /// (0: every tick), 0–10000.
    #[arg(long, value_name = "MS", default_value_t = 10.0, value_parser = values::reference_ms)]
    pub reference_ms: f64,
    /// Largest force error a recommended point may have, as a fraction of
    /// the largest reference force, (0, 1].
    #[arg(long, default_value_t = 0.01, value_parser = values::fraction)]
    pub force_tolerance: f64,
    /// Threads for the accuracy runs (default: the cores this process may
    /// use); timing always runs alone afterwards, on one thread.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub threads: Option<u32>,
    /// Output directory (default `runs/sweep-<scene>-<UTC time>/`), new or
    /// empty: sweep.csv, sweep.json, front.svg.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write no files; print the table only.
    #[arg(long, conflicts_with = "out")]
    pub no_files: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// The first of each repeated item, in order (a repeat, anywhere in a
/// list, would repeat grid points).
fn first_of_each<T: PartialEq + Clone>(v: &[T]) -> Vec<T> {
    let mut out: Vec<T> = Vec::with_capacity(v.len());
    for x in v {
        if !out.contains(x) {
            out.push(x.clone());
        }
    }
    out
}

/// Runs the sweep, prints its table and writes its files.
pub fn run(args: &SweepArgs, stop: &StopFlag) -> Result<ExitCode> {
    let scene = match resolve(&args.scene) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return Ok(ExitCode::from(1));
        }
    };
    let grid = grid(args, &scene)?;
    if let Some(why) = refused(args, &grid) {
        eprintln!("haptloop: error: {why}");
        return Ok(ExitCode::from(2));
    }
    let n = grid.points().len();
    let run_dir = match (&args.out, args.no_files) {
        (_, true) => None,
        (Some(d), false) => Some(RunDir::claim(d)?),
        (None, false) => Some(RunDir::claim_fresh(&Path::new("runs").join(format!(
            "sweep-{}-{}",
            scene.compiled.name,
            super::output::utc_stamp()
        )))?),
    };
    let threads = args.threads.map_or_else(
        || haptloop_rt::thread::available_cores().len().max(1),
        |t| t as usize,
    );
    let options = Options {
        seconds: args.seconds,
        reference_every: Duration::from_secs_f64(args.reference_ms / 1000.0),
        threads,
        force_tolerance: args.force_tolerance,
    };
    eprintln!(
        "haptloop: sweeping `{}` over {n} points ({} s each, {threads} thread{} for accuracy, then timing alone); Ctrl-C stops",
        scene.compiled.name,
        args.seconds,
        if threads == 1 { "" } else { "s" }
    );
    let bar = (!args.quiet && std::io::stderr().is_terminal()).then(|| progress_bar(n));
    let progress = |p: Progress| {
        if let Some(b) = &bar {
            b.set_message(match p {
                Progress::Accuracy(_) => "(accuracy, in parallel)",
                Progress::Timing(_) => "(timing, alone)",
            });
            b.inc(1);
        }
    };
    let result = sweep::run(&scene, &grid, &options, stop, &progress)?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    super::emit(&report::table(&result));
    if let Some(dir) = run_dir {
        write_files(dir, &result)?;
    }
    if result.stopped_early {
        eprintln!(
            "haptloop: the sweep was stopped by a signal (exit status {})",
            super::signals::EXIT_SIGNAL
        );
        return Ok(ExitCode::from(super::signals::EXIT_SIGNAL));
    }
    Ok(ExitCode::SUCCESS)
}

/// The grid of the flags' lists, the scene's own gain and filter where
/// those lists are not given.
fn grid(args: &SweepArgs, scene: &Scene) -> Result<Grid> {
    let base = Plan::new(
        scene,
        &SessionOptions {
            seconds: args.seconds,
            deterministic: true,
            ..SessionOptions::default()
        },
    )?;
    let gain = if args.gain.is_empty() {
        vec![base.solver.gain]
    } else {
        first_of_each(&args.gain)
    };
    let velocity_filter_ms = if args.velocity_filter_ms.is_empty() {
        vec![base.solver.velocity_filter.as_secs_f64() * 1e3]
    } else {
        first_of_each(&args.velocity_filter_ms)
    };
    let iterations = first_of_each(&args.iterations);
    let rate_hz = first_of_each(&args.rate);
    let update = first_of_each(&args.update);
    let force_solver = first_of_each(&args.force_solver);
    Ok(Grid {
        iterations,
        update,
        force_solver,
        gain,
        rate_hz,
        velocity_filter_ms,
    })
}

/// Why the grid cannot be swept (a usage error), if it cannot: every
/// session must have a tick to measure, and the grid at most `MAX_POINTS`
/// points.
fn refused(args: &SweepArgs, grid: &Grid) -> Option<String> {
    if let Some(&slowest) = grid.rate_hz.iter().min()
        && (args.seconds * f64::from(slowest)).round() < 1.0
    {
        return Some(format!(
            "--seconds {} gives no tick at {slowest} Hz; at least {} s",
            args.seconds,
            1.0 / f64::from(slowest)
        ));
    }
    let n = grid.points().len();
    if n > MAX_POINTS {
        return Some(format!(
            "the grid has {n} points (the product of the lists); at most {MAX_POINTS}"
        ));
    }
    None
}

/// The progress bar of the 2 `n` runs (accuracy, then timing).
fn progress_bar(n: usize) -> ProgressBar {
    let b = ProgressBar::new(2 * n as u64);
    b.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} runs {msg} [{elapsed} < {eta}]")
            .expect("valid template"),
    );
    b
}

/// sweep.json, sweep.csv and front.svg in `dir`.
fn write_files(dir: RunDir, result: &sweep::Sweep) -> Result<()> {
    let d = dir.path();
    write_atomic(&d.join("sweep.json"), report::json(result)?.as_bytes())?;
    write_atomic(&d.join("sweep.csv"), report::csv(result).as_bytes())?;
    produce_atomic(&d.join("front.svg"), |p| report::front_svg(p, result))?;
    super::emit(&format!(
        "wrote {}/: sweep.json, sweep.csv, front.svg",
        d.display()
    ));
    dir.release()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::SweepArgs;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: SweepArgs,
    }

    #[test]
    fn lists_parse_and_bad_items_name_their_flag() {
        let ok = Cli::try_parse_from(["x", "four-bar", "--iterations", "1,4", "--rate", "1000"])
            .unwrap();
        assert_eq!(ok.args.iterations, [1, 4]);
        assert_eq!(ok.args.rate, [1000]);
        assert_eq!(ok.args.update.len(), 2);
        for bad in [
            &["--iterations", ""][..],
            &["--iterations", "1,,2"],
            &["--iterations", "0"],
            &["--rate", "50"],
            &["--rate", "1000,30000"],
            &["--update", "newton"],
            &["--gain", "0"],
            &["--velocity-filter-ms", "nan"],
            &["--seconds", "0"],
            &["--force-tolerance", "2"],
        ] {
            let e = Cli::try_parse_from(["x", "four-bar"].iter().chain(bad.iter()))
                .err()
                .unwrap_or_else(|| panic!("{bad:?} accepted"));
            assert_eq!(e.exit_code(), 2, "{bad:?}");
            assert!(e.to_string().contains(bad[0]), "{bad:?}: {e}");
        }
    }
}
