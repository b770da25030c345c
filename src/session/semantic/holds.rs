//! The hand's holds (a contact finger's `holds` schedule): take hold when a
//! hold's time has come and the fingertip is within reach, let go when it
//! ends. A hold is a pinch, a weld at the grab's relative pose
//! ([`HoldSpec`](haptloop_solver::HoldSpec) with its orientation).

use haptloop_solver::BodyId;
use nalgebra::Vector3;

use super::{EventKind, SemanticLoop};

/// A hold waits for the fingertip to come within this many fingertip radii
/// of the body's surface.
pub const HOLD_REACH_RADII: f64 = 2.0;

/// A hold in effect.
#[derive(Debug, Clone, Copy)]
pub(super) struct ActiveHold {
    /// Index in the schedule.
    pub(super) decl: usize,
    pub(super) tip: BodyId,
    pub(super) body: BodyId,
    /// The fingertip's centre in the body's frame when it took hold.
    pub(super) anchor: Vector3<f64>,
    /// R_bodyᵀ R_tip when it took hold: the pinch keeps it.
    pub(super) relative: nalgebra::Matrix3<f64>,
}

impl SemanticLoop {
    /// A cycle on a snapshot whose tick failed: its poses are not to be
    /// trusted, so nothing is searched or grabbed, but holds whose time is
    /// over end (a hand that lets go can only help a failing mechanism).
    pub fn step_unsolved(&mut self, t_s: f64) {
        if self.let_go(t_s) {
            self.holds_changed();
        }
    }

    /// Ends the holds whose time is over; true if any did.
    fn let_go(&mut self, t_s: f64) -> bool {
        let mut changed = false;
        let mut k = 0;
        while k < self.holds.len() {
            let h = self.holds[k];
            if t_s >= self.schedule[h.decl].until_s {
                self.holds.remove(k);
                self.done[h.decl] = true;
                let finger = self.finger_name(h.decl);
                self.event(t_s, EventKind::LetGo, h.body, &finger);
                changed = true;
            } else {
                k += 1;
            }
        }
        changed
    }

    pub(super) fn holds_changed(&mut self) {
        let pairs: Vec<[BodyId; 2]> = self.holds.iter().map(|h| [h.tip, h.body]).collect();
        self.scene.set_ignored(&pairs);
        self.dirty = true;
        self.check();
    }

    /// The hand's schedule: take hold when a hold's time has come and the
    /// fingertip is within reach; let go when it ends.
    pub(super) fn update_holds(&mut self, t_s: f64) {
        let mut changed = self.let_go(t_s);
        for i in 0..self.schedule.len() {
            let d = self.schedule[i];
            if self.done[i]
                || t_s < d.from_s
                || self.holds.iter().any(|h| h.decl == i)
                || !self.scene.is_present(d.body)
            {
                continue;
            }
            if t_s >= d.until_s {
                self.done[i] = true;
                continue;
            }
            let Some(&(_, tip, radius)) = self.tips.iter().find(|t| t.0 == d.finger.index()) else {
                continue;
            };
            if self.holds.iter().any(|h| h.tip == tip) {
                continue;
            }
            let centre = self.scene.pose(tip).r;
            let gap = self.scene.ball_distance_m(d.body, &centre, radius);
            let pose = self.scene.pose(d.body);
            if gap <= HOLD_REACH_RADII * radius {
                self.holds.push(ActiveHold {
                    decl: i,
                    tip,
                    body: d.body,
                    anchor: pose.local_point(&centre),
                    relative: pose.rot.transpose() * self.scene.pose(tip).rot,
                });
                let finger = self.finger_name(i);
                self.event(t_s, EventKind::Hold, d.body, &finger);
                if self.unconstrained(d.body) {
                    self.release_held(d.body, t_s);
                }
                changed = true;
            }
        }
        if changed {
            self.holds_changed();
        }
    }

    pub(super) fn finger_name(&self, decl: usize) -> String {
        let f = self.schedule[decl].finger.index();
        self.base.fingers()[f].name.clone()
    }
}
