//! Placing one body at a goal (Choi & Cremer §4.3, the interaction modes
//! besides dragging): *pull to goal* (closely spaced intermediate goals along
//! the straight path, each solved) and *solve for goal* (the final goal at
//! once). In both, a goal at which Newton-KKT does not converge within the
//! per-step iteration cap is "inappropriate" (§5): the step is split in two
//! halves, recursively, and the halves are solved in turn (subgoal
//! subdivision).
//!
//! ```text
//!  ModelBuilder (scene or mechanism) ─► goal model: its bodies and joints,
//!      one goal finger at body B's origin (point, or rigid with an orientation)
//!  q0 ─► assemble with the goal at B's q0 pose ─► path p(t), R(t), t ∈ [0, 1]
//!      pull: n = ⌈length / step⌉ segments; solve: one segment
//!      segment [a, b]: Placement::solve(q_ref = q) with the goal at p(b), R(b)
//!          (intermediate goals to `intermediate_tolerance`, the goal to the
//!          placement tolerance)
//!          converged ─► accept (a Step with its iterations)
//!          not ─► q restored, [a, m] then [m, b] (depth + 1, up to max_depth)
//!          not at max_depth ─► stop: q is the last converged configuration
//! ```
//!
//! The written configuration always satisfies the mechanism's rows to the
//! placement tolerance (it is a converged solve); an unreachable goal ends
//! at the last converged subgoal and says so.

mod path;

pub use path::{Goal, GoalPath};

use nalgebra::{UnitQuaternion, Vector3};

use crate::placement::{Placement, PlacementError, PlacementOptions, SolveStatus};
use crate::{BodyId, BuildError, FingerSpec, FingerTarget, Model, ModelBuilder};

/// The two modes of §4.3 besides dragging.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Closely spaced intermediate goals along the straight path.
    Pull,
    /// The final goal at once (subdivided only where Newton fails).
    Solve,
}

/// Knobs of a placement run.
#[derive(Debug, Clone)]
pub struct PlaceOptions {
    /// Pull or solve.
    pub mode: Mode,
    /// Pull: the longest intermediate step, metres of the goal point's path.
    pub pull_step_m: f64,
    /// Pull: the largest intermediate rotation, radians.
    pub pull_step_rad: f64,
    /// Halvings of a step at most before the goal is declared unreachable.
    pub max_depth: u32,
    /// The Newton-KKT settings of each step; its `max_iterations` is the
    /// per-step cap past which a subgoal is "inappropriate" and split, its
    /// tolerances those of the final goal.
    pub placement: PlacementOptions,
    /// Residual and step tolerance of intermediate goals (m): §4.3 asks
    /// "a moderately accurate solution at each intermediate goal, with a
    /// more accurate solution at the end of move". Default 1e-6 (a
    /// micrometre, below a PHANToM's encoder resolution).
    pub intermediate_tolerance: f64,
}

impl Default for PlaceOptions {
    fn default() -> Self {
        Self {
            mode: Mode::Pull,
            pull_step_m: 0.005,
            pull_step_rad: 0.05,
            max_depth: 8,
            placement: PlacementOptions {
                max_iterations: 8,
                ..PlacementOptions::default()
            },
            intermediate_tolerance: 1e-6,
        }
    }
}

/// One accepted step: the fraction of the path it reached, Newton
/// iterations it took, and its subdivision depth (0: not split).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Path fraction reached, in (0, 1].
    pub t: f64,
    /// Newton iterations of this step.
    pub iterations: u32,
    /// How many halvings led to it.
    pub depth: u32,
}

/// What a placement did.
#[derive(Debug, Clone)]
pub struct Placed {
    /// The goal model (the mechanism's bodies and joints and the goal finger).
    pub model: Model,
    /// The placed configuration (the last converged one), `model`'s layout.
    pub q: Vec<f64>,
    /// Iterations of the initial assembly (the goal at B's own pose).
    pub assembly_iterations: u32,
    /// The accepted steps, in order.
    pub steps: Vec<Step>,
    /// Solves that did not converge and were split.
    pub splits: u32,
    /// Path fraction reached: 1 when the goal was placed.
    pub reached: f64,
    /// How the last attempted solve ended (`Converged` when the goal was
    /// placed).
    pub last_status: SolveStatus,
}

