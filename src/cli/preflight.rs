//! `check`'s preflight: what `run` will meet, tried before it does, each
//! finding located at the field to change.
//!
//! * the assembly: Newton-KKT placement from the file's configuration; one
//!   that ends in `LeastSquares` lists its residual and the rows that
//!   conflict, at the first joint among them;
//! * the hand's path against the device's workspace box (device frame, from
//!   the home pose where the arm starts): a path that leaves it ends at the
//!   arm's mechanical stop;
//! * a short deterministic trial of the session: failed ticks, forces asked
//!   above the device's peak, a mean square force above its continuous
//!   rating (a note: when the thermal model would cut it if that lasted),
//!   the limits the devices met (workspace stops, saturation, thermal cuts).
//!
//! Warnings are what `run` will meet (`check` exits 3); notes are what it
//! may meet (printed, the exit status unchanged).
//!
//! Bodies that interpenetrate at the start are refused by `run` itself (the
//! session will not start), so `check` refuses them too.

use crate::scenes::Scene;
use crate::session::{self, Plan, SessionOptions};
use haptloop_devices::{Mount, PhantomModel};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::scene::SceneError;
use haptloop_solver::{Placement, PlacementOptions, Sense, SolveStatus};
use nalgebra::Vector3;
use std::ops::Range;
use std::time::Duration;

/// Default length of the trial, s: the fast loop at the scene's rate on the
/// mock clock (about 0.1–5 s of wall time for the built-in scenes); the
/// force after the 1 s start-up ramp is what the thermal estimate uses.
pub const DEFAULT_TRIAL_SECONDS: f64 = 2.0;

/// Rows of a least-squares assembly listed, at most.
const CONFLICT_ROWS: usize = 5;

/// One finding: a warning (what `run` will meet) or a note (what it may
/// meet: a trial's figure that matters only if it lasts).
#[derive(Debug, Clone)]
pub struct Finding {
    /// True for a warning (the exit status says so), false for a note.
    pub warning: bool,
    /// Where, and what.
    pub error: SceneError,
}

/// Every finding, in the order above (empty when nothing was found).
/// `stop` (the command's signal flag) ends the trial at its next tick.
pub fn findings(
    scene: &Scene,
    trial_seconds: f64,
    stop: &StopFlag,
) -> anyhow::Result<Vec<Finding>> {
    let mut out = Vec::new();
    out.extend(assembly(scene)?);
    out.extend(workspace(scene)?);
    out.extend(trial(scene, trial_seconds, stop)?);
    Ok(out)
}

fn warning(scene: &Scene, span: Range<usize>, message: String) -> Finding {
    Finding {
        warning: true,
        error: scene.loaded.error_at(span, format!("warning: {message}")),
    }
}

fn note(scene: &Scene, span: Range<usize>, message: String) -> Finding {
    Finding {
        warning: false,
        error: scene.loaded.error_at(span, format!("note: {message}")),
    }
}

/// Where a joint named `name` is written (else the scene's name).
fn joint_span(scene: &Scene, name: &str) -> Range<usize> {
    let joint = name.split('.').next().unwrap_or(name);
    scene
        .loaded
        .spec
        .joints
        .iter()
        .filter_map(|j| j.name.as_ref())
        .find(|n| n.get_ref() == joint)
        .map_or(scene.loaded.spec.scene.name.span(), |n| n.span())
}

/// The assembly `run` starts with: a least-squares end names its rows.
fn assembly(scene: &Scene) -> anyhow::Result<Option<Finding>> {
    let model = &scene.compiled.model;
    let plan = Plan::new(scene, &trial_options(0.001))?;
    let options = PlacementOptions::from_scene(
        Some(plan.assembly_tolerance_m),
        scene.compiled.settings.damping,
    );
    let mut placement = Placement::analyze(model, &options)?;
    let mut q = model.q0().to_vec();
    let targets = model.initial_targets();
    let info = placement.solve(model, &mut q, model.q0(), &targets)?;
    if info.status != SolveStatus::LeastSquares {
        return Ok(None);
    }
    let mut ev = model.evaluation();
    ev.evaluate_values(model, &q, &targets)?;
    let mut rows: Vec<(f64, usize)> = model
        .rows()
        .iter()
        .zip(ev.values())
        .enumerate()
        .map(|(k, (r, &v))| {
            let miss = match r.sense {
                Sense::Equality => v.abs(),
                Sense::Inequality => (-v).max(0.0),
                Sense::Friction => 0.0,
            };
            (miss, k)
        })
        .filter(|(miss, _)| *miss > plan.assembly_tolerance_m)
        .collect();
    rows.sort_by(|a, b| b.0.total_cmp(&a.0));
    let named: Vec<String> = rows
        .iter()
        .take(CONFLICT_ROWS)
        .map(|&(miss, k)| {
            let r = &model.rows()[k];
            let c = &model.constraints()[r.constraint.index()];
            let unit = match r.unit {
                haptloop_solver::RowUnit::Length => "m",
                haptloop_solver::RowUnit::Angle => "rad",
                haptloop_solver::RowUnit::Dimensionless => "",
            };
            format!("`{}` row {} ({miss:.2e} {unit})", c.name, k - c.rows.start)
        })
        .collect();
    let first = rows
        .first()
        .map(|&(_, k)| {
            model.constraints()[model.rows()[k].constraint.index()]
                .name
                .clone()
        })
        .unwrap_or_default();
    Ok(Some(warning(
        scene,
        joint_span(scene, &first),
        format!(
            "the assembly ends in LeastSquares: residual {:.2e} m after {} iterations; the rows \
             that conflict, largest first: {}{} — these joints cannot all close at once: change \
             the `anchor_i`, `anchor_j` or `length` of one of them (or start with --no-assembly \
             to watch it)",
            info.residual_length_m,
            info.iterations,
            named.join(", "),
            if rows.len() > CONFLICT_ROWS {
                format!(" and {} more", rows.len() - CONFLICT_ROWS)
            } else {
                String::new()
            }
        ),
    )))
}

