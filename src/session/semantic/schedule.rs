//! The scene's `[[schedule]]` on the slow loop (Gösele & Stuerzlinger §3.3,
//! §6): objects added and removed, the interaction mode switched.
//!
//! ```text
//!  add b:     SemanticScene::add (the valid place nearest b's declared pose, clear of the
//!             fingertips) ─► a placement: the program that follows carries it as a Shift
//!             of b's coordinates (the fast loop adopts it at a tick boundary); until the
//!             snapshots show b there, b is not mirrored; no valid place (a fingertip
//!             or a body in the way): add_failed, and b is tried again every RETRY_S
//!             until it fits (an add, late) or its remove comes
//!  remove b:  the hand lets go of b; SemanticScene::remove (its constraints broken, its
//!             successors released, or re-bound by Algorithm 1 as pending snaps)
//!  mode m:    unconstrained: the held object's constraints released (no pull, no exception
//!             unless overlapping) and no snaps for it while held; constrained: Algorithm 1
//!             at once for the held object's free bindings
//!  then:      dirty ─► the contact pairs without absent bodies, the model with the rows of
//!             the constraints now satisfied ─► one program through the usual queue
//! ```

use haptloop_solver::BodyId;
use haptloop_solver::geometry::Pose3;
use haptloop_solver::scene::{ScheduleAction, SemanticMode};
use nalgebra::{Rotation3, UnitQuaternion};

use super::{EventKind, SemanticLoop};

/// A placement counts as adopted by the fast loop when a snapshot shows the
/// body within this of it, m.
pub const ADOPTED_M: f64 = 1e-6;

/// How often an add that found no valid place is tried again, s: the search
/// costs a slow-loop cycle's worth, and a hand moves out of the way in
/// tenths of a second.
pub const RETRY_S: f64 = 0.05;

/// An add waiting for a valid place.
#[derive(Debug, Clone, Copy)]
pub(super) struct Waiting {
    body: BodyId,
    /// When the add was scheduled, s.
    since_s: f64,
    /// When it is tried next, s.
    next_s: f64,
}

impl SemanticLoop {
    /// Runs the schedule's entries whose time has come.
    pub(super) fn run_schedule(&mut self, t_s: f64) {
        self.retry_adds(t_s);
        while let Some(d) = self.ops.get(self.next_op).copied() {
            if d.at_s > t_s {
                break;
            }
            self.next_op += 1;
            match d.action {
                ScheduleAction::Add(b) => self.add(b, t_s),
                ScheduleAction::Remove(b) => self.remove(b, t_s),
                ScheduleAction::Mode(m) => self.switch_mode(m, t_s),
            }
            self.check();
        }
    }

    /// Tries again the adds whose retry time has come.
    fn retry_adds(&mut self, t_s: f64) {
        let mut k = 0;
        while k < self.waiting.len() {
            let w = self.waiting[k];
            if w.next_s > t_s {
                k += 1;
                continue;
            }
            if self.try_add(w.body, t_s) {
                self.waiting.swap_remove(k);
                let wait = t_s - w.since_s;
                self.report.adds_late += 1;
                self.report.add_wait_max_s = self.report.add_wait_max_s.max(wait);
                self.check();
            } else {
                self.waiting[k].next_s = t_s + RETRY_S;
                k += 1;
            }
        }
    }

    /// A scheduled add: placed now, or reported and put on the waiting list.
    fn add(&mut self, b: BodyId, t_s: f64) {
        if !self.try_add(b, t_s) {
            self.report.add_failures += 1;
            self.event(t_s, EventKind::AddFailed, b, "");
            self.waiting.push(Waiting {
                body: b,
                since_s: t_s,
                next_s: t_s + RETRY_S,
            });
        }
    }

    /// Puts `b` at the valid place nearest its declared pose; false when
    /// there is none (nothing changes then).
    fn try_add(&mut self, b: BodyId, t_s: f64) -> bool {
        let near = match (
            self.base.body_position(self.base.q0(), b),
            self.base.body_rotation(self.base.q0(), b),
        ) {
            (Some(r), Some(rot)) => Pose3 { r, rot },
            _ => return false,
        };
        let balls: Vec<_> = self
            .tips
            .iter()
            .map(|&(_, tip, radius)| (self.scene.pose(tip).r, radius))
            .collect();
        match self.scene.add(b, near, &balls) {
            Ok(a) => {
                let on = a.bound.first().map_or(String::new(), |(_, offer)| {
                    let o = self.scene.area(*offer).body;
                    self.scene.name(o).to_owned()
                });
                self.placements.push((b, a.pose));
                // Put there, not moved there.
                self.last[b.index()] = a.pose;
                self.report.adds += 1;
                self.event(t_s, EventKind::Add, b, &on);
                self.dirty = true;
                self.absent_changed = true;
                true
            }
            Err(_) => false,
        }
    }

