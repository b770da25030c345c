//! Load-time limits: what a scene may ask for, so that loading and running
//! it costs at most about linearly more as it grows. Every limit is checked
//! where the scene is read and refused with a message that names the limit
//! and the field to change; `docs/scene-format.md` ("Limits") lists them,
//! and `tests/it/scene_format.rs` keeps that table equal to [`LIMITS`].
//!
//! | limit | why |
//! |---|---|
//! | vertices per area | the polygon checks compare every edge with every other |
//! | binding areas per body | each satisfied binding adds rows between the same two bodies, a dense block of the force solve |
//! | inclusion rows per constraint | a binding's vertices × its offer's edges become inequality rows on one body pair (a 1000-vertex offer: 4000 rows, minutes to load) |
//! | points of a convex shape | its hull is computed once at load; the kept hull is cut to [`MAX_HULL_VERTICES`] |
//! | contact and release distance | the broad phase's pair list is sized by them |
//! | contact pairs per moving body | every pair brings witness rows; bodies that all touch each other make a dense block (see [`MAX_PAIRS_PER_BODY`]) |

use super::spec::{AreaSection, SceneFile, ShapeSpec};
use super::validate::Checker;
use super::{LoadedScene, SceneError};
use crate::contact::{contact_bodies, jointed_pairs};
use crate::geometry::broad::BroadPhase;
use crate::geometry::{Collider, ContactSettings, Pose3};
pub use crate::geometry::{MAX_HULL_VERTICES, MAX_PAIRS_PER_BODY};
use crate::semantic::{AreaKind, SemanticScene};
use crate::{BodyId, Model};

/// Vertices an offer or binding polygon has at most.
pub const MAX_AREA_VERTICES: usize = 64;
/// Binding areas one body has at most.
pub const MAX_BINDINGS_PER_BODY: usize = 4;
/// A binding's vertices × the vertices of an offer it fits, at most: the
/// inclusion rows its constraint would have.
pub const MAX_INCLUSION_ROWS: usize = 64;
/// Points a `convex` shape lists at most.
pub const MAX_CONVEX_POINTS: usize = 100_000;
/// The largest `contact_distance` and `release_distance`, m: the default
/// release distance, four times the default contact distance. The broad
/// phase pairs every body with what is within them, and a pair's witness
/// rows are tracked from there on: the built-in `cluttered` (100 objects of
/// 1–2 cm) ran 0.2 s of session in 1.6 s at the defaults, 3.8 s at 0.02 m,
/// 36 s at 0.03 m (441 pairs), over a minute at 0.1 m, and ran out of
/// memory at 1 m.
pub const MAX_CONTACT_DISTANCE_M: f64 = 0.02;

/// One documented limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// Its name in `docs/scene-format.md`.
    pub name: &'static str,
    /// Its value (a count, or metres).
    pub value: f64,
}

/// Every limit, as `docs/scene-format.md` lists them.
pub const LIMITS: &[Limit] = &[
    Limit {
        name: "area vertices",
        value: MAX_AREA_VERTICES as f64,
    },
    Limit {
        name: "bindings per body",
        value: MAX_BINDINGS_PER_BODY as f64,
    },
    Limit {
        name: "inclusion rows",
        value: MAX_INCLUSION_ROWS as f64,
    },
    Limit {
        name: "convex points",
        value: MAX_CONVEX_POINTS as f64,
    },
    Limit {
        name: "hull vertices",
        value: MAX_HULL_VERTICES as f64,
    },
    Limit {
        name: "contact pairs per body",
        value: MAX_PAIRS_PER_BODY as f64,
    },
    Limit {
        name: "contact distance",
        value: MAX_CONTACT_DISTANCE_M,
    },
];

type Check = Result<(), SceneError>;

