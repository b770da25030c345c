//! [`MotorDrive`]: what the motors of an arm do with a commanded force — the
//! thermal model's continuous-force cut, τ = Jᵀ F at the sensed angles, the
//! torque saturation — and the force they report. The simulated arm and a
//! replayed one run this same model on the same inputs (the force written,
//! the Jacobian of the counts read, the times), so a replay reports the
//! produced force, the thermal cuts and the saturations of the recording bit
//! for bit.
//!
//! The motors heat with the force they hold between writes (zero-order
//! hold, as the torque is held). The force reported is the one the torques
//! produce at the *sensed* configuration: the saturation scales all torques
//! by one factor, so it is the commanded (thermally cut) force times that
//! factor. What the simulated tip feels is J⁻ᵀ τ at the *true* angles, which
//! differs from it by the encoders' quantisation (about 1e-8 of the force).
//!
//! # Real-time
//! Stack arithmetic, at most one `exp` per write: no allocation.

use std::time::Duration;

use nalgebra::{Matrix3, Vector3};

use super::PhantomModel;
use super::motors::MotorLimits;
use super::thermal::ThermalModel;
use crate::device::MotorReport;

/// The motor model of one arm. See the [module docs](self).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorDrive {
    limits: MotorLimits,
    thermal: ThermalModel,
    thermal_on: bool,
    saturation_on: bool,
    /// |force| the motors hold since `since`, N.
    held_n: f64,
    since: Duration,
}

impl MotorDrive {
    /// Cold motors of `model`; `thermal` and `saturation` switch those limits
    /// on.
    pub fn new(model: &PhantomModel, thermal: bool, saturation: bool) -> Self {
        Self {
            limits: MotorLimits::for_peak_force(&model.geometry, model.peak_force_n),
            thermal: ThermalModel::new(model.continuous_force_n, model.thermal_time_constant_s),
            thermal_on: thermal,
            saturation_on: saturation,
            held_n: 0.0,
            since: Duration::ZERO,
        }
    }

    /// Normalised motor temperature (1 = steady state at the continuous
    /// rating), as of the last write or switch-off.
    pub fn thermal_load(&self) -> f64 {
        self.thermal.load()
    }

    /// Heats the motors with the held force up to `now`.
    fn advance(&mut self, now: Duration) {
        if now > self.since {
            if self.thermal_on {
                self.thermal
                    .update(self.held_n, (now - self.since).as_secs_f64());
            }
            self.since = now;
        }
    }

    /// The motors take `force_n_device` at `now`, mapped with the Jacobian
    /// at the sensed angles; a non-finite force switches them off.
    pub fn write(
        &mut self,
        force_n_device: Vector3<f64>,
        sensed_jacobian: &Matrix3<f64>,
        now: Duration,
    ) -> MotorReport {
        self.advance(now);
        if !force_n_device.iter().all(|v| v.is_finite()) {
            self.held_n = 0.0;
            return MotorReport::off();
        }
        let mut force = force_n_device;
        let allowed = if self.thermal_on {
            self.thermal.allowed_force_n()
        } else {
            f64::INFINITY
        };
        let thermal_limited = force.norm() > allowed;
        if thermal_limited {
            force *= allowed / force.norm();
        }
        let tau = sensed_jacobian.transpose() * force;
        let ratio = if self.saturation_on {
            self.limits.ratio(&tau)
        } else {
            1.0
        };
        let (torque_nm, produced) = if ratio < 1.0 {
            (tau * ratio, force * ratio)
        } else {
            (tau, force)
        };
        self.held_n = produced.norm();
        MotorReport {
            force_n_device: produced,
            torque_nm,
            thermal_limited,
            saturated: ratio < 1.0,
        }
    }

    /// The motors are switched off at `now`.
    pub fn off(&mut self, now: Duration) {
        self.advance(now);
        self.held_n = 0.0;
    }
}
