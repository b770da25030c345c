//! The constraint library: one kind per file, each giving its value and its
//! analytic Jacobian through the shared helpers of `block.rs`.
//!
//! | file | kind | rows | units |
//! |---|---|---|---|
//! | `spherical.rs` | spherical joint, Eq. 9 | 3 | m |
//! | `perpendicular.rs` | perpendicular axes, Eq. 10 | 1 | angle |
//! | `universal.rs` | universal joint, Eq. 11 | 3 + 1 | m, angle |
//! | `revolute.rs` | revolute joint | 3 + 2 | m, angle |
//! | `prismatic.rs` | prismatic joint | 2 + 3 | m, angle |
//! | `weld.rs` | fixed joint | 3 + 3 | m, angle |
//! | `distance.rs` | distance joint (strut) | 1 | m |
//! | `point_plane.rs` | `point_on_plane` joint (=) and point–plane inequality (≥) | 1 | m |
//! | `finger.rs` | point grasp / rigid grasp | 3 / 3 + 3 | m, angle |
//! | `quat_norm.rs` | Euler-parameter norm, one per moving body | 1 | dimensionless |
//! | `limit.rs` | joint limits on a revolute / prismatic / distance coordinate (≥) | 2 | angle or m |
//! | `bound.rs` | bounds on a design-variable component (≥), or a pin (=) when lo = hi | 2 / 1 | m |
//! | `witness/` | contact witnesses (≥), one witness kind per file, and friction stick rows | per pair | m |
//! | `gear.rs` | gear pair: two revolutes at a ratio of whole numbers, Fig. 12 | 1 | angle |
//! | `rack_pinion.rs` | rack and pinion: a prismatic following a revolute | 1 | m |
//! | `crate::parametric` | `on_surface` (3 rows, m, with (u, v) columns) and `rolling` (2 rows, m) | 3 / 2 | m |
//! | `surface.rs` | semantic surface constraints: plane rows (=) and polygon inclusion (≥), parameters in the witness table's tail | 3 / per vertex × edge | m |
//!
//! `axes.rs` holds the reference directions of the axis-aligning joints.

pub(crate) mod axes;
pub(crate) mod block;
pub(crate) mod bound;
pub(crate) mod distance;
pub(crate) mod finger;
pub(crate) mod gear;
pub(crate) mod limit;
mod meta;
pub(crate) mod perpendicular;
pub(crate) mod point_plane;
pub(crate) mod prismatic;
pub(crate) mod quat_norm;
pub(crate) mod rack_pinion;
pub(crate) mod revolute;
pub(crate) mod spherical;
pub(crate) mod surface;
pub(crate) mod universal;
pub(crate) mod weld;
pub mod witness;

#[cfg(test)]
mod tests_scale;

pub use meta::{ConstraintInfo, ConstraintKind, RowInfo, RowUnit, Sense};

use block::{Ctx, Groups, Sink, Slot};

/// A compiled constraint: its geometry, ready to evaluate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Geometry {
    Spherical(spherical::Spherical),
    Perpendicular(perpendicular::Perpendicular),
    Universal(universal::Universal),
    Revolute(revolute::Revolute),
    Prismatic(prismatic::Prismatic),
    Weld(weld::Weld),
    Distance(distance::Distance),
    PointPlane(point_plane::PointPlane),
    Finger(finger::Finger),
    QuatNorm(quat_norm::QuatNorm),
    Limit(limit::Limit),
    Contact(witness::ContactRows),
    Bound(bound::DesignBound),
    Surface(surface::SurfaceRows),
    Gear(gear::Gear),
    RackPinion(rack_pinion::RackPinion),
    OnSurface(crate::parametric::contact::OnSurface),
    Rolling(crate::parametric::rolling::Rolling),
}

