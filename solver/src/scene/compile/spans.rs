//! Builder errors mapped to the span of the field they are about.

use super::convert::objective_spec;
use crate::model::{BuildError, DesignParam, Owner};
use crate::objective::ObjectiveSpec;
use crate::scene::LoadedScene;
use crate::scene::SceneError;
use crate::scene::spec::{BodySection, FreeSpec, JointSection, ObjectiveSection};
use std::ops::Range;
use toml::Spanned;

impl LoadedScene {
    /// Maps a builder error to the span of the field it is about.
    pub(super) fn build_error(&self, e: &BuildError) -> SceneError {
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
                    (Some(g), false) => crate::scene::gear::gear_field(g, e),
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
            msg.push_str(&format!(
                " (bodies: {})",
                crate::scene::validate::list(&known)
            ));
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
