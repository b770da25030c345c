//! Compiles one `[[joint]]` spec (and its limits) into constraint geometry,
//! validating it and allocating its design-variable columns.

use std::f64::consts::PI;

use nalgebra::Vector3;

use super::compiler::{Compiler, DEGENERATE, check_bounds, finite, in_range, unit};
use super::error::{BuildError, Owner};
use super::layout::DesignOwner;
use super::spec::{DesignParam, JointKind, JointSpec};
use crate::constraint::axes::JointAxes;
use crate::constraint::block::{Pair, Param1, Param3};
use crate::constraint::limit::{Limit, Limited};
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry};
use crate::constraint::{
    distance::Distance, perpendicular::Perpendicular, point_plane::PointPlane,
    prismatic::Prismatic, revolute::Revolute, spherical::Spherical, universal::Universal,
    weld::Weld,
};
use crate::{BodyId, ConstraintId};

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
        JointKind::OnSurface | JointKind::Rolling => ConstraintKind::OnSurface,
    }
}

/// A joint's constraint, its limits', and a rolling joint's no-slip rows
/// (appended among the equalities after the quaternion norms).
type Compiled = (
    ConstraintInfo,
    Geometry,
    Option<(ConstraintInfo, Geometry)>,
    Option<(ConstraintInfo, Geometry)>,
);

/// A joint spec whose names resolved and whose numbers are finite and
/// consistent with its kind.
struct Checked<'s> {
    spec: &'s JointSpec,
    name: String,
    owner: Owner,
    bodies: [BodyId; 2],
    /// Unit body-frame axes (`[n, n]` for a plane normal; unused kinds: z).
    axes: [Vector3<f64>; 2],
}

/// Validates the `k`-th joint and compiles it (and its limits, if any).
pub(super) fn compile_joint(
    k: usize,
    s: &JointSpec,
    cx: &mut Compiler,
) -> Result<Compiled, BuildError> {
    let j = check(k, s, cx)?;
    let (pair, length) = params(&j, ConstraintId(k as u32), cx)?;
    let geometry = match s.kind {
        JointKind::OnSurface | JointKind::Rolling => surface_contact(&j, pair, cx)?,
        _ => geometry(&j, pair, length, cx)?,
    };
    let info = |name: String, kind| ConstraintInfo {
        name,
        kind,
        rows: 0..0,
        bodies: j.bodies.map(Some),
        finger: None,
        limits: None,
    };
    let limit = match s.limits {
        None => None,
        Some([lo, hi]) => {
            let (kind, g) = compile_limit(&j.owner, s, &geometry, lo, hi)?;
            Some((info(format!("{}.limits", j.name), kind), g))
        }
    };
    let rolling = match (s.kind, geometry) {
        (JointKind::Rolling, Geometry::OnSurface(g)) => Some((
            info(format!("{}.roll", j.name), ConstraintKind::Rolling),
            Geometry::Rolling(crate::parametric::rolling::Rolling {
                pair: g.pair,
                contact: g.index,
                slot: 0, // assigned by the builder
            }),
        )),
        _ => None,
    };
    Ok((
        info(j.name.clone(), constraint_kind(s.kind)),
        geometry,
        limit,
        rolling,
    ))
}

/// An `on_surface` or `rolling` joint: its surface registered with the
/// compiler (initial (u, v) by projecting anchor i at the initial poses).
fn surface_contact(j: &Checked, pair: Pair, cx: &mut Compiler) -> Result<Geometry, BuildError> {
    let s = j.spec;
    let bad = |field: &'static str, why: String| BuildError::Surface {
        owner: j.owner.clone(),
        field,
        why,
    };
    let Some(spec) = s.surface else {
        return Err(bad(
            "surface",
            format!("a `{}` joint needs a `surface`", s.kind),
        ));
    };
    let radius = s.radius_m.unwrap_or(0.0);
    if !(0.0..=10.0).contains(&radius) {
        return Err(bad(
            "radius",
            format!("`radius` = {radius} must be finite, in [0, 10] m"),
        ));
    }
    if s.kind == JointKind::Rolling && radius <= 0.0 {
        return Err(bad(
            "radius",
            "a `rolling` joint needs the ball's `radius` > 0".into(),
        ));
    }
    let [bi, bj] = j.bodies.map(|b| b.index());
    if cx.is_flexible(j.bodies[1]) {
        return Err(bad(
            "kind",
            format!(
                "the surface's body `{}` is flexible: a surface does not bend",
                s.bodies[1]
            ),
        ));
    }
    if s.kind == JointKind::Rolling {
        if !cx.bodies[bj].fixed || cx.bodies[bi].fixed {
            return Err(bad(
                "kind",
                "a `rolling` joint rolls a moving ball (body i) on a fixed body's surface (body j)"
                    .into(),
            ));
        }
        if !matches!(pair.anchor[0], Param3::Const(_)) {
            return Err(bad(
                "kind",
                format!("the rolling ball `{}` must be rigid", s.bodies[0]),
            ));
        }
    }
    if !s.free.is_empty() {
        return Err(bad(
            "kind",
            format!("a `{}` joint has no design variables", s.kind),
        ));
    }
    let surface = crate::parametric::surface::check(&spec).map_err(|why| bad("surface", why))?;
    let (f0, f1) = (cx.frames[bi], cx.frames[bj]);
    let p = f1
        .rot
        .tr_mul(&(f0.point(&Vector3::from(s.anchors_m[0])) - f1.r));
    let ([u, v], _) = surface.project(&p, radius);
    if !surface.covers(u, v) {
        return Err(bad(
            "anchors",
            format!(
                "anchor i at the initial poses lies off the surface's patch (u, v) = ({u}, {v})"
            ),
        ));
    }
    let mass = [bi, bj]
        .iter()
        .find(|&&b| !cx.bodies[b].fixed)
        .map_or(1.0, |&b| cx.bodies[b].mass_kg);
    let contact = crate::parametric::SurfaceContact {
        surface,
        radius_m: radius,
        uv_col: 0,
    };
    let index = cx.surface(
        &j.name,
        contact,
        [u, v],
        crate::parametric::UV_METRIC * mass,
    );
    Ok(Geometry::OnSurface(crate::parametric::contact::OnSurface {
        pair,
        index,
    }))
}