impl Geometry {
    /// Number of rows.
    pub fn rows(&self) -> usize {
        match self {
            Self::Spherical(_) => spherical::Spherical::ROWS,
            Self::Perpendicular(_) => perpendicular::Perpendicular::ROWS,
            Self::Universal(_) => universal::Universal::ROWS,
            Self::Revolute(_) => revolute::Revolute::ROWS,
            Self::Prismatic(_) => prismatic::Prismatic::ROWS,
            Self::Weld(_) => weld::Weld::ROWS,
            Self::Distance(_) => distance::Distance::ROWS,
            Self::PointPlane(_) => point_plane::PointPlane::ROWS,
            Self::Finger(f) => f.rows(),
            Self::QuatNorm(_) => quat_norm::QuatNorm::ROWS,
            Self::Limit(_) => limit::Limit::ROWS,
            Self::Contact(c) => c.rows as usize,
            Self::Bound(b) => b.rows(),
            Self::Surface(s) => s.rows as usize,
            Self::Gear(_) => gear::Gear::ROWS,
            Self::RackPinion(_) => rack_pinion::RackPinion::ROWS,
            Self::OnSurface(_) => crate::parametric::contact::OnSurface::ROWS,
            Self::Rolling(_) => crate::parametric::rolling::Rolling::ROWS,
        }
    }

    /// Whether the rows depend on the poses of the two ends of
    /// [`frames`](Self::frames) (false for quaternion norms and design
    /// bounds, which read raw coordinates).
    pub fn has_ends(&self) -> bool {
        !matches!(self, Self::QuatNorm(_) | Self::Bound(_))
    }

    /// Whether every row is invariant to scaling a body's Euler parameters
    /// e, i.e. its derivative on e is orthogonal to e. True for every kind
    /// whose body columns are written from a world-frame gradient
    /// ([`block::Sink::row`]: the e columns are Ω(e)ᵀ g and Ω(e) e = 0,
    /// `crate::rotation`); such a row's entry in A = C_q M̃⁻¹ C_qᵀ with a
    /// body's quaternion-norm row 2eᵀ is then zero in exact arithmetic,
    /// because M̃_e⁻¹ e = (|e|²/4c′) e (`force::inertia`), and the force
    /// factor leaves that coupling out of its pattern (`force::gram`).
    /// False for the norm row itself, which reads e raw. Exhaustive on
    /// purpose: a new kind that writes a body's e columns through
    /// [`block::Sink::set`] must answer false.
    pub fn scale_free_in_e(&self) -> bool {
        match self {
            Self::QuatNorm(_) => false,
            // Design-variable and surface-parameter columns only
            // (`Sink::set` on `Slot::Length`); body columns through `row`.
            Self::Bound(_) | Self::Distance(_) | Self::OnSurface(_) => true,
            Self::Spherical(_)
            | Self::Perpendicular(_)
            | Self::Universal(_)
            | Self::Revolute(_)
            | Self::Prismatic(_)
            | Self::Weld(_)
            | Self::PointPlane(_)
            | Self::Finger(_)
            | Self::Limit(_)
            | Self::Contact(_)
            | Self::Surface(_)
            | Self::Gear(_)
            | Self::RackPinion(_)
            | Self::Rolling(_) => true,
        }
    }

    /// The column groups every row of this constraint touches.
    pub fn groups(&self) -> Groups {
        match self {
            Self::Spherical(j) => j.pair.groups(),
            Self::Perpendicular(j) => j.pair.groups(),
            Self::Universal(j) => j.pair.groups(),
            Self::Revolute(j) => j.pair.groups(),
            Self::Prismatic(j) => j.pair.groups(),
            Self::Weld(j) => j.pair.groups(),
            Self::Distance(j) => {
                let mut g = j.pair.groups();
                if let block::Param1::Free(c) = j.length {
                    g[Slot::Length as usize] = Some((c, 1));
                }
                g
            }
            Self::PointPlane(j) => j.pair.groups(),
            Self::Finger(j) => j.pair.groups(),
            Self::QuatNorm(j) => j.groups(),
            Self::Limit(j) => j.groups(),
            Self::Contact(c) => c.pair.groups(),
            Self::Bound(b) => b.groups(),
            Self::Surface(s) => s.pair.groups(),
            Self::Gear(j) => j.pair.groups(),
            Self::RackPinion(j) => j.pair.groups(),
            Self::OnSurface(s) => s.pair.groups(),
            Self::Rolling(r) => r.pair.groups(),
        }
    }

