//! [`SafetyConfig`]: the limits the safety layer enforces, with units and the
//! reason for each default.

use std::time::Duration;

use crate::error::DeviceError;

/// Limits enforced by [`crate::SafeDevice`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SafetyConfig {
    /// Force magnitude clamp, newtons. `None` (default) uses the device's peak
    /// force: the most the motors can do; lower it for a gentler session.
    pub peak_force_n: Option<f64>,
    /// Largest change of the force vector per second, N/s (default 2000 N/s =
    /// 2 N per 1 kHz tick: a full Premium peak in ~4 ms, slow enough to stop a
    /// one-tick spike from reaching the hand at full size, fast enough not to
    /// soften a stiff wall at human contact speeds). Applied per write as
    /// `rate × loop_period`, whatever the time since the last write, and only
    /// to growing or turning force: decreasing force is never limited.
    pub max_force_rate_n_per_s: f64,
    /// Start-up ramp: force scales linearly from 0 to 1 over this time after
    /// the first write, a cleared fault, a stop or a velocity cut; after a
    /// stall the ramp is shorter, in proportion to the stall (see
    /// [`crate::safety::RECOVERY_RAMP_PER_GAP`]) (default 1 s; CHAI3D's
    /// force rise uses 2 s, but the session registers the device so the initial
    /// force error is zero, and 1 s is long enough that a surprise force grows
    /// at under 9 N/s on a Premium).
    pub ramp: Duration,
    /// Tip speed above which force is cut, m/s (default 2 m/s: above deliberate
    /// hand motion with a stylus, below the speed an unstable loop reaches; the
    /// vendors have the same guard: `HD_SOFTWARE_VELOCITY_LIMIT`, Force
    /// Dimension's VELOCITY force-off).
    pub max_speed_m_per_s: f64,
    /// Window of the speed estimate (default 10 ms: one encoder count over 10 ms
    /// is 3–5.5 mm/s of quantisation noise; CHAI3D uses 15 ms, DHD 20 ms).
    pub velocity_window: Duration,
    /// Period of the loop driving the device (default 1 ms).
    pub loop_period: Duration,
    /// Motors off when no write arrives for this many periods (default 10: a
    /// 10 ms stall at 1 kHz; the hardware watchdog is armed with the same time).
    pub watchdog_periods: u32,
    /// Consecutive bad readings (held) tolerated before the fault latches and
    /// force is cut (default 10: 10 ms of holding at 1 kHz).
    pub max_consecutive_bad_readings: u32,
    /// Fastest plausible joint speed, rad/s (default 25 rad/s ≈ 5 m/s at the
    /// Premium's tip): a count change beyond it in one period is a jump.
    pub max_joint_speed_rad_per_s: f64,
}

impl Default for SafetyConfig {
    fn default() -> Self {
        Self {
            peak_force_n: None,
            max_force_rate_n_per_s: 2000.0,
            ramp: Duration::from_secs(1),
            max_speed_m_per_s: 2.0,
            velocity_window: Duration::from_millis(10),
            loop_period: Duration::from_millis(1),
            watchdog_periods: 10,
            max_consecutive_bad_readings: 10,
            max_joint_speed_rad_per_s: 25.0,
        }
    }
}

impl SafetyConfig {
    /// Defaults for a loop with the given period.
    pub fn for_period(loop_period: Duration) -> Self {
        Self {
            loop_period,
            ..Self::default()
        }
    }

    /// Watchdog timeout: `watchdog_periods × loop_period`.
    pub fn watchdog_timeout(&self) -> Duration {
        self.loop_period * self.watchdog_periods
    }

    pub(crate) fn validate(&self) -> Result<(), DeviceError> {
        let positive = |what: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(DeviceError::InvalidConfig {
                    what,
                    value: v.to_string(),
                    reason: "must be finite and > 0",
                })
            }
        };
        if let Some(p) = self.peak_force_n {
            positive("peak_force_n", p)?;
        }
        positive("max_force_rate_n_per_s", self.max_force_rate_n_per_s)?;
        positive("max_speed_m_per_s", self.max_speed_m_per_s)?;
        positive("max_joint_speed_rad_per_s", self.max_joint_speed_rad_per_s)?;
        if self.loop_period.is_zero() || self.watchdog_periods == 0 {
            return Err(DeviceError::InvalidConfig {
                what: "watchdog",
                value: format!("{:?} x {}", self.loop_period, self.watchdog_periods),
                reason: "period and count must be > 0",
            });
        }
        Ok(())
    }
}
