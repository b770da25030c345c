//! Public, per-constraint and per-row metadata.

use std::fmt;
use std::ops::Range;

use crate::{BodyId, ConstraintId, FingerId};

/// What a constraint is. Determines its rows and their units (see
/// [`ConstraintKind::row_unit`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ConstraintKind {
    /// Spherical joint: 3 rows, m.
    Spherical,
    /// Perpendicular axes: 1 row, angle.
    Perpendicular,
    /// Universal joint: 3 rows m, 1 row angle.
    Universal,
    /// Revolute joint: 3 rows m, 2 rows angle.
    Revolute,
    /// Prismatic joint: 2 rows m, 3 rows angle.
    Prismatic,
    /// Fixed joint (weld): 3 rows m, 3 rows angle.
    Fixed,
    /// Distance joint: 1 row, m.
    Distance,
    /// Point held on a plane of another body: 1 row, m.
    PointOnPlane,
    /// Point grasp of a finger: 3 rows, m.
    PointFinger,
    /// Rigid grasp of a finger: 3 rows m, 3 rows angle.
    RigidFinger,
    /// eᵀe − 1 of one moving body: 1 row, dimensionless.
    QuaternionNorm,
    /// Limits on a revolute joint's angle: 2 inequality rows, angle.
    RevoluteLimit,
    /// Limits on a prismatic joint's displacement: 2 inequality rows, m.
    PrismaticLimit,
    /// Limits on a distance joint's measured length: 2 inequality rows, m.
    DistanceLimit,
    /// Point–plane non-penetration N·P ≥ 0 (contact witness): 1 row, m.
    PointPlaneInequality,
    /// The witness rows of a tracked contact pair (≥ 0, one per slot), m.
    Contact,
    /// The two friction stick rows of a fingertip contact, m.
    ContactFriction,
    /// Bounds on one design-variable component: 2 inequality rows, m.
    DesignBound,
    /// A design-variable component held at its bound (lo = hi): 1 row, m.
    DesignPin,
    /// A satisfied semantic surface constraint's plane rows (Gösele &
    /// Stuerzlinger §3.1.1): three points of the binding area on the offer
    /// area's plane, so the areas are coplanar with anti-parallel orientation
    /// vectors: 3 rows, m.
    SurfacePlane,
    /// The same constraint's polygon inclusion: each vertex of the binding
    /// polygon on the inner side of each edge of the (convex) offer polygon
    /// (≥ 0): one row per vertex and edge, m.
    SurfaceInclusion,
    /// A hand's hold on a body: the fingertip's centre fixed in the body
    /// (a spherical joint the slow loop adds and removes): 3 rows, m.
    Hold,
    /// A point held on a parametric surface with its (u, v) coordinates
    /// (Nelson & Cohen App. E; `crate::parametric`): 3 rows, m.
    OnSurface,
    /// A ball rolling without slipping on a surface: the contact point's
    /// tangential displacement over a tick (nonholonomic): 2 rows, m.
    Rolling,
}

impl ConstraintKind {
    /// Unit kind of local row `row` (0-based within the constraint).
    pub fn row_unit(self, row: usize) -> RowUnit {
        use ConstraintKind::*;
        let metres = match self {
            Spherical | Distance | PointOnPlane | PointFinger | PrismaticLimit | DistanceLimit
            | PointPlaneInequality | Contact | ContactFriction | DesignBound | DesignPin
            | SurfacePlane | SurfaceInclusion | Hold | OnSurface | Rolling => {
                return RowUnit::Length;
            }
            Perpendicular | RevoluteLimit => return RowUnit::Angle,
            QuaternionNorm => return RowUnit::Dimensionless,
            Universal | Revolute | Fixed | RigidFinger => 3,
            Prismatic => 2,
        };
        if row < metres {
            RowUnit::Length
        } else {
            RowUnit::Angle
        }
    }

    /// Equality (C = 0) or inequality (C ≥ 0).
    pub fn sense(self) -> Sense {
        use ConstraintKind::*;
        match self {
            RevoluteLimit | PrismaticLimit | DistanceLimit | PointPlaneInequality | Contact
            | DesignBound | SurfaceInclusion => Sense::Inequality,
            ContactFriction => Sense::Friction,
            _ => Sense::Equality,
        }
    }

    /// Lower-case name, as in scene files where the kind comes from one.
    pub fn as_str(self) -> &'static str {
        use ConstraintKind::*;
        match self {
            Spherical => "spherical",
            Perpendicular => "perpendicular",
            Universal => "universal",
            Revolute => "revolute",
            Prismatic => "prismatic",
            Fixed => "fixed",
            Distance => "distance",
            PointOnPlane => "point_on_plane",
            PointFinger => "point finger",
            RigidFinger => "rigid finger",
            QuaternionNorm => "quaternion norm",
            RevoluteLimit => "revolute limit",
            PrismaticLimit => "prismatic limit",
            DistanceLimit => "distance limit",
            PointPlaneInequality => "point-plane inequality",
            Contact => "contact",
            ContactFriction => "contact friction",
            DesignBound => "design bound",
            DesignPin => "design pin",
            SurfacePlane => "surface plane",
            SurfaceInclusion => "surface inclusion",
            Hold => "hold",
            OnSurface => "on_surface",
            Rolling => "rolling",
        }
    }
}

impl fmt::Display for ConstraintKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Whether a row must vanish or stay non-negative.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sense {
    /// C = 0.
    Equality,
    /// C ≥ 0 (feasible side positive).
    Inequality,
    /// A friction stick row: C = 0 while its contact sticks (the Coulomb
    /// cone holds), free while it slips.
    Friction,
}

/// The physical unit of a row's value, for per-row scaling (K of Eq. 3) and for
/// reporting residuals in metres and radians separately.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RowUnit {
    /// Metres (positions, offsets, distances).
    Length,
    /// Dimensionless rows whose small values are angles in radians: cosines of
    /// perpendicular axes, orientation errors, hinge angles.
    Angle,
    /// Pure numbers that are not angles: the quaternion norm rows eᵀe − 1.
    Dimensionless,
}

/// Metadata of one row of C.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RowInfo {
    /// The constraint this row belongs to.
    pub constraint: ConstraintId,
    /// Equality or inequality.
    pub sense: Sense,
    /// Unit of the row's value.
    pub unit: RowUnit,
}

/// Metadata of one constraint.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstraintInfo {
    /// Joint or finger name; `"<joint>.limits"`, `"<body>.norm"`, or the
    /// inequality's name.
    pub name: String,
    /// What it is.
    pub kind: ConstraintKind,
    /// Its rows in C (contiguous).
    pub rows: Range<usize>,
    /// The two bodies it relates (`None`: the world, e.g. a finger target or a
    /// world plane). Fixed bodies appear here but have no columns.
    pub bodies: [Option<BodyId>; 2],
    /// The finger, for finger constraints.
    pub finger: Option<FingerId>,
    /// The joint it limits, for limit constraints.
    pub limits: Option<ConstraintId>,
}

impl ConstraintInfo {
    /// Equality or inequality.
    pub fn sense(&self) -> Sense {
        self.kind.sense()
    }
}
