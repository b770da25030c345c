//! `haptloop bench SCENE`: the session tick of a scene on the mock clock
//! (deterministic inputs, no sleeping), timed per stage on the monotonic
//! clock (`session::timing`).

use super::output::{check_writable, write_atomic};
use super::solver_args::SolverArgs;
use crate::report::summary::{Stages, Summary};
use crate::scenes::resolve;
use crate::session::{self, Plan, SessionOptions, Stage};
use anyhow::{Result, bail};
use clap::Args;
use haptloop_rt::probe::Percentiles;
use haptloop_rt::schedule::StopFlag;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

/// Flags of `haptloop bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// A built-in scene (see `haptloop scenes`) or a scene file (TOML).
    pub scene: String,
    /// Ticks to run (1–10000000). The slow loop steps in lockstep every
    /// 5 ms of session time, as in `run --deterministic`.
    #[arg(long, default_value_t = 5000, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    pub ticks: u64,
    /// Write the figures as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// The solver flags, as for `run`.
    #[command(flatten)]
    pub solver: SolverArgs,
}

/// p50, p99, p99.9 and max of one figure, ns.
#[derive(Debug, Clone, Copy, Serialize)]
struct Quantiles {
    p50: u64,
    p99: u64,
    p999: u64,
    max: u64,
}

impl From<Percentiles> for Quantiles {
    fn from(p: Percentiles) -> Self {
        Quantiles {
            p50: p.p50,
            p99: p.p99,
            p999: p.p999,
            max: p.max,
        }
    }
}

#[derive(Debug, Clone, Serialize)]
struct Violation {
    /// Largest length-row violation of any tick, m.
    max: f64,
    /// RMS over ticks of the length rows' RMS, m.
    rms: f64,
    /// Largest angle-row violation of any tick, rad.
    max_rad: f64,
    /// The session report's verdict: what the figures are, or why there
    /// are none ("no joint rows", "all ticks failed"), never NaN in text.
    verdict: String,
}

/// What `--json` writes.
#[derive(Debug, Serialize)]
struct BenchJson {
    scene: String,
    ticks: u64,
    rate_hz: u32,
    iterations: u32,
    /// The Eq. 7 solver: `cholesky`, `matvec`, `matvec:N`, `tree`, `tree:N`,
    /// `multilevel`, `multilevel:N` or `cg:N`.
    force_solver: String,
    /// The update rule, `projected` or `gradient`.
    update: &'static str,
    /// The coordinates the tick ran in, and why (`Program::coordinates`).
    coordinates: String,
    /// Constraint gain K.
    gain: f64,
    /// The velocity filter's time constant, ms.
    velocity_filter_ms: f64,
    tick_ns: Quantiles,
    tick_without_device_ns: Quantiles,
    /// Mean of `tick_without_device_ns`.
    tick_without_device_mean_ns: f64,
    stages: BTreeMap<&'static str, Quantiles>,
    /// One slow-loop step (every 5 ms of session time), ns.
    slow_step_ns: Quantiles,
    slow_steps: u64,
    violation: Violation,
    solver_failures: u64,
}

/// The session options of a bench: `solver`'s flags at `rate` for
/// `seconds`, deterministic.
pub(super) fn bench_options(solver: &SolverArgs, rate: u32, seconds: f64) -> SessionOptions {
    let mut options = SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    };
    solver.apply(&mut options);
    options.rate_hz = Some(rate);
    options
}

