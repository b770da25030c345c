//! Semantic constraints on the slow loop (Gösele & Stuerzlinger), felt
//! through the fast loop's rows.
//!
//! ```text
//!  slow loop, every cycle:  snapshot q + finger forces ─► SemanticScene::set_pose (mirror)
//!     hand holds (the contact fingers' `holds` schedule): grab / let go
//!     a held object pulled off its offer harder than break_force ─► break (exception list)
//!     exception pairs apart and out of snap range ─► release
//!     moved objects' free bindings ─► Algorithm 1 (snap, pending until its ramp arrives)
//!     an object at rest starting to move ─► move (printed only)
//!     an offer object moving its bound successors ─► group_move
//!     structure changed? ─► Model::with_semantic (surfaces + holds) ─► contact rebase or
//!                           Program::new ─► program queue (the fast loop ramps and carries)
//! ```
//!
//! The fast loop never waits for any of this and only ever sees rows; the
//! mirrored scene is checked with consistent(s) after every operation and
//! the result counted. `holds.rs` runs the hand's schedule, `report.rs`
//! holds the events and figures.

use std::sync::Arc;

use anyhow::{Context, Result};
use haptloop_rt::clock::{Clock, MonotonicClock};
use haptloop_solver::geometry::Pose3;
use haptloop_solver::scene::{HoldDecl, ScheduleDecl, SemanticMode};
use haptloop_solver::semantic::{AreaId, SemanticScene};
use haptloop_solver::{BodyId, HoldSpec, Model};
use nalgebra::Vector3;

mod holds;
mod report;
mod schedule;

use holds::ActiveHold;
pub use report::{Event, EventKind, SemanticReport};

/// A displacement per slow-loop cycle above this counts as moving, m (a
/// drag at 4 mm/s; the rotation counts at the body's radius).
pub const MOVING_M: f64 = 2e-5;

/// Cycles an offer object must rest before its group's next motion is a new
/// `group_move` event (100 ms at the 5 ms slow period).
pub const REST_CYCLES: u32 = 20;

/// The slow loop's semantic state (see the module docs).
pub struct SemanticLoop {
    scene: SemanticScene,
    base: Arc<Model>,
    current: Arc<Model>,
    /// Contact fingers: (finger index, fingertip body, radius).
    tips: Vec<(usize, BodyId, f64)>,
    schedule: Vec<HoldDecl>,
    /// Per schedule entry: done (held and let go, or expired).
    done: Vec<bool>,
    holds: Vec<ActiveHold>,
    /// Per object: its pose at the last cycle.
    last: Vec<Pose3>,
    /// Per object: cycles it has rested (offer objects' group motion).
    rest: Vec<u32>,
    /// Edges (offer, binding) whose group motion has been reported.
    moving_edges: Vec<(BodyId, BodyId)>,
    /// Pending snaps: binding area and when they were made.
    pending: Vec<(AreaId, f64)>,
    dirty: bool,
    report: SemanticReport,
    /// The scene's `[[schedule]]`, by time, and the next entry to run.
    ops: Vec<ScheduleDecl>,
    next_op: usize,
    /// The interaction mode (§6).
    mode: SemanticMode,
    /// Added bodies' poses not yet sent to the fast loop, and those sent but
    /// not yet seen in a snapshot (not mirrored until then).
    placements: Vec<(BodyId, Pose3)>,
    arriving: Vec<(BodyId, Pose3)>,
    /// Adds that found no valid place: the body, when it was scheduled and
    /// when it is tried next (s); retried until it fits or is removed.
    waiting: Vec<schedule::Waiting>,
    /// An add or remove changed which bodies are absent.
    absent_changed: bool,
}

/// What a scene schedules for the semantic loop: the `[[schedule]]`
/// entries, the bodies absent at the start, the starting mode.
#[derive(Debug, Clone, Default)]
pub struct SemanticPlan {
    /// `[[schedule]]`, by time.
    pub ops: Vec<ScheduleDecl>,
    /// Bodies absent at the start.
    pub absent: Vec<BodyId>,
    /// The mode at the start.
    pub mode: SemanticMode,
}

