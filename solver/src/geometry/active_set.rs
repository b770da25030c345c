//! The active set of non-penetration inequalities (Choi & Cremer §3.2), run
//! on the slow loop once per cycle from a snapshot of the fast loop's
//! configuration.
//!
//! ```text
//!  poses ──► broad phase (BVH, AABBs loosened by each pair's reach)
//!        ──► narrow phase per candidate (warm-started GJK, nearest features)
//!        ──► per pair: add below contact_distance + reach (pre-emptive),
//!            replace primitives whose features changed (required removal),
//!            drop beyond release_distance (optional removal),
//!            guard nearby vertices and edges (§3.2.1 before it happens;
//!            `ContactSettings::guards`),
//!            on penetration: expand the witness to the higher-dimensional
//!            feature (`expansion.rs`) and, deeper than the tolerance, ask
//!            for a backup (revert, add, retry)
//!        ──► Cycle: did the set of pairs change (a new program) or only the
//!            primitives in their slots (a witness table for the running one)
//! ```
//!
//! **Reach.** The fast loop runs several ticks between two cycles, on the
//! witnesses it was given. A pair is tracked pre-emptively when its surfaces
//! are closer than `contact_distance` plus twice the distance the two bodies
//! moved (relative, translation plus rotation at their radii) during the last
//! cycle, or will move over the next one at their current velocity if that
//! is more (`set_expected_motion`): a pair closing in at speed v over a
//! cycle of T is tracked at least 2 v T before it touches, so a witness row
//! exists before the fast loop needs it.
//!
//! **Tunnelling.** A pair that the swept broad phase (last and current AABBs)
//! reports, that is not tracked and is separated now but whose shapes swept
//! through each other along the cycle's translation (parry's time of impact
//! < 1), passed through without ever being close at a sampled instant: that
//! is a penetration too, and asks for a backup.

use std::collections::BTreeMap;

use nalgebra::Vector3;
use parry3d_f64::query::{ShapeCastOptions, cast_shapes};

use super::broad::BroadPhase;
use super::convert::{Pose3, to_glam};
use super::expansion::{expand_on_penetration, expand_overlap, merge};
use super::narrow::{PairCache, PairQuery, query_pair};
use super::pair::PairView;
use super::primitives::{expand, primitives, select, value_at};
use super::shape::Collider;
use crate::constraint::witness::friction::{stick_rows, twist_row};
use crate::constraint::witness::{PlaneWitness, Witness, WitnessType};

/// Knobs of the active set, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSettings {
    /// Witnesses are added below this surface distance (plus the pair's reach).
    pub contact_distance_m: f64,
    /// A tracked pair is dropped beyond this distance.
    pub release_distance_m: f64,
    /// Penetration deeper than this asks for a backup.
    pub penetration_tolerance_m: f64,
    /// Row slots of a body–body pair.
    pub slots_per_pair: usize,
    /// Row slots of a fingertip–body pair.
    pub finger_slots: usize,
    /// Pairs a moving body (fingertips included) is tracked in at most,
    /// nearest first (see [`MAX_PAIRS_PER_BODY`]).
    pub max_pairs_per_body: usize,
    /// Pre-emptive guards (§3.2's "preventatively adds inequalities once
    /// nearest feature distances fall below some threshold", extended to
    /// every vertex and edge within a pair's reach): on, a tilting body's
    /// next corner has a row before it touches. Off, only the nearest
    /// features have rows, and a penetration is answered by the backup and
    /// the §3.2.1 expansion alone (the paper's other approach). Scene key
    /// `[solver] contact_guards`; default on.
    pub guards: bool,
    /// The edge guards keep only edge pairs that can meet edge on edge (the
    /// normal of the plane both edges span within both edges' normal cones,
    /// `guards::edges_can_meet`). On, `stack` after long host stalls no
    /// longer throws its top box (a side edge against a top edge at
    /// coinciding corners read the column's sideways offset as a
    /// penetration); off by default: with it `place` on sit-on-chair stops
    /// short of its blocked goal and a cluttered lockstep run's low-rank
    /// release is no longer bit-identical to refactoring (BENCHMARKS.md,
    /// issue 23, "the throws").
    pub edge_cones: bool,
}

