//! How the design variables, objectives and joint torques moved over the
//! run, in `summary.json`.

use serde::{Deserialize, Serialize};

/// How one design-variable component (m) or objective value moved over the
/// run: at the start (after assembly), at the end, and its extremes over the
/// ticks that succeeded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DesignFigure {
    /// At the start.
    #[serde(with = "crate::report::figure")]
    pub start: f64,
    /// After the last tick that succeeded.
    #[serde(with = "crate::report::figure")]
    pub end: f64,
    /// Smallest.
    #[serde(with = "crate::report::figure")]
    pub min: f64,
    /// Largest.
    #[serde(with = "crate::report::figure")]
    pub max: f64,
}

impl From<crate::session::Range4> for DesignFigure {
    fn from(r: crate::session::Range4) -> Self {
        Self {
            start: r.start,
            end: r.end,
            min: r.min,
            max: r.max,
        }
    }
}

/// One objective's reported value over the run (its unit depends on the
/// kind: see `docs/scene-format.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectiveFigure {
    /// The objective's kind.
    pub kind: String,
    /// Its weight.
    pub weight: f64,
    /// Start, end, min and max of its reported value.
    #[serde(flatten)]
    pub value: DesignFigure,
}
