//! Compiling [`ObjectiveSpec`]s against a built model: names resolved,
//! dexterity chains found in the joints, numbers checked. Every error names
//! the objective (by its name, or its kind).

use nalgebra::Vector3;

use super::dexterity::{Axis, Column, Dexterity};
use super::joint_limit::Centred;
use super::obstacle::{Avoid, Obstacle};
use super::spec::{ObjectiveSpec, ObstacleSpec};
use super::straight_line::StraightLine;
use super::{Objective, Objectives, Term};
use crate::constraint::Geometry;
use crate::model::{BuildError, Owner};
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
        let body = |n: &str| {
            model.body_id(n).ok_or_else(|| BuildError::UnknownBody {
                owner: owner(),
                body: n.to_owned(),
            })
        };
        let finite = |field: &'static str, v: &[f64]| {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(BuildError::NonFinite {
                    owner: owner(),
                    field,
                })
            }
        };
        let term = match s {
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
                continue;
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
                continue;
            }
            ObjectiveSpec::Dexterity {
                chain,
                point_m,
                directions,
                ..
            } => {
                finite("point", point_m)?;
                for d in directions {
                    finite("directions", d)?;
                }
                Term::Dexterity(dexterity(model, chain, point_m, directions, &owner, &bad)?)
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
                Term::Obstacle(Avoid {
                    points: pts,
                    obstacle,
                    distance_m: *distance_m,
                })
            }
            ObjectiveSpec::StraightLine {
                body: b,
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
                    body: body(b)?,
                    point: Vector3::from(*point_m),
                    line_point: Vector3::from(*line_point_m),
                    direction: u.normalize(),
                })
            }
            ObjectiveSpec::JointLimitDistance { joints, .. } => {
                Term::JointLimits(joint_limits(model, joints, &owner, &bad)?)
            }
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

/// The chain's columns, the tip and the reach at q0.
fn dexterity(
    model: &Model,
    chain: &[String],
    point_m: &[f64; 3],
    directions: &[[f64; 3]],
    owner: &dyn Fn() -> Owner,
    bad: &dyn Fn(&'static str, &'static str) -> BuildError,
) -> Result<Dexterity, BuildError> {
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
    let mut columns = Vec::new();
    let mut points = Vec::new(); // joint points at q0, for the reach
    let frame = |b: usize| model.body_frame(model.q0(), BodyId(b as u32));
    for (k, pair) in ids.windows(2).enumerate() {
        let (a, b) = (pair[0], pair[1]);
        let joint = model.constraints().iter().enumerate().find(|(_, c)| {
            c.finger.is_none()
                && c.limits.is_none()
                && (c.bodies == [Some(a), Some(b)] || c.bodies == [Some(b), Some(a)])
        });
        let Some((ci, info)) = joint else {
            return Err(BuildError::ChainNotJoined {
                owner: owner(),
                a: chain[k].clone(),
                b: chain[k + 1].clone(),
            });
        };
        let origin = |p: &crate::constraint::block::Pair| Some((p.frame[0], p.anchor[0]));
        let world = |i: usize| Axis::World(Vector3::ith(i, 1.0));
        let (p, cols): (_, Vec<Column>) = match &model.geometry[ci] {
            Geometry::Revolute(j) => (
                j.pair,
                vec![Column {
                    axis: Axis::Body(j.pair.frame[0], j.axes.h_i),
                    origin: origin(&j.pair),
                }],
            ),
            Geometry::Prismatic(j) => (
                j.pair,
                vec![Column {
                    axis: Axis::Body(j.pair.frame[0], j.axes.h_i),
                    origin: None,
                }],
            ),
            Geometry::Spherical(j) => (
                j.pair,
                (0..3)
                    .map(|i| Column {
                        axis: world(i),
                        origin: origin(&j.pair),
                    })
                    .collect(),
            ),
            Geometry::Universal(j) => (
                j.pair,
                (0..2)
                    .map(|e| Column {
                        axis: Axis::Body(j.pair.frame[e], j.axes[e]),
                        origin: origin(&j.pair),
                    })
                    .collect(),
            ),
            _ => {
                return Err(BuildError::ChainJointKind {
                    owner: owner(),
                    joint: info.name.clone(),
                    kind: info.kind,
                });
            }
        };
        columns.extend(cols);
        let f = frame(p.frame[0]).unwrap_or(crate::rotation::BodyFrame::IDENTITY);
        let k0 = match p.anchor[0] {
            crate::constraint::block::Param3::Const(v) => v,
            crate::constraint::block::Param3::Free(c) => {
                Vector3::new(model.q0()[c], model.q0()[c + 1], model.q0()[c + 2])
            }
            crate::constraint::block::Param3::Flex(i) => model.flex_anchors[i as usize].k,
        };
        points.push(f.point(&k0));
    }
    let last = *ids.last().expect("two or more");
    if model.bodies()[last.index()].fixed {
        // The point rides on the last body: on a fixed one it never moves,
        // J̃ is zero and F sits at its floor for good.
        return Err(bad(
            "chain",
            "base first, tip last: its last body is fixed, so its point never moves (is the chain reversed?)",
        ));
    }
    let tip = Vector3::from(*point_m);
    if let Some(f) = frame(last.index()) {
        points.push(f.point(&tip));
    }
    let reach = points
        .windows(2)
        .map(|w| (w[1] - w[0]).norm())
        .sum::<f64>()
        .max(1e-3);
    let mut dirs = [Vector3::x(), Vector3::y(), Vector3::z()];
    let rows = if directions.is_empty() {
        3
    } else {
        if directions.len() > 3 {
            return Err(bad("directions", "one to three world directions"));
        }
        for (d, given) in dirs.iter_mut().zip(directions) {
            let v = Vector3::from(*given);
            if v.norm() < 1e-12 {
                return Err(bad("directions", "non-zero vectors"));
            }
            *d = v.normalize();
        }
        let n = directions.len();
        let gram = nalgebra::DMatrix::from_fn(n, n, |a, b| dirs[a].dot(&dirs[b]));
        if gram.determinant() < 1e-6 {
            return Err(bad("directions", "independent (not parallel) directions"));
        }
        n
    };
    Ok(Dexterity {
        columns,
        tip: (last, tip),
        directions: dirs,
        rows,
        reach_m: reach,
    })
}

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
