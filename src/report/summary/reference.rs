//! The fast loop's force against the converged reference in
//! `summary.json` (`session::reference`).

use super::{MaxRms, SessionOutcome};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The fast loop's force against the converged reference: the same tick,
/// from the same state, replayed to convergence (`session::reference`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// One tick in this many was sampled.
    pub every_ticks: u64,
    /// Ticks sampled.
    pub samples: u64,
    /// Samples compared (the figures cover these only).
    pub compared: u64,
    /// Why nothing was compared, when nothing was (the figures are then
    /// `"NaN"`).
    pub missing: Option<String>,
    /// |F − F*| per finger and sample, N: the force the solver asked for
    /// (before the safety layer) against the reference's.
    pub force_error_n: MaxRms,
    /// The same over the reference force: max error / max |F*|, RMS error /
    /// RMS |F*|.
    pub force_error_relative: MaxRms,
    /// Largest and RMS |F*|, N.
    pub force_n: MaxRms,
    /// Largest distance of a body origin from the reference configuration
    /// per sample, m: max and RMS over samples.
    pub configuration_error_m: MaxRms,
    /// Samples not compared, by why: the fast tick failed, the reference's
    /// solve failed, it did not converge, a newer sample replaced it.
    pub not_compared: BTreeMap<String, u64>,
    /// Compared samples whose reference stopped at round-off above the
    /// 1e-12 m tolerance (included; `last_step_max_m` says how far).
    pub round_off: u64,
    /// Most iterations a reference took.
    pub iterations_max: u32,
    /// Largest last step of a compared reference, m.
    #[serde(with = "crate::report::figure")]
    pub last_step_max_m: f64,
}

impl Reference {
    pub(super) fn of(o: &SessionOutcome) -> Reference {
        let r = &o.slow.reference;
        let nan = MaxRms {
            max: f64::NAN,
            rms: f64::NAN,
        };
        let missing = if let Some(why) = o.slow.reference_unsupported {
            Some(format!("not measured: {why}"))
        } else if o.fingers.is_empty() {
            Some("not measured: the scene has no fingers, so no force to compare".to_string())
        } else if r.compared > 0 {
            None
        } else if r.captured == 0 {
            Some("not measured: no tick was sampled".to_string())
        } else {
            Some(format!(
                "not measured: none of the {} sampled ticks could be compared",
                r.captured
            ))
        };
        let measured = missing.is_none();
        let pick = |m: MaxRms| if measured { m } else { nan };
        let not_compared = [
            ("fast_tick_failed", r.fast_failed),
            ("reference_failed", r.reference_failed),
            ("not_converged", r.not_converged),
            ("overwritten", r.overwritten),
        ]
        .into_iter()
        .filter(|(_, n)| *n > 0)
        .map(|(k, n)| (k.to_string(), n))
        .collect();
        Reference {
            every_ticks: o.plan.reference_every_ticks,
            samples: r.captured,
            compared: r.compared,
            missing,
            force_error_n: pick(MaxRms {
                max: r.force_error_max_n,
                rms: r.force_error_rms_n(),
            }),
            force_error_relative: pick(MaxRms {
                max: r.force_error_max_n / r.force_max_n,
                rms: r.force_error_rms_n() / r.force_rms_n(),
            }),
            force_n: pick(MaxRms {
                max: r.force_max_n,
                rms: r.force_rms_n(),
            }),
            configuration_error_m: pick(MaxRms {
                max: r.q_error_max_m,
                rms: r.q_error_rms_m(),
            }),
            not_compared,
            round_off: r.round_off,
            iterations_max: r.iterations_max,
            last_step_max_m: if measured {
                r.last_step_max_m
            } else {
                f64::NAN
            },
        }
    }
}
