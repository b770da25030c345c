//! The [`Device`] trait: what the fast loop needs from a force-feedback arm,
//! simulated or real, and the small `Copy` values that cross it.
//!
//! # Contract for implementors (simulated or a real driver)
//!
//! A driver for OpenHaptics HD (`hdGetIntegerv(HD_CURRENT_ENCODER_VALUES)`,
//! `hdSetDoublev(HD_CURRENT_FORCE)`), the Force Dimension SDK (`dhdGetPosition`,
//! `dhdSetForce`) or libnifalcon (`runIOLoop` + its kinematics) maps onto it as:
//!
//! * [`Device::read`]: latch the newest encoder counts, convert them to joint
//!   angles and the tip position (forward kinematics), sample buttons, stamp the
//!   reading with the session time it was asked for.
//! * [`Device::write`]: take a Cartesian force in the **device frame** (newtons),
//!   map it to joint torques with the transposed Jacobian at the sensed
//!   configuration (τ = Jᵀ F), apply the device's own limits (motor saturation,
//!   thermal protection) and report what was actually commanded.
//! * [`Device::motors_off`]: zero torque now (watchdog, faults).
//! * [`Device::set_hardware_watchdog`]: arm a device-side watchdog if the device
//!   has one (`dhdSetWatchdog`); the safety layer keeps a software one anyway.
//!
//! Neither `read` nor `write` may allocate, lock, print or block beyond one
//! device round trip: they run on the pinned fast thread every tick. Transient
//! problems are reported as [`DeviceFault`] values (`Copy`, heap-free); the
//! [`crate::safety::SafeDevice`] wrapper turns them into held readings, cut
//! force and counters.

use std::time::Duration;

use nalgebra::{UnitQuaternion, Vector3};

/// Number of actuated (and encoded) arm joints of every supported model.
pub const ARM_JOINTS: usize = 3;

/// One sample of the device, as the fast loop sees it.
///
/// Everything is in the **device frame**: metres, origin at the calibration
/// (home) pose, x to the user's right, y up, z toward the user (the OpenHaptics
/// convention).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceReading {
    /// Session time the reading belongs to (the `now` passed to `read`).
    pub time: Duration,
    /// Raw encoder counts of the three actuated joints (0 at the home pose).
    pub joint_counts: [i32; ARM_JOINTS],
    /// Joint angles in radians recovered from the counts (quantised).
    pub joint_angles_rad: Vector3<f64>,
    /// Tip (gimbal centre) position, metres, device frame.
    pub tip_m_device: Vector3<f64>,
    /// Stylus orientation sensed by the gimbal, device frame. The gimbal is
    /// sensed but not actuated on the modelled arms: no torque is rendered.
    pub orientation_device: UnitQuaternion<f64>,
    /// Button bit mask (bit 0 = primary stylus button).
    pub buttons: u8,
    /// Status bits set by the device or the safety layer.
    pub flags: ReadingFlags,
}

impl DeviceReading {
    /// A reading at the home pose with nothing set, used before the first good
    /// sample exists.
    pub fn home(time: Duration) -> Self {
        Self {
            time,
            joint_counts: [0; ARM_JOINTS],
            joint_angles_rad: Vector3::zeros(),
            tip_m_device: Vector3::zeros(),
            orientation_device: UnitQuaternion::identity(),
            buttons: 0,
            flags: ReadingFlags::EMPTY,
        }
    }

    /// True when every floating-point field is finite.
    pub fn is_finite(&self) -> bool {
        self.joint_angles_rad.iter().all(|v| v.is_finite())
            && self.tip_m_device.iter().all(|v| v.is_finite())
            && self.orientation_device.coords.iter().all(|v| v.is_finite())
    }
}

/// Status bits of a [`DeviceReading`] (a tiny bit set; `Copy`, no allocation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ReadingFlags(pub u16);

impl ReadingFlags {
    /// Nothing to report.
    pub const EMPTY: Self = Self(0);
    /// The safety layer returned the last good reading instead of this tick's.
    pub const HELD: Self = Self(1 << 0);
    /// The device reports loss of an encoder signal (open wire / no
    /// transitions); joints named by [`ReadingFlags::joint_mask`].
    pub const ENCODER_SIGNAL_LOST: Self = Self(1 << 1);
    /// The reading was rejected because a count jumped implausibly far.
    pub const ENCODER_JUMP: Self = Self(1 << 2);
    /// The reading had a non-finite value and was rejected.
    pub const NON_FINITE: Self = Self(1 << 3);
    /// The device delivered no reading this tick.
    pub const DROPPED: Self = Self(1 << 4);
    /// The device is disconnected.
    pub const DISCONNECTED: Self = Self(1 << 5);
    /// Device-side watchdog has switched the motors off.
    pub const MOTORS_OFF: Self = Self(1 << 6);

    /// Bits 8..11 name joints (bit 8 = joint 0) for encoder flags.
    pub const fn joint(j: usize) -> Self {
        Self(1 << (8 + j))
    }

    /// Joint mask (bit j = joint j) carried in bits 8..11.
    pub const fn joint_mask(self) -> u8 {
        ((self.0 >> 8) & 0b111) as u8
    }

    /// True when all bits of `other` are set.
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// Union of two flag sets.
    #[must_use]
    pub const fn with(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }
}

