//! Motor heating and the continuous-force cut.
//!
//! Copper losses grow with the square of current, i.e. of force, and the winding
//! temperature follows them with a first-order lag. The normalised temperature
//! rise `load` obeys
//!
//! ```text
//! τ_th · d(load)/dt = (|F| / F_cont)² − load
//! ```
//!
//! so `load` settles at 1 exactly when the continuous rating is applied
//! forever. When `load` reaches 1 the model **cuts the force to the continuous
//! rating** (magnitude clamp, direction kept) until it cools below
//! [`ThermalModel::RELEASE_LOAD`], as OpenHaptics does when it reports
//! `HD_WARM_MOTORS`. With τ_th = 20 s the Premium can hold its 8.5 N peak for
//! about 0.55 s from cold (τ_th·−ln(1 − (1.4/8.5)²)).
//!
//! # Real-time
//! At most one `exp` per update (cached for a repeated step length): no
//! allocation, constant time.

/// First-order thermal model of the motors of one arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalModel {
    continuous_force_n: f64,
    time_constant_s: f64,
    load: f64,
    limiting: bool,
    /// Cache of the last step length and its `1 − exp(−dt/τ)`.
    last_dt_s: f64,
    last_a: f64,
}

impl ThermalModel {
    /// Load below which a cut is released (hysteresis, so the cut does not
    /// chatter at the threshold).
    pub const RELEASE_LOAD: f64 = 0.9;

    /// A cold model for a motor set rated `continuous_force_n` with winding time
    /// constant `time_constant_s`.
    pub fn new(continuous_force_n: f64, time_constant_s: f64) -> Self {
        Self {
            continuous_force_n,
            time_constant_s: time_constant_s.max(1e-6),
            load: 0.0,
            limiting: false,
            last_dt_s: 0.0,
            last_a: 0.0,
        }
    }

    /// Normalised temperature rise (1 = steady state at the continuous rating).
    pub fn load(&self) -> f64 {
        self.load
    }

    /// True while the force is being cut to the continuous rating.
    pub fn limiting(&self) -> bool {
        self.limiting
    }

    /// Advances the temperature by `dt_s` seconds with `force_n` applied.
    pub fn update(&mut self, force_n: f64, dt_s: f64) {
        let target = (force_n / self.continuous_force_n).powi(2);
        if dt_s != self.last_dt_s {
            self.last_dt_s = dt_s;
            self.last_a = 1.0 - (-dt_s / self.time_constant_s).exp();
        }
        self.load += self.last_a * (target - self.load);
        if self.load >= 1.0 {
            self.limiting = true;
        } else if self.load < Self::RELEASE_LOAD {
            self.limiting = false;
        }
    }

    /// The largest force magnitude allowed now, newtons (∞ when not limiting).
    pub fn allowed_force_n(&self) -> f64 {
        if self.limiting {
            self.continuous_force_n
        } else {
            f64::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn continuous_rating_never_trips_and_peak_trips_on_time() {
        let mut m = ThermalModel::new(1.4, 20.0);
        for _ in 0..600_000 {
            m.update(1.4 * 0.999, 1e-3); // 10 minutes just under the rating
        }
        assert!(!m.limiting() && m.load() < 1.0);

        let mut m = ThermalModel::new(1.4, 20.0);
        let mut t = 0.0;
        while !m.limiting() {
            m.update(8.5, 1e-3);
            t += 1e-3;
        }
        let expected = -20.0 * (1.0 - (1.4f64 / 8.5).powi(2)).ln();
        assert!(
            (t - expected).abs() < 2e-3,
            "tripped after {t} s, expected {expected}"
        );
        // Released only after cooling below the hysteresis threshold.
        m.update(0.0, 0.5);
        assert!(
            m.limiting(),
            "0.5 s of cooling is not enough to drop below 0.9"
        );
        m.update(0.0, 2.0);
        assert!(m.load() < ThermalModel::RELEASE_LOAD && !m.limiting());
    }
}