/// Names, bodies, finiteness, design variables, `length` and `axes`.
fn check<'s>(k: usize, s: &'s JointSpec, cx: &Compiler) -> Result<Checked<'s>, BuildError> {
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
    let bodies = [
        cx.resolve(&owner, &s.bodies[0])?,
        cx.resolve(&owner, &s.bodies[1])?,
    ];
    if bodies[0] == bodies[1] {
        return Err(BuildError::SameBody {
            owner,
            body: s.bodies[0].clone(),
        });
    }
    if bodies.iter().all(|b| cx.bodies[b.index()].fixed) {
        return Err(BuildError::BothFixed { owner });
    }
    in_range(&owner, "anchors", s.anchors_m.as_flattened())?;
    finite(
        &owner,
        "axes",
        s.axes.as_ref().map_or(&[][..], |a| a.as_flattened()),
    )?;
    in_range(&owner, "length", s.length_m.as_slice())?;
    finite(
        &owner,
        "limits",
        s.limits.as_ref().map_or(&[][..], |l| &l[..]),
    )?;
    for (i, &param) in s.free.iter().enumerate() {
        if s.free[..i].contains(&param) {
            return Err(BuildError::DuplicateFree { owner, param });
        }
        let supported = match param {
            DesignParam::Length => s.kind == JointKind::Distance,
            DesignParam::Position => false,
            _ => s.kind != JointKind::Perpendicular,
        };
        if !supported {
            return Err(BuildError::UnsupportedFree {
                owner,
                kind: s.kind,
                param,
            });
        }
    }
    let surface_kind = matches!(s.kind, JointKind::OnSurface | JointKind::Rolling);
    if !surface_kind && (s.surface.is_some() || s.radius_m.is_some()) {
        return Err(BuildError::Surface {
            owner,
            field: if s.surface.is_some() {
                "surface"
            } else {
                "radius"
            },
            why: format!(
                "`surface` and `radius` belong to `on_surface` and `rolling` joints, not `{}`",
                s.kind
            ),
        });
    }
    if s.length_m.is_some() && s.kind != JointKind::Distance {
        return Err(BuildError::UnexpectedLength {
            owner,
            kind: s.kind,
        });
    }
    use JointKind as K;
    let needs_axes = matches!(
        s.kind,
        K::Revolute | K::Universal | K::Prismatic | K::Perpendicular | K::PointOnPlane
    );
    let axes = match (&s.axes, needs_axes) {
        (None, true) => {
            return Err(BuildError::MissingAxes {
                owner,
                kind: s.kind,
            });
        }
        (Some(a), true) if s.kind == K::PointOnPlane => [unit(&owner, "axes[1]", a[1])?; 2],
        (Some(a), true) => [
            unit(&owner, "axes[0]", a[0])?,
            unit(&owner, "axes[1]", a[1])?,
        ],
        _ => [Vector3::z(); 2],
    };
    Ok(Checked {
        spec: s,
        name,
        owner,
        bodies,
        axes,
    })
}

