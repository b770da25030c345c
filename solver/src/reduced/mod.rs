//! The quasi-static tick in joint (tree) coordinates (issue 23): what
//! `Program` runs with `SolverSettings::coordinates` = `Joint` (or `Auto`
//! on a model it accepts; `program/joint.rs` wires it in: resync, failure
//! paths, report), and the Eq. 7 force core there, measured against the
//! augmented one.
//!
//! - `tree`: a breadth-first spanning tree of the joint graph rooted at the
//!   ground; tree joints give the joint coordinates, the other joints'
//!   rows (loop closures) stay rows, as the fingers' do.
//! - `kinematics`: S(q), the map from joint rates to augmented velocities
//!   (C_tree,q S = 0, eᵀė = 0), and forward kinematics along the joints.
//! - `core`: H = Sᵀ M̃ S (composite rigid-body algorithm), J_r = C_{r,q} S
//!   and the finger Schur complement after the loop rows, with the loop
//!   rows' redundancy masked once (`mask`: an ordered Cholesky of the
//!   loop block with dropping).
//! - `tick` (with `rows`, `stage`, `small`): a whole quasi-static tick in
//!   joint coordinates — the projected update on θ with forward kinematics,
//!   only the loop and finger rows evaluated, and Eq. 7 — on plain loops
//!   over preallocated slices; `resync` moves it to a q it did not tick to.
//! - `branch`: H = Lᵀ L along the tree's branches (no fill) and the solves,
//!   Y and W over each row's nonzeros, for `stage`; `stage_check` (tests)
//!   checks every factor and solve of a run against the dense path.
//! - `probe` (tests, ignored): times the augmented force stage against this
//!   one at the same q; `tick_probe` times the whole ticks.
//!
//! Joints handled: revolute, universal, spherical, prismatic, fixed (a
//! weld: no coordinate). Revolute and prismatic limits on tree joints are
//! bounds on a joint coordinate (`limits`); rigid fingers' orientation rows
//! are kept rows like their point rows (`finger6`). Models with design
//! variables, auxiliary columns (flexible bodies, surfaces), free anchors,
//! other inequality rows or limits on loop-closing joints are refused.

mod branch;
mod core;
mod end;
mod finger6;
mod kinematics;
mod limits;
mod mask;
mod project;
mod resync;
mod rows;
mod small;
mod stage;
mod tick;
mod tree;

#[cfg(test)]
mod fk_tests;
#[cfg(test)]
mod probe;
#[cfg(test)]
mod stage_check;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tick_probe;
#[cfg(test)]
mod tick_tests;

pub use core::{JointSpace, PINV_RATIO, PIVOT_RATIO, ZERO_ROW};
pub use kinematics::{Kinematics, displace};
pub use resync::{History, MotionOut};
pub use tick::JointTick;
pub use tree::JointTree;

/// Why a model or a configuration has no joint-space form here.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReducedError {
    /// The model has something this module does not handle.
    #[error("not handled in joint coordinates: {0}")]
    Unsupported(String),
    /// A body's quaternion is degenerate at q.
    #[error("body {0} has a degenerate quaternion")]
    Degenerate(usize),
    /// A loop or finger row wrote an entry with no joint-space form.
    #[error("a row's Jacobian entry has no joint-space form")]
    RawEntry,
    /// A matrix that should be positive definite is not.
    #[error("{0} is not positive definite")]
    NotPositive(&'static str),
}
