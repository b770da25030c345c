//! A joint tick that fails for a reason other than bad input (a factor not
//! positive, a degenerate pose, a divergence limit, non-finite outputs) is
//! run again, in the same call, as the augmented tick (whose machinery a
//! joint program keeps built) from the unchanged q.
//!
//! Before it, the augmented state is brought to q as `set_q` does, without
//! allocating: `q_ref` = q, the augmented motion history at rest at q (the
//! augmented force stage's history is not kept by joint ticks, so it is the
//! only history that is correct there), then `refresh` (C_q and the force
//! factor at q toward the last targets). The fallback tick is therefore the
//! tick an augmented-only program gives after `set_q(q)`: bit for bit when
//! its multipliers and last targets are the same (a test). If the refresh
//! or the augmented tick fails, its failure stands (q restored, outputs
//! zero). Either way the joint tick is then resynced at the program's q with
//! its motion history at rest, and the next tick tries joint coordinates
//! again. [`Program::joint_fallbacks`] counts fallbacks.
//!
//! **The tree rows after a fallback.** An augmented tick leaves the tree
//! joints and the quaternion norms slightly open (it closes them over
//! later ticks), and joint ticks never evaluate those rows: forward
//! kinematics would keep them at whatever q the joint tick was resynced
//! at, for the rest of the run (BENCHMARKS.md, issue 23, the joint tick at
//! the extremes: a tree row 3.2e-4 m open and |e|² off by 8.6e-3 on
//! Peaucellier). So the joint tick after a fallback first projects q onto
//! the tree (`JointTick::project_onto_tree`: norms and tree rows closed to
//! round-off, the loop rows left to its steps) and resyncs there.
//! The fallback tick itself stays the augmented tick, bit for bit. If it
//! ends with a row open beyond the opening trigger's floor (1e-2 L), the
//! ticks after it run augmented, continuing its state, until one ends
//! within it (`joint_recovery`): next to a singular pose the joint tick
//! would open the loops again (the four-bar's 1 m step: 15.0 mm and 4
//! fallbacks without this, 12.8 mm for the augmented tick).

use super::stages::{Ordered, StageMarks};
use super::tick::{max_scaled_change, within};
use super::{Program, TickOutcome, TickReport};
use crate::FingerTarget;
use crate::reduced::History;

/// A joint tick whose loop rows end more open than they started and
/// beyond this × L falls back to the augmented tick ([`opens_loops`]).
pub(super) const OPENING_FLOOR: f64 = 1e-2;

/// Whether a joint tick opened its loops: near a singular pose (the
/// four-bar pulled taut) the chord iteration in joint coordinates opens the
/// loop rows 1.5–5× a tick, and further than the augmented tick does
/// (forward kinematics carries each joint's second-order error down the
/// chain to the loop-closing rows); no step or violation limit catches it
/// before 0.1 L. A tick that works closes its loop rows (they are hard
/// rows, whatever the target does). `before` and `after` are the loop
/// rows' largest |C| at the tick's start and end (metres and radians),
/// `length_m` is L. NaN is caught by the step check after it.
#[inline]
pub(super) fn opens_loops(before: f64, after: f64, length_m: f64) -> bool {
    after > before && after > OPENING_FLOOR * length_m
}

/// A failure injected into the next joint tick (tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Injected {
    /// The fallback fails too, as if the refresh at q had failed.
    augmented_too: bool,
}

/// Whether a joint tick's failure falls back to the augmented tick: every
/// failure but bad input (bad targets, a zero time step), which the
/// augmented tick would refuse the same way.
pub(super) fn falls_back(status: &TickOutcome) -> bool {
    !matches!(status, TickOutcome::Eval(_) | TickOutcome::ZeroDt)
}

impl Program {
    /// Joint ticks that failed and were run as augmented ticks instead
    /// (0 for a program ticking in augmented coordinates).
    pub fn joint_fallbacks(&self) -> u64 {
        self.joint_fallbacks
    }

    /// Ticks run augmented after a fallback that left the rows open (see
    /// the module docs; 0 for a program ticking in augmented coordinates).
    pub fn joint_recovery_ticks(&self) -> u64 {
        self.joint.as_ref().map_or(0, |j| j.recovery_ticks)
    }

