//! Interval snapshots: per-interval histograms and miss counts that reach a
//! non-real-time reporter without blocking the tick.
//!
//! A fixed pool of boxed [`IntervalStats`] circulates through two crossbeam
//! `ArrayQueue`s. The fast thread records into the one it holds; when an
//! interval ends it pushes that box to the *filled* queue and pops a clean one
//! from the *free* queue. The reporter pops filled boxes, reads them, and the
//! [`IntervalSnapshot`] guard resets each box and returns it to the free queue
//! when dropped — all resetting happens on the reporter's thread. If the
//! reporter falls behind and no clean box is free, the fast thread keeps
//! recording into the box it has (the interval simply gets longer): it never
//! waits, allocates or loses a count.

use super::MissCounts;
use crate::clock::Nanos;
use crate::hist::LatencyHistogram;
use crossbeam::queue::ArrayQueue;
use std::sync::Arc;

/// Histograms and counts for one reporting interval.
#[derive(Debug, Clone, Default)]
pub struct IntervalStats {
    /// Index of the first slot in the interval.
    pub first_index: u64,
    /// Clock time of the interval's first tick start.
    pub started: Nanos,
    /// Clock time of the interval's last tick end.
    pub ended: Nanos,
    /// Ticks run in the interval.
    pub ticks: u64,
    /// Misses in the interval.
    pub misses: MissCounts,
    /// Wake-up lateness (start − deadline), ns.
    pub lateness: LatencyHistogram,
    /// Tick body compute time (end − start), ns.
    pub compute: LatencyHistogram,
    /// Start-to-start period, ns.
    pub period: LatencyHistogram,
}

impl IntervalStats {
    fn clear(&mut self) {
        self.first_index = 0;
        self.started = Nanos::ZERO;
        self.ended = Nanos::ZERO;
        self.ticks = 0;
        self.misses = MissCounts::default();
        self.lateness.reset();
        self.compute.reset();
        self.period.reset();
    }
}

struct Pool {
    free: ArrayQueue<Box<IntervalStats>>,
    filled: ArrayQueue<Box<IntervalStats>>,
}

/// The fast thread's side: holds the current interval.
pub(crate) struct IntervalSender {
    pool: Arc<Pool>,
    current: Box<IntervalStats>,
    pub(crate) open: bool,
}

/// The reporter's side: receives finished intervals.
pub struct IntervalReceiver {
    pool: Arc<Pool>,
}

/// A finished interval; returns its box to the pool (reset) when dropped.
pub struct IntervalSnapshot {
    pool: Arc<Pool>,
    stats: Option<Box<IntervalStats>>,
}

/// Creates the pool: `slots` boxes in all (one held by the fast thread).
pub(crate) fn interval_channel(slots: usize) -> (IntervalSender, IntervalReceiver) {
    let slots = slots.max(2);
    let pool = Arc::new(Pool {
        free: ArrayQueue::new(slots),
        filled: ArrayQueue::new(slots),
    });
    for _ in 1..slots {
        let _ = pool.free.push(Box::default());
    }
    (
        IntervalSender {
            pool: pool.clone(),
            current: Box::default(),
            open: false,
        },
        IntervalReceiver { pool },
    )
}

impl IntervalSender {
    /// The interval being recorded.
    #[inline]
    pub(crate) fn current(&mut self) -> &mut IntervalStats {
        &mut self.current
    }

    /// Hands the current interval to the reporter if a clean box is free;
    /// otherwise keeps recording into the current one. Returns true if sent.
    ///
    /// # Real-time
    /// Two lock-free queue operations; no allocation.
    pub(crate) fn try_finish(&mut self) -> bool {
        let Some(fresh) = self.pool.free.pop() else {
            return false;
        };
        let full = std::mem::replace(&mut self.current, fresh);
        // Cannot fail: `slots` boxes exist and one is now `current`.
        if let Err(full) = self.pool.filled.push(full) {
            std::mem::forget(full);
        }
        self.open = false;
        true
    }
}

impl IntervalReceiver {
    /// The oldest finished interval, if any. Never blocks.
    pub fn try_recv(&self) -> Option<IntervalSnapshot> {
        self.pool.filled.pop().map(|b| IntervalSnapshot {
            pool: self.pool.clone(),
            stats: Some(b),
        })
    }
}

impl std::ops::Deref for IntervalSnapshot {
    type Target = IntervalStats;
    fn deref(&self) -> &IntervalStats {
        self.stats.as_ref().expect("present until drop")
    }
}

impl Drop for IntervalSnapshot {
    fn drop(&mut self) {
        if let Some(mut b) = self.stats.take() {
            b.clear();
            let _ = self.pool.free.push(b);
        }
    }
}
