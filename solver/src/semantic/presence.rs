//! Adding and removing objects during a session (§3.3): "when an object is
//! added to the scene it has to be placed at a position where it does not
//! collide with any other object in the scene. Removing an object from a
//! scene is a trivial task: satisfied surface constraints can be broken up
//! and collisions can be removed from the scene. Both operations cannot
//! render a consistent scene inconsistent."
//!
//! ```text
//!  remove(o): o's satisfied bindings broken (no exception entry: o is gone),
//!             the bindings of o's successors released, o out of the grids and
//!             of every collision test; each released object then runs
//!             Algorithm 1 (it re-binds to a close offer, or stays free)
//!  add(o, near): o back in the scene at the valid place nearest `near`:
//!             for each binding b of o and each fitting offer a of a present
//!             object: o turned (about the smallest axis) so b's orientation
//!             vector is −a's, then slid over a's plane on a grid of spots,
//!             nearest first; the first spot with b included in a, no
//!             collision, no directed cycle and every keep-out ball (the
//!             fingertips) clear wins, refined by bisection towards the
//!             wanted spot (so it ends where the valid region begins) → satisfied(a, b) at once (aligned, not
//!             pending); an object without bindings goes where `near` is if
//!             that is clear; other objects' free bindings then aligned with
//!             its offers are satisfied (the loader's rule, nothing moves)
//! ```
//!
//! An absent object has no bonds, no grid entries and takes part in no
//! collision test, so consistent(s) holds before and after each operation
//! (the tests in `solver/tests/semantic/presence.rs` check it).

use nalgebra::{Rotation3, Unit, Vector3};

use super::area::AreaId;
use super::satisfy::Snap;
use super::scene::SemanticScene;
use super::spec::AreaKind;
use crate::BodyId;
use crate::geometry::Pose3;

/// Spots tried per offer area at most when adding (a grid over the offer
/// polygon's bounding rectangle, nearest to the wanted place first).
pub const ADD_SPOTS: usize = 4096;

/// Spots along a side of an offer, at most (the grid's step is the
/// larger of this fraction of the offer and a quarter of the binding's
/// radius).
pub const GRID_SIDE: usize = 64;

/// An added object overlaps nothing deeper than this, m (touching is
/// allowed: round-off of exactly touching shapes stays far below it).
pub const PLACE_OVERLAP_M: f64 = 1e-9;

/// Bisections refining the first valid grid spot towards the wanted place
/// (the grid step over 2^24: well under a micrometre).
pub const REFINE_STEPS: usize = 24;

/// What a removal did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Removal {
    /// The removed object's own satisfied constraints, broken: (binding,
    /// offer).
    pub broken: Vec<(AreaId, AreaId)>,
    /// Its successors' constraints on its offers, released: (binding,
    /// offer).
    pub released: Vec<(AreaId, AreaId)>,
    /// Released objects that Algorithm 1 bound again to a close offer.
    pub rebound: Vec<Snap>,
}

/// Where an added object was put.
#[derive(Debug, Clone, PartialEq)]
pub struct Addition {
    /// Its pose.
    pub pose: Pose3,
    /// The constraints satisfied where it was put: (binding, offer).
    pub bound: Vec<(AreaId, AreaId)>,
    /// Other objects' free bindings found aligned with its offers there,
    /// satisfied.
    pub others_bound: usize,
    /// How far from the wanted place it was put (its origin), m.
    pub moved_m: f64,
}

/// Why an object could not be added or removed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PresenceError {
    /// Adding an object already in the scene (or removing an absent one).
    #[error("`{0}` is already {1}")]
    Already(String, &'static str),
    /// A fixed object cannot be placed.
    #[error("`{0}` is fixed: fixed objects are neither added nor removed")]
    Fixed(String),
    /// No spot on any fitting offer is free.
    #[error(
        "no valid place for `{0}`: every spot on its fitting offers collides or leaves the offer"
    )]
    NoPlace(String),
}

impl SemanticScene {
    /// Whether object `o` is in the scene (declared objects start present;
    /// [`remove`](Self::remove) takes one out, [`add`](Self::add) puts it
    /// back).
    pub fn is_present(&self, o: BodyId) -> bool {
        !self.absent.get(o.index()).copied().unwrap_or(false)
    }

    /// Present objects, counted.
    pub fn present_count(&self) -> usize {
        self.absent.iter().filter(|a| !**a).count()
    }

    /// Removes object `o` (see the module docs); `pending`: snaps of the
    /// released objects are carried out by a fast loop.
    pub fn remove(&mut self, o: BodyId, pending: bool) -> Result<Removal, PresenceError> {
        if !self.is_present(o) {
            return Err(PresenceError::Already(self.name(o).into(), "absent"));
        }
        if self.objects[o.index()].fixed {
            return Err(PresenceError::Fixed(self.name(o).into()));
        }
        let mut out = Removal::default();
        for b in self.objects[o.index()].bindings.clone() {
            if let Some(bond) = self.remove_bond(b) {
                out.broken.push((b, bond.offer));
            }
        }
        for b in self.children[o.index()].clone() {
            if let Some(bond) = self.remove_bond(b) {
                out.released.push((b, bond.offer));
            }
        }
        self.exceptions.retain(|p| !p.contains(&o));
        self.absent[o.index()] = true;
        self.unindex(o);
        for &(b, _) in &out.released.clone() {
            if let Some(s) = self.satisfy(b, pending) {
                out.rebound.push(s);
            }
        }
        Ok(out)
    }

