//! The semantic layer in reports: `haptloop check`'s line, the
//! `"semantic"` section of `summary.json` (events with times and the grouping
//! graph at the end) and its lines in the text report.

use std::fmt::Write as _;

use haptloop_solver::scene::CompiledScene;
use serde::{Deserialize, Serialize};

use crate::session::SemanticReport;

/// One constraint event: `kind` is `snap`, `group_move`, `break` or
/// `release`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SemanticEvent {
    /// Session time, s.
    pub t_s: f64,
    /// What happened.
    pub kind: String,
    /// The bound body.
    pub binding_body: String,
    /// The body offering the area it is (or was) bound to; for a group move,
    /// the body that moved and carried it.
    pub offer_body: String,
}

/// The semantic figures of a run (absent for scenes without semantics).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Semantic {
    /// Constraint events in time order.
    pub events: Vec<SemanticEvent>,
    /// The grouping graph at the end: `[offer_body, binding_body]` edges,
    /// sorted.
    pub graph: Vec<[String; 2]>,
    /// What is not a constraint event, printed with them: an object at rest
    /// starting to move (`move`, with the finger holding it if one does) and
    /// the hand taking hold (`hold`) and letting go (`let_go`), the finger as
    /// `offer_body`.
    #[serde(default)]
    pub other_events: Vec<SemanticEvent>,
    /// Constraints satisfied when the scene loaded.
    pub loaded: usize,
    /// consistent(s) evaluations (after loading and every operation).
    pub consistency_checks: u64,
    /// Evaluations that found the scene inconsistent (0 is the invariant).
    pub inconsistent: u64,
    /// The first inconsistency, in words.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_inconsistency: Option<String>,
    /// Snaps whose pull had not arrived by the end.
    pub pending_at_end: usize,
    /// Longest time from a snap to its arrival, s (null: none arrived).
    #[serde(with = "super::figure")]
    pub arrival_max_s: f64,
    /// Programs sent for a semantic change.
    pub programs: u64,
    /// Changes whose program was not built or sent.
    pub program_failures: u64,
    /// Objects added (`[[schedule]] add`), removed, and adds that found no
    /// valid place.
    #[serde(default)]
    pub adds: u64,
    /// See `adds`.
    #[serde(default)]
    pub removes: u64,
    /// See `adds`. Such an add is tried again every 50 ms until it fits
    /// (`adds_late`) or its remove comes.
    #[serde(default)]
    pub add_failures: u64,
    /// Adds that found no place at their time and were placed later, and the
    /// longest wait, s (null: none).
    #[serde(default)]
    pub adds_late: u64,
    /// See `adds_late`.
    #[serde(with = "super::figure")]
    pub add_wait_max_s: f64,
    /// Adds still waiting for a valid place at the end: those bodies never
    /// entered the scene.
    #[serde(default)]
    pub adds_waiting_at_end: usize,
    /// Shaped objects in the scene at the end.
    #[serde(default)]
    pub objects_at_end: usize,
    /// Satisfied constraints at the end.
    #[serde(default)]
    pub constraints_at_end: usize,
    /// The interaction mode at the end (`constrained`, `unconstrained`).
    #[serde(default)]
    pub mode_at_end: String,
    /// One slow-loop semantic cycle, µs: mean and largest.
    #[serde(with = "super::figure")]
    pub cycle_us_mean: f64,
    /// Same, largest.
    #[serde(with = "super::figure")]
    pub cycle_us_max: f64,
}

impl From<&SemanticReport> for Semantic {
    fn from(r: &SemanticReport) -> Self {
        let (constraint, other): (Vec<_>, Vec<_>) =
            r.events.iter().partition(|e| e.kind.is_constraint());
        let ev = |e: &crate::session::Event| SemanticEvent {
            // Session time on the tick grid: no float noise in the file.
            t_s: (e.t_s * 1e6).round() / 1e6,
            kind: e.kind.as_str().to_owned(),
            binding_body: e.binding_body.clone(),
            offer_body: e.offer_body.clone(),
        };
        Semantic {
            events: constraint.into_iter().map(ev).collect(),
            graph: r
                .graph
                .iter()
                .map(|(a, b)| [a.clone(), b.clone()])
                .collect(),
            other_events: other.into_iter().map(ev).collect(),
            loaded: r.loaded,
            consistency_checks: r.checks,
            inconsistent: r.inconsistent,
            first_inconsistency: r.first_inconsistency.clone(),
            pending_at_end: r.pending_at_end,
            arrival_max_s: r.arrival_max_s,
            programs: r.programs,
            program_failures: r.program_failures,
            adds: r.adds,
            removes: r.removes,
            add_failures: r.add_failures,
            adds_late: r.adds_late,
            add_wait_max_s: r.add_wait_max_s,
            adds_waiting_at_end: r.adds_waiting_at_end,
            objects_at_end: r.present_at_end,
            constraints_at_end: r.constraints_at_end,
            mode_at_end: r.mode_at_end.to_owned(),
            cycle_us_mean: if r.cycles == 0 {
                f64::NAN
            } else {
                r.cycle_ns_sum as f64 / r.cycles as f64 / 1e3
            },
            cycle_us_max: r.cycle_ns_max as f64 / 1e3,
        }
    }
}

