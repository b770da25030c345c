//! Build-time state shared by the joints and fingers of one model: body lookup
//! by name, initial frames, design-variable column allocation; and the finger
//! compiler.

use std::collections::HashMap;

use nalgebra::Vector3;

use super::error::{BuildError, Owner};
use super::layout::{DesignOwner, DesignVar};
use super::spec::{DesignParam, FingerSpec, Grasp};
use super::{Body, Finger};
use crate::constraint::block::{Pair, Param3};
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry, finger};
use crate::rotation::BodyFrame;
use crate::{BodyId, ConstraintId, FingerId};

/// Below this, a world distance between anchors counts as coincident (metres)
/// and a cross product of unit axes counts as parallel.
pub(super) const DEGENERATE: f64 = 1e-9;

/// Build-time state shared by the joints and fingers of one model.
pub(super) struct Compiler<'a> {
    pub bodies: &'a [Body],
    by_name: &'a HashMap<&'a str, BodyId>,
    /// Initial frames of every body, then the world.
    pub frames: &'a [BodyFrame],
    pub body_cols: &'a [Option<usize>],
    next_col: usize,
    design_vars: Vec<DesignVar>,
    dv_q0: Vec<f64>,
    pub lever: f64,
    /// Per body: its index among the flexible bodies.
    flexible: Vec<Option<usize>>,
    /// The flexible bodies (columns assigned by `finish`).
    pub flex_bodies: Vec<crate::flexible::body::FlexBody>,
    /// Deforming anchors, their columns relative to their body's block
    /// until `finish`.
    anchors: Vec<crate::flexible::anchor::FlexAnchor>,
    /// Per anchor: its flexible body.
    anchor_body: Vec<usize>,
    /// Surface contacts (their (u, v) columns assigned by `finish`), each
    /// with its joint's name, initial (u, v) and metric, kg/m².
    surfaces: Vec<(crate::parametric::SurfaceContact, String, [f64; 2], f64)>,
}

