//! [`ContactManager`]: the slow loop's contact cycle (see the module docs of
//! [`crate::contact`]).
//!
//! ```text
//!  q (a snapshot of the fast loop) ─► poses ─► ActiveSet::update (broad, narrow, witnesses)
//!     penetration beyond the tolerance ─► backup: the cycle again at the last clean q,
//!                                         a program for its pairs, q reset there
//!     set of pairs changed            ─► Model::with_contacts + Program::new (symbolic here)
//!     features changed                ─► a witness table for the running program
//! ```

use std::sync::Arc;

use super::bodies::{contact_bodies, jointed_pairs};
use crate::constraint::witness::Witness;
use crate::geometry::{ActiveSet, ContactSettings, Cycle, PairSpec, Pose3};
use crate::{BodyId, BuildError, Model, Objectives, Program, ProgramError, SolverSettings};

/// What the fast loop should be given after a cycle.
#[derive(Debug)]
pub enum ContactUpdate {
    /// Nothing changed that the fast loop needs.
    None,
    /// Witness features changed inside tracked pairs: [`ContactManager::table`]
    /// holds the new table for [`ContactManager::current_model`].
    Table,
    /// The set of tracked pairs changed (or a penetration was backed up):
    /// run `program` from now on. With `reset`, its q replaces the running
    /// one (the backup to the last clean configuration); without, the running
    /// state carries over.
    Program {
        /// The program, its witness table applied.
        program: Box<Program>,
        /// The configuration to restart from (a backup), if any.
        reset: Option<Vec<f64>>,
    },
}

/// Why a contact program could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ContactError {
    /// The model with the contact rows could not be built.
    #[error("contact rows: {0}")]
    Build(#[from] BuildError),
    /// Its program could not be built (its message is the program's: a
    /// prefix here would print twice in an error chain).
    #[error(transparent)]
    Program(#[from] ProgramError),
}

/// The slow loop's contact state (see the module docs).
#[derive(Debug)]
pub struct ContactManager {
    active: ActiveSet,
    /// The mechanism without contact rows.
    base: Arc<Model>,
    /// The model of the program the fast loop was last given.
    current: Arc<Model>,
    /// The pairs of `current`.
    pairs: Vec<PairSpec>,
    settings: SolverSettings,
    /// The design objectives every program it builds carries.
    objectives: Arc<Objectives>,
    table: Vec<Witness>,
    /// The table the fast loop last received (with `current`'s program or
    /// as a table).
    published: Vec<Witness>,
    /// q of the last snapshot without a penetration beyond the tolerance.
    last_clean: Option<Vec<f64>>,
    poses: Vec<Pose3>,
    /// Programs the fast loop handed back, by the pairs their model holds
    /// (most recently returned last), for reuse when the same set of pairs
    /// comes back: no model to build, no symbolic analysis.
    cache: Vec<Program>,
    /// How the last programs were obtained.
    builds: BuildCounts,
    /// Scratch: each body's expected motion over the next cycle, m.
    expected: Vec<f64>,
    /// Bodies out of the scene (a semantic schedule's removals): in no pair.
    absent: Vec<u32>,
    /// A penetration (not a tunnel) this deep or shallower is not backed up
    /// ([`set_backup_floor`](Self::set_backup_floor)); 0: every one is.
    backup_floor_m: f64,
}

/// How many contact programs were built new and how many taken from the
/// cache by structure.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BuildCounts {
    /// Built: model with contact rows, program, symbolic analysis.
    pub built: u64,
    /// Reused from the cache (a set of pairs seen before).
    pub reused: u64,
    /// Whether the last program was reused.
    pub last_reused: bool,
}

/// Programs kept for reuse: contacts that flicker between a few sets of pairs
/// find theirs; a cluttered scene's stream of new sets does not grow memory.
pub const PROGRAM_CACHE: usize = 8;

