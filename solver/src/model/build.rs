//! [`ModelBuilder`]: collects specs, validates them and compiles a [`Model`].

use std::collections::HashMap;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::compiler::{Compiler, check_bounds, compile_finger};
use super::error::{BuildError, Owner};
use super::joints::compile_joint;
use super::layout::{DesignOwner, DesignVar, Layout};
use super::spec::{
    BodySpec, DEFAULT_DENSITY_KG_M3, DEFAULT_INERTIA_RADIUS_M, DEFAULT_MASS_KG, DesignParam,
    FINGERTIP_MASS_KG, FingerSpec, Fingertip, JointSpec, MAX_FINGERTIP_RADIUS_M, MAX_FRICTION,
    Shape,
};
use super::{Body, Model, initial_frame, next_model_id};
use crate::constraint::bound::DesignBound;
use crate::constraint::quat_norm::QuatNorm;
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry, RowInfo};
use crate::geometry::HullSimplification;
use crate::geometry::simplify::{MAX_HULL_VERTICES, simplify_hull};
use crate::rotation::BodyFrame;
use crate::{BodyId, ConstraintId, FingerId};

/// Collects bodies, joints, fingers and gravity, then [`build`](Self::build)s a
/// validated [`Model`]. Mirrors the scene format: one call per `[[body]]`,
/// `[[joint]]`, `[[finger]]`; nothing is checked until `build`.
#[derive(Debug, Clone, Default)]
pub struct ModelBuilder {
    bodies: Vec<BodySpec>,
    joints: Vec<JointSpec>,
    gears: Vec<super::gears::GearSpec>,
    fingers: Vec<FingerSpec>,
    gravity: [f64; 3],
}

impl ModelBuilder {
    /// An empty builder (zero gravity).
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets gravity, m/s², world frame (`scene.gravity`).
    pub fn gravity(&mut self, gravity_m_s2: [f64; 3]) -> &mut Self {
        self.gravity = gravity_m_s2;
        self
    }

    /// Adds a body; its id is its insertion index.
    pub fn body(&mut self, spec: BodySpec) -> BodyId {
        self.bodies.push(spec);
        BodyId(self.bodies.len() as u32 - 1)
    }

    /// Adds a joint; the k-th joint becomes `ConstraintId(k)` in the model.
    pub fn joint(&mut self, spec: JointSpec) -> ConstraintId {
        self.joints.push(spec);
        ConstraintId(self.joints.len() as u32 - 1)
    }

    /// Adds a gear coupling between two joints (`[[gear]]`); gears become
    /// constraints after the joints, in insertion order.
    pub fn gear(&mut self, spec: super::gears::GearSpec) -> &mut Self {
        self.gears.push(spec);
        self
    }

    /// The gears added so far, in order.
    pub fn gear_specs(&self) -> &[super::gears::GearSpec] {
        &self.gears
    }

    /// Adds a finger; its id is its insertion index.
    pub fn finger(&mut self, spec: FingerSpec) -> FingerId {
        self.fingers.push(spec);
        FingerId(self.fingers.len() as u32 - 1)
    }

    /// The bodies added so far, in order.
    pub fn body_specs(&self) -> &[BodySpec] {
        &self.bodies
    }

    /// The joints added so far, in order.
    pub fn joint_specs(&self) -> &[JointSpec] {
        &self.joints
    }

    /// The fingers added so far, in order.
    pub fn finger_specs(&self) -> &[FingerSpec] {
        &self.fingers
    }

    /// Gravity, m/s², world frame.
    pub fn gravity_m_s2(&self) -> [f64; 3] {
        self.gravity
    }

    /// Validates everything and compiles the model. The error names the first
    /// offending body, joint or finger (in that order) and what is wrong.
    pub fn build(&self) -> Result<Model, BuildError> {
        self.build_with(true)
    }

