//! [`SimPhantom`]: a simulated PHANToM arm held by a simulated hand.
//!
//! The tip is a point of the model's apparent mass `m` with viscous damping
//! `b_arm`, driven by the motor force (held joint torques mapped through J⁻ᵀ at
//! the *true* configuration), the hand's grip force and, at the workspace edge,
//! stiff end stops:
//!
//! ```text
//! m v̇ = J(θ)⁻ᵀ τ + k_h (x_target − x) + b_h (v_target − v) − b_arm v + F_stops
//! ```
//!
//! Every `read`/`write`/`motors_off` first integrates this up to the `now` it
//! is given, in equal sub-steps no longer than `loop_period / substeps`
//! (≥ 4 sub-steps per loop period), with velocity Verlet and the damping
//! terms implicit (unconditionally stable for any damping, and free of the
//! phase lead that would make a sampled wall look more stable than it is). The torque written
//! at one tick is held until the next (zero-order hold), as on the real arm.
//! Sensing quantises the true joint angles with the encoders; `write` maps the
//! force with Jᵀ at the *sensed* angles, like a real driver. Same calls with the
//! same times ⇒ bit-identical results (deterministic mode).
//!
//! # Real-time
//! No allocation, no locks, no syscalls. `read`/`write` run at most
//! [`SimPhantom::MAX_SUBSTEPS_PER_CALL`] sub-steps (a longer gap is covered with
//! longer sub-steps), each a few hundred flops.

use std::time::Duration;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use super::drive::MotorDrive;
use super::encoder::Encoder;
use super::options::SimOptions;
use super::{PhantomModel, stops};
use crate::device::{Device, DeviceFault, DeviceInfo, DeviceReading, MotorReport, ReadingFlags};
use crate::error::DeviceError;
use crate::fault::{FaultSchedule, InjectedFault};
use crate::hand::Hand;

/// A simulated PHANToM arm with its simulated hand. See the [module docs](self).
#[derive(Debug, Clone)]
pub struct SimPhantom {
    model: &'static PhantomModel,
    info: DeviceInfo,
    options: SimOptions,
    encoder: Encoder,
    gimbal: Encoder,
    hand: Hand,
    anchor_m_device: Vector3<f64>,
    p: Vector3<f64>,
    v: Vector3<f64>,
    t: Duration,
    max_substep_ns: u64,
    torque_nm: Vector3<f64>,
    motors_on: bool,
    last_write: Duration,
    hw_watchdog: Option<Duration>,
    watchdog_tripped: bool,
    /// Jacobian at the last sensed (quantised) angles: what `write` maps with.
    sensed_jacobian: Matrix3<f64>,
    last_motor_force: Vector3<f64>,
    /// The motors: thermal cut, saturation, the force they report.
    drive: MotorDrive,
    faults: FaultSchedule,
    frozen_counts: [Option<i32>; 3],
    hand_work_j: f64,
    motor_work_j: f64,
    /// Forces at the current state (end of the last sub-step), reused as the
    /// start of the next one; cleared whenever torque or hand change.
    cached_forces: Option<Forces>,
    /// (hand orientation, its quantised reading).
    gimbal_cache: Option<(UnitQuaternion<f64>, UnitQuaternion<f64>)>,
}

/// Forces on the tip at one state, newtons, device frame.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Forces {
    /// Everything but the implicit viscous terms.
    total: Vector3<f64>,
    /// Motor part.
    motor: Vector3<f64>,
    /// Grip spring part.
    grip_spring: Vector3<f64>,
    /// Hand target velocity, m/s.
    target_velocity: Vector3<f64>,
}

impl SimPhantom {
    /// Longest run of sub-steps one call performs.
    pub const MAX_SUBSTEPS_PER_CALL: u64 = 4096;

