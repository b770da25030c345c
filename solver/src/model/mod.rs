//! The mechanism model: bodies, the coordinate [`Layout`], the compiled
//! constraints with per-row metadata, fingers and gravity. Built once by
//! [`ModelBuilder`], immutable afterwards; [`Model::with_inequalities`] derives a
//! model with extra point–plane inequalities for a new active set,
//! [`Model::with_semantic`] one with satisfied surface constraints and holds.

mod assembler;
mod auxiliary;
mod body;
mod build;
mod compiler;
mod contact;
mod error;
mod gears;
mod inequality;
mod joints;
mod layout;
mod spec;
mod surface;

pub use auxiliary::{AuxBlock, AuxOwner, Rest};
/// The check every compiled value goes through (objectives use it too).
pub(crate) use body::finite;
pub use build::ModelBuilder;
pub use contact::{ContactLayout, ContactPair};
pub use error::{BuildError, Owner};
pub use gears::{GearKind, GearSpec, MAX_GEAR_TEETH};
pub use inequality::{PlaneOwner, PointPlaneSpec};
pub use layout::{DesignOwner, DesignVar, Layout};
pub use spec::{
    BodySpec, Bounds, ContactSurface, DEFAULT_FINGERTIP_RADIUS_M, DEFAULT_INERTIA_RADIUS_M,
    DEFAULT_MASS_KG, DesignParam, FINGERTIP_MASS_KG, FingerSpec, Fingertip, Grasp, JointKind,
    JointSpec, MAX_FINGERTIP_RADIUS_M, MAX_FRICTION, Shape, UnknownName,
};
pub use surface::{HoldSpec, SemanticLayout, SnapSettings, SurfaceInfo, SurfaceRow, SurfaceSpec};

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use crate::constraint::{ConstraintInfo, Geometry, RowInfo};
use crate::rotation::BodyFrame;
use crate::{BodyId, ConstraintId, FingerId, FingerTarget};

/// One rigid body.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Unique name.
    pub name: String,
    /// Fixed bodies have no coordinates; their pose is the initial one forever.
    pub fixed: bool,
    /// Initial position of the origin, metres, world frame.
    pub position_m: Vector3<f64>,
    /// Initial orientation, body → world (normalised).
    pub orientation: UnitQuaternion<f64>,
    /// Mass, kilograms.
    pub mass_kg: f64,
    /// Principal moments of inertia about the body axes, kg·m².
    pub inertia_kg_m2: Vector3<f64>,
    /// Collision shape, body frame (`None`: takes part in no contact).
    pub shape: Option<Shape>,
    /// A contact finger's fingertip: driven by its finger, feels no gravity.
    pub fingertip: bool,
    /// Coulomb μ of its contacts with other bodies (see
    /// [`BodySpec::friction`](crate::BodySpec::friction)).
    pub friction: f64,
    /// Its convex shape was cut to [`MAX_HULL_VERTICES`](crate::geometry::MAX_HULL_VERTICES)
    /// points at build (`shape` holds the kept ones; `None` when nothing was
    /// cut off): how, and the largest distance a given point lies from the
    /// kept hull.
    pub hull: Option<crate::geometry::HullSimplification>,
    /// Restitution of its contacts, in [0, 1] (see
    /// [`BodySpec::restitution`](crate::BodySpec::restitution)).
    pub restitution: f64,
    /// Velocity damping, 1/s (see
    /// [`BodySpec::damping_per_s`](crate::BodySpec::damping_per_s)).
    pub damping_per_s: f64,
    /// Initial velocity, m/s, world frame.
    pub velocity_m_s: Vector3<f64>,
    /// Initial angular velocity, rad/s, world frame.
    pub angular_velocity_rad_s: Vector3<f64>,
}

/// One finger: a point (or rigid) grasp of a moving body.
#[derive(Debug, Clone, PartialEq)]
pub struct Finger {
    /// Unique name.
    pub name: String,
    /// The moving body held.
    pub body: BodyId,
    /// Attachment point, metres, body frame.
    pub point_m: Vector3<f64>,
    /// Point (3 rows), rigid (6 rows) or contact (a fingertip body, 3 rows).
    pub grasp: Grasp,
    /// Its constraint.
    pub constraint: ConstraintId,
    /// A contact finger's fingertip (radius, friction).
    pub tip: Option<Fingertip>,
}

