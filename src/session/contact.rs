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
//!  fast loop, every tick:   newest frame for its model ─► Program::apply_witnesses (copy + refactor;
//!                           quasi-static: evaluation + one factorisation, no whole force solve)
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
use haptloop_solver::contact::{ContactManager, ContactUpdate};
use haptloop_solver::geometry::{ContactSettings, Cycle};
use haptloop_solver::{Model, Program, SolverSettings};

use super::messages::{Correction, Handover, RowsStamp};
use super::track::{ContactPoint, contact_points};

/// The witness table of one model, published by the slow loop.
#[derive(Debug, Clone, Default)]
pub struct WitnessFrame {
    /// The model the table belongs to ([`Model::id`]).
    pub model_id: u64,
    /// Increases with every frame published.
    pub generation: u64,
    /// Grid slot of the snapshot it was computed from.
    pub snapshot_tick: u64,
    /// That snapshot's [`Snapshot::contact_motion`](super::Snapshot): the
    /// motion the table is trusted for counts from it (`witness_age`). A
    /// frame of the same generation again says the table is still the
    /// active set's at a newer snapshot.
    pub snapshot_motion: f64,
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
    /// Snapshots whose exact penetration was beyond the session's bound
    /// for a broken world ([`ContactLoop::broken_m`]): the force is cut
    /// with the backup that answers them.
    pub broken: u64,
    /// Frames that only confirmed the running table at a newer snapshot.
    pub confirmations: u64,
    /// Cycles that found a penetration beyond the tolerance and did not
    /// back it up: two backups in a row had not cleared it (each reset
    /// came back to the same depth), so it is held and reported, and backed
    /// up again only if it grows past [`held_penetration_cap_m`].
    pub held: u64,
    /// The deepest penetration a held cycle had, m (at most
    /// [`held_penetration_cap_m`]).
    pub max_held_m: f64,
    /// Most pairs tracked at once.
    pub max_tracked: u32,
    /// Largest and total time to build a program for a new structure, ns.
    pub build_ns_max: u64,
    /// Total build time, ns (mean = this / structure_changes).
    pub build_ns_sum: u64,
    /// Programs for a new structure taken from the cache by structure (a set
    /// of pairs seen before: no model, no symbolic analysis).
    pub reused: u64,
    /// Largest and total time to prepare a reused program, ns.
    pub reuse_ns_max: u64,
    /// Total, ns (mean = this / reused).
    pub reuse_ns_sum: u64,
    /// Largest and total time of one active-set cycle, ns.
    pub cycle_ns_max: u64,
    /// Total cycle time, ns.
    pub cycle_ns_sum: u64,
}

/// Two shaped bodies overlap deeper than the penetration tolerance where the
/// session would start: the session refuses to start.
#[derive(Debug, Clone, PartialEq)]
pub struct Interpenetration {
    /// The two bodies.
    pub bodies: [String; 2],
    /// How deep, m (the deepest pair of the first cycle).
    pub depth_m: f64,
    /// `[solver] penetration_tolerance`, m.
    pub tolerance_m: f64,
}

impl std::fmt::Display for Interpenetration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "bodies `{}` and `{}` interpenetrate by {:.3e} m where the session starts (after \
             the assembly), deeper than the penetration tolerance {:.3e} m: move one of them \
             (its `position`), or change its shape",
            self.bodies[0], self.bodies[1], self.depth_m, self.tolerance_m
        )
    }
}

impl std::error::Error for Interpenetration {}

/// The penetration beyond which the world counts as broken, like a joint
/// violation beyond the session's `broken_m`: deeper than the contact
/// distance (no witness row was there to hold it) and ten times the
/// tolerance, m.
pub fn broken_penetration_m(c: &ContactSettings) -> f64 {
    c.contact_distance_m.max(10.0 * c.penetration_tolerance_m)
}