/// What [`Compiler::finish`] hands back.
pub(super) struct Finished {
    pub design_vars: Vec<DesignVar>,
    /// Initial values of the design variables, then of the surface
    /// contacts' (u, v); the flexible deformations start at 0.
    pub q0_tail: Vec<f64>,
    pub len: usize,
    pub lever: f64,
    pub flex_bodies: Vec<crate::flexible::body::FlexBody>,
    pub anchors: Vec<crate::flexible::anchor::FlexAnchor>,
    pub surfaces: Vec<crate::parametric::SurfaceContact>,
    /// The auxiliary blocks, in column order: surface contacts' (u, v),
    /// then flexible deformations (rest 0 last, as `program::objective`
    /// needs).
    pub aux: Vec<super::auxiliary::AuxBlock>,
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
            flexible: vec![None; bodies.len()],
            flex_bodies: Vec::new(),
            anchors: Vec::new(),
            anchor_body: Vec::new(),
            surfaces: Vec::new(),
        }
    }

    /// Registers a surface contact of joint `name` starting at `uv0` with
    /// metric `metric_kg` per m² on (u, v); its index.
    pub fn surface(
        &mut self,
        name: &str,
        contact: crate::parametric::SurfaceContact,
        uv0: [f64; 2],
        metric_kg: f64,
    ) -> u32 {
        self.surfaces
            .push((contact, name.to_owned(), uv0, metric_kg));
        self.surfaces.len() as u32 - 1
    }

    /// Declares `body` flexible (its beam compiled).
    pub fn flexible(&mut self, body: BodyId, beam: crate::flexible::body::FlexBody) {
        self.flexible[body.index()] = Some(self.flex_bodies.len());
        self.flex_bodies.push(beam);
    }

    /// Whether `body` is flexible.
    pub fn is_flexible(&self, body: BodyId) -> bool {
        self.flexible[body.index()].is_some()
    }

    /// The clamp x of flexible body `body`, metres.
    pub fn clamp_of(&self, body: BodyId) -> Option<f64> {
        let k = self.flexible[body.index()]?;
        Some(self.flex_bodies[k].beam.spec.clamp_m)
    }

    /// The parameter of body point `k` of `body` (body frame): a constant,
    /// or on a flexible body off its clamp a deforming anchor. A point
    /// beyond the beam's span is an error.
    pub fn anchor(
        &mut self,
        owner: &Owner,
        body: BodyId,
        k: Vector3<f64>,
    ) -> Result<Param3, BuildError> {
        let Some(fb) = self.flexible[body.index()] else {
            return Ok(Param3::Const(k));
        };
        let beam = &self.flex_bodies[fb].beam;
        if !beam.covers(k.x) {
            let [x0, x1] = beam.spec.span_m;
            return Err(BuildError::Flexible {
                owner: owner.clone(),
                why: format!(
                    "the point at x = {} m of flexible body `{}` lies off its span [{x0}, {x1}] m",
                    k.x,
                    self.bodies[body.index()].name
                ),
            });
        }
        let a = crate::flexible::anchor::FlexAnchor {
            k,
            col: 0,
            modes: beam.modes(),
            shape: beam.shape(k.x),
        };
        if a.is_rigid() {
            return Ok(Param3::Const(k));
        }
        self.anchors.push(a);
        self.anchor_body.push(fb);
        Ok(Param3::Flex(self.anchors.len() as u32 - 1))
    }

    /// Assigns the auxiliary columns after the design variables (surface
    /// contacts, then flexible bodies) and hands everything back.
    pub fn finish(mut self) -> Result<Finished, BuildError> {
        use super::auxiliary::{AuxBlock, AuxOwner, Rest};
        let mut col = self.next_col;
        let mut aux = Vec::new();
        let mut q0_tail = self.dv_q0;
        let mut surfaces = Vec::with_capacity(self.surfaces.len());
        for (k, (mut sc, name, uv0, metric)) in self.surfaces.into_iter().enumerate() {
            sc.uv_col = col;
            let h = nalgebra::DMatrix::from_diagonal_element(2, 2, metric);
            aux.extend(AuxBlock::new(
                format!("{name}.uv"),
                AuxOwner::Surface(k),
                Rest::Current,
                col,
                &h,
            ));
            q0_tail.extend_from_slice(&uv0);
            surfaces.push(sc);
            col += 2;
        }
        for (k, fb) in self.flex_bodies.iter_mut().enumerate() {
            fb.col = col;
            let name = format!("{}.flex", self.bodies[fb.body.index()].name);
            let block = AuxBlock::new(
                name,
                AuxOwner::Flexible(k),
                Rest::Zero,
                col,
                &fb.beam.stiffness(),
            )
            .ok_or_else(|| BuildError::Flexible {
                owner: Owner::Body(self.bodies[fb.body.index()].name.clone()),
                why: "its stiffness matrix is not positive definite".into(),
            })?;
            aux.push(block);
            col += fb.width();
        }
        for (a, &b) in self.anchors.iter_mut().zip(&self.anchor_body) {
            a.col = self.flex_bodies[b].col;
        }
        Ok(Finished {
            design_vars: self.design_vars,
            q0_tail,
            len: col,
            lever: self.lever,
            flex_bodies: self.flex_bodies,
            anchors: self.anchors,
            surfaces,
            aux,
        })
    }

    pub fn resolve(&self, owner: &Owner, name: &str) -> Result<BodyId, BuildError> {
        self.by_name
            .get(name)
            .copied()
            .ok_or_else(|| BuildError::UnknownBody {
                owner: owner.clone(),
                body: name.to_owned(),
            })
    }

    /// Allocates the columns of one design variable of `owner` (named
    /// `"<name>.<param>"`), starting at `init`, with optional per-component
    /// bounds (already checked).
    pub fn free(
        &mut self,
        owner: DesignOwner,
        name: &str,
        param: DesignParam,
        init: &[f64],
        bounds: Option<&super::spec::Bounds>,
    ) -> usize {
        let offset = self.next_col;
        self.design_vars.push(DesignVar {
            name: format!("{name}.{param}"),
            owner,
            param,
            offset,
            width: init.len(),
            bounds: bounds.map(|b| [0, 1, 2].map(|k| b.component(k))),
        });
        self.dv_q0.extend_from_slice(init);
        self.next_col += init.len();
        offset
    }
}

