//! The contact rows of a model (Choi & Cremer §3.2): for each tracked pair of
//! shaped bodies, one constraint of `slots` witness rows (≥ 0, metres), and,
//! for a fingertip with friction, a second constraint of two stick rows.
//! They are appended after every other row, so the mechanism's constraints
//! and rows keep their indices; the row parameters live in the
//! [`Evaluation`](crate::Evaluation)'s witness table, so the slow loop can
//! change features without a new model. A new model (and program) is needed
//! only when the set of pairs changes.

use super::assembler::Assembler;
use super::error::{BuildError, Owner};
use super::{Model, next_model_id};
use crate::constraint::block::{Pair, Param3};
use crate::constraint::witness::ContactRows;
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry};
use crate::geometry::PairSpec;
use crate::{BodyId, ConstraintId, FingerId};
use nalgebra::Vector3;

/// One tracked pair's rows.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactPair {
    /// End 0 (A; a fingertip when there is one) and end 1 (B).
    pub bodies: [BodyId; 2],
    /// The witness rows.
    pub normal: ConstraintId,
    /// The friction stick rows: two at a fingertip, three (the third the
    /// twist row) between two bodies.
    pub friction: Option<ConstraintId>,
    /// The fingertip's finger, if A is one.
    pub finger: Option<FingerId>,
    /// Coulomb μ of the pair (the fingertip's; 0 without friction rows).
    pub mu: f64,
    /// First witness-table slot of the normal rows (the friction rows follow
    /// them).
    pub first_slot: usize,
}

/// Every contact row of a model.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ContactLayout {
    /// Tracked pairs, in the order of the witness table.
    pub pairs: Vec<ContactPair>,
    /// Entries of the witness table (one per contact or friction row).
    pub slots: usize,
    /// Index of the first contact constraint (all later ones are contact
    /// constraints).
    pub first_constraint: usize,
    /// The pairs it was built from, in order (the key of a program cache by
    /// structure).
    pub specs: Vec<PairSpec>,
}

impl Model {
    /// The contact rows (empty for a model without tracked pairs).
    pub fn contact(&self) -> &ContactLayout {
        &self.contact
    }

    /// This model's mechanism (every constraint before the contact rows)
    /// plus the rows of `pairs`, in order. Allocates; for the slow thread.
    /// The new model has a new identity.
    pub fn with_contacts(&self, pairs: &[PairSpec]) -> Result<Model, BuildError> {
        let keep = if self.contact.pairs.is_empty() {
            self.constraints.len()
        } else {
            self.contact.first_constraint
        };
        let rows_kept = self
            .constraints
            .get(keep)
            .map_or(self.rows.len(), |c| c.rows.start);
        let mut out = Assembler {
            infos: self.constraints[..keep].to_vec(),
            geometry: self.geometry[..keep].to_vec(),
            rows: self.rows[..rows_kept].to_vec(),
        };
        let world = self.bodies.len();
        let mut layout = ContactLayout {
            pairs: Vec::with_capacity(pairs.len()),
            slots: 0,
            first_constraint: keep,
            specs: pairs.to_vec(),
        };
        for p in pairs {
            let [a, b] = p.bodies.map(|i| i as usize);
            let name = |what: &str| {
                format!(
                    "{what} {}|{}",
                    self.bodies.get(a).map_or("?", |x| x.name.as_str()),
                    self.bodies.get(b).map_or("?", |x| x.name.as_str())
                )
            };
            if a >= world || b >= world {
                return Err(BuildError::UnknownBody {
                    owner: Owner::Inequality(name("contact")),
                    body: format!("#{}", a.max(b)),
                });
            }
            if a == b {
                return Err(BuildError::SameBody {
                    owner: Owner::Inequality(name("contact")),
                    body: self.bodies[a].name.clone(),
                });
            }
            let col = |k: usize| self.layout.body_cols[k];
            if col(a).is_none() && col(b).is_none() {
                return Err(BuildError::BothFixed {
                    owner: Owner::Inequality(name("contact")),
                });
            }
            let pair = Pair {
                frame: [a, b],
                col: [col(a), col(b)],
                anchor: [Param3::Const(Vector3::zeros()); 2],
            };
            let finger = self
                .fingers
                .iter()
                .position(|f| f.tip.is_some() && f.body.index() == a)
                .map(|k| FingerId(k as u32));
            let mu = finger
                .and_then(|f| self.fingers[f.index()].tip)
                .map_or_else(
                    || (self.bodies[a].friction * self.bodies[b].friction).sqrt(),
                    |t| t.friction,
                );
            let first_slot = layout.slots;
            let normal = ConstraintId(out.infos.len() as u32);
            out.push(
                info(name("contact"), ConstraintKind::Contact, a, b),
                Geometry::Contact(ContactRows {
                    pair,
                    first_slot: first_slot as u32,
                    rows: p.slots,
                }),
            );
            layout.slots += p.slots as usize;
            let friction = if p.friction {
                // Two stick rows at a fingertip; two bodies add the twist row.
                let rows = if finger.is_some() { 2 } else { 3 };
                let id = ConstraintId(out.infos.len() as u32);
                out.push(
                    info(name("friction"), ConstraintKind::ContactFriction, a, b),
                    Geometry::Contact(ContactRows {
                        pair,
                        first_slot: layout.slots as u32,
                        rows,
                    }),
                );
                layout.slots += rows as usize;
                Some(id)
            } else {
                None
            };
            layout.pairs.push(ContactPair {
                bodies: [BodyId(a as u32), BodyId(b as u32)],
                normal,
                friction,
                finger,
                mu: if p.friction { mu } else { 0.0 },
                first_slot,
            });
        }
        Ok(Model {
            id: next_model_id(),
            geometry: out.geometry,
            constraints: out.infos,
            rows: out.rows,
            contact: layout,
            ..self.clone()
        })
    }
}

fn info(name: String, kind: ConstraintKind, a: usize, b: usize) -> ConstraintInfo {
    ConstraintInfo {
        name,
        kind,
        rows: 0..0,
        bodies: [Some(BodyId(a as u32)), Some(BodyId(b as u32))],
        finger: None,
        limits: None,
    }
}
