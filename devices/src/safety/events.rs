//! Why force was cut, and the counters the session's end report lists.
//!
//! # Real-time
//! Counters are fixed arrays of `u64`; recording never allocates.

use std::time::Duration;

use crate::fault::FaultKind;

/// Why the safety layer (or the device behind it) reduced or cut the force.
/// Like the Force Dimension SDK's force-off causes, plus the limiters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CutReason {
    /// The command was NaN or ∞: zero force sent.
    NonFiniteForce,
    /// A latched fault (disconnect, lost encoder, long bad-reading run).
    Fault,
    /// No write within the watchdog time: motors switched off.
    Watchdog,
    /// Tip speed above the limit: force cut.
    Velocity,
    /// Magnitude clamped to the peak force (direction kept).
    Clamp,
    /// The device's thermal model cut the force to the continuous rating.
    Thermal,
    /// Start-up / re-engagement ramp scaled the force down.
    Ramp,
    /// Change per tick limited.
    RateLimit,
    /// A motor torque saturated inside the device.
    MotorSaturation,
}

impl CutReason {
    /// Number of reasons.
    pub const COUNT: usize = 9;
    /// All reasons in priority order (the first present is the primary one).
    pub const ALL: [CutReason; Self::COUNT] = [
        CutReason::NonFiniteForce,
        CutReason::Fault,
        CutReason::Watchdog,
        CutReason::Velocity,
        CutReason::Clamp,
        CutReason::Thermal,
        CutReason::Ramp,
        CutReason::RateLimit,
        CutReason::MotorSaturation,
    ];

    /// Position in [`CutReason::ALL`].
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Bit of this reason in a [`CutSet`].
    pub const fn bit(self) -> u16 {
        1 << (self as u16)
    }

    /// Short name for reports.
    pub const fn name(self) -> &'static str {
        match self {
            CutReason::NonFiniteForce => "non-finite force",
            CutReason::Fault => "fault",
            CutReason::Watchdog => "watchdog",
            CutReason::Velocity => "velocity limit",
            CutReason::Clamp => "peak-force clamp",
            CutReason::Thermal => "thermal",
            CutReason::Ramp => "start-up ramp",
            CutReason::RateLimit => "rate limit",
            CutReason::MotorSaturation => "motor saturation",
        }
    }
}

/// The set of reasons that acted on one tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CutSet(pub u16);

impl CutSet {
    /// Adds a reason.
    pub fn insert(&mut self, r: CutReason) {
        self.0 |= r.bit();
    }

    /// True if `r` acted.
    pub fn contains(self, r: CutReason) -> bool {
        self.0 & r.bit() != 0
    }

    /// The highest-priority reason present.
    pub fn primary(self) -> Option<CutReason> {
        CutReason::ALL.into_iter().find(|r| self.contains(*r))
    }
}

/// The last time force was cut, with sizes (newtons).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutRecord {
    /// Primary reason.
    pub reason: CutReason,
    /// Session time.
    pub at: Duration,
    /// Magnitude asked for, newtons (NaN for a non-finite command).
    pub requested_n: f64,
    /// Magnitude sent, newtons.
    pub applied_n: f64,
}

/// The last fault detected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultRecord {
    /// What.
    pub kind: FaultKind,
    /// Joint concerned, for encoder faults.
    pub joint: Option<u8>,
    /// Session time.
    pub at: Duration,
}

/// One line of the end report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SafetyEvent {
    /// Force was cut or limited.
    Cut(CutReason),
    /// A fault was detected.
    Fault(FaultKind),
}

/// Event counters of one device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SafetyCounters {
    /// Writes seen.
    pub writes: u64,
    /// Readings returned held (last good value instead of this tick's).
    pub held_readings: u64,
    /// Good readings whose tip was outside the device's workspace box: the
    /// arm was at (or pushed past) a mechanical stop.
    pub outside_workspace: u64,
    cut_ticks: [u64; CutReason::COUNT],
    cut_episodes: [u64; CutReason::COUNT],
    faults: [u64; FaultKind::COUNT],
    previous: CutSet,
}

impl SafetyCounters {
    /// Ticks on which `reason` acted.
    pub fn cut_ticks(&self, reason: CutReason) -> u64 {
        self.cut_ticks[reason.index()]
    }

    /// Separate episodes (runs of consecutive ticks) of `reason`.
    pub fn cut_episodes(&self, reason: CutReason) -> u64 {
        self.cut_episodes[reason.index()]
    }

    /// Ticks on which fault `kind` was detected.
    pub fn faults(&self, kind: FaultKind) -> u64 {
        self.faults[kind.index()]
    }

    /// Non-zero counters as (event, ticks), for the end report.
    pub fn events(&self) -> impl Iterator<Item = (SafetyEvent, u64)> + '_ {
        let cuts = CutReason::ALL
            .into_iter()
            .map(|r| (SafetyEvent::Cut(r), self.cut_ticks(r)));
        let faults = FaultKind::ALL
            .into_iter()
            .map(|k| (SafetyEvent::Fault(k), self.faults(k)));
        cuts.chain(faults).filter(|(_, n)| *n > 0)
    }

    pub(crate) fn record_tick(&mut self, set: CutSet) {
        for r in CutReason::ALL {
            if set.contains(r) {
                self.cut_ticks[r.index()] += 1;
                if !self.previous.contains(r) {
                    self.cut_episodes[r.index()] += 1;
                }
            }
        }
        self.previous = set;
    }

    pub(crate) fn record_fault(&mut self, kind: FaultKind) {
        self.faults[kind.index()] += 1;
    }
}

impl CutReason {
    /// A short human name for reports.
    pub fn as_str(self) -> &'static str {
        match self {
            CutReason::NonFiniteForce => "non-finite force zeroed",
            CutReason::Fault => "force cut by a fault",
            CutReason::Watchdog => "watchdog motors-off",
            CutReason::Velocity => "velocity limit",
            CutReason::Clamp => "peak-force clamp",
            CutReason::Thermal => "thermal cut",
            CutReason::Ramp => "start-up ramp",
            CutReason::RateLimit => "force rate limit",
            CutReason::MotorSaturation => "motor saturation",
        }
    }
}

impl std::fmt::Display for SafetyEvent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SafetyEvent::Cut(r) => write!(f, "{} (ticks)", r.as_str()),
            SafetyEvent::Fault(k) => write!(f, "fault: {k:?} (ticks)"),
        }
    }
}
