//! Compiles one `[[joint]]` or `[[finger]]` spec into constraint geometry,
//! validating it and allocating its design-variable columns.

use std::collections::HashMap;
use std::f64::consts::PI;

use nalgebra::Vector3;

use super::error::{BuildError, Owner};
use super::layout::DesignVar;
use super::spec::{DesignParam, FingerSpec, Grasp, JointKind, JointSpec};
use super::{Body, Finger};
use crate::constraint::axes::JointAxes;
use crate::constraint::block::{Pair, Param1, Param3};
use crate::constraint::limit::{Limit, Limited};
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry};
use crate::constraint::{
    distance::Distance, finger, perpendicular::Perpendicular, point_plane::PointPlane,
    prismatic::Prismatic, revolute::Revolute, spherical::Spherical, universal::Universal,
    weld::Weld,
};
use crate::rotation::BodyFrame;
use crate::{BodyId, ConstraintId};

/// Below this, a world distance between anchors counts as coincident (metres)
/// and a cross product of unit axes counts as parallel.
const DEGENERATE: f64 = 1e-9;

/// Build-time state shared by the joints and fingers of one model.
pub(super) struct Compiler<'a> {
    bodies: &'a [Body],
    by_name: &'a HashMap<&'a str, BodyId>,
    /// Initial frames of every body, then the world.
    frames: &'a [BodyFrame],
    body_cols: &'a [Option<usize>],
    next_col: usize,
    design_vars: Vec<DesignVar>,
    dv_q0: Vec<f64>,
    lever: f64,
}

impl<'a> Compiler<'a> {
    pub fn new(
        bodies: &'a [Body],
        by_name: &'a HashMap<&'a str, BodyId>,
        frames: &'a [BodyFrame],
        body_cols: &'a [Option<usize>],
        first_design_col: usize,
    ) -> Self {
        Self {
            bodies,
            by_name,
            frames,
            body_cols,
            next_col: first_design_col,
            design_vars: Vec::new(),
            dv_q0: Vec::new(),
            lever: 1e-3,
        }
    }

    /// Design variables, their initial values, the total coordinate count and
    /// the characteristic length.
    pub fn finish(self) -> (Vec<DesignVar>, Vec<f64>, usize, f64) {
        (self.design_vars, self.dv_q0, self.next_col, self.lever)
    }

    fn resolve(&self, owner: &Owner, name: &str) -> Result<BodyId, BuildError> {
        self.by_name
            .get(name)
            .copied()
            .ok_or_else(|| BuildError::UnknownBody {
                owner: owner.clone(),
                body: name.to_owned(),
            })
    }

    fn free(&mut self, joint: ConstraintId, name: &str, param: DesignParam, init: &[f64]) -> usize {
        let offset = self.next_col;
        self.design_vars.push(DesignVar {
            name: format!("{name}.{param}"),
            joint,
            param,
            offset,
            width: init.len(),
        });
        self.dv_q0.extend_from_slice(init);
        self.next_col += init.len();
        offset
    }
}

fn finite(owner: &Owner, field: &'static str, v: &[f64]) -> Result<(), BuildError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(BuildError::NonFinite {
            owner: owner.clone(),
            field,
        })
    }
}

fn unit(owner: &Owner, field: &'static str, v: [f64; 3]) -> Result<Vector3<f64>, BuildError> {
    let v = Vector3::from(v);
    let n = v.norm();
    if n > DEGENERATE {
        Ok(v / n)
    } else {
        Err(BuildError::ZeroAxis {
            owner: owner.clone(),
            field,
        })
    }
}

fn constraint_kind(kind: JointKind) -> ConstraintKind {
    match kind {
        JointKind::Spherical => ConstraintKind::Spherical,
        JointKind::Revolute => ConstraintKind::Revolute,
        JointKind::Universal => ConstraintKind::Universal,
        JointKind::Prismatic => ConstraintKind::Prismatic,
        JointKind::Fixed => ConstraintKind::Fixed,
        JointKind::Distance => ConstraintKind::Distance,
        JointKind::Perpendicular => ConstraintKind::Perpendicular,
        JointKind::PointOnPlane => ConstraintKind::PointOnPlane,
    }
}

type Compiled = (ConstraintInfo, Geometry, Option<(ConstraintInfo, Geometry)>);