/// The deepest penetration the backup policy holds instead of backing it
/// up, m: ten times the tolerance (the tolerance's leg of the broken
/// bound), and at most half the broken bound. Fixed by the scene's contact
/// settings: a held run's depth no longer depends on a depth sampled where
/// a stall fell (it was twice the depth found at the second backup in a
/// row: 2.02 mm after one stall, 0.30 mm after another; BENCHMARKS.md,
/// issue 23, "a fixed cap on held backups"). 1 mm for the built-in contact
/// scenes (tolerance 0.1 mm, contact distance 5 mm).
pub fn held_penetration_cap_m(c: &ContactSettings) -> f64 {
    (10.0 * c.penetration_tolerance_m).min(0.5 * broken_penetration_m(c))
}

/// Where a snapshot was taken: its grid slot and its
/// [`Snapshot::contact_motion`](super::Snapshot).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct At {
    /// Grid slot.
    pub tick: u64,
    /// Motion so far, ticks' worth of the contact speed limit.
    pub motion: f64,
}

/// The slow loop's contact state: the solver's [`ContactManager`] plus the
/// exchange with the fast loop and timing.
pub struct ContactLoop {
    manager: ContactManager,
    /// The scene's penetration tolerance, m.
    tolerance_m: f64,
    /// A penetration beyond this means the world came apart, m.
    broken_m: f64,
    frames: MailboxWriter<WitnessFrame>,
    generation: u64,
    stats: ContactSlowStats,
    /// Backups sent in consecutive cycles.
    backups_in_a_row: u32,
    /// The manager's backup floor, m (0: every penetration is backed up).
    floor_m: f64,
    /// What the floor is while backups are held, m
    /// ([`held_penetration_cap_m`]).
    cap_m: f64,
}

impl ContactLoop {
    /// The contact loop of `base` (`None` without two shaped bodies that
    /// could touch: such scenes compile without any contact machinery).
    pub fn new(
        base: Arc<Model>,
        settings: SolverSettings,
        contact: ContactSettings,
        frames: MailboxWriter<WitnessFrame>,
        objectives: Arc<haptloop_solver::Objectives>,
    ) -> Option<Self> {
        let manager = ContactManager::new(base, settings, contact)?.with_objectives(objectives);
        Some(Self {
            manager,
            tolerance_m: contact.penetration_tolerance_m,
            broken_m: broken_penetration_m(&contact),
            frames,
            generation: 0,
            stats: ContactSlowStats::default(),
            backups_in_a_row: 0,
            floor_m: 0.0,
            cap_m: held_penetration_cap_m(&contact),
        })
    }

    /// The first active set at `q` (before the clock starts): the program
    /// the session starts with, its witness table applied and q set.
    pub fn initial(&mut self, q: &[f64]) -> anyhow::Result<Program> {
        let clock = MonotonicClock::new();
        let start = clock.now();
        let (cycle, program) = self.manager.initial(q)?;
        if let Some(&[a, b]) = cycle.backups.first() {
            // Starting inside each other, the pair would be backed up to
            // this very configuration on every cycle: refused, as a scene
            // with semantic areas refuses it when it loads.
            let body = |i: u32| {
                self.manager.current_model().bodies()[i as usize]
                    .name
                    .clone()
            };
            return Err(Interpenetration {
                bodies: [body(a), body(b)],
                depth_m: cycle.max_penetration_m,
                tolerance_m: self.tolerance_m,
            }
            .into());
        }
        self.note(&cycle, (clock.now() - start).0);
        Ok(program)
    }

    /// What it saw and did.
    pub fn stats(&self) -> ContactSlowStats {
        self.stats
    }

    /// The active contact points of the last cycle, appended to `out`.
    pub fn contacts(&self, out: &mut Vec<ContactPoint>) {
        contact_points(&self.manager, out);
    }

    /// Keeps a program the fast loop handed back for reuse (the cache by
    /// structure, see `ContactManager::recycle`).
    pub fn recycle(&mut self, program: Program) {
        self.manager.recycle(program);
    }

