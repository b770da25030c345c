//! `haptloop check FILE`: validate a scene and print what it compiles to.

use crate::scenes::{Scene, resolve};
use crate::session::{self, Plan, SessionOptions};
use anyhow::Result;
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::scene::SceneError;
use haptloop_solver::scene::{CompiledScene, HandPath};
use haptloop_solver::{Grasp, Model, RowUnit, Sense};
use std::collections::BTreeMap;
use std::process::ExitCode;

pub use super::preflight::DEFAULT_TRIAL_SECONDS;

/// Exit status of a scene that is valid but whose preflight found what
/// `run` will meet (warnings printed, each at the field to change; notes
/// alone leave the status 0).
pub const EXIT_FINDINGS: u8 = 3;

/// Validates `arg` (a file or built-in name), builds everything `run`
/// builds before its clock starts (fast-loop program with its gain check and
/// symbolic factorisation, placement analysis, assembly, devices) and runs
/// the preflight (`super::preflight`: the assembly, the hand's path against
/// the workspace, a `trial_seconds` deterministic trial). Prints the
/// compiled summary and the findings: exit 0 without a warning, 3 with
/// one; the located error and exit 1 when the scene cannot run.
/// A signal during the trial stops it; the command then says how far it
/// got and exits 130 without findings.
pub fn run(arg: &str, trial_seconds: f64, stop: &StopFlag) -> Result<ExitCode> {
    let scene = match resolve(arg) {
        Ok(scene) => scene,
        Err(e) => {
            eprintln!("{e}");
            return Ok(ExitCode::from(1));
        }
    };
    if let Err(e) = builds(&scene) {
        eprintln!("{e}");
        return Ok(ExitCode::from(1));
    }
    super::emit(summary(&scene).trim_end_matches('\n'));
    let findings = match super::preflight::findings(&scene, trial_seconds, stop) {
        Ok(_) if stop.is_requested() => {
            eprintln!(
                "haptloop check: interrupted during the {trial_seconds} s trial: no preflight \
                 findings (the scene loads and builds; `--seconds` shortens the trial)"
            );
            return Ok(ExitCode::from(super::EXIT_SIGNAL));
        }
        Ok(f) => f,
        Err(e) => {
            let l = &scene.loaded;
            eprintln!(
                "{}",
                l.error_at(
                    l.spec.scene.name.span(),
                    format!("the scene loads but its trial run failed: {e:#}")
                )
            );
            return Ok(ExitCode::from(1));
        }
    };
    let warnings = findings.iter().filter(|f| f.warning).count();
    let notes = findings.len() - warnings;
    if findings.is_empty() {
        super::emit(&format!(
            "  preflight    assembly, hand paths within the workspace, a {trial_seconds} s trial: nothing found"
        ));
        return Ok(ExitCode::SUCCESS);
    }
    super::emit(&format!(
        "  preflight    {warnings} warning{}, {notes} note{} (assembly, hand paths, a {trial_seconds} s trial):",
        if warnings == 1 { "" } else { "s" },
        if notes == 1 { "" } else { "s" }
    ));
    for f in &findings {
        eprintln!("{}", f.error);
    }
    if warnings == 0 {
        return Ok(ExitCode::SUCCESS);
    }
    Ok(ExitCode::from(EXIT_FINDINGS))
}

/// Builds what `run` builds for `scene` at its own settings, and turns a
/// failure into an error located at the scene's `[solver]` table (whose
/// settings the program is built from), else at its name.
pub fn builds(scene: &Scene) -> std::result::Result<(), SceneError> {
    let options = SessionOptions {
        seconds: 0.001,
        deterministic: true,
        ..SessionOptions::default()
    };
    let built = Plan::new(scene, &options)
        .and_then(|plan| session::build(scene, &plan, MockClock::new(Nanos(0))).map(|_| ()));
    built.map_err(|e| {
        let l = &scene.loaded;
        // Bodies that start inside each other: at the second body's
        // `position` (else its name).
        let overlap = e
            .chain()
            .find_map(|c| c.downcast_ref::<session::Interpenetration>());
        let body = overlap.and_then(|o| {
            l.spec
                .bodies
                .iter()
                .find(|b| *b.name.get_ref() == o.bodies[1])
                .map(|b| b.position.as_ref().map_or(b.name.span(), |p| p.span()))
        });
        let span = match (body, l.text.find("[solver]")) {
            (Some(span), _) => span,
            (None, Some(at)) => at..at + 1,
            (None, None) => l.spec.scene.name.span(),
        };
        l.error_at(span, format!("the scene loads but cannot run: {e:#}"))
    })
}

/// The compiled scene, one aspect per line.
pub fn summary(scene: &Scene) -> String {
    let c = &scene.compiled;
    let mut out = format!(
        "{}: ok — scene `{}`: {}\n",
        scene.loaded.file, c.name, c.description
    );
    out += &structure_lines(&c.model);
    out += &design_lines(&c.model);
    for o in &c.objectives.terms {
        out += &format!(
            "  objective    {} ({}, weight {})\n",
            o.name, o.kind, o.weight
        );
    }
    out += &row_lines(&c.model);
    out += &device_lines(c);
    out += &finger_lines(c);
    out += &contact_lines(c);
    out += &crate::report::semantic::check_lines(c);
    out
}

