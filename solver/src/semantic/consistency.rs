//! The consistency predicate (§3.3):
//!
//! ```text
//!  consistent(s) ⇔ ∀ a, b: satisfied(a, b) → aligned(a, b) ∧ l(b) ≤_L l(a)
//!                ∧ ∀ o, o': collision(o, o') → ∃ a ∈ A(o), b ∈ B(o'): satisfied(a, b)
//!                                             ∨ ∃ a ∈ A(o'), b ∈ B(o): satisfied(a, b)
//! ```
//!
//! with the exception list's pairs (§5.3) and ignored pairs (joints, holds)
//! exempt from the collision clause, and no directed cycle in the grouping
//! graph (§4.1). aligned(a, b): coplanar, orientation vectors anti-parallel,
//! b's polygon inside a's, each within the alignment tolerance; a `pending`
//! constraint (its snap is still arriving in the fast loop) only within the
//! snap distance and angle it was satisfied from.

use std::fmt;

use super::area::{AreaId, Relation, relation};
use super::collide::Collision;
use super::scene::SemanticScene;

/// Why a scene is not consistent.
#[derive(Debug, Clone, PartialEq)]
pub enum Inconsistency {
    /// A satisfied constraint's areas are not aligned.
    Misaligned {
        /// The binding area.
        binding: AreaId,
        /// The offer area.
        offer: AreaId,
        /// How they lie.
        relation: Relation,
    },
    /// A satisfied constraint's labels do not fit.
    Unfit {
        /// The binding area.
        binding: AreaId,
        /// The offer area.
        offer: AreaId,
    },
    /// Two objects collide without a constraint between them.
    Collision(Collision),
    /// The grouping graph has a directed cycle.
    Cycle,
}

impl fmt::Display for Inconsistency {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Misaligned {
                binding,
                offer,
                relation: r,
            } => write!(
                f,
                "binding area {} is not aligned with offer area {}: {:.3e} m off the plane, \
                 {:.3e} rad from anti-parallel, {:.3e} m outside",
                binding.0, offer.0, r.off_plane_m, r.angle_rad, r.outside_m
            ),
            Self::Unfit { binding, offer } => write!(
                f,
                "binding area {} does not fit offer area {}",
                binding.0, offer.0
            ),
            Self::Collision(c) => write!(
                f,
                "bodies #{} and #{} overlap by {:.3e} m and no satisfied constraint binds them",
                c.bodies[0].0, c.bodies[1].0, c.depth_m
            ),
            Self::Cycle => f.write_str("the grouping graph has a directed cycle"),
        }
    }
}

impl SemanticScene {
    /// aligned(a, b) for binding area `b` and offer area `a` at the current
    /// poses (`pending`: within the snap distance and angle, see the module
    /// docs).
    pub fn aligned(&self, b: AreaId, a: AreaId, pending: bool) -> bool {
        let s = &self.settings;
        let (ab, aa) = (&self.areas[b.index()], &self.areas[a.index()]);
        let r = relation(
            ab,
            &self.objects[ab.body.index()].pose,
            aa,
            &self.objects[aa.body.index()].pose,
        );
        let tol = s.align_tolerance;
        if pending {
            r.off_plane_m <= s.snap_distance_m + ab.radius_m * s.snap_angle_rad + tol
                && r.angle_rad <= s.snap_angle_rad + tol
                && r.outside_m <= s.snap_distance_m + tol
        } else {
            r.off_plane_m <= tol && r.angle_rad <= tol && r.outside_m <= tol
        }
    }

    /// consistent(s) (see the module docs): `Ok` or the first reason not.
    pub fn consistent(&self) -> Result<(), Inconsistency> {
        for (b, bond) in self.bonds() {
            let (lb, la) = (
                self.areas[b.index()].label,
                self.areas[bond.offer.index()].label,
            );
            if !self.order.fits(lb, la) {
                return Err(Inconsistency::Unfit {
                    binding: b,
                    offer: bond.offer,
                });
            }
            if !self.aligned(b, bond.offer, bond.pending) {
                let (ab, aa) = (&self.areas[b.index()], &self.areas[bond.offer.index()]);
                return Err(Inconsistency::Misaligned {
                    binding: b,
                    offer: bond.offer,
                    relation: relation(
                        ab,
                        &self.objects[ab.body.index()].pose,
                        aa,
                        &self.objects[aa.body.index()].pose,
                    ),
                });
            }
        }
        if let Some(c) = self.collisions().first() {
            return Err(Inconsistency::Collision(*c));
        }
        if self.has_directed_cycle() {
            return Err(Inconsistency::Cycle);
        }
        Ok(())
    }
}