impl ContactSettings {
    /// Row slots of the pair of `a` and `b`. A sphere (a point core) touches
    /// anything at one point, and the guards that pre-empt a tilting body's
    /// next corner need two polyhedra: such a pair gets a fingertip's
    /// `finger_slots` (a fingertip is a sphere too), not `slots_per_pair`.
    /// Every slot is a row of the force solve whether it holds a witness or
    /// not, and rows of bodies that touch each other make a dense block: a
    /// 3 × 3 × 3 pile of touching spheres (133 pairs) spent 38 ms a tick in
    /// Eq. 7 with 8 slots a pair.
    pub fn slots(&self, a: &ContactBody, b: &ContactBody) -> usize {
        let point = |c: &ContactBody| matches!(c.collider.core, super::shape::Core::Point);
        if a.fingertip || point(a) || point(b) {
            self.finger_slots.min(self.slots_per_pair)
        } else {
            self.slots_per_pair
        }
    }
}

/// Contact pairs a moving body takes part in at most. Every pair brings
/// `slots_per_pair` rows, and the rows of bodies that all touch each other
/// make a dense block of the force solve (its factorisation grows with the
/// cube of the block: 25 boxes at one spot, 300 pairs, took 17 s to build a
/// program; 50 never finished). Equal spheres can touch 12 others at most;
/// a box in a stack touches 26 neighbours only in a lattice packed without
/// gaps. Beyond this the farthest pairs are not tracked (counted per cycle
/// as [`Cycle::crowded`]); a scene that starts that crowded is refused at
/// load.
pub const MAX_PAIRS_PER_BODY: usize = 16;

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            contact_distance_m: 0.005,
            release_distance_m: 0.02,
            penetration_tolerance_m: 1e-4,
            slots_per_pair: 8,
            finger_slots: 2,
            max_pairs_per_body: MAX_PAIRS_PER_BODY,
            guards: true,
            edge_cones: false,
        }
    }
}

/// A body as the contact machinery sees it.
#[derive(Debug, Clone)]
pub struct ContactBody {
    /// Its collider.
    pub collider: Collider,
    /// Fixed bodies never collide with each other.
    pub fixed: bool,
    /// A contact finger's fingertip: always end 0 of its pairs; two
    /// fingertips do not collide.
    pub fingertip: bool,
    /// Coulomb μ of its contacts (0: frictionless). A fingertip's governs
    /// its pairs; two other bodies use the geometric mean of theirs.
    pub friction: f64,
}

impl ContactBody {
    /// Coulomb μ of the pair `a`–`b` (`a` the fingertip when there is one).
    pub fn pair_friction(a: &ContactBody, b: &ContactBody) -> f64 {
        if a.fingertip {
            a.friction
        } else {
            (a.friction * b.friction).sqrt()
        }
    }
}

/// One tracked pair's state.
#[derive(Debug, Clone)]
struct Tracked {
    cache: PairCache,
    witnesses: Vec<Witness>,
    /// Stick rows: two tangent rows and, between two bodies, the twist row.
    friction: Option<[PlaneWitness; 3]>,
    /// Primitives made by a §3.2.1 expansion, kept while they stay within
    /// the pair's window (the backup's retry needs them).
    expanded: Vec<Witness>,
    distance_m: f64,
}

/// A tracked pair as a model needs it to lay out its rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct PairSpec {
    /// Body indices (end 0 = A, end 1 = B).
    pub bodies: [u32; 2],
    /// Witness row slots.
    pub slots: u32,
    /// Friction stick rows (μ > 0): two at a fingertip, three (with the
    /// twist row) between two bodies.
    pub friction: bool,
}

/// What one cycle found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Cycle {
    /// The set of tracked pairs changed: the model's rows must be rebuilt.
    pub structure_changed: bool,
    /// Primitives whose features changed in pairs that stayed tracked.
    pub witness_changes: u32,
    /// Pairs found penetrating deeper than the tolerance, or tunnelled
    /// through each other: the configuration should be backed up.
    pub backups: Vec<[u32; 2]>,
    /// Deepest penetration seen, metres (0 if none).
    pub max_penetration_m: f64,
    /// Witnesses expanded to a higher-dimensional feature on penetration
    /// (§3.2.1).
    pub expansions: u32,
    /// Of `backups`, the pairs that tunnelled (swept through each other
    /// between two cycles without being close at either); the others were
    /// deeper than the tolerance.
    pub tunnels: u32,
    /// Candidate pairs from the broad phase.
    pub candidates: u32,
    /// Tracked pairs after the cycle.
    pub tracked: u32,
    /// Pairs within reach left untracked because a moving body of theirs
    /// was already in [`ContactSettings::max_pairs_per_body`] nearer ones.
    pub crowded: u32,
}

