//! A counting global allocator that proves the real-time rules in tests.
//!
//! [`CountingAllocator`] wraps the system allocator and counts allocations,
//! deallocations and reallocations **per thread**, so a test can run a tick body
//! on one thread while the test harness allocates freely on others. Install it in
//! a test binary (never in a library):
//!
//! ```ignore
//! #[global_allocator]
//! static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;
//!
//! let (_, stats) = haptloop_rt::alloc::count(|| tick_body.tick());
//! assert_eq!(stats.total(), 0);
//! ```
//!
//! Counting is only active while a thread is inside [`count`] (or between
//! [`CountScope::start`] and [`CountScope::finish`]); elsewhere the allocator is a
//! plain pass-through with one thread-local read of overhead.
//!
//! # Real-time
//! The counters live in `const`-initialised thread-locals of `Cell<u64>` type,
//! which need no destructor registration and never allocate themselves.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// A pass-through global allocator that counts (de)allocations per thread while
/// counting is enabled on that thread. See the [module docs](self).
#[derive(Debug, Default, Clone, Copy)]
pub struct CountingAllocator;

thread_local! {
    static ACTIVE: Cell<bool> = const { Cell::new(false) };
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
    static DEALLOCS: Cell<u64> = const { Cell::new(0) };
    static REALLOCS: Cell<u64> = const { Cell::new(0) };
    static BYTES: Cell<u64> = const { Cell::new(0) };
}

/// What a thread allocated while counting was enabled.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct AllocStats {
    /// Calls to `alloc` / `alloc_zeroed`.
    pub allocs: u64,
    /// Calls to `dealloc`.
    pub deallocs: u64,
    /// Calls to `realloc`.
    pub reallocs: u64,
    /// Bytes requested by `alloc`, `alloc_zeroed` and `realloc` (new size).
    pub bytes: u64,
}

impl AllocStats {
    /// Total number of allocator calls of any kind.
    pub fn total(&self) -> u64 {
        self.allocs + self.deallocs + self.reallocs
    }
}

#[inline]
fn bump(counter: &'static std::thread::LocalKey<Cell<u64>>, by: u64) {
    // `try_with`: during thread teardown the thread-locals may be gone; the
    // allocator must never panic, so such calls are simply not counted.
    let active = ACTIVE.try_with(Cell::get).unwrap_or(false);
    if active {
        let _ = counter.try_with(|c| c.set(c.get() + by));
    }
}

// SAFETY: every method forwards to `System` with the caller's arguments unchanged;
// the counting touches only thread-local `Cell`s and never allocates.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump(&ALLOCS, 1);
        bump(&BYTES, layout.size() as u64);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        bump(&ALLOCS, 1);
        bump(&BYTES, layout.size() as u64);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        bump(&DEALLOCS, 1);
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump(&REALLOCS, 1);
        bump(&BYTES, new_size as u64);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Turns counting on or off for the current thread; returns the previous
/// setting. Prefer [`count`] or [`CountScope`]; this is for windows that span
/// several calls of a `Send` object (start in one tick, finish in `on_stop`).
pub fn set_counting(on: bool) -> bool {
    ACTIVE.with(|a| a.replace(on))
}

/// This thread's cumulative counters (they only grow while counting is on).
pub fn thread_stats() -> AllocStats {
    read()
}

impl std::ops::Sub for AllocStats {
    type Output = AllocStats;
    fn sub(self, earlier: AllocStats) -> AllocStats {
        AllocStats {
            allocs: self.allocs - earlier.allocs,
            deallocs: self.deallocs - earlier.deallocs,
            reallocs: self.reallocs - earlier.reallocs,
            bytes: self.bytes - earlier.bytes,
        }
    }
}

fn read() -> AllocStats {
    AllocStats {
        allocs: ALLOCS.with(Cell::get),
        deallocs: DEALLOCS.with(Cell::get),
        reallocs: REALLOCS.with(Cell::get),
        bytes: BYTES.with(Cell::get),
    }
}

/// A counting window on the current thread. Not `Send`: it must finish on the
/// thread that started it.
#[derive(Debug)]
pub struct CountScope {
    start: AllocStats,
    was_active: bool,
    _not_send: std::marker::PhantomData<*const ()>,
}

impl CountScope {
    /// Starts counting this thread's allocator calls.
    pub fn start() -> Self {
        let was_active = ACTIVE.with(|a| a.replace(true));
        Self {
            start: read(),
            was_active,
            _not_send: std::marker::PhantomData,
        }
    }

    /// Stops counting and returns what this thread did since [`CountScope::start`].
    pub fn finish(self) -> AllocStats {
        let end = read();
        ACTIVE.with(|a| a.set(self.was_active));
        end - self.start
    }
}

/// Runs `f` on the current thread and returns its result with the allocator calls
/// it made. Only meaningful when [`CountingAllocator`] is the global allocator;
/// otherwise the stats are all zero.
pub fn count<R>(f: impl FnOnce() -> R) -> (R, AllocStats) {
    let scope = CountScope::start();
    let r = f();
    (r, scope.finish())
}

/// True when [`CountingAllocator`] is this binary's global allocator: probes by
/// making one small allocation inside a counting window.
pub fn is_installed() -> bool {
    let (_, stats) = count(|| std::hint::black_box(Box::new(0u64)));
    stats.allocs > 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[global_allocator]
    static ALLOC: CountingAllocator = CountingAllocator;

    #[test]
    fn counts_a_vec_and_nothing_else() {
        assert!(is_installed());
        let (v, stats) = count(|| {
            let mut v: Vec<u64> = Vec::with_capacity(4);
            v.extend_from_slice(&[1, 2, 3, 4]);
            v
        });
        assert_eq!(stats.allocs, 1);
        assert_eq!(stats.bytes, 32);
        assert_eq!(stats.deallocs, 0);
        let (_, stats) = count(|| drop(v));
        assert_eq!(stats.deallocs, 1);
        let (_, stats) = count(|| (0..100u64).sum::<u64>());
        assert_eq!(stats.total(), 0);
    }

    #[test]
    fn other_threads_are_not_counted() {
        let scope = CountScope::start();
        std::thread::scope(|s| {
            s.spawn(|| std::hint::black_box(vec![0u8; 1024]));
        });
        let stats = scope.finish();
        // Spawning a scoped thread allocates on this thread (its handle), but the
        // 1 KiB vector allocated on the child is not ours.
        assert!(
            stats.bytes < 1024,
            "counted another thread's bytes: {stats:?}"
        );
    }

    #[test]
    fn nested_scopes_restore_state() {
        let outer = CountScope::start();
        let (_, inner) = count(|| std::hint::black_box(Box::new(1u32)));
        assert_eq!(inner.allocs, 1);
        let _b = std::hint::black_box(Box::new(2u32));
        let outer = outer.finish();
        assert_eq!(outer.allocs, 2);
    }
}
