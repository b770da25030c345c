//! The program's contact state between the slow loop's witness updates:
//! the witness table it runs on and the fingertips' friction stick anchors.
//!
//! **Witness updates.** The slow loop publishes a witness table for the
//! program's model ([`Program::apply_witnesses`]); the fast loop copies it in
//! at a tick boundary (no allocation: the table's length is the model's) and
//! refactors once: for a quasi-static program only what the next steps use
//! (evaluation, activation, one factorisation: `refresh_chord`), not a whole
//! force solve. A fingertip's friction anchors are the fast loop's own
//! while its contact persists: a stuck contact must not jump to where the
//! slow loop saw it a few milliseconds ago.
//!
//! **Inertial motion** (`SolverSettings::dynamics`) has its own module:
//! the prediction, Coulomb friction on the step's forces, restitution and
//! the energy account are in `program::inertial` over `crate::dynamics`.
//! The anchoring below is the quasi-static mode's (a fingertip's friction
//! judged against the user's grip).

use nalgebra::Vector3;

use super::Program;
use crate::constraint::witness::Witness;
use crate::force::INEQUALITY_ACTIVE_BAND;
use crate::force::friction::STICK_SPEED_M_S;

impl Program {
    /// Copies a witness table from the slow loop into the running program and
    /// refactors. `false` (nothing changed) when its length is not this
    /// model's [`ContactLayout::slots`](crate::ContactLayout::slots). Friction
    /// anchors of contacts that persist are kept (see the module docs).
    ///
    /// A quasi-static program with the projected update and no friction
    /// row sticking refactors only what its next steps use: C and C_q at q
    /// with the new table, the rows active there (as a force solve's
    /// activation decides them from C and the multipliers) and A's factor
    /// ([`refresh_chord`](Self::refresh_chord)); other programs run a whole
    /// force solve as a refresh.
    ///
    /// # Real-time
    /// No allocation; O(slots) copies, one evaluation and one Eq. 7
    /// assembly and factorisation (or a whole force solve, see above).
    pub fn apply_witnesses(&mut self, table: &[Witness]) -> bool {
        if !self.copy_witnesses(table) {
            return false;
        }
        let _ = self.refresh_chord();
        true
    }

    /// The refresh after a new witness table: evaluation, activation and
    /// one factorisation, without the force solve's multipliers and
    /// outputs, its release of
    /// pulling rows or its Coulomb judgement. The factor and row scales are
    /// those of [`refresh`](Self::refresh) at the same state: a force solve
    /// that releases a pulling row activates the rows again from C and the
    /// multipliers before it ends (the projected update keeps the kinematic
    /// active set), and with no friction row sticking there is no slip to
    /// judge. Under inertial motion, with the gradient update, another
    /// force solver than the Cholesky or a sticking friction row: a whole
    /// refresh.
    pub(super) fn refresh_chord(&mut self) -> super::TickOutcome {
        use super::TickOutcome;
        let chord = !self.settings.dynamics
            && self.settings.update == crate::UpdateRule::Projected
            && self.settings.force_solver == crate::ForceSolver::Cholesky
            && !self.feedback.stick.iter().any(|&s| s);
        if !chord {
            return self.refresh();
        }
        if let Err(e) = self.ev.evaluate(&self.model, &self.q, &self.last_targets) {
            return TickOutcome::Eval(e);
        }
        // As a refresh's force solve: rows forced active by earlier steps
        // are decided afresh (unless carried, see `Feedback::compute`).
        if !std::mem::take(&mut self.feedback.carry_forced) {
            self.feedback.forced.fill(false);
        }
        self.chord_refreshes += 1;
        match (self.feedback).refactor_for_steps(
            &self.scaling,
            &self.settings,
            &self.ev,
            &self.lambda,
        ) {
            Ok(()) => TickOutcome::Ok,
            Err(_) => TickOutcome::ForceSolve,
        }
    }

    /// Witness tables taken with the chord refresh (see
    /// [`apply_witnesses`](Self::apply_witnesses)) since the program was
    /// built.
    pub fn chord_refreshes(&self) -> u64 {
        self.chord_refreshes
    }

    /// Makes every projected step evaluate C and multiply C_q over every
    /// row (`full`), or only over the contact rows of bodies that move (the
    /// default, `al::moved`: the same values bit for bit). For comparisons.
    pub fn set_full_steps(&mut self, full: bool) {
        self.projected.set_full_steps(full, &self.model);
    }

    /// Makes every evaluation write every row (`full`), or leave alone the
    /// contact rows whose bodies and witnesses are unchanged since they were
    /// written (the default, `evaluate::since`: the same values and Jacobian
    /// bit for bit). For comparisons.
    pub fn set_full_evaluation(&mut self, full: bool) {
        self.ev.track_unmoved(&self.model, !full);
    }

    /// The evaluation the program runs on: C and C_q at the last evaluated
    /// q, and the witness table (for comparisons).
    pub fn evaluation(&self) -> &crate::Evaluation {
        &self.ev
    }

    /// Contact constraints the Jacobian evaluations left alone because
    /// neither body had moved and their witnesses were unchanged, summed
    /// over the program's life.
    pub fn evaluation_contacts_skipped(&self) -> u64 {
        self.ev.unmoved_contacts_skipped()
    }