pub(super) fn finite(owner: &Owner, field: &'static str, v: &[f64]) -> Result<(), BuildError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(BuildError::NonFinite {
            owner: owner.clone(),
            field,
        })
    }
}

/// Largest |coordinate| a model accepts for positions, anchors, lengths and
/// finger points, m. A scene is a mechanism in a room, not the solar system:
/// beyond this, squared distances lose every digit a joint needs (the
/// 1e200-metre anchor that made the gain check divide ∞ by ∞).
pub const MAX_COORDINATE_M: f64 = 1e4;

/// Ok if every entry of `v` is within ±[`MAX_COORDINATE_M`] (NaN is caught
/// by [`finite`] first).
pub(super) fn in_range(owner: &Owner, field: &'static str, v: &[f64]) -> Result<(), BuildError> {
    finite(owner, field, v)?;
    match v.iter().find(|x| x.abs() > MAX_COORDINATE_M) {
        None => Ok(()),
        Some(&value) => Err(BuildError::OutOfRange {
            owner: owner.clone(),
            field,
            value,
        }),
    }
}

pub(super) fn unit(
    owner: &Owner,
    field: &'static str,
    v: [f64; 3],
) -> Result<Vector3<f64>, BuildError> {
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

/// Checks `bounds` against the variables an entry frees: `(param, initial
/// value)` each, named `"<name>.<param>"`. Errors name the first problem.
pub(super) fn check_bounds(
    owner: &Owner,
    name: &str,
    bounds: Option<&super::spec::Bounds>,
    vars: &[(DesignParam, &[f64])],
) -> Result<(), BuildError> {
    use super::spec::Bounds;
    let Some(b) = bounds else {
        return Ok(());
    };
    if vars.is_empty() {
        return Err(BuildError::BoundsWithoutFree {
            owner: owner.clone(),
        });
    }
    let flat: &[f64] = match b {
        Bounds::Scalar(v) => v,
        Bounds::Vector(v) => v.as_flattened(),
    };
    finite(owner, "bounds", flat)?;
    for &(param, init) in vars {
        if matches!(b, Bounds::Vector(_)) && init.len() != 3 {
            return Err(BuildError::BoundsShape {
                owner: owner.clone(),
                param,
            });
        }
        for (k, &value) in init.iter().enumerate() {
            let [lo, hi] = b.component(k);
            if lo > hi {
                return Err(BuildError::BoundsReversed {
                    owner: owner.clone(),
                    lo,
                    hi,
                });
            }
            // Written with finite digits: 1 nm of slack.
            if value < lo - 1e-9 || value > hi + 1e-9 {
                let var = if init.len() == 1 {
                    format!("{name}.{param}")
                } else {
                    format!("{name}.{param}.{}", ["x", "y", "z"][k])
                };
                return Err(BuildError::OutsideBounds {
                    owner: owner.clone(),
                    var,
                    value,
                    lo,
                    hi,
                });
            }
        }
    }
    Ok(())
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
    let anchor = cx.anchor(&owner, body, point)?;
    let rigid = s.grasp == Grasp::Rigid;
    let clamp = cx.clamp_of(body).unwrap_or(0.0);
    if rigid && matches!(anchor, Param3::Flex(_)) {
        return Err(BuildError::Flexible {
            owner,
            why: format!(
                "a rigid grasp holds the orientation of flexible body `{}`'s frame, which is its \
                 section at its clamp (x = {} m) only: put the point there, or use a point grasp",
                s.body, clamp
            ),
        });
    }
    let pair = Pair {
        frame: [body.index(), world],
        col: [Some(col), None],
        anchor: [anchor, Param3::Const(Vector3::zeros())],
    };
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
        tip: s.tip,
    };
    let info = ConstraintInfo {
        name: s.name.clone(),
        kind,
        rows: 0..0,
        bodies: [Some(body), None],
        finger: Some(FingerId(k as u32)),
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
