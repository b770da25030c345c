//! The real-time thread flags `run` and `probe` share.

use clap::Args;
use haptloop_rt::thread::{CoreChoice, ThreadConfig};
use std::time::Duration;

/// How the fast thread asks the OS for real-time service. What the OS
/// grants is read back and reported; a refused priority or memory lock never
/// stops a run. An explicit `--core` this process cannot use is a usage error
/// caught before anything runs (the run would otherwise be on a core the user
/// did not ask for).
#[derive(Debug, Clone, Args)]
pub struct RtArgs {
    /// Spin window before each deadline, µs (0: sleep straight to the
    /// deadline). 50–100 µs removes most wake-up jitter at that much CPU per
    /// period.
    #[arg(long, default_value_t = 0)]
    pub spin_us: u64,
    /// Core to pin the real-time thread to (default: the last core this process
    /// may use).
    #[arg(long)]
    pub core: Option<usize>,
    /// SCHED_FIFO priority 1–99; 0 stays SCHED_OTHER.
    #[arg(long, default_value_t = 80, value_parser = clap::value_parser!(u8).range(0..=99))]
    pub priority: u8,
    /// Do not request mlockall.
    #[arg(long)]
    pub no_mlock: bool,
}

impl Default for RtArgs {
    fn default() -> Self {
        RtArgs {
            spin_us: 0,
            core: None,
            priority: 80,
            no_mlock: false,
        }
    }
}

impl RtArgs {
    /// The spin window.
    pub fn spin(&self) -> Duration {
        Duration::from_micros(self.spin_us)
    }

    /// Checks what can be checked before a run: an explicit core must be one
    /// this process may use.
    pub fn check(&self) -> Result<(), String> {
        match self.core {
            Some(c) => {
                let available = haptloop_rt::thread::available_cores();
                if available.contains(&c) {
                    Ok(())
                } else {
                    Err(format!(
                        "--core {c}: not available to this process (available: {available:?})"
                    ))
                }
            }
            None => Ok(()),
        }
    }

    /// The spin window must be shorter than the period at `rate_hz` (a
    /// usage error naming `--spin-us` otherwise).
    pub fn check_spin(&self, rate_hz: u32) -> Result<(), String> {
        let period_ns = 1_000_000_000 / u64::from(rate_hz.max(1));
        if self.spin_us.saturating_mul(1000) >= period_ns {
            return Err(format!(
                "--spin-us {}: the spin window must be shorter than the period, {} µs at {rate_hz} Hz",
                self.spin_us,
                period_ns as f64 / 1e3
            ));
        }
        Ok(())
    }

    /// The thread requests these flags make (the rest at their defaults).
    pub fn thread(&self) -> ThreadConfig {
        ThreadConfig {
            core: self.core.map_or(CoreChoice::Last, CoreChoice::Id),
            fifo_priority: (self.priority > 0).then_some(self.priority),
            lock_memory: !self.no_mlock,
            ..ThreadConfig::default()
        }
    }
}
