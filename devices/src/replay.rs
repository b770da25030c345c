//! [`ReplayDevice`]: plays a recorded [`Trace`] back as a device, so a
//! deterministic session driven by it reproduces the recorded forces bit for bit.
//!
//! `read(now)` returns the reading built from the counts and gimbal
//! orientation of the last row whose time is ≤ `now` (the same conversion a
//! live device uses: [`crate::PhantomModel::reading_from_counts`], or
//! [`crate::VirtualParams::reading_from_counts`] for a `virtual` trace); before the
//! first row it reports [`DeviceFault::Dropped`], and more than one period
//! past the last row [`DeviceFault::Disconnected`]: a trace that ends is a
//! device that went away, so the safety layer latches and cuts force. `write`
//! moves nothing; it reports the force as produced (a replayed device has no
//! motors), so the safety layer sees a healthy device.
//!
//! # Real-time
//! `read` advances a cursor (amortised O(1)); no allocation.

use std::time::Duration;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::device::{Device, DeviceFault, DeviceInfo, DeviceReading, MotorReport};
use crate::error::DeviceError;
use crate::phantom::PhantomModel;
use crate::trace::Trace;
use crate::virtual_device::{VIRTUAL_MODEL, VirtualParams};

/// How recorded counts become a reading.
#[derive(Debug, Clone, Copy)]
enum Counts {
    /// A PHANToM's joint encoders.
    Phantom(&'static PhantomModel),
    /// A virtual device's tip in micrometres.
    Virtual,
}

/// A device that replays recorded encoder counts.
#[derive(Debug, Clone)]
pub struct ReplayDevice {
    model: Counts,
    info: DeviceInfo,
    trace: Trace,
    cursor: usize,
}

impl ReplayDevice {
    /// A replay of `trace`; its header's model must be a known model (a
    /// PHANToM or `virtual`).
    pub fn new(trace: Trace) -> Result<Self, DeviceError> {
        let (model, info) = if trace.header.model == VIRTUAL_MODEL {
            let params = VirtualParams::for_rate_hz(trace.header.rate_hz);
            (Counts::Virtual, params.info())
        } else {
            let m = PhantomModel::by_name(&trace.header.model)?;
            (Counts::Phantom(m), m.info())
        };
        Ok(Self {
            model,
            info,
            trace,
            cursor: 0,
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
                    Counts::Phantom(m) => m.reading_from_counts(&row.counts, now),
                    Counts::Virtual => VirtualParams::reading_from_counts(&row.counts, now),
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
