//! Collision tests (§3.2) with parry, through the contact module's
//! colliders: two objects collide when their shapes overlap deeper than
//! [`SemanticSettings::collision_tolerance_m`](super::SemanticSettings)
//! (touching is not colliding: constraints rely on touching surfaces).
//! Pairs bound by a satisfied constraint, pairs on the exception list,
//! ignored pairs (joints, holds) and pairs of fixed bodies are never tested.

use parry3d_f64::query;

use super::scene::{SemanticScene, aabb};
use crate::BodyId;
use crate::geometry::Pose3;
use crate::geometry::convert::to_na;

/// Two objects found overlapping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collision {
    /// The objects.
    pub bodies: [BodyId; 2],
    /// How deep they overlap, m.
    pub depth_m: f64,
}

impl SemanticScene {
    /// How deep objects `x` and `y` overlap at poses `px`, `py` (0 when
    /// apart, or when either has no shape), m.
    pub fn overlap_m(&self, x: BodyId, px: &Pose3, y: BodyId, py: &Pose3) -> f64 {
        let (Some(a), Some(b)) = (
            self.objects[x.index()].collider.as_ref(),
            self.objects[y.index()].collider.as_ref(),
        ) else {
            return 0.0;
        };
        match query::contact(&px.to_parry(), &*a.full, &py.to_parry(), &*b.full, 0.0) {
            Ok(Some(c)) => (-c.dist).max(0.0),
            _ => 0.0,
        }
    }

    /// Distance from a ball of `radius_m` at the world point `centre` to
    /// object `o`'s shape, m (0 when they overlap; infinite without a shape).
    pub fn ball_distance_m(
        &self,
        o: BodyId,
        centre: &nalgebra::Vector3<f64>,
        radius_m: f64,
    ) -> f64 {
        let Some(c) = self.objects[o.index()].collider.as_ref() else {
            return f64::INFINITY;
        };
        let ball = Pose3 {
            r: *centre,
            rot: nalgebra::Matrix3::identity(),
        };
        query::distance(
            &ball.to_parry(),
            &parry3d_f64::shape::Ball::new(radius_m),
            &self.objects[o.index()].pose.to_parry(),
            &*c.full,
        )
        .map_or(f64::INFINITY, |d| d.distance)
    }

    /// Whether the collisions of `x` and `y` are tested at all (two fixed
    /// bodies never collide: walls meet the floor by construction).
    pub fn tested(&self, x: BodyId, y: BodyId) -> bool {
        let both_fixed = self.objects[x.index()].fixed && self.objects[y.index()].fixed;
        let excepted = self
            .exceptions
            .iter()
            .any(|&[a, b]| (a == x && b == y) || (a == y && b == x));
        let absent = !self.is_present(x) || !self.is_present(y);
        !(x == y
            || absent
            || both_fixed
            || excepted
            || self.bound_pair(x, y)
            || self.is_ignored(x, y))
    }

    /// The first collision of the objects `moved` at the poses `poses`
    /// (same order) with any object not in `moved` (at its own pose), other
    /// than the pair `skip`. Objects in `moved` are never tested against
    /// each other (they move together).
    pub fn first_collision(
        &self,
        moved: &[BodyId],
        poses: &[Pose3],
        skip: Option<[BodyId; 2]>,
    ) -> Option<Collision> {
        let tol = self.settings.collision_tolerance_m;
        for (&x, px) in moved.iter().zip(poses) {
            let Some(c) = self.objects[x.index()].collider.as_ref() else {
                continue;
            };
            let bb = c.full.compute_aabb(&px.to_parry());
            let (lo, hi) = aabb([to_na(bb.mins), to_na(bb.maxs)].into_iter(), tol);
            for y in self.objects_near(&lo, &hi) {
                let y = BodyId(y);
                if moved.binary_search(&y).is_ok()
                    || skip.is_some_and(|[a, b]| (a == x && b == y) || (a == y && b == x))
                    || !self.tested(x, y)
                {
                    continue;
                }
                let depth = self.overlap_m(x, px, y, &self.objects[y.index()].pose);
                if depth > tol {
                    return Some(Collision {
                        bodies: [x, y],
                        depth_m: depth,
                    });
                }
            }
        }
        None
    }

    /// Every tested pair overlapping deeper than the tolerance at the
    /// current poses.
    pub fn collisions(&self) -> Vec<Collision> {
        let tol = self.settings.collision_tolerance_m;
        let mut out = Vec::new();
        for (i, o) in self.objects.iter().enumerate() {
            let Some(c) = o.collider.as_ref() else {
                continue;
            };
            let x = BodyId(i as u32);
            let bb = c.full.compute_aabb(&o.pose.to_parry());
            let (lo, hi) = aabb([to_na(bb.mins), to_na(bb.maxs)].into_iter(), tol);
            for y in self.objects_near(&lo, &hi) {
                let y = BodyId(y);
                if y <= x || !self.tested(x, y) {
                    continue;
                }
                let depth = self.overlap_m(x, &o.pose, y, &self.objects[y.index()].pose);
                if depth > tol {
                    out.push(Collision {
                        bodies: [x, y],
                        depth_m: depth,
                    });
                }
            }
        }
        out
    }
}
