//! What `haptloop sweep` prints and writes: a table, `sweep.csv`,
//! `sweep.json` and `front.svg` (CPU load against accuracy, the front joined,
//! the recommendation circled).

use crate::sweep::{Axis, MaxRms, Point, Sweep, Verdict};
use anyhow::Result;
use haptloop_solver::UpdateRule;
use serde::Serialize;
use std::fmt::Write as _;

mod front;
pub use front::front_svg;

pub(crate) fn rule(u: UpdateRule) -> &'static str {
    match u {
        UpdateRule::Projected => "projected",
        UpdateRule::Gradient => "gradient",
    }
}

/// The rule column: the update rule, and the force solver unless it is the
/// Cholesky (`projected matvec`).
fn rule_label(k: &crate::sweep::Knobs) -> String {
    match k.force_solver {
        haptloop_solver::ForceSolver::Cholesky => rule(k.update).to_string(),
        f => format!("{} {}", rule(k.update), f.label()),
    }
}

/// A max/RMS pair as `sweep.json` writes it (non-finite by name).
#[derive(Debug, Clone, Copy, Serialize)]
struct Fig {
    #[serde(with = "super::figure")]
    max: f64,
    #[serde(with = "super::figure")]
    rms: f64,
}

impl From<MaxRms> for Fig {
    fn from(m: MaxRms) -> Self {
        Fig {
            max: m.max,
            rms: m.rms,
        }
    }
}

/// Tick time, ns (`"NaN"` for a point that did not run).
#[derive(Debug, Clone, Copy, Serialize)]
struct TickNs {
    #[serde(with = "super::figure")]
    p50: f64,
    #[serde(with = "super::figure")]
    p99: f64,
    #[serde(with = "super::figure")]
    max: f64,
}

#[derive(Debug, Clone, Serialize)]
struct JsonPoint {
    iterations: u32,
    update: &'static str,
    /// `cholesky`, `matvec` or `matvec:N`.
    force_solver: String,
    gain: f64,
    rate_hz: u32,
    velocity_filter_ms: f64,
    tick_ns: TickNs,
    /// Ticks over the period (compute alone).
    overruns: Option<u64>,
    /// Fraction of a core: tick p50 × rate.
    #[serde(with = "super::figure")]
    load: f64,
    violation_m: Fig,
    force_error_n: Fig,
    #[serde(with = "super::figure")]
    force_max_n: f64,
    tracking_m: Fig,
    failed_ticks: Option<u64>,
    failure_kinds: std::collections::BTreeMap<String, u64>,
    reference_samples: u64,
    reference_missing: Option<String>,
    /// Largest penetration, m (`"NaN"`: no contact machinery).
    #[serde(with = "super::figure")]
    penetration_m: f64,
    passive: bool,
    pareto: bool,
    verdict: &'static str,
    /// Why the point did not run, if it did not.
    error: Option<String>,
}

#[derive(Debug, Clone, Serialize)]
struct JsonSweep<'a> {
    scene: &'a str,
    seconds: f64,
    reference_every_ms: f64,
    tolerance_m: Option<f64>,
    force_tolerance: f64,
    axis: &'static str,
    points: Vec<JsonPoint>,
    recommended: Option<usize>,
    /// Stopped by a signal before every point was measured and timed.
    stopped_early: bool,
    /// Per point that is not recommendable, why (the first criterion it
    /// misses), as the table's last column says.
    not_recommended: Vec<String>,
}

fn json_point(p: &Point) -> JsonPoint {
    let nan = MaxRms {
        max: f64::NAN,
        rms: f64::NAN,
    };
    let (a, error) = match &p.accuracy {
        Ok(a) => (Some(a), None),
        Err(e) => (None, Some(e.clone())),
    };
    let t = p.timing;
    let ns = |f: fn(&crate::session::timing::TickTiming) -> u64| {
        t.as_ref().map_or(f64::NAN, |t| f(t) as f64)
    };
    JsonPoint {
        iterations: p.knobs.iterations,
        update: rule(p.knobs.update),
        force_solver: p.knobs.force_solver.label(),
        gain: p.knobs.gain,
        rate_hz: p.knobs.rate_hz,
        velocity_filter_ms: p.knobs.velocity_filter_ms,
        tick_ns: TickNs {
            p50: ns(|t| t.p50_ns),
            p99: ns(|t| t.p99_ns),
            max: ns(|t| t.max_ns),
        },
        overruns: t.map(|t| t.over_period),
        load: p.load(),
        violation_m: a.map_or(nan, |a| a.violation_m).into(),
        force_error_n: a.map_or(nan, |a| a.force_error_n).into(),
        force_max_n: a.map_or(f64::NAN, |a| a.force_max_n),
        tracking_m: a.map_or(nan, |a| a.tracking_m).into(),
        failed_ticks: a.map(|a| a.failed_ticks),
        failure_kinds: a.map(|a| a.failure_kinds.clone()).unwrap_or_default(),
        reference_samples: a.map_or(0, |a| a.reference_samples),
        reference_missing: a.and_then(|a| a.reference_missing.clone()),
        penetration_m: a.map_or(f64::NAN, |a| a.penetration_m),
        passive: p.passive,
        pareto: p.pareto,
        verdict: p.verdict.as_str(),
        error,
    }
}

