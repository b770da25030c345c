//! What the contact machinery saw and did, in `summary.json`.

use super::SessionOutcome;
use serde::{Deserialize, Serialize};

/// What the contact machinery saw and did (scenes whose shaped bodies can
/// touch; absent otherwise).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// Deepest penetration seen, m: the larger of the two below.
    #[serde(with = "crate::report::figure")]
    pub max_penetration_m: f64,
    /// The penetration the scene tolerates (`penetration_tolerance`), m.
    pub tolerance_m: f64,
    /// `kept`, `EXCEEDED`, with the failed ticks counted as for the
    /// violation.
    pub verdict: String,
    /// Deepest penetration measured exactly (parry, separating axis) in the
    /// fast loop's snapshots, every slow-loop cycle, m.
    #[serde(with = "crate::report::figure")]
    pub max_penetration_exact_m: f64,
    /// Deepest violation of a witness row in use at the end of a tick that
    /// succeeded, every tick, m.
    #[serde(with = "crate::report::figure")]
    pub max_penetration_rows_m: f64,
    /// Most witness rows active (pushing) in one tick.
    pub max_active: u32,
    /// Primitive witnesses whose features changed inside tracked pairs.
    pub witness_changes: u64,
    /// Backups: a penetration beyond the tolerance (or a tunnel) seen in a
    /// snapshot, answered by reverting to the last clean configuration.
    pub backups: u64,
    /// Witnesses expanded to a higher-dimensional feature on penetration.
    pub expansions: u64,
    /// New programs because the set of tracked pairs changed.
    pub structure_changes: u64,
    /// Witness tables published for the running program.
    pub witness_tables: u64,
    /// Most pairs tracked at once.
    pub max_tracked_pairs: u32,
    /// In-tick activations (refactorisations for a contact a step would
    /// have violated).
    pub activations: u64,
    /// Ticks that ran out of activations.
    pub activation_limit_ticks: u64,
    /// Most fingertip contacts sticking (friction) at once.
    pub max_sticking: u32,
    /// Witness updates (tables and programs) the fast loop took over.
    pub updates: u64,
    /// Ticks from the snapshot an update was computed from to the tick that
    /// used it: mean.
    #[serde(with = "crate::report::figure")]
    pub latency_ticks_mean: f64,
    /// Same, largest.
    pub latency_ticks_max: u64,
    /// One slow-loop contact cycle (broad + narrow phase, witnesses), µs:
    /// mean and largest.
    #[serde(with = "crate::report::figure")]
    pub cycle_us_mean: f64,
    /// Same, largest.
    #[serde(with = "crate::report::figure")]
    pub cycle_us_max: f64,
    /// Building a program for a new set of pairs (symbolic analysis
    /// included), µs: mean and largest.
    #[serde(with = "crate::report::figure")]
    pub build_us_mean: f64,
    /// Same, largest.
    #[serde(with = "crate::report::figure")]
    pub build_us_max: f64,
    /// Structure changes served from the cache by structure (a set of pairs
    /// seen before), and preparing one of those, µs: mean and largest
    /// (`"NaN"` when none was reused).
    pub reused: u64,
    /// Mean, µs.
    #[serde(with = "crate::report::figure")]
    pub reuse_us_mean: f64,
    /// Largest, µs.
    #[serde(with = "crate::report::figure")]
    pub reuse_us_max: f64,
    /// The contact speed limit, m/s: `contact_distance` per slow-loop
    /// cycle, the most a shaped body may move.
    #[serde(default)]
    pub speed_limit_m_per_s: f64,
    /// Ticks in which it held a shaped body back (a fingertip then lags its
    /// device).
    #[serde(default)]
    pub speed_limited_ticks: u64,
    /// The largest finger tracking error in such a tick, m.
    #[serde(default)]
    pub speed_limit_lag_max_m: f64,
    /// A penetration beyond this means the world came apart, m (the
    /// contact distance, at least ten times the tolerance).
    #[serde(default)]
    pub broken_penetration_m: f64,
    /// Slow-loop snapshots whose exact penetration was beyond it, and ticks
    /// whose witness rows were (failed: force cut). Either makes the
    /// verdict `BROKEN`.
    #[serde(default)]
    pub broken_snapshots: u64,
    /// Same, ticks.
    #[serde(default)]
    pub broken_ticks: u64,
    /// Slow-loop cycles that found a penetration beyond the tolerance and
    /// held it instead of backing it up: two backups in a row had not
    /// cleared it (the penetration stays, reported above).
    #[serde(default)]
    pub backups_held: u64,
    /// Ticks in which the witness rows were too old to move any body (the
    /// slow loop was late; the motion they are trusted for counts from
    /// their snapshot).
    #[serde(default)]
    pub stale_stopped_ticks: u64,
    /// The most motion since their snapshot the rows in use were asked to
    /// cover, in ticks at the contact speed limit (the budget is two
    /// slow-loop cycles).
    #[serde(default, with = "crate::report::figure")]
    pub max_witness_age_ticks: f64,
}