impl Placed {
    /// True when the body is at its goal.
    pub fn at_goal(&self) -> bool {
        self.reached == 1.0
    }

    /// Mean Newton iterations per accepted step (NaN without steps).
    pub fn mean_iterations(&self) -> f64 {
        let sum: u32 = self.steps.iter().map(|s| s.iterations).sum();
        f64::from(sum) / self.steps.len() as f64
    }

    /// Most Newton iterations of one accepted step.
    pub fn max_iterations(&self) -> u32 {
        self.steps.iter().map(|s| s.iterations).max().unwrap_or(0)
    }
}

/// Why a placement could not start.
#[derive(Debug, thiserror::Error)]
pub enum PlaceError {
    /// No body of that name, or it is fixed.
    #[error("body `{0}`: no moving body of that name (moving bodies: {1})")]
    Body(String, String),
    /// A goal or option that is not finite or not positive.
    #[error("{0}")]
    Invalid(&'static str),
    /// The goal model could not be built.
    #[error("goal model: {0}")]
    Build(#[from] BuildError),
    /// The placement could not be analysed or run.
    #[error("placement: {0}")]
    Placement(#[from] PlacementError),
    /// The mechanism could not be assembled with the body where it is.
    #[error("the mechanism does not assemble at its initial configuration ({0:?})")]
    Assembly(SolveStatus),
}

/// The name of the goal finger added to the mechanism.
const GOAL_FINGER: &str = "goal";

/// `builder`'s bodies and joints, with one goal finger on `body` (rigid when
/// `rigid`): the same q layout as `builder.build_joints_only()` for scenes
/// without contact fingers.
pub fn goal_model(builder: &ModelBuilder, body: &str, rigid: bool) -> Result<Model, PlaceError> {
    let moving: Vec<&str> = builder
        .body_specs()
        .iter()
        .filter(|b| !b.fixed)
        .map(|b| b.name.as_str())
        .collect();
    if !moving.contains(&body) {
        return Err(PlaceError::Body(body.to_owned(), moving.join(", ")));
    }
    let mut b = ModelBuilder::new();
    b.gravity(builder.gravity_m_s2());
    for s in builder.body_specs() {
        b.body(s.clone());
    }
    for j in builder.joint_specs() {
        b.joint(j.clone());
    }
    b.finger(match rigid {
        true => FingerSpec::rigid(GOAL_FINGER, body, [0.0; 3]),
        false => FingerSpec::point(GOAL_FINGER, body, [0.0; 3]),
    });
    Ok(b.build()?)
}

/// Places `body` of `builder`'s mechanism at `goal` (see the module docs).
pub fn place(
    builder: &ModelBuilder,
    body: &str,
    goal: &Goal,
    opts: &PlaceOptions,
) -> Result<Placed, PlaceError> {
    goal.check()?;
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !(positive(opts.pull_step_m) && positive(opts.pull_step_rad)) || opts.max_depth > 20 {
        return Err(PlaceError::Invalid(
            "pull steps must be finite and > 0, max_depth at most 20",
        ));
    }
    if !positive(opts.intermediate_tolerance) {
        return Err(PlaceError::Invalid(
            "intermediate_tolerance must be finite and > 0",
        ));
    }
    let model = goal_model(builder, body, goal.orientation.is_some())?;
    let id = model.body_id(body).expect("checked above");
    let mut placement = Placement::analyze(&model, &opts.placement)?;
    let coarse = PlacementOptions {
        tolerance: opts.intermediate_tolerance.max(opts.placement.tolerance),
        step_tolerance: opts
            .intermediate_tolerance
            .max(opts.placement.step_tolerance),
        ..opts.placement.clone()
    };
    let intermediate = Placement::analyze(&model, &coarse)?;
    let mut q = model.q0().to_vec();
    let start = pose(&model, &q, id);
    let assembly = solve_at(&mut placement, &model, &mut q, &target(start.0, start.1))?;
    if assembly.0 != SolveStatus::Converged {
        return Err(PlaceError::Assembly(assembly.0));
    }
    let (p0, r0) = pose(&model, &q, id);
    let path = GoalPath::new(p0, r0, goal);
    let segments = match opts.mode {
        Mode::Solve => 1,
        Mode::Pull => path.segments(opts.pull_step_m, opts.pull_step_rad),
    };
    let mut run = Run {
        placement,
        intermediate,
        model: &model,
        path: &path,
        max_depth: opts.max_depth,
        steps: Vec::new(),
        splits: 0,
        last: SolveStatus::Converged,
    };
    let mut reached = 0.0;
    for k in 1..=segments {
        let b = k as f64 / segments as f64;
        match run.segment(&mut q, reached, b, 0)? {
            true => reached = b,
            false => {
                reached = run.steps.last().map_or(0.0, |s| s.t);
                break;
            }
        }
    }
    Ok(Placed {
        model: model.clone(),
        q,
        assembly_iterations: assembly.1,
        steps: run.steps,
        splits: run.splits,
        reached,
        last_status: run.last,
    })
}

/// The state of one placement along its path.
struct Run<'a> {
    /// The final goal's solver (full tolerance).
    placement: Placement,
    /// Intermediate goals' solver (`intermediate_tolerance`).
    intermediate: Placement,
    model: &'a Model,
    path: &'a GoalPath,
    max_depth: u32,
    steps: Vec<Step>,
    splits: u32,
    last: SolveStatus,
}

impl Run<'_> {
    /// Solves from path fraction `a` (where q is) to `b`; on failure splits
    /// in two. False when a step at `max_depth` failed (q is then the last
    /// converged configuration).
    fn segment(
        &mut self,
        q: &mut Vec<f64>,
        a: f64,
        b: f64,
        depth: u32,
    ) -> Result<bool, PlaceError> {
        let saved = q.clone();
        let (p, r) = self.path.at(b);
        let solver = match b >= 1.0 {
            true => &mut self.placement,
            false => &mut self.intermediate,
        };
        let (status, iterations) = solve_at(solver, self.model, q, &target(p, r))?;
        self.last = status;
        if status == SolveStatus::Converged {
            self.steps.push(Step {
                t: b,
                iterations,
                depth,
            });
            return Ok(true);
        }
        q.copy_from_slice(&saved);
        if depth >= self.max_depth {
            return Ok(false);
        }
        self.splits += 1;
        let m = 0.5 * (a + b);
        Ok(self.segment(q, a, m, depth + 1)? && self.segment(q, m, b, depth + 1)?)
    }
}

/// One Newton-KKT solve from `q` with q_ref = q (least change, Eq. 4).
fn solve_at(
    placement: &mut Placement,
    model: &Model,
    q: &mut [f64],
    target: &FingerTarget,
) -> Result<(SolveStatus, u32), PlaceError> {
    let q_ref = q.to_vec();
    let info = placement.solve(model, q, &q_ref, std::slice::from_ref(target))?;
    Ok((info.status, info.iterations))
}

fn target(p: Vector3<f64>, r: UnitQuaternion<f64>) -> FingerTarget {
    FingerTarget {
        position_m: p,
        orientation: r,
    }
}

/// Position and orientation of `body` at `q`.
pub fn pose(model: &Model, q: &[f64], body: BodyId) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let p = model.body_position(q, body).expect("a moving body");
    let r = model.body_rotation(q, body).expect("a moving body");
    let rot = nalgebra::Rotation3::from_matrix_unchecked(r);
    (p, UnitQuaternion::from_rotation_matrix(&rot))
}