/// Each device's hand path against its workspace box.
fn workspace(scene: &Scene) -> anyhow::Result<Vec<Finding>> {
    let mut out = Vec::new();
    for (k, d) in scene.compiled.devices.iter().enumerate() {
        let model = PhantomModel::by_name(&d.model)?;
        let mount = Mount::new(Vector3::zeros(), d.orientation_wxyz, d.scale)?;
        let path = session::device_trajectory(&d.hand.path, scene.traces[k].as_ref(), &mount);
        let (lo, hi) = path.extent(Duration::from_secs(86_400));
        let half = model.workspace_half_extent_m;
        let axes = ["x", "y", "z"];
        let outside: Vec<String> = (0..3)
            .filter(|&i| lo[i] < -half[i] || hi[i] > half[i])
            .map(|i| {
                let reach = if hi[i] > half[i] { hi[i] } else { lo[i] };
                format!(
                    "{} = {:.3} m (the box is ±{:.3} m)",
                    axes[i], reach, half[i]
                )
            })
            .collect();
        if outside.is_empty() {
            continue;
        }
        let spec = scene.loaded.spec.devices.get(k);
        let span = spec
            .and_then(|s| s.hand.as_ref().map(|h| h.span()))
            .or_else(|| spec.map(|s| s.name.span()))
            .unwrap_or(scene.loaded.spec.scene.name.span());
        out.push(warning(
            scene,
            span,
            format!(
                "device `{}`: the hand's path leaves the {}'s workspace box (device frame, from \
                 the home pose where the arm starts): it reaches {}; there the arm sits at its \
                 mechanical stop and the scene's force is not what the user feels — shrink the \
                 path, or change the device's `scale` (scene metres per device metre, now {})",
                d.name,
                d.model,
                outside.join(", "),
                d.scale
            ),
        ));
    }
    Ok(out)
}

/// The trial's tick against the period it must fit in real time (the
/// monotonic clock's whole tick; the trial itself runs on a mock clock). A
/// median over twice the period is a warning: most ticks of a real-time run
/// would overrun, whatever the machine's load. The tail is not judged here:
/// on a shared machine it measures the load, not the scene.
fn tick_cost(scene: &Scene, o: &session::SessionOutcome, seconds: f64) -> Option<Finding> {
    let t = o.stats.stages.tick.summary();
    let period_us = 1e6 / f64::from(o.plan.rate_hz);
    let p50 = t.p50 as f64 / 1e3;
    if t.count == 0 || p50 <= 2.0 * period_us {
        return None;
    }
    let span = match scene.loaded.text.find("[solver]") {
        Some(at) => at..at + 1,
        None => scene.loaded.spec.scene.name.span(),
    };
    Some(warning(
        scene,
        span,
        format!(
            "in a {seconds} s trial the tick costs {p50:.0} µs at the median, over twice the \
             {period_us:.0} µs period at {} Hz: most ticks of a real-time run would overrun — \
             lower `[solver] rate_hz` or `iterations`, or make the scene smaller (`haptloop \
             run --deterministic` reports the tick's stages)",
            o.plan.rate_hz
        ),
    ))
}