    fn remove(&mut self, b: BodyId, t_s: f64) {
        // An add still waiting for a place is called off: the body never came.
        self.waiting.retain(|w| w.body != b);
        let before = self.holds.len();
        self.holds.retain(|h| h.body != b);
        if self.holds.len() != before {
            self.holds_changed();
        }
        self.placements.retain(|p| p.0 != b);
        self.arriving.retain(|p| p.0 != b);
        let Ok(r) = self.scene.remove(b, true) else {
            return;
        };
        self.report.removes += 1;
        self.event(t_s, EventKind::Remove, b, "");
        let name = self.scene.name(b).to_owned();
        for (c, _) in &r.released {
            self.pending.retain(|(p, _)| p != c);
            let body = self.scene.area(*c).body;
            self.event(t_s, EventKind::Release, body, &name);
        }
        for s in &r.rebound {
            let body = self.scene.area(s.binding).body;
            let offer = self.scene.name(self.scene.area(s.offer).body).to_owned();
            self.pending.push((s.binding, t_s));
            self.event(t_s, EventKind::Snap, body, &offer);
        }
        self.dirty = true;
        self.absent_changed = true;
    }

    fn switch_mode(&mut self, m: SemanticMode, t_s: f64) {
        if m == self.mode {
            return;
        }
        self.mode = m;
        self.event(t_s, EventKind::Mode, BodyId(0), m.as_str());
        let held: Vec<BodyId> = self.holds.iter().map(|h| h.body).collect();
        for o in held {
            match m {
                SemanticMode::Unconstrained => self.release_held(o, t_s),
                SemanticMode::Constrained => self.snap_held(o, t_s),
            }
        }
    }

    /// The unconstrained mode on held object `o`: its satisfied bindings
    /// released (its successors stay bound to it).
    pub(super) fn release_held(&mut self, o: BodyId, t_s: f64) {
        for b in self.scene.objects()[o.index()].bindings.clone() {
            if let Some(a) = self.scene.release(b) {
                let offer = self.scene.name(self.scene.area(a).body).to_owned();
                self.pending.retain(|(p, _)| *p != b);
                self.event(t_s, EventKind::Release, o, &offer);
                self.dirty = true;
                self.check();
            }
        }
    }

    /// Back to constrained: Algorithm 1 for held object `o` where it is.
    fn snap_held(&mut self, o: BodyId, t_s: f64) {
        for snap in self.scene.satisfy_object(o, true) {
            let offer = self.scene.name(self.scene.area(snap.offer).body).to_owned();
            self.pending.push((snap.binding, t_s));
            self.event(t_s, EventKind::Snap, o, &offer);
            self.dirty = true;
            self.check();
        }
    }

    /// Whether object `o`'s constraints are off now (unconstrained mode,
    /// held).
    pub(super) fn unconstrained(&self, o: BodyId) -> bool {
        self.mode == SemanticMode::Unconstrained && self.holds.iter().any(|h| h.body == o)
    }

    /// The bodies out of the scene, as the contact machinery numbers them.
    pub fn absent_bodies(&self) -> Vec<u32> {
        (0..self.scene.objects().len() as u32)
            .filter(|&i| !self.scene.is_present(BodyId(i)))
            .collect()
    }

    /// True once after an add or a remove: the contact pairs must change.
    pub fn take_absent_changed(&mut self) -> bool {
        std::mem::take(&mut self.absent_changed)
    }

    /// `q` with the placements not yet adopted by the fast loop written in
    /// (added bodies where the scene put them); `None` when there are none.
    pub fn placed_q(&self, q: &[f64]) -> Option<Vec<f64>> {
        if self.placements.is_empty() {
            return None;
        }
        let mut out = q.to_vec();
        for &(b, pose) in &self.placements {
            let Some(k) = self.base.layout().body_offset(b) else {
                continue;
            };
            let e_old = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[k + 3],
                q[k + 4],
                q[k + 5],
                q[k + 6],
            ));
            let mut e =
                UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(pose.rot));
            if e.coords.dot(&e_old.coords) < 0.0 {
                e = UnitQuaternion::new_unchecked(-e.into_inner());
            }
            out[k..k + 3].copy_from_slice(pose.r.as_slice());
            out[k + 3..k + 7].copy_from_slice(&[e.w, e.i, e.j, e.k]);
        }
        Some(out)
    }

    /// Records whether the program carrying the placements was sent: sent
    /// ones are awaited in the snapshots, unsent ones go with the next.
    pub fn placements_sent(&mut self, sent: bool) {
        if sent {
            self.arriving.append(&mut self.placements);
        }
    }

    /// Whether the snapshot `q` shows body `b` where the scene placed it
    /// (an arriving placement is dropped then); true for bodies without a
    /// placement.
    pub(super) fn adopted(&mut self, b: BodyId, q: &[f64]) -> bool {
        if self.placements.iter().any(|p| p.0 == b) {
            return false;
        }
        let Some(k) = self.arriving.iter().position(|p| p.0 == b) else {
            return true;
        };
        let r = self.base.body_position(q, b);
        if r.is_some_and(|r| (r - self.arriving[k].1.r).norm() <= ADOPTED_M) {
            self.arriving.swap_remove(k);
            return true;
        }
        false
    }

    /// The interaction mode now.
    pub fn mode(&self) -> SemanticMode {
        self.mode
    }
}