    /// A simulated arm of `model` held by `hand`, at rest at `options.start_m_device`.
    pub fn new(
        model: &'static PhantomModel,
        options: SimOptions,
        hand: Hand,
    ) -> Result<Self, DeviceError> {
        options.validate()?;
        let (theta, _) = model.geometry.inverse(&options.start_m_device);
        let encoder = Encoder::new(model.counts_per_rev);
        Ok(Self {
            model,
            info: model.info(),
            options,
            encoder,
            gimbal: Encoder::new(model.gimbal_counts_per_rev),
            hand,
            anchor_m_device: options.start_m_device,
            p: options.start_m_device,
            v: Vector3::zeros(),
            t: Duration::ZERO,
            max_substep_ns: (options.loop_period.as_nanos() as u64
                / u64::from(options.substeps_per_period))
            .max(1),
            torque_nm: Vector3::zeros(),
            motors_on: false,
            last_write: Duration::ZERO,
            hw_watchdog: None,
            watchdog_tripped: false,
            sensed_jacobian: model
                .geometry
                .jacobian(&encoder.angles(&encoder.counts(&theta))),
            last_motor_force: Vector3::zeros(),
            drive: MotorDrive::new(model, options.thermal, options.motor_saturation),
            faults: FaultSchedule::default(),
            frozen_counts: [None; 3],
            hand_work_j: 0.0,
            motor_work_j: 0.0,
            cached_forces: None,
            gimbal_cache: None,
        })
    }

    /// Builds the arm for a scene model name (`phantom-premium-1.5`,
    /// `phantom-omni`, `phantom-touch`).
    pub fn by_name(model: &str, options: SimOptions, hand: Hand) -> Result<Self, DeviceError> {
        Self::new(PhantomModel::by_name(model)?, options, hand)
    }

