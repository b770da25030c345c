//! Handing a new contact program to the fast loop without a factorisation
//! on the fast thread.
//!
//! ```text
//!  slow thread, a new set of pairs:  Program::new / cached ─► prepare_handover(snapshot q)
//!                                    (evaluation + Eq. 7 factor at that q, touching rows active)
//!  fast thread, the swap:            adopt_state: q, motion, multipliers carried over;
//!                                    the prepared factor is kept (no refactorisation)
//! ```
//!
//! Until the first tick's force solve refactors at its end, its projected
//! steps run on the factor of A = D C_q M̃⁻¹ C_qᵀ D made at the snapshot a
//! few milliseconds old, with C_q of the same moment: a chord step, as
//! every step after a tick's first already is; C (the residual) is
//! evaluated at every step. A contact row the step would push through is
//! activated and the step retaken with a fresh factor (`MAX_ACTIVATIONS`
//! per tick), as for any row.
//!
//! A witness table (features changed inside the pairs) is still copied in
//! and refactored on the fast thread (`Program::apply_witnesses`; in
//! quasi-static programs one evaluation and one factorisation, no whole
//! force solve): copied in with C_q re-evaluated but the old factor kept,
//! the penetration on `cluttered` grew 700×; copied in after the tick's
//! steps, before the evaluation the force solve factors, `arm-push`'s joint
//! violation grew from 6.6e-10 m to 2.4e-6 m, and `cluttered` in real time
//! went beyond its penetration tolerance in 4 of 6 runs (main: 0 of 6)
//! (BENCHMARKS.md, issue 23).

use super::{Program, ProgramError, TickOutcome};
use crate::al::scaling::Role;
use crate::force::INEQUALITY_ACTIVE_BAND;

impl Program {
    /// Prepares a program the slow thread is about to hand over for a
    /// snapshot's configuration `q`: q set there (as [`set_q`](Self::set_q))
    /// and the Eq. 7 matrix factored at it with every contact and
    /// inequality row that touches (C within [`INEQUALITY_ACTIVE_BAND`])
    /// active, as the running program's pushing rows are. The next
    /// [`adopt_state`](Self::adopt_state) then keeps this factor instead of
    /// refactoring on the fast thread.
    ///
    /// Slow thread: two evaluations and force solves.
    pub fn prepare_handover(&mut self, q: &[f64]) -> Result<(), ProgramError> {
        self.set_q(q)?;
        // Under inertial motion Eq. 7 takes the steps' filtered contact
        // forces as known (`force::feedback::contact_forces_known`): that
        // history is the running program's, so a factor solved here without
        // it is not the one the fast loop needs (a pinch's contact reported
        // a 1.6 N pull with it). Such programs refactor on adoption.
        if crate::force::feedback::contact_forces_known(&self.settings) {
            self.prepared = false;
            return Ok(());
        }
        let c = self.ev.values();
        let mut any = false;
        for (i, f) in self.feedback.forced.iter_mut().enumerate() {
            let touching = matches!(self.scaling.role[i], Role::Contact | Role::Inequality)
                && c[i] <= INEQUALITY_ACTIVE_BAND;
            *f = touching;
            any |= touching;
        }
        if any {
            // Kept through the solve (not re-decided by zero multipliers);
            // a touching row that would pull is released there as always.
            self.feedback.carry_forced = true;
            if !matches!(self.refresh(), TickOutcome::Ok) {
                // The plain refresh of `set_q` stands in for it.
                let _ = self.refresh();
            }
        }
        self.feedback.carry_forced = false;
        self.prepared = true;
        Ok(())
    }

    /// Whether the program's factor was prepared on the slow thread for the
    /// hand-over ([`prepare_handover`](Self::prepare_handover)) and not yet
    /// taken over.
    pub fn is_prepared(&self) -> bool {
        self.prepared
    }

    /// [`adopt_state`](Self::adopt_state) without its refactorisation, for a
    /// caller that moves q right after (`shift_q`, `set_q`: they refactor).
    ///
    /// # Real-time
    /// As `adopt_state`, without the evaluation and force solve.
    pub fn adopt_state_unfactored(&mut self, old: &Program) {
        self.prepared = true;
        self.adopt_state(old);
    }

    /// Refactors the Eq. 7 matrix at the current q (a hand-over whose
    /// correction could not be applied, see `Handover::take_over`).
    ///
    /// # Real-time
    /// No allocation; one evaluation and one force solve.
    pub fn refresh_factor(&mut self) -> bool {
        let ok = matches!(self.refresh(), TickOutcome::Ok);
        self.joint_resync(crate::reduced::History::Keep);
        ok
    }

    /// Bounds the motion of the next ticks by the age of the witness data
    /// they run on: at most `ticks` ticks' worth of the contact speed limit
    /// (`SolverSettings::contact_step_m`, per shaped body), 1 a tick as
    /// before when more is left, none at all at 0 (the bodies stop where they
    /// are). The session sets it every tick from the motion since the
    /// snapshot its witness rows were computed at, so a slow loop that is
    /// late (a long program build, a descheduled thread) slows the bodies to
    /// a stop instead of letting them run past rows built for where they
    /// were. No effect without a contact speed limit.
    ///
    /// # Real-time
    /// No allocation.
    pub fn set_contact_budget(&mut self, ticks: f64) {
        self.contact_budget = if ticks.is_nan() { 0.0 } else { ticks };
    }

    /// How much of the contact speed limit the last tick used, in ticks'
    /// worth (0–1; 0 without a contact speed limit or after a failed tick):
    /// the largest motion of a shaped body's points over its allowance.
    pub fn last_contact_motion(&self) -> f64 {
        if !self.contact_step_m.is_finite() || !self.tick_budget.is_finite() {
            return 0.0;
        }
        (self.tick_budget - self.step_budget_m).clamp(0.0, 1.0)
    }
}