fn trial_options(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

/// A deterministic trial of the session.
fn trial(scene: &Scene, seconds: f64, stop: &StopFlag) -> anyhow::Result<Vec<Finding>> {
    let plan = Plan::new(scene, &trial_options(seconds))?;
    let o = session::run(scene, plan, stop, &mut |_| {})?;
    let mut out = Vec::new();
    out.extend(tick_cost(scene, &o, seconds));
    out.extend(failures(scene, &o, seconds));
    for k in 0..scene.compiled.devices.len() {
        out.extend(device_load(scene, &o, seconds, k)?);
    }
    out.extend(device_limits(scene, &o, seconds));
    Ok(out)
}

/// The span a finding about device `k` points at: its model, else the
/// scene's name.
fn device_span(scene: &Scene, k: usize) -> Range<usize> {
    let name_span = scene.loaded.spec.scene.name.span();
    scene
        .loaded
        .spec
        .devices
        .get(k)
        .map_or(name_span, |d| d.model.span())
}

/// The trial's failed ticks, by kind (a warning: zero force was written
/// on them).
fn failures(scene: &Scene, o: &session::SessionOutcome, seconds: f64) -> Option<Finding> {
    let s = &o.stats;
    if s.solver_failures == 0 {
        return None;
    }
    let kinds: Vec<String> = session::FailureKind::ALL
        .iter()
        .zip(&s.failure_kinds)
        .filter(|(_, n)| **n > 0)
        .map(|(k, n)| format!("{} × {n}", k.as_str()))
        .collect();
    let span = match scene.loaded.text.find("[solver]") {
        Some(at) => at..at + 1,
        None => scene.loaded.spec.scene.name.span(),
    };
    Some(warning(
        scene,
        span,
        format!(
            "in a {seconds} s trial, {} of {} ticks failed ({}): zero force was written on \
             them; see `haptloop run` for the figures, and the `[solver]` settings",
            s.solver_failures,
            s.ticks,
            kinds.join(", ")
        ),
    ))
}

/// Device `k`'s load in the trial against its model's ratings: a force
/// asked above its peak (a warning), an RMS force after the start-up ramp
/// above its continuous rating (a note: the thermal model would cut it).
fn device_load(
    scene: &Scene,
    o: &session::SessionOutcome,
    seconds: f64,
    k: usize,
) -> anyhow::Result<Vec<Finding>> {
    let d = &scene.compiled.devices[k];
    let s = &o.stats;
    let mut out = Vec::new();
    let model = PhantomModel::by_name(&d.model)?;
    let fingers: Vec<usize> = scene
        .compiled
        .fingers
        .iter()
        .filter(|f| f.device == k)
        .map(|f| f.finger.index())
        .collect();
    let asked = fingers
        .iter()
        .map(|&i| s.fingers[i].commanded_max)
        .fold(0.0, f64::max);
    // What heats the motors: the force rendered once the start-up ramp
    // is over (the assembly's first moments are not the run's).
    let ramp = haptloop_devices::SafetyConfig::default().ramp.as_secs_f64();
    let mean_sq = fingers
        .iter()
        .map(|&i| {
            let late: Vec<f64> = o.recorder.force[i]
                .points
                .iter()
                .filter(|(t, _)| *t >= ramp)
                .map(|(_, f)| f * f)
                .collect();
            late.iter().sum::<f64>() / late.len().max(1) as f64
        })
        .fold(0.0, f64::max);
    let what = "change `[solver] coupling_stiffness`, the hand's path or the bodies' masses, \
                or use a stronger device `model`";
    if asked > model.peak_force_n {
        out.push(warning(
            scene,
            device_span(scene, k),
            format!(
                "device `{}`: in a {seconds} s trial the solver asks for up to {asked:.3} N, \
                 above the {}'s {} N peak force: the safety layer clamps it and the user \
                 feels less than the scene — {what}",
                d.name, d.model, model.peak_force_n
            ),
        ));
    }
    let cont = model.continuous_force_n;
    let cut_already = o.device_limits.get(k).is_some_and(|l| l.thermal_cut > 0);
    if mean_sq > cont * cont && !cut_already {
        let steady = mean_sq / (cont * cont);
        let after = -model.thermal_time_constant_s * (1.0 - 1.0 / steady).ln();
        out.push(note(
            scene,
            device_span(scene, k),
            format!(
                "device `{}`: in a {seconds} s trial the force after the start-up ramp is \
                 {:.3} N RMS, above the {}'s {cont} N continuous rating: if that lasts, the \
                 thermal model cuts the force to {cont} N after about {after:.1} s of a run \
                 (a run's report says whether it did) — {what}",
                d.name,
                mean_sq.sqrt(),
                d.model
            ),
        ));
    }
    Ok(out)
}

/// The devices' limits the trial met (workspace stops, thermal cuts, motor
/// saturation), a warning per device.
fn device_limits(scene: &Scene, o: &session::SessionOutcome, seconds: f64) -> Vec<Finding> {
    let mut out = Vec::new();
    for (k, l) in o.device_limits.iter().enumerate() {
        let met: Vec<String> = [
            (l.outside_workspace, "at a workspace stop"),
            (l.thermal_cut, "cut by the thermal model"),
            (l.motor_saturation, "with a motor torque saturated"),
        ]
        .into_iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{what} on {n} ticks"))
        .collect();
        if !met.is_empty() {
            out.push(warning(
                scene,
                device_span(scene, k),
                format!(
                    "device `{}` in a {seconds} s trial: {}",
                    l.device,
                    met.join(", ")
                ),
            ));
        }
    }
    out
}
