//! [`SemanticScene`]: objects with poses and shapes, their areas, the label
//! order, the satisfied constraints (the grouping graph's edges), the
//! exception list, and the spatial indices the algorithms query.

use nalgebra::Vector3;

use super::area::{Area, AreaId};
use super::grid::Grid;
use super::labels::{Label, LabelCycle, LabelOrder};
use super::spec::{AreaKind, SemanticSettings, SemanticSpec};
use crate::geometry::convert::to_na;
use crate::geometry::{Collider, Pose3};
use crate::{BodyId, Model};

/// One object of the scene: a body of the model.
#[derive(Debug, Clone)]
pub struct Object {
    /// The body's name.
    pub name: String,
    /// Fixed bodies never move (a snap or a move that would move one is
    /// rejected).
    pub fixed: bool,
    /// Its pose, world frame.
    pub pose: Pose3,
    /// Its shape (`None`: it collides with nothing; fingertips).
    pub collider: Option<Collider>,
    /// Its offer areas.
    pub offers: Vec<AreaId>,
    /// Its binding areas.
    pub bindings: Vec<AreaId>,
}

/// A satisfied surface constraint, stored with its binding area (a binding
/// area satisfies at most one offer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bond {
    /// The offer area it is satisfied with.
    pub offer: AreaId,
    /// Satisfied, but the fast loop is still pulling the binding onto the
    /// offer (a snap's ramp, see `program/semantic.rs`): aligned within the
    /// snap distance and angle rather than the alignment tolerance.
    pub pending: bool,
}

/// Why a semantic scene could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SemanticError {
    /// The label order has a cycle.
    #[error("{0}")]
    Labels(#[from] LabelCycle),
    /// An area names a body the model does not have.
    #[error("area {area} names body #{body}, which the model does not have")]
    UnknownBody {
        /// The area's index in the spec.
        area: usize,
        /// The body index.
        body: u32,
    },
    /// An offer area's polygon is not convex (its inclusion rows need one).
    #[error("offer area {area} of `{body}` is not convex")]
    NotConvex {
        /// The area's index in the spec.
        area: usize,
        /// The body.
        body: String,
    },
}

/// See the module docs.
#[derive(Debug, Clone)]
pub struct SemanticScene {
    pub(super) objects: Vec<Object>,
    pub(super) areas: Vec<Area>,
    pub(super) order: LabelOrder,
    pub(super) settings: SemanticSettings,
    /// Per area: its bond if it is a satisfied binding area.
    pub(super) bound: Vec<Option<Bond>>,
    /// Per object: the binding areas bound to one of its offers (its
    /// children in the grouping graph).
    pub(super) children: Vec<Vec<AreaId>>,
    /// (binding object, offer object) pairs whose constraint was broken and
    /// which have not separated yet (§5.3).
    pub(super) exceptions: Vec<[BodyId; 2]>,
    /// Pairs whose collisions are never tested (bodies joined by a joint, a
    /// hand and what it holds), each sorted.
    pub(super) ignored: Vec<[BodyId; 2]>,
    pub(super) object_grid: Grid,
    pub(super) offer_grid: Grid,
    /// Per object: taken out of the scene (`presence.rs`).
    pub(super) absent: Vec<bool>,
}