/// The active set (see the module docs).
#[derive(Debug)]
pub struct ActiveSet {
    bodies: Vec<Option<ContactBody>>,
    excluded: Vec<[u32; 2]>,
    settings: ContactSettings,
    broad: BroadPhase,
    tracked: BTreeMap<[u32; 2], Tracked>,
    last_poses: Vec<Pose3>,
    /// Per body: how far it may move over the next cycle at its current
    /// velocity, metres (empty: unknown; [`set_expected_motion`](Self::set_expected_motion)).
    expected: Vec<f64>,
}

impl ActiveSet {
    /// One entry per model body (`None`: no shape). `excluded`: pairs that
    /// never collide (bodies joined by a joint).
    pub fn new(
        bodies: Vec<Option<ContactBody>>,
        excluded: Vec<[u32; 2]>,
        settings: ContactSettings,
    ) -> Self {
        let mut excluded: Vec<[u32; 2]> = excluded
            .into_iter()
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        excluded.sort_unstable();
        Self {
            bodies,
            excluded,
            settings,
            broad: BroadPhase::default(),
            tracked: BTreeMap::new(),
            last_poses: Vec::new(),
            expected: Vec::new(),
        }
    }

    /// How far each body (one entry per model body) will move over the
    /// next cycle at its current velocity, metres: its speed (linear plus
    /// radius × angular) times the cycle. The next [`update`](Self::update)
    /// takes the larger of this and the body's motion over the last cycle
    /// as its motion, so a body that just started moving fast (thrown,
    /// bounced, released with a velocity) has its pairs tracked as far
    /// ahead as it will fly.
    pub fn set_expected_motion(&mut self, expected_m: &[f64]) {
        self.expected.clear();
        self.expected.extend_from_slice(expected_m);
    }

    /// Replaces the pairs that never collide (a model derived with new
    /// joints: semantic constraints, holds) and stops tracking any that are
    /// now excluded.
    pub fn set_excluded(&mut self, excluded: Vec<[u32; 2]>) {
        let mut excluded: Vec<[u32; 2]> = excluded
            .into_iter()
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        excluded.sort_unstable();
        excluded.dedup();
        self.tracked.retain(|k, _| {
            excluded
                .binary_search(&[k[0].min(k[1]), k[0].max(k[1])])
                .is_err()
        });
        self.excluded = excluded;
    }

    /// Each body's bounding radius, metres (0 without a shape).
    pub fn radii(&self) -> Vec<f64> {
        self.bodies
            .iter()
            .map(|b| b.as_ref().map_or(0.0, |b| b.collider.radius_m))
            .collect()
    }

    /// The settings.
    pub fn settings(&self) -> &ContactSettings {
        &self.settings
    }

    /// Number of bodies with a shape.
    pub fn shaped(&self) -> usize {
        self.bodies.iter().flatten().count()
    }

    /// The tracked pairs in row order (sorted by body indices).
    pub fn pairs(&self) -> Vec<PairSpec> {
        self.tracked
            .keys()
            .map(|&k| {
                let a = self.bodies[k[0] as usize].as_ref();
                let b = self.bodies[k[1] as usize].as_ref();
                let mu = match (a, b) {
                    (Some(a), Some(b)) => ContactBody::pair_friction(a, b),
                    _ => 0.0,
                };
                PairSpec {
                    bodies: k,
                    slots: match (a, b) {
                        (Some(a), Some(b)) => self.settings.slots(a, b),
                        _ => self.settings.slots_per_pair,
                    } as u32,
                    friction: mu > 0.0,
                }
            })
            .collect()
    }

    /// The witnesses of pair `bodies` (empty if not tracked).
    pub fn witnesses(&self, bodies: [u32; 2]) -> &[Witness] {
        self.tracked
            .get(&bodies)
            .map_or(&[], |t| t.witnesses.as_slice())
    }

    /// Writes every tracked pair's primitives (then `Off`) and friction rows
    /// into `table`, pair by pair in [`pairs`](Self::pairs) order: `slots`
    /// rows each, then the friction rows where the pair has them (2 at a
    /// fingertip, 3 between two bodies). Returns the number of entries
    /// written.
    pub fn fill(&self, table: &mut Vec<Witness>) -> usize {
        table.clear();
        for spec in self.pairs() {
            let t = &self.tracked[&spec.bodies];
            for k in 0..spec.slots as usize {
                table.push(t.witnesses.get(k).copied().unwrap_or_default());
            }
            if spec.friction {
                let fingertip = self.bodies[spec.bodies[0] as usize]
                    .as_ref()
                    .is_some_and(|b| b.fingertip);
                let n = if fingertip { 2 } else { 3 };
                match t.friction {
                    Some(rows) => table.extend(rows[..n].iter().map(|&w| Witness::Plane(w))),
                    None => table.extend(std::iter::repeat_n(Witness::Off, n)),
                }
            }
        }
        table.len()
    }

