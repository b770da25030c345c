//! What the two loops send each other: the fast loop's [`Snapshot`] (every
//! tick, newest wins) and the slow loop's [`Handover`] (a program and how it
//! corrects the configuration it adopts). Both loops and the contact loop
//! depend on this module and on no other loop's, so `fast`, `slow` and
//! `contact` form no import cycle.

use haptloop_solver::Program;
use std::time::Duration;

/// How a handed-over program corrects the configuration it adopts.
#[derive(Debug, Clone)]
pub enum Correction {
    /// Keep the adopted q (a structure change).
    None,
    /// Add this displacement to the adopted q, keeping velocities: a
    /// re-projection computed for a snapshot a few ticks old.
    Shift(Vec<f64>),
    /// Replace q and restart the motion at rest: recovery from a broken
    /// configuration, placed from the last good one.
    Reset(Vec<f64>),
}

/// Which snapshot the witness rows of a handed-over program were computed
/// at (`witness_age`: the motion they are trusted for counts from there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RowsStamp {
    /// The rows the fast loop runs on now (a re-projection, a semantic
    /// change: the published table): keep counting from their snapshot.
    Keep,
    /// Computed at a snapshot that carried this [`Snapshot::contact_motion`].
    At(f64),
    /// Computed at the configuration the hand-over resets q to (a backup).
    Fresh,
}

/// What the slow loop sends the fast loop.
pub struct Handover {
    /// The program to run from now on.
    pub program: Program,
    /// What to do with the adopted configuration.
    pub correction: Correction,
    /// Grid slot of the snapshot it answers (contact changes: the latency
    /// from a witness change to the fast loop using it is measured from it).
    pub snapshot_tick: Option<u64>,
    /// Which snapshot its witness rows come from.
    pub rows: RowsStamp,
    /// The slow loop found the world broken (a penetration beyond the
    /// session's bound): the fast loop cuts the force when it takes this
    /// over, as after a failed tick.
    pub broken: bool,
    /// The witness-frame generation of its table (contact programs).
    pub generation: Option<u64>,
}

impl Handover {
    /// A program without a correction (the initial one).
    pub fn new(program: Program) -> Self {
        Handover {
            program,
            correction: Correction::None,
            snapshot_tick: None,
            rows: RowsStamp::Keep,
            broken: false,
            generation: None,
        }
    }

    /// Called on the fast thread when `self` replaces `old`: carries the
    /// running state over, then applies the correction.
    ///
    /// # Real-time
    /// No allocation (the correction vector was allocated by the slow loop).
    /// A program prepared on the slow thread (`Program::prepare_handover`)
    /// keeps its factor; a correction refactors once, after the state is
    /// carried over (not before as well).
    pub fn take_over(&mut self, old: &Handover) {
        let p = &mut self.program;
        match &self.correction {
            Correction::None => p.adopt_state(&old.program),
            Correction::Shift(dq) => {
                p.adopt_state_unfactored(&old.program);
                if p.shift_q(dq).is_err() {
                    p.refresh_factor();
                }
            }
            Correction::Reset(q) => {
                p.adopt_state_unfactored(&old.program);
                if p.set_q(q).is_err() {
                    p.refresh_factor();
                }
            }
        }
    }
}

/// What the fast loop hands the slow loop every tick (newest wins).
#[derive(Debug, Clone, Default)]
pub struct Snapshot {
    /// Grid slot of the tick.
    pub tick: u64,
    /// Session time, grid-aligned.
    pub time: Duration,
    /// Configuration after the tick (program layout).
    pub q: Vec<f64>,
    /// Largest length-row violation, m.
    pub max_violation_m: f64,
    /// Largest angle-row violation, rad.
    pub max_violation_rad: f64,
    /// False if the tick's solve failed or the mechanism came apart.
    pub solved: bool,
    /// Each finger's force as the solver computed it (on the finger, N,
    /// scene frame; before the safety layer): what the hand pulls with.
    pub finger_force_n: Vec<[f64; 3]>,
    /// Largest length-row violation of every tick since the snapshot the
    /// slow loop last took, this one's included, m: the slow loop looks
    /// every few ticks, and a violation that comes and goes with its period
    /// must not slip between its looks.
    pub peak_violation_m: f64,
    /// Per model body: speed (m/s) and angular speed (rad/s) over the tick
    /// (the contact cycle tracks pairs as far ahead as they will move).
    pub speeds: Vec<[f64; 2]>,
    /// The bodies' motion so far, ticks' worth of the contact speed limit
    /// (`witness_age`): rows computed at this snapshot are stamped with it.
    pub contact_motion: f64,
}
