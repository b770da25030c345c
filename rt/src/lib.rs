//! haptloop-rt: the real-time core.
pub mod alloc;