    /// Marks object `o` absent from the start (a scene whose schedule adds
    /// it later); nothing is checked or broken (call before any bond).
    pub fn start_absent(&mut self, o: BodyId) {
        self.absent[o.index()] = true;
        self.unindex(o);
    }

    /// Adds object `o` at the valid place nearest `near` (see the module
    /// docs), keeping clear of the balls `keep_out` (centre, radius).
    pub fn add(
        &mut self,
        o: BodyId,
        near: Pose3,
        keep_out: &[(Vector3<f64>, f64)],
    ) -> Result<Addition, PresenceError> {
        if self.is_present(o) {
            return Err(PresenceError::Already(self.name(o).into(), "present"));
        }
        if self.objects[o.index()].fixed {
            return Err(PresenceError::Fixed(self.name(o).into()));
        }
        self.absent[o.index()] = false;
        self.index(o);
        let bindings = self.objects[o.index()].bindings.clone();
        let mut best: Option<(f64, Pose3, AreaId, AreaId)> = None;
        for &b in &bindings {
            for a in 0..self.areas.len() {
                let a = AreaId(a as u32);
                if let Some((cost, pose)) = self.best_spot(b, a, &near, keep_out)
                    && best.as_ref().is_none_or(|x| cost < x.0)
                {
                    best = Some((cost, pose, b, a));
                }
            }
        }
        let placed = match best {
            Some((_, pose, b, a)) => {
                self.set_pose(o, pose);
                self.add_bond(b, a, false);
                let mut bound = vec![(b, a)];
                bound.extend(self.bind_aligned(o));
                Some((pose, bound))
            }
            None if bindings.is_empty() && self.clear_at(o, near, keep_out) => {
                self.set_pose(o, near);
                Some((near, Vec::new()))
            }
            None => None,
        };
        let Some((pose, bound)) = placed else {
            self.start_absent(o);
            return Err(PresenceError::NoPlace(self.name(o).into()));
        };
        // Others' free bindings now aligned with its offers (the loader's
        // rule; nothing moves).
        let taken = self.satisfy_aligned();
        Ok(Addition {
            pose,
            bound,
            others_bound: taken,
            moved_m: (pose.r - near.r).norm(),
        })
    }

    /// The other free bindings of `o` already aligned with a fitting offer
    /// where it was put: satisfied too.
    fn bind_aligned(&mut self, o: BodyId) -> Vec<(AreaId, AreaId)> {
        let mut out = Vec::new();
        for b in self.objects[o.index()].bindings.clone() {
            if self.bond(b).is_some() {
                continue;
            }
            let found = self
                .search_close(b)
                .into_iter()
                .find(|x| self.aligned(b, x.offer, false) && !self.would_cycle(b, x.offer));
            if let Some(x) = found {
                self.add_bond(b, x.offer, false);
                out.push((b, x.offer));
            }
        }
        out
    }

