//! The periodic loop itself: absolute deadlines on a fixed grid, an optional
//! spin window, miss accounting, the overrun policy and the safety hook.

use super::body::{MissCounts, RunLimit, SafetyEvent, StopFlag, Tick, TickBody, TickStatus};
use super::config::{ConfigError, OverrunPolicy, ScheduleConfig, Timing};
use super::intervals::{IntervalReceiver, IntervalSender, interval_channel};
use crate::clock::{Clock, Nanos};
use crate::hist::{LatencyHistogram, Summary};
use serde::{Deserialize, Serialize};

/// Interval boxes in circulation: the fast thread holds one; the reporter may
/// hold one while up to six wait.
const INTERVAL_POOL: usize = 8;

/// The three per-tick latency histograms of a loop.
#[derive(Debug, Clone, Default)]
pub struct LoopHistograms {
    /// Wake-up lateness: start − deadline.
    pub lateness: LatencyHistogram,
    /// Compute time of the tick body: end − start.
    pub compute: LatencyHistogram,
    /// Start-to-start period.
    pub period: LatencyHistogram,
}

impl LoopHistograms {
    fn prefaulted() -> Self {
        let mut h = LoopHistograms::default();
        // `reset` writes every count, so every page of the (calloc'd, possibly
        // untouched) count arrays is resident before the loop first records.
        h.lateness.reset();
        h.compute.reset();
        h.period.reset();
        h
    }
}

/// Everything a loop counted, ready to print or serialise.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LoopReport {
    /// Configured rate, Hz.
    pub rate_hz: u32,
    /// Spin window, ns.
    pub spin_ns: u64,
    /// Ticks run.
    pub ticks: u64,
    /// Grid slots elapsed (ticks + skipped).
    pub slots: u64,
    /// Missed deadlines by kind.
    pub misses: MissCounts,
    /// Ticks that returned a fault.
    pub faults: u64,
    /// Safety-hook calls (faults and miss streaks).
    pub safety_events: u64,
    /// Wake-up lateness, ns.
    pub lateness_ns: Summary,
    /// Compute time, ns.
    pub compute_ns: Summary,
    /// Start-to-start period, ns.
    pub period_ns: Summary,
}

/// Why [`Periodic::run`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunEnd {
    /// The stop flag was set; the loop stopped at a tick boundary.
    Stopped,
    /// The run limit was reached.
    Limit,
}

/// The periodic scheduler on the current thread, driven by clock `C`.
///
/// Build it off the fast thread ([`Periodic::new`] allocates the histograms),
/// then call [`Periodic::run`] on the thread that should tick — usually via
/// [`super::spawn_loop`], which prepares a pinned real-time thread first.
pub struct Periodic<C: Clock> {
    clock: C,
    timing: Timing,
    policy: OverrunPolicy,
    streak_limit: u32,
    rate_hz: u32,
    hist: LoopHistograms,
    misses: MissCounts,
    ticks: u64,
    slots: u64,
    faults: u64,
    safety_events: u64,
    intervals: IntervalSender,
}

impl<C: Clock> Periodic<C> {
    /// Validates `config` and preallocates everything the loop needs. Returns the
    /// scheduler and the receiving end of its interval snapshots.
    pub fn new(config: &ScheduleConfig, clock: C) -> Result<(Self, IntervalReceiver), ConfigError> {
        let timing = config.validate()?;
        let (intervals, receiver) = interval_channel(INTERVAL_POOL);
        Ok((
            Periodic {
                clock,
                timing,
                policy: config.overrun,
                streak_limit: config.miss_streak_limit,
                rate_hz: config.rate_hz,
                hist: LoopHistograms::prefaulted(),
                misses: MissCounts::default(),
                ticks: 0,
                slots: 0,
                faults: 0,
                safety_events: 0,
                intervals,
            },
            receiver,
        ))
    }

    /// The clock driving this loop.
    pub fn clock(&self) -> &C {
        &self.clock
    }

    /// The loop period.
    pub fn period(&self) -> Nanos {
        self.timing.period
    }

    /// Runs ticks on a fixed grid starting one period from now, until `stop` is
    /// requested or `limit` is reached. May be called again: each call starts a
    /// fresh grid, and counts and histograms accumulate.
    ///
    /// # Real-time
    /// Allocates nothing; per tick it makes one sleep syscall (plus clock reads
    /// through the vDSO), records three histogram values twice (total and
    /// interval), and may push/pop one interval box on lock-free queues.
    pub fn run<B: TickBody>(&mut self, body: &mut B, limit: RunLimit, stop: &StopFlag) -> RunEnd {
        let Timing {
            period, late_bound, ..
        } = self.timing;
        let run_start = self.clock.now();
        let origin = run_start + period;
        let end_at = limit.duration.map(|d| run_start + d);
        let base = self.slots;
        let mut index = 0u64;
        let mut prev_start: Option<Nanos> = None;
        let mut streak = 0u32;
        let mut streak_reported = false;
        loop {
            if stop.is_requested() {
                return self.finish_run(RunEnd::Stopped);
            }
            let deadline = origin + Nanos(index * period.0);
            if limit.slots.is_some_and(|n| index >= n) || end_at.is_some_and(|e| deadline > e) {
                return self.finish_run(RunEnd::Limit);
            }
            self.wait_until(deadline);
            if stop.is_requested() {
                return self.finish_run(RunEnd::Stopped);
            }
            let start = self.clock.now();
            let tick = Tick {
                index: base + index,
                deadline,
                start,
            };
            let status = body.tick(&tick);
            let end = self.clock.now();

            let lateness = start - deadline;
            let compute = end - start;
            let mut missed = MissCounts {
                late: u64::from(lateness > late_bound),
                overrun: u64::from(compute > period),
                skipped: 0,
            };
            index += 1;
            let next = origin + Nanos(index * period.0);
            let behind = slots_behind(end, next, late_bound, period);
            missed.skipped = match self.policy {
                OverrunPolicy::Skip => behind,
                OverrunPolicy::CatchUp { max_burst } => behind.saturating_sub(u64::from(max_burst)),
            };
            // Slots past the run's end are not skipped: they never belonged to
            // the run (a stall across the end used to count them, 408 slots
            // for a 400-slot limit).
            missed.skipped = missed
                .skipped
                .min(slots_left(index, &limit, end_at, origin, period));
            index += missed.skipped;

            self.record(&tick, end, lateness, compute, prev_start, &missed);
            prev_start = Some(start);

            if let TickStatus::Fault(f) = status {
                self.faults += 1;
                self.safety_events += 1;
                body.on_safety(SafetyEvent::Fault(f));
            }
            if missed.late + missed.overrun + missed.skipped == 0 {
                streak = 0;
                streak_reported = false;
            } else {
                let n = u64::from(missed.late + missed.overrun > 0) + missed.skipped;
                streak = streak.saturating_add(u32::try_from(n).unwrap_or(u32::MAX));
                if streak >= self.streak_limit && !streak_reported {
                    streak_reported = true;
                    self.safety_events += 1;
                    body.on_safety(SafetyEvent::MissStreak { misses: streak });
                }
            }
        }
    }

