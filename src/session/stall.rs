//! Injected host stalls for deterministic sessions (`run --deterministic
//! --stall SECONDS:PERIODS`): the mock clock jumps forward after a chosen
//! tick, exactly as if the host had stalled the fast thread, so the
//! scheduler counts the overrun, skips the grid slots it can no longer meet
//! and hands the next tick `PERIODS` periods after this one. What a real
//! stall does to the world and the motors can then be reproduced bit for
//! bit (BENCHMARKS.md, "Contact: missed ticks").

use anyhow::{Result, bail};
use haptloop_rt::clock::{MockClock, Nanos};
use std::time::Duration;

/// One injected stall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stall {
    /// Session time of the tick after which the host stalls, s.
    pub at_s: f64,
    /// Periods between that tick and the next one (≥ 2; 1 is no stall).
    pub periods: u64,
}

impl Stall {
    /// Parses `SECONDS:PERIODS`, e.g. `1.5:20`.
    pub fn parse(s: &str) -> Result<Stall> {
        Self::parse_flag("--stall", s)
    }

    /// Parses `SECONDS:PERIODS` given to `flag` (named in the errors).
    pub fn parse_flag(flag: &str, s: &str) -> Result<Stall> {
        let Some((at, n)) = s.split_once(':') else {
            bail!("{flag} `{s}`: expected SECONDS:PERIODS, e.g. 1.5:20");
        };
        let at_s: f64 = match at.trim().parse() {
            Ok(v) if f64::is_finite(v) && v >= 0.0 => v,
            _ => bail!("{flag} `{s}`: SECONDS must be a finite number ≥ 0, got `{at}`"),
        };
        let periods: u64 = match n.trim().parse() {
            Ok(v) if (2..=100_000).contains(&v) => v,
            _ => bail!("{flag} `{s}`: PERIODS must be an integer in 2–100000, got `{n}`"),
        };
        Ok(Stall { at_s, periods })
    }

    /// The grid slot of the tick after which it stalls, at `rate_hz`
    /// (slot k is due at (k + 1) periods).
    fn slot(&self, rate_hz: u32) -> u64 {
        ((self.at_s * f64::from(rate_hz)).round() as u64).saturating_sub(1)
    }
}

/// Plays a plan's stalls on the mock clock, in time order.
#[derive(Debug)]
pub(super) struct StallPlayer {
    clock: MockClock,
    period: Duration,
    /// (slot, periods), sorted by slot.
    due: Vec<(u64, u64)>,
    next: usize,
    /// The slow loop's stalls, (slot, periods), sorted by slot.
    slow_due: Vec<(u64, u64)>,
    slow_next: usize,
    /// No slow step before this slot.
    slow_until: u64,
}

impl StallPlayer {
    pub(super) fn new(
        stalls: &[Stall],
        slow: &[Stall],
        rate_hz: u32,
        period: Duration,
        clock: MockClock,
    ) -> Self {
        let slots = |v: &[Stall]| {
            let mut d: Vec<(u64, u64)> = v.iter().map(|s| (s.slot(rate_hz), s.periods)).collect();
            d.sort_unstable();
            d
        };
        StallPlayer {
            clock,
            period,
            due: slots(stalls),
            next: 0,
            slow_due: slots(slow),
            slow_next: 0,
            slow_until: 0,
        }
    }

    /// True while the slow loop is stalled at grid slot `index` (`--slow-stall`):
    /// it takes no step, so the fast loop runs on witness tables and programs
    /// that grow old, as when the slow thread is descheduled or a contact
    /// program takes long to build.
    pub(super) fn slow_stalled(&mut self, index: u64) -> bool {
        // From the tick after the stall's slot on, `periods` ticks.
        while let Some(&(slot, periods)) = self.slow_due.get(self.slow_next) {
            if slot >= index {
                break;
            }
            self.slow_next += 1;
            self.slow_until = self.slow_until.max(slot + 1 + periods);
        }
        index < self.slow_until
    }

    /// After the tick of grid slot `index`: if a stall is due, the clock
    /// jumps so that the next tick comes `periods` periods after this one.
    /// (The scheduler starts a mock tick at its deadline, so the jump is
    /// the stall's whole length.)
    ///
    /// # Real-time
    /// No allocation.
    pub(super) fn after_tick(&mut self, index: u64) {
        // A stall whose slot an earlier stall skipped comes on the first
        // tick after it.
        if let Some(&(slot, periods)) = self.due.get(self.next)
            && slot <= index
        {
            self.next += 1;
            let ns = self.period.as_nanos() as u64;
            self.clock.advance(Nanos(ns.saturating_mul(periods)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Stall;

    #[test]
    fn stalls_parse_and_say_what_is_wrong() {
        let s = Stall::parse("1.5:20").unwrap();
        assert_eq!((s.at_s, s.periods), (1.5, 20));
        assert_eq!(s.slot(1000), 1499);
        for bad in ["1.5", "x:2", "1:1", "1:-3", "-1:5", "nan:5", "1:100001"] {
            let e = Stall::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--stall"), "{bad}: {e}");
        }
    }
}