    /// The same model without the finger constraints: the
    /// same bodies (contact fingers' fingertips included), the same layout of
    /// q, joint, quaternion-norm and design-bound rows only (for
    /// re-projection, which must not hold a finger where the mechanism cannot
    /// reach).
    pub fn build_joints_only(&self) -> Result<Model, BuildError> {
        self.build_with(false)
    }

    fn build_with(&self, with_fingers: bool) -> Result<Model, BuildError> {
        if !self.gravity.iter().all(|v| v.is_finite()) {
            return Err(BuildError::NonFinite {
                owner: Owner::Scene,
                field: "gravity",
            });
        }
        let bodies = self.compile_bodies()?;
        let mut by_name = HashMap::new();
        for (i, b) in bodies.iter().enumerate() {
            if by_name.insert(b.name.as_str(), BodyId(i as u32)).is_some() {
                return Err(BuildError::DuplicateName {
                    owner: Owner::Body(b.name.clone()),
                });
            }
        }
        let mut body_cols = Vec::with_capacity(bodies.len());
        let mut col = 0;
        for b in &bodies {
            body_cols.push((!b.fixed).then_some(col));
            col += if b.fixed { 0 } else { 7 };
        }
        let mut frames: Vec<BodyFrame> = bodies.iter().map(initial_frame).collect();
        frames.push(BodyFrame::IDENTITY);
        let mut cx = Compiler::new(&bodies, &by_name, &frames, &body_cols, col);
        let origin_cols = self.design_columns(&bodies, &mut cx);

        let mut out = Assembler::default();
        let joints = self.compile_joints(&mut cx, &mut out)?;
        self.compile_gears(&cx, &origin_cols, &mut out)?;
        let fingers = if with_fingers {
            self.compile_fingers(&mut cx, &mut out)?
        } else {
            Vec::new()
        };
        let fin = cx.finish()?;
        push_norms(&bodies, &body_cols, &mut out);
        let (rolling, equality_rows) =
            push_tail_rows(joints.rolls, joints.limits, &fin.design_vars, &mut out);
        let q0 = initial_q(&bodies, &fin.q0_tail, fin.len);
        Ok(Model {
            id: next_model_id(),
            bodies,
            fingers,
            layout: Layout {
                body_cols,
                origin_cols,
                design_vars: fin.design_vars,
                body_coords: col,
                aux: fin.aux,
                len: fin.len,
            },
            geometry: out.geometry,
            constraints: out.infos,
            rows: out.rows,
            q0,
            gravity: Vector3::from(self.gravity),
            equality_rows,
            characteristic_length: fin.lever,
            contact: super::ContactLayout::default(),
            semantic: super::SemanticLayout::default(),
            torque_joints: joints.torque,
            flexible: fin.flex_bodies,
            flex_anchors: fin.anchors,
            surfaces: fin.surfaces,
            rolling,
            colliding_joints: (self.joints.iter().enumerate())
                .filter(|(_, j)| j.collide)
                .map(|(k, _)| ConstraintId(k as u32))
                .collect(),
        })
    }

    /// The scene's bodies, then one body per finger with a tip (marked as
    /// fingertips).
    fn compile_bodies(&self) -> Result<Vec<Body>, BuildError> {
        let tips = self
            .fingers
            .iter()
            .filter_map(|f| f.tip.map(|t| tip_body(f, &t)))
            .collect::<Result<Vec<_>, _>>()?;
        let mut bodies = self
            .bodies
            .iter()
            .chain(&tips)
            .enumerate()
            .map(|(i, s)| body(i, s))
            .collect::<Result<Vec<_>, _>>()?;
        for b in &mut bodies[self.bodies.len()..] {
            b.fingertip = true;
        }
        Ok(bodies)
    }

