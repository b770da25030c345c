//! Contact on the two loops (Choi & Cremer §3.2): the slow loop keeps the
//! active set of witnesses, the fast loop runs on whatever it was last given
//! and never waits for it.
//!
//! ```text
//!  slow loop, every cycle:  snapshot q ─► ActiveSet::update (broad, narrow, witnesses)
//!     pairs changed? ──yes─► Model::with_contacts + Program::new (+ witness table) ─► program queue
//!          │                 (a penetration deeper than the tolerance: the same, from the
//!          │                  last clean configuration, as a Reset: the backup)
//!          └──no───────────► witness table ─► WitnessFrame mailbox
//!  fast loop, every tick:   newest frame for its model ─► Program::apply_witnesses (copy + refactor)
//!                           each step: an inactive contact it would violate is activated and
//!                           the step retaken (at most MAX_ACTIVATIONS refactorisations)
//! ```
//!
//! The fast loop never runs a symbolic analysis: a structure change (a pair
//! entering or leaving the set) arrives as a whole program, analysed on the
//! slow thread; feature changes inside a pair only change row parameters.
//! A pair is tracked from `contact_distance` plus twice its last cycle's
//! motion (the reach), so the rows exist before the fast loop needs them.

use std::sync::Arc;

use haptloop_rt::clock::{Clock, MonotonicClock};
use haptloop_rt::exchange::{MailboxReader, MailboxWriter, ProgramSender};
use haptloop_solver::constraint::witness::Witness;
use haptloop_solver::geometry::{ActiveSet, ContactBody, ContactSettings, Cycle, PairSpec, Pose3};
use haptloop_solver::{ConstraintKind, Model, Program, SolverSettings};

use super::slow::{Correction, Handover};

/// The witness table of one model, published by the slow loop.
#[derive(Debug, Clone, Default)]
pub struct WitnessFrame {
    /// The model the table belongs to ([`Model::id`]).
    pub model_id: u64,
    /// Increases with every frame published.
    pub generation: u64,
    /// Grid slot of the snapshot it was computed from.
    pub snapshot_tick: u64,
    /// One entry per slot of the model's contact layout.
    pub table: Vec<Witness>,
}

/// What the contact machinery did, slow loop side.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactSlowStats {
    /// Cycles run.
    pub cycles: u64,
    /// Primitive witnesses replaced because their features changed.
    pub witness_changes: u64,
    /// Backups: a penetration beyond the tolerance (or a tunnel) seen in a
    /// snapshot, answered by reverting to the last clean configuration with
    /// the new witnesses.
    pub backups: u64,
    /// Witnesses expanded to a higher-dimensional feature on penetration.
    pub expansions: u64,
    /// Programs built because the set of pairs changed.
    pub structure_changes: u64,
    /// Witness frames published.
    pub frames: u64,
    /// Deepest penetration measured exactly (parry) in a snapshot, m.
    pub max_penetration_m: f64,
    /// Most pairs tracked at once.
    pub max_tracked: u32,
    /// Largest and total time to build a program for a new structure, ns.
    pub build_ns_max: u64,
    /// Total build time, ns (mean = this / structure_changes).
    pub build_ns_sum: u64,
    /// Largest and total time of one active-set cycle, ns.
    pub cycle_ns_max: u64,
    /// Total cycle time, ns.
    pub cycle_ns_sum: u64,
}

/// The slow loop's contact state.
pub struct ContactLoop {
    active: ActiveSet,
    /// The mechanism without contact rows.
    base: Arc<Model>,
    /// The model of the program the fast loop was last sent.
    current: Arc<Model>,
    /// The pairs of `current`.
    pairs: Vec<PairSpec>,
    settings: SolverSettings,
    table: Vec<Witness>,
    published: Vec<Witness>,
    frames: MailboxWriter<WitnessFrame>,
    generation: u64,
    /// q of the last snapshot without a penetration beyond the tolerance.
    last_clean: Option<Vec<f64>>,
    poses: Vec<Pose3>,
    stats: ContactSlowStats,
}

