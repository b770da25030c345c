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

use super::stages::{Ordered, StageMarks};
use super::{Program, TickOutcome, TickReport};
use crate::FingerTarget;
use crate::reduced::History;

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
        report
    }
}