    /// Registers flexible bodies and the free positions of fixed bodies (the
    /// first design columns); returns each body's origin column.
    fn design_columns(&self, bodies: &[Body], cx: &mut Compiler) -> Vec<Option<usize>> {
        for (i, s) in self.bodies.iter().enumerate() {
            if let Some(beam) = s.flexible {
                let id = BodyId(i as u32);
                let beam = crate::flexible::beam::Beam::new(beam, bodies[i].mass_kg);
                cx.flexible(id, crate::flexible::body::FlexBody::new(id, beam));
            }
        }
        let mut origin_cols = vec![None; bodies.len()];
        for (i, s) in self.bodies.iter().enumerate() {
            if s.free.contains(&DesignParam::Position) {
                let owner = DesignOwner::Body(BodyId(i as u32));
                let bounds = s.bounds.as_ref();
                origin_cols[i] =
                    Some(cx.free(owner, &s.name, DesignParam::Position, &s.position_m, bounds));
            }
        }
        origin_cols
    }

    /// The joints' rows, in scene order; their limits and rolling rows come
    /// back to be appended after the equalities.
    fn compile_joints(
        &self,
        cx: &mut Compiler,
        out: &mut Assembler,
    ) -> Result<CompiledJoints, BuildError> {
        let mut joints = CompiledJoints::default();
        let mut joint_names = HashMap::new();
        for (k, spec) in self.joints.iter().enumerate() {
            let (info, geometry, limit, roll) = compile_joint(k, spec, cx)?;
            joints.rolls.extend(roll);
            if spec.name.is_some() && joint_names.insert(info.name.clone(), ()).is_some() {
                return Err(BuildError::DuplicateName {
                    owner: Owner::Joint(info.name),
                });
            }
            joints
                .limits
                .extend(limit.map(|(info, g)| (info, g, ConstraintId(k as u32))));
            if spec.report_torque {
                if !matches!(
                    info.kind,
                    ConstraintKind::Revolute | ConstraintKind::Prismatic
                ) {
                    return Err(BuildError::TorqueJointKind {
                        owner: Owner::Joint(info.name),
                        kind: spec.kind,
                    });
                }
                joints.torque.push(ConstraintId(k as u32));
            }
            out.push(info, geometry);
        }
        Ok(joints)
    }

    /// The gears' rows, after the joints they couple.
    fn compile_gears(
        &self,
        cx: &Compiler,
        origin_cols: &[Option<usize>],
        out: &mut Assembler,
    ) -> Result<(), BuildError> {
        let n_joints = self.joints.len();
        for spec in &self.gears {
            let (info, geometry) =
                super::gears::compile_gear(spec, out, n_joints, cx, origin_cols)?;
            if out.infos[..n_joints].iter().any(|j| j.name == info.name)
                || out.infos[n_joints..].iter().any(|g| g.name == info.name)
            {
                return Err(BuildError::DuplicateName {
                    owner: Owner::Gear(info.name),
                });
            }
            out.push(info, geometry);
        }
        Ok(())
    }

    /// The fingers' rows.
    fn compile_fingers(
        &self,
        cx: &mut Compiler,
        out: &mut Assembler,
    ) -> Result<Vec<super::Finger>, BuildError> {
        let mut fingers = Vec::with_capacity(self.fingers.len());
        for (k, spec) in self.fingers.iter().enumerate() {
            if fingers.iter().any(|f: &super::Finger| f.name == spec.name) {
                return Err(BuildError::DuplicateName {
                    owner: Owner::Finger(spec.name.clone()),
                });
            }
            let constraint = ConstraintId(out.infos.len() as u32);
            let (finger, info, geometry) = compile_finger(k, spec, constraint, cx)?;
            fingers.push(finger);
            out.push(info, geometry);
        }
        Ok(fingers)
    }
}

/// What compiling the joints leaves for later: limit rows (with their
/// joint), rolling rows, the joints whose torque is reported.
#[derive(Default)]
struct CompiledJoints {
    limits: Vec<(ConstraintInfo, Geometry, ConstraintId)>,
    rolls: Vec<(ConstraintInfo, Geometry)>,
    torque: Vec<ConstraintId>,
}

