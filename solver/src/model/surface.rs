//! The rows of satisfied semantic surface constraints and of a hand's holds
//! (`crate::semantic` decides which; `constraint/surface.rs` evaluates
//! them): [`Model::with_semantic`] derives a model from a mechanism without
//! any (the scene's), with each surface's three plane rows and each hold's
//! three (spherical) or six (weld) rows inserted at the end of the equality rows (so equalities stay a
//! prefix of C) and each surface's inclusion rows after every inequality.
//! Joints keep their `ConstraintId`s, fingers theirs; the model has a new
//! identity. Contact rows are derived afterwards ([`Model::with_contacts`]),
//! whose witness slots take the head of the table while the surface rows'
//! parameters stay at its tail.

use super::assembler::Assembler;
use super::error::{BuildError, Owner};
use super::{Model, next_model_id};
use crate::constraint::block::{Pair, Param3};
use crate::constraint::spherical::Spherical;
use crate::constraint::surface::SurfaceRows;
use crate::constraint::weld::Weld;
use crate::constraint::witness::{PlaneWitness, WitnessType};
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry, Sense};
use crate::{BodyId, ConstraintId};
use nalgebra::Vector3;

/// One point–plane row of a surface constraint: `normal·(P − P₀) (− offset)`
/// with P on the binding body and the plane on the offer body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceRow {
    /// The point P, binding body frame, m.
    pub point_m: [f64; 3],
    /// A point P₀ of the plane, offer body frame, m.
    pub plane_point_m: [f64; 3],
    /// The plane's normal, offer body frame (normalised here).
    pub normal: [f64; 3],
}

/// A satisfied surface constraint as rows (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceSpec {
    /// Unique among the model's constraints (a hand-over carries its
    /// multipliers and snap offsets by name).
    pub name: String,
    /// The bound body (its binding area's points).
    pub binding: BodyId,
    /// The offering body (its offer area's plane and edges).
    pub offer: BodyId,
    /// Three non-collinear points of the binding area on the offer plane.
    pub plane: [SurfaceRow; 3],
    /// Binding vertices against offer edges (inward normals), ≥ 0.
    pub inclusion: Vec<SurfaceRow>,
}

/// A hand's hold: the fingertip's anchor and a body's anchor coincide.
#[derive(Debug, Clone, PartialEq)]
pub struct HoldSpec {
    /// Unique among the model's constraints.
    pub name: String,
    /// The contact finger's fingertip body.
    pub tip: BodyId,
    /// The body it holds.
    pub body: BodyId,
    /// Anchor in the fingertip's frame, m (its centre: the origin).
    pub tip_anchor_m: [f64; 3],
    /// Anchor in the held body's frame, m.
    pub body_anchor_m: [f64; 3],
    /// `Some(R_bodyᵀ R_tip)` at the grab: the hold also keeps this relative
    /// orientation (a pinch: 6 rows, a weld), so a body held off its centre
    /// does not swing about the fingertip (least astonishment would turn a
    /// light, long body rather than translate it); `None`: a spherical
    /// joint (3 rows).
    pub orientation: Option<nalgebra::Matrix3<f64>>,
}

/// How fast and how hard a snap may pull (the fast loop's ramp of the snap
/// offsets, `program/semantic.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SnapSettings {
    /// Speed at which the largest offset of a surface shrinks, m/s.
    pub speed_m_per_s: f64,
    /// The ramp pauses while any finger's force differs from what it was
    /// when the snap began by more than this, N.
    pub force_limit_n: f64,
}

impl Default for SnapSettings {
    fn default() -> Self {
        Self {
            speed_m_per_s: 0.05,
            force_limit_n: 2.0,
        }
    }
}

/// One surface constraint's place in the model.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceInfo {
    /// Its name.
    pub name: String,
    /// The bound body.
    pub binding: BodyId,
    /// The offering body.
    pub offer: BodyId,
    /// The plane rows' constraint.
    pub plane: ConstraintId,
    /// The inclusion rows' constraint (`None` without inclusion rows).
    pub inclusion: Option<ConstraintId>,
    /// Index of its first entry in [`SemanticLayout::slots`] (plane rows,
    /// then inclusion rows).
    pub first_slot: usize,
    /// Its entries: 3 + inclusion rows.
    pub slots: usize,
}

