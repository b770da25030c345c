//! Compiling [`ObjectiveSpec`]s against a built model: names resolved,
//! dexterity chains found in the joints, numbers checked. Every error names
//! the objective (by its name, or its kind).

use nalgebra::Vector3;

use super::compile_chain::{ChainSpec, dexterity};
use super::inverse_distance::InverseDistance;
use super::joint_limit::Centred;
use super::obstacle::{Avoid, Obstacle};
use super::spec::{ObjectiveSpec, ObstacleSpec};
use super::straight_line::StraightLine;
use super::workspace::{Link, Workspace};
use super::{Objective, Objectives, Term};
use crate::constraint::Geometry;
use crate::constraint::block::Param3;
use crate::model::{BuildError, Owner, finite};
use crate::{BodyId, ConstraintKind, Model};

/// The name objective `k` of `specs` goes by: its `name`, else its kind,
/// with `#n` (1-based among its kind) when the kind repeats.
pub(crate) fn display_name(specs: &[ObjectiveSpec], k: usize) -> String {
    let s = &specs[k];
    if let Some(n) = s.name() {
        return n.to_owned();
    }
    let kind = s.kind();
    let same: Vec<usize> = (0..specs.len())
        .filter(|&i| specs[i].kind() == kind && specs[i].name().is_none())
        .collect();
    if same.len() > 1 {
        let n = same.iter().position(|&i| i == k).unwrap_or(0) + 1;
        format!("{kind}#{n}")
    } else {
        kind.as_str().to_owned()
    }
}

/// Compiles `specs` against `model` (bodies, joints and their geometry,
/// q0). Allocates; build time only.
pub(crate) fn compile(specs: &[ObjectiveSpec], model: &Model) -> Result<Objectives, BuildError> {
    let mut out = Objectives::default();
    let mut seen = (false, false);
    for (k, s) in specs.iter().enumerate() {
        let name = display_name(specs, k);
        let owner = || Owner::Objective(name.clone());
        let bad = |field: &'static str, why: &'static str| BuildError::BadObjective {
            owner: owner(),
            field,
            why,
        };
        let w = s.weight();
        if !(w.is_finite() && w >= 0.0) {
            return Err(bad("weight", "a finite number ≥ 0"));
        }
        if out.terms.iter().any(|t| t.name == name) {
            return Err(BuildError::DuplicateName { owner: owner() });
        }
        global(&mut out, &mut seen, s, w, &bad)?;
        let Some(term) = term(model, s, &owner, &bad)? else {
            continue;
        };
        out.terms.push(Objective {
            name,
            kind: s.kind(),
            weight: w,
            term,
        });
    }
    Ok(out)
}

/// The objectives that set a weight of the whole problem (`finger`,
/// `least_astonishment`, each at most once; `seen` says which came): sets
/// it in `out`; any other kind leaves `out` as it is.
fn global(
    out: &mut Objectives,
    seen: &mut (bool, bool),
    s: &ObjectiveSpec,
    w: f64,
    bad: Bad,
) -> Result<(), BuildError> {
    match s {
        ObjectiveSpec::Finger { .. } => {
            if std::mem::replace(&mut seen.0, true) {
                return Err(bad(
                    "kind",
                    "given once: a scene has one `finger` objective (its weight is the fingers' pull)",
                ));
            }
            if w <= 0.0 {
                return Err(bad(
                    "weight",
                    "> 0 for finger (a finger that does not pull holds nothing)",
                ));
            }
            out.finger_weight = w;
        }
        ObjectiveSpec::LeastAstonishment { design_weight, .. } => {
            if std::mem::replace(&mut seen.1, true) {
                return Err(bad(
                    "kind",
                    "given once: a scene has one `least_astonishment` objective (its weight divides every other)",
                ));
            }
            if w <= 0.0 {
                return Err(bad(
                    "weight",
                    "> 0 for least_astonishment (every other weight is divided by it)",
                ));
            }
            if !(design_weight.is_finite() && *design_weight > 0.0) {
                return Err(bad("design_weight", "a finite number > 0"));
            }
            out.least_astonishment = w;
            out.design_weight = *design_weight;
        }
        _ => {}
    }
    Ok(())
}