    /// Takes the bodies `absent` out of every contact pair (objects not in
    /// the scene); the next rebase or cycle builds the program without them.
    pub fn set_absent(&mut self, absent: &[u32]) {
        self.manager.set_absent(absent);
    }

    /// Takes `base` as the mechanism from now on (a semantic change: new
    /// surface rows or holds) and returns the program for it at `q`, its
    /// build time counted with the structure changes.
    pub fn rebase(&mut self, base: Arc<Model>, q: &[f64]) -> Option<Program> {
        let clock = MonotonicClock::new();
        let start = clock.now();
        let program = self.manager.rebase(base, q).ok()?;
        let ns = (clock.now() - start).0;
        self.stats.structure_changes += 1;
        self.stats.build_ns_max = self.stats.build_ns_max.max(ns);
        self.stats.build_ns_sum += ns;
        Some(program)
    }

    /// A program for the model the fast loop runs, with its current witness
    /// table (a re-projection's hand-over).
    pub fn program_for_current(&self) -> Option<Program> {
        self.manager.program_for_current().ok()
    }

    /// The bodies' speeds at the next snapshot (per model body, m/s and
    /// rad/s): the next cycle tracks pairs as far ahead as twice what they
    /// will move in a slow period, as it does for what they moved in the
    /// last one.
    pub fn set_speeds(&mut self, speeds: &[[f64; 2]]) {
        (self.manager).set_speeds(speeds, super::SLOW_PERIOD.as_secs_f64());
    }

    /// A penetration beyond this means the world came apart, m.
    pub fn broken_m(&self) -> f64 {
        self.broken_m
    }

    /// One slow-loop cycle on a snapshot taken `at`. Returns true if it
    /// sent a program (the caller then skips its own re-projection this
    /// cycle).
    pub fn step(
        &mut self,
        q: &[f64],
        at: At,
        solved: bool,
        programs: &mut ProgramSender<Handover>,
    ) -> bool {
        let clock = MonotonicClock::new();
        let start = clock.now();
        let may_send = programs.in_flight() == 0;
        let (cycle, update) = self.manager.step(q, solved, may_send);
        self.note(&cycle, (clock.now() - start).0);
        let broken = cycle.max_penetration_m > self.broken_m;
        let reset = matches!(&update, ContactUpdate::Program { reset: Some(_), .. });
        let held = !cycle.backups.is_empty() && !reset;
        if held && self.floor_m > 0.0 && cycle.max_penetration_m <= self.floor_m {
            self.stats.held += 1;
            self.stats.max_held_m = self.stats.max_held_m.max(cycle.max_penetration_m);
        }
        self.backup_policy(&cycle, reset);
        self.stats.broken += u64::from(broken);
        match update {
            ContactUpdate::None => {
                if (cycle.backups.is_empty() || held) && self.table_is_current() {
                    // The running rows are still what this snapshot asks
                    // for: they are trusted from here on.
                    self.publish(at);
                    self.stats.confirmations += 1;
                }
                false
            }
            ContactUpdate::Table => {
                self.generation += 1;
                self.publish(at);
                self.stats.frames += 1;
                false
            }
            ContactUpdate::Program { program, reset } => {
                let ns = (clock.now() - start).0;
                if self.manager.builds().last_reused {
                    self.stats.reused += 1;
                    self.stats.reuse_ns_max = self.stats.reuse_ns_max.max(ns);
                    self.stats.reuse_ns_sum += ns;
                } else {
                    self.stats.build_ns_max = self.stats.build_ns_max.max(ns);
                    self.stats.build_ns_sum += ns;
                }
                self.stats.structure_changes += 1;
                let (correction, rows) = match reset {
                    Some(q) => {
                        self.stats.backups += 1;
                        (Correction::Reset(q), RowsStamp::Fresh)
                    }
                    None => (Correction::None, RowsStamp::At(at.motion)),
                };
                // Its table is this generation's: the fast loop takes the
                // frames that confirm it as stamps only.
                self.generation += 1;
                programs
                    .try_send(Box::new(Handover {
                        program: *program,
                        correction,
                        snapshot_tick: Some(at.tick),
                        rows,
                        broken,
                        generation: Some(self.generation),
                    }))
                    .is_ok()
            }
        }
    }