/// The semantic rows of a model (empty for a model without any).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SemanticLayout {
    /// Satisfied surface constraints, in row order.
    pub surfaces: Vec<SurfaceInfo>,
    /// Holds: (name, fingertip, held body, constraint).
    pub holds: Vec<(String, BodyId, BodyId, ConstraintId)>,
    /// Parameters of every surface row at zero offset, in order; they fill
    /// the tail of an evaluation's witness table.
    pub slots: Vec<PlaneWitness>,
    /// The snap ramp's limits.
    pub snap: SnapSettings,
}

impl SemanticLayout {
    /// True without surfaces and holds.
    pub fn is_empty(&self) -> bool {
        self.surfaces.is_empty() && self.holds.is_empty()
    }
}

impl Model {
    /// The semantic rows (empty for a model without any).
    pub fn semantic(&self) -> &SemanticLayout {
        &self.semantic
    }

    /// This mechanism (which must have neither contact nor semantic rows)
    /// plus the rows of `surfaces` and `holds` (see the module docs).
    /// Allocates; for the slow thread. The new model has a new identity.
    pub fn with_semantic(
        &self,
        surfaces: &[SurfaceSpec],
        holds: &[HoldSpec],
        snap: SnapSettings,
    ) -> Result<Model, BuildError> {
        if !self.contact.pairs.is_empty() || !self.semantic.is_empty() {
            return Err(BuildError::AlreadyDerived {
                owner: Owner::Scene,
            });
        }
        let world = self.bodies.len();
        let split = self
            .constraints
            .iter()
            .position(|c| c.kind.sense() != Sense::Equality)
            .unwrap_or(self.constraints.len());
        let mut out = Assembler::default();
        for (info, g) in self.constraints[..split].iter().zip(&self.geometry) {
            out.push(info.clone(), *g);
        }
        let mut layout = SemanticLayout {
            snap,
            ..SemanticLayout::default()
        };
        let inclusions = self.push_surfaces(&mut out, &mut layout, surfaces, world)?;
        self.push_holds(&mut out, &mut layout, holds, world)?;
        let equality_rows = out.rows.len();
        for (info, g) in self.constraints[split..]
            .iter()
            .zip(&self.geometry[split..])
        {
            out.push(info.clone(), *g);
        }
        for (k, info, rows) in inclusions {
            layout.surfaces[k].inclusion = Some(ConstraintId(out.infos.len() as u32));
            out.push(info, Geometry::Surface(rows));
        }
        Ok(Model {
            id: next_model_id(),
            geometry: out.geometry,
            constraints: out.infos,
            rows: out.rows,
            equality_rows,
            semantic: layout,
            ..self.clone()
        })
    }

    /// The plane rows of `surfaces` (pushed on `out`, their witness slots
    /// and entries on `layout`); returns their inclusion rows, which go
    /// after the inequalities: (surface index, constraint, rows).
    fn push_surfaces(
        &self,
        out: &mut Assembler,
        layout: &mut SemanticLayout,
        surfaces: &[SurfaceSpec],
        world: usize,
    ) -> Result<Vec<(usize, ConstraintInfo, SurfaceRows)>, BuildError> {
        let total: usize = surfaces.iter().map(|s| 3 + s.inclusion.len()).sum();
        let mut inclusions = Vec::new();
        for s in surfaces {
            let owner = || Owner::Inequality(s.name.clone());
            let pair = self.pair(&owner, s.binding, s.offer, world)?;
            let first_slot = layout.slots.len();
            for r in s.plane.iter().chain(&s.inclusion) {
                layout.slots.push(plane_witness(&owner, r)?);
            }
            let from_end = |k: usize| (total - (first_slot + k)) as u32;
            let plane = ConstraintId(out.infos.len() as u32);
            out.push(
                info(&s.name, "plane", ConstraintKind::SurfacePlane, s),
                Geometry::Surface(SurfaceRows {
                    pair,
                    from_end: from_end(0),
                    rows: 3,
                }),
            );
            if !s.inclusion.is_empty() {
                inclusions.push((
                    layout.surfaces.len(),
                    info(&s.name, "inclusion", ConstraintKind::SurfaceInclusion, s),
                    SurfaceRows {
                        pair,
                        from_end: from_end(3),
                        rows: s.inclusion.len() as u32,
                    },
                ));
            }
            layout.surfaces.push(SurfaceInfo {
                name: s.name.clone(),
                binding: s.binding,
                offer: s.offer,
                plane,
                inclusion: None,
                first_slot,
                slots: 3 + s.inclusion.len(),
            });
        }
        Ok(inclusions)
    }

