//! Monotonic time: the only module that reads the OS clock.
//!
//! Everything else in haptloop takes time from a [`Clock`]: the real
//! [`MonotonicClock`] (`CLOCK_MONOTONIC`, absolute `clock_nanosleep`) on the
//! fast thread, or a [`MockClock`] that tests and deterministic sessions advance
//! by hand, so a whole session can run bit-identically as fast as possible.
//!
//! Times are [`Nanos`]: nanoseconds on the clock's own monotonic axis, never
//! wall-clock time and never a bare `f64` of seconds.

use std::fmt;
use std::ops::{Add, AddAssign, Sub};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// A point or span on a monotonic clock, in nanoseconds.
///
/// Subtraction saturates at zero: a "lateness" of a tick that started before its
/// deadline (which the scheduler never does, but a mock might) reads as 0, never
/// as a wrapped-around huge number.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Nanos(pub u64);

impl Nanos {
    /// Zero.
    pub const ZERO: Nanos = Nanos(0);

    /// From a [`Duration`], saturating at `u64::MAX` ns (584 years).
    pub fn from_duration(d: Duration) -> Self {
        Nanos(u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
    }

    /// As a [`Duration`].
    pub fn as_duration(self) -> Duration {
        Duration::from_nanos(self.0)
    }

    /// Nanoseconds as `u64`.
    pub fn as_u64(self) -> u64 {
        self.0
    }

    /// `self − earlier`, or zero if `earlier` is later.
    pub fn saturating_sub(self, earlier: Nanos) -> Nanos {
        Nanos(self.0.saturating_sub(earlier.0))
    }
}

impl Add for Nanos {
    type Output = Nanos;
    fn add(self, rhs: Nanos) -> Nanos {
        Nanos(self.0.saturating_add(rhs.0))
    }
}

impl AddAssign for Nanos {
    fn add_assign(&mut self, rhs: Nanos) {
        *self = *self + rhs;
    }
}

impl Sub for Nanos {
    type Output = Nanos;
    fn sub(self, rhs: Nanos) -> Nanos {
        self.saturating_sub(rhs)
    }
}

impl fmt::Display for Nanos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ns", self.0)
    }
}

/// A monotonic clock that can also wait for an absolute deadline.
///
/// # Real-time
/// Implementations used on the fast thread must not allocate or lock. The OS
/// clock reads through the vDSO (no syscall); `sleep_until` is the loop's one
/// syscall per tick.
pub trait Clock: Send {
    /// Current time on this clock's axis.
    fn now(&self) -> Nanos;

    /// Blocks until `now() >= deadline` (absolute deadline; returns at once if it
    /// has passed). Never a relative sleep, so delays do not accumulate.
    fn sleep_until(&self, deadline: Nanos);

    /// True for clocks that do not follow real time ([`MockClock`]); the
    /// scheduler then skips spin windows and OS-level thread setup is optional.
    fn is_simulated(&self) -> bool {
        false
    }
}

/// The OS monotonic clock: `clock_gettime(CLOCK_MONOTONIC)` and
/// `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)`.
#[derive(Debug, Default, Clone, Copy)]
pub struct MonotonicClock;

impl MonotonicClock {
    /// The OS clock.
    pub fn new() -> Self {
        MonotonicClock
    }
}

fn to_timespec(t: Nanos) -> libc::timespec {
    libc::timespec {
        tv_sec: (t.0 / 1_000_000_000) as libc::time_t,
        tv_nsec: (t.0 % 1_000_000_000) as libc::c_long,
    }
}

impl Clock for MonotonicClock {
    fn now(&self) -> Nanos {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable timespec; CLOCK_MONOTONIC always exists
        // on Linux, so the call cannot fail.
        unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
        Nanos(ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64)
    }

    fn sleep_until(&self, deadline: Nanos) {
        let ts = to_timespec(deadline);
        loop {
            // SAFETY: `ts` is a valid timespec; with TIMER_ABSTIME the remainder
            // pointer is unused and may be null.
            let rc = unsafe {
                libc::clock_nanosleep(
                    libc::CLOCK_MONOTONIC,
                    libc::TIMER_ABSTIME,
                    &ts,
                    std::ptr::null_mut(),
                )
            };
            // clock_nanosleep returns the error number directly; EINTR (a signal,
            // e.g. Ctrl-C) just means "sleep again until the same absolute time".
            if rc != libc::EINTR {
                return;
            }
        }
    }
}

/// A clock that only moves when told to: `sleep_until` jumps straight to the
/// deadline, and [`MockClock::advance`] simulates compute time or a host stall.
///
/// Clones share the same time, so a test can hold one handle while the
/// scheduler owns another.
#[derive(Debug, Clone, Default)]
pub struct MockClock {
    now: Arc<AtomicU64>,
}

impl MockClock {
    /// A mock clock starting at `start`.
    pub fn new(start: Nanos) -> Self {
        MockClock {
            now: Arc::new(AtomicU64::new(start.0)),
        }
    }

    /// Moves time forward by `by` (simulated compute time or a stall).
    pub fn advance(&self, by: Nanos) {
        self.now.fetch_add(by.0, Ordering::SeqCst);
    }

    /// Sets the time to `t` if that is later than now (time never goes back).
    pub fn advance_to(&self, t: Nanos) {
        self.now.fetch_max(t.0, Ordering::SeqCst);
    }
}

impl Clock for MockClock {
    fn now(&self) -> Nanos {
        Nanos(self.now.load(Ordering::SeqCst))
    }

    fn sleep_until(&self, deadline: Nanos) {
        self.advance_to(deadline);
    }

    fn is_simulated(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nanos_arithmetic_saturates() {
        assert_eq!(Nanos(5) - Nanos(7), Nanos::ZERO);
        assert_eq!(Nanos(u64::MAX) + Nanos(1), Nanos(u64::MAX));
        assert_eq!(
            Nanos::from_duration(Duration::from_micros(3)).as_u64(),
            3_000
        );
        assert_eq!(Nanos(1_500).as_duration(), Duration::from_nanos(1_500));
    }

    #[test]
    fn mock_clock_jumps_to_deadlines_and_never_goes_back() {
        let c = MockClock::new(Nanos(100));
        let shared = c.clone();
        c.sleep_until(Nanos(1_000));
        assert_eq!(shared.now(), Nanos(1_000));
        c.sleep_until(Nanos(500));
        assert_eq!(c.now(), Nanos(1_000));
        shared.advance(Nanos(250));
        assert_eq!(c.now(), Nanos(1_250));
        assert!(c.is_simulated());
    }

    #[test]
    fn monotonic_clock_is_monotonic_and_sleeps_to_absolute_deadlines() {
        let c = MonotonicClock::new();
        let t0 = c.now();
        let deadline = t0 + Nanos(200_000);
        c.sleep_until(deadline);
        let t1 = c.now();
        assert!(
            t1 >= deadline,
            "woke before the deadline: {t1} < {deadline}"
        );
        // A deadline in the past returns at once (structure, not speed: it
        // must not wait for another full period).
        c.sleep_until(t0);
        assert!(c.now() >= t1);
        assert!(!c.is_simulated());
    }
}
