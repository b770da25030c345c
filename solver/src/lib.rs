//! haptloop-solver: augmented-coordinate mechanism models, a constraint library
//! with analytic Jacobians, the sparse Jacobian the fast loop and the
//! placement solver iterate on, and the fast loop's [`Program`] (constraint
//! update and force feedback).
//!
//! Principal types and how data flows through them:
//!
//! ```text
//!  BodySpec / JointSpec / FingerSpec ──► ModelBuilder::build() ──► Model
//!  (scene vocabulary, names)                (validates: BuildError   │  bodies, Layout (q columns),
//!                                            names the offender)     │  constraints + RowInfo per row
//!                                                                    ▼
//!  q (Layout order) + FingerTarget per finger ──► Evaluation::evaluate(&Model, q, targets)
//!                                                   │  in place, zero allocation
//!                                                   ├─► values():   C(q)   (equalities, then ≥ 0 rows)
//!                                                   └─► jacobian(): C_q(q) (Jacobian: fixed CSR pattern,
//!                                                                   mul_vec / mul_t_vec, faer view)
//! ```
//!
//! The fast loop wraps that evaluation: `Program::new(Arc<Model>, SolverSettings)`,
//! or `Program::with_objectives` with the design objectives compiled against
//! the model (`Objectives::compile`; the model knows nothing of them) (slow thread) → `tick(targets, dt)` per device sample → `TickReport` and
//! `finger_outputs()` (forces for the device) → `adopt_state(&old)` when the
//! slow thread hands over a replacement.
//!
//! - [`Model`]: bodies (7 coordinates r, e = [w, x, y, z] per moving body; none
//!   for fixed bodies), free design variables, compiled constraints, per-row
//!   metadata ([`RowInfo`]: constraint, equality/inequality, unit), fingers,
//!   gravity. Immutable; [`Model::with_inequalities`] derives a model with
//!   extra point–plane rows for a new contact active set.
//! - [`Layout`]: which columns of q belong to which body and design variable;
//!   [`Model::q0`] is the initial configuration.
//! - [`Evaluation`]: allocated once per model; [`Evaluation::evaluate`] fills C
//!   and C_q in place with bounded work and no allocation.
//! - [`Jacobian`]: the fixed sparsity pattern (CSR, a transposed index, a
//!   zero-copy faer view) and the products C_q·v, C_qᵀ·v.
//! - [`Placement`] ([`placement`]): the slow thread's Newton-KKT solver —
//!   symbolic analysis of J Jᵀ once per structure ([`Placement::analyze`],
//!   cached by [`PlacementCache`]), then allocation-free damped Newton
//!   iterations with slack inequalities ([`Placement::solve`] → [`SolveInfo`]).
//! - [`Program`] ([`al`], [`force`]): the fast loop's solver. Built once per
//!   model from [`SolverSettings`], masking rows that are linearly dependent
//!   at q0 ([`Redundancy`]); [`Program::tick`] runs the update toward
//!   the finger targets (a Gauss–Newton projection with the force solve's
//!   factor, or Nelson & Cohen's Eq. 1–3: [`UpdateRule`]), then the finger
//!   loads of Eq. 7–8 plus a virtual coupling ([`FingerOutput`], force on the
//!   finger, world frame), with zero allocation, and refuses a finite but
//!   absurd result ([`TickOutcome::Diverged`]); [`reference_finger_wrenches`]
//!   is the dense reference. [`Program::converged_tick`] replays a tick
//!   saved as [`TickState`]s to convergence: the force a converged update
//!   would have rendered, against which the fast loop's force error is
//!   measured.
//! - [`semantic`]: Gösele & Stuerzlinger's semantic constraints on the slow
//!   loop (labels, snapping, checkMove, the grouping graph, consistency);
//!   a satisfied constraint reaches the fast loop as rows
//!   ([`Model::with_semantic`]).
//! - [`mechanisms`]: built-in models (spatial four-bar, Stewart platform, a
//!   132-body sphere toy), each assembled at q0.
//!
//! ```
//! use haptloop_solver::{BodySpec, FingerSpec, JointKind, JointSpec, ModelBuilder};
//!
//! let mut b = ModelBuilder::new();
//! b.gravity([0.0, 0.0, -9.81]);
//! b.body(BodySpec::fixed("ground"));
//! b.body(BodySpec::new("arm").at([0.1, 0.0, 0.0]).mass(0.05));
//! b.joint(
//!     JointSpec::new(JointKind::Revolute, "ground", "arm")
//!         .named("hinge")
//!         .anchors([0.0; 3], [-0.1, 0.0, 0.0])
//!         .axes([0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
//!         .limits(-1.0, 1.0),
//! );
//! b.finger(FingerSpec::point("index", "arm", [0.1, 0.0, 0.0]));
//! let model = b.build()?;
//!
//! let mut ev = model.evaluation(); // allocates once
//! let mut targets = model.initial_targets();
//! targets[0].position_m.y += 0.01; // the finger moved; nothing is rebuilt
//! ev.evaluate(&model, model.q0(), &targets)?; // C and C_q, in place
//! let mut dq = vec![0.0; model.n_coords()];
//! ev.jacobian().mul_t_vec(ev.values(), &mut dq)?; // C_qᵀ C
//! assert!((ev.values()[model.constraints()[1].rows.start + 1] + 0.01).abs() < 1e-15);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Rotations use the rational form R(e) = A_h(e)/|e|² (see [`rotation`]), exact
//! for non-unit e, with one quaternion-norm row per moving body.

