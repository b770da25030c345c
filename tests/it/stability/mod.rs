//! Numerical stability at the extremes: a matrix over the built-in
//! mechanisms (masses 1e-4 and 1e3 kg, geometry × 1e-3 and × 10, gains
//! × 1e-3 and × 1e3, 100 Hz and 20 kHz, a hand at 5 m/s, a 1 m step of the
//! hand), singular poses, two fingers pulling a body apart, and a long
//! deterministic run. Every case runs a whole session (devices, safety
//! layer, slow loop) on the mock clock and asserts, tick by tick:
//!
//! - no NaN or infinity anywhere in the outputs (q, multipliers, every
//!   finger output, every tick report figure);
//! - the force the motors rendered within each device's peak force;
//! - every quaternion's |e|² within 1e-9 of 1 at every tick (no drift);
//! - the violation back within the scene's tolerance (scaled with the
//!   geometry) within the case's stated number of ticks after its
//!   disturbance ends, and no failed tick from then on; a case that cannot
//!   recover must fail as counted, named failures (`failure_kinds`), and
//!   its report must not say "kept".
//!
//! No timing: every figure is deterministic. The matrix's sweeps (masses,
//! geometry, gains, rates, the fast hand and the 1 m step) and the million
//! ticks take minutes each unoptimised (the whole module about 14 minutes), so
//! a debug build skips them: `cargo test --release` runs them all.

mod dead_point;
mod edit;
mod four_bar;
mod harness;
mod joint_extremes;
mod long_run;
mod matrix;
mod stewart;