    /// The rows of `holds` (a weld with a relative orientation, else a
    /// spherical joint between the anchors), pushed on `out` and listed in
    /// `layout`.
    fn push_holds(
        &self,
        out: &mut Assembler,
        layout: &mut SemanticLayout,
        holds: &[HoldSpec],
        world: usize,
    ) -> Result<(), BuildError> {
        for h in holds {
            let owner = || Owner::Inequality(h.name.clone());
            let mut pair = self.pair(&owner, h.tip, h.body, world)?;
            for (v, field) in [
                (&h.tip_anchor_m, "tip anchor"),
                (&h.body_anchor_m, "anchor"),
            ] {
                if !v.iter().all(|x| x.is_finite()) {
                    return Err(BuildError::NonFinite {
                        owner: owner(),
                        field,
                    });
                }
            }
            pair.anchor = [
                Param3::Const(h.tip_anchor_m.into()),
                Param3::Const(h.body_anchor_m.into()),
            ];
            let id = ConstraintId(out.infos.len() as u32);
            out.push(
                ConstraintInfo {
                    name: h.name.clone(),
                    kind: ConstraintKind::Hold,
                    rows: 0..0,
                    bodies: [Some(h.tip), Some(h.body)],
                    finger: None,
                    limits: None,
                },
                match h.orientation {
                    Some(relative) if relative.iter().all(|x| x.is_finite()) => {
                        Geometry::Weld(Weld { pair, relative })
                    }
                    Some(_) => {
                        return Err(BuildError::NonFinite {
                            owner: owner(),
                            field: "orientation",
                        });
                    }
                    None => Geometry::Spherical(Spherical { pair }),
                },
            );
            layout.holds.push((h.name.clone(), h.tip, h.body, id));
        }
        Ok(())
    }

    /// The two ends of a semantic constraint between bodies `a` and `b`.
    fn pair(
        &self,
        owner: &dyn Fn() -> Owner,
        a: BodyId,
        b: BodyId,
        world: usize,
    ) -> Result<Pair, BuildError> {
        for id in [a, b] {
            if id.index() >= world {
                return Err(BuildError::UnknownBody {
                    owner: owner(),
                    body: id.to_string(),
                });
            }
        }
        if a == b {
            return Err(BuildError::SameBody {
                owner: owner(),
                body: self.bodies[a.index()].name.clone(),
            });
        }
        let col = |k: BodyId| self.layout.body_cols[k.index()];
        if col(a).is_none() && col(b).is_none() {
            return Err(BuildError::BothFixed { owner: owner() });
        }
        Ok(Pair {
            frame: [a.index(), b.index()],
            col: [col(a), col(b)],
            anchor: [Param3::Const(Vector3::zeros()); 2],
        })
    }
}

fn plane_witness(owner: &dyn Fn() -> Owner, r: &SurfaceRow) -> Result<PlaneWitness, BuildError> {
    for (v, field) in [
        (&r.point_m, "surface point"),
        (&r.plane_point_m, "surface plane point"),
        (&r.normal, "surface normal"),
    ] {
        if !v.iter().all(|x| x.is_finite()) {
            return Err(BuildError::NonFinite {
                owner: owner(),
                field,
            });
        }
    }
    let n = Vector3::from(r.normal);
    if n.norm() <= 1e-9 {
        return Err(BuildError::ZeroAxis {
            owner: owner(),
            field: "surface normal",
        });
    }
    Ok(PlaneWitness {
        origin: WitnessType::Surface,
        features: [0, 0],
        point_end: 0,
        point: r.point_m.into(),
        plane_point: r.plane_point_m.into(),
        normal: n.normalize(),
        margin: 0.0,
    })
}

fn info(name: &str, part: &str, kind: ConstraintKind, s: &SurfaceSpec) -> ConstraintInfo {
    ConstraintInfo {
        name: format!("{name}.{part}"),
        kind,
        rows: 0..0,
        bodies: [Some(s.binding), Some(s.offer)],
        finger: None,
        limits: None,
    }
}
