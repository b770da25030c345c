//! The slow loop: watches the fast loop's newest snapshot, re-projects the
//! mechanism with Newton-KKT placement when the fast loop's violation exceeds
//! its threshold, hands the result over through the program queue, and
//! collects (and drops, here, off the real-time thread) the programs the fast
//! loop hands back. It never blocks the fast loop: it only polls the mailbox
//! and the queue.

use super::fast::Snapshot;
use haptloop_rt::exchange::{MailboxReader, ProgramSender};
use haptloop_solver::{
    FingerId, FingerTarget, Model, Placement, Program, SolveInfo, SolveStatus, SolverSettings,
};
use nalgebra::UnitQuaternion;
use std::sync::Arc;

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

/// What the slow loop sends the fast loop.
pub struct Handover {
    /// The program to run from now on.
    pub program: Program,
    /// What to do with the adopted configuration.
    pub correction: Correction,
}

impl Handover {
    /// A program without a correction (the initial one).
    pub fn new(program: Program) -> Self {
        Handover {
            program,
            correction: Correction::None,
        }
    }

    /// Called on the fast thread when `self` replaces `old`: carries the
    /// running state over, then applies the correction.
    ///
    /// # Real-time
    /// No allocation (the correction vector was allocated by the slow loop).
    pub fn take_over(&mut self, old: &Handover) {
        self.program.adopt_state(&old.program);
        match &self.correction {
            Correction::None => {}
            Correction::Shift(dq) => {
                let _ = self.program.shift_q(dq);
            }
            Correction::Reset(q) => {
                let _ = self.program.set_q(q);
            }
        }
    }
}

/// What the slow loop saw and did.
#[derive(Debug, Clone, Copy, Default)]
pub struct SlowStats {
    /// Steps run.
    pub steps: u64,
    /// Snapshots that were newer than the previous step's.
    pub fresh_snapshots: u64,
    /// Largest violation seen in a snapshot, m.
    pub max_seen_violation_m: f64,
    /// Re-projections started (violation over the threshold).
    pub reprojections: u64,
    /// Re-projections from the last good configuration (the snapshot was broken).
    pub recoveries: u64,
    /// Placements that did not converge (the result was still sent if finite).
    pub placements_not_converged: u64,
    /// Programs sent to the fast loop.
    pub programs_sent: u64,
    /// Replaced programs collected back and dropped here.
    pub programs_dropped: u64,
    /// The last placement's outcome.
    pub last_placement: Option<SolveInfo>,
}

/// The slow loop's state.
pub struct SlowLoop {
    pub(super) snapshots: MailboxReader<Snapshot>,
    pub(super) programs: ProgramSender<Handover>,
    pub(super) model: Arc<Model>,
    pub(super) settings: SolverSettings,
    pub(super) placement: Placement,
    /// Violation above which the fast loop's configuration is re-projected, m.
    pub(super) threshold_m: f64,
    /// Violation above which a snapshot is considered broken, m.
    pub(super) broken_m: f64,
    pub(super) last_good: Vec<f64>,
    pub(super) stats: SlowStats,
}

impl SlowLoop {
    /// One pass: collect returned programs, read the newest snapshot, and
    /// re-project if the fast loop has drifted past the threshold.
    pub fn step(&mut self) {
        self.stats.steps += 1;
        self.stats.programs_dropped += self.programs.collect_all() as u64;
        if !self.snapshots.refresh() {
            return;
        }
        self.stats.fresh_snapshots += 1;
        let snap = self.snapshots.latest();
        let v = snap.max_violation_m;
        self.stats.max_seen_violation_m = self.stats.max_seen_violation_m.max(v);
        let finite = v.is_finite() && snap.q.iter().all(|x| x.is_finite());
        if snap.solved && finite && v <= self.threshold_m {
            self.last_good.clear();
            self.last_good.extend_from_slice(&snap.q);
            return;
        }
        // One re-projection in flight at a time: wait until the fast loop has
        // swapped the last one in and handed its predecessor back.
        if self.programs.in_flight() > 0 {
            return;
        }
        let broken = !(snap.solved && finite && v <= self.broken_m);
        let recover = broken && !self.last_good.is_empty();
        let snapshot_q = snap.q.clone();
        self.reproject(&snapshot_q, recover);
    }

    fn reproject(&mut self, snapshot_q: &[f64], recover: bool) {
        self.stats.reprojections += 1;
        self.stats.recoveries += u64::from(recover);
        let mut q = if recover {
            self.last_good.clone()
        } else {
            snapshot_q.to_vec()
        };
        let q_ref = q.clone();
        // Keep every finger where it is (and a rigid grasp's body as it is
        // turned): re-projection repairs the joints, it does not move the user.
        let targets: Vec<FingerTarget> = self
            .model
            .fingers()
            .iter()
            .enumerate()
            .map(|(i, f)| FingerTarget {
                position_m: self
                    .model
                    .finger_point(&q, FingerId(i as u32))
                    .unwrap_or_default(),
                orientation: self
                    .model
                    .body_rotation(&q, f.body)
                    .map(|r| UnitQuaternion::from_matrix(&r))
                    .unwrap_or_else(UnitQuaternion::identity),
            })
            .collect();
        let info = match self.placement.solve(&self.model, &mut q, &q_ref, &targets) {
            Ok(info) => info,
            Err(_) => return,
        };
        self.stats.last_placement = Some(info);
        if info.status != SolveStatus::Converged {
            self.stats.placements_not_converged += 1;
        }
        if !q.iter().all(|x| x.is_finite()) {
            return;
        }
        let correction = if recover {
            Correction::Reset(q)
        } else {
            Correction::Shift(q.iter().zip(snapshot_q).map(|(a, b)| a - b).collect())
        };
        let Ok(program) = Program::new(self.model.clone(), self.settings) else {
            return;
        };
        if self
            .programs
            .try_send(Box::new(Handover {
                program,
                correction,
            }))
            .is_ok()
        {
            self.stats.programs_sent += 1;
        }
    }

    /// What it saw and did.
    pub fn stats(&self) -> SlowStats {
        self.stats
    }
}