/// One quaternion-norm row per free body.
fn push_norms(bodies: &[Body], body_cols: &[Option<usize>], out: &mut Assembler) {
    for (i, b) in bodies.iter().enumerate() {
        if let Some(col) = body_cols[i] {
            let info = ConstraintInfo {
                name: format!("{}.norm", b.name),
                kind: ConstraintKind::QuaternionNorm,
                rows: 0..0,
                bodies: [Some(BodyId(i as u32)), None],
                finger: None,
                limits: None,
            };
            out.push(info, Geometry::QuatNorm(QuatNorm { col }));
        }
    }
}

/// Rolling joints' no-slip rows and pinned design components (equalities),
/// then the joint limits and the design bounds (inequalities). Returns the
/// rolling constraints' indices and the number of equality rows.
fn push_tail_rows(
    rolls: Vec<(ConstraintInfo, Geometry)>,
    limits: Vec<(ConstraintInfo, Geometry, ConstraintId)>,
    design_vars: &[DesignVar],
    out: &mut Assembler,
) -> (Vec<usize>, usize) {
    let mut rolling = Vec::with_capacity(rolls.len());
    for (slot, (info, mut g)) in rolls.into_iter().enumerate() {
        if let Geometry::Rolling(r) = &mut g {
            r.slot = slot as u32;
        }
        rolling.push(out.infos.len());
        out.push(info, g);
    }
    let bounds = design_bounds(design_vars);
    for (info, g) in bounds.iter().filter(|(_, g)| g.lo == g.hi) {
        out.push(info.clone(), Geometry::Bound(*g));
    }
    let equality_rows = out.rows.len();
    for (mut info, geometry, joint) in limits {
        info.limits = Some(joint);
        out.push(info, geometry);
    }
    for (info, g) in bounds.iter().filter(|(_, g)| g.lo != g.hi) {
        out.push(info.clone(), Geometry::Bound(*g));
    }
    (rolling, equality_rows)
}

/// q at the scene's poses: each free body's position and quaternion, then
/// the design and auxiliary tail (undeformed flexible bodies at 0).
fn initial_q(bodies: &[Body], tail: &[f64], len: usize) -> Vec<f64> {
    let mut q0 = Vec::with_capacity(len);
    for b in bodies.iter().filter(|b| !b.fixed) {
        let o = b.orientation.quaternion();
        q0.extend_from_slice(b.position_m.as_slice());
        q0.extend_from_slice(&[o.w, o.i, o.j, o.k]);
    }
    q0.extend_from_slice(tail);
    q0.resize(len, 0.0);
    q0
}

/// Appends constraints, assigning their row ranges and row metadata.
#[derive(Default)]
pub(super) struct Assembler {
    pub infos: Vec<ConstraintInfo>,
    pub geometry: Vec<Geometry>,
    pub rows: Vec<RowInfo>,
}

impl Assembler {
    pub fn push(&mut self, mut info: ConstraintInfo, geometry: Geometry) {
        let id = ConstraintId(self.infos.len() as u32);
        let n = geometry.rows();
        let start = self.rows.len();
        info.rows = start..start + n;
        self.rows.extend((0..n).map(|r| RowInfo {
            constraint: id,
            sense: info.kind.sense(),
            unit: info.kind.row_unit(r),
        }));
        self.infos.push(info);
        self.geometry.push(geometry);
    }
}

/// One bound constraint per bounded design-variable component: its info
/// (named `"<component>.bounds"`, the owner's bodies) and geometry.
fn design_bounds(vars: &[DesignVar]) -> Vec<(ConstraintInfo, DesignBound)> {
    let mut out = Vec::new();
    for d in vars {
        let Some(b) = d.bounds else { continue };
        let bodies = match d.owner {
            DesignOwner::Body(id) => [Some(id), None],
            DesignOwner::Joint(_) => [None, None],
        };
        for (k, &[lo, hi]) in b.iter().take(d.width).enumerate() {
            let kind = if lo == hi {
                ConstraintKind::DesignPin
            } else {
                ConstraintKind::DesignBound
            };
            let info = ConstraintInfo {
                name: format!("{}.bounds", d.component_name(k)),
                kind,
                rows: 0..0,
                bodies,
                finger: None,
                limits: None,
            };
            out.push((
                info,
                DesignBound {
                    col: d.offset + k,
                    lo,
                    hi,
                },
            ));
        }
    }
    out
}

