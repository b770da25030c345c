//! Shared builders and drivers of the inertial-motion tests.
#![allow(dead_code)] // shared by the test modules; not every module uses every helper

use std::time::Duration;

use haptloop_solver::geometry::{ContactSettings, Shape};
use haptloop_solver::{Model, SolverSettings};

pub use crate::contact_common::Lockstep;

/// g, m/s².
pub const G: f64 = 9.81;

/// The two rates every check runs at, Hz.
pub const RATES: [u32; 2] = [1000, 250];

/// Inertial motion with the solver's defaults otherwise.
pub fn dynamics() -> SolverSettings {
    SolverSettings {
        dynamics: true,
        ..SolverSettings::default()
    }
}

/// A box shape of half extents `h`.
pub fn cuboid(h: [f64; 3]) -> Shape {
    Shape::Box { half_extents_m: h }
}

/// The fast loop at `rate_hz` with the slow loop's contact cycle every 5
/// ms, and the contact speed limit the session sets (contact distance per
/// cycle).
pub fn lockstep(model: Model, rate_hz: u32) -> Lockstep {
    let contact = ContactSettings::default();
    let every = (rate_hz as u64 * 5 / 1000).max(1);
    let settings = SolverSettings {
        contact_step_m: contact.contact_distance_m / every as f64,
        ..dynamics()
    };
    let mut l = Lockstep::with_settings(model, settings, contact);
    l.every = every;
    l.dt = period(rate_hz);
    l
}

/// One period at `rate_hz`.
pub fn period(rate_hz: u32) -> Duration {
    Duration::from_nanos(1_000_000_000 / u64::from(rate_hz))
}

/// Ticks in `seconds` at `rate_hz`.
pub fn ticks(seconds: f64, rate_hz: u32) -> usize {
    (seconds * f64::from(rate_hz)).round() as usize
}

/// |a − b| / |b|.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}