    /// Frame indices of the two ends (for the Jacobian writer).
    pub fn frames(&self) -> [usize; 2] {
        match self {
            Self::Spherical(j) => j.pair.frame,
            Self::Perpendicular(j) => j.pair.frame,
            Self::Universal(j) => j.pair.frame,
            Self::Revolute(j) => j.pair.frame,
            Self::Prismatic(j) => j.pair.frame,
            Self::Weld(j) => j.pair.frame,
            Self::Distance(j) => j.pair.frame,
            Self::PointPlane(j) => j.pair.frame,
            Self::Finger(j) => j.pair.frame,
            // The norm row writes raw values only; any frame will do.
            Self::QuatNorm(_) => [0, 0],
            Self::Limit(j) => j.pair().frame,
            Self::Contact(c) => c.pair.frame,
            // Raw values only, like the norm row.
            Self::Bound(_) => [0, 0],
            Self::Surface(s) => s.pair.frame,
            Self::Gear(j) => j.pair.frame,
            Self::RackPinion(j) => j.pair.frame,
            Self::OnSurface(s) => s.pair.frame,
            Self::Rolling(r) => r.pair.frame,
        }
    }

    /// The anchors of the two ends (constants for the kinds without a pair
    /// of anchors): where a flexible body's deforming points are found.
    pub fn anchors(&self) -> [block::Param3; 2] {
        let none = [block::Param3::Const(nalgebra::Vector3::zeros()); 2];
        match self {
            Self::Spherical(j) => j.pair.anchor,
            Self::Perpendicular(j) => j.pair.anchor,
            Self::Universal(j) => j.pair.anchor,
            Self::Revolute(j) => j.pair.anchor,
            Self::Prismatic(j) => j.pair.anchor,
            Self::Weld(j) => j.pair.anchor,
            Self::Distance(j) => j.pair.anchor,
            Self::PointPlane(j) => j.pair.anchor,
            Self::Finger(j) => j.pair.anchor,
            Self::Limit(j) => j.pair().anchor,
            Self::Contact(c) => c.pair.anchor,
            Self::Surface(s) => s.pair.anchor,
            Self::OnSurface(s) => s.pair.anchor,
            Self::Rolling(r) => r.pair.anchor,
            Self::Gear(j) => j.pair.anchor,
            Self::RackPinion(j) => j.pair.anchor,
            Self::QuatNorm(_) | Self::Bound(_) => none,
        }
    }

    /// Writes this constraint's rows of C into `c` and of C_q into `sink`.
    #[inline]
    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        match self {
            Self::Spherical(j) => j.eval(x, c, sink),
            Self::Perpendicular(j) => j.eval(x, c, sink),
            Self::Universal(j) => j.eval(x, c, sink),
            Self::Revolute(j) => j.eval(x, c, sink),
            Self::Prismatic(j) => j.eval(x, c, sink),
            Self::Weld(j) => j.eval(x, c, sink),
            Self::Distance(j) => j.eval(x, c, sink),
            Self::PointPlane(j) => j.eval(x, c, sink),
            Self::Finger(j) => j.eval(x, c, sink),
            Self::QuatNorm(j) => j.eval(x, c, sink),
            Self::Limit(j) => j.eval(x, c, sink),
            Self::Contact(j) => j.eval(x, c, sink),
            Self::Bound(j) => j.eval(x, c, sink),
            Self::Surface(j) => j.eval(x, c, sink),
            Self::Gear(j) => j.eval(x, c, sink),
            Self::RackPinion(j) => j.eval(x, c, sink),
            Self::OnSurface(j) => j.eval(x, c, sink),
            Self::Rolling(j) => j.eval(x, c, sink),
        }
    }
}