impl Checker<'_> {
    /// The limits that need nothing but the file: area sizes, bindings per
    /// body, points of convex shapes. Runs before the checks whose cost
    /// they bound (the polygon checks are quadratic in the vertices).
    pub(super) fn limits(&self, s: &SceneFile) -> Check {
        for (v, what) in [
            (&s.solver.contact_distance, "contact_distance"),
            (&s.solver.release_distance, "release_distance"),
        ] {
            if let Some(v) = v
                && *v.get_ref() > MAX_CONTACT_DISTANCE_M
            {
                return Err(self.err(
                    v.span(),
                    format!(
                        "{what} {} m is over {MAX_CONTACT_DISTANCE_M} m (every body is paired \
                         with what lies within it); the default contact distance is 0.005 m",
                        v.get_ref()
                    ),
                ));
            }
        }
        for b in &s.bodies {
            if let Some(extra) = b.binding.get(MAX_BINDINGS_PER_BODY) {
                return Err(self.err(
                    extra.label.span(),
                    format!(
                        "body `{}` has {} binding areas; a body has at most {MAX_BINDINGS_PER_BODY} \
                         (each satisfied binding adds rows between the same two bodies): merge \
                         them into fewer `[[body.binding]]` polygons",
                        b.name.get_ref(),
                        b.binding.len()
                    ),
                ));
            }
            for a in b.offer.iter().chain(&b.binding) {
                self.area_size(a)?;
            }
            if let Some(shape) = &b.shape
                && let ShapeSpec::Convex(pts) = shape.get_ref()
                && pts.len() > MAX_CONVEX_POINTS
            {
                return Err(self.err(
                    shape.span(),
                    format!(
                        "convex shape lists {} points; at most {MAX_CONVEX_POINTS} (its hull is \
                         cut to {MAX_HULL_VERTICES} vertices anyway)",
                        pts.len()
                    ),
                ));
            }
        }
        Ok(())
    }

    fn area_size(&self, a: &AreaSection) -> Check {
        let n = a.polygon.get_ref().len();
        if n > MAX_AREA_VERTICES {
            return Err(self.err(
                a.polygon.span(),
                format!("polygon has {n} vertices; an area has at most {MAX_AREA_VERTICES}"),
            ));
        }
        Ok(())
    }
}

