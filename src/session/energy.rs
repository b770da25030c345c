//! The energy account of a session with inertial motion: the mechanical
//! energy of the moving bodies at the first and last ticks that succeeded,
//! and the largest rise of (energy − the fingers' work) over any stretch of
//! the run: energy the simulation put into the bodies (and so, through the
//! coupling, into the user's hand) that no finger did.
//!
//! # Real-time
//! `record` is a few comparisons on preallocated fields.

use haptloop_solver::dynamics::EnergySample;

/// Accumulated over the ticks that succeeded and carried a figure.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnergyStats {
    /// Ticks whose energy was recorded.
    pub ticks: u64,
    /// Energy at the first recorded tick, J.
    pub start_j: f64,
    /// Energy at the last recorded tick, J.
    pub end_j: f64,
    /// Largest rise of energy − finger work over any stretch, J (≥ 0).
    pub max_injected_j: f64,
    /// The lowest energy − finger work so far, J.
    low_j: f64,
}

impl EnergyStats {
    /// Records one tick's figures (skipped unless `solved` and valid).
    #[inline]
    pub fn record(&mut self, e: &EnergySample, solved: bool) {
        if !(solved && e.valid && e.energy_j.is_finite() && e.finger_work_j.is_finite()) {
            return;
        }
        let unexplained = e.energy_j - e.finger_work_j;
        if self.ticks == 0 {
            self.start_j = e.energy_j;
            self.low_j = unexplained;
        }
        self.ticks += 1;
        self.end_j = e.energy_j;
        self.low_j = self.low_j.min(unexplained);
        self.max_injected_j = self.max_injected_j.max(unexplained - self.low_j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(energy_j: f64, finger_work_j: f64) -> EnergySample {
        EnergySample {
            valid: true,
            energy_j,
            finger_work_j,
        }
    }

    #[test]
    fn a_rise_the_fingers_paid_for_is_not_injected_and_one_they_did_not_is() {
        let mut s = EnergyStats::default();
        for (e, w) in [(1.0, 0.0), (0.5, 0.0), (1.5, 1.0), (1.7, 1.0), (1.6, 1.0)] {
            s.record(&at(e, w), true);
        }
        // Dissipated to 0.5, the fingers gave 1.0 (1.5 is paid for), then
        // 0.2 J appeared from nowhere.
        assert!((s.max_injected_j - 0.2).abs() < 1e-12, "{s:?}");
        assert_eq!((s.start_j, s.end_j, s.ticks), (1.0, 1.6, 5));
        // A failed tick or one without a figure is not recorded.
        s.record(&at(100.0, 0.0), false);
        s.record(&EnergySample::default(), true);
        assert_eq!(s.ticks, 5);
    }
}
