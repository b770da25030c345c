//! Tick bodies and clocks shared by the scheduler tests.

use haptloop_rt::clock::{Clock, MockClock, Nanos};
use haptloop_rt::schedule::{SafetyEvent, StopFlag, Tick, TickBody, TickStatus};

/// A body that records every tick, can burn mock time, fault, or stop.
pub struct Recorder {
    pub clock: MockClock,
    pub ticks: Vec<Tick>,
    pub safety: Vec<SafetyEvent<u8>>,
    /// (tick index, mock nanoseconds of compute to simulate)
    pub stall_at: Option<(u64, u64)>,
    /// Simulated compute time of every tick, ns.
    pub compute_ns: u64,
    pub fault_at: Option<u64>,
    pub stop_at: Option<(u64, StopFlag)>,
    pub stopped: u32,
}

impl Recorder {
    pub fn new(clock: MockClock) -> Self {
        Recorder {
            clock,
            ticks: Vec::with_capacity(100_000),
            safety: Vec::with_capacity(64),
            stall_at: None,
            compute_ns: 0,
            fault_at: None,
            stop_at: None,
            stopped: 0,
        }
    }
}

impl TickBody for Recorder {
    type Fault = u8;

    fn tick(&mut self, tick: &Tick) -> TickStatus<u8> {
        self.ticks.push(*tick);
        self.clock.advance(Nanos(self.compute_ns));
        if let Some((i, ns)) = self.stall_at
            && i == tick.index
        {
            self.clock.advance(Nanos(ns));
        }
        if let Some((i, stop)) = &self.stop_at
            && *i == tick.index
        {
            stop.request();
        }
        if self.fault_at == Some(tick.index) {
            return TickStatus::Fault(7);
        }
        TickStatus::Ok
    }

    fn on_safety(&mut self, event: SafetyEvent<u8>) {
        self.safety.push(event);
    }

    fn on_stop(&mut self) {
        self.stopped += 1;
    }
}

/// A mock clock whose n-th sleep oversleeps by a fixed stall (a host stall
/// while the thread was waiting for its deadline).
#[derive(Clone)]
pub struct StallingClock {
    pub inner: MockClock,
    pub stall_on_sleep: u64,
    pub stall_ns: u64,
    sleeps: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

impl StallingClock {
    pub fn new(stall_on_sleep: u64, stall_ns: u64) -> Self {
        StallingClock {
            inner: MockClock::new(Nanos(1_000_000_000)),
            stall_on_sleep,
            stall_ns,
            sleeps: Default::default(),
        }
    }
}

impl Clock for StallingClock {
    fn now(&self) -> Nanos {
        self.inner.now()
    }
    fn sleep_until(&self, deadline: Nanos) {
        let n = self
            .sleeps
            .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        self.inner.sleep_until(deadline);
        if n == self.stall_on_sleep {
            self.inner.advance(Nanos(self.stall_ns));
        }
    }
    fn is_simulated(&self) -> bool {
        true
    }
}
