//! `haptloop place SCENE --body B --goal x,y,z[,qw,qx,qy,qz] [--mode
//! pull|solve]`: Choi & Cremer's pull-to-goal and solve-for-goal (§4.3) on
//! a scene's mechanism, with subgoal subdivision where Newton-KKT does not
//! converge (`haptloop_solver::place`). Writes the scene with its bodies at
//! the placed configuration and reports Newton iterations per step.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use haptloop_solver::place::{Goal, Mode, PlaceOptions, Placed, place, pose};
use haptloop_solver::scene::BodyPose;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::scenes::resolve;

/// Exit status when the goal could not be reached (the file is still
/// written, at the last converged subgoal).
pub const EXIT_NOT_REACHED: u8 = 3;

/// The two modes of §4.3 besides dragging.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ModeArg {
    /// Closely spaced intermediate goals along the straight path.
    Pull,
    /// The final goal at once, subdivided only where Newton fails.
    Solve,
}

/// Arguments of `haptloop place`.
#[derive(Debug, Args)]
pub struct PlaceArgs {
    /// A scene file path or a built-in scene name.
    pub scene: String,
    /// The moving body to place (its origin goes to the goal).
    #[arg(long)]
    pub body: String,
    /// The goal: x,y,z (m, scene frame) and optionally an orientation
    /// qw,qx,qy,qz (normalised).
    #[arg(long, value_parser = goal, allow_hyphen_values = true)]
    pub goal: Goal,
    /// pull: intermediate goals every --step metres; solve: the goal at once.
    #[arg(long, value_enum, default_value = "pull")]
    pub mode: ModeArg,
    /// Pull: the longest intermediate step, m (> 0).
    #[arg(long, default_value_t = 0.005, value_parser = super::values::positive)]
    pub step: f64,
    /// Newton iterations per step past which a subgoal is split, 1–10000.
    #[arg(long, default_value_t = 8, value_parser = super::values::iterations)]
    pub max_iterations: u32,
    /// Ignore contact between shaped bodies (by default a placement holds
    /// their non-penetration inequalities: a body stops against what it
    /// meets).
    #[arg(long)]
    pub no_contact: bool,
    /// Where to write the placed scene (default: placed-<scene>.toml).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Parses `x,y,z[,qw,qx,qy,qz]`.
fn goal(s: &str) -> Result<Goal, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("`{s}`: {e}; expected x,y,z or x,y,z,qw,qx,qy,qz"))?;
    if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
        return Err(format!("`{s}`: {bad} is not a finite number"));
    }
    let orientation = match v.len() {
        3 => None,
        7 => {
            let q = Quaternion::new(v[3], v[4], v[5], v[6]);
            if q.norm() < 1e-9 {
                return Err(format!("`{s}`: the quaternion is zero"));
            }
            Some(UnitQuaternion::from_quaternion(q))
        }
        n => {
            return Err(format!(
                "`{s}`: {n} numbers; expected 3 (x,y,z) or 7 (x,y,z,qw,qx,qy,qz)"
            ));
        }
    };
    Ok(Goal {
        position_m: Vector3::new(v[0], v[1], v[2]),
        orientation,
    })
}

/// Runs the command: 0 when placed, 3 when the goal was not reached, 1
/// when the scene or body is invalid.
pub fn run(a: &PlaceArgs) -> Result<ExitCode> {
    let scene = match resolve(&a.scene) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return Ok(ExitCode::from(1));
        }
    };
    let opts = PlaceOptions {
        mode: match a.mode {
            ModeArg::Pull => Mode::Pull,
            ModeArg::Solve => Mode::Solve,
        },
        pull_step_m: a.step,
        contact: !a.no_contact,
        placement: haptloop_solver::PlacementOptions {
            max_iterations: a.max_iterations,
            ..haptloop_solver::PlacementOptions::default()
        },
        ..PlaceOptions::default()
    };
    let placed = match place(&scene.loaded.builder(), &a.body, &a.goal, &opts) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("haptloop: place {}: {e}", a.scene);
            return Ok(ExitCode::from(1));
        }
    };
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("placed-{}.toml", scene.compiled.name)));
    let text = scene.loaded.with_poses(&poses(&placed));
    // The written scene must load and hold the placed poses: checked here
    // before it is written.
    haptloop_solver::scene::parse(&out.display().to_string(), &text, None)
        .and_then(|l| l.compile())
        .map_err(|e| anyhow::anyhow!("the placed scene does not load: {e}"))?;
    super::output::write_atomic(&out, text.as_bytes())
        .with_context(|| format!("writing {}", out.display()))?;
    super::emit(&report(a, &placed, &out));
    Ok(match placed.at_goal() {
        true => ExitCode::SUCCESS,
        false => ExitCode::from(EXIT_NOT_REACHED),
    })
}

/// Every moving body's pose in the placed configuration.
fn poses(placed: &Placed) -> Vec<BodyPose> {
    let m = &placed.model;
    m.layout()
        .moving_bodies()
        .map(|(id, _)| {
            let (p, r) = pose(m, &placed.q, id);
            BodyPose {
                name: m.bodies()[id.index()].name.clone(),
                position_m: p.into(),
                orientation_wxyz: [r.w, r.i, r.j, r.k],
            }
        })
        .collect()
}

fn report(a: &PlaceArgs, p: &Placed, out: &std::path::Path) -> String {
    let mode = match a.mode {
        ModeArg::Pull => "pull",
        ModeArg::Solve => "solve",
    };
    let blocked = p.reached == 1.0 && !p.at_goal();
    let verdict = match p.at_goal() {
        true => "placed at the goal".to_owned(),
        false if blocked => format!(
            "BLOCKED by contact: the body rests {:.3} mm from its goal, against what it met",
            1e3 * p.goal_gap_m
        ),
        false => format!(
            "NOT REACHED: stopped at {:.1} % of the path (last solve {:?}); the file holds the last converged subgoal",
            100.0 * p.reached,
            p.last_status
        ),
    };
    let iters: Vec<String> = p
        .steps
        .iter()
        .map(|s| format!("{}{}", s.iterations, if s.blocked { "b" } else { "" }))
        .collect();
    let contact = match &p.contact {
        None => "none (fewer than two shaped bodies, or --no-contact)".to_owned(),
        Some(c) => format!(
            "{} pairs tracked at the end, {} backups, {} blocked steps (b), deepest penetration {:.2e} m",
            c.tracked_pairs, c.backups, c.blocked, c.max_penetration_m
        ),
    };
    format!(
        "place {} body {} mode {mode}: {verdict}\n  assembly     {} Newton iterations\n  steps        {} accepted, {} split (subgoal subdivision)\n  iterations   mean {:.2} per step, max {} (Choi & Cremer: fewer than 3 per drag step)\n  per step     {}\n  contact      {contact}\n  written      {}",
        a.scene,
        a.body,
        p.assembly_iterations,
        p.steps.len(),
        p.splits,
        if p.steps.is_empty() {
            0.0
        } else {
            p.mean_iterations()
        },
        p.max_iterations(),
        iters.join(" "),
        out.display()
    )
}
