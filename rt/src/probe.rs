//! The latency probe users run first: the scheduler with a synthetic tick load,
//! alternating in one-second blocks with the bare reference loop on the same
//! core at the same priority, so machine drift hits both alike.

use crate::clock::{Clock, MonotonicClock, Nanos};
use crate::hist::{LatencyHistogram, Summary};
use crate::reference::BareLoop;
use crate::schedule::{
    LoopError, LoopHistograms, LoopReport, MissCounts, Periodic, RunLimit, ScheduleConfig,
    StopFlag, Tick, TickBody, TickStatus,
};
use crate::thread::{CoreChoice, Granted, ThreadConfig, ThreadUsage, spawn_rt};
use serde::{Deserialize, Serialize};
use std::time::Duration;

/// What to probe.
#[derive(Debug, Clone)]
pub struct ProbeConfig {
    /// Loop rate, Hz.
    pub rate_hz: u32,
    /// Time for the scheduler; the reference loop gets the same again.
    pub duration: Duration,
    /// Spin window before each deadline.
    pub spin: Duration,
    /// Core to pin both loops to.
    pub core: CoreChoice,
    /// `SCHED_FIFO` priority for both loops (`None`: `SCHED_OTHER`).
    pub fifo_priority: Option<u8>,
    /// Request `mlockall`.
    pub lock_memory: bool,
    /// Synthetic compute per tick (calibrated arithmetic, not a sleep).
    pub load: Duration,
    /// Alternation block length.
    pub block: Duration,
}

impl Default for ProbeConfig {
    fn default() -> Self {
        ProbeConfig {
            rate_hz: 1000,
            duration: Duration::from_secs(5),
            spin: Duration::ZERO,
            core: CoreChoice::Last,
            fifo_priority: Some(80),
            lock_memory: true,
            load: Duration::from_micros(10),
            block: Duration::from_secs(1),
        }
    }
}

/// Percentiles as the probe's JSON spells them, in ns.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Percentiles {
    /// Median.
    pub p50: u64,
    /// 99th percentile.
    pub p99: u64,
    /// 99.9th percentile.
    pub p999: u64,
    /// 99.99th percentile.
    pub p9999: u64,
    /// Exact maximum.
    pub max: u64,
}

impl From<Summary> for Percentiles {
    fn from(s: Summary) -> Self {
        Percentiles {
            p50: s.p50,
            p99: s.p99,
            p999: s.p999,
            p9999: s.p9999,
            max: s.max,
        }
    }
}

/// The bare reference loop's figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceReport {
    /// Wake-ups.
    pub ticks: u64,
    /// Late wake-ups plus skipped slots.
    pub missed: u64,
    /// Wake-up lateness.
    pub lateness_ns: Percentiles,
}

/// The probe's report (`haptloop probe --json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProbeReport {
    /// Loop rate, Hz.
    pub rate_hz: u32,
    /// Seconds each loop ran.
    pub seconds: f64,
    /// Spin window, µs.
    pub spin_us: u64,
    /// Synthetic load per tick, µs.
    pub load_us: u64,
    /// Scheduler ticks run.
    pub ticks: u64,
    /// Scheduler missed deadlines (late + overrun + skipped).
    pub missed: u64,
    /// Missed deadlines by kind.
    pub misses: MissCounts,
    /// What the OS granted the probe thread.
    pub granted: Granted,
    /// Scheduler wake-up lateness.
    pub lateness_ns: Percentiles,
    /// Tick compute time.
    pub compute_ns: Percentiles,
    /// Start-to-start period.
    pub period_ns: Percentiles,
    /// The bare reference loop over the same total time.
    pub reference: ReferenceReport,
    /// Scheduler lateness p99.9 divided by the reference's (≤ 1.1: the
    /// scheduler adds no measurable jitter). `None` if the reference p99.9 is 0.
    pub ratio_p999: Option<f64>,
    /// Page faults and context switches on the probe thread during both loops.
    pub usage: ThreadUsage,
}

/// The probe's report plus the histograms behind it.
pub struct ProbeOutcome {
    /// Summary figures.
    pub report: ProbeReport,
    /// Scheduler histograms.
    pub scheduler: LoopHistograms,
    /// Reference-loop lateness histogram.
    pub reference: LatencyHistogram,
}

