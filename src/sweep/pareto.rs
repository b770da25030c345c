//! The Pareto front of a sweep and its recommendation.
//!
//! **Cost** is the fraction of a core the fast loop takes: the median tick
//! times the rate (so a cheap tick at 10 kHz can cost more than a dear one
//! at 1 kHz). **Accuracy** is the largest force error against the converged
//! reference; in scenes where that is not measured (contact), the largest
//! violation. A point is on the front when no other point that ran without
//! a failed tick is at least as cheap and at least as accurate, and better
//! in one of the two.
//!
//! **The recommendation** is the cheapest point that meets every criterion
//! (costs within [`COST_TIE`] of the cheapest count as equal: timings on
//! this shared machine move by about that much between runs; among those the
//! more accurate wins), checked in this order:
//! 1. its session ran, and no tick failed;
//! 2. its violation is within the scene's `violation_tolerance`;
//! 3. its force error is within `force_tolerance` of the largest reference
//!    force (default 1 %, well under the 7–10 % force JND of human touch);
//! 4. its p99 tick fits in half the period: these hot-loop timings ran
//!    1.4–2× faster than the pinned real-time thread (BENCHMARKS.md);
//! 5. the virtual coupling is passive at the rate for a relaxed grip
//!    (Colgate: k T/2 + B < b; without it a light hold buzzes).

use super::Point;

/// Costs within this fraction of the cheapest recommendable point's are
/// treated as equal, and the most accurate of them is recommended.
pub const COST_TIE: f64 = 0.1;

/// What the front's accuracy axis is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// Largest force error against the converged reference, N.
    ForceError,
    /// Largest violation, m (the force error is not measured).
    Violation,
    /// Largest penetration, m (contact scenes without joint rows: neither
    /// the force error nor a violation is measured).
    Penetration,
    /// Neither is measured: no front.
    None,
}

impl Axis {
    /// Name in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Axis::ForceError => "force error max (N)",
            Axis::Violation => "violation max (m)",
            Axis::Penetration => "penetration max (m)",
            Axis::None => "none",
        }
    }

    /// The point's value on this axis (NaN: none).
    pub fn value(self, p: &Point) -> f64 {
        match (&p.accuracy, self) {
            (Ok(a), Axis::ForceError) => a.force_error_n.max,
            (Ok(a), Axis::Violation) => a.violation_m.max,
            (Ok(a), Axis::Penetration) => a.penetration_m,
            _ => f64::NAN,
        }
    }
}

/// What a recommended point must meet besides running cleanly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Criteria {
    /// The scene's violation tolerance, m.
    pub tolerance_m: Option<f64>,
    /// Largest force error as a fraction of the largest reference force.
    pub force_tolerance: f64,
    /// The scene's penetration tolerance, m (scenes with contact).
    pub penetration_tolerance_m: f64,
}

/// Why a point is (not) recommendable: the first criterion it misses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Meets every criterion.
    Recommendable,
    /// Its session could not run (or the sweep was stopped before it ran).
    NotRun,
    /// Its accuracy was measured, but the sweep was stopped before it was
    /// timed.
    NotTimed,
    /// Some ticks failed.
    FailedTicks,
    /// Violation above the scene's tolerance.
    Violation,
    /// Force error above the force tolerance.
    ForceError,
    /// Penetration above the scene's penetration tolerance.
    Penetration,
    /// p99 tick above half the period.
    TooSlow,
    /// The coupling is not passive at this rate.
    NotPassive,
}

impl Verdict {
    /// A short word for tables.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Recommendable => "ok",
            Verdict::NotRun => "not run",
            Verdict::NotTimed => "not timed (the sweep was stopped)",
            Verdict::FailedTicks => "failed ticks",
            Verdict::Violation => "violation > tolerance",
            Verdict::ForceError => "force error > tolerance",
            Verdict::Penetration => "penetration > tolerance",
            Verdict::TooSlow => "p99 > period/2",
            Verdict::NotPassive => "coupling not passive",
        }
    }
}

