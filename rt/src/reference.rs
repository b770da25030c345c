//! The bare reference loop: plain absolute `clock_nanosleep` on the same grid,
//! nothing else. The probe alternates it with the scheduler so a user sees how
//! much the scheduler adds over the machine's own timer.

use crate::clock::{Clock, Nanos};
use crate::hist::LatencyHistogram;
use crate::schedule::StopFlag;

/// A periodic wake-up loop that only records its lateness.
pub struct BareLoop<C: Clock> {
    clock: C,
    period: Nanos,
    late_bound: Nanos,
    lateness: LatencyHistogram,
    ticks: u64,
    late: u64,
    skipped: u64,
}

impl<C: Clock> BareLoop<C> {
    /// A reference loop with the same period and late bound as the scheduler it
    /// is compared with (misses are counted by the same rule).
    pub fn new(clock: C, period: Nanos, late_bound: Nanos) -> Self {
        let mut lateness = LatencyHistogram::new();
        lateness.reset(); // touch every page before the loop records
        BareLoop {
            clock,
            period,
            late_bound,
            lateness,
            ticks: 0,
            late: 0,
            skipped: 0,
        }
    }

    /// Wakes on the grid `now + k·period` for `duration` (or until `stop`).
    pub fn run(&mut self, duration: Nanos, stop: &StopFlag) {
        let start = self.clock.now();
        let end = start + duration;
        let mut deadline = start + self.period;
        while deadline <= end && !stop.is_requested() {
            self.clock.sleep_until(deadline);
            let woke = self.clock.now();
            let late = woke - deadline;
            self.lateness.record(late.0);
            self.ticks += 1;
            self.late += u64::from(late > self.late_bound);
            deadline += self.period;
            // Same realignment rule as the scheduler's default policy.
            while woke > deadline + self.late_bound {
                deadline += self.period;
                self.skipped += 1;
            }
        }
    }

    /// Wake-ups so far.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// Late wake-ups plus skipped slots.
    pub fn missed(&self) -> u64 {
        self.late + self.skipped
    }

    /// The lateness histogram.
    pub fn lateness(&self) -> &LatencyHistogram {
        &self.lateness
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::MockClock;

    #[test]
    fn counts_wakeups_on_the_grid() {
        let clock = MockClock::new(Nanos(0));
        let mut l = BareLoop::new(clock, Nanos(1_000_000), Nanos(500_000));
        l.run(Nanos(1_000_000_000), &StopFlag::new());
        assert_eq!((l.ticks(), l.missed()), (1000, 0));
        assert_eq!(l.lateness().max(), 0);
    }
}