    /// One cycle at `poses` (one per model body, fixed ones included).
    pub fn update(&mut self, poses: &[Pose3]) -> Cycle {
        let mut cycle = Cycle::default();
        if self.last_poses.len() != poses.len() {
            self.last_poses = poses.to_vec();
        }
        let motion: Vec<f64> = poses
            .iter()
            .zip(&self.last_poses)
            .zip(&self.bodies)
            .map(|((p, l), b)| {
                let radius = b.as_ref().map_or(0.0, |b| b.collider.radius_m);
                let angle = rotation_angle(&(p.rot * l.rot.transpose()));
                (p.r - l.r).norm() + radius * angle
            })
            .zip(self.expected.iter().copied().chain(std::iter::repeat(0.0)))
            .map(|(moved, expected)| moved.max(expected))
            .collect();
        let max_motion = motion.iter().copied().fold(0.0, f64::max);
        // Swept broad phase: the current AABBs loosened enough to reach last
        // cycle's poses and the pre-emptive window.
        let idx: Vec<u32> = (0..self.bodies.len() as u32)
            .filter(|&i| self.bodies[i as usize].is_some())
            .collect();
        let set: Vec<(&Collider, Pose3)> = idx
            .iter()
            .map(|&i| {
                let b = self.bodies[i as usize].as_ref().expect("shaped");
                (&b.collider, poses[i as usize])
            })
            .collect();
        let margin = self
            .settings
            .release_distance_m
            .max(self.settings.contact_distance_m)
            + 4.0 * max_motion;
        let raw: Vec<(u32, u32)> = self.broad.pairs(&set, margin).to_vec();
        drop(set);
        let candidates: Vec<[u32; 2]> = raw
            .iter()
            .map(|&(i, j)| [idx[i as usize], idx[j as usize]])
            .filter_map(|p| self.ordered(p))
            .collect();
        cycle.candidates = candidates.len() as u32;
        let before: Vec<[u32; 2]> = self.tracked.keys().copied().collect();
        let mut seen = Vec::with_capacity(candidates.len());
        for pair in candidates {
            seen.push(pair);
            let reach = self.settings.contact_distance_m
                + 2.0 * (motion[pair[0] as usize] + motion[pair[1] as usize]);
            self.visit(pair, poses, reach, &mut cycle);
        }
        // Tracked pairs the broad phase no longer reports are beyond release.
        seen.sort_unstable();
        self.tracked.retain(|k, _| seen.binary_search(k).is_ok());
        cycle.crowded = self.cap_pairs_per_body();
        let after: Vec<[u32; 2]> = self.tracked.keys().copied().collect();
        cycle.structure_changed = before != after;
        cycle.tracked = after.len() as u32;
        self.last_poses.copy_from_slice(poses);
        cycle
    }

    /// Keeps every moving body in at most
    /// [`ContactSettings::max_pairs_per_body`] tracked pairs, nearest pairs
    /// first (a penetrating pair before any separated one); returns how many
    /// pairs were dropped.
    fn cap_pairs_per_body(&mut self) -> u32 {
        let cap = self.settings.max_pairs_per_body;
        let bodies = &self.bodies;
        let moving = |b: u32| bodies[b as usize].as_ref().is_some_and(|c| !c.fixed);
        let mut count = vec![0usize; bodies.len()];
        for key in self.tracked.keys() {
            for &b in key.iter().filter(|&&b| moving(b)) {
                count[b as usize] += 1;
            }
        }
        if count.iter().all(|&c| c <= cap) {
            return 0;
        }
        let mut order: Vec<([u32; 2], f64)> = self
            .tracked
            .iter()
            .map(|(k, t)| (*k, t.distance_m))
            .collect();
        order.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        count.fill(0);
        let mut dropped = 0;
        for (key, _) in order {
            if key.iter().any(|&b| moving(b) && count[b as usize] >= cap) {
                self.tracked.remove(&key);
                dropped += 1;
            } else {
                for &b in key.iter().filter(|&&b| moving(b)) {
                    count[b as usize] += 1;
                }
            }
        }
        dropped
    }