/// The axis the points support: force error where any point measured it.
pub fn axis(points: &[Point]) -> Axis {
    let any = |a: Axis| points.iter().any(|p| a.value(p).is_finite());
    if any(Axis::ForceError) {
        Axis::ForceError
    } else if any(Axis::Violation) {
        Axis::Violation
    } else if any(Axis::Penetration) {
        Axis::Penetration
    } else {
        Axis::None
    }
}

fn verdict(p: &Point, c: &Criteria) -> Verdict {
    let Ok(a) = &p.accuracy else {
        return Verdict::NotRun;
    };
    let Some(t) = &p.timing else {
        return Verdict::NotTimed;
    };
    if a.failed_ticks > 0 {
        return Verdict::FailedTicks;
    }
    if let Some(tol) = c.tolerance_m
        && a.violation_m.max.is_finite()
        && a.violation_m.max > tol
    {
        return Verdict::Violation;
    }
    if a.force_error_n.max.is_finite() && a.force_error_n.max > c.force_tolerance * a.force_max_n {
        return Verdict::ForceError;
    }
    if a.penetration_m.is_finite() && a.penetration_m > c.penetration_tolerance_m {
        return Verdict::Penetration;
    }
    let period_ns = 1e9 / f64::from(p.knobs.rate_hz);
    if t.p99_ns as f64 > 0.5 * period_ns {
        return Verdict::TooSlow;
    }
    if !p.passive {
        return Verdict::NotPassive;
    }
    Verdict::Recommendable
}