/// The term of an objective of the problem's sum; `None` for `finger` and
/// `least_astonishment`, which set weights of the whole problem
/// (`global`).
fn term(
    model: &Model,
    s: &ObjectiveSpec,
    owner: &dyn Fn() -> Owner,
    bad: Bad,
) -> Result<Option<Term>, BuildError> {
    let finite = |field: &'static str, v: &[f64]| finite(owner, field, v);
    Ok(Some(match s {
        ObjectiveSpec::Finger { .. } | ObjectiveSpec::LeastAstonishment { .. } => return Ok(None),
        ObjectiveSpec::Dexterity {
            chain,
            point_m,
            directions,
            angular_directions,
            closure,
            ..
        } => {
            finite("point", point_m)?;
            for d in directions {
                finite("directions", d)?;
            }
            for d in angular_directions {
                finite("angular_directions", d)?;
            }
            let spec = ChainSpec {
                chain,
                closure,
                point_m,
                directions,
                angular: angular_directions,
            };
            Term::Dexterity(dexterity(model, &spec, owner, bad)?)
        }
        ObjectiveSpec::Obstacle {
            points,
            obstacle,
            distance_m,
            ..
        } => {
            if !(distance_m.is_finite() && *distance_m > 0.0) {
                return Err(bad("distance", "a finite number > 0 (metres)"));
            }
            let (points, obstacle) = avoided(model, points, obstacle, owner, bad)?;
            Term::Obstacle(Avoid {
                points,
                obstacle,
                distance_m: *distance_m,
            })
        }
        ObjectiveSpec::InverseDistance {
            points, obstacle, ..
        } => {
            let (points, obstacle) = avoided(model, points, obstacle, owner, bad)?;
            Term::InverseDistance(InverseDistance {
                points,
                obstacle,
                scale_m: model.characteristic_length_m(),
            })
        }
        ObjectiveSpec::WorkspaceVolume { chain, point_m, .. } => {
            finite("point", point_m)?;
            Term::Workspace(workspace(model, chain, point_m, owner, bad)?)
        }
        ObjectiveSpec::StraightLine {
            body,
            point_m,
            line_point_m,
            direction,
            ..
        } => {
            finite("point", point_m)?;
            finite("line_point", line_point_m)?;
            finite("direction", direction)?;
            let u = Vector3::from(*direction);
            if u.norm() < 1e-12 {
                return Err(bad("direction", "a non-zero vector"));
            }
            Term::StraightLine(StraightLine {
                body: model.body_id(body).ok_or_else(|| BuildError::UnknownBody {
                    owner: owner(),
                    body: body.to_owned(),
                })?,
                point: Vector3::from(*point_m),
                line_point: Vector3::from(*line_point_m),
                direction: u.normalize(),
            })
        }
        ObjectiveSpec::JointLimitDistance { joints, .. } => {
            Term::JointLimits(joint_limits(model, joints, owner, bad)?)
        }
    }))
}

/// Body points kept away from an obstacle (body, point in its frame).
type Avoiding = Vec<(BodyId, Vector3<f64>)>;

/// The avoiding points and the obstacle of `obstacle` and
/// `inverse_distance`.
fn avoided(
    model: &Model,
    points: &[(String, [f64; 3])],
    obstacle: &ObstacleSpec,
    owner: &dyn Fn() -> Owner,
    bad: Bad,
) -> Result<(Avoiding, Obstacle), BuildError> {
    let finite = |field: &'static str, v: &[f64]| finite(owner, field, v);
    let body = |n: &str| {
        model.body_id(n).ok_or_else(|| BuildError::UnknownBody {
            owner: owner(),
            body: n.to_owned(),
        })
    };
    if points.is_empty() {
        return Err(bad("points", "at least one { body, point }"));
    }
    let obstacle = match obstacle {
        ObstacleSpec::World(p) => {
            finite("obstacle", p)?;
            Obstacle::World(Vector3::from(*p))
        }
        ObstacleSpec::Body { body: b, point_m } => {
            finite("obstacle_point", point_m)?;
            Obstacle::Body(body(b)?, Vector3::from(*point_m))
        }
    };
    let mut pts = Vec::with_capacity(points.len());
    for (b, p) in points {
        finite("points", p)?;
        let id = body(b)?;
        if matches!(obstacle, Obstacle::Body(o, _) if o == id) {
            return Err(bad(
                "points",
                "on bodies other than the obstacle's (an obstacle cannot avoid itself)",
            ));
        }
        pts.push((id, Vector3::from(*p)));
    }
    Ok((pts, obstacle))
}