impl SemanticLoop {
    /// The semantic loop of a scene (`None` without areas and holds), at
    /// the assembled configuration `q` of `base` (the scene's model): the
    /// constraints aligned at load satisfied, the model with their rows
    /// built. Allocates.
    pub fn new(
        base: Arc<Model>,
        spec: Option<&haptloop_solver::semantic::SemanticSpec>,
        schedule: &[HoldDecl],
        plan: &SemanticPlan,
        q: &[f64],
    ) -> Result<Option<Self>> {
        if spec.is_none() && schedule.is_empty() {
            return Ok(None);
        }
        let empty = haptloop_solver::semantic::SemanticSpec::default();
        let spec = spec.unwrap_or(&empty);
        let mut scene =
            SemanticScene::from_model(&base, q, spec).context("building the semantic scene")?;
        for &b in &plan.absent {
            scene.start_absent(b);
        }
        let loaded = scene.satisfy_aligned();
        let tips = base
            .fingers()
            .iter()
            .enumerate()
            .filter_map(|(k, f)| f.tip.map(|t| (k, f.body, t.radius_m)))
            .collect();
        let n = base.bodies().len();
        let mut s = Self {
            last: scene.objects().iter().map(|o| o.pose).collect(),
            scene,
            current: base.clone(),
            base,
            tips,
            schedule: schedule.to_vec(),
            done: vec![false; schedule.len()],
            holds: Vec::new(),
            rest: vec![REST_CYCLES; n],
            moving_edges: Vec::new(),
            pending: Vec::new(),
            dirty: false,
            report: SemanticReport {
                loaded,
                arrival_max_s: f64::NAN,
                add_wait_max_s: f64::NAN,
                ..SemanticReport::default()
            },
            ops: plan.ops.clone(),
            next_op: 0,
            mode: plan.mode,
            placements: Vec::new(),
            arriving: Vec::new(),
            waiting: Vec::new(),
            absent_changed: false,
        };
        s.check();
        s.current = Arc::new(s.model()?);
        Ok(Some(s))
    }

    /// The model with the rows of the satisfied constraints and holds now.
    fn model(&self) -> Result<Model> {
        let holds: Vec<HoldSpec> = self
            .holds
            .iter()
            .map(|h| HoldSpec {
                name: format!(
                    "hold {}|{}",
                    self.scene.name(h.tip),
                    self.scene.name(h.body)
                ),
                tip: h.tip,
                body: h.body,
                tip_anchor_m: [0.0; 3],
                body_anchor_m: [h.anchor.x, h.anchor.y, h.anchor.z],
                orientation: Some(h.relative),
            })
            .collect();
        self.base
            .with_semantic(
                &self.scene.surface_specs(),
                &holds,
                self.scene.settings().snap,
            )
            .context("the semantic rows")
    }

    /// The model of the program the fast loop was last given (or is about
    /// to be).
    pub fn current_model(&self) -> &Arc<Model> {
        &self.current
    }

    /// True when the satisfied constraints or holds changed since the last
    /// program was sent.
    pub fn dirty(&self) -> bool {
        self.dirty
    }

    /// Builds the model for the current state (call when [`dirty`](Self::dirty)
    /// and a program can be sent); `None` (counted) if it cannot be built.
    pub fn take_model(&mut self) -> Option<Arc<Model>> {
        self.dirty = false;
        match self.model() {
            Ok(m) => {
                self.current = Arc::new(m);
                Some(self.current.clone())
            }
            Err(_) => {
                self.report.program_failures += 1;
                None
            }
        }
    }

    /// Records a program sent (or not) for a change, with its build time.
    pub fn note_program(&mut self, sent: bool, ns: u64) {
        if sent {
            self.report.programs += 1;
            self.report.build_ns_max = self.report.build_ns_max.max(ns);
            self.report.build_ns_sum += ns;
        } else {
            self.report.program_failures += 1;
        }
    }