/// `sweep.json`.
pub fn json(s: &Sweep) -> Result<String> {
    let j = JsonSweep {
        scene: &s.scene,
        seconds: s.seconds,
        reference_every_ms: s.reference_every.as_secs_f64() * 1e3,
        tolerance_m: s.tolerance_m,
        force_tolerance: s.criteria.force_tolerance,
        axis: s.axis.as_str(),
        points: s.points.iter().map(json_point).collect(),
        recommended: s.recommended,
        stopped_early: s.stopped_early,
        not_recommended: reasons(s),
    };
    Ok(serde_json::to_string_pretty(&j)? + "\n")
}

/// `sweep.csv`: one row per point, the same fields as `sweep.json` (figures
/// that were not measured are `NaN`).
pub fn csv(s: &Sweep) -> String {
    let mut out = String::from(
        "index,iterations,update,force_solver,gain,rate_hz,velocity_filter_ms,tick_p50_ns,tick_p99_ns,tick_max_ns,\
         overruns,load,violation_max_m,violation_rms_m,force_error_max_n,force_error_rms_n,force_max_n,\
         tracking_max_m,tracking_rms_m,failed_ticks,reference_samples,penetration_m,passive,pareto,recommended,verdict\n",
    );
    for (i, p) in s.points.iter().enumerate() {
        let j = json_point(p);
        let _ = writeln!(
            out,
            "{i},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            j.iterations,
            j.update,
            j.force_solver,
            j.gain,
            j.rate_hz,
            j.velocity_filter_ms,
            j.tick_ns.p50,
            j.tick_ns.p99,
            j.tick_ns.max,
            j.overruns.map_or("NaN".into(), |v| v.to_string()),
            j.load,
            j.violation_m.max,
            j.violation_m.rms,
            j.force_error_n.max,
            j.force_error_n.rms,
            j.force_max_n,
            j.tracking_m.max,
            j.tracking_m.rms,
            j.failed_ticks.map_or("NaN".into(), |v| v.to_string()),
            j.reference_samples,
            j.penetration_m,
            j.passive,
            j.pareto,
            s.recommended == Some(i),
            j.verdict,
        );
    }
    out
}

fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2e}")
    } else {
        "–".into()
    }
}

/// The table printed at the end of a sweep.
pub fn table(s: &Sweep) -> String {
    let mut out = header(s);
    for (i, p) in s.points.iter().enumerate() {
        out.push_str(&row(s, i, p));
    }
    out.push('\n');
    out.push_str(&front_line(s));
    out.push_str(&recommendation(s));
    out
}

/// The title line and the column heads.
fn header(s: &Sweep) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "haptloop sweep {}: {} points, {} s each (deterministic); reference every {}{}",
        s.scene,
        s.points.len(),
        s.seconds,
        if s.reference_every.is_zero() {
            "tick".to_string()
        } else {
            format!("{:.0} ms", s.reference_every.as_secs_f64() * 1e3)
        },
        if s.stopped_early {
            " — STOPPED EARLY: points not measured or not timed say so"
        } else {
            ""
        }
    );
    let _ = writeln!(
        out,
        "\n  {:>3} {:<16} {:>3} {:>7} {:>6} {:>5} {:>8} {:>8} {:>6} {:>5} {:>9} {:>9} {:>9} {:>8} {:>6}  front · verdict",
        "#",
        "rule",
        "it",
        "K",
        "Hz",
        "τ ms",
        "p50 µs",
        "p99 µs",
        "load",
        "over",
        "viol max",
        "F err max",
        "F err RMS",
        "track mm",
        "failed",
    );
    out
}