/// Runs the bench and prints (and writes) its figures.
pub fn run(args: &BenchArgs, stop: &StopFlag) -> Result<ExitCode> {
    let scene = match resolve(&args.scene) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return Ok(ExitCode::from(1));
        }
    };
    if let Some(path) = &args.json {
        check_writable(path)?;
    }
    let rate = args
        .solver
        .rate
        .or(scene.compiled.settings.rate_hz)
        .unwrap_or(1000);
    let seconds = args.ticks as f64 / f64::from(rate);
    if seconds > 86_400.0 {
        bail!("--ticks {} at {rate} Hz is more than a day", args.ticks);
    }
    let options = bench_options(&args.solver, rate, seconds);
    let plan = Plan::new(&scene, &options)?;
    let plan_solver = plan.solver.force_solver;
    let (update, gain) = (plan.solver.update, plan.solver.gain);
    let velocity_filter_ms = plan.solver.velocity_filter.as_secs_f64() * 1e3;
    let outcome = session::run(&scene, plan, stop, &mut |_| {})?;
    let s = Summary::of(&outcome);
    let json = BenchJson {
        scene: s.scene.clone(),
        ticks: s.ticks,
        rate_hz: s.rate_hz,
        iterations: s.iterations,
        force_solver: plan_solver.label(),
        update: crate::report::sweep::rule(update),
        coordinates: outcome.coordinates.clone(),
        gain,
        velocity_filter_ms,
        tick_ns: s.stages_ns.tick.into(),
        tick_without_device_ns: s.stages_ns.tick_without_device.into(),
        tick_without_device_mean_ns: s.stages_ns.tick_without_device_mean,
        stages: Stage::ALL
            .iter()
            .map(|&st| (st.key(), s.stages_ns.get(st).into()))
            .collect(),
        slow_step_ns: s.slow_loop.step_ns.into(),
        slow_steps: outcome.slow.steps,
        violation: Violation {
            max: s.violation.max,
            rms: s.violation.rms,
            max_rad: s.violation.max_rad,
            verdict: s.violation.verdict.clone(),
        },
        solver_failures: s.safety.solver_failures,
    };
    super::emit(&render(&json, &s.stages_ns));
    if let Some(path) = &args.json {
        write_atomic(
            path,
            (serde_json::to_string_pretty(&json)? + "\n").as_bytes(),
        )?;
    }
    Ok(ExitCode::SUCCESS)
}

fn render(b: &BenchJson, stages: &Stages) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "haptloop bench {}: {} ticks at {} Hz on the mock clock, {} {} update iteration{} per tick, gain {}, velocity filter {} ms, {} force solver",
        b.scene,
        b.ticks,
        b.rate_hz,
        b.iterations,
        b.update,
        if b.iterations == 1 { "" } else { "s" },
        b.gain,
        b.velocity_filter_ms,
        b.force_solver
    );
    let _ = writeln!(out, "  coordinates: {}", b.coordinates);
    let _ = writeln!(
        out,
        "\n  {:<18} {:>9} {:>9} {:>9} {:>10}   (µs, monotonic clock)",
        "", "p50", "p99", "p99.9", "max"
    );
    let row = |out: &mut String, label: &str, q: Quantiles| {
        let us = |ns: u64| ns as f64 / 1e3;
        let _ = writeln!(
            out,
            "  {label:<18} {:>9.1} {:>9.1} {:>9.1} {:>10.1}",
            us(q.p50),
            us(q.p99),
            us(q.p999),
            us(q.max)
        );
    };
    row(&mut out, "tick", b.tick_ns);
    for st in Stage::ALL {
        row(
            &mut out,
            &format!("  {}", st.label()),
            stages.get(st).into(),
        );
    }
    row(&mut out, "tick w/o device", b.tick_without_device_ns);
    let _ = writeln!(
        out,
        "  (tick w/o device: mean {:.1} µs)",
        b.tick_without_device_mean_ns / 1e3
    );
    let _ = writeln!(
        out,
        "\nslow loop: {} steps (every 5 ms of session time), p50 {:.1} µs, max {:.1} µs a step",
        b.slow_steps,
        b.slow_step_ns.p50 as f64 / 1e3,
        b.slow_step_ns.max as f64 / 1e3
    );
    let v = &b.violation;
    if [v.max, v.max_rad, v.rms].iter().all(|x| x.is_finite()) {
        let _ = write!(
            out,
            "constraint violation: max {:.2e} m, {:.2e} rad; RMS {:.2e} m; solver failures: {}",
            v.max, v.max_rad, v.rms, b.solver_failures
        );
    } else {
        let _ = write!(
            out,
            "constraint violation: {}; solver failures: {}",
            v.verdict, b.solver_failures
        );
    }
    out
}
