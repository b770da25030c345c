//! Human-readable reports.

pub mod probe;