impl LoadedScene {
    /// Every binding, with every offer it fits, would have at most
    /// [`MAX_INCLUSION_ROWS`] inclusion rows (its vertices × the offer's).
    /// One pass over the bindings and the distinct offer labels.
    pub(super) fn check_inclusion_rows(&self, scene: &SemanticScene) -> Check {
        // Per offer label: the largest offer polygon and its body.
        let mut largest: std::collections::BTreeMap<u32, (usize, BodyId)> = Default::default();
        for a in scene.areas().iter().filter(|a| a.kind == AreaKind::Offer) {
            let e = largest.entry(a.label.0).or_insert((0, a.body));
            if a.polygon.len() > e.0 {
                *e = (a.polygon.len(), a.body);
            }
        }
        let spans = self.area_spans();
        for (k, b) in scene.areas().iter().enumerate() {
            if b.kind != AreaKind::Binding {
                continue;
            }
            let worst = largest
                .iter()
                .filter(|(l, _)| scene.order().fits(b.label, crate::semantic::Label(**l)))
                .map(|(_, v)| *v)
                .max_by_key(|v| v.0);
            if let Some((na, body)) = worst
                && b.polygon.len() * na > MAX_INCLUSION_ROWS
            {
                let span = spans.get(k).cloned().unwrap_or(0..0);
                return Err(self.error_at(
                    span,
                    format!(
                        "this binding has {} vertices and fits an offer of `{}` with {na}: its \
                         constraint would have {} inclusion rows (vertices × vertices); at most \
                         {MAX_INCLUSION_ROWS}: use fewer vertices on one of them",
                        b.polygon.len(),
                        scene.name(body),
                        b.polygon.len() * na
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The `polygon` spans of every area, in the order the semantic spec
    /// lists them (per body: offers, then bindings).
    fn area_spans(&self) -> Vec<std::ops::Range<usize>> {
        self.spec
            .bodies
            .iter()
            .flat_map(|b| b.offer.iter().chain(&b.binding))
            .map(|a| a.polygon.span())
            .collect()
    }

    /// No moving shaped body starts within `contact_distance` of more than
    /// [`MAX_PAIRS_PER_BODY`] others: the contact machinery would track only
    /// the nearest of them, from the first cycle on. Broad phase over every
    /// shaped body, then exact distances for the bodies it finds crowded
    /// only, stopping at the first one over the limit.
    pub(super) fn check_crowding(&self, model: &Model, contact: &ContactSettings) -> Check {
        let bodies = contact_bodies(model, false);
        let idx: Vec<usize> = (0..bodies.len()).filter(|&i| bodies[i].is_some()).collect();
        if idx.len() <= MAX_PAIRS_PER_BODY {
            return Ok(());
        }
        let mut excluded = jointed_pairs(model);
        for p in &mut excluded {
            p.sort_unstable();
        }
        excluded.sort_unstable();
        let pose = |i: usize| {
            let id = BodyId(i as u32);
            match (
                model.body_position(model.q0(), id),
                model.body_rotation(model.q0(), id),
            ) {
                (Some(r), Some(rot)) => Pose3 { r, rot },
                _ => Pose3::IDENTITY,
            }
        };
        let set: Vec<(&Collider, Pose3)> = idx
            .iter()
            .map(|&i| (&bodies[i].as_ref().expect("shaped").collider, pose(i)))
            .collect();
        let mut broad = BroadPhase::default();
        let mut near: Vec<Vec<usize>> = vec![Vec::new(); bodies.len()];
        for &(a, b) in broad.pairs(&set, contact.contact_distance_m) {
            let (i, j) = (idx[a as usize], idx[b as usize]);
            let (bi, bj) = (
                bodies[i].as_ref().expect("shaped"),
                bodies[j].as_ref().expect("shaped"),
            );
            let key = [i.min(j) as u32, i.max(j) as u32];
            if (bi.fixed && bj.fixed)
                || (bi.fingertip && bj.fingertip)
                || excluded.binary_search(&key).is_ok()
            {
                continue;
            }
            near[i].push(j);
            near[j].push(i);
        }
        for (i, others) in near.iter().enumerate() {
            let Some(bi) = bodies[i].as_ref().filter(|b| !b.fixed) else {
                continue;
            };
            if others.len() <= MAX_PAIRS_PER_BODY {
                continue;
            }
            let within = others
                .iter()
                .filter(|&&j| {
                    let bj = bodies[j].as_ref().expect("shaped");
                    parry3d_f64::query::distance(
                        &pose(i).to_parry(),
                        &*bi.collider.full,
                        &pose(j).to_parry(),
                        &*bj.collider.full,
                    )
                    .is_ok_and(|d| d.distance < contact.contact_distance_m)
                })
                .take(MAX_PAIRS_PER_BODY + 1)
                .count();
            if within > MAX_PAIRS_PER_BODY {
                return Err(self.crowded(i, model, contact, others.len()));
            }
        }
        Ok(())
    }

    fn crowded(
        &self,
        i: usize,
        model: &Model,
        contact: &ContactSettings,
        near: usize,
    ) -> SceneError {
        let name = &model.bodies()[i].name;
        let s = &self.spec;
        let span =
            s.bodies
                .iter()
                .find(|b| b.name.get_ref() == name)
                .map_or(s.scene.name.span(), |b| {
                    b.position
                        .as_ref()
                        .map_or(b.name.span(), toml::Spanned::span)
                });
        self.error_at(
            span,
            format!(
                "body `{name}` starts within contact_distance ({} m) of more than \
                 {MAX_PAIRS_PER_BODY} other shaped bodies (up to {near} in its reach); a moving body \
                 is tracked in at most {MAX_PAIRS_PER_BODY} contact pairs: spread the bodies out or \
                 lower [solver] contact_distance",
                contact.contact_distance_m
            ),
        )
    }
}
