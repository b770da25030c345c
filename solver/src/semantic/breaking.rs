//! Breaking a satisfied constraint (§5.3): the constraint is removed and its
//! pair of objects goes on the exception list, whose collisions are ignored
//! (numerically, two surfaces that touched may overlap a little) until the
//! pair separates. Separated here means: not colliding **and** the binding
//! no longer close to any of the other object's offers. The second clause
//! is ours: a haptic session searches for snaps every slow-loop cycle, and a
//! cup pulled off a table is still within the snap distance for a moment;
//! without it the table would take it straight back.

use super::area::AreaId;
use super::scene::SemanticScene;
use crate::BodyId;

impl SemanticScene {
    /// Breaks binding area `b`'s constraint. Returns the offer area it was
    /// satisfied with (`None`: it was not satisfied).
    pub fn break_bond(&mut self, b: AreaId) -> Option<AreaId> {
        let bond = self.remove_bond(b)?;
        let pair = [
            self.areas[b.index()].body,
            self.areas[bond.offer.index()].body,
        ];
        if !self.exceptions.contains(&pair) {
            self.exceptions.push(pair);
        }
        Some(bond.offer)
    }

    /// Releases binding area `b`'s constraint without a pull (the
    /// unconstrained mode turning a held object's constraints off): the
    /// pair goes on the exception list only if the two overlap deeper than
    /// the collision tolerance, so the binding may snap straight back when
    /// the constraints are on again. Returns the offer area.
    pub fn release(&mut self, b: AreaId) -> Option<AreaId> {
        let bond = self.remove_bond(b)?;
        let (x, y) = (
            self.areas[b.index()].body,
            self.areas[bond.offer.index()].body,
        );
        let (px, py) = (self.pose(x), self.pose(y));
        if self.overlap_m(x, &px, y, &py) > self.settings.collision_tolerance_m
            && !self.exceptions.contains(&[x, y])
        {
            self.exceptions.push([x, y]);
        }
        Some(bond.offer)
    }

    /// Whether the objects of an exception pair have separated (see the
    /// module docs).
    pub fn separated(&self, [x, y]: [BodyId; 2]) -> bool {
        let tol = self.settings.collision_tolerance_m;
        let (px, py) = (self.pose(x), self.pose(y));
        if self.overlap_m(x, &px, y, &py) > tol {
            return false;
        }
        let s = &self.settings;
        !self.objects[x.index()].bindings.iter().any(|&b| {
            self.objects[y.index()].offers.iter().any(|&a| {
                let r =
                    super::area::relation(&self.areas[b.index()], &px, &self.areas[a.index()], &py);
                r.distance_m <= s.snap_distance_m
                    && r.distance_m >= -(s.snap_distance_m + tol)
                    && r.outside_m <= s.snap_distance_m
            })
        })
    }

    /// Drops every exception pair that has separated; returns them.
    pub fn update_exceptions(&mut self) -> Vec<[BodyId; 2]> {
        let (gone, kept): (Vec<_>, Vec<_>) =
            self.exceptions.iter().partition(|&&p| self.separated(p));
        self.exceptions = kept;
        gone
    }
}
