//! Scheduler configuration: rate, spin window, overrun policy, miss bounds.

use crate::clock::Nanos;
use crate::thread::ThreadConfig;
use std::time::Duration;

/// Lowest supported loop rate, Hz.
pub const MIN_RATE_HZ: u32 = 100;
/// Highest supported loop rate, Hz.
pub const MAX_RATE_HZ: u32 = 20_000;

/// What to do with grid slots whose deadline passed while the loop was busy or
/// stalled. Either way every such slot is counted; nothing is hidden.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OverrunPolicy {
    /// Drop the missed slots and realign to the next slot on the original grid
    /// (default). Never runs ticks back-to-back: no burst after a stall.
    #[default]
    Skip,
    /// Run up to `max_burst` missed slots back-to-back (for bodies that integrate
    /// with a fixed step and want every step), then drop the rest and realign.
    /// Choosing this accepts a burst of at most `max_burst` ticks after a stall.
    CatchUp {
        /// Most missed slots run back-to-back after one overrun.
        max_burst: u32,
    },
}

/// Everything the periodic scheduler needs to know.
#[derive(Debug, Clone)]
pub struct ScheduleConfig {
    /// Loop rate in Hz, 100 … 20 000.
    pub rate_hz: u32,
    /// Busy-wait window before each deadline: sleep until `deadline − spin`,
    /// then spin on the clock. Zero (default) sleeps straight to the deadline.
    /// 50–100 µs removes most wake-up jitter at the cost of that much CPU per
    /// period (8 % at 1 kHz with 100 µs).
    pub spin: Duration,
    /// What to do with missed slots.
    pub overrun: OverrunPolicy,
    /// A tick starting later than this after its deadline is a *late* miss.
    /// `None` (default) means half a period: a force computed that late is
    /// already half a period stale.
    pub late_bound: Option<Duration>,
    /// After this many consecutive missed slots the body's safety hook runs
    /// (once per streak). Default 8: 8 ms of stale force at 1 kHz.
    pub miss_streak_limit: u32,
    /// Length of the interval snapshots sent to the reporter. Default 1 s.
    pub interval: Duration,
    /// OS-level requests for the fast thread (pinning, FIFO, mlock …).
    pub thread: ThreadConfig,
}

impl Default for ScheduleConfig {
    fn default() -> Self {
        ScheduleConfig {
            rate_hz: 1000,
            spin: Duration::ZERO,
            overrun: OverrunPolicy::Skip,
            late_bound: None,
            miss_streak_limit: 8,
            interval: Duration::from_secs(1),
            thread: ThreadConfig::default(),
        }
    }
}

/// A configuration the scheduler refuses.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ConfigError {
    /// Rate outside 100 … 20 000 Hz.
    #[error("rate {0} Hz is outside the supported {MIN_RATE_HZ}–{MAX_RATE_HZ} Hz")]
    Rate(u32),
    /// Spin window not shorter than the period.
    #[error("spin window {spin_us} µs must be shorter than the period {period_us} µs")]
    Spin {
        /// Requested spin, µs.
        spin_us: u64,
        /// Period, µs.
        period_us: u64,
    },
    /// A zero miss-streak limit would fire the safety hook on every tick.
    #[error("miss streak limit must be at least 1")]
    StreakLimit,
    /// Interval snapshots shorter than one period.
    #[error("snapshot interval must be at least one period")]
    Interval,
}

/// A validated configuration with derived nanosecond figures.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Timing {
    pub period: Nanos,
    pub spin: Nanos,
    pub late_bound: Nanos,
    pub interval: Nanos,
}

impl ScheduleConfig {
    /// The loop period.
    pub fn period(&self) -> Duration {
        Duration::from_nanos(1_000_000_000 / u64::from(self.rate_hz.max(1)))
    }

    pub(crate) fn validate(&self) -> Result<Timing, ConfigError> {
        if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&self.rate_hz) {
            return Err(ConfigError::Rate(self.rate_hz));
        }
        let period = Nanos::from_duration(self.period());
        let spin = Nanos::from_duration(self.spin);
        if spin >= period {
            return Err(ConfigError::Spin {
                spin_us: spin.0 / 1000,
                period_us: period.0 / 1000,
            });
        }
        if self.miss_streak_limit == 0 {
            return Err(ConfigError::StreakLimit);
        }
        let interval = Nanos::from_duration(self.interval);
        if interval < period {
            return Err(ConfigError::Interval);
        }
        let late_bound = self
            .late_bound
            .map(Nanos::from_duration)
            .unwrap_or(Nanos(period.0 / 2));
        Ok(Timing {
            period,
            spin,
            late_bound,
            interval,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_out_of_range_settings() {
        let bad_rate = ScheduleConfig {
            rate_hz: 50,
            ..Default::default()
        };
        assert_eq!(bad_rate.validate().unwrap_err(), ConfigError::Rate(50));
        let bad_spin = ScheduleConfig {
            rate_hz: 10_000,
            spin: Duration::from_micros(100),
            ..Default::default()
        };
        assert!(matches!(
            bad_spin.validate().unwrap_err(),
            ConfigError::Spin {
                spin_us: 100,
                period_us: 100
            }
        ));
        let t = ScheduleConfig {
            rate_hz: 20_000,
            ..Default::default()
        }
        .validate()
        .unwrap();
        assert_eq!(t.period, Nanos(50_000));
        assert_eq!(t.late_bound, Nanos(25_000));
    }
}
