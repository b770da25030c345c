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
//!
//! With two or more shaped bodies, every solve also holds the
//! non-penetration inequalities of the pairs the active set tracks
//! (`contact.rs`): a step that penetrates is backed up and solved again with
//! the pairs it met, and a goal inside another body ends against it.

mod contact;
mod path;

pub use contact::ContactReport;
pub use path::{Goal, GoalPath};

use crate::geometry::ContactSettings;
use contact::{Contact, blocked_reference};

use nalgebra::{UnitQuaternion, Vector3};

use crate::placement::{PlacementCache, PlacementError, PlacementOptions, SolveStatus};
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
    /// Respect contact between shaped bodies (on by default; off, bodies
    /// pass through each other as in a mechanism without shapes).
    pub contact: bool,
    /// Penetration (the narrow phase's, metres) above which a solved step
    /// is backed up and solved again with the pairs it met. Default 1e-6:
    /// a converged solve holds its witness rows to the placement tolerance,
    /// so more than a micrometre means a pair or feature was missing.
    pub penetration_tolerance_m: f64,
    /// Pairs get rows once their surfaces are closer than this plus twice
    /// the step (m; `[solver] contact_distance`'s default, 5 mm).
    pub contact_distance_m: f64,
}

/// Backups of one step at most before it counts as failed (and is split).
const MAX_BACKUPS: u32 = 3;

/// Newton iterations a blocked step may take (at least; the per-step cap
/// when that is higher): the placement's default cap.
const BLOCKED_ITERATIONS: u32 = 50;

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
            contact: true,
            penetration_tolerance_m: 1e-6,
            contact_distance_m: ContactSettings::default().contact_distance_m,
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
    /// The goal lay inside another body: the step ended against it
    /// (`iterations` counts both solves, the goal's and the blocked one's).
    pub blocked: bool,
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
    /// What contact did (`None`: fewer than two shaped bodies, or contact
    /// off).
    pub contact: Option<ContactReport>,
    /// Distance from the body's origin to the goal position at the end, m.
    pub goal_gap_m: f64,
}

