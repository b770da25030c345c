//! The builder's vocabulary for objectives ([`ObjectiveSpec`], mirroring the
//! scene's `[[objective]]`) and its compilation against a built model:
//! names resolved, chains found, numbers checked. Errors name the objective.

use std::fmt;
use std::str::FromStr;

use nalgebra::Vector3;

use super::dexterity::{Axis, Column, Dexterity};
use super::joint_limit::Centred;
use super::obstacle::{Avoid, Obstacle};
use super::straight_line::StraightLine;
use super::{Objective, Objectives, Term};
use crate::constraint::Geometry;
use crate::model::{BuildError, Owner, UnknownName};
use crate::{BodyId, ConstraintKind, Model};

/// `[[objective]] kind`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ObjectiveKind {
    /// The finger rows' penalty (its weight only).
    Finger,
    /// ½‖q − q₀‖ in the update's metric (its weight only).
    LeastAstonishment,
    /// Manipulability of a chain at a body point, Eq. 12–14.
    Dexterity,
    /// Body points kept away from an obstacle point, Eq. 15.
    Obstacle,
    /// A body point kept on a line, Fig. 10.
    StraightLine,
    /// Limited joints kept near the middle of their limits.
    JointLimitDistance,
}

impl ObjectiveKind {
    /// Every kind, in declaration order.
    pub const ALL: &'static [Self] = &[
        Self::Finger,
        Self::LeastAstonishment,
        Self::Dexterity,
        Self::Obstacle,
        Self::StraightLine,
        Self::JointLimitDistance,
    ];

    /// The scene-file spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Finger => "finger",
            Self::LeastAstonishment => "least_astonishment",
            Self::Dexterity => "dexterity",
            Self::Obstacle => "obstacle",
            Self::StraightLine => "straight_line",
            Self::JointLimitDistance => "joint_limit_distance",
        }
    }
}

impl fmt::Display for ObjectiveKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for ObjectiveKind {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        Self::ALL
            .iter()
            .copied()
            .find(|k| k.as_str() == s)
            .ok_or_else(|| UnknownName {
                what: "ObjectiveKind",
                name: s.to_owned(),
                expected: Self::ALL
                    .iter()
                    .map(|k| k.as_str())
                    .collect::<Vec<_>>()
                    .join(" | "),
            })
    }
}

/// The obstacle of an `obstacle` objective.
#[derive(Debug, Clone, PartialEq)]
pub enum ObstacleSpec {
    /// A fixed world point, metres.
    World([f64; 3]),
    /// A point of a body (body frame, metres): it moves with the body.
    Body {
        /// The body.
        body: String,
        /// The point, body frame.
        point_m: [f64; 3],
    },
}

/// One `[[objective]]`: its kind's parameters, by name.
#[derive(Debug, Clone, PartialEq)]
pub enum ObjectiveSpec {
    /// The finger rows' weight.
    Finger {
        /// Weight, ≥ 0.
        weight: f64,
    },
    /// Least astonishment's weight and the design variables' metric.
    LeastAstonishment {
        /// Weight, > 0.
        weight: f64,
        /// Design variables' metric relative to a body of mean mass, > 0.
        design_weight: f64,
    },
    /// Maximise the manipulability of `chain` at `point_m` of its last body.
    Dexterity {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// Bodies joined in order, base first (at least 2).
        chain: Vec<String>,
        /// The point x on the last body, body frame, metres.
        point_m: [f64; 3],
        /// Task directions (world, 1–3, independent); empty: x, y, z.
        directions: Vec<[f64; 3]>,
    },
    /// Keep body points at least `distance_m` from an obstacle.
    Obstacle {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// (body, point in its frame), at least one.
        points: Vec<(String, [f64; 3])>,
        /// The obstacle.
        obstacle: ObstacleSpec,
        /// Activation distance D, metres, > 0.
        distance_m: f64,
    },
    /// Keep a body point on a world line.
    StraightLine {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// The body.
        body: String,
        /// The point, body frame, metres.
        point_m: [f64; 3],
        /// A point of the line, world frame, metres.
        line_point_m: [f64; 3],
        /// The line's direction, world frame (non-zero).
        direction: [f64; 3],
    },
    /// Keep joints near the middle of their limits.
    JointLimitDistance {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// Joint names (each with `limits`); empty: every joint with limits.
        joints: Vec<String>,
    },
}

impl ObjectiveSpec {
    /// Its kind.
    pub fn kind(&self) -> ObjectiveKind {
        match self {
            Self::Finger { .. } => ObjectiveKind::Finger,
            Self::LeastAstonishment { .. } => ObjectiveKind::LeastAstonishment,
            Self::Dexterity { .. } => ObjectiveKind::Dexterity,
            Self::Obstacle { .. } => ObjectiveKind::Obstacle,
            Self::StraightLine { .. } => ObjectiveKind::StraightLine,
            Self::JointLimitDistance { .. } => ObjectiveKind::JointLimitDistance,
        }
    }

    /// Its weight.
    pub fn weight(&self) -> f64 {
        match *self {
            Self::Finger { weight }
            | Self::LeastAstonishment { weight, .. }
            | Self::Dexterity { weight, .. }
            | Self::Obstacle { weight, .. }
            | Self::StraightLine { weight, .. }
            | Self::JointLimitDistance { weight, .. } => weight,
        }
    }

    /// Its name, if given.
    pub fn name(&self) -> Option<&str> {
        match self {
            Self::Finger { .. } | Self::LeastAstonishment { .. } => None,
            Self::Dexterity { name, .. }
            | Self::Obstacle { name, .. }
            | Self::StraightLine { name, .. }
            | Self::JointLimitDistance { name, .. } => name.as_deref(),
        }
    }
}

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
                    return Err(BuildError::DuplicateName { owner: owner() });
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
                    return Err(BuildError::DuplicateName { owner: owner() });
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
        };
        points.push(f.point(&k0));
    }
    let last = *ids.last().expect("two or more");
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
