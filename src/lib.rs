//! haptloop: real-time haptic interaction with constrained virtual mechanisms.
//!
//! The library behind the `haptloop` command. It wires the three crates
//! together; each of them is documented on its own:
//!
//! ```text
//!  scenes::resolve(SCENE|FILE) ─► Scene { CompiledScene (haptloop_solver), hand traces }
//!  cli ─► probe (haptloop_rt::probe) │ scenes │ check │ run (session) │ sweep (sweep → session)
//!  report ─► text reports, summary.json, percentile distributions, SVG plots
//! ```
//!
//! Exit codes of the binary (README, "Exit status"): 0 success; 1 a runtime
//! error or an invalid scene (printed with file:line:column or the cause
//! chain); 2 a usage error; 3 a run that finished with failed ticks or a
//! replay that diverged (or a `check` whose preflight warns); 130 stopped by
//! a signal.

pub mod cli;
pub mod export;
pub mod report;
pub mod scenes;
pub mod session;
pub mod sweep;
pub mod view;