impl Placed {
    /// True when the body is at its goal (the whole path solved, the last
    /// step not blocked by contact).
    pub fn at_goal(&self) -> bool {
        self.reached == 1.0 && !self.steps.last().is_some_and(|s| s.blocked)
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
    Ok(mechanism(builder, body, Some(rigid))?.build()?)
}

/// `builder`'s bodies and joints (and a goal finger on `body` when `goal`
/// says point or rigid).
fn mechanism(
    builder: &ModelBuilder,
    body: &str,
    goal: Option<bool>,
) -> Result<ModelBuilder, PlaceError> {
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
    if let Some(rigid) = goal {
        b.finger(match rigid {
            true => FingerSpec::rigid(GOAL_FINGER, body, [0.0; 3]),
            false => FingerSpec::point(GOAL_FINGER, body, [0.0; 3]),
        });
    }
    Ok(b)
}

/// Places `body` of `builder`'s mechanism at `goal` (see the module docs).
pub fn place(
    builder: &ModelBuilder,
    body: &str,
    goal: &Goal,
    opts: &PlaceOptions,
) -> Result<Placed, PlaceError> {
    goal.check()?;
    check_options(opts)?;
    let model = goal_model(builder, body, goal.orientation.is_some())?;
    let free = mechanism(builder, body, None)?.build()?;
    let id = model.body_id(body).expect("checked above");
    let settings = ContactSettings {
        contact_distance_m: opts.contact_distance_m,
        penetration_tolerance_m: opts.penetration_tolerance_m,
        ..ContactSettings::default()
    };
    let contact = match opts.contact {
        true => Contact::new(&model, &free, settings),
        false => None,
    };
    let coarse = PlacementOptions {
        tolerance: opts.intermediate_tolerance.max(opts.placement.tolerance),
        step_tolerance: opts
            .intermediate_tolerance
            .max(opts.placement.step_tolerance),
        ..opts.placement.clone()
    };
    // A blocked step ends on a contact face, where several rows become
    // active at once (a box's four corners): Newton identifies that set
    // in a few iterations more than a free step; the per-step cap would
    // split it for no gain.
    let blocked = |o: &PlacementOptions| PlacementOptions {
        max_iterations: o.max_iterations.max(BLOCKED_ITERATIONS),
        ..o.clone()
    };
    let mut run = Run {
        blocked_fine: PlacementCache::new(blocked(&opts.placement), 8),
        blocked_coarse: PlacementCache::new(blocked(&coarse), 8),
        fine: PlacementCache::new(opts.placement.clone(), 8),
        coarse: PlacementCache::new(coarse, 8),
        model: &model,
        free: &free,
        body: id,
        path: None,
        max_depth: opts.max_depth,
        penetration_tolerance_m: opts.penetration_tolerance_m,
        contact,
        steps: Vec::new(),
        splits: 0,
        last: SolveStatus::Converged,
    };
    let mut q = model.q0().to_vec();
    let start = pose(&model, &q, id);
    if let Some(c) = &mut run.contact {
        c.expect_motion(0.0);
        c.cycle(&q)?;
    }
    let assembly = run.solve(&mut q, &target(start.0, start.1), true)?;
    if assembly.0 != SolveStatus::Converged {
        return Err(PlaceError::Assembly(assembly.0));
    }
    let (p0, r0) = pose(&model, &q, id);
    let path = GoalPath::new(p0, r0, goal);
    let segments = match opts.mode {
        Mode::Solve => 1,
        Mode::Pull => path.segments(opts.pull_step_m, opts.pull_step_rad),
    };
    if let Some(c) = &mut run.contact {
        c.expect_motion(path.length_m() / segments as f64);
        c.cycle(&q)?;
    }
    run.path = Some(path);
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
    let goal_gap_m = (pose(&model, &q, id).0 - goal.position_m).norm();
    Ok(Placed {
        model: model.clone(),
        q,
        assembly_iterations: assembly.1,
        steps: run.steps,
        splits: run.splits,
        reached,
        last_status: run.last,
        contact: run.contact.map(|c| c.report),
        goal_gap_m,
    })
}

fn check_options(opts: &PlaceOptions) -> Result<(), PlaceError> {
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
    if !(positive(opts.penetration_tolerance_m) && positive(opts.contact_distance_m)) {
        return Err(PlaceError::Invalid(
            "penetration_tolerance_m and contact_distance_m must be finite and > 0",
        ));
    }
    Ok(())
}

/// The state of one placement along its path.
struct Run<'a> {
    /// Solvers of final goals (full tolerance) and of intermediate ones
    /// (`intermediate_tolerance`), by structure (contact rows change it).
    fine: PlacementCache,
    coarse: PlacementCache,
    /// The same for blocked steps (a higher iteration cap).
    blocked_fine: PlacementCache,
    blocked_coarse: PlacementCache,
    /// The mechanism with the goal finger, and without it.
    model: &'a Model,
    free: &'a Model,
    body: BodyId,
    path: Option<GoalPath>,
    max_depth: u32,
    penetration_tolerance_m: f64,
    contact: Option<Contact>,
    steps: Vec<Step>,
    splits: u32,
    last: SolveStatus,
}

