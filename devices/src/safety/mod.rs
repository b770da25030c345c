//! The safety layer: [`SafeDevice`] wraps every device, so the fast loop can
//! only reach a motor through it.
//!
//! Read path: software watchdog → device read → reject non-finite, dropped,
//! jumped or signal-lost readings (hold the last good one and flag it; latch the
//! fault and cut force when it persists or is fatal) → speed estimate.
//!
//! Write path, in order: NaN/∞ guard (zero force, fault counted) → latched
//! fault (zero) → velocity limit (zero, then re-ramp) → peak clamp (direction
//! kept) → ramp → rate limit → device (thermal cut, torque saturation). Every
//! stage that acts is counted ([`SafetyCounters`]) and the primary one is kept
//! as the [`CutRecord`] of why force was last cut.
//!
//! # Decreasing force is never limited
//! The rate limit bounds how fast force can *grow or turn*, never how fast it
//! falls: a command is first split into the part that shrinks the last output
//! toward zero (its projection onto the segment from 0 to the last output),
//! which passes at once, and the rest, which may change by at most
//! `max_force_rate_n_per_s × loop_period` per write. So a zero command, a force
//! cut and a stop ([`SafeDevice::stop`]) reach zero force on the same write,
//! and a write after a gap (a host stall) is bounded by one period's step, not
//! by the length of the gap.
//!
//! # Recovery after a stall
//! When writes stop for longer than the watchdog timeout the motors go off. On
//! re-engagement force ramps back over a time proportionate to the gap:
//! [`RECOVERY_RAMP_PER_GAP`] × the gap, at most [`SafetyConfig::ramp`] (so a
//! 3 ms stall ramps back in 30 ms, a stall of 100 ms or more over the full
//! start-up ramp), and never shorter than what was left of a ramp under way
//! (a stall during the start-up ramp does not cut it short). Start-up, a
//! cleared fault and a velocity cut always use the full ramp.
//!
//! # Real-time
//! `read` and `write` allocate nothing, take no locks and make no syscalls;
//! their cost is the device's plus O(1) work (the speed estimate scans at most
//! 128 samples).

mod config;
mod events;
mod velocity;

pub use config::SafetyConfig;
pub use events::{CutReason, CutRecord, CutSet, FaultRecord, SafetyCounters, SafetyEvent};
pub use velocity::VelocityEstimator;

use std::time::Duration;

use nalgebra::Vector3;

use crate::device::{Device, DeviceFault, DeviceReading, MotorReport, ReadingFlags};
use crate::error::DeviceError;
use crate::fault::FaultKind;

/// Re-engagement ramp per unit of stall: after writes stopped for a gap `g`,
/// force ramps back over `RECOVERY_RAMP_PER_GAP × g` (capped at the start-up
/// ramp). Ten times the gap: the hand has been unsupported for `g`, so force
/// returns an order of magnitude more slowly than it vanished.
pub const RECOVERY_RAMP_PER_GAP: u32 = 10;

/// Health of a wrapped device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Health {
    /// Readings are fresh, force is allowed.
    Ok,
    /// The last reading was bad and the previous good one is being held.
    Holding(FaultKind),
    /// A fault is latched: force is cut until [`SafeDevice::clear_fault`].
    Fault(FaultKind),
}

/// What one write did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WriteOutcome {
    /// Force sent to the device after the safety stages, newtons, device frame.
    pub force_n_device: Vector3<f64>,
    /// What the device's motors did with it.
    pub motor: MotorReport,
    /// Stages that acted this tick.
    pub cuts: CutSet,
}

/// A device behind the safety layer. See the [module docs](self).
#[derive(Debug)]
pub struct SafeDevice<D> {
    device: D,
    config: SafetyConfig,
    peak_force_n: f64,
    last_good: Option<DeviceReading>,
    bad_run: u32,
    holding: Option<FaultKind>,
    latched: Option<FaultKind>,
    velocity: VelocityEstimator,
    last_output: Vector3<f64>,
    last_write: Option<Duration>,
    ramp_start: Option<Duration>,
    /// Length of the ramp that `ramp_start` begins.
    ramp_len: Duration,
    watchdog_fired: bool,
    pending: CutSet,
    counters: SafetyCounters,
    last_cut: Option<CutRecord>,
    last_fault: Option<FaultRecord>,
}