impl ContactLoop {
    /// The contact loop of `base` (`None` without two shaped bodies that
    /// could touch: such scenes compile without any contact machinery).
    pub fn new(
        base: Arc<Model>,
        settings: SolverSettings,
        contact: ContactSettings,
        frames: MailboxWriter<WitnessFrame>,
    ) -> Option<Self> {
        let bodies = contact_bodies(&base);
        if bodies.iter().flatten().count() < 2 {
            return None;
        }
        let active = ActiveSet::new(bodies, jointed_pairs(&base), contact);
        Some(Self {
            active,
            current: base.clone(),
            base,
            pairs: Vec::new(),
            settings,
            table: Vec::new(),
            published: Vec::new(),
            frames,
            generation: 0,
            last_clean: None,
            poses: Vec::new(),
            stats: ContactSlowStats::default(),
        })
    }

    /// The first active set at `q` (before the clock starts): the model and
    /// program the session starts with, its witness table applied.
    pub fn initial(&mut self, q: &[f64]) -> anyhow::Result<Program> {
        let cycle = self.cycle(q);
        self.note(&cycle);
        self.last_clean = Some(q.to_vec());
        let program = self.build_program()?;
        Ok(program)
    }

    /// What it saw and did.
    pub fn stats(&self) -> ContactSlowStats {
        self.stats
    }

    /// The model of the program last sent (re-projections build on it).
    pub fn current_model(&self) -> &Arc<Model> {
        &self.current
    }

    /// The witness table of the current model (for a program built on it).
    pub fn table(&self) -> &[Witness] {
        &self.table
    }

    /// One slow-loop cycle on a snapshot. Returns true if it sent a program
    /// (the caller then skips its own re-projection this cycle).
    pub fn step(
        &mut self,
        q: &[f64],
        snapshot_tick: u64,
        solved: bool,
        programs: &mut ProgramSender<Handover>,
    ) -> bool {
        let cycle = self.cycle(q);
        self.note(&cycle);
        let penetrating = !cycle.backups.is_empty();
        if !penetrating && solved {
            match &mut self.last_clean {
                Some(v) => v.copy_from_slice(q),
                None => self.last_clean = Some(q.to_vec()),
            }
        }
        if programs.in_flight() > 0 {
            return false;
        }
        if penetrating && let Some(clean) = self.last_clean.clone() {
            // Backup (§3.2): revert to the last clean configuration, with the
            // witnesses of the pairs that penetrated added there, and retry.
            let again = self.cycle(&clean);
            self.note_changes_only(&again);
            self.stats.backups += 1;
            return self.send(programs, Correction::Reset(clean), snapshot_tick);
        }
        if self.active.pairs() != self.pairs {
            return self.send(programs, Correction::None, snapshot_tick);
        }
        self.active.fill(&mut self.table);
        if self.table != self.published {
            self.publish(snapshot_tick);
        }
        false
    }

    fn cycle(&mut self, q: &[f64]) -> Cycle {
        let clock = MonotonicClock::new();
        let start = clock.now();
        self.poses.clear();
        for (i, _) in self.base.bodies().iter().enumerate() {
            let id = haptloop_solver::BodyId(i as u32);
            let r = self.base.body_position(q, id);
            let rot = self.base.body_rotation(q, id);
            self.poses.push(match (r, rot) {
                (Some(r), Some(rot)) => Pose3 { r, rot },
                _ => Pose3::IDENTITY,
            });
        }
        let cycle = self.active.update(&self.poses);
        let ns = (clock.now() - start).0;
        self.stats.cycles += 1;
        self.stats.cycle_ns_max = self.stats.cycle_ns_max.max(ns);
        self.stats.cycle_ns_sum += ns;
        cycle
    }

    fn note(&mut self, c: &Cycle) {
        self.note_changes_only(c);
        self.stats.max_penetration_m = self.stats.max_penetration_m.max(c.max_penetration_m);
    }

