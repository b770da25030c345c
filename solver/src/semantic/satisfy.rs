//! Algorithm 1, satisfyConstraint(b, o, s), and its search for close offers
//! (§5.1).
//!
//! ```text
//!  offers ← searchCloseBindings(b, s): fitting offers a (l(b) ≤ l(a)) of other objects whose
//!           plane is within the maximal distance of b's, whose orientation vector is within the
//!           snap angle of b's reversed, and whose polygon includes b's perpendicular projection;
//!           each with (t, r): r about an axis parallel to a (through b's centroid) turning b's
//!           orientation vector onto −a's, then t along a's normal onto its plane
//!  nearest first: if checkMove(o, t, r) (o–o' collisions off) leaves (t, r) unchanged and the
//!           new edge o' → o closes no directed cycle: satisfied(a, b), apply (t, r) to o and its
//!           successors (b's inclusion in a re-checked at the new pose), done
//! ```
//!
//! [`SemanticScene::satisfy_aligned`] is the loader's version: every binding
//! already aligned with a fitting offer is satisfied where it is.

use nalgebra::Vector3;

use super::area::{AreaId, Relation, relation};
use super::motion::Move;
use super::scene::SemanticScene;
use super::spec::AreaKind;
use crate::BodyId;

/// A close offer for a binding area (searchCloseBindings).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The offer area.
    pub offer: AreaId,
    /// How the binding lies against it now.
    pub relation: Relation,
    /// The motion that aligns them.
    pub mv: Move,
    /// Distance plus the angle at the binding's radius, m: nearest first.
    pub cost_m: f64,
}

/// A newly satisfied constraint and the motion applied for it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snap {
    /// The binding area.
    pub binding: AreaId,
    /// The offer area it now satisfies.
    pub offer: AreaId,
    /// The motion applied to the binding's object and its group.
    pub mv: Move,
    /// How far the binding was from the offer before (distance, angle).
    pub before: Relation,
}

impl SemanticScene {
    /// searchCloseBindings(b, s): the fitting offers close to binding area
    /// `b` (see the module docs), nearest first (ties: lower area index).
    /// Offers of `b`'s own object, and of objects on the exception list
    /// with it, are not candidates.
    pub fn search_close(&self, b: AreaId) -> Vec<Candidate> {
        let s = &self.settings;
        let area = &self.areas[b.index()];
        if area.kind != AreaKind::Binding || !self.is_present(area.body) {
            return Vec::new();
        }
        let o = area.body;
        let pb = self.objects[o.index()].pose;
        let mut out = Vec::new();
        for a in self.offers_near(b, &pb) {
            let a = AreaId(a);
            let offer = &self.areas[a.index()];
            let o2 = offer.body;
            if o2 == o
                || !self.order.fits(area.label, offer.label)
                || self
                    .exceptions
                    .iter()
                    .any(|&[x, y]| (x == o && y == o2) || (x == o2 && y == o))
            {
                continue;
            }
            let pa = self.objects[o2.index()].pose;
            let rel = relation(area, &pb, offer, &pa);
            let depth = s.collision_tolerance_m + s.align_tolerance;
            if rel.distance_m > s.snap_distance_m
                || rel.distance_m < -depth
                || rel.angle_rad > s.snap_angle_rad
                || rel.outside_m > s.align_tolerance
            {
                continue;
            }
            let na = offer.normal_w(&pa);
            let nb = area.normal_w(&pb);
            let axis = nb.cross(&-na);
            let r = if axis.norm() > 1e-15 {
                axis.normalize() * rel.angle_rad
            } else {
                Vector3::zeros()
            };
            let center = area.centroid_w(&pb);
            // The centroid stays put under the rotation; then onto the plane.
            let t = -na * rel.distance_m;
            out.push(Candidate {
                offer: a,
                relation: rel,
                mv: Move { center, t, r },
                cost_m: rel.distance_m.abs() + area.radius_m * rel.angle_rad,
            });
        }
        out.sort_by(|x, y| x.cost_m.total_cmp(&y.cost_m).then(x.offer.cmp(&y.offer)));
        out
    }

    /// Algorithm 1 for binding area `b` (see the module docs). `None`: no
    /// close offer could be satisfied (or `b` is already satisfied, or its
    /// object is fixed). The new constraint is marked `pending` when
    /// `pending` (a session whose fast loop will carry the motion out).
    pub fn satisfy(&mut self, b: AreaId, pending: bool) -> Option<Snap> {
        if self.bond(b).is_some() {
            return None;
        }
        let o = self.areas[b.index()].body;
        if self.objects[o.index()].fixed || !self.is_present(o) {
            return None;
        }
        for x in self.search_close(b) {
            let o2 = self.areas[x.offer.index()].body;
            if self.would_cycle(b, x.offer) {
                continue;
            }
            let m = self.check_move(o, x.mv, Some([o, o2]));
            if !m.same_as(&x.mv) {
                continue;
            }
            let group = self.group(o);
            let saved: Vec<_> = group.iter().map(|g| self.pose(*g)).collect();
            for g in &group {
                let p = x.mv.apply(&self.pose(*g));
                self.set_pose(*g, p);
            }
            if !self.aligned(b, x.offer, false) {
                for (g, p) in group.iter().zip(saved) {
                    self.set_pose(*g, p);
                }
                continue;
            }
            self.add_bond(b, x.offer, pending);
            return Some(Snap {
                binding: b,
                offer: x.offer,
                mv: x.mv,
                before: x.relation,
            });
        }
        None
    }

    /// Algorithm 1 for every free binding area of `o`, in order.
    pub fn satisfy_object(&mut self, o: BodyId, pending: bool) -> Vec<Snap> {
        let bindings = self.objects[o.index()].bindings.clone();
        bindings
            .into_iter()
            .filter_map(|b| self.satisfy(b, pending))
            .collect()
    }

    /// The loader's pass: every free binding area already aligned (within
    /// the tolerance) with a fitting offer is satisfied with the nearest
    /// one, unless that would close a directed cycle. Nothing moves.
    /// Returns the constraints satisfied.
    pub fn satisfy_aligned(&mut self) -> usize {
        let mut n = 0;
        for b in 0..self.areas.len() {
            let b = AreaId(b as u32);
            if self.areas[b.index()].kind != AreaKind::Binding || self.bond(b).is_some() {
                continue;
            }
            let found = self
                .search_close(b)
                .into_iter()
                .find(|x| self.aligned(b, x.offer, false) && !self.would_cycle(b, x.offer));
            if let Some(x) = found {
                self.add_bond(b, x.offer, false);
                n += 1;
            }
        }
        n
    }
}