/// The two ends and the length, with design-variable columns allocated in the
/// order `free` lists them (after checking `bounds` against their initial
/// values). The default length is the anchors' initial distance.
fn params(j: &Checked, id: ConstraintId, cx: &mut Compiler) -> Result<(Pair, Param1), BuildError> {
    let s = j.spec;
    let mut anchor = s.anchors_m.map(|a| Param3::Const(Vector3::from(a)));
    if s.kind == JointKind::Perpendicular {
        anchor = [Param3::Const(Vector3::zeros()); 2];
    }
    let [bi, bj] = j.bodies.map(|b| b.index());
    let [f0, f1] = [bi, bj].map(|b| cx.frames[b]);
    let initial = (f0.point(&Vector3::from(s.anchors_m[0]))
        - f1.point(&Vector3::from(s.anchors_m[1])))
    .norm();
    let l0 = s.length_m.unwrap_or(initial);
    let mut length = Param1::Const(l0);
    for a in &s.anchors_m {
        cx.lever = cx.lever.max(Vector3::from(*a).norm());
    }
    let inits: Vec<(DesignParam, &[f64])> = s
        .free
        .iter()
        .map(|&p| match p {
            DesignParam::AnchorI => (p, &s.anchors_m[0][..]),
            DesignParam::AnchorJ => (p, &s.anchors_m[1][..]),
            _ => (p, std::slice::from_ref(&l0)),
        })
        .collect();
    check_bounds(&j.owner, &j.name, s.bounds.as_ref(), &inits)?;
    let owner = DesignOwner::Joint(id);
    let bounds = s.bounds.as_ref();
    for &p in &s.free {
        match (p, length) {
            (DesignParam::AnchorI, _) => {
                anchor[0] = Param3::Free(cx.free(owner, &j.name, p, &s.anchors_m[0], bounds))
            }
            (DesignParam::AnchorJ, _) => {
                anchor[1] = Param3::Free(cx.free(owner, &j.name, p, &s.anchors_m[1], bounds))
            }
            (DesignParam::Length, Param1::Const(l)) => {
                length = Param1::Free(cx.free(owner, &j.name, p, &[l], bounds))
            }
            (DesignParam::Length, Param1::Free(_)) | (DesignParam::Position, _) => {}
        }
    }
    // Points of flexible bodies deform with them (`crate::flexible`).
    for (end, a) in anchor.iter_mut().enumerate() {
        let body = j.bodies[end];
        if !cx.is_flexible(body) {
            continue;
        }
        *a = match *a {
            Param3::Const(k) => cx.anchor(&j.owner, body, k)?,
            _ => {
                return Err(BuildError::Flexible {
                    owner: j.owner.clone(),
                    why: format!(
                        "the anchor on flexible body `{}` cannot be a design variable",
                        s.bodies[end]
                    ),
                });
            }
        };
    }
    let uses_axes = |end: usize| match s.kind {
        JointKind::Spherical
        | JointKind::Distance
        | JointKind::Perpendicular
        | JointKind::OnSurface
        | JointKind::Rolling => false,
        JointKind::PointOnPlane => end == 1,
        _ => true,
    };
    for (end, a) in anchor.iter().enumerate() {
        if uses_axes(end) && matches!(a, Param3::Flex(_)) {
            return Err(BuildError::Flexible {
                owner: j.owner.clone(),
                why: format!(
                    "a `{}` joint uses the axes of flexible body `{}`, which are its section's at \
                     its clamp only: anchor it there (or use a spherical or distance joint)",
                    s.kind, s.bodies[end]
                ),
            });
        }
    }
    let pair = Pair {
        frame: [bi, bj],
        col: [cx.body_cols[bi], cx.body_cols[bj]],
        anchor,
    };
    Ok((pair, length))
}

/// The kind-specific geometry, checked for degeneracy at the initial poses.
fn geometry(
    j: &Checked,
    pair: Pair,
    length: Param1,
    cx: &Compiler,
) -> Result<Geometry, BuildError> {
    let (s, axes, owner) = (j.spec, j.axes, || j.owner.clone());
    let f = j.bodies.map(|b| cx.frames[b.index()]);
    let perpendicular_ok = || {
        let c = (f[0].rot * axes[0]).cross(&(f[1].rot * axes[1]));
        if c.norm() > DEGENERATE {
            Ok(())
        } else {
            Err(BuildError::ParallelAxes {
                owner: owner(),
                kind: s.kind,
            })
        }
    };
    let joint_axes = || JointAxes::new(axes[0], axes[1], &f[0].rot, &f[1].rot);
    Ok(match s.kind {
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
            if let Some(l) = s.length_m.filter(|l| *l <= 0.0) {
                return Err(BuildError::NonPositiveLength {
                    owner: owner(),
                    length_m: l,
                });
            }
            let [p0, p1] = [0, 1].map(|e| f[e].point(&Vector3::from(s.anchors_m[e])));
            if (p0 - p1).norm() < DEGENERATE {
                return Err(BuildError::CoincidentAnchors { owner: owner() });
            }
            Geometry::Distance(Distance { pair, length })
        }
        JointKind::OnSurface | JointKind::Rolling => {
            unreachable!("surface joints compile in `surface_contact`")
        }
    })
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