    /// The model simulated.
    pub fn model(&self) -> &'static PhantomModel {
        self.model
    }

    /// Schedules a fault (set-up time).
    pub fn inject(
        &mut self,
        fault: InjectedFault,
        start: Duration,
        duration: Option<Duration>,
    ) -> Result<(), DeviceError> {
        self.faults.inject(fault, start, duration)
    }

    /// The hand holding the arm.
    pub fn hand(&self) -> &Hand {
        &self.hand
    }

    /// Mutable access to the hand (change trajectory, buttons, orientation).
    pub fn hand_mut(&mut self) -> &mut Hand {
        self.cached_forces = None;
        &mut self.hand
    }

    /// The hand's anchor (trajectory origin), metres, device frame.
    pub fn anchor_m_device(&self) -> Vector3<f64> {
        self.anchor_m_device
    }

    /// Time the physics has been integrated to.
    pub fn time(&self) -> Duration {
        self.t
    }

    /// True (unquantised) tip position, metres, device frame.
    pub fn true_tip_m_device(&self) -> Vector3<f64> {
        self.p
    }

    /// True tip velocity, m/s, device frame.
    pub fn true_velocity_m_per_s(&self) -> Vector3<f64> {
        self.v
    }

    /// Kinetic energy of the tip, joules.
    pub fn kinetic_energy_j(&self) -> f64 {
        0.5 * self.model.tip_mass_kg * self.v.norm_squared()
    }

    /// Energy stored in the grip spring now, joules.
    pub fn grip_energy_j(&self) -> f64 {
        let target = self.hand.target(&self.anchor_m_device, self.t).offset_m;
        0.5 * self.hand.grip.stiffness_n_per_m * (target - self.p).norm_squared()
    }

    /// Work done on the system by the moving hand target since the start
    /// (∫ F_grip · v_target dt), joules.
    pub fn hand_work_j(&self) -> f64 {
        self.hand_work_j
    }

    /// Work done by the motors on the tip since the start, joules.
    pub fn motor_work_j(&self) -> f64 {
        self.motor_work_j
    }

    /// True while the motors are energised.
    pub fn motors_on(&self) -> bool {
        self.motors_on
    }

    /// Normalised motor temperature (1 = steady state at the continuous rating).
    pub fn thermal_load(&self) -> f64 {
        self.drive.thermal_load()
    }

    /// Integrates the arm up to `now` (no-op if `now` is not later).
    ///
    /// # Real-time
    /// No allocation; at most [`Self::MAX_SUBSTEPS_PER_CALL`] sub-steps.
    pub fn advance_to(&mut self, now: Duration) {
        if now <= self.t {
            return;
        }
        let gap_ns = (now - self.t).as_nanos() as u64;
        let n = gap_ns
            .div_ceil(self.max_substep_ns)
            .clamp(1, Self::MAX_SUBSTEPS_PER_CALL);
        let h = gap_ns as f64 * 1e-9 / n as f64;
        let t0 = self.t.as_secs_f64();
        for i in 0..n {
            let t_start = t0 + i as f64 * h;
            self.check_hw_watchdog(t_start);
            self.substep(t_start, h);
        }
        self.t = now;
    }

    fn check_hw_watchdog(&mut self, t_s: f64) {
        if let Some(timeout) = self.hw_watchdog
            && self.motors_on
            && t_s >= (self.last_write + timeout).as_secs_f64()
        {
            self.motors_on = false;
            self.torque_nm = Vector3::zeros();
            self.watchdog_tripped = true;
            self.cached_forces = None;
            self.drive.off(Duration::from_secs_f64(t_s));
        }
    }

    /// One velocity-Verlet step of length `h` starting at `t_start_s`, with the
    /// damping terms implicit in each half step. Position advances with the
    /// mean of the start and end half-step velocities, so a force held over the
    /// step (ZOH) moves the tip exactly as it would in continuous time: the
    /// integrator adds no phase lead that would hide the ZOH's destabilising
    /// half-period delay (a semi-implicit Euler step does, and overstates the
    /// stable stiffness by n/(n−1) with n sub-steps).
    fn substep(&mut self, t_start_s: f64, h: f64) {
        let m = self.model.tip_mass_kg;
        let c = (self.model.arm_damping_n_s_per_m + self.hand.grip.damping_n_s_per_m) / m;
        let start = match self.cached_forces.take() {
            Some(f) => f,
            None => self.forces(&self.p, &self.v, t_start_s),
        };
        let v_half = (self.v + start.total * (0.5 * h / m)) / (1.0 + 0.5 * h * c);
        let dp = v_half * h;
        let p_new = self.p + dp;
        let end = self.forces(&p_new, &v_half, t_start_s + h);
        let v_new = (v_half + end.total * (0.5 * h / m)) / (1.0 + 0.5 * h * c);
        // Work bookkeeping for the passivity measurement (trapezoidal in time).
        let b_h = self.hand.grip.damping_n_s_per_m;
        let grip_start = start.grip_spring + (start.target_velocity - self.v) * b_h;
        let grip_end = end.grip_spring + (end.target_velocity - v_new) * b_h;
        self.hand_work_j +=
            0.5 * (grip_start.dot(&start.target_velocity) + grip_end.dot(&end.target_velocity)) * h;
        self.motor_work_j += (0.5 * (start.motor + end.motor)).dot(&dp);
        self.p = p_new;
        self.v = v_new;
        self.last_motor_force = end.motor;
        self.cached_forces = Some(end);
    }

    /// Forces at a state, without the (implicit) viscous terms.
    fn forces(&self, p: &Vector3<f64>, v: &Vector3<f64>, t_s: f64) -> Forces {
        let g = &self.model.geometry;
        let motor = if self.motors_on {
            // At a singular pose keep the last force rather than divide by ~0.
            g.joint_trig_at_position(p)
                .and_then(|t| g.force_for_torques_from_trig(t, &self.torque_nm))
                .unwrap_or(self.last_motor_force)
        } else {
            Vector3::zeros()
        };
        let target = self.hand.trajectory.sample_s(t_s);
        let grip_spring =
            (self.anchor_m_device + target.offset_m - p) * self.hand.grip.stiffness_n_per_m;
        let stops = if self.options.end_stops {
            stops::end_stop_force(self.model, p, v)
        } else {
            Vector3::zeros()
        };
        let total = motor
            + grip_spring
            + target.velocity_m_per_s * self.hand.grip.damping_n_s_per_m
            + stops;
        Forces {
            total,
            motor,
            grip_spring,
            target_velocity: target.velocity_m_per_s,
        }
    }

    /// The stylus orientation as the gimbal encoders report it (roll, pitch,
    /// yaw each quantised), cached while the hand's orientation is unchanged.
    fn quantised_orientation(&mut self) -> UnitQuaternion<f64> {
        let held = self.hand.orientation_device;
        if let Some((q, sensed)) = self.gimbal_cache
            && q == held
        {
            return sensed;
        }
        let (r, p, y) = held.euler_angles();
        let a = self
            .gimbal
            .angles(&self.gimbal.counts(&Vector3::new(r, p, y)));
        let sensed = UnitQuaternion::from_euler_angles(a[0], a[1], a[2]);
        self.gimbal_cache = Some((held, sensed));
        sensed
    }
}