/// A validated mechanism. See the [crate docs](crate) for how it is used.
#[derive(Debug, Clone)]
pub struct Model {
    pub(crate) id: u64,
    pub(crate) bodies: Vec<Body>,
    pub(crate) fingers: Vec<Finger>,
    pub(crate) layout: Layout,
    pub(crate) geometry: Vec<Geometry>,
    pub(crate) constraints: Vec<ConstraintInfo>,
    pub(crate) rows: Vec<RowInfo>,
    pub(crate) q0: Vec<f64>,
    pub(crate) gravity: Vector3<f64>,
    pub(crate) equality_rows: usize,
    pub(crate) characteristic_length: f64,
    pub(crate) contact: ContactLayout,
    pub(crate) semantic: SemanticLayout,
    /// Joints whose motor torque is reported (`report_torque`), in joint order.
    pub(crate) torque_joints: Vec<ConstraintId>,
    /// Flexible bodies (`crate::flexible`; empty: a rigid model).
    pub(crate) flexible: Vec<crate::flexible::body::FlexBody>,
    /// The deforming points `Param3::Flex` indexes.
    pub(crate) flex_anchors: Vec<crate::flexible::anchor::FlexAnchor>,
    /// Surface contacts (`crate::parametric`; `Ctx::surfaces`).
    pub(crate) surfaces: Vec<crate::parametric::SurfaceContact>,
    /// The rolling constraints (their indices; the anchor table's order).
    pub(crate) rolling: Vec<usize>,
    /// Joints whose two bodies collide with each other
    /// ([`JointSpec::collide`](crate::JointSpec::collide)).
    pub(crate) colliding_joints: Vec<ConstraintId>,
}

fn next_model_id() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

impl Model {
    /// This model's identity: every model built or derived gets a new one,
    /// and an [`Evaluation`](crate::Evaluation) serves only its own.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// All bodies, fixed ones included, in builder order.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The body called `name`.
    pub fn body_id(&self, name: &str) -> Option<BodyId> {
        self.bodies
            .iter()
            .position(|b| b.name == name)
            .map(|i| BodyId(i as u32))
    }

    /// The joints whose motor torque (or force) is reported, in joint order
    /// (`report_torque`; revolute or prismatic joints).
    pub fn torque_joints(&self) -> &[ConstraintId] {
        &self.torque_joints
    }

    /// The fingers, in builder order (also the order of the targets slice).
    pub fn fingers(&self) -> &[Finger] {
        &self.fingers
    }

    /// The finger called `name`.
    pub fn finger_id(&self, name: &str) -> Option<FingerId> {
        self.fingers
            .iter()
            .position(|f| f.name == name)
            .map(|i| FingerId(i as u32))
    }

    /// Where each body and design variable lives in q.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Number of coordinates (columns of C_q).
    pub fn n_coords(&self) -> usize {
        self.layout.len
    }

    /// Number of rows of C.
    pub fn n_rows(&self) -> usize {
        self.rows.len()
    }

    /// All constraints. Order: joints (so the k-th joint is `ConstraintId(k)`),
    /// fingers, quaternion norms (equalities), then joint limits and point–plane
    /// inequalities.
    pub fn constraints(&self) -> &[ConstraintInfo] {
        &self.constraints
    }

    /// The constraint called `name`.
    pub fn constraint_id(&self, name: &str) -> Option<ConstraintId> {
        self.constraints
            .iter()
            .position(|c| c.name == name)
            .map(|i| ConstraintId(i as u32))
    }

    /// Per-row metadata, one entry per row of C.
    pub fn rows(&self) -> &[RowInfo] {
        &self.rows
    }

    /// The equality rows (C = 0): always a prefix of C.
    pub fn equality_rows(&self) -> Range<usize> {
        0..self.equality_rows
    }

    /// The inequality rows (C ≥ 0): always a suffix of C.
    pub fn inequality_rows(&self) -> Range<usize> {
        self.equality_rows..self.rows.len()
    }

    /// The initial configuration: bodies at their given poses (unit quaternions),
    /// design variables at their given values.
    pub fn q0(&self) -> &[f64] {
        &self.q0
    }

    /// Finger targets that the initial configuration satisfies exactly: each
    /// finger's world point and its body's orientation at q0.
    pub fn initial_targets(&self) -> Vec<FingerTarget> {
        self.fingers
            .iter()
            .map(|f| {
                let b = &self.bodies[f.body.index()];
                FingerTarget {
                    position_m: b.position_m + b.orientation * f.point_m,
                    orientation: b.orientation,
                }
            })
            .collect()
    }

