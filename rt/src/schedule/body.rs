//! What the scheduler hands a tick body and what the body hands back.

use crate::clock::Nanos;
use serde::{Deserialize, Serialize};
use std::fmt::Debug;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// One tick of the periodic loop, as the body sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tick {
    /// The grid slot: deadline = origin + index × period. Skipped slots make it
    /// jump, so `index − previous index` periods have elapsed since the last tick.
    pub index: u64,
    /// When this tick was due (clock time).
    pub deadline: Nanos,
    /// When it actually started (clock time); `start − deadline` is its lateness.
    pub start: Nanos,
}

/// What a tick body reports back. `F` is the body's own `Copy` fault type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TickStatus<F> {
    /// The tick did its work.
    Ok,
    /// Something the safety hook must act on (a device fault, a non-finite
    /// force …). The loop keeps running; the body decides how to recover.
    Fault(F),
}

/// Why the scheduler calls the body's safety hook.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SafetyEvent<F> {
    /// This many consecutive slots were missed (late, overrun or skipped).
    /// Called once per streak, when it reaches the configured limit.
    MissStreak {
        /// Consecutive misses so far.
        misses: u32,
    },
    /// The tick returned a fault.
    Fault(F),
}

/// The work the fast thread does every period. The fast thread runs nothing
/// else.
///
/// # Real-time
/// `tick` must not allocate, lock, log or do I/O, and must run in bounded time;
/// a counting-allocator test should prove it for every implementation.
pub trait TickBody {
    /// The body's own heap-free fault value.
    type Fault: Copy + Debug + Send + 'static;

    /// Does one period's work.
    fn tick(&mut self, tick: &Tick) -> TickStatus<Self::Fault>;

    /// Called after a fault or when a miss streak reaches its limit. The place to
    /// cut motor forces. Same real-time rules as `tick`.
    fn on_safety(&mut self, _event: SafetyEvent<Self::Fault>) {}

    /// Called once on the fast thread when the loop ends (stop request or run
    /// limit), after the last tick: the place to leave hardware safe.
    fn on_stop(&mut self) {}
}

/// Counted deadline misses, by kind. A tick can be both late and overrun.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct MissCounts {
    /// Ticks that started later than the late bound after their deadline.
    pub late: u64,
    /// Ticks whose compute time exceeded the period.
    pub overrun: u64,
    /// Grid slots never run (dropped to realign after a stall or overrun).
    pub skipped: u64,
}

impl MissCounts {
    /// All missed deadlines: late + overrun + skipped.
    pub fn total(&self) -> u64 {
        self.late + self.overrun + self.skipped
    }

    pub(crate) fn add(&mut self, other: &MissCounts) {
        self.late += other.late;
        self.overrun += other.overrun;
        self.skipped += other.skipped;
    }
}

/// A shared stop request: set it from any thread (Ctrl-C handler, the slow
/// loop, the body itself); the loop stops at the next tick boundary.
#[derive(Debug, Clone, Default)]
pub struct StopFlag(Arc<AtomicBool>);

impl StopFlag {
    /// A flag that is not set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Requests a stop.
    pub fn request(&self) {
        self.0.store(true, Ordering::Release);
    }

    /// True once a stop was requested.
    #[inline]
    pub fn is_requested(&self) -> bool {
        self.0.load(Ordering::Acquire)
    }
}

/// When a [`super::Periodic::run`] call returns (besides a stop request).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RunLimit {
    /// Return after this many grid slots (run or skipped).
    pub slots: Option<u64>,
    /// Return before the first slot whose deadline is past this span from the
    /// start of the run.
    pub duration: Option<Nanos>,
}

impl RunLimit {
    /// No limit: run until stopped.
    pub fn forever() -> Self {
        Self::default()
    }

    /// Run `n` grid slots.
    pub fn slots(n: u64) -> Self {
        RunLimit {
            slots: Some(n),
            duration: None,
        }
    }

    /// Run for `d` of clock time.
    pub fn duration(d: std::time::Duration) -> Self {
        RunLimit {
            slots: None,
            duration: Some(Nanos::from_duration(d)),
        }
    }
}
