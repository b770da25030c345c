//! haptloop-rt: the real-time core — a hard-rate periodic scheduler on a pinned
//! core, latency histograms, and lock-free exchange between the fast loop and
//! the slow loop.
//!
//! Principal types and how data flows through them:
//!
//! ```text
//!  clock::MonotonicClock / clock::MockClock     the only readers of time
//!        │
//!  schedule::Periodic<C> ── run(body, limit, stop) ──► TickBody::tick(&Tick) → TickStatus
//!        │   (spawn_loop: on a thread prepared by thread::spawn_rt → thread::Granted)
//!        ├─► hist::LatencyHistogram ×3 (lateness, compute, period) → schedule::LoopReport
//!        └─► schedule::IntervalReceiver (1 s IntervalStats, for a reporter thread)
//!
//!  exchange::mailbox        fast → slow: newest snapshot (triple buffer, wait-free)
//!  exchange::program_channel slow → fast: Box<Program>; fast → slow: the replaced one
//!  probe::run_probe         scheduler vs. bare reference loop (reference::BareLoop)
//!  alloc::CountingAllocator test-only proof that the fast path allocates nothing
//! ```
//!
//! Everything the fast thread calls documents a `# Real-time` section: whether it
//! allocates, locks or makes a syscall, and what bounds its run time.

pub mod alloc;
pub mod clock;
pub mod exchange;
pub mod hist;
pub mod probe;
pub mod reference;
pub mod schedule;
pub mod thread;
