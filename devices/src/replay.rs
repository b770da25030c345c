//! [`ReplayDevice`]: plays a recorded [`Trace`] back as a device, so a
//! deterministic session driven by it reproduces the recorded session bit
//! for bit, and says where it does not.
//!
//! `read(now)` returns the reading built from the counts and gimbal
//! orientation of the last row whose time is ≤ `now` (the same conversion a
//! live device uses: [`crate::PhantomModel::reading_from_counts`], or
//! [`crate::VirtualParams::reading_from_counts`] for a `virtual` trace); before the
//! first row it reports [`DeviceFault::Dropped`], and more than one period
//! past the last row [`DeviceFault::Disconnected`]: a trace that ends is a
//! device that went away, so the safety layer latches and cuts force.
//!
//! `write` runs the arm's own motor model ([`MotorDrive`]: thermal cut,
//! Jᵀ at the sensed angles of the replayed counts, saturation) on the force
//! it is sent, as the simulated arm does, so the produced force, thermal cuts
//! and saturations are those of the recording. It also compares that force
//! with the row's recorded `out_*`: a replay of the same scene with the same
//! settings sends exactly the recorded force on every tick; the first tick
//! that differs ([`ReplayCheck`]) means the trace is not this session's
//! recording (another scene's rows under an edited header, other flags).
//!
//! # Real-time
//! `read` advances a cursor (amortised O(1)); no allocation.

use std::time::Duration;

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

use crate::device::{Device, DeviceFault, DeviceInfo, DeviceReading, MotorReport};
use crate::error::DeviceError;
use crate::phantom::{MotorDrive, PhantomModel};
use crate::trace::Trace;
use crate::virtual_device::{VIRTUAL_MODEL, VirtualParams};

/// How recorded counts become a reading.
#[derive(Debug, Clone, Copy)]
enum Counts {
    /// A PHANToM's joint encoders.
    Phantom(&'static PhantomModel),
    /// A virtual device's tip in micrometres.
    Virtual(VirtualParams),
}

/// How a replay's forces compared with the recording's.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ReplayCheck {
    /// Ticks whose force sent to the device was compared with the row's
    /// recorded `out_*`.
    pub compared: u64,
    /// Of those, ticks where the two differ (bit for bit).
    pub diverged: u64,
    /// Session time of the first tick that differs.
    pub first_divergence: Option<Duration>,
    /// Largest |sent − recorded|, N.
    pub max_difference_n: f64,
}

/// A device that replays recorded encoder counts.
#[derive(Debug, Clone)]
pub struct ReplayDevice {
    model: Counts,
    info: DeviceInfo,
    trace: Trace,
    cursor: usize,
    /// The arm's motor model (a virtual device has none: it clamps to its
    /// peak, [`VirtualParams::applied`]).
    drive: Option<MotorDrive>,
    /// Jacobian at the angles of the counts read last.
    sensed_jacobian: Matrix3<f64>,
    /// The row whose recorded force the last write was compared with.
    compared_row: Option<usize>,
    check: ReplayCheck,
}

impl ReplayDevice {
    /// A replay of `trace`; its header's model must be a known model (a
    /// PHANToM or `virtual`).
    pub fn new(trace: Trace) -> Result<Self, DeviceError> {
        let (model, info, drive, sensed_jacobian) = if trace.header.model == VIRTUAL_MODEL {
            let params = VirtualParams::for_rate_hz(trace.header.rate_hz);
            (
                Counts::Virtual(params),
                params.info(),
                None,
                Matrix3::identity(),
            )
        } else {
            let m = PhantomModel::by_name(&trace.header.model)?;
            let j = m.geometry.jacobian(&Vector3::zeros());
            (
                Counts::Phantom(m),
                m.info(),
                Some(MotorDrive::new(m, true, true)),
                j,
            )
        };
        Ok(Self {
            model,
            info,
            trace,
            cursor: 0,
            drive,
            sensed_jacobian,
            compared_row: None,
            check: ReplayCheck::default(),
        })
    }

    /// The trace being replayed.
    pub fn trace(&self) -> &Trace {
        &self.trace
    }

    /// Time of the last row: how far the trace reaches.
    pub fn end(&self) -> Duration {
        self.trace.rows.last().map_or(Duration::ZERO, |r| r.time)
    }

    /// True once `read` has reached the last row.
    pub fn finished(&self) -> bool {
        self.cursor + 1 >= self.trace.rows.len()
    }

    /// How the forces sent so far compare with the recording's.
    pub fn check(&self) -> ReplayCheck {
        self.check
    }

    /// Compares the first force written at a row's own time with the force
    /// recorded there.
    fn compare(&mut self, force_n_device: &Vector3<f64>, now: Duration) {
        let Some(row) = self.trace.rows.get(self.cursor) else {
            return;
        };
        if row.time != now || self.compared_row == Some(self.cursor) {
            return;
        }
        self.compared_row = Some(self.cursor);
        self.check.compared += 1;
        let recorded = row.output_n_device;
        let same = force_n_device
            .iter()
            .zip(recorded.iter())
            .all(|(a, b)| a.to_bits() == b.to_bits());
        if !same {
            self.check.diverged += 1;
            self.check.first_divergence.get_or_insert(now);
            let d = (force_n_device - recorded).norm();
            // A NaN difference (a non-finite force) counts as the largest.
            if d.is_nan() || d > self.check.max_difference_n {
                self.check.max_difference_n = d;
            }
        }
    }
}

impl Device for ReplayDevice {
    fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn read(&mut self, now: Duration) -> Result<DeviceReading, DeviceFault> {
        let rows = &self.trace.rows;
        while self.cursor + 1 < rows.len() && rows[self.cursor + 1].time <= now {
            self.cursor += 1;
        }
        let period =
            Duration::from_nanos(1_000_000_000 / u64::from(self.trace.header.rate_hz.max(1)));
        match rows.get(self.cursor) {
            Some(row) if self.cursor + 1 == rows.len() && now > row.time + period => {
                Err(DeviceFault::Disconnected)
            }
            Some(row) if row.time <= now => {
                let mut r = match self.model {
                    Counts::Phantom(m) => {
                        let r = m.reading_from_counts(&row.counts, now);
                        self.sensed_jacobian = m.geometry.jacobian(&r.joint_angles_rad);
                        r
                    }
                    Counts::Virtual(_) => VirtualParams::reading_from_counts(&row.counts, now),
                };
                let [w, x, y, z] = row.orientation_wxyz;
                r.orientation_device = UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z));
                Ok(r)
            }
            _ => Err(DeviceFault::Dropped),
        }
    }

    fn write(
        &mut self,
        force_n_device: Vector3<f64>,
        now: Duration,
    ) -> Result<MotorReport, DeviceFault> {
        self.compare(&force_n_device, now);
        Ok(match (&mut self.drive, self.model) {
            (Some(d), _) => d.write(force_n_device, &self.sensed_jacobian, now),
            (None, Counts::Virtual(p)) => p.applied(force_n_device),
            (None, Counts::Phantom(_)) => MotorReport::off(),
        })
    }

    fn motors_off(&mut self, now: Duration) {
        if let Some(d) = &mut self.drive {
            d.off(now);
        }
    }
}
