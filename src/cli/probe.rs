//! `haptloop probe`.

use super::output::{check_writable, write_atomic};
use super::rt_args::RtArgs;
use super::values;
use crate::report;
use anyhow::{Context, Result, bail};
use clap::Args;
use haptloop_rt::probe::{ProbeConfig, run_probe};
use haptloop_rt::schedule::{MAX_RATE_HZ, MIN_RATE_HZ, StopFlag};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// Flags of `haptloop probe`.
#[derive(Debug, Args)]
pub struct ProbeArgs {
    /// Loop rate in Hz (100–20000).
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u32).range(i64::from(MIN_RATE_HZ)..=i64::from(MAX_RATE_HZ)))]
    pub rate: u32,
    /// Seconds for the scheduler, (0, 86400]; the reference loop runs as long
    /// again.
    #[arg(long, default_value_t = 5.0, value_parser = values::seconds)]
    pub seconds: f64,
    /// Real-time thread requests (both loops).
    #[command(flatten)]
    pub rt: RtArgs,
    /// Synthetic compute per tick, µs (calibrated arithmetic, not a sleep).
    #[arg(long, default_value_t = 10)]
    pub load_us: u64,
    /// Write the report as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write the histograms as HdrHistogram percentile distributions (.hgrm,
    /// µs) into DIR.
    #[arg(long, value_name = "DIR")]
    pub hgrm: Option<PathBuf>,
}

impl Default for ProbeArgs {
    fn default() -> Self {
        ProbeArgs {
            rate: 1000,
            seconds: 5.0,
            rt: RtArgs::default(),
            load_us: 10,
            json: None,
            hgrm: None,
        }
    }
}

impl ProbeArgs {
    fn to_config(&self) -> Result<ProbeConfig> {
        if !(self.seconds.is_finite() && self.seconds > 0.0 && self.seconds <= 86_400.0) {
            bail!(
                "--seconds must be a number in (0, 86400], got {}",
                self.seconds
            );
        }
        let thread = self.rt.thread();
        Ok(ProbeConfig {
            rate_hz: self.rate,
            duration: Duration::from_secs_f64(self.seconds),
            spin: self.rt.spin(),
            core: thread.core,
            fifo_priority: thread.fifo_priority,
            lock_memory: thread.lock_memory,
            load: Duration::from_micros(self.load_us),
            ..ProbeConfig::default()
        })
    }
}

/// Runs the probe and prints (and optionally writes) its report.
pub fn run(args: &ProbeArgs, stop: &StopFlag) -> Result<ExitCode> {
    if let Err(msg) = args.rt.check_spin(args.rate) {
        return Ok(super::usage_error(&msg));
    }
    let config = args.to_config()?;
    // Fail now, not after the whole probe, if the outputs cannot be written.
    if let Some(path) = &args.json {
        check_writable(path)?;
    }
    if let Some(dir) = &args.hgrm {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        check_writable(&dir.join("lateness.hgrm"))?;
    }
    eprintln!("{}", report::probe::banner(&config));
    let outcome = run_probe(&config, stop).context("probe failed")?;
    super::emit(&report::probe::render(&outcome.report));
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&outcome.report)?;
        write_atomic(path, (text + "\n").as_bytes())?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(dir) = &args.hgrm {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let files = [
            ("lateness.hgrm", &outcome.scheduler.lateness),
            ("compute.hgrm", &outcome.scheduler.compute),
            ("period.hgrm", &outcome.scheduler.period),
            ("reference-lateness.hgrm", &outcome.reference),
        ];
        for (name, hist) in files {
            let path = dir.join(name);
            write_atomic(&path, hist.percentile_distribution(1000.0).as_bytes())?;
        }
        eprintln!("wrote 4 percentile distributions (µs) to {}", dir.display());
    }
    Ok(ExitCode::SUCCESS)
}
