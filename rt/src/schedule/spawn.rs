//! Running a [`Periodic`] loop on its own pinned real-time thread.

use super::body::{RunLimit, StopFlag, TickBody};
use super::config::{ConfigError, ScheduleConfig};
use super::intervals::IntervalReceiver;
use super::periodic::{LoopHistograms, LoopReport, Periodic, RunEnd};
use crate::clock::Clock;
use crate::thread::{Granted, RtThread, SpawnError, ThreadUsage, spawn_rt};

/// Why a loop could not be started.
#[derive(Debug, thiserror::Error)]
pub enum LoopError {
    /// The schedule configuration is invalid.
    #[error("invalid schedule")]
    Config(#[from] ConfigError),
    /// The real-time thread could not be started.
    #[error(transparent)]
    Spawn(#[from] SpawnError),
    /// The loop thread panicked (a bug in a tick body).
    #[error("the fast loop thread panicked")]
    Panicked,
}

/// What a finished loop hands back.
pub struct LoopOutcome<B> {
    /// The tick body, returned to the caller's thread.
    pub body: B,
    /// Counts and percentiles.
    pub report: LoopReport,
    /// The full histograms.
    pub histograms: LoopHistograms,
    /// What the OS granted the thread.
    pub granted: Granted,
    /// Page faults and context switches during the loop (after setup).
    pub usage: ThreadUsage,
    /// Why the loop ended.
    pub end: RunEnd,
}

/// A loop running on its own thread.
pub struct LoopHandle<B> {
    thread: RtThread<LoopOutcome<B>>,
    /// Interval snapshots for a reporter thread to poll.
    pub intervals: IntervalReceiver,
}

impl<B> LoopHandle<B> {
    /// What the OS granted the loop's thread.
    pub fn granted(&self) -> &Granted {
        &self.thread.granted
    }

    /// True once the loop has ended (never blocks): a reporter polls this.
    pub fn is_finished(&self) -> bool {
        self.thread.is_finished()
    }

    /// Waits for the loop to end (set the [`StopFlag`] or let the limit expire).
    pub fn join(self) -> Result<LoopOutcome<B>, LoopError> {
        self.thread.join().map_err(|_| LoopError::Panicked)
    }
}

/// Builds a [`Periodic`] loop here (allocating its histograms off the fast
/// thread), starts a real-time thread prepared per `config.thread`, and runs
/// `body` on it until `stop` is requested or `limit` is reached; then calls
/// `body.on_stop()` on that thread.
pub fn spawn_loop<B, C>(
    config: &ScheduleConfig,
    clock: C,
    mut body: B,
    stop: StopFlag,
    limit: RunLimit,
) -> Result<LoopHandle<B>, LoopError>
where
    B: TickBody + Send + 'static,
    C: Clock + 'static,
{
    let (mut periodic, intervals) = Periodic::new(config, clock)?;
    let thread = spawn_rt(config.thread.clone(), move |granted: &Granted| {
        let before = ThreadUsage::now();
        let end = periodic.run(&mut body, limit, &stop);
        let usage = ThreadUsage::now().since(before);
        body.on_stop();
        LoopOutcome {
            report: periodic.report(),
            histograms: periodic.histograms().clone(),
            granted: granted.clone(),
            usage,
            end,
            body,
        }
    })?;
    Ok(LoopHandle { thread, intervals })
}