    /// Every event so far, in time order.
    pub fn events(&self) -> &[Event] {
        &self.report.events
    }

    /// What it saw and did so far, with the graph as it stands.
    pub fn report(&self) -> SemanticReport {
        let mut r = self.report.clone();
        r.graph = self
            .scene
            .edges()
            .into_iter()
            .map(|(a, b)| (self.scene.name(a).to_owned(), self.scene.name(b).to_owned()))
            .collect();
        r.graph.sort();
        r.pending_at_end = self.pending.len();
        r.adds_waiting_at_end = self.waiting.len();
        r.present_at_end = self
            .scene
            .objects()
            .iter()
            .enumerate()
            .filter(|(i, o)| {
                self.scene.is_present(BodyId(*i as u32))
                    && !self.tips.iter().any(|t| t.1.index() == *i)
                    && o.collider.is_some()
            })
            .count();
        r.constraints_at_end = self.scene.bonds().count();
        r.mode_at_end = self.mode.as_str();
        r
    }

    /// The mirrored scene.
    pub fn scene(&self) -> &SemanticScene {
        &self.scene
    }

    fn event(&mut self, t_s: f64, kind: EventKind, binding: BodyId, offer: &str) {
        self.report.events.push(Event {
            t_s,
            kind,
            binding_body: self.scene.name(binding).to_owned(),
            offer_body: offer.to_owned(),
        });
    }

    fn check(&mut self) {
        self.report.checks += 1;
        if let Err(e) = self.scene.consistent() {
            self.report.inconsistent += 1;
            if self.report.first_inconsistency.is_none() {
                self.report.first_inconsistency = Some(e.to_string());
            }
        }
    }

    /// One cycle on a snapshot: `q` of the running model (the base's layout:
    /// semantic rows add no coordinates), each finger's force (N, world, on
    /// the finger) and the session time. Marks the loop dirty when the rows
    /// must change. Allocates (slow thread).
    pub fn step(&mut self, q: &[f64], finger_force_n: &[[f64; 3]], t_s: f64) {
        let clock = MonotonicClock::new();
        let start = clock.now();
        self.mirror(q);
        self.run_schedule(t_s);
        self.update_holds(t_s);
        self.breaks(finger_force_n, t_s);
        for [b, o] in self.scene.update_exceptions() {
            let name = self.scene.name(o).to_owned();
            self.event(t_s, EventKind::Release, b, &name);
            self.check();
        }
        self.arrivals(t_s);
        self.snaps(t_s);
        self.group_moves(t_s);
        let ns = (clock.now() - start).0;
        self.report.cycles += 1;
        self.report.cycle_ns_max = self.report.cycle_ns_max.max(ns);
        self.report.cycle_ns_sum += ns;
    }

    /// Mirrors the fast loop's poses; remembers the last ones.
    fn mirror(&mut self, q: &[f64]) {
        for i in 0..self.last.len() {
            let id = BodyId(i as u32);
            self.last[i] = self.scene.pose(id);
            if !self.adopted(id, q) {
                // Placed by an add, not yet in the fast loop's q.
                continue;
            }
            if let (Some(r), Some(rot)) = (
                self.base.body_position(q, id),
                self.base.body_rotation(q, id),
            ) {
                self.scene.set_pose(id, Pose3 { r, rot });
            }
        }
    }

    /// How far object `o` moved since the last cycle (rotation at its
    /// shape's radius), m.
    fn moved(&self, o: BodyId) -> f64 {
        let (a, b) = (self.last[o.index()], self.scene.pose(o));
        let radius = self.scene.objects()[o.index()]
            .collider
            .as_ref()
            .map_or(0.0, |c| c.radius_m);
        let turn = (a.rot.transpose() * b.rot - nalgebra::Matrix3::identity()).norm();
        (b.r - a.r).norm() + radius * turn
    }

