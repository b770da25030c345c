//! Compiling a validated scene into what a session needs — and only that: a
//! [`Model`] (no coordinates for fixed bodies, design variables only where
//! marked free), one [`DeviceDecl`] per `[[device]]`, the finger wiring, the
//! solver settings the file set, and the semantic layer (areas, label
//! order, `[semantic]`, checked consistent; `compile_semantic.rs`).
//!
//! Builder errors come back as [`SceneError`]s pointing at the offending field.

use super::LoadedScene;
use super::SceneError;
use super::compile_semantic::HoldDecl;
use super::decl::{DeviceDecl, FingerDecl, HandDecl, HandPath};
use super::model_specs::{body_spec, joint_spec, normalised, objective_spec};
use super::spec::{GraspSpec, SolverSection};
use crate::model::{DEFAULT_FINGERTIP_RADIUS_M, FingerSpec, JointSpec};
use crate::objective::ObjectiveSpec;
use crate::{Model, ModelBuilder, RowUnit, Sense};
use std::path::PathBuf;
use toml::Spanned;

/// The `[solver]` values the file set (unset keys are `None`; the session
/// fills them from command-line flags or the solver's defaults).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SceneSettings {
    /// Fast-loop rate, Hz.
    pub rate_hz: Option<u32>,
    /// AL iterations per tick.
    pub iterations: Option<u32>,
    /// h.
    pub step: Option<f64>,
    /// K.
    pub gain: Option<f64>,
    /// k₂.
    pub multiplier_gain: Option<f64>,
    /// Newton-KKT stopping tolerance.
    pub placement_tolerance: Option<f64>,
    /// μ.
    pub damping: Option<f64>,
    /// Witness activation distance, m.
    pub contact_distance: Option<f64>,
    /// Witness removal distance, m.
    pub release_distance: Option<f64>,
    /// Violation the scene promises to stay under, m.
    pub violation_tolerance: Option<f64>,
    /// Virtual-coupling stiffness, N/m.
    pub coupling_stiffness: Option<f64>,
    /// Virtual-coupling damping, N·s/m.
    pub coupling_damping: Option<f64>,
    /// Velocity low-pass time constant, s.
    pub velocity_filter: Option<f64>,
    /// Inertial motion (`dynamics`).
    pub dynamics: Option<bool>,
    /// Contact penetration beyond which the slow loop backs up, m.
    pub penetration_tolerance: Option<f64>,
    /// Pre-emptive witness guards (`contact_guards`).
    pub contact_guards: Option<bool>,
}

/// A scene compiled to what it needs.
#[derive(Debug, Clone)]
pub struct CompiledScene {
    /// `[scene] name`.
    pub name: String,
    /// `[scene] description`.
    pub description: String,
    /// The mechanism.
    pub model: Model,
    /// Its design objectives and the built-in weights (`[[objective]]`),
    /// for [`Program::with_objectives`](crate::Program::with_objectives).
    pub objectives: std::sync::Arc<crate::Objectives>,
    /// The mechanism without its fingers: the same q layout, joint and
    /// quaternion-norm rows only.
    pub joints_only: Model,
    /// `[solver]` values the file set.
    pub settings: SceneSettings,
    /// One per `[[device]]`, in file order.
    pub devices: Vec<DeviceDecl>,
    /// One per `[[finger]]`, in file order (the model's finger order).
    pub fingers: Vec<FingerDecl>,
    /// Bodies with a collision shape (contact machinery is compiled only for these).
    pub shaped_bodies: usize,
    /// Semantic offer + binding areas declared.
    pub semantic_areas: usize,
    /// The semantic layer: areas, label order, `[semantic]` settings
    /// (`None` without areas; checked consistent at q0).
    pub semantic: Option<crate::semantic::SemanticSpec>,
    /// The contact fingers' scheduled holds.
    pub holds: Vec<HoldDecl>,
    /// Design variables switched on and off during the run, by time
    /// (`[[design_flag]]`, plus any `--design-on` / `--design-off`).
    pub design_flags: Vec<super::DesignFlagDecl>,
    /// Objects added and removed, modes switched, by time (`[[schedule]]`).
    pub schedule: Vec<super::ScheduleDecl>,
    /// Bodies absent at the start (their first schedule entry adds them).
    pub absent: Vec<crate::BodyId>,
}