/// A workspace chain's links: each body after the base, from its inbound
/// joint's anchor to its outbound one's (the last: to `point_m`); V₀ at q0.
fn workspace(
    model: &Model,
    chain: &[String],
    point_m: &[f64; 3],
    owner: &dyn Fn() -> Owner,
    bad: Bad,
) -> Result<Workspace, BuildError> {
    if chain.len() < 2 {
        return Err(bad("chain", "at least two bodies, base first"));
    }
    let ids = chain
        .iter()
        .map(|n| {
            model.body_id(n).ok_or_else(|| BuildError::UnknownBody {
                owner: owner(),
                body: n.clone(),
            })
        })
        .collect::<Result<Vec<BodyId>, _>>()?;
    // The anchor on body `b` of the joint between `a` and `b`.
    let anchor_on = |k: usize, b: BodyId| -> Result<Param3, BuildError> {
        let (a, c) = (ids[k], ids[k + 1]);
        let found = model
            .constraints()
            .iter()
            .zip(&model.geometry)
            .find(|(i, _)| {
                i.finger.is_none()
                    && i.limits.is_none()
                    && (i.bodies == [Some(a), Some(c)] || i.bodies == [Some(c), Some(a)])
            });
        let Some((info, g)) = found else {
            return Err(BuildError::ChainNotJoined {
                owner: owner(),
                a: chain[k].clone(),
                b: chain[k + 1].clone(),
            });
        };
        let pair = match g {
            Geometry::Revolute(j) => j.pair,
            Geometry::Spherical(j) => j.pair,
            Geometry::Universal(j) => j.pair,
            _ => {
                return Err(BuildError::ChainJointKind {
                    owner: owner(),
                    joint: info.name.clone(),
                    kind: info.kind,
                });
            }
        };
        let end = usize::from(pair.frame[1] == b.index());
        if matches!(pair.anchor[end], Param3::Flex(_)) {
            return Err(bad(
                "chain",
                "rigid bodies (a flexible body's links have no fixed length)",
            ));
        }
        Ok(pair.anchor[end])
    };
    let mut links = Vec::new();
    for k in 1..ids.len() {
        let inbound = anchor_on(k - 1, ids[k])?;
        let outbound = if k + 1 < ids.len() {
            anchor_on(k, ids[k])?
        } else {
            Param3::Const(Vector3::from(*point_m))
        };
        links.push(Link { inbound, outbound });
    }
    if !links
        .iter()
        .any(|l| matches!(l.inbound, Param3::Free(_)) || matches!(l.outbound, Param3::Free(_)))
    {
        return Err(bad(
            "chain",
            "a chain with a free anchor (its link lengths move only through free anchors)",
        ));
    }
    let l = model.characteristic_length_m();
    let mut w = Workspace {
        links,
        scale_m2: l * l,
        v0_m3: 1.0,
    };
    let v0 = w.volume(model.q0());
    if !(v0.is_finite() && v0 > 0.0) {
        return Err(bad("chain", "links of non-zero length at the start"));
    }
    w.v0_m3 = v0;
    Ok(w)
}

/// An error constructor: (field, what was expected).
pub(super) type Bad<'a> = &'a dyn Fn(&'static str, &'static str) -> BuildError;

/// The named joints' limits (every limited joint when `joints` is empty).
fn joint_limits(
    model: &Model,
    joints: &[String],
    owner: &dyn Fn() -> Owner,
    bad: &dyn Fn(&'static str, &'static str) -> BuildError,
) -> Result<Centred, BuildError> {
    let limit_of = |joint: usize| {
        model
            .constraints()
            .iter()
            .zip(&model.geometry)
            .find_map(|(c, g)| match g {
                Geometry::Limit(l) if c.limits.map(|j| j.index()) == Some(joint) => Some(*l),
                _ => None,
            })
    };
    let mut limits = Vec::new();
    if joints.is_empty() {
        for (c, g) in model.constraints().iter().zip(&model.geometry) {
            if let (Geometry::Limit(l), Some(_)) = (g, c.limits) {
                limits.push(*l);
            }
        }
        if limits.is_empty() {
            return Err(bad(
                "joints",
                "a model with limited joints (none has `limits`)",
            ));
        }
    }
    for name in joints {
        let joint = model
            .constraints()
            .iter()
            .position(|c| {
                &c.name == name
                    && c.finger.is_none()
                    && c.limits.is_none()
                    && !matches!(
                        c.kind,
                        ConstraintKind::QuaternionNorm
                            | ConstraintKind::DesignBound
                            | ConstraintKind::DesignPin
                    )
            })
            .ok_or_else(|| BuildError::UnknownJoint {
                owner: owner(),
                joint: name.clone(),
            })?;
        let l = limit_of(joint).ok_or_else(|| BuildError::NoLimits {
            owner: owner(),
            joint: name.clone(),
        })?;
        limits.push(l);
    }
    let l = model.characteristic_length_m();
    Ok(Centred {
        limits,
        scale_m2: l * l,
    })
}
