//! The scheduler on a real pinned thread and the OS clock. These assert counts
//! and structure, never speed: the machine is shared and noisy.

use haptloop_rt::alloc::{AllocStats, set_counting, thread_stats};
use haptloop_rt::clock::MonotonicClock;
use haptloop_rt::schedule::{
    RunEnd, RunLimit, ScheduleConfig, StopFlag, Tick, TickBody, TickStatus, spawn_loop,
};
use haptloop_rt::thread::ThreadConfig;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// Counts ticks (visible to other threads) and the allocator calls made on the
/// fast thread from tick 10 to the end of the loop.
#[derive(Default)]
struct Counting {
    seen: Arc<AtomicU64>,
    baseline: Option<AllocStats>,
    allocated: Option<AllocStats>,
    stops: u32,
    acc: f64,
}

impl TickBody for Counting {
    type Fault = ();
    fn tick(&mut self, tick: &Tick) -> TickStatus<()> {
        if tick.index >= 10 && self.baseline.is_none() {
            set_counting(true);
            self.baseline = Some(thread_stats());
        }
        self.acc += (tick.index as f64).sqrt();
        self.seen.fetch_add(1, Ordering::Relaxed);
        TickStatus::Ok
    }
    fn on_stop(&mut self) {
        if let Some(b) = self.baseline {
            self.allocated = Some(thread_stats() - b);
            set_counting(false);
        }
        self.stops += 1;
    }
}

fn test_config(rate_hz: u32) -> ScheduleConfig {
    ScheduleConfig {
        rate_hz,
        thread: ThreadConfig {
            // Tests share the machine with the harness: no FIFO, no mlockall.
            fifo_priority: None,
            lock_memory: false,
            ..ThreadConfig::default()
        },
        ..ScheduleConfig::default()
    }
}

#[test]
fn a_real_loop_accounts_for_every_slot_and_allocates_nothing() {
    let handle = spawn_loop(
        &test_config(2000),
        MonotonicClock::new(),
        Counting::default(),
        StopFlag::new(),
        RunLimit::slots(400),
    )
    .unwrap();
    let out = handle.join().unwrap();
    let r = &out.report;
    assert_eq!(out.end, RunEnd::Limit);
    assert_eq!(r.slots, 400);
    assert_eq!(r.ticks + r.misses.skipped, 400);
    assert_eq!(r.lateness_ns.count, r.ticks);
    assert_eq!(r.compute_ns.count, r.ticks);
    assert_eq!(r.period_ns.count, r.ticks - 1);
    assert_eq!(out.body.seen.load(Ordering::Relaxed), r.ticks);
    assert_eq!(out.body.stops, 1);
    assert!(!out.granted.fifo);
    let allocated = out.body.allocated.expect("counted from tick 10");
    assert_eq!(allocated.total(), 0, "fast thread allocated: {allocated:?}");
}

#[test]
fn a_stop_request_from_another_thread_ends_the_loop_at_a_tick_boundary() {
    let stop = StopFlag::new();
    let body = Counting::default();
    let seen = body.seen.clone();
    let handle = spawn_loop(
        &test_config(1000),
        MonotonicClock::new(),
        body,
        stop.clone(),
        RunLimit::forever(),
    )
    .unwrap();
    // Wait (bounded: 60 s of real time) until the loop has ticked 50 times.
    let clock = MonotonicClock::new();
    let give_up = {
        use haptloop_rt::clock::Clock;
        clock.now() + haptloop_rt::clock::Nanos::from_duration(Duration::from_secs(60))
    };
    while seen.load(Ordering::Relaxed) < 50 {
        use haptloop_rt::clock::Clock;
        assert!(clock.now() < give_up, "loop never reached 50 ticks");
        std::thread::yield_now();
    }
    stop.request();
    let out = handle.join().unwrap();
    assert_eq!(out.end, RunEnd::Stopped);
    assert!(out.report.ticks >= 50);
    assert_eq!(out.body.seen.load(Ordering::Relaxed), out.report.ticks);
    assert_eq!(out.body.stops, 1, "on_stop ran once, on the fast thread");
}