impl<D: Device> SafeDevice<D> {
    /// Wraps `device`; arms its hardware watchdog (if any) with the software
    /// watchdog's timeout.
    pub fn new(mut device: D, config: SafetyConfig) -> Result<Self, DeviceError> {
        config.validate()?;
        let peak_force_n = config
            .peak_force_n
            .unwrap_or(device.info().limits.peak_force_n);
        device.set_hardware_watchdog(Some(config.watchdog_timeout()));
        Ok(Self {
            device,
            config,
            peak_force_n,
            last_good: None,
            bad_run: 0,
            holding: None,
            latched: None,
            velocity: VelocityEstimator::new(config.velocity_window),
            last_output: Vector3::zeros(),
            last_write: None,
            ramp_start: None,
            ramp_len: config.ramp,
            watchdog_fired: false,
            pending: CutSet::default(),
            counters: SafetyCounters::default(),
            last_cut: None,
            last_fault: None,
        })
    }

    /// The wrapped device.
    pub fn device(&self) -> &D {
        &self.device
    }

    /// The wrapped device, mutably (set-up, inspection; not for bypassing).
    pub fn device_mut(&mut self) -> &mut D {
        &mut self.device
    }

    /// The limits in force.
    pub fn config(&self) -> &SafetyConfig {
        &self.config
    }

    /// Event counters.
    pub fn counters(&self) -> &SafetyCounters {
        &self.counters
    }

    /// Why force was last cut or limited, if ever.
    pub fn last_cut(&self) -> Option<CutRecord> {
        self.last_cut
    }

    /// The last fault detected, if any.
    pub fn last_fault(&self) -> Option<FaultRecord> {
        self.last_fault
    }

    /// Current health.
    pub fn health(&self) -> Health {
        match (self.latched, self.holding) {
            (Some(k), _) => Health::Fault(k),
            (None, Some(k)) => Health::Holding(k),
            (None, None) => Health::Ok,
        }
    }

    /// Current tip-speed estimate, m/s.
    pub fn speed_m_per_s(&self) -> f64 {
        self.velocity.speed()
    }

    /// Clears a latched fault (after the cause is fixed): the next reading is
    /// accepted as the new reference (re-homing) and force ramps up again.
    pub fn clear_fault(&mut self) {
        self.latched = None;
        self.holding = None;
        self.bad_run = 0;
        self.last_good = None;
        self.velocity.clear();
        self.restart_ramp(self.config.ramp);
    }

    /// Stops the device: zero force on this write (no rate limit delays it)
    /// and the motors switched off. The next [`write`](Self::write) re-engages
    /// with the full start-up ramp.
    ///
    /// # Real-time
    /// No allocation, no locks; the device's write and motors-off.
    pub fn stop(&mut self, now: Duration) -> WriteOutcome {
        let out = self.write(Vector3::zeros(), now);
        self.device.motors_off(now);
        self.restart_ramp(self.config.ramp);
        out
    }

    fn restart_ramp(&mut self, len: Duration) {
        self.ramp_start = None;
        self.ramp_len = len;
    }

