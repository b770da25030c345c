//! Which bodies of a model take part in contact, and which pairs never do.

use crate::geometry::ContactBody;
use crate::{ConstraintKind, Model};

/// One entry per body of `model`: its collider if it has a shape (`None`
/// otherwise, or if the shape cannot be compiled, which the scene loader has
/// already refused). A contact finger's fingertip carries its friction;
/// other bodies theirs when `body_friction` (inertial motion: friction
/// between bodies is a force, and forces move bodies only then), else 0.
pub fn contact_bodies(model: &Model, body_friction: bool) -> Vec<Option<ContactBody>> {
    model
        .bodies()
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let collider = b.shape.as_ref()?.collider().ok()?;
            let friction = model
                .fingers()
                .iter()
                .find(|f| f.body.index() == i && f.tip.is_some())
                .and_then(|f| f.tip)
                .map_or(if body_friction { b.friction } else { 0.0 }, |t| t.friction);
            Some(ContactBody {
                collider,
                fixed: b.fixed,
                fingertip: b.fingertip,
                friction,
            })
        })
        .collect()
}

/// Pairs of bodies joined by a joint: they never collide with each other
/// (a hinge's two links overlap at the hinge by construction), unless every
/// joint between them says `collide` (a door and its frame, a link that
/// folds onto the next).
pub fn jointed_pairs(model: &Model) -> Vec<[u32; 2]> {
    model
        .constraints()
        .iter()
        .enumerate()
        .filter(|(k, c)| {
            let joint = c.limits.unwrap_or(crate::ConstraintId(*k as u32));
            !model.joint_collides(joint)
        })
        .map(|(_, c)| c)
        .filter(|c| {
            c.finger.is_none()
                && !matches!(
                    c.kind,
                    ConstraintKind::QuaternionNorm
                        | ConstraintKind::Contact
                        | ConstraintKind::ContactFriction
                )
        })
        .filter_map(|c| match c.bodies {
            [Some(a), Some(b)] => Some([a.0, b.0]),
            _ => None,
        })
        .collect()
}