pub mod al;
mod cholesky;
pub mod constraint;
pub mod contact;
pub mod dynamics;
mod evaluate;
pub mod flexible;
pub mod force;
pub mod geometry;
mod ids;
mod jacobian;
pub mod mechanisms;
mod model;
pub mod objective;
pub mod parametric;
pub mod place;
pub mod placement;
pub mod program;
pub mod reduced;
pub mod rotation;
pub mod scene;
pub mod semantic;

pub use al::{
    Coordinates, ForceSolver, InvalidSetting, RedundancyCheck, SolverSettings, UpdateRule,
};
pub use constraint::{ConstraintInfo, ConstraintKind, RowInfo, RowUnit, Sense};
pub use evaluate::{EvalError, Evaluation, FingerTarget};
pub use force::{
    FingerWrench, MultilevelStats, Redundancy, ReferenceError, TreeStats, reference_finger_wrenches,
};
pub use ids::{BodyId, ConstraintId, DesignVarId, FingerId};
pub use jacobian::{Jacobian, ShapeError};
pub use model::{AuxBlock, AuxOwner, ContactSurface, Rest};
pub use model::{
    Body, BodySpec, Bounds, BuildError, ContactLayout, ContactPair, DEFAULT_FINGERTIP_RADIUS_M,
    DEFAULT_INERTIA_RADIUS_M, DEFAULT_MASS_KG, DesignOwner, DesignParam, DesignVar,
    FINGERTIP_MASS_KG, Finger, FingerSpec, Fingertip, Grasp, JointKind, JointSpec, Layout,
    MAX_FINGERTIP_RADIUS_M, MAX_FRICTION, Model, ModelBuilder, Owner, PlaneOwner, PointPlaneSpec,
    Shape, UnknownName,
};
pub use model::{GearKind, GearSpec, MAX_GEAR_TEETH};
pub use model::{HoldSpec, SemanticLayout, SnapSettings, SurfaceInfo, SurfaceRow, SurfaceSpec};
pub use objective::{
    Objective, ObjectiveEval, ObjectiveKind, ObjectiveSpec, Objectives, ObstacleSpec,
};
pub use placement::{
    Placement, PlacementCache, PlacementError, PlacementOptions, SolveInfo, SolveStatus,
};
pub use program::{
    AssemblyReport, ConvergedTick, CoordinatesChoice, CostEstimate, Divergence, DivergenceLimits,
    FactorRefresher, FingerOutput, Program, ProgramError, RefreshedFactor, TickOutcome, TickReport,
    TickState,
};