    /// Reads the device at `now`; always returns a reading: the fresh one, or
    /// the last good one flagged [`ReadingFlags::HELD`] plus the cause.
    ///
    /// # Real-time
    /// No allocation, no locks; the device's read plus O(1).
    pub fn read(&mut self, now: Duration) -> DeviceReading {
        self.software_watchdog(now);
        let fresh = self.device.read(now);
        let bad = match fresh {
            Err(DeviceFault::Disconnected) => Some((
                FaultKind::Disconnected,
                ReadingFlags::DISCONNECTED,
                None,
                true,
            )),
            Err(DeviceFault::Dropped) => Some((
                FaultKind::DroppedReading,
                ReadingFlags::DROPPED,
                None,
                false,
            )),
            Ok(r) if !r.is_finite() => Some((
                FaultKind::NonFiniteReading,
                ReadingFlags::NON_FINITE,
                None,
                false,
            )),
            Ok(r) if r.flags.contains(ReadingFlags::ENCODER_SIGNAL_LOST) => {
                let mask = r.flags.joint_mask();
                let flags =
                    ReadingFlags::ENCODER_SIGNAL_LOST.with(ReadingFlags(u16::from(mask) << 8));
                Some((
                    FaultKind::EncoderSignalLost,
                    flags,
                    Some(mask.trailing_zeros() as u8),
                    true,
                ))
            }
            Ok(r) => self.jumped_joint(&r).map(|j| {
                (
                    FaultKind::EncoderJump,
                    ReadingFlags::ENCODER_JUMP.with(ReadingFlags::joint(j)),
                    Some(j as u8),
                    false,
                )
            }),
        };
        match (fresh, bad) {
            (Ok(r), None) => {
                if r.flags.contains(ReadingFlags::MOTORS_OFF) && !self.watchdog_fired {
                    self.fire_watchdog(now);
                }
                self.bad_run = 0;
                self.holding = None;
                let limits = &self.device.info().limits;
                let (lo, hi) = (limits.workspace_min_m_device, limits.workspace_max_m_device);
                if (0..3).any(|i| r.tip_m_device[i] < lo[i] || r.tip_m_device[i] > hi[i]) {
                    self.counters.outside_workspace += 1;
                }
                self.last_good = Some(r);
                self.velocity.push(now, r.tip_m_device);
                r
            }
            (_, Some((kind, flags, joint, fatal))) => self.hold(now, kind, flags, joint, fatal),
            // `bad` is None only for Ok readings.
            (Err(_), None) => self.hold(
                now,
                FaultKind::DroppedReading,
                ReadingFlags::DROPPED,
                None,
                false,
            ),
        }
    }

    /// Commands `force_n_device` (newtons, device frame) through every safety
    /// stage at `now`.
    ///
    /// # Real-time
    /// No allocation, no locks; the device's write plus O(1).
    pub fn write(&mut self, force_n_device: Vector3<f64>, now: Duration) -> WriteOutcome {
        let mut cuts = std::mem::take(&mut self.pending);
        let requested = force_n_device.norm();
        let out = if !force_n_device.iter().all(|v| v.is_finite()) {
            self.counters.record_fault(FaultKind::NonFiniteForce);
            self.last_fault = Some(FaultRecord {
                kind: FaultKind::NonFiniteForce,
                joint: None,
                at: now,
            });
            cuts.insert(CutReason::NonFiniteForce);
            Vector3::zeros()
        } else if self.latched.is_some() {
            cuts.insert(CutReason::Fault);
            Vector3::zeros()
        } else if self.velocity.speed() > self.config.max_speed_m_per_s {
            cuts.insert(CutReason::Velocity);
            self.restart_ramp(self.config.ramp);
            Vector3::zeros()
        } else {
            self.limit(force_n_device, now, &mut cuts)
        };
        let motor = match self.device.write(out, now) {
            Ok(m) => m,
            Err(fault) => {
                if fault == DeviceFault::Disconnected {
                    self.latch(FaultKind::Disconnected, None, now);
                }
                MotorReport::off()
            }
        };
        if motor.thermal_limited {
            cuts.insert(CutReason::Thermal);
        }
        if motor.saturated {
            cuts.insert(CutReason::MotorSaturation);
        }
        self.last_output = out;
        self.last_write = Some(now);
        self.watchdog_fired = false;
        self.counters.writes += 1;
        self.counters.record_tick(cuts);
        if let Some(reason) = cuts.primary() {
            self.last_cut = Some(CutRecord {
                reason,
                at: now,
                requested_n: requested,
                applied_n: motor.force_n_device.norm(),
            });
        }
        WriteOutcome {
            force_n_device: out,
            motor,
            cuts,
        }
    }