/// The lines of the end-of-run report: the events with their times (moves,
/// holds and let-gos included), then the grouping graph.
pub fn lines(out: &mut String, s: &Semantic) {
    let _ = writeln!(
        out,
        "semantic: {} constraints at load, {} events, {} programs ({} failed); consistent(s) {} of {} checks{}; \
         slow-loop cycle mean {:.0} µs, max {:.0} µs",
        s.loaded,
        s.events.len(),
        s.programs,
        s.program_failures,
        s.consistency_checks - s.inconsistent,
        s.consistency_checks,
        s.first_inconsistency
            .as_ref()
            .map_or(String::new(), |e| format!(" (first failure: {e})")),
        s.cycle_us_mean,
        s.cycle_us_max
    );
    let mut all: Vec<&SemanticEvent> = s.events.iter().chain(&s.other_events).collect();
    // At one time: the hand's grab, then what moves, then the constraints.
    let rank = |k: &str| match k {
        "hold" => 0,
        "move" => 1,
        "let_go" => 3,
        _ => 2,
    };
    all.sort_by(|a, b| {
        a.t_s
            .total_cmp(&b.t_s)
            .then(rank(&a.kind).cmp(&rank(&b.kind)))
    });
    for e in all {
        let what = match e.kind.as_str() {
            "snap" => format!("{} snaps onto {}", e.binding_body, e.offer_body),
            "group_move" => format!("{} carries {}", e.offer_body, e.binding_body),
            "break" => format!("{} pulled off {}", e.binding_body, e.offer_body),
            "release" => format!("{} clear of {}", e.binding_body, e.offer_body),
            "move" if e.offer_body.is_empty() => format!("{} moves", e.binding_body),
            "move" => format!("{} moves {}", e.offer_body, e.binding_body),
            "hold" => format!("{} takes hold of {}", e.offer_body, e.binding_body),
            "let_go" => format!("{} lets go of {}", e.offer_body, e.binding_body),
            "add" if e.offer_body.is_empty() => format!("{} added", e.binding_body),
            "add" => format!("{} added onto {}", e.binding_body, e.offer_body),
            "add_failed" => format!(
                "{} not added: no valid place yet (tried again every 50 ms)",
                e.binding_body
            ),
            "remove" => format!("{} removed", e.binding_body),
            "mode" => format!("{} mode", e.offer_body),
            other => format!("{other} {} {}", e.binding_body, e.offer_body),
        };
        let _ = writeln!(out, "  {:>7.3} s  {:<10} {what}", e.t_s, e.kind);
    }
    if s.pending_at_end > 0 {
        let _ = writeln!(
            out,
            "  {} snap{} still pulling at the end",
            s.pending_at_end,
            if s.pending_at_end == 1 { "" } else { "s" }
        );
    }
    if s.adds + s.removes + s.add_failures > 0 || s.mode_at_end == "unconstrained" {
        let late = if s.adds_late > 0 {
            format!(
                " ({} of them late: no valid place at first, added after up to {:.2} s)",
                s.adds_late, s.add_wait_max_s
            )
        } else {
            String::new()
        };
        let _ = writeln!(
            out,
            "objects: {} added{late}, {} removed, {} never added (still no valid place at the end); {} in the scene and {} constraints at the end; {} mode",
            s.adds,
            s.removes,
            s.adds_waiting_at_end,
            s.objects_at_end,
            s.constraints_at_end,
            s.mode_at_end
        );
    }
    if s.graph.is_empty() {
        let _ = writeln!(out, "grouping graph: empty");
    } else {
        let edges: Vec<String> = s.graph.iter().map(|[a, b]| format!("{a} → {b}")).collect();
        let _ = writeln!(out, "grouping graph: {}", edges.join(", "));
    }
}

/// `haptloop check`'s semantic line.
pub fn check_lines(c: &CompiledScene) -> String {
    match (&c.semantic, c.holds.len()) {
        (None, 0) => "  semantic     no areas\n".to_string(),
        (None, n) => format!("  semantic     no areas; {n} scheduled holds\n"),
        (Some(s), n) if c.schedule.is_empty() => format!("{}\n", areas_line(s, n)),
        (Some(s), n) => format!(
            "{}; {} scheduled operations ({} absent at the start)\n",
            areas_line(s, n),
            c.schedule.len(),
            c.absent.len()
        ),
    }
}

/// The areas, labels and settings of `s`, with `n` scheduled holds.
fn areas_line(s: &haptloop_solver::semantic::SemanticSpec, n: usize) -> String {
    let offers = s
        .areas
        .iter()
        .filter(|a| a.kind == haptloop_solver::semantic::AreaKind::Offer)
        .count();
    let labels: std::collections::BTreeSet<&str> = s
        .labels
        .iter()
        .map(String::as_str)
        .chain(s.order.iter().flat_map(|(a, b)| [a.as_str(), b.as_str()]))
        .chain(s.areas.iter().map(|a| a.label.as_str()))
        .collect();
    format!(
        "  semantic     {offers} offer and {} binding areas, {} labels; consistent at load; \
         snap within {} m / {:.2} rad, break at {} N; {n} scheduled holds",
        s.areas.len() - offers,
        labels.len(),
        s.settings.snap_distance_m,
        s.settings.snap_angle_rad,
        s.settings.break_force_n
    )
}