impl ContactManager {
    /// The contact manager of `base` (`None` when fewer than two bodies have
    /// a shape: such scenes compile without any contact machinery).
    pub fn new(
        base: Arc<Model>,
        settings: SolverSettings,
        contact: ContactSettings,
    ) -> Option<Self> {
        let bodies = contact_bodies(&base, settings.dynamics);
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
            objectives: Arc::new(Objectives::default()),
            table: Vec::new(),
            published: Vec::new(),
            last_clean: None,
            poses: Vec::new(),
            cache: Vec::new(),
            builds: BuildCounts::default(),
            expected: Vec::new(),
            absent: Vec::new(),
            backup_floor_m: 0.0,
        })
    }

    /// The same manager building its programs with `objectives` (by
    /// default none, every built-in weight 1).
    pub fn with_objectives(mut self, objectives: Arc<Objectives>) -> Self {
        self.objectives = objectives;
        self
    }

    /// Takes back a program the fast loop handed back (it is replaced): kept
    /// for reuse when its set of pairs comes back (the oldest is dropped past
    /// [`PROGRAM_CACHE`]; one of a mechanism replaced by
    /// [`rebase`](Self::rebase) is dropped). Allocates (slow thread).
    pub fn recycle(&mut self, program: Program) {
        if program.model().semantic() != self.base.semantic() {
            // A program of the mechanism before a rebase (other semantic
            // rows or holds): never to be handed out again.
            return;
        }
        if program.model().contact().specs.is_empty() && self.pairs.is_empty() {
            // The bare mechanism's program: Program::new is cheap for it.
            return;
        }
        self.cache
            .retain(|p| p.model().contact().specs != program.model().contact().specs);
        self.cache.push(program);
        if self.cache.len() > PROGRAM_CACHE {
            self.cache.remove(0);
        }
    }

    /// Takes `base` as the mechanism from now on (the same bodies and
    /// layout with other joints: satisfied semantic constraints, a hand's
    /// holds; its jointed pairs stop colliding), runs a cycle at `q` and
    /// returns the program for it and the pairs in reach. Programs kept for
    /// reuse belonged to the old mechanism and are dropped. Allocates.
    pub fn rebase(&mut self, base: Arc<Model>, q: &[f64]) -> Result<Program, ContactError> {
        self.base = base;
        self.active.set_excluded(self.excluded());
        self.cache.clear();
        let _ = self.cycle(q);
        self.build_program()
    }

    /// Takes the bodies `absent` out of every pair from now on (and puts
    /// back those no longer listed): objects removed from the scene, or not
    /// added yet. The next cycle (or [`rebase`](Self::rebase)) builds the
    /// program for the pairs that remain.
    pub fn set_absent(&mut self, absent: &[u32]) {
        self.absent = absent.to_vec();
        self.active.set_excluded(self.excluded());
    }

    /// The pairs that never collide: jointed pairs and every pair with an
    /// absent body.
    fn excluded(&self) -> Vec<[u32; 2]> {
        let n = self.base.bodies().len() as u32;
        let mut out = jointed_pairs(&self.base);
        for &a in &self.absent {
            out.extend((0..n).filter(|&b| b != a).map(|b| [a, b]));
        }
        out
    }

    /// Backs up only penetrations deeper than `depth_m` (and tunnels) from
    /// now on; 0 (the default) backs up every one beyond the tolerance. The
    /// session raises it when backups in a row do not clear a penetration
    /// (the rows put the bodies back where the exact check finds them
    /// inside each other, and each reset only pulls the world back to a
    /// configuration the hand has left), and lowers it again after a clean
    /// cycle. A cycle it holds still never counts as clean.
    pub fn set_backup_floor(&mut self, depth_m: f64) {
        self.backup_floor_m = if depth_m.is_finite() {
            depth_m.max(0.0)
        } else {
            0.0
        };
    }

    /// How the contact programs so far were obtained.
    pub fn builds(&self) -> BuildCounts {
        self.builds
    }

    /// The first cycle, at `q` (before the clock starts): the program the
    /// session starts with, its witness table applied and q set. Allocates.
    pub fn initial(&mut self, q: &[f64]) -> Result<(Cycle, Program), ContactError> {
        let cycle = self.cycle(q);
        self.last_clean = Some(q.to_vec());
        let mut program = self.build_program()?;
        program.set_q(q)?;
        Ok((cycle, program))
    }

    /// One cycle on a snapshot `q` of the fast loop (`solved`: its tick
    /// succeeded). `may_send_program`: the caller can hand a program over now
    /// (none is in flight); otherwise a structure change waits for a later
    /// cycle and only tables are produced. Allocates (slow thread).
    pub fn step(
        &mut self,
        q: &[f64],
        solved: bool,
        may_send_program: bool,
    ) -> (Cycle, ContactUpdate) {
        let cycle = self.cycle(q);
        let penetrating = !cycle.backups.is_empty();
        if !penetrating && solved {
            match &mut self.last_clean {
                Some(v) if v.len() == q.len() => v.copy_from_slice(q),
                _ => self.last_clean = Some(q.to_vec()),
            }
        }
        if !may_send_program {
            return (cycle, self.table_update());
        }
        let held = cycle.tunnels == 0 && cycle.max_penetration_m <= self.backup_floor_m;
        if penetrating
            && !held
            && let Some(clean) = self.last_clean.clone()
        {
            // Backup (§3.2): revert to the last clean configuration, where the
            // pairs that penetrated are tracked (they were seen moving that
            // far), and retry from there.
            let again = self.cycle(&clean);
            let mut cycle = cycle;
            cycle.witness_changes += again.witness_changes;
            cycle.expansions += again.expansions;
            cycle.structure_changed |= again.structure_changed;
            return match self.build_program() {
                Ok(program) => (
                    cycle,
                    ContactUpdate::Program {
                        program: Box::new(program),
                        reset: Some(clean),
                    },
                ),
                Err(_) => (cycle, ContactUpdate::None),
            };
        }
        if self.active.pairs() != self.pairs {
            return match self.build_program() {
                Ok(mut program) => {
                    // Factored here at the snapshot, so the fast thread
                    // takes it over without refactoring (a q of another
                    // layout leaves it unprepared: the fast thread refactors).
                    let _ = program.prepare_handover(q);
                    (
                        cycle,
                        ContactUpdate::Program {
                            program: Box::new(program),
                            reset: None,
                        },
                    )
                }
                Err(_) => (cycle, ContactUpdate::None),
            };
        }
        (cycle, self.table_update())
    }

    /// A table for the running program if its witnesses changed.
    fn table_update(&mut self) -> ContactUpdate {
        if self.active.pairs() != self.pairs {
            // The running program has other pairs: its table cannot hold
            // these; wait until the structure change can be sent.
            return ContactUpdate::None;
        }
        self.active.fill(&mut self.table);
        if self.table == self.published {
            return ContactUpdate::None;
        }
        self.published.clone_from(&self.table);
        ContactUpdate::Table
    }

    /// The velocities of the bodies at the next snapshot: per model body,
    /// its speed and angular speed (m/s, rad/s; fixed bodies 0), and the
    /// time until the cycle after it, s. The next [`step`](Self::step)
    /// tracks pairs as far ahead as they will move in that time
    /// (`ActiveSet::set_expected_motion`). Allocates only when the body
    /// count changes.
    pub fn set_speeds(&mut self, speeds: &[[f64; 2]], horizon_s: f64) {
        let radii = self.active.radii();
        self.expected.clear();
        self.expected.extend(
            speeds
                .iter()
                .zip(radii.iter().copied().chain(std::iter::repeat(0.0)))
                .map(|(&[v, w], r)| (v + r * w) * horizon_s),
        );
        self.active.set_expected_motion(&self.expected);
    }

    /// The poses of the last cycle, one per model body.
    pub fn poses(&self) -> &[Pose3] {
        &self.poses
    }

    /// The model of the program last built (re-projections build on it).
    pub fn current_model(&self) -> &Arc<Model> {
        &self.current
    }

    /// The witness table of [`current_model`](Self::current_model), as last
    /// published.
    pub fn published(&self) -> &[Witness] {
        &self.published
    }

    /// The active set (tracked pairs, their witnesses).
    pub fn active_set(&self) -> &ActiveSet {
        &self.active
    }

    /// A program for the current model with the published table (for a
    /// re-projection sent by the caller). Allocates.
    pub fn program_for_current(&self) -> Result<Program, ProgramError> {
        let mut program =
            Program::with_objectives(self.current.clone(), self.objectives.clone(), self.settings)?;
        program.apply_witnesses(&self.published);
        Ok(program)
    }

    fn cycle(&mut self, q: &[f64]) -> Cycle {
        self.poses.clear();
        for i in 0..self.base.bodies().len() {
            let id = BodyId(i as u32);
            let pose = match (
                self.base.body_position(q, id),
                self.base.body_rotation(q, id),
            ) {
                (Some(r), Some(rot)) => Pose3 { r, rot },
                _ => Pose3::IDENTITY,
            };
            self.poses.push(pose);
        }
        self.active.update(&self.poses)
    }

    /// A program for the active set's pairs, its table applied: reused from
    /// the cache when one for exactly these pairs came back, else built.
    fn build_program(&mut self) -> Result<Program, ContactError> {
        let pairs = self.active.pairs();
        self.active.fill(&mut self.table);
        let cached = self
            .cache
            .iter()
            .position(|p| p.model().contact().specs == pairs);
        let program = match cached {
            Some(k) => {
                let mut program = self.cache.remove(k);
                program.reset_witnesses(&self.table);
                self.builds.reused += 1;
                self.builds.last_reused = true;
                program
            }
            None => {
                let model = Arc::new(self.base.with_contacts(&pairs)?);
                let mut program =
                    Program::with_objectives(model, self.objectives.clone(), self.settings)?;
                program.reset_witnesses(&self.table);
                self.builds.built += 1;
                self.builds.last_reused = false;
                program
            }
        };
        self.current = program.model_arc().clone();
        self.pairs = pairs;
        self.published.clone_from(&self.table);
        Ok(program)
    }
}
