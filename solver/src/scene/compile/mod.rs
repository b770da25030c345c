//! Compiling a validated scene into what a session needs — and only that: a
//! [`Model`](crate::Model) (no coordinates for fixed bodies, design variables only where
//! marked free), one [`DeviceDecl`] per `[[device]]`, the finger wiring, the
//! solver settings the file set, and the semantic layer (areas, label
//! order, `[semantic]`, checked consistent; `compile_semantic.rs`).
//!
//! Builder errors come back as [`SceneError`]s pointing at the offending field.
//!
//! One kind per file: what a compiled scene is (`decl.rs`), the file's
//! sections as the builder's specs (`convert.rs`), the simulated hand
//! (`hand.rs`), the initial configuration against the joints' limits
//! (`initial_limits.rs`), builder errors mapped to spans (`spans.rs`).

mod convert;
mod decl;
mod hand;
mod initial_limits;
mod spans;

pub(super) use convert::shape;
pub use decl::{CompiledScene, DeviceDecl, FingerDecl, HandDecl, HandPath, SceneSettings};

use crate::ModelBuilder;
use crate::model::{DEFAULT_FINGERTIP_RADIUS_M, FingerSpec, JointSpec};
use crate::objective::ObjectiveSpec;
use crate::scene::LoadedScene;
use crate::scene::SceneError;
use crate::scene::spec::GraspSpec;
use convert::{body_spec, joint_spec, normalised, objective_spec, settings};

impl LoadedScene {
    /// The `[[joint]]` tables as the model builder takes them, in file order
    /// (axes as written, not normalised), e.g. to write the mechanism in
    /// another program's format.
    pub fn joint_specs(&self) -> Vec<JointSpec> {
        self.spec.joints.iter().map(joint_spec).collect()
    }

    /// The scene's bodies, joints and fingers as a
    /// [`ModelBuilder`], not built yet (`compile` builds it and maps its
    /// errors to spans; `haptloop place` builds a goal model from it).
    pub fn builder(&self) -> ModelBuilder {
        let s = &self.spec;
        let mut builder = ModelBuilder::new();
        if let Some(g) = &s.scene.gravity {
            builder.gravity(g.get_ref().get());
        }
        for b in &s.bodies {
            builder.body(body_spec(b));
        }
        for j in &s.joints {
            builder.joint(joint_spec(j));
        }
        for g in &s.gears {
            builder.gear(crate::scene::gear::gear_spec(g));
        }
        for f in &s.fingers {
            let point = f.point.as_ref().map_or([0.0; 3], |p| p.get_ref().get());
            let body = || {
                f.body
                    .as_ref()
                    .map_or(String::new(), |b| b.get_ref().clone())
            };
            let spec = match f.grasp.as_ref().map_or(GraspSpec::Point, |g| *g.get_ref()) {
                GraspSpec::Point => FingerSpec::point(f.name.get_ref().clone(), body(), point),
                GraspSpec::Rigid => FingerSpec::rigid(f.name.get_ref().clone(), body(), point),
                GraspSpec::Contact => FingerSpec::contact(
                    f.name.get_ref().clone(),
                    f.position.as_ref().map_or([0.0; 3], |p| p.get_ref().get()),
                    f.radius
                        .as_ref()
                        .map_or(DEFAULT_FINGERTIP_RADIUS_M, |r| *r.get_ref()),
                    f.friction.as_ref().map_or(0.0, |m| *m.get_ref()),
                ),
            };
            builder.finger(spec);
        }
        builder
    }

    /// The `[[objective]]` tables as [`Objectives::compile`](crate::Objectives::compile)
    /// takes them, in file order.
    pub fn objective_specs(&self) -> Vec<ObjectiveSpec> {
        self.spec.objectives.iter().map(objective_spec).collect()
    }

    /// Builds the model and wires devices to fingers. Every error names the
    /// file, line and column of the offending value.
    pub fn compile(&self) -> Result<CompiledScene, SceneError> {
        let s = &self.spec;
        let builder = self.builder();
        // The same mechanism without finger rows: same bodies (fingertips
        // included), same layout of q, joint rows only (for re-projection
        // onto the nearest assembled configuration, which must not hold a
        // finger where the mechanism cannot reach).
        let joints_only = builder
            .build_joints_only()
            .map_err(|e| self.build_error(&e))?;
        let model = builder.build().map_err(|e| self.build_error(&e))?;
        let objectives = crate::Objectives::compile(&self.objective_specs(), &model)
            .map_err(|e| self.build_error(&e))?;
        self.check_limits_at_q0(&model)?;
        let mut contact = crate::geometry::ContactSettings::default();
        if let Some(d) = &s.solver.contact_distance {
            contact.contact_distance_m = *d.get_ref();
        }
        self.check_crowding(&model, &contact)?;
        let penetration = s
            .solver
            .penetration_tolerance
            .as_ref()
            .map_or(contact.penetration_tolerance_m, |x| *x.get_ref());
        let areas = s
            .bodies
            .iter()
            .any(|b| !b.offer.is_empty() || !b.binding.is_empty());
        let (schedule, absent) = self.compile_schedule(&model, areas)?;
        let semantic = self.compile_semantic(&model, penetration, &absent)?;
        let holds = self.compile_holds(&model);
        let design_flags = self.compile_design_flags(&model)?;

        let devices = s
            .devices
            .iter()
            .map(|d| DeviceDecl {
                name: d.name.get_ref().clone(),
                model: d.model.get_ref().clone(),
                model_span: d.model.span(),
                scale: d.scale.as_ref().map_or(1.0, |x| *x.get_ref()),
                orientation_wxyz: d
                    .orientation
                    .as_ref()
                    .map_or([1.0, 0.0, 0.0, 0.0], |q| normalised(*q.get_ref()).get()),
                hand: self.hand(d.hand.as_ref()),
            })
            .collect();
        let fingers = s
            .fingers
            .iter()
            .map(|f| FingerDecl {
                name: f.name.get_ref().clone(),
                device: s
                    .devices
                    .iter()
                    .position(|d| d.name.get_ref() == f.device.get_ref())
                    .expect("validated: every finger names a known device"),
                finger: model
                    .finger_id(f.name.get_ref())
                    .expect("built from these fingers"),
            })
            .collect();
        Ok(CompiledScene {
            objectives: std::sync::Arc::new(objectives),
            name: s.scene.name.get_ref().clone(),
            description: s.scene.description.clone().unwrap_or_default(),
            model,
            joints_only,
            settings: settings(&s.solver),
            devices,
            fingers,
            shaped_bodies: s.bodies.iter().filter(|b| b.shape.is_some()).count(),
            semantic_areas: s
                .bodies
                .iter()
                .map(|b| b.offer.len() + b.binding.len())
                .sum(),
            semantic,
            holds,
            design_flags,
            schedule,
            absent,
        })
    }
}