    /// The pair in row order (fingertip first, else lower index first), or
    /// `None` if it never collides.
    fn ordered(&self, [i, j]: [u32; 2]) -> Option<[u32; 2]> {
        let (bi, bj) = (
            self.bodies[i as usize].as_ref()?,
            self.bodies[j as usize].as_ref()?,
        );
        if (bi.fixed && bj.fixed)
            || (bi.fingertip && bj.fingertip)
            || self.excluded.binary_search(&[i.min(j), i.max(j)]).is_ok()
        {
            return None;
        }
        Some(if bj.fingertip && !bi.fingertip {
            [j, i]
        } else {
            [i.min(j), i.max(j)]
        })
    }

    fn visit(&mut self, pair: [u32; 2], poses: &[Pose3], reach: f64, cycle: &mut Cycle) {
        let s = self.settings;
        let (a, b) = (
            self.bodies[pair[0] as usize].as_ref().expect("shaped"),
            self.bodies[pair[1] as usize].as_ref().expect("shaped"),
        );
        let view = PairView {
            a: &a.collider,
            pa: poses[pair[0] as usize],
            b: &b.collider,
            pb: poses[pair[1] as usize],
        };
        let slots = s.slots(a, b);
        let window = s.release_distance_m.max(s.contact_distance_m + reach);
        let was = self.tracked.get(&pair).cloned();
        // A pair that had no rows during the last cycle may have passed
        // through itself in it (it is then on the wrong side, where new rows
        // would hold it): that asks for a backup whatever it looks like now.
        if was.is_none() && self.tunnelled(pair, poses) {
            cycle.backups.push(pair);
            cycle.tunnels += 1;
        }
        let mut cache = was.as_ref().map(|t| t.cache.clone()).unwrap_or_default();
        let Some(q) = query_pair(view.a, &view.pa, view.b, &view.pb, window, &mut cache) else {
            self.tracked.remove(&pair);
            return;
        };
        let depth = -q.distance_m;
        if depth > 0.0 {
            cycle.max_penetration_m = cycle.max_penetration_m.max(depth);
        }
        let track = match &was {
            Some(_) => q.distance_m < s.release_distance_m.max(s.contact_distance_m + reach),
            None => q.distance_m < s.contact_distance_m + reach,
        };
        if !track {
            self.tracked.remove(&pair);
            return;
        }
        let mut out = Vec::with_capacity(8);
        let mut expanded = Vec::new();
        if s.guards {
            // The next features already have rows: the expansion is asked
            // for only when the cores overlap (no nearest features at all).
            if q.features.is_some() {
                primitives(&view, &q, &mut out);
            } else if let Some(prev) = &was {
                cycle.expansions += expand_overlap(&view, &prev.witnesses, &mut out);
            }
        } else {
            // §3.2.1 at any penetration: a tracked pair's held vertices'
            // neighbours below their face expand the witness; without new
            // violators, the primitives of an earlier expansion stay while
            // they are near.
            if let Some(prev) = &was {
                if depth > 0.0 {
                    let made = expand_on_penetration(&view, &prev.witnesses, &mut expanded);
                    cycle.expansions += made;
                }
                if expanded.is_empty() {
                    let near = |w: &&Witness| value_at(w, &view.pa, &view.pb).0 < window;
                    expanded.extend(prev.expanded.iter().filter(near));
                }
            }
            merge(&mut out, &expanded);
            if q.features.is_some() {
                let mut nearest = Vec::with_capacity(8);
                primitives(&view, &q, &mut nearest);
                merge(&mut out, &nearest);
            }
        }
        if out.is_empty() {
            out.push(fallback(&view, &q));
        }
        if s.guards {
            let overlap = (-q.distance_m).max(0.0);
            expand(&view, reach, overlap, s.edge_cones, &mut out);
        }
        select(&view, slots, &mut out);
        if depth > s.penetration_tolerance_m {
            cycle.backups.push(pair);
        }
        if let Some(prev) = &was {
            cycle.witness_changes += changes(&prev.witnesses, &out);
        }
        let friction = if ContactBody::pair_friction(a, b) > 0.0 {
            let carried = was.as_ref().and_then(|t| t.friction);
            Some(carried.unwrap_or_else(|| friction_rows(&view, &q, a.fingertip, &out)))
        } else {
            None
        };
        self.tracked.insert(
            pair,
            Tracked {
                cache,
                witnesses: out,
                friction,
                expanded,
                distance_m: q.distance_m,
            },
        );
    }