    /// Clamp, ramp and rate limit of a finite force.
    fn limit(&mut self, force: Vector3<f64>, now: Duration, cuts: &mut CutSet) -> Vector3<f64> {
        let mut f = force;
        let norm = f.norm();
        if norm > self.peak_force_n {
            f *= self.peak_force_n / norm;
            cuts.insert(CutReason::Clamp);
        }
        let start = *self.ramp_start.get_or_insert(now);
        let ramp_s = self.ramp_len.as_secs_f64();
        let s = if ramp_s > 0.0 {
            ((now - start.min(now)).as_secs_f64() / ramp_s).min(1.0)
        } else {
            1.0
        };
        if s < 1.0 && norm > 0.0 {
            f *= s;
            cuts.insert(CutReason::Ramp);
        }
        // One period's step, whatever the gap since the last write: a write
        // after a stall must not jump by the stall's worth of rate.
        let max_step = self.config.max_force_rate_n_per_s * self.config.loop_period.as_secs_f64();
        let shrunk = shrink_toward_zero(&self.last_output, &f);
        let rest = f - shrunk;
        let step = rest.norm();
        if step > max_step {
            f = shrunk + rest * (max_step / step);
            cuts.insert(CutReason::RateLimit);
        }
        f
    }

    fn software_watchdog(&mut self, now: Duration) {
        if let Some(w) = self.last_write
            && !self.watchdog_fired
            && now.saturating_sub(w) > self.config.watchdog_timeout()
        {
            self.device.motors_off(now);
            self.fire_watchdog(now);
        }
    }

    fn fire_watchdog(&mut self, now: Duration) {
        self.watchdog_fired = true;
        let gap = self
            .last_write
            .map_or(Duration::ZERO, |w| now.saturating_sub(w));
        // A stall never shortens a ramp under way (the start-up ramp above
        // all): the new ramp lasts at least what was left of the old one.
        let left = match self.ramp_start {
            Some(start) => self.ramp_len.saturating_sub(now.saturating_sub(start)),
            None => self.ramp_len,
        };
        let len = self.config.ramp.min(gap * RECOVERY_RAMP_PER_GAP).max(left);
        self.restart_ramp(len);
        self.last_cut = Some(CutRecord {
            reason: CutReason::Watchdog,
            at: now,
            requested_n: self.last_output.norm(),
            applied_n: 0.0,
        });
        self.last_output = Vector3::zeros();
        self.pending.insert(CutReason::Watchdog);
    }

    fn jumped_joint(&self, r: &DeviceReading) -> Option<usize> {
        let last = self.last_good?;
        let dt = r
            .time
            .saturating_sub(last.time)
            .max(self.config.loop_period)
            .as_secs_f64();
        let counts_per_rev = self.device.info().counts_per_rev;
        (0..3).find(|&j| {
            let per_rad = f64::from(counts_per_rev[j]) / std::f64::consts::TAU;
            let allowed = (self.config.max_joint_speed_rad_per_s * dt * per_rad).ceil() + 2.0;
            f64::from(r.joint_counts[j].abs_diff(last.joint_counts[j])) > allowed
        })
    }

    fn hold(
        &mut self,
        now: Duration,
        kind: FaultKind,
        flags: ReadingFlags,
        joint: Option<u8>,
        fatal: bool,
    ) -> DeviceReading {
        self.counters.record_fault(kind);
        self.counters.held_readings += 1;
        self.last_fault = Some(FaultRecord {
            kind,
            joint,
            at: now,
        });
        self.bad_run += 1;
        self.holding = Some(kind);
        if fatal || self.bad_run > self.config.max_consecutive_bad_readings {
            self.latch(kind, joint, now);
        }
        let mut r = self.last_good.unwrap_or_else(|| DeviceReading::home(now));
        r.time = now;
        r.flags = r.flags.with(ReadingFlags::HELD).with(flags);
        r
    }

    fn latch(&mut self, kind: FaultKind, joint: Option<u8>, now: Duration) {
        if self.latched.is_none() {
            self.latched = Some(kind);
            self.last_fault = Some(FaultRecord {
                kind,
                joint,
                at: now,
            });
            self.device.motors_off(now);
            self.last_output = Vector3::zeros();
            self.restart_ramp(self.config.ramp);
        }
    }
}

/// The part of `command` that only shrinks `last` toward zero: the point of the
/// segment from 0 to `last` nearest to `command`. Moving there never increases
/// force, so the rate limit lets it through at once.
fn shrink_toward_zero(last: &Vector3<f64>, command: &Vector3<f64>) -> Vector3<f64> {
    let l2 = last.norm_squared();
    if l2 == 0.0 {
        return Vector3::zeros();
    }
    last * (command.dot(last) / l2).clamp(0.0, 1.0)
}
