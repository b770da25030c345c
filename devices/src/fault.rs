//! Fault injection (simulated devices) and the fault kinds the safety layer
//! detects and counts.
//!
//! | injected | what the device does | detected as | outcome in [`crate::SafeDevice`] |
//! |---|---|---|---|
//! | [`InjectedFault::NanReading`] | reading carries NaN angles/position | [`FaultKind::NonFiniteReading`] | hold last good reading, flag `NON_FINITE`; a run longer than the limit cuts force (latched) |
//! | [`InjectedFault::DroppedReading`] | `read` returns [`crate::DeviceFault::Dropped`] | [`FaultKind::DroppedReading`] | hold last good reading, flag `DROPPED`; long runs latch and cut |
//! | [`InjectedFault::StuckEncoder`] | one joint's count freezes; the encoder interface reports signal loss | [`FaultKind::EncoderSignalLost`] | cut force at once, latched; reading held |
//! | [`InjectedFault::EncoderJump`] | one joint's count jumps by N counts | [`FaultKind::EncoderJump`] | reading rejected (held, flag `ENCODER_JUMP`); a persistent offset latches and cuts |
//! | [`InjectedFault::Disconnect`] | `read`/`write` return [`crate::DeviceFault::Disconnected`], motors off | [`FaultKind::Disconnected`] | cut force at once, latched; reading held |
//!
//! A frozen count cannot be told from a joint at rest by counts alone, so
//! stuck-encoder detection relies on the interface's signal-loss status (as
//! differential encoder receivers with open-wire detection provide); a driver
//! without that status cannot detect it.
//!
//! # Real-time
//! The schedule is a fixed array: querying it never allocates.

use std::time::Duration;

use crate::device::ARM_JOINTS;
use crate::error::DeviceError;

/// A fault a simulated device can be told to produce.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InjectedFault {
    /// Readings carry NaN.
    NanReading,
    /// The joint's encoder count stops changing (signal lost).
    StuckEncoder {
        /// Joint index 0..3.
        joint: u8,
    },
    /// No reading is delivered.
    DroppedReading,
    /// The device disconnects (motors off, reads and writes fail).
    Disconnect,
    /// The joint's count is offset by `counts` (a glitch or missed index).
    EncoderJump {
        /// Joint index 0..3.
        joint: u8,
        /// Offset added to the count.
        counts: i32,
    },
}

/// A detected fault kind, for counters and health (`Copy`, heap-free).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// A reading held NaN or ∞.
    NonFiniteReading,
    /// The device delivered no reading.
    DroppedReading,
    /// A count changed faster than the arm can move.
    EncoderJump,
    /// The device reported an encoder signal loss.
    EncoderSignalLost,
    /// The device is disconnected.
    Disconnected,
    /// The loop commanded a NaN or ∞ force.
    NonFiniteForce,
}

impl FaultKind {
    /// Number of kinds.
    pub const COUNT: usize = 6;
    /// All kinds, in counter order.
    pub const ALL: [FaultKind; Self::COUNT] = [
        FaultKind::NonFiniteReading,
        FaultKind::DroppedReading,
        FaultKind::EncoderJump,
        FaultKind::EncoderSignalLost,
        FaultKind::Disconnected,
        FaultKind::NonFiniteForce,
    ];

    /// Position in [`FaultKind::ALL`].
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Short name for reports.
    pub const fn name(self) -> &'static str {
        match self {
            FaultKind::NonFiniteReading => "non-finite reading",
            FaultKind::DroppedReading => "dropped reading",
            FaultKind::EncoderJump => "encoder jump",
            FaultKind::EncoderSignalLost => "encoder signal lost",
            FaultKind::Disconnected => "disconnected",
            FaultKind::NonFiniteForce => "non-finite force command",
        }
    }
}

/// A fault active from `start` until `end` (exclusive; `None` = forever).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScheduledFault {
    /// What happens.
    pub fault: InjectedFault,
    /// First session time it is active.
    pub start: Duration,
    /// First session time it is no longer active.
    pub end: Option<Duration>,
}

/// Faults active at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ActiveFaults {
    /// Readings are NaN.
    pub nan: bool,
    /// Reading dropped.
    pub dropped: bool,
    /// Disconnected.
    pub disconnected: bool,
    /// Bit j: joint j's encoder is stuck.
    pub stuck_mask: u8,
    /// Count offset per joint.
    pub jump_counts: [i32; ARM_JOINTS],
}

/// Up to [`FaultSchedule::CAPACITY`] scheduled faults.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FaultSchedule {
    slots: [Option<ScheduledFault>; FaultSchedule::CAPACITY],
}

impl FaultSchedule {
    /// Maximum number of scheduled faults.
    pub const CAPACITY: usize = 8;

    /// Schedules `fault` from `start` for `duration` (None = until the end).
    /// Set-up time only. Joint indices ≥ 3 are an error.
    pub fn inject(
        &mut self,
        fault: InjectedFault,
        start: Duration,
        duration: Option<Duration>,
    ) -> Result<(), DeviceError> {
        if let InjectedFault::StuckEncoder { joint } | InjectedFault::EncoderJump { joint, .. } =
            fault
            && usize::from(joint) >= ARM_JOINTS
        {
            return Err(DeviceError::InvalidConfig {
                what: "fault joint",
                value: joint.to_string(),
                reason: "joints are 0, 1, 2",
            });
        }
        let slot =
            self.slots
                .iter_mut()
                .find(|s| s.is_none())
                .ok_or(DeviceError::FaultScheduleFull {
                    capacity: Self::CAPACITY,
                })?;
        *slot = Some(ScheduledFault {
            fault,
            start,
            end: duration.map(|d| start + d),
        });
        Ok(())
    }

    /// The faults active at `now`.
    pub fn active(&self, now: Duration) -> ActiveFaults {
        let mut a = ActiveFaults::default();
        for s in self.slots.iter().flatten() {
            if now < s.start || s.end.is_some_and(|e| now >= e) {
                continue;
            }
            match s.fault {
                InjectedFault::NanReading => a.nan = true,
                InjectedFault::DroppedReading => a.dropped = true,
                InjectedFault::Disconnect => a.disconnected = true,
                InjectedFault::StuckEncoder { joint } => a.stuck_mask |= 1 << joint,
                InjectedFault::EncoderJump { joint, counts } => {
                    a.jump_counts[usize::from(joint)] += counts
                }
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_and_capacity() {
        let mut s = FaultSchedule::default();
        s.inject(
            InjectedFault::EncoderJump {
                joint: 1,
                counts: 500,
            },
            Duration::from_millis(10),
            Some(Duration::from_millis(5)),
        )
        .unwrap();
        assert_eq!(s.active(Duration::from_millis(9)).jump_counts, [0, 0, 0]);
        assert_eq!(s.active(Duration::from_millis(10)).jump_counts, [0, 500, 0]);
        assert_eq!(s.active(Duration::from_millis(15)).jump_counts, [0, 0, 0]);
        assert!(
            s.inject(
                InjectedFault::StuckEncoder { joint: 3 },
                Duration::ZERO,
                None
            )
            .is_err()
        );
        for _ in 1..FaultSchedule::CAPACITY {
            s.inject(InjectedFault::NanReading, Duration::ZERO, None)
                .unwrap();
        }
        assert!(matches!(
            s.inject(InjectedFault::NanReading, Duration::ZERO, None),
            Err(DeviceError::FaultScheduleFull { capacity: 8 })
        ));
    }
}