    /// True when the pair, not close at either end of the cycle, swept
    /// through itself along the cycle's translations.
    fn tunnelled(&self, pair: [u32; 2], poses: &[Pose3]) -> bool {
        let (i, j) = (pair[0] as usize, pair[1] as usize);
        let (Some(a), Some(b)) = (self.bodies[i].as_ref(), self.bodies[j].as_ref()) else {
            return false;
        };
        let (la, lb) = (self.last_poses[i], self.last_poses[j]);
        let (va, vb) = (poses[i].r - la.r, poses[j].r - lb.r);
        let rel = (va - vb).norm();
        if rel < 0.5 * a.collider.radius_m.min(b.collider.radius_m) {
            return false;
        }
        let opts = ShapeCastOptions {
            max_time_of_impact: 1.0,
            stop_at_penetration: false,
            ..Default::default()
        };
        matches!(
            cast_shapes(
                &la.to_parry(),
                to_glam(&va),
                &*a.collider.full,
                &lb.to_parry(),
                to_glam(&vb),
                &*b.collider.full,
                opts,
            ),
            Ok(Some(hit)) if hit.time_of_impact < 1.0
        )
    }

    /// Distance of a tracked pair at the last cycle, metres.
    pub fn distance(&self, bodies: [u32; 2]) -> Option<f64> {
        self.tracked.get(&bodies).map(|t| t.distance_m)
    }
}

/// Primitives added or removed between the old and the new list, by
/// features (a primitive that only moved along its face is not a change).
fn changes(old: &[Witness], new: &[Witness]) -> u32 {
    let added = new
        .iter()
        .filter(|w| !old.iter().any(|o| o.same_features(w)))
        .count();
    let removed = old
        .iter()
        .filter(|o| !new.iter().any(|w| w.same_features(o)))
        .count();
    (added + removed) as u32
}

/// A plane through the deepest points of a penetration (parry's contact),
/// normal out of B: used when nothing better is known.
fn fallback(view: &PairView, q: &PairQuery) -> Witness {
    let n_b = view.pb.local_dir(&-q.normal);
    Witness::Plane(PlaneWitness {
        origin: WitnessType::VertexFace,
        // No features: a key no vertex or face has (expansions skip it).
        features: [u32::MAX, u32::MAX],
        point_end: 0,
        point: view.pa.local_point(&q.core_point_a),
        plane_point: view.pb.local_point(&q.core_point_b),
        normal: n_b,
        margin: view.margin(),
    })
}

/// The two stick rows of A touching B, tangential to B's outward contact
/// normal. A fingertip's centre is held over B's closest point (rolling
/// the ball does not move it); two bodies are held together at the centre
/// of their contact patch (the mean of the points the witness primitives
/// hold), the same world point on both.
fn friction_rows(
    view: &PairView,
    q: &PairQuery,
    fingertip: bool,
    primitives: &[Witness],
) -> [PlaneWitness; 3] {
    let n_b = view.pb.local_dir(&-q.normal);
    if fingertip {
        let rows = stick_rows(
            view.pa.local_point(&q.core_point_a),
            view.pb.local_point(&q.core_point_b),
            n_b,
        );
        return [rows[0], rows[1], rows[1]];
    }
    let held = held_points(primitives, &view.pa, &view.pb);
    let centre = if held.is_empty() {
        (q.core_point_a + q.core_point_b) * 0.5
    } else {
        held.iter().sum::<Vector3<f64>>() / held.len() as f64
    };
    let rows = stick_rows(
        view.pa.local_point(&centre),
        view.pb.local_point(&centre),
        n_b,
    );
    // The twist row's arm: half the smaller body's radius along the first
    // tangent (any non-zero arm holds the twist; this one keeps it inside
    // the patch's scale).
    let arm = 0.5 * view.a.radius_m.min(view.b.radius_m).max(1e-3);
    let at = centre + view.pb.rot * rows[0].normal * arm;
    [
        rows[0],
        rows[1],
        twist_row(&rows, view.pa.local_point(&at), view.pb.local_point(&at)),
    ]
}

/// The angle of a rotation matrix, radians.
fn rotation_angle(r: &nalgebra::Matrix3<f64>) -> f64 {
    ((r.trace() - 1.0) * 0.5).clamp(-1.0, 1.0).acos()
}

/// World positions of the points the primitives of a pair hold (for
/// reports and plots).
pub fn held_points(w: &[Witness], pa: &Pose3, pb: &Pose3) -> Vec<Vector3<f64>> {
    w.iter()
        .filter(|w| w.is_on())
        .map(|w| value_at(w, pa, pb).1)
        .collect()
}