impl SemanticScene {
    /// The objects of `model` (every body; fingertips without a shape here)
    /// at the poses of `q`, with the areas and order of `spec`. No
    /// constraint is satisfied yet ([`satisfy_aligned`](Self::satisfy_aligned)
    /// does that for a loaded scene).
    pub fn from_model(
        model: &Model,
        q: &[f64],
        spec: &SemanticSpec,
    ) -> Result<Self, SemanticError> {
        let objects = model
            .bodies()
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let id = BodyId(i as u32);
                let pose = match (model.body_position(q, id), model.body_rotation(q, id)) {
                    (Some(r), Some(rot)) => Pose3 { r, rot },
                    _ => Pose3::IDENTITY,
                };
                Object {
                    name: b.name.clone(),
                    fixed: b.fixed,
                    pose,
                    collider: if b.fingertip {
                        None
                    } else {
                        b.shape.as_ref().and_then(|s| s.collider().ok())
                    },
                    offers: Vec::new(),
                    bindings: Vec::new(),
                }
            })
            .collect();
        Self::new(objects, spec)
    }

    /// A scene of `objects` (their `offers`/`bindings` are filled from
    /// `spec`, whose areas name objects by index).
    pub fn new(mut objects: Vec<Object>, spec: &SemanticSpec) -> Result<Self, SemanticError> {
        let order = LabelOrder::new(
            spec.labels
                .iter()
                .map(String::as_str)
                .chain(spec.areas.iter().map(|a| a.label.as_str())),
            &spec.order,
        )?;
        let mut areas = Vec::with_capacity(spec.areas.len());
        for o in &mut objects {
            o.offers.clear();
            o.bindings.clear();
        }
        for (k, a) in spec.areas.iter().enumerate() {
            let Some(obj) = objects.get_mut(a.body.index()) else {
                return Err(SemanticError::UnknownBody {
                    area: k,
                    body: a.body.0,
                });
            };
            let label = order
                .label(&a.label)
                .expect("every area label was interned");
            let area = Area::new(a.body, a.kind, label, &a.polygon_m, a.normal);
            if a.kind == AreaKind::Offer && !convex(&area) {
                return Err(SemanticError::NotConvex {
                    area: k,
                    body: obj.name.clone(),
                });
            }
            let id = AreaId(k as u32);
            match a.kind {
                AreaKind::Offer => obj.offers.push(id),
                AreaKind::Binding => obj.bindings.push(id),
            }
            areas.push(area);
        }
        let mut order = order;
        let labels_of = |kind: AreaKind| -> Vec<Label> {
            areas
                .iter()
                .filter(|a: &&Area| a.kind == kind)
                .map(|a| a.label)
                .collect()
        };
        let (from, to) = (labels_of(AreaKind::Binding), labels_of(AreaKind::Offer));
        order.precompute(&from, &to);
        let cell = grid_cell(&objects);
        let n = objects.len();
        let mut scene = Self {
            bound: vec![None; areas.len()],
            children: vec![Vec::new(); n],
            exceptions: Vec::new(),
            ignored: Vec::new(),
            object_grid: Grid::new(cell),
            offer_grid: Grid::new(cell),
            objects,
            areas,
            order,
            settings: spec.settings,
            absent: vec![false; n],
        };
        for i in 0..n {
            scene.index(BodyId(i as u32));
        }
        Ok(scene)
    }

    /// The settings.
    pub fn settings(&self) -> &SemanticSettings {
        &self.settings
    }

    /// The label order.
    pub fn order(&self) -> &LabelOrder {
        &self.order
    }

    /// Every object, by body index.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// Every area, by [`AreaId`].
    pub fn areas(&self) -> &[Area] {
        &self.areas
    }

    /// Area `a`.
    pub fn area(&self, a: AreaId) -> &Area {
        &self.areas[a.index()]
    }

    /// The name of object `o`.
    pub fn name(&self, o: BodyId) -> &str {
        self.objects.get(o.index()).map_or("?", |x| x.name.as_str())
    }

    /// The pose of object `o`.
    pub fn pose(&self, o: BodyId) -> Pose3 {
        self.objects[o.index()].pose
    }

    /// Moves object `o` to `pose` (no checks: the session mirrors the fast
    /// loop's configuration with it; the algorithms move objects through
    /// [`move_object`](Self::move_object) and [`satisfy`](Self::satisfy)).
    pub fn set_pose(&mut self, o: BodyId, pose: Pose3) {
        if self.objects[o.index()].pose != pose {
            self.objects[o.index()].pose = pose;
            self.index(o);
        }
    }

    /// The bond of binding area `b`, if it is satisfied.
    pub fn bond(&self, b: AreaId) -> Option<Bond> {
        self.bound.get(b.index()).copied().flatten()
    }

    /// Every satisfied constraint: (binding area, bond), by binding area.
    pub fn bonds(&self) -> impl Iterator<Item = (AreaId, Bond)> + '_ {
        self.bound
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.map(|b| (AreaId(i as u32), b)))
    }

    /// Marks binding area `b`'s bond as aligned (its snap has arrived) or
    /// pending.
    pub fn set_pending(&mut self, b: AreaId, pending: bool) {
        if let Some(Some(bond)) = self.bound.get_mut(b.index()) {
            bond.pending = pending;
        }
    }

    /// The exception list: (binding object, offer object) of broken
    /// constraints whose objects have not separated.
    pub fn exceptions(&self) -> &[[BodyId; 2]] {
        &self.exceptions
    }

    /// Pairs whose collisions are never tested (joints, holds); replaces the
    /// previous list.
    pub fn set_ignored(&mut self, pairs: &[[BodyId; 2]]) {
        self.ignored = pairs
            .iter()
            .map(|&[a, b]| if a <= b { [a, b] } else { [b, a] })
            .collect();
        self.ignored.sort_unstable();
        self.ignored.dedup();
    }

    pub(super) fn is_ignored(&self, a: BodyId, b: BodyId) -> bool {
        let k = if a <= b { [a, b] } else { [b, a] };
        self.ignored.binary_search(&k).is_ok()
    }

    pub(super) fn add_bond(&mut self, b: AreaId, offer: AreaId, pending: bool) {
        self.bound[b.index()] = Some(Bond { offer, pending });
        let parent = self.areas[offer.index()].body;
        self.children[parent.index()].push(b);
    }

    pub(super) fn remove_bond(&mut self, b: AreaId) -> Option<Bond> {
        let bond = self.bound.get_mut(b.index())?.take()?;
        let parent = self.areas[bond.offer.index()].body;
        self.children[parent.index()].retain(|&x| x != b);
        Some(bond)
    }

    /// Refreshes object `o`'s entries in the grids.
    pub(super) fn index(&mut self, o: BodyId) {
        if self.absent[o.index()] {
            self.unindex(o);
            return;
        }
        let obj = &self.objects[o.index()];
        if let Some(c) = &obj.collider {
            let bb = c.full.compute_aabb(&obj.pose.to_parry());
            self.object_grid.set(o.0, &to_na(bb.mins), &to_na(bb.maxs));
        }
        let reach = self.settings.snap_distance_m + self.settings.align_tolerance;
        for &a in &obj.offers {
            let (lo, hi) = aabb(self.areas[a.index()].vertices_w(&obj.pose), reach);
            self.offer_grid.set(a.0, &lo, &hi);
        }
    }

    /// Offer areas whose box (loosened by the snap distance) meets the box
    /// of binding area `b` at `pose`.
    pub(super) fn offers_near(&self, b: AreaId, pose: &Pose3) -> Vec<u32> {
        let (lo, hi) = aabb(self.areas[b.index()].vertices_w(pose), 0.0);
        let mut out = Vec::new();
        self.offer_grid.query(&lo, &hi, &mut out);
        out
    }

    /// Objects whose shape's box meets the box `[lo, hi]`.
    pub(super) fn objects_near(&self, lo: &Vector3<f64>, hi: &Vector3<f64>) -> Vec<u32> {
        let mut out = Vec::new();
        self.object_grid.query(lo, hi, &mut out);
        out
    }
}

/// The box of `points`, loosened by `margin` on every side.
pub(super) fn aabb(
    points: impl Iterator<Item = Vector3<f64>>,
    margin: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    (lo.add_scalar(-margin), hi.add_scalar(margin))
}

/// Whether every vertex lies inside every edge's half-plane.
fn convex(a: &Area) -> bool {
    let tol = 1e-9 * a.radius_m.max(1e-9);
    a.edges
        .iter()
        .all(|(p, m)| m.norm() > 0.5 && a.polygon.iter().all(|v| m.dot(&(v - p)) >= -tol))
}

/// The grid's cell: about twice the median object's size (at least 1 cm),
/// so an object covers a few cells and a cell holds a few objects.
fn grid_cell(objects: &[Object]) -> f64 {
    let mut sizes: Vec<f64> = objects
        .iter()
        .filter_map(|o| o.collider.as_ref().map(|c| c.radius_m))
        .collect();
    if sizes.is_empty() {
        return 1.0;
    }
    sizes.sort_by(f64::total_cmp);
    (4.0 * sizes[sizes.len() / 2]).max(0.01)
}
