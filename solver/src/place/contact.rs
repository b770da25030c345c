//! Contact inside a placement (Choi & Cremer §3.2 within §4.3's modes): the
//! non-penetration inequalities of the geometry module's active set become
//! rows of every Newton-KKT solve along the goal path, so a placed body
//! stops against what it meets instead of ending inside it.
//!
//! ```text
//!  q (where the step starts) ─► ActiveSet::update (pre-emptive: pairs within
//!      contact_distance + 2 × the step's motion) ─► Model::with_contacts
//!      (a new model only when the set of pairs changes) + the witness table
//!  solve the step with those rows ─► ActiveSet::update at the result
//!      penetration ≤ tolerance ─► accept
//!      deeper ─► backup (§3.2): q back to the step's start, a cycle there
//!               (its reach now covers the motion that penetrated, and the
//!               §3.2.1 expansion has run), solve again
//! ```
//!
//! A goal inside another body cannot be met with the goal as a row; such a
//! step is solved with the goal as the objective instead ("blocked", see
//! [`blocked_reference`]): the least change from the whole mechanism moved
//! rigidly to the goal, subject to the joints and the contact rows: a body
//! pushed into a seat comes to rest on it, under the goal.

use nalgebra::{UnitQuaternion, Vector3};

use super::PlaceError;
use crate::constraint::witness::Witness;
use crate::contact::{contact_bodies, jointed_pairs};
use crate::geometry::{ActiveSet, ContactSettings, Cycle, PairSpec, Pose3};
use crate::{BodyId, Model};

/// What contact did in a placement.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactReport {
    /// Backups (§3.2): solves whose result penetrated deeper than the
    /// tolerance, undone and solved again with the pairs they met.
    pub backups: u32,
    /// Steps whose goal lay inside another body: solved with the goal as
    /// the objective, ending against the contact short of the goal.
    pub blocked: u32,
    /// Deepest penetration of an accepted configuration, metres (the
    /// narrow phase's distance, not the rows'); 0 when nothing touched.
    pub max_penetration_m: f64,
    /// Pairs tracked at the end.
    pub tracked_pairs: u32,
    /// Models with contact rows built (one per new set of pairs).
    pub models_built: u32,
}

/// The contact state of one placement.
pub(super) struct Contact {
    active: ActiveSet,
    /// The mechanism with the goal finger, and without it (same layout).
    goal: Model,
    free: Model,
    pairs: Vec<PairSpec>,
    /// `goal` and `free` with the rows of `pairs`.
    goal_rows: Model,
    free_rows: Model,
    table: Vec<Witness>,
    poses: Vec<Pose3>,
    expected: Vec<f64>,
    pub(super) report: ContactReport,
}

impl Contact {
    /// The contact state of `goal` (`free`: the same mechanism without the
    /// goal finger), or `None` when fewer than two bodies have a shape.
    pub(super) fn new(goal: &Model, free: &Model, settings: ContactSettings) -> Option<Self> {
        let bodies = contact_bodies(goal, false);
        if bodies.iter().flatten().count() < 2 {
            return None;
        }
        let active = ActiveSet::new(bodies, jointed_pairs(goal), settings);
        Some(Self {
            active,
            goal: goal.clone(),
            free: free.clone(),
            pairs: Vec::new(),
            goal_rows: goal.clone(),
            free_rows: free.clone(),
            table: Vec::new(),
            poses: Vec::new(),
            expected: Vec::new(),
            report: ContactReport::default(),
        })
    }

    /// Every moving body may move up to `metres` in the next step: pairs
    /// within twice that (plus `contact_distance`) get rows before it.
    pub(super) fn expect_motion(&mut self, metres: f64) {
        self.expected.clear();
        self.expected.resize(self.goal.bodies().len(), metres);
        self.active.set_expected_motion(&self.expected);
    }

    /// One cycle of the active set at `q`: the pairs and witnesses there;
    /// new models when the set of pairs changed.
    pub(super) fn cycle(&mut self, q: &[f64]) -> Result<Cycle, PlaceError> {
        self.poses.clear();
        for i in 0..self.goal.bodies().len() {
            let id = BodyId(i as u32);
            let pose = match (
                self.goal.body_position(q, id),
                self.goal.body_rotation(q, id),
            ) {
                (Some(r), Some(rot)) => Pose3 { r, rot },
                _ => Pose3::IDENTITY,
            };
            self.poses.push(pose);
        }
        let cycle = self.active.update(&self.poses);
        let pairs = self.active.pairs();
        if pairs != self.pairs {
            self.goal_rows = self.goal.with_contacts(&pairs)?;
            self.free_rows = self.free.with_contacts(&pairs)?;
            self.pairs = pairs;
            self.report.models_built += 1;
        }
        self.active.fill(&mut self.table);
        self.report.tracked_pairs = self.pairs.len() as u32;
        Ok(cycle)
    }

    /// Whether any pair is tracked (contact could block a goal).
    pub(super) fn any_pairs(&self) -> bool {
        !self.pairs.is_empty()
    }

    /// The goal model with the current contact rows.
    pub(super) fn goal_model(&self) -> &Model {
        &self.goal_rows
    }

    /// The model without the goal finger, with the current contact rows.
    pub(super) fn free_model(&self) -> &Model {
        &self.free_rows
    }

    /// The witness table of the current rows.
    pub(super) fn table(&self) -> &[Witness] {
        &self.table
    }
}

/// The reference of a blocked step: `q` with every moving body moved by the
/// rigid motion that takes `body` from its pose in `q` to `p` (and `r`,
/// when the goal has an orientation): min ½‖q − q_ref‖² subject to the
/// joints and contact rows is then the mechanism moved as far toward the
/// goal as contact lets it, changed as little as possible otherwise.
pub(super) fn blocked_reference(
    model: &Model,
    q: &[f64],
    body: BodyId,
    p: Vector3<f64>,
    r: Option<UnitQuaternion<f64>>,
) -> Vec<f64> {
    let (p0, r0) = super::pose(model, q, body);
    let turn = r.map_or(UnitQuaternion::identity(), |r| r * r0.inverse());
    let mut out = q.to_vec();
    let layout = model.layout();
    for (id, _) in layout.moving_bodies() {
        let (Some(pos), Some(rot)) = (layout.position_range(id), layout.rotation_range(id)) else {
            continue;
        };
        let x = Vector3::new(q[pos.start], q[pos.start + 1], q[pos.start + 2]);
        let moved = p + turn * (x - p0);
        out[pos.clone()].copy_from_slice(moved.as_slice());
        if r.is_some() {
            let e = &q[rot.clone()];
            let e = nalgebra::Quaternion::new(e[0], e[1], e[2], e[3]);
            let e = turn.quaternion() * e;
            out[rot].copy_from_slice(&[e.w, e.i, e.j, e.k]);
        }
    }
    out
}