    /// Backups that do not clear a penetration are not repeated: after two
    /// in a row the manager holds penetrations up to the fixed cap
    /// ([`held_penetration_cap_m`]) until a clean cycle. A deeper one is
    /// backed up all the same (to the last clean configuration) and the
    /// hold goes on.
    fn backup_policy(&mut self, cycle: &Cycle, reset: bool) {
        let floor = if reset {
            self.backups_in_a_row += 1;
            if self.backups_in_a_row >= 2 {
                self.cap_m
            } else {
                0.0
            }
        } else if cycle.backups.is_empty() {
            self.backups_in_a_row = 0;
            0.0
        } else {
            self.floor_m
        };
        if floor != self.floor_m {
            self.floor_m = floor;
            self.manager.set_backup_floor(floor);
        }
    }

    /// The active set's pairs are the running program's and its table the
    /// one last published: nothing new for the fast loop.
    fn table_is_current(&self) -> bool {
        let m = &self.manager;
        m.active_set().pairs() == m.current_model().contact().specs
    }

    fn note(&mut self, c: &Cycle, ns: u64) {
        let s = &mut self.stats;
        s.cycles += 1;
        s.cycle_ns_max = s.cycle_ns_max.max(ns);
        s.cycle_ns_sum += ns;
        s.witness_changes += u64::from(c.witness_changes);
        s.expansions += u64::from(c.expansions);
        s.max_tracked = s.max_tracked.max(c.tracked);
        s.max_penetration_m = s.max_penetration_m.max(c.max_penetration_m);
    }

    /// Publishes the running table stamped with the snapshot `at`
    /// (`generation` unchanged: a confirmation of the table last sent).
    fn publish(&mut self, at: At) {
        let (id, generation, table) = (
            self.manager.current_model().id(),
            self.generation,
            self.manager.published(),
        );
        self.frames.publish_with(|f| {
            f.model_id = id;
            f.generation = generation;
            f.snapshot_tick = at.tick;
            f.snapshot_motion = at.motion;
            f.table.clear();
            f.table.extend_from_slice(table);
        });
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

    /// A program whose table is of `generation` was taken over: frames of
    /// that generation only confirm it.
    pub fn taken_over(&mut self, generation: u64) {
        self.applied = self.applied.max(generation);
    }

    /// Applies the newest frame to `program` if it is for its model and new.
    /// Returns its snapshot when applied, or when it confirms the table
    /// applied last at a newer snapshot (`table: false`).
    ///
    /// # Real-time
    /// No allocation: a mailbox read and a copy of the table into the
    /// program's (same length), then one refactorisation.
    pub fn apply(&mut self, program: &mut Program) -> Option<Received> {
        if !self.frames.refresh() {
            return None;
        }
        let f = self.frames.latest();
        if f.model_id != program.model().id() || f.generation < self.applied {
            return None;
        }
        let stamp = |table| Received {
            tick: f.snapshot_tick,
            motion: f.snapshot_motion,
            table,
        };
        if f.generation == self.applied {
            return Some(stamp(false));
        }
        if program.apply_witnesses(&f.table) {
            self.applied = f.generation;
            Some(stamp(true))
        } else {
            None
        }
    }
}

/// A witness frame the fast loop took.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Received {
    /// Its snapshot's grid slot.
    pub tick: u64,
    /// Its snapshot's [`Snapshot::contact_motion`](super::Snapshot).
    pub motion: f64,
    /// A new table was applied (else a confirmation of the last one).
    pub table: bool,
}