/// The fingertip body of a contact finger: a ball of the finger's radius and
/// [`FINGERTIP_MASS_KG`] at its start position.
fn tip_body(f: &FingerSpec, t: &Fingertip) -> Result<BodySpec, BuildError> {
    let owner = || Owner::Finger(f.name.clone());
    if !(t.radius_m.is_finite() && t.radius_m > 0.0 && t.radius_m <= MAX_FINGERTIP_RADIUS_M) {
        return Err(BuildError::BadFingertip {
            owner: owner(),
            field: "radius",
            value: t.radius_m,
            why: "finite, > 0 and at most 1 m (a larger ball is a body with a `shape`)",
        });
    }
    if !(t.friction.is_finite() && (0.0..=MAX_FRICTION).contains(&t.friction)) {
        return Err(BuildError::BadFingertip {
            owner: owner(),
            field: "friction",
            value: t.friction,
            why: "finite and in [0, 10]",
        });
    }
    if !t.position_m.iter().all(|x| x.is_finite()) {
        return Err(BuildError::NonFinite {
            owner: owner(),
            field: "position",
        });
    }
    super::compiler::in_range(&owner(), "position", &t.position_m)?;
    let i = 0.4 * FINGERTIP_MASS_KG * t.radius_m * t.radius_m;
    Ok(BodySpec::new(f.body.clone())
        .at(t.position_m)
        .mass(FINGERTIP_MASS_KG)
        .inertia([i; 3])
        .shape(Shape::Sphere {
            radius_m: t.radius_m,
        }))
}

/// Mass and inertia of a body: as given; else from its shape at its density
/// (inertia scaled to a given mass); else the defaults.
fn mass_and_inertia(
    s: &BodySpec,
    shape: Option<&Shape>,
    com_slack_m: f64,
    owner: &dyn Fn() -> Owner,
) -> Result<(f64, [f64; 3]), BuildError> {
    let from_shape = match shape {
        Some(shape) => {
            let density = s.density_kg_m3.unwrap_or(DEFAULT_DENSITY_KG_M3);
            if !(density.is_finite() && density > 0.0) {
                return Err(BuildError::Shape {
                    owner: owner(),
                    field: "density",
                    error: crate::geometry::ShapeError::Size {
                        field: "density",
                        value: density,
                    },
                });
            }
            if s.mass_kg.is_some() && s.inertia_kg_m2.is_some() {
                // Checked for sizes only: mass and inertia are given.
                shape.collider().map_err(|error| BuildError::Shape {
                    owner: owner(),
                    field: "shape",
                    error,
                })?;
                None
            } else {
                // Of the kept hull (its centre of mass may lie up to the
                // distance it was cut by from the given shape's).
                Some(
                    shape
                        .mass_properties_within(density, com_slack_m)
                        .map_err(|error| BuildError::Shape {
                            owner: owner(),
                            field: "shape",
                            error,
                        })?,
                )
            }
        }
        None => None,
    };
    let mass_kg = s
        .mass_kg
        .or(from_shape.map(|m| m.mass_kg))
        .unwrap_or(DEFAULT_MASS_KG);
    let inertia = match (s.inertia_kg_m2, from_shape) {
        (Some(i), _) => i,
        (None, Some(m)) => m.inertia_kg_m2.map(|x| x * mass_kg / m.mass_kg),
        (None, None) => [0.4 * mass_kg * DEFAULT_INERTIA_RADIUS_M * DEFAULT_INERTIA_RADIUS_M; 3],
    };
    Ok((mass_kg, inertia))
}