    /// A held object pulled away from an offer it is bound to harder than
    /// `break_force` (the finger's force on the user's hand, −F, along the
    /// offer's orientation vector) breaks that constraint.
    fn breaks(&mut self, finger_force_n: &[[f64; 3]], t_s: f64) {
        let limit = self.scene.settings().break_force_n;
        let mut broken = Vec::new();
        for h in &self.holds {
            let f = self.schedule[h.decl].finger.index();
            let Some(force) = finger_force_n.get(f).map(|v| Vector3::from(*v)) else {
                continue;
            };
            for &b in &self.scene.objects()[h.body.index()].bindings {
                let Some(bond) = self.scene.bond(b) else {
                    continue;
                };
                let offer = self.scene.area(bond.offer);
                let n = offer.normal_w(&self.scene.pose(offer.body));
                if -force.dot(&n) > limit {
                    broken.push(b);
                }
            }
        }
        for b in broken {
            let body = self.scene.area(b).body;
            if let Some(a) = self.scene.break_bond(b) {
                let offer = self.scene.name(self.scene.area(a).body).to_owned();
                self.pending.retain(|(p, _)| *p != b);
                self.event(t_s, EventKind::Break, body, &offer);
                self.dirty = true;
                self.check();
            }
        }
    }

    /// Pending snaps whose binding is aligned now have arrived.
    fn arrivals(&mut self, t_s: f64) {
        let mut k = 0;
        while k < self.pending.len() {
            let (b, since) = self.pending[k];
            let arrived = match self.scene.bond(b) {
                Some(bond) => self.scene.aligned(b, bond.offer, false),
                None => true,
            };
            if arrived {
                self.scene.set_pending(b, false);
                self.pending.swap_remove(k);
                let dt = t_s - since;
                let m = &mut self.report.arrival_max_s;
                *m = if m.is_nan() { dt } else { m.max(dt) };
            } else {
                k += 1;
            }
        }
    }

    /// Algorithm 1 for the free bindings of every object that moved.
    fn snaps(&mut self, t_s: f64) {
        for i in 0..self.last.len() {
            let o = BodyId(i as u32);
            let obj = &self.scene.objects()[i];
            if obj.fixed
                || obj.bindings.is_empty()
                || self.moved(o) <= 0.0
                || self.unconstrained(o)
                || !self.scene.is_present(o)
            {
                continue;
            }
            for snap in self.scene.satisfy_object(o, true) {
                let offer = self.scene.name(self.scene.area(snap.offer).body).to_owned();
                self.pending.push((snap.binding, t_s));
                self.event(t_s, EventKind::Snap, o, &offer);
                self.dirty = true;
                self.check();
            }
        }
    }

    /// An offer object that starts moving and moves a bound object along is
    /// a group move (once per edge until the offer object rests again).
    fn group_moves(&mut self, t_s: f64) {
        for i in 0..self.last.len() {
            let o = BodyId(i as u32);
            if self.scene.objects()[i].fixed || !self.scene.is_present(o) {
                continue;
            }
            let moving = self.moved(o) > MOVING_M;
            if !moving {
                self.rest[i] = self.rest[i].saturating_add(1);
                if self.rest[i] >= REST_CYCLES {
                    self.moving_edges.retain(|(p, _)| *p != o);
                }
                continue;
            }
            let started = self.rest[i] >= REST_CYCLES;
            self.rest[i] = 0;
            let tip = self.tips.iter().any(|t| t.1 == o);
            let carried = self
                .scene
                .parents_of(o)
                .into_iter()
                .any(|p| self.moved(p) > MOVING_M);
            if started && !tip && !carried {
                let by = self
                    .holds
                    .iter()
                    .find(|h| h.body == o)
                    .map_or(String::new(), |h| self.finger_name(h.decl));
                self.event(t_s, EventKind::Move, o, &by);
            }
            for c in self.scene.children_of(o) {
                if self.moved(c) > MOVING_M && !self.moving_edges.contains(&(o, c)) {
                    self.moving_edges.push((o, c));
                    let name = self.scene.name(o).to_owned();
                    self.event(t_s, EventKind::GroupMove, c, &name);
                }
            }
        }
    }
}
