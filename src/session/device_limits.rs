//! What each device's own limits did during a session — the workspace
//! stops, the peak-force clamp and the motors' saturation, the thermal cut —
//! and, for a replayed device, whether the replay reproduced its recording.
//! The report turns these into warnings: a force the user was meant to feel
//! and did not, said next to the figures that assume they did.

use super::rig::{Rig, SessionDevice};
use haptloop_devices::{CutReason, Device, ReplayCheck};

/// One device's limits over a session, in ticks.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceLimitTicks {
    /// Scene name of the device.
    pub device: String,
    /// Its model.
    pub model: String,
    /// Ticks whose reading had the tip outside the workspace box: the arm
    /// was at (or pushed past) a mechanical stop.
    pub outside_workspace: u64,
    /// Ticks the safety layer clamped the command to the peak force.
    pub peak_clamp: u64,
    /// Ticks a motor torque saturated inside the device.
    pub motor_saturation: u64,
    /// Ticks the thermal model cut the force to the continuous rating.
    pub thermal_cut: u64,
    /// Peak force, N.
    pub peak_force_n: f64,
    /// Continuous force, N.
    pub continuous_force_n: f64,
    /// A replayed device: how its forces compared with the recording's.
    pub replay: Option<ReplayCheck>,
}

impl DeviceLimitTicks {
    /// Every device of `rig`, scene order.
    pub fn of(rig: &Rig) -> Vec<DeviceLimitTicks> {
        rig.devices
            .iter()
            .map(|d| {
                let c = d.device.counters();
                let info = d.device.device().info();
                DeviceLimitTicks {
                    device: d.name.clone(),
                    model: info.model.to_string(),
                    outside_workspace: c.outside_workspace,
                    peak_clamp: c.cut_ticks(CutReason::Clamp),
                    motor_saturation: c.cut_ticks(CutReason::MotorSaturation),
                    thermal_cut: c.cut_ticks(CutReason::Thermal),
                    peak_force_n: info.limits.peak_force_n,
                    continuous_force_n: info.limits.continuous_force_n,
                    replay: match d.device.device() {
                        SessionDevice::Replay(r) => Some(r.check()),
                        SessionDevice::Sim(_) | SessionDevice::Virtual(_) => None,
                    },
                }
            })
            .collect()
    }
}