/// The body of spec `s` (the `i`-th), every key checked.
fn body(i: usize, s: &BodySpec) -> Result<Body, BuildError> {
    if s.name.is_empty() {
        return Err(BuildError::EmptyName {
            owner: Owner::Body(format!("#{}", i + 1)),
        });
    }
    let owner = || Owner::Body(s.name.clone());
    let finite = |field, v: &[f64]| finite(&owner, field, v);
    finite("position", &s.position_m)?;
    super::compiler::in_range(&owner(), "position", &s.position_m)?;
    finite("orientation", &s.orientation_wxyz)?;
    if let Some(m) = s.mass_kg {
        finite("mass", &[m])?;
    }
    let (shape, hull) = kept_hull(s, &owner)?;
    let slack = hull.map_or(0.0, |h| h.error_m);
    let (mass_kg, inertia) = mass_and_inertia(s, shape.as_ref(), slack, &owner)?;
    check_mass(s, mass_kg, inertia, &owner)?;
    if !(s.friction.is_finite() && (0.0..=MAX_FRICTION).contains(&s.friction)) {
        return Err(BuildError::BadFriction {
            owner: owner(),
            value: s.friction,
        });
    }
    motion(s, &owner)?;
    check_free(s, &owner)?;
    check_flexible(s, &owner)?;
    let freed: Vec<(DesignParam, &[f64])> =
        s.free.iter().map(|&p| (p, &s.position_m[..])).collect();
    check_bounds(&owner(), &s.name, s.bounds.as_ref(), &freed)?;
    let [w, x, y, z] = s.orientation_wxyz;
    let q = Quaternion::new(w, x, y, z);
    let n2 = q.norm_squared();
    if n2 <= 0.0 || !n2.is_finite() {
        return Err(BuildError::ZeroOrientation { owner: owner() });
    }
    Ok(Body {
        name: s.name.clone(),
        fixed: s.fixed,
        position_m: Vector3::from(s.position_m),
        orientation: UnitQuaternion::from_quaternion(q),
        mass_kg,
        inertia_kg_m2: Vector3::from(inertia),
        shape,
        fingertip: false,
        friction: s.friction,
        hull,
        restitution: s.restitution,
        damping_per_s: s.damping_per_s,
        velocity_m_s: Vector3::from(s.velocity_m_s),
        angular_velocity_rad_s: Vector3::from(s.angular_velocity_rad_s),
    })
}

/// Fails with `NonFinite` naming `field` unless every value of `v` is
/// finite.
fn finite(owner: &dyn Fn() -> Owner, field: &'static str, v: &[f64]) -> Result<(), BuildError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(BuildError::NonFinite {
            owner: owner(),
            field,
        })
    }
}

/// The body's shape with a hull past the vertex budget cut, and what the
/// cut cost (when it cost anything). The cut comes before anything uses
/// the hull (mass properties included): every later collider is built
/// from the kept vertices.
fn kept_hull(
    s: &BodySpec,
    owner: &dyn Fn() -> Owner,
) -> Result<(Option<Shape>, Option<HullSimplification>), BuildError> {
    Ok(match &s.shape {
        Some(Shape::Convex { points_m }) => {
            match simplify_hull(points_m, MAX_HULL_VERTICES).map_err(|e| BuildError::Shape {
                owner: owner(),
                field: "shape",
                error: e.into(),
            })? {
                Some(cut) => (
                    Some(Shape::Convex {
                        points_m: cut.points_m.clone(),
                    }),
                    (cut.error_m > 0.0).then(|| cut.summary()),
                ),
                None => (s.shape.clone(), None),
            }
        }
        other => (other.clone(), None),
    })
}