/// The bodies, coordinates, auxiliary blocks and constraints (count and
/// rows per kind) of `m`.
fn structure_lines(m: &Model) -> String {
    let moving = m.bodies().iter().filter(|b| !b.fixed).count();
    let design = m.layout().design_vars().len();
    let mut kinds: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    for k in m.constraints() {
        let e = kinds.entry(format!("{:?}", k.kind)).or_default();
        e.0 += 1;
        e.1 += k.rows.len();
    }
    let kinds: Vec<String> = kinds
        .iter()
        .map(|(k, (n, r))| format!("{n} {k} ({r} row{})", if *r == 1 { "" } else { "s" }))
        .collect();
    let mut out = format!(
        "  bodies       {} ({moving} moving with 7 coordinates each, {} fixed with none)\n",
        m.bodies().len(),
        m.bodies().len() - moving
    );
    out += &format!(
        "  coordinates  {} ({} body, {design} free design variable{}{})\n",
        m.n_coords(),
        m.layout().body_coords(),
        if design == 1 { "" } else { "s" },
        match m.layout().aux_coords() {
            0 => String::new(),
            n => format!(", {n} auxiliary"),
        }
    );
    for a in m.layout().aux_blocks() {
        out += &format!(
            "  auxiliary    {} ({} coordinates from column {})\n",
            a.name, a.width, a.offset
        );
    }
    out += &format!("  constraints  {}\n", kinds.join(", "));
    out
}

/// Each design variable of `m`: its components and bounds.
fn design_lines(m: &Model) -> String {
    let mut out = String::new();
    for d in m.layout().design_vars() {
        let bounds = d.bounds.map_or("unbounded".to_string(), |b| {
            let r: Vec<String> = b[..d.width]
                .iter()
                .map(|[lo, hi]| format!("[{lo}, {hi}]"))
                .collect();
            format!("bounds {}", r.join(" "))
        });
        let parts = if d.width == 1 {
            "1 component".to_string()
        } else {
            format!("{} components", d.width)
        };
        out += &format!("  design       {} ({parts}, m; {bounds})\n", d.name);
    }
    out
}

/// The rows of `m` by sense and unit, and its Jacobian's size.
fn row_lines(m: &Model) -> String {
    let angle_rows = m.rows().iter().filter(|r| r.unit == RowUnit::Angle).count();
    let ineq = m
        .rows()
        .iter()
        .filter(|r| r.sense == Sense::Inequality)
        .count();
    let nnz = m.evaluation().jacobian().nnz();
    let mut out = format!(
        "  rows         {} ({} equality, {ineq} inequality; {angle_rows} angular)\n",
        m.n_rows(),
        m.n_rows() - ineq
    );
    out += &format!(
        "  jacobian     {} × {}, {nnz} stored nonzeros\n",
        m.n_rows(),
        m.n_coords()
    );
    out
}

/// Each device: model, scale and the hand's path.
fn device_lines(c: &CompiledScene) -> String {
    let mut out = String::new();
    for d in &c.devices {
        let hand = match &d.hand.path {
            HandPath::Still => "still".to_string(),
            HandPath::Circle { radius_m, hz, .. } => format!("circle r = {radius_m} m at {hz} Hz"),
            HandPath::Line { to_m, seconds } => format!("line to {to_m:?} m over {seconds} s"),
            HandPath::Waypoints { points } => format!(
                "{} waypoints over {} s",
                points.len(),
                points.last().map_or(0.0, |p| p[0])
            ),
            HandPath::Trace { path, .. } => format!("trace {}", path.display()),
        };
        out += &format!(
            "  device       {} ({}, scale {}, hand {hand})\n",
            d.name, d.model, d.scale
        );
    }
    out
}

/// Each finger: its device, body and grasp.
fn finger_lines(c: &CompiledScene) -> String {
    let m = &c.model;
    let mut out = String::new();
    for f in &c.fingers {
        let mf = &m.fingers()[f.finger.index()];
        let grasp = match mf.grasp {
            Grasp::Point => "point grasp, 3 rows",
            Grasp::Rigid => "rigid grasp, 6 rows",
            Grasp::Contact => "contact fingertip, 3 rows",
        };
        out += &format!(
            "  finger       {} → device {}, body {}, {grasp}\n",
            f.name,
            c.devices[f.device].name,
            m.bodies()[mf.body.index()].name
        );
    }
    out
}

/// Whether contact is compiled, and every hull cut to the vertex budget.
fn contact_lines(c: &CompiledScene) -> String {
    let mut out = match c.shaped_bodies {
        0 => "  contact      no shapes: no contact machinery compiled\n".to_string(),
        n => format!(
            "  contact      {n} shaped bod{}: witnesses on the slow loop, their rows in the fast loop\n",
            if n == 1 { "y" } else { "ies" }
        ),
    };
    for b in c.model.bodies() {
        if let Some(h) = &b.hull {
            out += &format!(
                "  hull         {}: {} points cut to {} (at most {} per hull); the shape lies within {:.3} mm of the one given\n",
                b.name,
                h.from_points,
                h.vertices,
                haptloop_solver::geometry::MAX_HULL_VERTICES,
                h.error_m * 1e3
            );
        }
    }
    out
}
