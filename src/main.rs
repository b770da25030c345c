//! `haptloop`: real-time haptic interaction with constrained virtual mechanisms.
//!
//! This binary is thin: it parses flags into typed values ([`cli`]), hands them
//! to the library crates, and prints reports ([`report`]).
//!
//! Exit codes: 0 success; 1 a runtime error (printed with its cause chain);
//! 2 a usage error (bad flags, printed by clap).

mod cli;
mod report;

use std::process::ExitCode;

fn main() -> ExitCode {
    match cli::run() {
        Ok(code) => code,
        Err(err) => {
            eprintln!("haptloop: error: {err:#}");
            ExitCode::from(1)
        }
    }
}
