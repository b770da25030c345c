//! [`ReplayDevice`]: plays a recorded [`Trace`] back as a device, so a
//! deterministic session driven by it reproduces the recorded forces bit for bit.
//!
//! `read(now)` returns the reading built from the counts of the last row whose
//! time is ≤ `now` (the same conversion a live device uses:
//! [`crate::PhantomModel::reading_from_counts`]); before the first row it
//! reports [`DeviceFault::Dropped`]. The gimbal is not recorded, so the
//! orientation is the identity. `write` moves nothing; it reports the force
//! as produced so the safety layer sees a healthy device.
//!
//! # Real-time
//! `read` advances a cursor (amortised O(1)); no allocation.

use std::time::Duration;

use nalgebra::Vector3;

use crate::device::{Device, DeviceFault, DeviceInfo, DeviceReading, MotorReport};
use crate::error::DeviceError;
use crate::phantom::PhantomModel;
use crate::trace::Trace;

/// A device that replays recorded encoder counts.
#[derive(Debug, Clone)]
pub struct ReplayDevice {
    model: &'static PhantomModel,
    info: DeviceInfo,
    trace: Trace,
    cursor: usize,
}

impl ReplayDevice {
    /// A replay of `trace`; its header's model must be a known model.
    pub fn new(trace: Trace) -> Result<Self, DeviceError> {
        let model = PhantomModel::by_name(&trace.header.model)?;
        Ok(Self {
            model,
            info: model.info(),
            trace,
            cursor: 0,
        })
    }

    /// The trace being replayed.
    pub fn trace(&self) -> &Trace {
        &self.trace
    }

    /// True once `read` has reached the last row.
    pub fn finished(&self) -> bool {
        self.cursor + 1 >= self.trace.rows.len()
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
        match rows.get(self.cursor) {
            Some(row) if row.time <= now => Ok(self.model.reading_from_counts(&row.counts, now)),
            _ => Err(DeviceFault::Dropped),
        }
    }

    fn write(
        &mut self,
        force_n_device: Vector3<f64>,
        _now: Duration,
    ) -> Result<MotorReport, DeviceFault> {
        if !force_n_device.iter().all(|v| v.is_finite()) {
            return Ok(MotorReport::off());
        }
        Ok(MotorReport {
            force_n_device,
            ..MotorReport::off()
        })
    }

    fn motors_off(&mut self, _now: Duration) {}
}
