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
use super::settings::SceneSettings;
use super::spec::{
    Arr, BodySection, BoundsSpec, FreeSpec, GraspSpec, JointKindSpec, JointSection,
    ObjectiveSection, Quat, ShapeSpec,
};
use crate::model::{
    BodySpec, Bounds, BuildError, DEFAULT_FINGERTIP_RADIUS_M, DesignParam, FingerSpec, JointKind,
    JointSpec, Owner, Shape,
};
use crate::objective::{ObjectiveKind, ObjectiveSpec, ObstacleSpec};
use crate::{FingerId, Model, ModelBuilder, RowUnit, Sense};
use std::ops::Range;
use std::path::PathBuf;
use toml::Spanned;

/// What the simulated hand does, in the scene frame (offsets from the finger's
/// initial world position).
#[derive(Debug, Clone, PartialEq)]
pub enum HandPath {
    /// Stay where the finger starts.
    Still,
    /// r((cos ωt − 1)u + sin ωt v).
    Circle {
        /// m.
        radius_m: f64,
        /// Revolutions per second.
        hz: f64,
        /// In-plane direction.
        u: [f64; 3],
        /// In-plane direction.
        v: [f64; 3],
    },
    /// Move by `to_m` over `seconds`, then hold.
    Line {
        /// m.
        to_m: [f64; 3],
        /// s.
        seconds: f64,
    },
    /// Offsets at given times, linearly interpolated (an inline trace):
    /// `[t_s, dx_m, dy_m, dz_m]`, times strictly increasing.
    Waypoints {
        /// The points.
        points: Vec<[f64; 4]>,
    },
    /// A CSV trace, path resolved relative to the scene file.
    Trace {
        /// Resolved path.
        path: PathBuf,
        /// Where the path was written, for errors.
        span: Range<usize>,
    },
}

/// A simulated hand: trajectory plus optional grip settings.
#[derive(Debug, Clone, PartialEq)]
pub struct HandDecl {
    /// The trajectory.
    pub path: HandPath,
    /// Grip stiffness, N/m (None: the device crate's default).
    pub stiffness_n_per_m: Option<f64>,
    /// Grip damping, N·s/m (None: default).
    pub damping_n_s_per_m: Option<f64>,
}

/// One `[[device]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceDecl {
    /// Unique name.
    pub name: String,
    /// Device model name (validated by the session against the device crate).
    pub model: String,
    /// Where `model` was written, for errors.
    pub model_span: Range<usize>,
    /// Scene metres per device metre.
    pub scale: f64,
    /// Device frame in the scene, `[w, x, y, z]`, normalised.
    pub orientation_wxyz: [f64; 4],
    /// The simulated hand (default: still).
    pub hand: HandDecl,
}