fn settings(s: &SolverSection) -> SceneSettings {
    let f = |v: &Option<Spanned<f64>>| v.as_ref().map(|x| *x.get_ref());
    SceneSettings {
        rate_hz: s.rate_hz.as_ref().map(|x| *x.get_ref()),
        iterations: s.iterations.as_ref().map(|x| *x.get_ref()),
        step: f(&s.step),
        gain: f(&s.gain),
        multiplier_gain: f(&s.multiplier_gain),
        placement_tolerance: f(&s.placement_tolerance),
        damping: f(&s.damping),
        contact_distance: f(&s.contact_distance),
        release_distance: f(&s.release_distance),
        violation_tolerance: f(&s.violation_tolerance),
        coupling_stiffness: f(&s.coupling_stiffness),
        coupling_damping: f(&s.coupling_damping),
        velocity_filter: f(&s.velocity_filter),
        dynamics: s.dynamics.as_ref().map(|x| *x.get_ref()),
        penetration_tolerance: f(&s.penetration_tolerance),
        contact_guards: s.contact_guards.as_ref().map(|x| *x.get_ref()),
    }
}

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
            builder.gear(super::gear::gear_spec(g));
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

    fn hand(&self, hand: Option<&Spanned<super::spec::HandSection>>) -> HandDecl {
        let Some(h) = hand.map(Spanned::get_ref) else {
            return HandDecl {
                path: HandPath::Still,
                stiffness_n_per_m: None,
                damping_n_s_per_m: None,
            };
        };
        let path = if let Some(c) = &h.circle {
            let c = c.get_ref();
            HandPath::Circle {
                radius_m: c.radius,
                hz: c.hz,
                u: c.u.get(),
                v: c.v.get(),
            }
        } else if let Some(l) = &h.line {
            HandPath::Line {
                to_m: l.get_ref().to.get(),
                seconds: l.get_ref().seconds,
            }
        } else if let Some(w) = &h.waypoints {
            HandPath::Waypoints {
                points: w.get_ref().iter().map(|p| p.get()).collect(),
            }
        } else if let Some(t) = &h.trace {
            let rel = PathBuf::from(t.get_ref());
            let path = match &self.dir {
                Some(dir) if rel.is_relative() => dir.join(rel),
                _ => rel,
            };
            HandPath::Trace {
                path,
                span: t.span(),
            }
        } else {
            HandPath::Still
        };
        HandDecl {
            path,
            stiffness_n_per_m: h.stiffness.as_ref().map(|x| *x.get_ref()),
            damping_n_s_per_m: h.damping.as_ref().map(|x| *x.get_ref()),
        }
    }

    /// An initial configuration outside a joint's own limits is an error at
    /// that joint's `limits` (the fast loop would start with a violated
    /// inequality and ask for an enormous force to fix it in one tick).
    fn check_limits_at_q0(&self, model: &Model) -> Result<(), SceneError> {
        /// Slack for a configuration written with finite digits: 1 µm or µrad.
        const SLACK: f64 = 1e-6;
        let mut ev = model.evaluation();
        if ev
            .evaluate(model, model.q0(), &model.initial_targets())
            .is_err()
        {
            return Ok(()); // non-finite q0: the builder's checks report it
        }
        for (r, row) in model.rows().iter().enumerate() {
            let v = ev.values()[r];
            if row.sense != Sense::Inequality || v >= -SLACK {
                continue;
            }
            let c = &model.constraints()[row.constraint.index()];
            let Some(joint) = c.name.strip_suffix(".limits") else {
                continue;
            };
            let j = match joint
                .strip_prefix('#')
                .and_then(|k| k.parse::<usize>().ok())
            {
                Some(k) => self.spec.joints.get(k.saturating_sub(1)),
                None => self
                    .spec
                    .joints
                    .iter()
                    .find(|j| j.name.as_ref().is_some_and(|n| n.get_ref() == joint)),
            };
            let span = j
                .and_then(|j| j.limits.as_ref().map(Spanned::span))
                .unwrap_or(0..0);
            let unit = match row.unit {
                RowUnit::Angle => "rad",
                _ => "m",
            };
            return Err(self.error_at(
                span,
                format!(
                    "joint `{joint}`: the initial configuration (bodies' positions and orientations as written) is outside these limits by {:.3e} {unit}; move the bodies inside the limits or widen them",
                    -v
                ),
            ));
        }
        Ok(())
    }
}