/// Validates the `k`-th joint and compiles it (and its limits, if any).
pub(super) fn compile_joint(
    k: usize,
    s: &JointSpec,
    cx: &mut Compiler,
) -> Result<Compiled, BuildError> {
    let name = match &s.name {
        Some(n) if n.is_empty() => {
            return Err(BuildError::EmptyName {
                owner: Owner::Joint(format!("#{}", k + 1)),
            });
        }
        Some(n) => n.clone(),
        None => format!("#{}", k + 1),
    };
    let owner = Owner::Joint(name.clone());
    let id = ConstraintId(k as u32);
    let b = [
        cx.resolve(&owner, &s.bodies[0])?,
        cx.resolve(&owner, &s.bodies[1])?,
    ];
    if b[0] == b[1] {
        return Err(BuildError::SameBody {
            owner,
            body: s.bodies[0].clone(),
        });
    }
    if b.iter().all(|b| cx.bodies[b.index()].fixed) {
        return Err(BuildError::BothFixed { owner });
    }
    finite(&owner, "anchors", s.anchors_m.as_flattened())?;
    if let Some(axes) = &s.axes {
        finite(&owner, "axes", axes.as_flattened())?;
    }
    finite(&owner, "length", s.length_m.as_slice())?;
    finite(
        &owner,
        "limits",
        s.limits.as_ref().map_or(&[][..], |l| &l[..]),
    )?;
    for (i, p) in s.free.iter().enumerate() {
        if s.free[..i].contains(p) {
            return Err(BuildError::DuplicateFree { owner, param: *p });
        }
        let ok = match p {
            DesignParam::Length => s.kind == JointKind::Distance,
            _ => s.kind != JointKind::Perpendicular,
        };
        if !ok {
            return Err(BuildError::UnsupportedFree {
                owner,
                kind: s.kind,
                param: *p,
            });
        }
    }
    if s.length_m.is_some() && s.kind != JointKind::Distance {
        return Err(BuildError::UnexpectedLength {
            owner,
            kind: s.kind,
        });
    }
    let needs_axes = matches!(
        s.kind,
        JointKind::Revolute
            | JointKind::Universal
            | JointKind::Prismatic
            | JointKind::Perpendicular
            | JointKind::PointOnPlane
    );
    let axes = match (&s.axes, needs_axes) {
        (None, true) => {
            return Err(BuildError::MissingAxes {
                owner,
                kind: s.kind,
            });
        }
        (Some(a), true) if s.kind == JointKind::PointOnPlane => {
            let n = unit(&owner, "axes[1]", a[1])?;
            [n, n]
        }
        (Some(a), true) => [
            unit(&owner, "axes[0]", a[0])?,
            unit(&owner, "axes[1]", a[1])?,
        ],
        _ => [Vector3::z(); 2],
    };

    let f = [cx.frames[b[0].index()], cx.frames[b[1].index()]];
    let mut anchor = [0, 1].map(|e| Param3::Const(Vector3::from(s.anchors_m[e])));
    if s.kind == JointKind::Perpendicular {
        anchor = [Param3::Const(Vector3::zeros()); 2];
    }
    for a in &s.anchors_m {
        cx.lever = cx.lever.max(Vector3::from(*a).norm());
    }
    let world_anchor = |e: usize| f[e].point(&Vector3::from(s.anchors_m[e]));
    let initial_length = (world_anchor(0) - world_anchor(1)).norm();
    let mut length = Param1::Const(s.length_m.unwrap_or(initial_length));
    for p in &s.free {
        match p {
            DesignParam::AnchorI => {
                anchor[0] = Param3::Free(cx.free(id, &name, *p, &s.anchors_m[0]))
            }
            DesignParam::AnchorJ => {
                anchor[1] = Param3::Free(cx.free(id, &name, *p, &s.anchors_m[1]))
            }
            DesignParam::Length => {
                let Param1::Const(l) = length else { continue };
                length = Param1::Free(cx.free(id, &name, *p, &[l]));
            }
        }
    }
    let pair = Pair {
        frame: [b[0].index(), b[1].index()],
        col: [cx.body_cols[b[0].index()], cx.body_cols[b[1].index()]],
        anchor,
    };
    let perpendicular_ok = || {
        let c = (f[0].rot * axes[0]).cross(&(f[1].rot * axes[1]));
        if c.norm() > DEGENERATE {
            Ok(())
        } else {
            Err(BuildError::ParallelAxes {
                owner: owner.clone(),
                kind: s.kind,
            })
        }
    };
    let joint_axes = || JointAxes::new(axes[0], axes[1], &f[0].rot, &f[1].rot);
    let geometry = match s.kind {
        JointKind::Spherical => Geometry::Spherical(Spherical { pair }),
        JointKind::Universal => {
            perpendicular_ok()?;
            Geometry::Universal(Universal { pair, axes })
        }
        JointKind::Perpendicular => {
            perpendicular_ok()?;
            Geometry::Perpendicular(Perpendicular { pair, axes })
        }
        JointKind::Revolute => Geometry::Revolute(Revolute {
            pair,
            axes: joint_axes(),
        }),
        JointKind::Prismatic => Geometry::Prismatic(Prismatic {
            pair,
            axes: joint_axes(),
        }),
        JointKind::Fixed => Geometry::Weld(Weld {
            pair,
            relative: f[1].rot.tr_mul(&f[0].rot),
        }),
        JointKind::PointOnPlane => Geometry::PointPlane(PointPlane {
            pair,
            normal: axes[1],
        }),
        JointKind::Distance => {
            if initial_length < DEGENERATE {
                return Err(BuildError::CoincidentAnchors { owner });
            }
            if let Some(l) = s.length_m.filter(|l| *l <= 0.0) {
                return Err(BuildError::NonPositiveLength { owner, length_m: l });
            }
            Geometry::Distance(Distance { pair, length })
        }
    };
    let info = |name: String, kind| ConstraintInfo {
        name,
        kind,
        rows: 0..0,
        bodies: [Some(b[0]), Some(b[1])],
        finger: None,
        limits: None,
    };
    let limit = match s.limits {
        None => None,
        Some([lo, hi]) => Some(compile_limit(&owner, s, &geometry, lo, hi)?)
            .map(|(kind, g)| (info(format!("{name}.limits"), kind), g)),
    };
    Ok((info(name, constraint_kind(s.kind)), geometry, limit))
}

