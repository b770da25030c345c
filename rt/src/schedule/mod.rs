//! The hard-rate periodic scheduler.
//!
//! A [`Periodic`] loop wakes on an absolute grid of deadlines
//! (`origin + index × period`, `clock_nanosleep(TIMER_ABSTIME)`, optionally
//! sleeping to `deadline − spin` and spinning the rest), runs one
//! [`TickBody::tick`], and records lateness, compute time and period in HDR
//! histograms. It never sleeps for a relative period, so delays never
//! accumulate.
//!
//! Misses are counted, never hidden: a tick that starts more than the late
//! bound after its deadline is *late*; one whose compute exceeds the period is
//! an *overrun*; grid slots that can no longer start in time are *skipped*
//! (default [`OverrunPolicy::Skip`]: realign to the next slot on the original
//! grid, no burst) or partly run back-to-back ([`OverrunPolicy::CatchUp`],
//! bounded). A fault returned by the body, or a streak of consecutive misses,
//! calls the body's safety hook.
//!
//! ```text
//!   deadline k      deadline k+1     deadline k+2 …
//!   |--lateness--|--compute--|         (start ≥ deadline; end − start = compute)
//!   sleep ──────►│ tick body │ record │ sleep ──────►│ …
//! ```

mod body;
mod config;
mod intervals;
mod periodic;
mod spawn;

pub use body::{MissCounts, RunLimit, SafetyEvent, StopFlag, Tick, TickBody, TickStatus};
pub use config::{ConfigError, MAX_RATE_HZ, MIN_RATE_HZ, OverrunPolicy, ScheduleConfig};
pub use intervals::{IntervalReceiver, IntervalSnapshot, IntervalStats};
pub use periodic::{LoopHistograms, LoopReport, Periodic, RunEnd};
pub use spawn::{LoopError, LoopHandle, LoopOutcome, spawn_loop};