    #[inline]
    fn wait_until(&self, deadline: Nanos) {
        let spin = self.timing.spin;
        if spin > Nanos::ZERO && !self.clock.is_simulated() {
            self.clock.sleep_until(deadline - spin);
            while self.clock.now() < deadline {
                std::hint::spin_loop();
            }
        } else {
            self.clock.sleep_until(deadline);
        }
    }

    #[inline]
    fn record(
        &mut self,
        tick: &Tick,
        end: Nanos,
        lateness: Nanos,
        compute: Nanos,
        prev_start: Option<Nanos>,
        missed: &MissCounts,
    ) {
        self.ticks += 1;
        self.slots += 1 + missed.skipped;
        self.misses.add(missed);
        self.hist.lateness.record(lateness.0);
        self.hist.compute.record(compute.0);
        let period = prev_start.map(|p| tick.start - p);
        if let Some(p) = period {
            self.hist.period.record(p.0);
        }
        // An interval holds the ticks that *start* within it, so at 1 kHz a 1 s
        // interval holds exactly 1000 ticks when none is missed.
        if self.intervals.open
            && tick.start - self.intervals.current().started >= self.timing.interval
        {
            self.intervals.try_finish();
        }
        if !self.intervals.open {
            self.intervals.open = true;
            let iv = self.intervals.current();
            iv.first_index = tick.index;
            iv.started = tick.start;
        }
        let iv = self.intervals.current();
        iv.ended = end;
        iv.ticks += 1;
        iv.misses.add(missed);
        iv.lateness.record(lateness.0);
        iv.compute.record(compute.0);
        if let Some(p) = period {
            iv.period.record(p.0);
        }
    }

    fn finish_run(&mut self, end: RunEnd) -> RunEnd {
        if self.intervals.open {
            self.intervals.try_finish();
        }
        end
    }

    /// Counts and percentile summaries so far.
    pub fn report(&self) -> LoopReport {
        LoopReport {
            rate_hz: self.rate_hz,
            spin_ns: self.timing.spin.0,
            ticks: self.ticks,
            slots: self.slots,
            misses: self.misses,
            faults: self.faults,
            safety_events: self.safety_events,
            lateness_ns: self.hist.lateness.summary(),
            compute_ns: self.hist.compute.summary(),
            period_ns: self.hist.period.summary(),
        }
    }

    /// The full histograms (for percentile-distribution export).
    pub fn histograms(&self) -> &LoopHistograms {
        &self.hist
    }
}

/// Number of grid slots starting at `next` (spaced by `period`) whose deadline
/// plus `late_bound` is already before `now`: the slots that can no longer start
/// on time.
fn slots_behind(now: Nanos, next: Nanos, late_bound: Nanos, period: Nanos) -> u64 {
    let on_time_until = next + late_bound;
    if now <= on_time_until {
        0
    } else {
        (now.0 - on_time_until.0 - 1) / period.0 + 1
    }
}

/// How many slots from `index` on still belong to a run with this limit: the
/// slot count's rest and the slots whose deadline is not past `end_at`.
fn slots_left(
    index: u64,
    limit: &RunLimit,
    end_at: Option<Nanos>,
    origin: Nanos,
    period: Nanos,
) -> u64 {
    let by_count = limit.slots.map_or(u64::MAX, |n| n.saturating_sub(index));
    let by_time = end_at.map_or(u64::MAX, |e| {
        if e < origin {
            0
        } else {
            ((e - origin).0 / period.0.max(1) + 1).saturating_sub(index)
        }
    });
    by_count.min(by_time)
}

#[cfg(test)]
mod tests {
    use super::slots_behind;
    use crate::clock::Nanos;

    #[test]
    fn slots_behind_counts_only_slots_that_cannot_start_in_time() {
        let (p, b) = (Nanos(1000), Nanos(500));
        assert_eq!(slots_behind(Nanos(1500), Nanos(1000), b, p), 0);
        assert_eq!(slots_behind(Nanos(1501), Nanos(1000), b, p), 1);
        assert_eq!(slots_behind(Nanos(2500), Nanos(1000), b, p), 1);
        assert_eq!(slots_behind(Nanos(2501), Nanos(1000), b, p), 2);
        assert_eq!(slots_behind(Nanos(6200), Nanos(1000), b, p), 5);
    }
}
