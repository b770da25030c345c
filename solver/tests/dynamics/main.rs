//! Inertial motion against closed forms (issue 19): free fall, projectiles,
//! torque-free spin, gliding, a pendulum's period and energy, Coulomb
//! friction on an incline and under a push, restitution and a fast ball
//! against a thin plate, each at 1 kHz and at 250 Hz. One binary, a module
//! per area; the fast loop and the slow loop's contact cycle run in
//! lockstep as the session's deterministic mode runs them.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

#[path = "../contact/common.rs"]
mod contact_common;

mod alloc;
mod ballistic;
mod bounce;
mod common;
mod friction;
mod pendulum;
mod twist;