/// One point's row: a point not timed or not run shows "–", never 0.
fn row(s: &Sweep, i: usize, p: &Point) -> String {
    let k = &p.knobs;
    let (tp50, tp99, over) = p.timing.map_or(("–".into(), "–".into(), "–".into()), |t| {
        (
            format!("{:.1}", t.p50_ns as f64 / 1e3),
            format!("{:.1}", t.p99_ns as f64 / 1e3),
            t.over_period.to_string(),
        )
    });
    let load = if p.load().is_finite() {
        format!("{:.1}%", 100.0 * p.load())
    } else {
        "–".into()
    };
    let (viol, fmax, frms, track, failed) = match &p.accuracy {
        Ok(a) => (
            sci(a.violation_m.max),
            sci(a.force_error_n.max),
            sci(a.force_error_n.rms),
            if a.tracking_m.rms.is_finite() {
                format!("{:.2}", a.tracking_m.rms * 1e3)
            } else {
                "–".into()
            },
            a.failed_ticks.to_string(),
        ),
        Err(_) => ("–".into(), "–".into(), "–".into(), "–".into(), "–".into()),
    };
    let mark = match (p.pareto, s.recommended == Some(i)) {
        (_, true) => "* ◀ recommended",
        (true, false) => "*",
        (false, false) => " ",
    };
    let verdict = match (&p.accuracy, p.verdict) {
        (Err(e), _) => format!("not run: {e}"),
        (_, Verdict::Recommendable) => String::new(),
        (_, v) => v.as_str().to_string(),
    };
    format!(
        "  {i:>3} {:<16} {:>3} {:>7} {:>6} {:>5} {tp50:>8} {tp99:>8} {load:>6} {over:>5} {viol:>9} {fmax:>9} {frms:>9} {track:>8} {failed:>6}  {mark} {verdict}\n",
        rule_label(k),
        k.iterations,
        format!("{}", k.gain),
        k.rate_hz,
        format!("{}", k.velocity_filter_ms),
    )
}

/// What the front is drawn against, and why when it is not the force error.
fn front_line(s: &Sweep) -> String {
    match s.axis {
        Axis::None => "no Pareto front: neither the force error, a violation nor a penetration is measured in this scene\n".to_string(),
        a => {
            let why = if matches!(a, Axis::Violation | Axis::Penetration) {
                let why = s
                    .points
                    .iter()
                    .find_map(|p| p.accuracy.as_ref().ok()?.reference_missing.clone())
                    .unwrap_or_default();
                format!(" (force error not measured: {why})")
            } else {
                String::new()
            };
            format!("front (*): CPU load (tick p50 × rate) against {}{why}\n", a.as_str())
        }
    }
}

/// The criteria a recommended point meets, naming only what was measured.
fn criteria(s: &Sweep) -> String {
    let measured = |f: fn(&crate::sweep::Accuracy) -> f64| {
        s.points
            .iter()
            .any(|p| p.accuracy.as_ref().is_ok_and(|a| f(a).is_finite()))
    };
    let violation = match s.tolerance_m {
        Some(t) if measured(|a| a.violation_m.max) => format!("violation within {t:e} m, "),
        Some(_) => "violation (not measured), ".to_string(),
        None => "violation (no scene tolerance), ".to_string(),
    };
    let force = if measured(|a| a.force_error_n.max) {
        format!(
            "force error within {:.0} % of the largest force, ",
            s.criteria.force_tolerance * 100.0
        )
    } else {
        "force error (not measured), ".to_string()
    };
    let penetration = if measured(|a| a.penetration_m) {
        format!(
            "penetration within {:e} m, ",
            s.criteria.penetration_tolerance_m
        )
    } else {
        String::new()
    };
    format!(
        "no failed tick, {violation}{force}{penetration}p99 tick within half the period, coupling passive \
         at the rate for a relaxed grip"
    )
}

/// The recommended point, or why each point misses.
fn recommendation(s: &Sweep) -> String {
    let crit = criteria(s);
    let mut out = String::new();
    match s.recommended {
        Some(i) => {
            let p = &s.points[i];
            let k = &p.knobs;
            let _ = writeln!(
                out,
                "recommended: #{i}: {} update, {} iteration{}, gain {}, {} Hz, velocity filter {} ms \
                 ({:.1} % of a core) — the cheapest point with {crit}",
                rule_label(k),
                k.iterations,
                if k.iterations == 1 { "" } else { "s" },
                k.gain,
                k.rate_hz,
                k.velocity_filter_ms,
                100.0 * p.load(),
            );
        }
        None => {
            let _ = writeln!(
                out,
                "recommended: none: a recommended point needs {crit}; each point misses one:"
            );
            for line in reasons(s) {
                let _ = writeln!(out, "  {line}");
            }
        }
    }
    out
}

/// Why the points are not recommendable, one line per reason with the
/// points it stops (`coupling not passive: #0, #3`), in the order the
/// criteria are checked.
fn reasons(s: &Sweep) -> Vec<String> {
    let mut by: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, p) in s.points.iter().enumerate() {
        let why = match (&p.accuracy, p.verdict) {
            (_, Verdict::Recommendable) => continue,
            (Err(e), _) => format!("not run ({e})"),
            (_, v) => v.as_str().to_string(),
        };
        match by.iter_mut().find(|(w, _)| *w == why) {
            Some((_, pts)) => pts.push(i),
            None => by.push((why, vec![i])),
        }
    }
    by.into_iter()
        .map(|(why, pts)| {
            let list: Vec<String> = pts.iter().map(|i| format!("#{i}")).collect();
            format!("{why}: {}", list.join(", "))
        })
        .collect()
}