fn compile_limit(
    owner: &Owner,
    s: &JointSpec,
    geometry: &Geometry,
    lo: f64,
    hi: f64,
) -> Result<(ConstraintKind, Geometry), BuildError> {
    let owner = || owner.clone();
    let (kind, joint) = match *geometry {
        Geometry::Revolute(j) => (ConstraintKind::RevoluteLimit, Limited::Angle(j)),
        Geometry::Prismatic(j) => (ConstraintKind::PrismaticLimit, Limited::Displacement(j)),
        Geometry::Distance(j) => (ConstraintKind::DistanceLimit, Limited::Length(j)),
        _ => {
            return Err(BuildError::LimitsUnsupported {
                owner: owner(),
                kind: s.kind,
            });
        }
    };
    if lo > hi {
        return Err(BuildError::LimitsReversed {
            owner: owner(),
            lo,
            hi,
        });
    }
    if kind == ConstraintKind::RevoluteLimit && (lo <= -PI || hi >= PI) {
        return Err(BuildError::AngleLimitsOutOfRange {
            owner: owner(),
            lo,
            hi,
        });
    }
    if let Limited::Length(Distance {
        length: Param1::Const(l),
        ..
    }) = joint
        && (l < lo || l > hi)
    {
        return Err(BuildError::LengthOutsideLimits {
            owner: owner(),
            length_m: l,
            lo,
            hi,
        });
    }
    Ok((kind, Geometry::Limit(Limit { joint, lo, hi })))
}

/// Validates the `k`-th finger and compiles its constraint.
pub(super) fn compile_finger(
    k: usize,
    s: &FingerSpec,
    constraint: ConstraintId,
    cx: &mut Compiler,
) -> Result<(Finger, ConstraintInfo, Geometry), BuildError> {
    if s.name.is_empty() {
        return Err(BuildError::EmptyName {
            owner: Owner::Finger(format!("#{}", k + 1)),
        });
    }
    let owner = Owner::Finger(s.name.clone());
    let body = cx.resolve(&owner, &s.body)?;
    let Some(col) = cx.body_cols[body.index()] else {
        return Err(BuildError::FingerOnFixedBody {
            owner,
            body: s.body.clone(),
        });
    };
    finite(&owner, "point", &s.point_m)?;
    let point = Vector3::from(s.point_m);
    cx.lever = cx.lever.max(point.norm());
    let world = cx.frames.len() - 1;
    let pair = Pair {
        frame: [body.index(), world],
        col: [Some(col), None],
        anchor: [Param3::Const(point), Param3::Const(Vector3::zeros())],
    };
    let rigid = s.grasp == Grasp::Rigid;
    let kind = if rigid {
        ConstraintKind::RigidFinger
    } else {
        ConstraintKind::PointFinger
    };
    let finger = Finger {
        name: s.name.clone(),
        body,
        point_m: point,
        grasp: s.grasp,
        constraint,
    };
    let info = ConstraintInfo {
        name: s.name.clone(),
        kind,
        rows: 0..0,
        bodies: [Some(body), None],
        finger: Some(crate::FingerId(k as u32)),
        limits: None,
    };
    Ok((
        finger,
        info,
        Geometry::Finger(finger::Finger {
            pair,
            finger: k,
            rigid,
        }),
    ))
}
