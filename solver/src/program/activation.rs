//! The projected update's activation within a tick: a step predicted that
//! inactive inequality rows would be violated, so they join the active set
//! and A is refactored before the step is taken again.
//!
//! The steps need A's factor (with the finger block's Schur complement)
//! and the row scales, not multipliers: the step solves for its own y with
//! that factor. With the Cholesky force solver the activation therefore
//! refactors only (`Feedback::refactor_for_steps`: the same activation, the
//! same assembly and factor as `Feedback::force_active`) and skips the
//! multiplier solve, whose results the tick's force solve overwrites before
//! anything reads them (its release test, the finger wrenches and the
//! contact forces all read the multipliers of its own solve). Other force
//! solvers keep the whole `force_active`.

use super::Program;
use crate::ForceSolver;

impl Program {
    /// Refactors with the rows a step marked in `Feedback::forced` active;
    /// false when the factorisation failed.
    ///
    /// # Real-time
    /// No allocation; one assembly and numeric factorisation (plus a
    /// multiplier solve with the CG and matvec force solvers).
    pub(super) fn activate_in_tick(&mut self) -> bool {
        if self.settings.force_solver == ForceSolver::Cholesky && !self.full_activation {
            self.feedback
                .refactor_for_steps(&self.scaling, &self.settings, &self.ev, &self.lambda)
                .is_ok()
        } else {
            self.feedback
                .force_active(&self.scaling, &self.settings, &self.ev, &self.lambda)
                .is_ok()
        }
    }

    /// Makes an in-tick activation run a whole multiplier solve
    /// (`Feedback::force_active`) as well as the refactorisation (`full`),
    /// or refactor only (the default with the Cholesky solver). For
    /// comparisons.
    pub fn set_full_activation(&mut self, full: bool) {
        self.full_activation = full;
    }
}
