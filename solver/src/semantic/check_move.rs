//! Algorithm 2, checkMove(o, t, r): whether a motion can be applied to
//! object o without making the scene inconsistent, and if not, what of it
//! can (§5.2).
//!
//! ```text
//!  group ← o and all objects grouped to o (its successors: they move with it)
//!  ovs   ← orientation vectors of satisfied constraints with b ∈ group, a ∉ group,
//!          parallel and anti-parallel duplicates removed
//!  |ovs| = 1: t ⊥ ovs[0], r about ovs[0]      |ovs| = 2: t ⊥ both, r ← 0
//!  |ovs| ≥ 3: t ← 0, r ← 0 (three directions: immovable)
//!  t, r ≠ 0: polygon inclusion lost, or the moved group collides → t ← 0, r ← 0
//! ```
//!
//! "r about ovs[0]" keeps the rotation's component about that vector (a
//! rotation about a plane's normal keeps the plane). A group holding a fixed
//! object does not move.

use nalgebra::Vector3;

use super::area::relation;
use super::motion::Move;
use super::scene::SemanticScene;
use crate::BodyId;
use crate::geometry::Pose3;

/// Two orientation vectors within this angle (rad) of parallel or
/// anti-parallel are one direction (line 3).
pub const PARALLEL_RAD: f64 = 1e-6;

impl SemanticScene {
    /// The orientation vectors restricting `group` (line 2, deduplicated),
    /// world frame, unit.
    pub fn orientation_vectors(&self, group: &[BodyId]) -> Vec<Vector3<f64>> {
        let mut ovs: Vec<Vector3<f64>> = Vec::new();
        for &g in group {
            for &b in &self.objects[g.index()].bindings {
                let Some(bond) = self.bond(b) else { continue };
                let a = &self.areas[bond.offer.index()];
                if group.binary_search(&a.body).is_ok() {
                    continue;
                }
                let v = a.normal_w(&self.objects[a.body.index()].pose);
                if !ovs.iter().any(|w| w.cross(&v).norm() <= PARALLEL_RAD) {
                    ovs.push(v);
                }
            }
        }
        ovs
    }

    /// Algorithm 2 (see the module docs) for moving `o` by `mv`; `skip`: a
    /// pair whose collisions are not tested (Algorithm 1 line 5: the object
    /// being snapped and the offer's object). Returns the motion that may be
    /// applied (possibly none).
    pub fn check_move(&self, o: BodyId, mv: Move, skip: Option<[BodyId; 2]>) -> Move {
        let group = self.group(o);
        if group.iter().any(|g| self.objects[g.index()].fixed) {
            return Move::none(mv.center);
        }
        let ovs = self.orientation_vectors(&group);
        let mut m = mv;
        match ovs.as_slice() {
            [] => {}
            [v] => {
                m.t -= v * v.dot(&m.t);
                m.r = v * v.dot(&m.r);
            }
            [v, w] => {
                let d = v.cross(w).normalize();
                m.t = d * d.dot(&m.t);
                m.r = Vector3::zeros();
            }
            _ => return Move::none(mv.center),
        }
        if m.is_none() {
            return m;
        }
        let poses: Vec<Pose3> = group
            .iter()
            .map(|g| m.apply(&self.objects[g.index()].pose))
            .collect();
        if !self.inclusion_kept(&group, &poses) {
            return Move::none(mv.center);
        }
        if self.first_collision(&group, &poses, skip).is_some() {
            return Move::none(mv.center);
        }
        m
    }

    /// Line 11: every satisfied constraint from the group to the rest stays
    /// aligned (coplanar and included) with the group at `poses`.
    fn inclusion_kept(&self, group: &[BodyId], poses: &[Pose3]) -> bool {
        let tol = self.settings.align_tolerance;
        for (&g, pg) in group.iter().zip(poses) {
            for &b in &self.objects[g.index()].bindings {
                let Some(bond) = self.bond(b) else { continue };
                let a = &self.areas[bond.offer.index()];
                if group.binary_search(&a.body).is_ok() {
                    continue;
                }
                let r = relation(
                    &self.areas[b.index()],
                    pg,
                    a,
                    &self.objects[a.body.index()].pose,
                );
                // A pending snap is still arriving: only its inclusion is
                // required here, its plane is the fast loop's business.
                let plane_ok = bond.pending || r.off_plane_m <= tol;
                if !(plane_ok && r.outside_m <= tol) {
                    return false;
                }
            }
        }
        true
    }

    /// An interactive move: checkMove, then the allowed part applied to `o`
    /// and its group. Returns what was applied.
    pub fn move_object(&mut self, o: BodyId, mv: Move) -> Move {
        let m = self.check_move(o, mv, None);
        if !m.is_none() {
            for g in self.group(o) {
                let p = m.apply(&self.objects[g.index()].pose);
                self.set_pose(g, p);
            }
        }
        m
    }
}