/// A transient problem reported by a device on the fast path (`Copy`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DeviceFault {
    /// No sample arrived this tick (a lost USB/FireWire packet).
    #[error("reading dropped")]
    Dropped,
    /// The device is gone; it stays gone until re-initialised.
    #[error("device disconnected")]
    Disconnected,
}

/// What the motors were actually asked to produce after the device's own
/// limits, returned by [`Device::write`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorReport {
    /// Force the joint torques produce at the tip right now, newtons, device frame.
    pub force_n_device: Vector3<f64>,
    /// Joint torques sent to the motors, newton-metres.
    pub torque_nm: Vector3<f64>,
    /// The thermal model limited the force to the continuous rating.
    pub thermal_limited: bool,
    /// A motor torque saturated; all torques were scaled together.
    pub saturated: bool,
}

impl MotorReport {
    /// A report of zero torque.
    pub fn off() -> Self {
        Self {
            force_n_device: Vector3::zeros(),
            torque_nm: Vector3::zeros(),
            thermal_limited: false,
            saturated: false,
        }
    }
}

/// Limits of a device, in its own frame and units; fill them from
/// `HD_NOMINAL_MAX_FORCE`, `HD_NOMINAL_MAX_CONTINUOUS_FORCE`,
/// `HD_USABLE_WORKSPACE_DIMENSIONS`, `HD_NOMINAL_MAX_STIFFNESS` on real hardware.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceLimits {
    /// Peak force the motors can exert briefly, newtons.
    pub peak_force_n: f64,
    /// Force the motors can sustain without overheating, newtons.
    pub continuous_force_n: f64,
    /// Lower corner of the usable workspace box, metres, device frame.
    pub workspace_min_m_device: Vector3<f64>,
    /// Upper corner of the usable workspace box, metres, device frame.
    pub workspace_max_m_device: Vector3<f64>,
    /// Nominal (datasheet) stiffness of the mechanism, N/m: a structural
    /// figure, not a stable rendering gain.
    pub nominal_stiffness_n_per_m: f64,
    /// Closed-loop stiffness known to be stable at 1 kHz on real hardware, N/m
    /// (CHAI3D's figure); the gain ceiling a scene should respect.
    pub stable_stiffness_1khz_n_per_m: f64,
}

/// Static description of a device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceInfo {
    /// Model name as used in scene files (`phantom-premium-1.5`).
    pub model: &'static str,
    /// Force and workspace limits.
    pub limits: DeviceLimits,
    /// Encoder counts per joint revolution (after the capstan reduction).
    pub counts_per_rev: [u32; ARM_JOINTS],
    /// Degrees of freedom sensed (3 position + 3 gimbal).
    pub sensed_dof: u8,
    /// Degrees of freedom actuated (3: force only, no torque).
    pub actuated_dof: u8,
}

/// A force-feedback arm as the fast loop drives it. See the [module docs](self).
///
/// # Real-time
/// Implementations must not allocate, lock or perform I/O beyond one device
/// round trip in `read`, `write` or `motors_off`, and must run in bounded time.
pub trait Device {
    /// Static description and limits.
    fn info(&self) -> &DeviceInfo;

    /// Samples the device at session time `now` (monotonic; a simulated device
    /// first advances its physics up to `now`).
    ///
    /// # Real-time
    /// No allocation, no locks; bounded by one device round trip (simulated: a
    /// bounded number of physics sub-steps).
    fn read(&mut self, now: Duration) -> Result<DeviceReading, DeviceFault>;

    /// Commands a Cartesian force, newtons, device frame, at session time `now`;
    /// the torque is held until the next write (zero-order hold).
    ///
    /// # Real-time
    /// No allocation, no locks; bounded time. A non-finite force must never
    /// reach a motor: implementations command zero torque instead.
    fn write(
        &mut self,
        force_n_device: Vector3<f64>,
        now: Duration,
    ) -> Result<MotorReport, DeviceFault>;

    /// Zeroes all motor torques immediately (until the next `write`).
    ///
    /// # Real-time
    /// No allocation, no locks; constant time.
    fn motors_off(&mut self, now: Duration);

    /// Arms (Some) or disarms (None) a device-side watchdog that switches the
    /// motors off when no `write` arrives within `timeout`. Returns false when
    /// the device has none. Not for the fast path (setup only).
    fn set_hardware_watchdog(&mut self, timeout: Option<Duration>) -> bool {
        let _ = timeout;
        false
    }

    /// Joint torques the motors apply right now, N·m (zero when they are
    /// off), or `None` when the device cannot report them. Read at the motor,
    /// after every software layer: what shutdown tests check.
    fn applied_torque_nm(&self) -> Option<Vector3<f64>> {
        None
    }
}

impl<D: Device + ?Sized> Device for Box<D> {
    fn info(&self) -> &DeviceInfo {
        (**self).info()
    }
    fn read(&mut self, now: Duration) -> Result<DeviceReading, DeviceFault> {
        (**self).read(now)
    }
    fn write(
        &mut self,
        force_n_device: Vector3<f64>,
        now: Duration,
    ) -> Result<MotorReport, DeviceFault> {
        (**self).write(force_n_device, now)
    }
    fn motors_off(&mut self, now: Duration) {
        (**self).motors_off(now)
    }
    fn set_hardware_watchdog(&mut self, timeout: Option<Duration>) -> bool {
        (**self).set_hardware_watchdog(timeout)
    }
    fn applied_torque_nm(&self) -> Option<Vector3<f64>> {
        (**self).applied_torque_nm()
    }
}
