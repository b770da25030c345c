//! Helpers shared by the integration tests.

use std::time::Duration;

use haptloop_devices::{Hand, SafeDevice, SafetyConfig, SimOptions, SimPhantom};
use nalgebra::Vector3;

/// 1 kHz loop period.
pub const T: Duration = Duration::from_millis(1);

/// Session time of tick `k` at 1 kHz.
pub fn tick(k: u64) -> Duration {
    T * k as u32
}

/// A simulated arm at 1 kHz behind a safety layer with `config`.
pub fn safe_sim(model: &str, hand: Hand, config: SafetyConfig) -> SafeDevice<SimPhantom> {
    let sim = SimPhantom::by_name(model, SimOptions::for_rate_hz(1000), hand).unwrap();
    SafeDevice::new(sim, config).unwrap()
}

/// Safety config with the ramp and rate limit out of the way, to test one stage.
pub fn no_ramp() -> SafetyConfig {
    SafetyConfig {
        ramp: Duration::ZERO,
        max_force_rate_n_per_s: 1e9,
        ..SafetyConfig::default()
    }
}

/// A virtual floor at y = 0 of stiffness `k` (N/m), from a sampled position.
pub fn wall(k: f64, p: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(0.0, (-p.y).max(0.0) * k, 0.0)
}
