//! Point–plane inequalities added at run time (contact witnesses): a derived
//! model with the same bodies, layout, joints and fingers plus extra `≥ 0` rows
//! appended after all existing rows, so every existing `ConstraintId` and row
//! index keeps its meaning.

use nalgebra::Vector3;

use super::assembler::Assembler;
use super::error::{BuildError, Owner};
use super::{Model, next_model_id};
use crate::BodyId;
use crate::constraint::block::{Pair, Param3};
use crate::constraint::point_plane::PointPlane;
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry};

/// What carries the plane of a point–plane inequality.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlaneOwner {
    /// A static plane, world frame.
    World,
    /// A plane attached to a body (moving or fixed), body frame.
    Body(BodyId),
}

/// N·(P − P₀) ≥ 0: the point P (on `body`) stays on the side of the plane
/// through P₀ that the normal N points to. Metres.
#[derive(Debug, Clone, PartialEq)]
pub struct PointPlaneSpec {
    /// Used in errors and [`ConstraintInfo::name`]; need not be unique.
    pub name: String,
    /// The body carrying the point.
    pub body: BodyId,
    /// The point, metres, in `body`'s frame.
    pub point_m: [f64; 3],
    /// The body (or world) carrying the plane.
    pub plane: PlaneOwner,
    /// A point of the plane, metres, in the plane owner's frame.
    pub plane_point_m: [f64; 3],
    /// The plane normal in the plane owner's frame (normalised here).
    pub normal: [f64; 3],
}

impl Model {
    /// A new model equal to this one plus the given point–plane inequalities,
    /// appended (in order) after every existing constraint and row. Allocates;
    /// call it off the real-time thread. The new model has a new identity, so
    /// an [`Evaluation`](crate::Evaluation) of this model refuses it.
    pub fn with_inequalities(&self, specs: &[PointPlaneSpec]) -> Result<Model, BuildError> {
        let mut out = Assembler {
            infos: self.constraints.clone(),
            geometry: self.geometry.clone(),
            rows: self.rows.clone(),
        };
        let world = self.bodies.len();
        for s in specs {
            let owner = || Owner::Inequality(s.name.clone());
            if s.name.is_empty() {
                return Err(BuildError::EmptyName { owner: owner() });
            }
            let known = |b: BodyId| {
                if b.index() < self.bodies.len() {
                    Ok(b.index())
                } else {
                    Err(BuildError::UnknownBody {
                        owner: owner(),
                        body: b.to_string(),
                    })
                }
            };
            let i = known(s.body)?;
            let j = match s.plane {
                PlaneOwner::World => world,
                PlaneOwner::Body(b) => known(b)?,
            };
            if i == j {
                return Err(BuildError::SameBody {
                    owner: owner(),
                    body: self.bodies[i].name.clone(),
                });
            }
            let col = |k: usize| {
                if k == world {
                    None
                } else {
                    self.layout.body_cols[k]
                }
            };
            if col(i).is_none() && col(j).is_none() {
                return Err(BuildError::BothFixed { owner: owner() });
            }
            for (field, v) in [
                ("point", &s.point_m),
                ("plane_point", &s.plane_point_m),
                ("normal", &s.normal),
            ] {
                if !v.iter().all(|x| x.is_finite()) {
                    return Err(BuildError::NonFinite {
                        owner: owner(),
                        field,
                    });
                }
            }
            let n = Vector3::from(s.normal);
            if n.norm() <= 1e-9 {
                return Err(BuildError::ZeroAxis {
                    owner: owner(),
                    field: "normal",
                });
            }
            let pair = Pair {
                frame: [i, j],
                col: [col(i), col(j)],
                anchor: [
                    Param3::Const(s.point_m.into()),
                    Param3::Const(s.plane_point_m.into()),
                ],
            };
            let info = ConstraintInfo {
                name: s.name.clone(),
                kind: ConstraintKind::PointPlaneInequality,
                rows: 0..0,
                bodies: [Some(s.body), (j != world).then_some(BodyId(j as u32))],
                finger: None,
                limits: None,
            };
            out.push(
                info,
                Geometry::PointPlane(PointPlane {
                    pair,
                    normal: n.normalize(),
                }),
            );
        }
        Ok(Model {
            id: next_model_id(),
            geometry: out.geometry,
            constraints: out.infos,
            rows: out.rows,
            ..self.clone()
        })
    }
}