/// A positive finite mass, and principal moments that are finite, at
/// least 0, above 0 on a moving body (a zero one leaves a rotation without
/// inertia and M singular: the force solve's factorisation then fails),
/// and satisfy the triangle inequalities.
fn check_mass(
    s: &BodySpec,
    mass_kg: f64,
    inertia: [f64; 3],
    owner: &dyn Fn() -> Owner,
) -> Result<(), BuildError> {
    finite(owner, "mass", &[mass_kg])?;
    if mass_kg <= 0.0 {
        return Err(BuildError::NonPositiveMass {
            owner: owner(),
            mass_kg,
        });
    }
    finite(owner, "inertia", &inertia)?;
    let [a, b, c] = inertia;
    let slack = 1e-9 * (a + b + c);
    if inertia.iter().any(|&x| x < 0.0)
        || (!s.fixed && inertia.iter().any(|&x| x <= 0.0))
        || a > b + c + slack
        || b > a + c + slack
        || c > a + b + slack
    {
        return Err(BuildError::BadInertia {
            owner: owner(),
            inertia_kg_m2: inertia,
        });
    }
    Ok(())
}

/// A body's design parameters: its position only, on a fixed body, each
/// once.
fn check_free(s: &BodySpec, owner: &dyn Fn() -> Owner) -> Result<(), BuildError> {
    for (k, &param) in s.free.iter().enumerate() {
        if param != DesignParam::Position || !s.fixed {
            return Err(BuildError::UnsupportedBodyFree {
                owner: owner(),
                param,
            });
        }
        if s.free[..k].contains(&param) {
            return Err(BuildError::DuplicateFree {
                owner: owner(),
                param,
            });
        }
    }
    Ok(())
}

/// A flexible body moves, has no shape, and its beam's keys are valid.
fn check_flexible(s: &BodySpec, owner: &dyn Fn() -> Owner) -> Result<(), BuildError> {
    if let Some(beam) = &s.flexible {
        let why = if s.fixed {
            Some("a flexible body must move (weld it to a fixed body at its clamp)".into())
        } else if s.shape.is_some() {
            Some("a flexible body takes part in no contact: its shape would not bend".into())
        } else {
            beam.check()
                .err()
                .map(|(field, why)| format!("flexible `{field}` {why}"))
        };
        if let Some(why) = why {
            return Err(BuildError::Flexible {
                owner: owner(),
                why,
            });
        }
    }
    Ok(())
}

/// Largest initial speed a body may be given, m/s (a bullet is 1 km/s).
pub const MAX_SPEED_M_S: f64 = 1e3;

/// Largest initial angular speed a body may be given, rad/s.
pub const MAX_SPIN_RAD_S: f64 = 1e4;

/// Largest velocity damping, 1/s (a body then stops within a microsecond).
pub const MAX_DAMPING_PER_S: f64 = 1e6;

/// The inertial-motion keys of a body: restitution, damping, initial
/// velocities.
fn motion(s: &BodySpec, owner: &dyn Fn() -> Owner) -> Result<(), BuildError> {
    let bad = |field, value, why| {
        Err(BuildError::BadMotion {
            owner: owner(),
            field,
            value,
            why,
        })
    };
    if !(s.restitution.is_finite() && (0.0..=1.0).contains(&s.restitution)) {
        return bad("restitution", s.restitution, "in [0, 1]");
    }
    if !(s.damping_per_s.is_finite() && (0.0..=MAX_DAMPING_PER_S).contains(&s.damping_per_s)) {
        return bad("damping", s.damping_per_s, "finite, ≥ 0 and at most 1e6 /s");
    }
    for (field, v, max, why) in [
        (
            "velocity",
            s.velocity_m_s,
            MAX_SPEED_M_S,
            "a speed of at most 1000 m/s",
        ),
        (
            "angular_velocity",
            s.angular_velocity_rad_s,
            MAX_SPIN_RAD_S,
            "an angular speed of at most 1e4 rad/s",
        ),
    ] {
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm <= max) {
            return bad(field, norm, why);
        }
        if s.fixed && norm > 0.0 {
            return bad(field, norm, "zero on a fixed body");
        }
    }
    Ok(())
}