    /// Contact constraints (a pair's witness rows) the projected steps
    /// left unevaluated because neither body had moved, summed over the
    /// program's life.
    pub fn step_contacts_skipped(&self) -> u64 {
        self.projected.skipped_contacts()
    }

    /// The copy of [`apply_witnesses`](Self::apply_witnesses), without the
    /// refresh.
    pub(super) fn copy_witnesses(&mut self, table: &[Witness]) -> bool {
        let keep = &self.friction_slot;
        // The contact slots: the table's head (semantic rows follow them).
        let n = self.model.contact().slots;
        let own = &mut self.ev.witnesses_mut()[..n];
        if table.len() != own.len() {
            return false;
        }
        for (i, (o, t)) in own.iter_mut().zip(table).enumerate() {
            if keep[i] && o.is_on() && t.is_on() {
                continue;
            }
            *o = *t;
        }
        true
    }

    /// Replaces the whole witness table, friction anchors included, and
    /// clears every stick flag: a program taken back into use for another
    /// moment (a recycled one, see `contact::ContactManager`) must carry
    /// nothing of its last use. `false` when the length is not this model's.
    /// Friction that survives the hand-over is then carried from the program
    /// it replaces by [`adopt_state`](Self::adopt_state).
    ///
    /// # Real-time
    /// No allocation; as [`apply_witnesses`](Self::apply_witnesses).
    pub fn reset_witnesses(&mut self, table: &[Witness]) -> bool {
        let n = self.model.contact().slots;
        let own = &mut self.ev.witnesses_mut()[..n];
        if table.len() != own.len() {
            return false;
        }
        own.copy_from_slice(table);
        self.feedback.stick.fill(false);
        self.inertial.slip.fill(Default::default());
        let _ = self.refresh();
        true
    }

    /// The witness table in use (the contact slots).
    pub fn witnesses(&self) -> &[Witness] {
        &self.ev.witnesses()[..self.model.contact().slots]
    }

    /// The largest pulling force of an active contact row in the last
    /// tick's force solve, N: 0 when every contact pushes. (A contact that
    /// would pull is released and the solve repeated; this is what remains.)
    pub fn contact_pull_n(&self) -> f64 {
        self.feedback.max_pull_n
    }

    /// Friction pairs that left the Coulomb cone (slipped) since the program
    /// was built.
    pub fn slips(&self) -> u64 {
        self.feedback.slips()
    }

    /// Friction anchors after a tick's steps, with C evaluated at the final q:
    /// a pair not touching (no active normal row within the band) neither
    /// sticks nor keeps its anchor; a slipping pair is re-anchored under the
    /// fingertip and sticks again once it slid less than
    /// [`STICK_SPEED_M_S`] × dt this tick. Returns true if an anchor moved
    /// (C must be evaluated again).
    pub(super) fn anchor_friction(&mut self, dt_s: f64) -> bool {
        let mut moved = false;
        for k in 0..self.feedback.friction.len() {
            let p = self.feedback.friction[k];
            let pair = &self.model.contact().pairs[self.friction_pair[k]];
            let normal_rows = self.model.constraints()[pair.normal.index()].rows.clone();
            let c = self.ev.values();
            let touching = normal_rows
                .clone()
                .any(|i| c[i] <= INEQUALITY_ACTIVE_BAND || self.lambda[i] > 0.0);
            let armed = self.ev.witnesses()[p.slots[0]].is_on();
            let stuck = self.feedback.stick[p.rows[0]];
            if stuck && touching && armed {
                continue;
            }
            let slip = c[p.rows[0]].hypot(c[p.rows[1]]);
            let (Some(a), Some(b)) = (
                self.model.body_frame(&self.q, pair.bodies[0]),
                self.model.body_frame(&self.q, pair.bodies[1]),
            ) else {
                continue;
            };
            // A's anchor (a fingertip's centre, a body's contact point) where
            // it is now, in B's frame.
            let anchor_a = match self.ev.witnesses()[p.slots[0]] {
                Witness::Plane(w) => w.point,
                _ => Vector3::zeros(),
            };
            let local: Vector3<f64> = b.rot.tr_mul(&(a.point(&anchor_a) - b.r));
            let table = self.ev.witnesses_mut();
            for s in p.slots {
                if let Witness::Plane(w) = &mut table[s] {
                    w.plane_point = local;
                    moved = true;
                }
            }
            let stick = armed && touching && slip <= STICK_SPEED_M_S * dt_s;
            for r in p.rows {
                self.feedback.stick[r] = stick;
            }
        }
        moved
    }

    /// Contact witness rows active in the last force solve.
    pub(super) fn active_contacts(&self) -> u32 {
        let scale = self.feedback.row_scale();
        self.model
            .contact()
            .pairs
            .iter()
            .flat_map(|p| self.model.constraints()[p.normal.index()].rows.clone())
            .filter(|&i| scale[i] != 0.0)
            .count() as u32
    }

    /// Friction pairs sticking after the last force solve.
    pub(super) fn sticking(&self) -> u32 {
        self.feedback
            .friction
            .iter()
            .filter(|p| {
                self.feedback.stick[p.rows[0]] && self.feedback.row_scale()[p.rows[0]] != 0.0
            })
            .count() as u32
    }
}