    /// Makes the next joint tick fail (as a force solve would), so that it
    /// falls back to the augmented tick; with `augmented_too` the fallback
    /// fails as well (as a failed refresh at q). False (nothing injected)
    /// for a program without a joint tick. For tests.
    #[doc(hidden)]
    pub fn fail_next_joint_tick(&mut self, augmented_too: bool) -> bool {
        let Some(j) = self.joint.as_mut() else {
            return false;
        };
        j.inject = Some(Injected { augmented_too });
        true
    }

    /// The augmented tick for a failed joint tick's call, from the
    /// unchanged q (see the module docs); the joint tick resynced after.
    ///
    /// # Real-time
    /// No allocation: one refresh (evaluation and factorisation), one
    /// augmented tick, one joint resync.
    pub(super) fn joint_fallback<M: StageMarks>(
        &mut self,
        targets: &[FingerTarget],
        dt_s: f64,
        marks: &mut Ordered<'_, M>,
    ) -> TickReport {
        self.joint_fallbacks += 1;
        let injected = self.joint.as_mut().and_then(|j| j.inject.take());
        self.q_ref.copy_from_slice(&self.q);
        self.feedback.motion.reset(&self.q);
        self.reset_velocities();
        let refreshed = match injected {
            Some(Injected {
                augmented_too: true,
            }) => TickOutcome::ForceSolve,
            _ => self.refresh(),
        };
        let report = match refreshed {
            TickOutcome::Ok => {
                let n = self.settings.iterations;
                self.run_tick(targets, dt_s, n, marks)
            }
            status => self.failed(status, 0),
        };
        self.joint_resync(History::Rest);
        let open = self.open_beyond_floor(&report);
        if report.status == TickOutcome::Ok
            && let Some(j) = self.joint.as_mut()
        {
            j.project = true;
            j.recovering = open;
        }
        report
    }

    /// Whether a tick's report has a row open beyond the opening trigger's
    /// floor (`OPENING_FLOOR` × L; angles and norms times L).
    fn open_beyond_floor(&self, r: &TickReport) -> bool {
        let l = self.scaling.length_m;
        let worst = r
            .max_violation_m
            .max(l * r.max_violation_rad)
            .max(l * r.max_norm_violation);
        // NaN-safe: a NaN report counts as open.
        !within(worst, OPENING_FLOOR * l)
    }

    /// A tick after a fallback that left the rows open beyond the opening
    /// trigger's floor: the augmented tick, continuing from the
    /// fallback's (the joint tick next to a singular pose opens its loops
    /// again, BENCHMARKS.md), until a tick ends within the floor; the next
    /// tick is then a joint tick (which first projects q onto the tree).
    ///
    /// # Real-time
    /// No allocation: one augmented tick.
    pub(super) fn joint_recovery<M: StageMarks>(
        &mut self,
        targets: &[FingerTarget],
        dt_s: f64,
        marks: &mut Ordered<'_, M>,
    ) -> TickReport {
        let report = if dt_s > 0.0 {
            let n = self.settings.iterations;
            self.run_tick(targets, dt_s, n, marks)
        } else {
            self.failed(TickOutcome::ZeroDt, 0)
        };
        let closed = report.status == TickOutcome::Ok && !self.open_beyond_floor(&report);
        if let Some(j) = self.joint.as_mut() {
            j.recovery_ticks += 1;
            j.recovering = !closed;
            j.project = true;
        }
        report
    }

    /// The joint tick's first act after a fallback (or a resync that found
    /// the tree rows open): q projected onto the tree, the joint tick
    /// resynced there, its motion history shifted (the outputs are the next
    /// tick's). A projection that fails (a degenerate quaternion)
    /// or would move q beyond the step limit (a corrupted q) leaves q and
    /// the joint tick stale: the tick falls back.
    ///
    /// # Real-time
    /// No allocation: one pass over the tree joints, one joint resync.
    pub(super) fn joint_project(&mut self) {
        let Some(j) = self.joint.as_mut() else {
            return;
        };
        j.project = false;
        self.q_ref.copy_from_slice(&self.q);
        // A projection further than the step limit (a corrupted q) is
        // refused as a step would be: the tick falls back, and the
        // augmented tick reports it.
        if j.tick.project_onto_tree(&mut self.q_ref).is_err()
            || !within(
                max_scaled_change(&self.q_ref, &self.q, &self.scaling.sqrt_metric),
                self.limits.step_m,
            )
        {
            j.stale = true;
            return;
        }
        self.q.copy_from_slice(&self.q_ref);
        // A correction, not a motion (after a fallback the history is at
        // rest already).
        self.joint_resync(History::Shift);
    }
}