impl Run<'_> {
    /// Solves from path fraction `a` (where q is) to `b`; on failure splits
    /// in two. False when a step at `max_depth` failed (q is then the last
    /// converged configuration). With contact, the active set's last cycle
    /// is at q on entry and on return.
    fn segment(
        &mut self,
        q: &mut Vec<f64>,
        a: f64,
        b: f64,
        depth: u32,
    ) -> Result<bool, PlaceError> {
        let saved = q.clone();
        let (p, r) = self.path.as_ref().expect("set before segments").at(b);
        for _ in 0..=MAX_BACKUPS {
            let Some((iterations, blocked)) = self.attempt(q, &saved, p, r, b >= 1.0)? else {
                break;
            };
            if let Some(c) = &mut self.contact {
                let cycle = c.cycle(q)?;
                if cycle.max_penetration_m > self.penetration_tolerance_m {
                    // Backup (§3.2): back to the step's start, where the
                    // pairs it met are now tracked, and again.
                    c.report.backups += 1;
                    q.copy_from_slice(&saved);
                    c.cycle(q)?;
                    continue;
                }
                c.report.max_penetration_m =
                    c.report.max_penetration_m.max(cycle.max_penetration_m);
                c.report.blocked += u32::from(blocked);
            }
            self.steps.push(Step {
                t: b,
                iterations,
                depth,
                blocked,
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

    /// One solve of a step from `saved` (= q) to the goal (p, r): the goal
    /// as a row, or, when that fails while pairs are tracked, the blocked
    /// form (the goal as the objective). Some((iterations, blocked)) when a
    /// solve converged (q is its result), None otherwise (q is `saved`).
    fn attempt(
        &mut self,
        q: &mut [f64],
        saved: &[f64],
        p: Vector3<f64>,
        r: UnitQuaternion<f64>,
        fine: bool,
    ) -> Result<Option<(u32, bool)>, PlaceError> {
        let (status, iterations) = self.solve(q, &target(p, r), fine)?;
        self.last = status;
        if status == SolveStatus::Converged {
            return Ok(Some((iterations, false)));
        }
        q.copy_from_slice(saved);
        if !self.contact.as_ref().is_some_and(|c| c.any_pairs()) {
            return Ok(None);
        }
        let turns = self.path.as_ref().is_some_and(|path| path.turns());
        let orientation = turns.then_some(r);
        let q_ref = blocked_reference(self.model, saved, self.body, p, orientation);
        let (mut status, mut more) = self.solve_blocked(q, &q_ref, fine)?;
        if status != SolveStatus::Converged && fine {
            // A final goal against a contact face with many rows active
            // at once (a figure's pelvis and thighs on a seat) may not
            // reach the placement's 1 nm within the cap; it ends at the
            // intermediate tolerance instead (1 µm by default).
            q.copy_from_slice(saved);
            let (s, m) = self.solve_blocked(q, &q_ref, false)?;
            (status, more) = (s, more + m);
        }
        if status != SolveStatus::Converged {
            q.copy_from_slice(saved);
            return Ok(None);
        }
        self.last = status;
        let gap = (pose(self.model, q, self.body).0 - p).norm();
        Ok(Some((
            iterations + more,
            gap > self.penetration_tolerance_m,
        )))
    }

    /// One Newton-KKT solve from `q` with q_ref = q (least change, Eq. 4),
    /// the goal finger at `target`, the contact rows where there are any.
    fn solve(
        &mut self,
        q: &mut [f64],
        target: &FingerTarget,
        fine: bool,
    ) -> Result<(SolveStatus, u32), PlaceError> {
        let (model, table) = match &self.contact {
            Some(c) => (c.goal_model(), c.table()),
            None => (self.model, &[][..]),
        };
        let cache = if fine {
            &mut self.fine
        } else {
            &mut self.coarse
        };
        let placement = cache.get(model)?;
        placement.set_witnesses(model, table)?;
        let q_ref = q.to_vec();
        let info = placement.solve(model, q, &q_ref, std::slice::from_ref(target))?;
        Ok((info.status, info.iterations))
    }

    /// The blocked form: min ½‖q − q_ref‖² subject to the joints and the
    /// contact rows, no goal row.
    fn solve_blocked(
        &mut self,
        q: &mut [f64],
        q_ref: &[f64],
        fine: bool,
    ) -> Result<(SolveStatus, u32), PlaceError> {
        let (model, table) = match &self.contact {
            Some(c) => (c.free_model(), c.table()),
            None => (self.free, &[][..]),
        };
        let cache = match fine {
            true => &mut self.blocked_fine,
            false => &mut self.blocked_coarse,
        };
        let placement = cache.get(model)?;
        placement.set_witnesses(model, table)?;
        let info = placement.solve(model, q, q_ref, &[])?;
        Ok((info.status, info.iterations))
    }
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