impl Contact {
    pub(super) fn of(o: &SessionOutcome) -> Option<Contact> {
        let s = &o.stats;
        let measured = s.solved_ticks();
        o.slow.contact.map(|c| {
            let f = &s.contact;
            let mean = |sum: u64, n: u64| {
                if n == 0 {
                    f64::NAN
                } else {
                    sum as f64 / n as f64
                }
            };
            let max_pen = c.max_penetration_m.max(f.max_penetration_m);
            let tol = o.plan.contact.penetration_tolerance_m;
            let failed = s.solver_failures;
            let within = max_pen <= tol;
            let bound = crate::session::broken_penetration_m(&o.plan.contact);
            let broken_ticks =
                s.failure_kinds[crate::session::FailureKind::PenetrationBeyondBroken as usize];
            let broken = c.broken + broken_ticks;
            Contact {
                max_penetration_m: max_pen,
                tolerance_m: tol,
                verdict: match (measured, failed, within) {
                    _ if broken > 0 || max_pen > bound => format!(
                        "BROKEN: bodies came apart ({} snapshots and {broken_ticks} ticks \
                         penetrated beyond {bound:.1e} m; force cut)",
                        c.broken
                    ),
                    (0, _, _) => "not measured: no tick succeeded".into(),
                    (_, 0, true) => "kept".into(),
                    (_, 0, false) => "EXCEEDED".into(),
                    (_, f, w) => format!(
                        "FAILED TICKS: {f} ticks failed and are not covered; over the {measured} that succeeded: {}",
                        if w { "within the tolerance" } else { "EXCEEDED" }
                    ),
                },
                max_penetration_exact_m: c.max_penetration_m,
                max_penetration_rows_m: f.max_penetration_m,
                max_active: f.max_active,
                witness_changes: c.witness_changes,
                backups: c.backups,
                expansions: c.expansions,
                structure_changes: c.structure_changes,
                witness_tables: c.frames,
                max_tracked_pairs: c.max_tracked,
                activations: f.activations,
                activation_limit_ticks: f.activation_limit_ticks,
                max_sticking: f.max_sticking,
                updates: f.updates,
                latency_ticks_mean: mean(f.latency_sum_ticks, f.updates),
                latency_ticks_max: f.latency_max_ticks,
                cycle_us_mean: mean(c.cycle_ns_sum, c.cycles) / 1e3,
                cycle_us_max: c.cycle_ns_max as f64 / 1e3,
                build_us_mean: mean(c.build_ns_sum, c.structure_changes - c.reused) / 1e3,
                build_us_max: c.build_ns_max as f64 / 1e3,
                reused: c.reused,
                reuse_us_mean: mean(c.reuse_ns_sum, c.reused) / 1e3,
                reuse_us_max: if c.reused == 0 {
                    f64::NAN
                } else {
                    c.reuse_ns_max as f64 / 1e3
                },
                speed_limit_m_per_s: o.plan.solver.contact_step_m * f64::from(o.plan.rate_hz),
                speed_limited_ticks: f.speed_limited_ticks,
                speed_limit_lag_max_m: f.speed_limit_lag_max_m,
                broken_penetration_m: bound,
                broken_snapshots: c.broken,
                broken_ticks,
                backups_held: c.held,
                stale_stopped_ticks: f.stale_stopped_ticks,
                max_witness_age_ticks: f.max_witness_age,
            }
        })
    }
}