    /// Gravity, m/s², world frame (zero if the scene gives none).
    pub fn gravity_m_s2(&self) -> Vector3<f64> {
        self.gravity
    }

    /// True when joint `joint` lets its two bodies' shapes collide
    /// ([`JointSpec::collide`](crate::JointSpec::collide)).
    pub fn joint_collides(&self, joint: ConstraintId) -> bool {
        self.colliding_joints.contains(&joint)
    }

    /// The largest lever arm in the model (anchor or finger point distance from
    /// its body origin), metres, at least 1 mm: a rotation δθ moves a point by
    /// about this × δθ, so it converts angle rows to metres when scaling K.
    pub fn characteristic_length_m(&self) -> f64 {
        self.characteristic_length
    }

    /// World position of a body's origin at `q`, metres (fixed bodies: their
    /// pose). `None` for an unknown body or a q of the wrong length.
    pub fn body_position(&self, q: &[f64], body: BodyId) -> Option<Vector3<f64>> {
        self.body_frame(q, body).map(|f| f.r)
    }

    /// Rotation matrix (body → world) of a body at `q`: the rational R(e), exact
    /// for non-unit e. `None` for an unknown body, a wrong-length q or a
    /// degenerate quaternion.
    pub fn body_rotation(&self, q: &[f64], body: BodyId) -> Option<Matrix3<f64>> {
        self.body_frame(q, body).map(|f| f.rot)
    }

    /// World position of a finger's attachment point at `q`, metres.
    pub fn finger_point(&self, q: &[f64], finger: FingerId) -> Option<Vector3<f64>> {
        let f = self.fingers.get(finger.index())?;
        if q.len() != self.layout.len {
            return None;
        }
        let g = &self.geometry[f.constraint.index()];
        let k = match g.anchors()[0] {
            crate::constraint::block::Param3::Flex(i) => self.flex_anchors[i as usize].point(q),
            _ => f.point_m,
        };
        self.body_frame(q, f.body).map(|fr| fr.point(&k))
    }

    pub(crate) fn body_frame(&self, q: &[f64], body: BodyId) -> Option<BodyFrame> {
        let b = self.bodies.get(body.index())?;
        if q.len() != self.layout.len {
            return None;
        }
        match (
            self.layout.body_offset(body),
            self.layout.origin_offset(body),
        ) {
            (Some(o), _) => BodyFrame::new(
                Vector3::new(q[o], q[o + 1], q[o + 2]),
                [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
            ),
            (None, Some(o)) => {
                let mut f = initial_frame(b);
                f.r = Vector3::new(q[o], q[o + 1], q[o + 2]);
                Some(f)
            }
            (None, None) => Some(initial_frame(b)),
        }
    }

    /// The column groups of constraint `k`: its geometry's, plus the design
    /// columns of any end that is a fixed body with a free position (those
    /// rows move with the body's origin: ∂p/∂r = I).
    pub(crate) fn constraint_groups(&self, k: usize) -> crate::constraint::block::Groups {
        use crate::constraint::block::Slot;
        let g = &self.geometry[k];
        let mut groups = g.groups();
        if g.has_ends() {
            for (end, &f) in g.frames().iter().enumerate() {
                if let Some(c) = self.layout.origin_cols.get(f).copied().flatten() {
                    groups[Slot::origin(end) as usize] = Some((c, 3));
                }
            }
            if let crate::constraint::Geometry::OnSurface(s) = g
                && let Some(sc) = self.surfaces.get(s.index as usize)
            {
                groups[Slot::Length as usize] = Some((sc.uv_col, 2));
            }
            if !self.flex_anchors.is_empty() {
                for (end, a) in g.anchors().iter().enumerate() {
                    if let crate::constraint::block::Param3::Flex(i) = *a {
                        let a = &self.flex_anchors[i as usize];
                        groups[Slot::anchor(end) as usize] = Some((a.col, a.width()));
                    }
                }
            }
        }
        groups
    }
}

/// The frame of a body at its initial (for fixed bodies: permanent) pose.
pub(crate) fn initial_frame(b: &Body) -> BodyFrame {
    let o = b.orientation.quaternion();
    BodyFrame::new(b.position_m, [o.w, o.i, o.j, o.k]).unwrap_or(BodyFrame::IDENTITY)
}