/// One `[[finger]]`, wired to its device and its model finger.
#[derive(Debug, Clone, PartialEq)]
pub struct FingerDecl {
    /// Unique name.
    pub name: String,
    /// Index into [`CompiledScene::devices`].
    pub device: usize,
    /// The finger in the model.
    pub finger: FingerId,
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

fn joint_kind(k: JointKindSpec) -> JointKind {
    match k {
        JointKindSpec::Spherical => JointKind::Spherical,
        JointKindSpec::Revolute => JointKind::Revolute,
        JointKindSpec::Universal => JointKind::Universal,
        JointKindSpec::Prismatic => JointKind::Prismatic,
        JointKindSpec::Fixed => JointKind::Fixed,
        JointKindSpec::Distance => JointKind::Distance,
        JointKindSpec::Perpendicular => JointKind::Perpendicular,
        JointKindSpec::PointOnPlane => JointKind::PointOnPlane,
        JointKindSpec::OnSurface => JointKind::OnSurface,
        JointKindSpec::Rolling => JointKind::Rolling,
    }
}

fn contact_surface(s: &super::spec::SurfaceSection) -> crate::ContactSurface {
    use super::spec::SurfaceTypeSpec as T;
    use crate::parametric::SurfaceKind as K;
    let r = s.radius.unwrap_or(f64::NAN);
    let kind = match s.kind {
        T::Plane => K::Plane,
        T::Bowl => K::Sphere {
            radius_m: r,
            concave: true,
        },
        T::Dome => K::Sphere {
            radius_m: r,
            concave: false,
        },
        T::Trough => K::Cylinder {
            radius_m: r,
            concave: true,
        },
        T::Ridge => K::Cylinder {
            radius_m: r,
            concave: false,
        },
    };
    crate::ContactSurface {
        kind,
        origin_m: s.origin.map_or([0.0; 3], |o| o.get()),
        orientation_wxyz: s.orientation.map_or([1.0, 0.0, 0.0, 0.0], |q| q.get()),
    }
}

fn body_spec(b: &BodySection) -> BodySpec {
    let mut spec = if b.fixed {
        BodySpec::fixed(b.name.get_ref().clone())
    } else {
        BodySpec::new(b.name.get_ref().clone())
    };
    if let Some(p) = &b.position {
        spec = spec.at(p.get_ref().get());
    }
    if let Some(q) = &b.orientation {
        spec = spec.oriented(q.get_ref().get());
    }
    spec.mass_kg = b.mass.as_ref().map(|m| *m.get_ref());
    spec.inertia_kg_m2 = b.inertia.as_ref().map(|i| i.get_ref().get());
    spec.shape = b.shape.as_ref().map(|s| shape(s.get_ref()));
    spec.density_kg_m3 = b.density.as_ref().map(|d| *d.get_ref());
    spec.friction = b.friction.as_ref().map_or(0.0, |m| *m.get_ref());
    spec.restitution = b.restitution.as_ref().map_or(0.0, |e| *e.get_ref());
    spec.damping_per_s = b.damping.as_ref().map_or(0.0, |c| *c.get_ref());
    spec.velocity_m_s = b.velocity.as_ref().map_or([0.0; 3], |v| v.get_ref().get());
    spec.angular_velocity_rad_s =
        (b.angular_velocity.as_ref()).map_or([0.0; 3], |w| w.get_ref().get());
    spec.free = b.free.iter().map(|f| free_param(*f.get_ref())).collect();
    spec.bounds = b.bounds.as_ref().map(|x| bounds(*x.get_ref()));
    spec.flexible = b.flexible.as_ref().map(|f| {
        let f = f.get_ref();
        crate::flexible::BeamSpec {
            span_m: f.span.get(),
            clamp_m: f.clamp.unwrap_or(0.0),
            stiffness_n_m2: [f.stiffness, f.stiffness_z.unwrap_or(f.stiffness)],
            modes: f.modes.map_or(3, |m| m as usize),
        }
    });
    spec
}

fn free_param(f: FreeSpec) -> DesignParam {
    match f {
        FreeSpec::Length => DesignParam::Length,
        FreeSpec::AnchorI => DesignParam::AnchorI,
        FreeSpec::AnchorJ => DesignParam::AnchorJ,
        FreeSpec::Position => DesignParam::Position,
    }
}

fn bounds(b: BoundsSpec) -> Bounds {
    match b {
        BoundsSpec::Scalar(v) => Bounds::Scalar(v),
        BoundsSpec::Vector(v) => Bounds::Vector(v),
    }
}

/// The builder's objective for a validated `[[objective]]` (keys the kind
/// does not take were refused by `validate`).
pub(super) fn objective_spec(o: &ObjectiveSection) -> ObjectiveSpec {
    let weight = o.weight.as_ref().map_or(1.0, |w| *w.get_ref());
    let name = o.name.as_ref().map(|n| n.get_ref().clone());
    let point =
        |p: &Option<Spanned<super::spec::Vec3>>| p.as_ref().map_or([0.0; 3], |p| p.get_ref().get());
    let names = |v: &Option<Spanned<Vec<Spanned<String>>>>| {
        v.as_ref().map_or(Vec::new(), |v| {
            v.get_ref().iter().map(|s| s.get_ref().clone()).collect()
        })
    };
    match o.kind.get_ref() {
        ObjectiveKind::Finger => ObjectiveSpec::Finger { weight },
        ObjectiveKind::LeastAstonishment => ObjectiveSpec::LeastAstonishment {
            weight,
            design_weight: o.design_weight.as_ref().map_or(1.0, |w| *w.get_ref()),
        },
        ObjectiveKind::Dexterity => ObjectiveSpec::Dexterity {
            name,
            weight,
            chain: names(&o.chain),
            point_m: point(&o.point),
            directions: o.directions.as_ref().map_or(Vec::new(), |d| {
                d.get_ref().iter().map(|v| v.get()).collect()
            }),
            angular_directions: o.angular_directions.as_ref().map_or(Vec::new(), |d| {
                d.get_ref().iter().map(|v| v.get()).collect()
            }),
            closure: names(&o.closure),
        },
        ObjectiveKind::Obstacle => ObjectiveSpec::Obstacle {
            name,
            weight,
            points: avoiding(o),
            obstacle: obstacle(o),
            distance_m: o.distance.as_ref().map_or(0.0, |d| *d.get_ref()),
        },
        ObjectiveKind::InverseDistance => ObjectiveSpec::InverseDistance {
            name,
            weight,
            points: avoiding(o),
            obstacle: obstacle(o),
        },
        ObjectiveKind::WorkspaceVolume => ObjectiveSpec::WorkspaceVolume {
            name,
            weight,
            chain: names(&o.chain),
            point_m: point(&o.point),
        },
        ObjectiveKind::StraightLine => ObjectiveSpec::StraightLine {
            name,
            weight,
            body: o
                .body
                .as_ref()
                .map_or(String::new(), |b| b.get_ref().clone()),
            point_m: point(&o.point),
            line_point_m: point(&o.line_point),
            direction: point(&o.direction),
        },
        ObjectiveKind::JointLimitDistance => ObjectiveSpec::JointLimitDistance {
            name,
            weight,
            joints: names(&o.joints),
        },
    }
}

/// An `obstacle` or `inverse_distance` objective's `points`.
fn avoiding(o: &ObjectiveSection) -> Vec<(String, [f64; 3])> {
    o.points.as_ref().map_or(Vec::new(), |p| {
        p.get_ref()
            .iter()
            .map(|r| {
                let r = r.get_ref();
                (
                    r.body.get_ref().clone(),
                    r.point.map_or([0.0; 3], |p| p.get()),
                )
            })
            .collect()
    })
}

/// An `obstacle` or `inverse_distance` objective's obstacle (validated:
/// exactly one of `obstacle`, `obstacle_body`).
fn obstacle(o: &ObjectiveSection) -> ObstacleSpec {
    match (&o.obstacle, &o.obstacle_body) {
        (Some(p), _) => ObstacleSpec::World(p.get_ref().get()),
        (None, b) => ObstacleSpec::Body {
            body: b.as_ref().map_or(String::new(), |b| b.get_ref().clone()),
            point_m: o
                .obstacle_point
                .as_ref()
                .map_or([0.0; 3], |p| p.get_ref().get()),
        },
    }
}

pub(super) fn shape(s: &ShapeSpec) -> Shape {
    match s {
        ShapeSpec::Box(h) => Shape::Box {
            half_extents_m: h.get(),
        },
        ShapeSpec::Sphere(r) => Shape::Sphere { radius_m: *r },
        ShapeSpec::Capsule {
            half_height,
            radius,
        } => Shape::Capsule {
            half_height_m: *half_height,
            radius_m: *radius,
        },
        ShapeSpec::Convex(pts) => Shape::Convex {
            points_m: pts.iter().map(|p| p.get()).collect(),
        },
    }
}

fn joint_spec(j: &JointSection) -> JointSpec {
    let [bi, bj] = &j.bodies.get_ref().0;
    let mut spec = JointSpec::new(
        joint_kind(*j.kind.get_ref()),
        bi.get_ref().clone(),
        bj.get_ref().clone(),
    );
    spec.name = j.name.as_ref().map(|n| n.get_ref().clone());
    if let Some(a) = &j.anchors {
        spec.anchors_m = a.get_ref().nested();
    }
    spec.axes = j.axes.as_ref().map(|a| a.get_ref().nested());
    spec.length_m = j.length.as_ref().map(|l| *l.get_ref());
    spec.limits = j.limits.as_ref().map(|l| l.get_ref().get());
    spec.free = j.free.iter().map(|f| free_param(*f.get_ref())).collect();
    spec.bounds = j.bounds.as_ref().map(|x| bounds(*x.get_ref()));
    spec.report_torque = j.report_torque.as_ref().is_some_and(|x| *x.get_ref());
    spec.surface = j.surface.as_ref().map(|x| contact_surface(x.get_ref()));
    spec.radius_m = j.radius.as_ref().map(|x| *x.get_ref());
    spec.collide = j.collide.as_ref().is_some_and(|c| *c.get_ref());
    spec
}

fn normalised(q: Quat) -> Quat {
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    Arr([q[0] / n, q[1] / n, q[2] / n, q[3] / n])
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
            settings: SceneSettings::from_section(&s.solver),
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

    /// Maps a builder error to the span of the field it is about.
    fn build_error(&self, e: &BuildError) -> SceneError {
        let s = &self.spec;
        let whole = 0..0;
        let span: Range<usize> = match e.owner() {
            Owner::Scene => s.scene.gravity.as_ref().map_or(whole, Spanned::span),
            Owner::Body(name) => {
                let dup = matches!(e, BuildError::DuplicateName { .. });
                let b = s
                    .bodies
                    .iter()
                    .filter(|b| b.name.get_ref() == name)
                    .nth(usize::from(dup));
                b.map_or(whole, |b| body_field(b, e))
            }
            Owner::Joint(name) => {
                let dup = matches!(e, BuildError::DuplicateName { .. });
                let j = match name.strip_prefix('#').and_then(|k| k.parse::<usize>().ok()) {
                    Some(k) => s.joints.get(k.saturating_sub(1)),
                    None => s
                        .joints
                        .iter()
                        .filter(|j| j.name.as_ref().is_some_and(|n| n.get_ref() == name))
                        .nth(usize::from(dup)),
                };
                j.map_or(whole, |j| joint_field(j, e))
            }
            Owner::Finger(name) => {
                let dup = matches!(e, BuildError::DuplicateName { .. });
                let f = s
                    .fingers
                    .iter()
                    .filter(|f| f.name.get_ref() == name)
                    .nth(usize::from(dup));
                f.map_or(whole, |f| match e {
                    BuildError::UnknownBody { .. } | BuildError::FingerOnFixedBody { .. } => {
                        f.body.as_ref().map_or(f.name.span(), Spanned::span)
                    }
                    BuildError::NonFinite {
                        field: "position", ..
                    }
                    | BuildError::OutOfRange {
                        field: "position", ..
                    } => f.position.as_ref().map_or(f.name.span(), Spanned::span),
                    BuildError::NonFinite { .. } | BuildError::Flexible { .. } => {
                        f.point.as_ref().map_or(f.name.span(), Spanned::span)
                    }
                    BuildError::BadFingertip {
                        field: "radius", ..
                    } => f.radius.as_ref().map_or(f.name.span(), Spanned::span),
                    BuildError::BadFingertip { .. } => {
                        f.friction.as_ref().map_or(f.name.span(), Spanned::span)
                    }
                    _ => f.name.span(),
                })
            }
            Owner::Objective(name) => {
                let specs: Vec<ObjectiveSpec> = s.objectives.iter().map(objective_spec).collect();
                let named: Vec<usize> = (0..specs.len())
                    .filter(|&k| &crate::objective::display_name(&specs, k) == name)
                    .collect();
                let dup = usize::from(matches!(e, BuildError::DuplicateName { .. }));
                let k = named.get(dup).or(named.last()).copied();
                k.map_or(whole, |k| objective_field(&s.objectives[k], e))
            }
            Owner::Gear(name) => {
                let dup = matches!(e, BuildError::DuplicateName { .. });
                let named: Vec<_> = s
                    .gears
                    .iter()
                    .filter(|g| g.name.get_ref() == name)
                    .collect();
                match (named.first(), dup) {
                    (Some(g), false) => super::gear::gear_field(g, e),
                    // Used twice among gears: the second; else it repeats a joint's.
                    (Some(g), true) => named.get(1).unwrap_or(g).name.span(),
                    (None, _) => whole,
                }
            }
            Owner::Inequality(_) => whole,
        };
        let mut msg = e.to_string();
        if let BuildError::UnknownBody { .. } = e {
            let known: Vec<&str> = s.bodies.iter().map(|b| b.name.get_ref().as_str()).collect();
            msg.push_str(&format!(" (bodies: {})", super::validate::list(&known)));
        }
        self.error_at(span, msg)
    }
}

fn body_field(b: &BodySection, e: &BuildError) -> Range<usize> {
    let or_name = |v: Option<Range<usize>>| v.unwrap_or_else(|| b.name.span());
    match e {
        BuildError::NonFinite {
            field: "position", ..
        }
        | BuildError::OutOfRange {
            field: "position", ..
        } => or_name(b.position.as_ref().map(Spanned::span)),
        BuildError::NonFinite {
            field: "orientation",
            ..
        }
        | BuildError::ZeroOrientation { .. } => or_name(b.orientation.as_ref().map(Spanned::span)),
        BuildError::NonFinite { field: "mass", .. } | BuildError::NonPositiveMass { .. } => {
            or_name(b.mass.as_ref().map(Spanned::span))
        }
        BuildError::NonFinite {
            field: "inertia", ..
        }
        | BuildError::BadInertia { .. } => or_name(b.inertia.as_ref().map(Spanned::span)),
        BuildError::Shape {
            field: "density", ..
        } => or_name(b.density.as_ref().map(Spanned::span)),
        BuildError::Shape { .. } => or_name(b.shape.as_ref().map(Spanned::span)),
        BuildError::BadFriction { .. } => or_name(b.friction.as_ref().map(Spanned::span)),
        BuildError::Flexible { .. } => or_name(b.flexible.as_ref().map(Spanned::span)),
        BuildError::BadMotion { field, .. } => or_name(match *field {
            "restitution" => b.restitution.as_ref().map(Spanned::span),
            "damping" => b.damping.as_ref().map(Spanned::span),
            "velocity" => b.velocity.as_ref().map(Spanned::span),
            _ => b.angular_velocity.as_ref().map(Spanned::span),
        }),
        BuildError::UnsupportedBodyFree { .. } | BuildError::DuplicateFree { .. } => {
            let dup = matches!(e, BuildError::DuplicateFree { .. });
            or_name(
                b.free
                    .iter()
                    .filter(|f| *f.get_ref() == FreeSpec::Position || !dup)
                    .nth(usize::from(dup))
                    .map(Spanned::span),
            )
        }
        BuildError::NonFinite {
            field: "bounds", ..
        }
        | BuildError::BoundsWithoutFree { .. }
        | BuildError::BoundsShape { .. }
        | BuildError::BoundsReversed { .. }
        | BuildError::OutsideBounds { .. } => or_name(b.bounds.as_ref().map(Spanned::span)),
        _ => b.name.span(),
    }
}

/// The span of the value of objective `o` that error `e` is about.
fn objective_field(o: &ObjectiveSection, e: &BuildError) -> Range<usize> {
    let head = o.name.as_ref().map_or(o.kind.span(), Spanned::span);
    let or_head = |v: Option<Range<usize>>| v.unwrap_or_else(|| head.clone());
    let in_list = |v: &Option<Spanned<Vec<Spanned<String>>>>, name: &str| {
        v.as_ref().and_then(|v| {
            v.get_ref()
                .iter()
                .find(|x| x.get_ref() == name)
                .map(Spanned::span)
        })
    };
    match e {
        BuildError::UnknownBody { body, .. } => or_head(
            in_list(&o.chain, body)
                .or_else(|| in_list(&o.closure, body))
                .or_else(|| {
                    o.points.as_ref().and_then(|p| {
                        p.get_ref()
                            .iter()
                            .find(|r| r.get_ref().body.get_ref() == body)
                            .map(|r| r.get_ref().body.span())
                    })
                })
                .or_else(|| o.body.as_ref().map(Spanned::span))
                .or_else(|| o.obstacle_body.as_ref().map(Spanned::span)),
        ),
        BuildError::ChainNotJoined { b, .. } => {
            or_head(in_list(&o.chain, b).or_else(|| in_list(&o.closure, b)))
        }
        BuildError::ChainJointKind { .. } => or_head(o.chain.as_ref().map(Spanned::span)),
        BuildError::UnknownJoint { joint, .. } | BuildError::NoLimits { joint, .. } => {
            or_head(in_list(&o.joints, joint))
        }
        BuildError::BadObjective { field: "kind", .. } => o.kind.span(),
        BuildError::BadObjective { field, .. } | BuildError::NonFinite { field, .. } => {
            let span = o
                .keys()
                .into_iter()
                .find(|(k, _)| k == field)
                .map(|(_, s)| s);
            or_head(span)
        }
        _ => head,
    }
}

fn joint_field(j: &JointSection, e: &BuildError) -> Range<usize> {
    let head = j.name.as_ref().map_or(j.kind.span(), Spanned::span);
    let or_head = |v: Option<Range<usize>>| v.unwrap_or_else(|| head.clone());
    let [bi, bj] = &j.bodies.get_ref().0;
    match e {
        BuildError::UnknownBody { body, .. } => {
            if bi.get_ref() == body {
                bi.span()
            } else {
                bj.span()
            }
        }
        BuildError::SameBody { .. } => bj.span(),
        BuildError::BothFixed { .. } => j.bodies.span(),
        BuildError::MissingAxes { .. } => j.kind.span(),
        BuildError::ZeroAxis { .. } | BuildError::ParallelAxes { .. } => {
            or_head(j.axes.as_ref().map(Spanned::span))
        }
        BuildError::NonFinite { field: "axes", .. } => or_head(j.axes.as_ref().map(Spanned::span)),
        BuildError::NonFinite {
            field: "anchors", ..
        }
        | BuildError::OutOfRange {
            field: "anchors", ..
        }
        | BuildError::CoincidentAnchors { .. }
        | BuildError::Flexible { .. } => or_head(j.anchors.as_ref().map(Spanned::span)),
        BuildError::Surface { field, .. } => or_head(match *field {
            "radius" => j.radius.as_ref().map(Spanned::span),
            "anchors" => j.anchors.as_ref().map(Spanned::span),
            "kind" => Some(j.kind.span()),
            _ => j.surface.as_ref().map(Spanned::span),
        }),
        BuildError::NonFinite {
            field: "length", ..
        }
        | BuildError::OutOfRange {
            field: "length", ..
        }
        | BuildError::NonPositiveLength { .. }
        | BuildError::UnexpectedLength { .. }
        | BuildError::LengthOutsideLimits { .. } => or_head(j.length.as_ref().map(Spanned::span)),
        BuildError::NonFinite {
            field: "limits", ..
        }
        | BuildError::LimitsReversed { .. }
        | BuildError::LimitsUnsupported { .. }
        | BuildError::AngleLimitsOutOfRange { .. } => or_head(j.limits.as_ref().map(Spanned::span)),
        BuildError::NonFinite {
            field: "bounds", ..
        }
        | BuildError::BoundsWithoutFree { .. }
        | BuildError::BoundsShape { .. }
        | BuildError::BoundsReversed { .. }
        | BuildError::OutsideBounds { .. } => or_head(j.bounds.as_ref().map(Spanned::span)),
        BuildError::TorqueJointKind { .. } => or_head(j.report_torque.as_ref().map(Spanned::span)),
        BuildError::UnsupportedFree { param, .. } | BuildError::DuplicateFree { param, .. } => {
            let want = match param {
                DesignParam::Length => FreeSpec::Length,
                DesignParam::AnchorI => FreeSpec::AnchorI,
                DesignParam::AnchorJ => FreeSpec::AnchorJ,
                DesignParam::Position => FreeSpec::Position,
            };
            let dup = matches!(e, BuildError::DuplicateFree { .. });
            j.free
                .iter()
                .filter(|f| *f.get_ref() == want)
                .nth(usize::from(dup))
                .map_or(head.clone(), Spanned::span)
        }
        _ => head,
    }
}
