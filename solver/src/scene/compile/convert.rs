//! A validated scene's sections as the model builder's specs.

use super::decl::SceneSettings;
use crate::model::{BodySpec, Bounds, DesignParam, JointKind, JointSpec, Shape};
use crate::objective::{ObjectiveSpec, ObstacleSpec};
use crate::scene::spec::{
    Arr, BodySection, BoundsSpec, FreeSpec, JointKindSpec, JointSection, ObjectiveKindSpec,
    ObjectiveSection, Quat, ShapeSpec, SolverSection,
};
use toml::Spanned;

pub(super) fn settings(s: &SolverSection) -> SceneSettings {
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
        coordinates: (s.coordinates.as_ref()).and_then(|c| crate::Coordinates::parse(c.get_ref())),
    }
}

pub(super) fn joint_kind(k: JointKindSpec) -> JointKind {
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

pub(super) fn contact_surface(s: &crate::scene::spec::SurfaceSection) -> crate::ContactSurface {
    use crate::parametric::SurfaceKind as K;
    use crate::scene::spec::SurfaceTypeSpec as T;
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

pub(super) fn body_spec(b: &BodySection) -> BodySpec {
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

pub(super) fn free_param(f: FreeSpec) -> DesignParam {
    match f {
        FreeSpec::Length => DesignParam::Length,
        FreeSpec::AnchorI => DesignParam::AnchorI,
        FreeSpec::AnchorJ => DesignParam::AnchorJ,
        FreeSpec::Position => DesignParam::Position,
    }
}

pub(super) fn bounds(b: BoundsSpec) -> Bounds {
    match b {
        BoundsSpec::Scalar(v) => Bounds::Scalar(v),
        BoundsSpec::Vector(v) => Bounds::Vector(v),
    }
}

/// The builder's objective for a validated `[[objective]]` (keys the kind
/// does not take were refused by `validate`).
pub(in crate::scene) fn objective_spec(o: &ObjectiveSection) -> ObjectiveSpec {
    let weight = o.weight.as_ref().map_or(1.0, |w| *w.get_ref());
    let name = o.name.as_ref().map(|n| n.get_ref().clone());
    let point = |p: &Option<Spanned<crate::scene::spec::Vec3>>| {
        p.as_ref().map_or([0.0; 3], |p| p.get_ref().get())
    };
    let names = |v: &Option<Spanned<Vec<Spanned<String>>>>| {
        v.as_ref().map_or(Vec::new(), |v| {
            v.get_ref().iter().map(|s| s.get_ref().clone()).collect()
        })
    };
    match o.kind.get_ref() {
        ObjectiveKindSpec::Finger => ObjectiveSpec::Finger { weight },
        ObjectiveKindSpec::LeastAstonishment => ObjectiveSpec::LeastAstonishment {
            weight,
            design_weight: o.design_weight.as_ref().map_or(1.0, |w| *w.get_ref()),
        },
        ObjectiveKindSpec::Dexterity => ObjectiveSpec::Dexterity {
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
        ObjectiveKindSpec::Obstacle => ObjectiveSpec::Obstacle {
            name,
            weight,
            points: avoiding(o),
            obstacle: obstacle(o),
            distance_m: o.distance.as_ref().map_or(0.0, |d| *d.get_ref()),
        },
        ObjectiveKindSpec::InverseDistance => ObjectiveSpec::InverseDistance {
            name,
            weight,
            points: avoiding(o),
            obstacle: obstacle(o),
        },
        ObjectiveKindSpec::WorkspaceVolume => ObjectiveSpec::WorkspaceVolume {
            name,
            weight,
            chain: names(&o.chain),
            point_m: point(&o.point),
        },
        ObjectiveKindSpec::StraightLine => ObjectiveSpec::StraightLine {
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
        ObjectiveKindSpec::JointLimitDistance => ObjectiveSpec::JointLimitDistance {
            name,
            weight,
            joints: names(&o.joints),
        },
    }
}

/// An `obstacle` or `inverse_distance` objective's `points`.
pub(super) fn avoiding(o: &ObjectiveSection) -> Vec<(String, [f64; 3])> {
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
pub(super) fn obstacle(o: &ObjectiveSection) -> ObstacleSpec {
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

pub(in crate::scene) fn shape(s: &ShapeSpec) -> Shape {
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

pub(super) fn joint_spec(j: &JointSection) -> JointSpec {
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

pub(super) fn normalised(q: Quat) -> Quat {
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    Arr([q[0] / n, q[1] / n, q[2] / n, q[3] / n])
}