    fn note_changes_only(&mut self, c: &Cycle) {
        self.stats.witness_changes += u64::from(c.witness_changes);
        self.stats.expansions += u64::from(c.expansions);
        self.stats.max_tracked = self.stats.max_tracked.max(c.tracked);
    }

    fn publish(&mut self, snapshot_tick: u64) {
        self.generation += 1;
        let (id, generation, table) = (self.current.id(), self.generation, &self.table);
        self.frames.publish_with(|f| {
            f.model_id = id;
            f.generation = generation;
            f.snapshot_tick = snapshot_tick;
            f.table.clear();
            f.table.extend_from_slice(table);
        });
        self.published.clone_from(&self.table);
        self.stats.frames += 1;
    }

    /// A program for the active set's pairs, its table applied.
    fn build_program(&mut self) -> anyhow::Result<Program> {
        let clock = MonotonicClock::new();
        let start = clock.now();
        let pairs = self.active.pairs();
        let model = Arc::new(self.base.with_contacts(&pairs)?);
        self.active.fill(&mut self.table);
        let mut program = Program::new(model.clone(), self.settings)?;
        program.apply_witnesses(&self.table);
        let ns = (clock.now() - start).0;
        self.stats.build_ns_max = self.stats.build_ns_max.max(ns);
        self.stats.build_ns_sum += ns;
        self.current = model;
        self.pairs = pairs;
        self.published.clone_from(&self.table);
        Ok(program)
    }

    fn send(
        &mut self,
        programs: &mut ProgramSender<Handover>,
        correction: Correction,
        snapshot_tick: u64,
    ) -> bool {
        let Ok(program) = self.build_program() else {
            return false;
        };
        self.stats.structure_changes += 1;
        programs
            .try_send(Box::new(Handover {
                program,
                correction,
                snapshot_tick: Some(snapshot_tick),
            }))
            .is_ok()
    }
}

/// The fast loop's side: applies the newest witness frame for its model.
pub struct WitnessInbox {
    frames: MailboxReader<WitnessFrame>,
    applied: u64,
}

impl WitnessInbox {
    /// Reads frames from `frames`.
    pub fn new(frames: MailboxReader<WitnessFrame>) -> Self {
        Self { frames, applied: 0 }
    }

    /// Applies the newest frame to `program` if it is for its model and new.
    /// Returns the frame's snapshot tick when applied.
    ///
    /// # Real-time
    /// No allocation: a mailbox read and a copy of the table into the
    /// program's (same length), then one refactorisation.
    pub fn apply(&mut self, program: &mut Program) -> Option<u64> {
        if !self.frames.refresh() {
            return None;
        }
        let f = self.frames.latest();
        if f.model_id != program.model().id() || f.generation <= self.applied {
            return None;
        }
        if program.apply_witnesses(&f.table) {
            self.applied = f.generation;
            Some(f.snapshot_tick)
        } else {
            None
        }
    }
}

/// One entry per body of `model`: its collider if it has a shape.
fn contact_bodies(model: &Model) -> Vec<Option<ContactBody>> {
    model
        .bodies()
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let collider = b.shape.as_ref()?.collider().ok()?;
            let friction = model
                .fingers()
                .iter()
                .find(|f| f.body.index() == i && f.tip.is_some())
                .and_then(|f| f.tip)
                .map_or(0.0, |t| t.friction);
            Some(ContactBody {
                collider,
                fixed: b.fixed,
                fingertip: b.fingertip,
                friction,
            })
        })
        .collect()
}

/// Pairs of bodies joined by a joint (they never collide with each other).
fn jointed_pairs(model: &Model) -> Vec<[u32; 2]> {
    model
        .constraints()
        .iter()
        .filter(|c| {
            c.finger.is_none()
                && !matches!(
                    c.kind,
                    ConstraintKind::QuaternionNorm
                        | ConstraintKind::Contact
                        | ConstraintKind::ContactFriction
                )
        })
        .filter_map(|c| match c.bodies {
            [Some(a), Some(b)] => Some([a.0, b.0]),
            _ => None,
        })
        .collect()
}
