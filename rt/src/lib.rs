//! haptloop-rt: the real-time core.
pub mod alloc;
pub mod clock;
pub mod exchange;
pub mod hist;
pub mod probe;
pub mod reference;
pub mod schedule;
pub mod thread;
