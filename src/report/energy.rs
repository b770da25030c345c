//! The `energy` block of `summary.json` and its line in the end report
//! (scenes with inertial motion).

use serde::{Deserialize, Serialize};

use crate::session::SessionOutcome;

/// Kinetic + potential energy of the moving bodies, J (potential −m g·r,
/// zero at the scene origin).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    /// At the first tick that succeeded.
    #[serde(with = "super::figure")]
    pub start_j: f64,
    /// At the last tick that succeeded.
    #[serde(with = "super::figure")]
    pub end_j: f64,
    /// The largest rise of (energy − the work the fingers did) over any
    /// stretch of the run: energy no finger put in. A simulation that
    /// injects energy into the user's hand is a stability problem.
    #[serde(with = "super::figure")]
    pub max_injected_j: f64,
    /// Ticks the figures cover (those that succeeded).
    pub ticks: u64,
    /// Ticks that failed and are not covered.
    pub failed_ticks: u64,
}

impl Energy {
    /// The block of a finished session (`None` without inertial motion).
    pub fn of(o: &SessionOutcome) -> Option<Energy> {
        if !o.plan.solver.dynamics {
            return None;
        }
        let e = &o.stats.energy;
        let none = e.ticks == 0;
        let or_nan = |v: f64| if none { f64::NAN } else { v };
        Some(Energy {
            start_j: or_nan(e.start_j),
            end_j: or_nan(e.end_j),
            max_injected_j: or_nan(e.max_injected_j),
            ticks: e.ticks,
            failed_ticks: o.stats.solver_failures,
        })
    }

    /// The report line.
    pub fn line(&self) -> String {
        if self.ticks == 0 {
            return "energy: not measured: no tick succeeded".into();
        }
        let cover = if self.failed_ticks == 0 {
            String::new()
        } else {
            format!(
                " (FAILED TICKS: {} ticks failed and are not covered; over the {} that succeeded)",
                self.failed_ticks, self.ticks
            )
        };
        format!(
            "energy: start {:.6} J, end {:.6} J, largest rise not done by the fingers {:.3e} J{cover}",
            self.start_j, self.end_j, self.max_injected_j
        )
    }
}