impl Device for SimPhantom {
    fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn read(&mut self, now: Duration) -> Result<DeviceReading, DeviceFault> {
        self.advance_to(now);
        let active = self.faults.active(now);
        if active.disconnected {
            self.motors_on = false;
            self.torque_nm = Vector3::zeros();
            self.cached_forces = None;
            self.drive.off(now);
            return Err(DeviceFault::Disconnected);
        }
        if active.dropped {
            return Err(DeviceFault::Dropped);
        }
        let (theta, _) = self.model.geometry.inverse(&self.p);
        let mut counts = self.encoder.counts(&theta);
        let mut flags = ReadingFlags::EMPTY;
        for (j, count) in counts.iter_mut().enumerate() {
            if active.stuck_mask & (1 << j) != 0 {
                *count = *self.frozen_counts[j].get_or_insert(*count);
                flags = flags
                    .with(ReadingFlags::ENCODER_SIGNAL_LOST)
                    .with(ReadingFlags::joint(j));
            } else {
                self.frozen_counts[j] = None;
            }
            *count = count.saturating_add(active.jump_counts[j]);
        }
        if self.watchdog_tripped && !self.motors_on {
            flags = flags.with(ReadingFlags::MOTORS_OFF);
        }
        // Same conversion as `PhantomModel::reading_from_counts`, fused with the
        // Jacobian the next `write` maps with.
        let angles = self.encoder.angles(&counts);
        let (tip, sensed_jacobian) = self.model.geometry.forward_and_jacobian(&angles);
        let mut reading = DeviceReading {
            time: now,
            joint_counts: counts,
            joint_angles_rad: angles,
            tip_m_device: tip,
            orientation_device: self.quantised_orientation(),
            buttons: self.hand.buttons,
            flags,
        };
        if active.nan {
            reading.joint_angles_rad = Vector3::repeat(f64::NAN);
            reading.tip_m_device = Vector3::repeat(f64::NAN);
        } else {
            self.sensed_jacobian = sensed_jacobian;
        }
        Ok(reading)
    }

    fn write(
        &mut self,
        force_n_device: Vector3<f64>,
        now: Duration,
    ) -> Result<MotorReport, DeviceFault> {
        self.advance_to(now);
        if self.faults.active(now).disconnected {
            self.motors_on = false;
            self.torque_nm = Vector3::zeros();
            self.cached_forces = None;
            self.drive.off(now);
            return Err(DeviceFault::Disconnected);
        }
        self.last_write = now;
        self.watchdog_tripped = false;
        // The motor model maps with the Jacobian at the sensed angles, like a
        // real driver; a non-finite force switches the motors off (defence in
        // depth: the safety layer never sends one).
        let report = self.drive.write(force_n_device, &self.sensed_jacobian, now);
        self.motors_on = force_n_device.iter().all(|v| v.is_finite());
        self.torque_nm = report.torque_nm;
        self.cached_forces = None;
        Ok(report)
    }

    fn motors_off(&mut self, now: Duration) {
        self.advance_to(now);
        self.motors_on = false;
        self.torque_nm = Vector3::zeros();
        self.cached_forces = None;
        self.drive.off(now);
    }

    fn set_hardware_watchdog(&mut self, timeout: Option<Duration>) -> bool {
        self.hw_watchdog = timeout;
        true
    }

    fn applied_torque_nm(&self) -> Option<Vector3<f64>> {
        Some(if self.motors_on {
            self.torque_nm
        } else {
            Vector3::zeros()
        })
    }
}