/// Fixed arithmetic work, calibrated once to take about the requested time.
struct SyntheticLoad {
    buf: Vec<f64>,
    reps: u32,
}

impl SyntheticLoad {
    fn work(&mut self) {
        for _ in 0..self.reps {
            for x in self.buf.iter_mut() {
                *x = x.mul_add(0.999_999, 1e-6);
            }
        }
        std::hint::black_box(&self.buf);
    }

    fn calibrated(target: Duration, clock: &MonotonicClock) -> Self {
        let mut load = SyntheticLoad {
            buf: vec![1.0; 256],
            reps: 64,
        };
        let t0 = clock.now();
        for _ in 0..50 {
            load.work();
        }
        let per_rep = ((clock.now() - t0).0 as f64 / (50.0 * 64.0)).max(1.0);
        load.reps = (Nanos::from_duration(target).0 as f64 / per_rep).round() as u32;
        load
    }
}

impl TickBody for SyntheticLoad {
    type Fault = ();
    fn tick(&mut self, _tick: &Tick) -> TickStatus<()> {
        self.work();
        TickStatus::Ok
    }
}

/// Runs the probe on one real-time thread and returns its report.
pub fn run_probe(config: &ProbeConfig, stop: &StopFlag) -> Result<ProbeOutcome, LoopError> {
    let schedule = ScheduleConfig {
        rate_hz: config.rate_hz,
        spin: config.spin,
        thread: ThreadConfig {
            name: "haptloop-probe".into(),
            core: config.core,
            fifo_priority: config.fifo_priority,
            lock_memory: config.lock_memory,
            ..ThreadConfig::default()
        },
        ..ScheduleConfig::default()
    };
    let clock = MonotonicClock::new();
    let (mut periodic, _intervals) = Periodic::new(&schedule, clock)?;
    let late_bound = Nanos(periodic.period().0 / 2);
    let mut reference = BareLoop::new(clock, periodic.period(), late_bound);
    let total = Nanos::from_duration(config.duration);
    let block = Nanos::from_duration(config.block.max(Duration::from_millis(10)));
    let (load, stop) = (config.load, stop.clone());
    let thread = spawn_rt(schedule.thread.clone(), move |_granted: &Granted| {
        let mut body = SyntheticLoad::calibrated(load, &clock);
        let before = ThreadUsage::now();
        let mut done = Nanos::ZERO;
        while done < total && !stop.is_requested() {
            let this = block.min(total - done);
            periodic.run(&mut body, RunLimit::duration(this.as_duration()), &stop);
            reference.run(this, &stop);
            done += this;
        }
        let usage = ThreadUsage::now().since(before);
        (
            periodic.report(),
            periodic.histograms().clone(),
            reference,
            usage,
            done,
        )
    })?;
    let granted = thread.granted.clone();
    let (report, hist, reference, usage, done) = thread.join().map_err(|_| LoopError::Panicked)?;
    Ok(build_outcome(
        config, granted, report, hist, reference, usage, done,
    ))
}

fn build_outcome(
    config: &ProbeConfig,
    granted: Granted,
    r: LoopReport,
    hist: LoopHistograms,
    reference: BareLoop<MonotonicClock>,
    usage: ThreadUsage,
    done: Nanos,
) -> ProbeOutcome {
    let ref_summary = reference.lateness().summary();
    let ratio_p999 =
        (ref_summary.p999 > 0).then(|| r.lateness_ns.p999 as f64 / ref_summary.p999 as f64);
    let report = ProbeReport {
        rate_hz: r.rate_hz,
        seconds: done.0 as f64 / 1e9,
        spin_us: r.spin_ns / 1000,
        load_us: u64::try_from(config.load.as_micros()).unwrap_or(u64::MAX),
        ticks: r.ticks,
        missed: r.misses.total(),
        misses: r.misses,
        granted,
        lateness_ns: r.lateness_ns.into(),
        compute_ns: r.compute_ns.into(),
        period_ns: r.period_ns.into(),
        reference: ReferenceReport {
            ticks: reference.ticks(),
            missed: reference.missed(),
            lateness_ns: ref_summary.into(),
        },
        ratio_p999,
        usage,
    };
    ProbeOutcome {
        report,
        scheduler: hist,
        reference: reference.lateness().clone(),
    }
}