    /// The nearest valid pose of binding `b`'s object with `b` on offer `a`
    /// (and its cost: distance of the origin from `near`), if any.
    fn best_spot(
        &mut self,
        b: AreaId,
        a: AreaId,
        near: &Pose3,
        keep_out: &[(Vector3<f64>, f64)],
    ) -> Option<(f64, Pose3)> {
        let (ab, aa) = (&self.areas[b.index()], &self.areas[a.index()]);
        let (o, o2) = (ab.body, aa.body);
        if aa.kind != AreaKind::Offer
            || o2 == o
            || !self.is_present(o2)
            || !self.order.fits(ab.label, aa.label)
            || self.would_cycle(b, a)
        {
            return None;
        }
        let pa = self.objects[o2.index()].pose;
        let na = aa.normal_w(&pa);
        let nb = ab.normal_w(near);
        // The smallest turn taking nb onto −na.
        // (nb = na: half a turn about an axis in a's plane.)
        let turn = Rotation3::rotation_between(&nb, &-na).unwrap_or_else(|| {
            Rotation3::from_axis_angle(&Unit::new_normalize(pa.dir(&aa.u)), std::f64::consts::PI)
        });
        let rot = turn.into_inner() * near.rot;
        let (u, v) = (pa.dir(&aa.u), pa.dir(&aa.v));
        let origin = aa.centroid_w(&pa);
        let c_local = ab.centroid;
        // The binding's centroid where `near` puts it, dropped onto a's plane.
        let want = near.point(&c_local);
        let want = want - na * na.dot(&(want - origin));
        let (mut lo, mut hi) = (
            nalgebra::Vector2::repeat(f64::INFINITY),
            nalgebra::Vector2::repeat(f64::NEG_INFINITY),
        );
        for p in aa.vertices_w(&pa) {
            let d = p - origin;
            let w = nalgebra::Vector2::new(d.dot(&u), d.dot(&v));
            lo = lo.inf(&w);
            hi = hi.sup(&w);
        }
        // A quarter of the binding's radius, coarser on offers far larger
        // than it (at most about GRID_SIDE² spots; the bisection refines).
        let step = (ab.radius_m / 4.0)
            .max((hi - lo).max() / GRID_SIDE as f64)
            .max(1e-3);
        // A grid through the wanted spot, over the offer's rectangle.
        let w = want - origin;
        let (wu, wv) = (w.dot(&u), w.dot(&v));
        let range = |l: f64, h: f64, c: f64| {
            ((l - c) / step).floor() as i64..=((h - c) / step).ceil() as i64
        };
        let (ri, rj) = (range(lo.x, hi.x, wu), range(lo.y, hi.y, wv));
        let mut spots: Vec<Vector3<f64>> = Vec::new();
        for i in ri {
            for j in rj.clone() {
                spots.push(want + u * (i as f64 * step) + v * (j as f64 * step));
            }
        }
        spots.sort_by(|x, y| (x - want).norm().total_cmp(&(y - want).norm()));
        spots.truncate(ADD_SPOTS);
        let saved = self.objects[o.index()].pose;
        let at = |p: Vector3<f64>| Pose3 {
            r: p - rot * c_local,
            rot,
        };
        // The first valid spot and the valid ones up to two steps farther
        // (a coarse grid may reach the region's nearest point along another
        // ray), each refined towards the wanted spot by bisection: the
        // boundary of the valid region on the segment between them.
        let mut found: Option<(f64, Pose3)> = None;
        let mut reach = f64::INFINITY;
        for p in spots {
            if (p - want).norm() > reach {
                break;
            }
            if !self.valid_at(b, a, at(p), keep_out) {
                continue;
            }
            reach = reach.min((p - want).norm() + 2.0 * step);
            let (mut good, mut bad) = (p, want);
            for _ in 0..REFINE_STEPS {
                let mid = (good + bad) / 2.0;
                if self.valid_at(b, a, at(mid), keep_out) {
                    good = mid;
                } else {
                    bad = mid;
                }
            }
            let pose = at(good);
            let cost = (pose.r - near.r).norm();
            if found.as_ref().is_none_or(|f| cost < f.0) {
                found = Some((cost, pose));
            }
        }
        self.set_pose(o, saved);
        found
    }

    /// Whether binding `b`'s object at `pose` lies on offer `a` (aligned)
    /// and clear of everything (leaves it there).
    fn valid_at(
        &mut self,
        b: AreaId,
        a: AreaId,
        pose: Pose3,
        keep_out: &[(Vector3<f64>, f64)],
    ) -> bool {
        let o = self.areas[b.index()].body;
        self.set_pose(o, pose);
        self.aligned(b, a, false) && self.clear_at(o, pose, keep_out)
    }

    /// Whether `o` at `pose` overlaps nothing deeper than [`PLACE_OVERLAP_M`]
    /// (stricter than the collision tolerance: an added object does not
    /// start inside another, which the contact rows would then push apart)
    /// and keeps clear of every ball.
    fn clear_at(&mut self, o: BodyId, pose: Pose3, keep_out: &[(Vector3<f64>, f64)]) -> bool {
        let saved = self.objects[o.index()].pose;
        self.set_pose(o, pose);
        let balls = keep_out
            .iter()
            .all(|(c, r)| self.ball_distance_m(o, c, *r) > 0.0);
        let free = balls && self.overlaps(o, &pose).is_none();
        self.set_pose(o, saved);
        free
    }

    /// The first tested object `o` overlaps deeper than [`PLACE_OVERLAP_M`]
    /// at `pose`.
    fn overlaps(&self, o: BodyId, pose: &Pose3) -> Option<BodyId> {
        let c = self.objects[o.index()].collider.as_ref()?;
        let bb = c.full.compute_aabb(&pose.to_parry());
        let (lo, hi) = super::scene::aabb(
            [
                crate::geometry::convert::to_na(bb.mins),
                crate::geometry::convert::to_na(bb.maxs),
            ]
            .into_iter(),
            self.settings.collision_tolerance_m,
        );
        self.objects_near(&lo, &hi)
            .into_iter()
            .map(BodyId)
            .find(|&y| {
                self.tested(o, y)
                    && self.overlap_m(o, pose, y, &self.objects[y.index()].pose) > PLACE_OVERLAP_M
            })
    }

    /// Takes object `o` and its offers out of the grids.
    pub(super) fn unindex(&mut self, o: BodyId) {
        self.object_grid.remove(o.0);
        for &a in &self.objects[o.index()].offers {
            self.offer_grid.remove(a.0);
        }
    }
}