/// Marks the front and every point's verdict; returns the recommendation.
pub fn mark(points: &mut [Point], axis: Axis, c: &Criteria) -> Option<usize> {
    let eligible: Vec<Option<(f64, f64)>> = points
        .iter()
        .map(|p| {
            let clean = matches!(&p.accuracy, Ok(a) if a.failed_ticks == 0);
            let (cost, acc) = (p.load(), axis.value(p));
            (clean && cost.is_finite() && acc.is_finite()).then_some((cost, acc))
        })
        .collect();
    for (i, p) in points.iter_mut().enumerate() {
        p.verdict = verdict(p, c);
        p.pareto = match eligible[i] {
            None => false,
            Some((cost, acc)) => !eligible
                .iter()
                .flatten()
                .any(|&(oc, oa)| oc <= cost && oa <= acc && (oc < cost || oa < acc)),
        };
    }
    let ok: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].verdict == Verdict::Recommendable)
        .collect();
    let cheapest = ok
        .iter()
        .map(|&i| points[i].load())
        .fold(f64::INFINITY, f64::min);
    ok.into_iter()
        .filter(|&i| points[i].load() <= cheapest * (1.0 + COST_TIE))
        .min_by(|&a, &b| {
            let (va, vb) = (axis.value(&points[a]), axis.value(&points[b]));
            va.total_cmp(&vb)
                .then(points[a].load().total_cmp(&points[b].load()))
                .then(a.cmp(&b))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::timing::TickTiming;
    use crate::sweep::{Accuracy, Knobs, MaxRms};
    use haptloop_solver::UpdateRule;

    fn point(rate_hz: u32, p50_ns: u64, force_error: f64, failed: u64) -> Point {
        let m = |v: f64| MaxRms { max: v, rms: v };
        Point {
            knobs: Knobs {
                iterations: 4,
                update: UpdateRule::Projected,
                gain: 1000.0,
                rate_hz,
                velocity_filter_ms: 10.0,
            },
            accuracy: Ok(Accuracy {
                violation_m: m(1e-9),
                force_error_n: m(force_error),
                force_max_n: 1.0,
                tracking_m: m(1e-3),
                failed_ticks: failed,
                failure_kinds: Default::default(),
                reference_samples: 10,
                reference_missing: None,
                penetration_m: f64::NAN,
            }),
            timing: Some(TickTiming {
                ticks: 100,
                p50_ns,
                p99_ns: p50_ns,
                max_ns: p50_ns,
                over_period: 0,
            }),
            passive: true,
            pareto: false,
            verdict: Verdict::Recommendable,
        }
    }

    #[test]
    fn the_front_is_the_undominated_clean_points_and_the_cheapest_good_one_is_recommended() {
        let c = Criteria {
            tolerance_m: Some(1e-6),
            force_tolerance: 0.01,
            penetration_tolerance_m: 1e-4,
        };
        let mut p = vec![
            point(1000, 10_000, 1e-3, 0),  // load 1 %, on the front
            point(1000, 20_000, 1e-3, 0),  // dominated by 0
            point(1000, 5_000, 0.5, 0),    // cheapest, on the front, force error too big
            point(1000, 30_000, 1e-6, 0),  // most accurate, on the front
            point(1000, 1_000, 1e-9, 3),   // failed ticks: never on the front
            point(1000, 600_000, 1e-9, 0), // p99 over half the period
        ];
        let r = mark(&mut p, Axis::ForceError, &c);
        let front: Vec<bool> = p.iter().map(|q| q.pareto).collect();
        assert_eq!(front, [true, false, true, true, false, true]);
        assert_eq!(p[2].verdict, Verdict::ForceError);
        assert_eq!(p[4].verdict, Verdict::FailedTicks);
        assert_eq!(p[5].verdict, Verdict::TooSlow);
        assert_eq!(r, Some(0));
        // Within 10 % of the cheapest cost, the more accurate point wins.
        p[1].timing.as_mut().unwrap().p50_ns = 10_500;
        p[1].accuracy.as_mut().unwrap().force_error_n.max = 1e-4;
        assert_eq!(mark(&mut p, Axis::ForceError, &c), Some(1));
        p[1].timing.as_mut().unwrap().p50_ns = 20_000;
        // Not passive: excluded, the next cheapest is taken.
        p[0].passive = false;
        assert_eq!(mark(&mut p, Axis::ForceError, &c), Some(1));
        assert_eq!(p[0].verdict, Verdict::NotPassive);
    }

    #[test]
    fn cost_is_cpu_load_so_a_cheap_tick_at_a_high_rate_can_cost_more() {
        let mut p = vec![point(10_000, 10_000, 1e-3, 0), point(1000, 50_000, 1e-3, 0)];
        let c = Criteria {
            tolerance_m: None,
            force_tolerance: 0.01,
            penetration_tolerance_m: 1e-4,
        };
        assert_eq!(mark(&mut p, Axis::ForceError, &c), Some(1));
        assert!((p[0].load() - 0.1).abs() < 1e-12 && (p[1].load() - 0.05).abs() < 1e-12);
        assert_eq!((p[0].pareto, p[1].pareto), (false, true));
    }

    /// A contact scene without joint rows measures neither force error nor
    /// violation: the front is cost against penetration, and a point over
    /// the penetration tolerance is never recommended.
    #[test]
    fn contact_scenes_trade_cost_against_penetration() {
        let mut p = vec![
            point(1000, 5_000, f64::NAN, 0),
            point(1000, 8_000, f64::NAN, 0),
            point(1000, 9_000, f64::NAN, 0),
        ];
        for (q, pen) in p.iter_mut().zip([3e-4, 5e-5, 6e-5]) {
            let a = q.accuracy.as_mut().unwrap();
            a.violation_m = MaxRms {
                max: f64::NAN,
                rms: f64::NAN,
            };
            a.penetration_m = pen;
        }
        assert_eq!(axis(&p), Axis::Penetration);
        let c = Criteria {
            tolerance_m: None,
            force_tolerance: 0.01,
            penetration_tolerance_m: 1e-4,
        };
        assert_eq!(mark(&mut p, Axis::Penetration, &c), Some(1));
        assert_eq!(p[0].verdict, Verdict::Penetration);
        let front: Vec<bool> = p.iter().map(|q| q.pareto).collect();
        assert_eq!(front, [true, true, false]);
    }
}
