//! [`SimOptions`]: how a simulated arm is integrated and which of its limits
//! are modelled.

use std::time::Duration;

use nalgebra::Vector3;

use crate::error::DeviceError;

/// Options of a simulated arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions {
    /// Period of the fast loop that will drive the device (default 1 ms).
    pub loop_period: Duration,
    /// Physics sub-steps per loop period, ≥ 4 (default 4: the minimum;
    /// velocity Verlet with 20 kN/m end stops is stable far beyond it).
    pub substeps_per_period: u32,
    /// Where the tip starts (and the hand's anchor), metres, device frame
    /// (default: the home pose, origin).
    pub start_m_device: Vector3<f64>,
    /// Enforce the continuous-force rating with the thermal model (default true).
    pub thermal: bool,
    /// Saturate motor torques at the peak force (default true).
    pub motor_saturation: bool,
    /// Stop the tip at the workspace box and the arm's reach (default true).
    pub end_stops: bool,
}

impl Default for SimOptions {
    fn default() -> Self {
        Self {
            loop_period: Duration::from_millis(1),
            substeps_per_period: 4,
            start_m_device: Vector3::zeros(),
            thermal: true,
            motor_saturation: true,
            end_stops: true,
        }
    }
}

impl SimOptions {
    /// Default options for a loop running at `rate_hz` ticks per second.
    pub fn for_rate_hz(rate_hz: u32) -> Self {
        Self {
            loop_period: Duration::from_nanos(1_000_000_000 / u64::from(rate_hz.max(1))),
            ..Self::default()
        }
    }

    pub(crate) fn validate(&self) -> Result<(), DeviceError> {
        if self.substeps_per_period < 4 {
            return Err(DeviceError::InvalidConfig {
                what: "substeps_per_period",
                value: self.substeps_per_period.to_string(),
                reason: "the arm must be integrated at least 4x the loop rate",
            });
        }
        if self.loop_period.is_zero()
            || self.loop_period.as_nanos() < u128::from(self.substeps_per_period)
        {
            return Err(DeviceError::InvalidConfig {
                what: "loop_period",
                value: format!("{:?}", self.loop_period),
                reason: "must be at least 1 ns per sub-step",
            });
        }
        if !self.start_m_device.iter().all(|v| v.is_finite()) {
            return Err(DeviceError::InvalidConfig {
                what: "start_m_device",
                value: format!("{:?}", self.start_m_device),
                reason: "must be finite",
            });
        }
        Ok(())
    }
}
