//! [`ModelBuilder`]: collects specs, validates them and compiles a [`Model`].

use std::collections::HashMap;

use nalgebra::Vector3;

use super::compiler::{Compiler, compile_finger};
use super::error::{BuildError, Owner};
use super::joints::compile_joint;
use super::layout::{DesignOwner, Layout};
use super::spec::{BodySpec, DesignParam, FingerSpec, JointSpec};
use super::{Body, Model, initial_frame, next_model_id};
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry};
use crate::rotation::BodyFrame;
use crate::{BodyId, ConstraintId, FingerId};

use super::assembler::{Assembler, initial_q, push_norms, push_tail_rows};
use super::body::{body, tip_body};

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
