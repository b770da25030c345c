//! `summary.json`'s account of the devices' own limits (workspace stops,
//! the peak clamp, saturation, thermal cuts) and of a replay against its
//! recording.

use serde::{Deserialize, Serialize};

/// What one device's own limits did, in ticks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeviceLimits {
    /// Device name.
    pub device: String,
    /// Ticks the tip was outside the workspace box (at a mechanical stop).
    pub outside_workspace_ticks: u64,
    /// Ticks the command was clamped to the peak force.
    pub peak_clamp_ticks: u64,
    /// Ticks a motor torque saturated.
    pub motor_saturation_ticks: u64,
    /// Ticks the thermal model cut the force to the continuous rating.
    pub thermal_cut_ticks: u64,
}

impl From<&crate::session::DeviceLimitTicks> for DeviceLimits {
    fn from(d: &crate::session::DeviceLimitTicks) -> Self {
        DeviceLimits {
            device: d.device.clone(),
            outside_workspace_ticks: d.outside_workspace,
            peak_clamp_ticks: d.peak_clamp,
            motor_saturation_ticks: d.motor_saturation,
            thermal_cut_ticks: d.thermal_cut,
        }
    }
}

/// One replayed device against its recording.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReplayDevice {
    /// Device name.
    pub device: String,
    /// Ticks whose force sent to the device was compared with the recorded
    /// one.
    pub compared: u64,
    /// Of those, ticks where they differ.
    pub diverged: u64,
    /// Session time of the first that differs, s.
    pub first_divergence_s: Option<f64>,
    /// Largest difference, N.
    #[serde(with = "super::figure")]
    pub max_difference_n: f64,
}

/// A replay against its recording: every device's forces, bit for bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Replay {
    /// `reproduced` or `DIVERGED` and where.
    pub verdict: String,
    /// Per device.
    pub devices: Vec<ReplayDevice>,
}

impl Replay {
    pub(crate) fn of(limits: &[crate::session::DeviceLimitTicks]) -> Option<Replay> {
        let devices: Vec<ReplayDevice> = limits
            .iter()
            .filter_map(|d| {
                let r = d.replay?;
                Some(ReplayDevice {
                    device: d.device.clone(),
                    compared: r.compared,
                    diverged: r.diverged,
                    first_divergence_s: r.first_divergence.map(|t| t.as_secs_f64()),
                    max_difference_n: r.max_difference_n,
                })
            })
            .collect();
        if devices.is_empty() {
            return None;
        }
        let compared: u64 = devices.iter().map(|d| d.compared).sum();
        let verdict = match devices.iter().find(|d| d.diverged > 0) {
            None => format!(
                "reproduced: every force sent to the device{} equals the recording's ({compared} writes compared)",
                if devices.len() == 1 { "" } else { "s" }
            ),
            Some(d) => format!(
                "DIVERGED: device `{}` was sent a force that differs from the recording's on {} of {} ticks, \
                 first at t = {} s",
                d.device,
                d.diverged,
                d.compared,
                d.first_divergence_s.unwrap_or(f64::NAN)
            ),
        };
        Some(Replay { verdict, devices })
    }

    /// True if any device's forces differ from the recording's.
    pub fn diverged(&self) -> bool {
        self.devices.iter().any(|d| d.diverged > 0)
    }
}
