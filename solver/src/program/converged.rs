//! The converged reference of one fast tick: what the tick would have
//! rendered had its update run to convergence (slow thread; measures the
//! fast loop's force error).
//!
//! ```text
//!  fast program ──save_state──► TickState (before tick k)     TickState (after tick k)
//!                                      │                              │ velocities, accelerations
//!  reference program (its own settings: projected rule, reference gain)
//!     converged_tick(before, after, targets_k, dt):
//!        load `before` (q, multipliers, motion and coupling history, last targets)
//!        q₀ as the tick sets it (inertial prediction, objectives' pull)
//!        repeat: evaluate C, C_q at q; factor C_q M⁻¹ C_qᵀ afresh; full projected step
//!        until the step is below `tolerance_m` (Gauss–Newton on the tick's KKT system)
//!        Eq. 7–8 + coupling at q* with `after`'s velocities and accelerations
//!  ──► finger_outputs() (F*), q() (q*), ConvergedTick (iterations, last step, violation)
//! ```
//!
//! **The problem** is the tick's own (see `al::projected`): least
//! astonishment ½‖q − q₀‖² in the mass metric at the tick's start, fingers
//! as penalty rows of weight K m̄, joints, norms and the active limits as
//! equalities, with the reference program's K (the session uses a large one,
//! so that the reference is the hard-finger limit whatever gain the fast
//! loop runs). Every iteration refactors at the current iterate, so the
//! iteration is Gauss–Newton on the KKT system: its fixed point satisfies
//! C_J(q*) = 0 and stationarity exactly; only the rate (linear when a finger
//! cannot reach its target) depends on the constraints' curvature it leaves
//! out.
//!
//! **The same q̈ history**: the reference force uses the fast loop's own
//! velocity and acceleration estimates of tick k (`after`, filtered as the
//! fast loop filtered them) and its coupling history, so the force error is
//! what the configuration error does to Eq. 7–8 and to the coupling, not a
//! catch-up acceleration the fast loop never had.
//!
//! Limits: scenes with contact rows are not supported (their witness tables
//! change with the slow loop's active set); the caller reports them as not
//! measured.
//!
//! # Real-time
//! Not for the fast thread: `converged_tick` runs up to `max_iterations`
//! factorisations. [`Program::save_state`] is the fast-thread part: no
//! allocation into a [`TickState`] made by [`Program::tick_state`] for the
//! same model, O(coordinates + bodies + fingers).

use nalgebra::Vector3;

use super::{FingerOutput, Program, ProgramError, TickOutcome};
use crate::FingerTarget;
use crate::al::projected::{CouplingStep, Step, StepError};
use crate::al::update::Violation;

/// A step below this (scaled metres) that is not at most half the one
/// before it has reached round-off: with a large reference gain and a finger
/// that cannot reach its target (K m̄ ≫ the mechanism's mass in the step's
/// normal equations) the iteration stalls there, at 1e-11–1e-10 m measured
/// on the four-bar, instead of reaching 1e-12.
pub const ROUND_OFF_STEP_M: f64 = 1e-9;

/// What a program's tick reads of its history, copied out so that another
/// program of the same model can replay the tick ([`Program::save_state`],
/// [`Program::converged_tick`]).
#[derive(Debug, Clone, Default)]
pub struct TickState {
    q: Vec<f64>,
    lambda: Vec<f64>,
    pub(super) q_prev: Vec<f64>,
    pub(super) v: Vec<Vector3<f64>>,
    pub(super) w: Vec<Vector3<f64>>,
    pub(super) a: Vec<Vector3<f64>>,
    pub(super) alpha: Vec<Vector3<f64>>,
    aux_v: Vec<f64>,
    aux_a: Vec<f64>,
    /// The objectives' pull on flexible deformations (`program::objective`).
    static_shift: Vec<f64>,
    pub(super) ticks: u32,
    pub(super) prev_error: Vec<Vector3<f64>>,
    last_targets: Vec<FingerTarget>,
    last_dt_s: f64,
    /// Per design column: switched off.
    design_off: Vec<bool>,
    /// The bodies' own velocities (inertial motion's prediction).
    vel: crate::dynamics::velocity::Velocities,
}

impl TickState {
    /// The configuration, layout order.
    pub fn q(&self) -> &[f64] {
        &self.q
    }
}

/// How a converged reference tick went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConvergedTick {
    /// `Ok`, or why the reference could not be computed (its outputs are
    /// then zero and mean nothing).
    pub status: TickOutcome,
    /// Iterations run (each one factorisation and one full projected step).
    pub iterations: u32,
    /// Largest scaled coordinate change of the last step, metres.
    pub last_step_m: f64,
    /// The last step was at most the tolerance.
    pub converged: bool,
    /// Largest length-row violation of the mechanism at q*, metres.
    pub max_violation_m: f64,
}

/// Copies `src` into `dst`, reallocating only when the lengths differ.
fn copy<T: Copy>(dst: &mut Vec<T>, src: &[T]) {
    if dst.len() == src.len() {
        dst.copy_from_slice(src);
    } else {
        dst.clear();
        dst.extend_from_slice(src);
    }
}

impl Program {
    /// A [`TickState`] sized for this program's model, holding its current
    /// state. Allocates: call it off the real-time thread.
    pub fn tick_state(&self) -> TickState {
        let mut s = TickState::default();
        self.save_state(&mut s);
        s
    }

    /// Copies what the next tick reads (q, multipliers, motion and coupling
    /// history, last targets and period) into `out`.
    ///
    /// # Real-time
    /// No allocation when `out` came from [`tick_state`](Self::tick_state)
    /// of a program of the same model; O(coordinates + rows + bodies).
    pub fn save_state(&self, out: &mut TickState) {
        let mo = &self.feedback.motion;
        copy(&mut out.q, &self.q);
        copy(&mut out.lambda, &self.lambda);
        copy(&mut out.q_prev, &mo.q_prev);
        copy(&mut out.v, &mo.v);
        copy(&mut out.w, &mo.w);
        copy(&mut out.a, &mo.a);
        copy(&mut out.alpha, &mo.alpha);
        copy(&mut out.aux_v, &mo.aux_v);
        copy(&mut out.aux_a, &mo.aux_a);
        copy(&mut out.static_shift, self.static_shift());
        out.ticks = mo.ticks;
        copy(&mut out.prev_error, self.feedback.prev_errors_snapshot());
        copy(&mut out.last_targets, &self.last_targets);
        out.last_dt_s = self.last_dt_s;
        copy(&mut out.design_off, self.design_off_flags());
        out.vel.copy_from(&self.inertial.vel);
        self.joint_history(out);
    }

    /// Replays the tick that went from `before` to `after` (states saved
    /// from a program of the same model) toward `targets` with period
    /// `dt_s`, converged: see the [module docs](self). Afterwards
    /// [`q`](Self::q) is q* and [`finger_outputs`](Self::finger_outputs)
    /// the reference forces (zero unless the status is `Ok`).
    ///
    /// The iteration stops at a step of at most `tolerance_m` (scaled
    /// metres), or after `max_iterations`, or when a step below
    /// [`ROUND_OFF_STEP_M`] stops shrinking (round-off: `converged` is then
    /// false and `last_step_m` says how close it came).
    ///
    /// # Real-time
    /// Slow thread only: up to `max_iterations` factorisations.
    pub fn converged_tick(
        &mut self,
        before: &TickState,
        after: &TickState,
        targets: &[FingerTarget],
        dt_s: f64,
        tolerance_m: f64,
        max_iterations: u32,
    ) -> Result<ConvergedTick, ProgramError> {
        self.check_replay(before, after, targets)?;
        self.load_tick(before, dt_s);
        let mut r = ConvergedTick {
            status: TickOutcome::Ok,
            iterations: 0,
            last_step_m: f64::INFINITY,
            converged: false,
            max_violation_m: f64::NAN,
        };
        let fail = |p: &mut Program, r: &mut ConvergedTick, status| {
            p.outputs.fill(FingerOutput::default());
            r.status = status;
        };
        if let Err(status) =
            self.iterate_to(before, targets, dt_s, tolerance_m, max_iterations, &mut r)
        {
            fail(self, &mut r, status);
            return Ok(r);
        }
        if let Err(e) = self.ev.evaluate(&self.model, &self.q, targets) {
            fail(self, &mut r, TickOutcome::Eval(e));
            return Ok(r);
        }
        let v = Violation::of(&self.model, &self.scaling, self.ev.values());
        r.max_violation_m = v.max_m;
        if let Err(status) = self.reference_forces(before, after, targets, dt_s) {
            fail(self, &mut r, status);
        }
        Ok(r)
    }

    /// Refuses states and targets of another model's size, and a
    /// non-finite q.
    fn check_replay(
        &self,
        before: &TickState,
        after: &TickState,
        targets: &[FingerTarget],
    ) -> Result<(), ProgramError> {
        let (n, m, bodies) = (self.q.len(), self.lambda.len(), self.feedback.masses.len());
        for (len, expected) in [
            (before.q.len(), n),
            (after.q.len(), n),
            (before.lambda.len(), m),
            (before.v.len(), bodies),
            (after.a.len(), bodies),
            (after.aux_a.len(), self.feedback.motion.aux_a.len()),
            (targets.len(), self.outputs.len()),
            (before.prev_error.len(), self.outputs.len()),
        ] {
            if len != expected {
                return Err(ProgramError::Length { expected, got: len });
            }
        }
        if let Some(index) = before.q.iter().position(|v| !v.is_finite()) {
            return Err(ProgramError::NonFinite { index });
        }
        Ok(())
    }

    /// Loads `before` (q, multipliers, motion and coupling history, last
    /// targets) and sets q₀ as the tick does (inertial prediction,
    /// objectives' pull).
    fn load_tick(&mut self, before: &TickState, dt_s: f64) {
        let bodies = self.feedback.masses.len();
        self.load_motion(before, &before.q_prev);
        self.load_design_flags(&before.design_off);
        self.set_static_shift(&before.static_shift);
        if before.vel.v.len() == bodies {
            self.inertial.vel.copy_from(&before.vel);
        }
        self.feedback.forced.fill(false);
        self.feedback.carry_forced = false;
        self.q.copy_from_slice(&before.q);
        self.lambda.copy_from_slice(&before.lambda);
        if before.last_targets.len() == self.last_targets.len() {
            self.last_targets.copy_from_slice(&before.last_targets);
        }
        self.last_dt_s = dt_s;
        self.q_ref.copy_from_slice(&self.q);
        self.anchor_rolling();
        self.saved_lambda.copy_from_slice(&self.lambda);
        self.predict(dt_s);
        self.rest_aux();
        self.pull_objectives();
        self.step_budget_m = f64::INFINITY;
    }

    /// Full projected steps, each from a fresh factor at the iterate, until
    /// a step is below `tolerance_m`, stalls at round-off, or
    /// `max_iterations` ran (counted in `r`); the outcome that ended it
    /// otherwise.
    fn iterate_to(
        &mut self,
        before: &TickState,
        targets: &[FingerTarget],
        dt_s: f64,
        tolerance_m: f64,
        max_iterations: u32,
        r: &mut ConvergedTick,
    ) -> Result<(), TickOutcome> {
        let mut activations = 0;
        while r.iterations < max_iterations {
            self.ev
                .evaluate(&self.model, &self.q, targets)
                .map_err(TickOutcome::Eval)?;
            // The factor at this iterate (the mass metric stays the tick
            // start's: the motion history's newest q is still q_{k−1}).
            self.feedback
                .force_active(&self.scaling, &self.settings, &self.ev, &self.lambda)
                .map_err(|_| TickOutcome::ForceSolve)?;
            let coupling = CouplingStep {
                dt_s,
                stiffness_n_per_m: self.settings.coupling_stiffness_n_per_m,
                damping_n_s_per_m: self.settings.coupling_damping_n_s_per_m,
                prev_error: &before.prev_error,
            };
            // A fresh Jacobian and factor each iteration: a fresh sequence.
            self.projected.begin();
            let step = self.projected.step(
                &self.model,
                &self.scaling,
                &mut self.ev,
                &mut self.feedback,
                &mut self.q,
                &self.q_goal,
                targets,
                1.0,
                f64::INFINITY,
                f64::INFINITY,
                &coupling,
                &mut self.lambda,
            );
            match step.map_err(outcome_of)? {
                Step::Taken(size) => {
                    r.iterations += 1;
                    let stalled = size <= ROUND_OFF_STEP_M && size > 0.5 * r.last_step_m;
                    r.last_step_m = size;
                    if !size.is_finite() {
                        return Err(TickOutcome::NonFinite);
                    }
                    if size <= tolerance_m || stalled {
                        r.converged = size <= tolerance_m;
                        break;
                    }
                }
                // Rows the step would violate are now forced active: the
                // next iteration factors with them.
                Step::Activate if activations < 8 * super::MAX_ACTIVATIONS => {
                    activations += 1;
                }
                Step::Activate | Step::Refused => return Err(TickOutcome::ForceSolve),
            }
        }
        Ok(())
    }

    /// Eq. 7–8 at q* with the fast loop's own velocity and acceleration
    /// estimates of this tick (`after`), and its coupling history.
    fn reference_forces(
        &mut self,
        before: &TickState,
        after: &TickState,
        targets: &[FingerTarget],
        dt_s: f64,
    ) -> Result<(), TickOutcome> {
        let q_star = std::mem::take(&mut self.q);
        self.load_motion(after, &q_star);
        self.q = q_star;
        self.feedback.set_prev_errors(&before.prev_error);
        let solved = self.feedback.compute(
            &self.model,
            &self.scaling,
            &self.settings,
            &self.q,
            &self.ev,
            &self.lambda,
            targets,
            dt_s,
            false,
            &mut self.outputs,
        );
        if solved.is_err() {
            Err(TickOutcome::ForceSolve)
        } else if !self.outputs.iter().all(FingerOutput::is_finite) {
            Err(TickOutcome::NonFinite)
        } else {
            Ok(())
        }
    }

    /// The motion history of `s` with `q_prev` as its newest configuration.
    fn load_motion(&mut self, s: &TickState, q_prev: &[f64]) {
        let mo = &mut self.feedback.motion;
        mo.q_prev.copy_from_slice(q_prev);
        mo.v.copy_from_slice(&s.v);
        mo.w.copy_from_slice(&s.w);
        mo.a.copy_from_slice(&s.a);
        mo.alpha.copy_from_slice(&s.alpha);
        mo.aux_v.copy_from_slice(&s.aux_v);
        mo.aux_a.copy_from_slice(&s.aux_a);
        mo.ticks = s.ticks;
    }
}

/// The tick outcome of a failed projected step.
fn outcome_of(e: StepError) -> TickOutcome {
    match e {
        StepError::Eval(e) => TickOutcome::Eval(e),
        StepError::NonFinite => TickOutcome::NonFinite,
        StepError::Solve => TickOutcome::ForceSolve,
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::time::Duration;

    use crate::mechanisms::four_bar;
    use crate::{Program, SolverSettings, TickOutcome, UpdateRule};

    /// A converged replay of a tick the projected rule already converged
    /// (16 steps) lands where it did; a one-step gradient tick is far off
    /// and its replay is not.
    #[test]
    fn a_converged_replay_matches_a_converged_tick_and_not_an_under_iterated_one() {
        // Also with the quaternion-norm rows out of the force factor (their
        // replay takes the coupled pattern: `force::feedback::norms`).
        for norm_rows_out in [false, true] {
            replay(SolverSettings {
                norm_rows_out,
                ..SolverSettings::default()
            });
        }
    }

    fn replay(base: SolverSettings) {
        let model = Arc::new(four_bar());
        let dt = Duration::from_millis(1);
        let mut reference = Program::new(model.clone(), base).unwrap();
        let mut targets = model.initial_targets();
        for (settings, close) in [
            (
                SolverSettings {
                    iterations: 16,
                    ..base
                },
                true,
            ),
            (
                SolverSettings {
                    update: UpdateRule::Gradient,
                    iterations: 1,
                    ..base
                },
                false,
            ),
        ] {
            let mut fast = Program::new(model.clone(), settings).unwrap();
            let mut before = fast.tick_state();
            let mut worst: f64 = 0.0;
            for k in 0..40 {
                targets[0].position_m.y += 2e-5;
                fast.save_state(&mut before);
                assert_eq!(fast.tick(&targets, dt).status, TickOutcome::Ok);
                let after = fast.tick_state();
                let r = reference
                    .converged_tick(&before, &after, &targets, dt.as_secs_f64(), 1e-12, 50)
                    .unwrap();
                assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
                assert!(r.last_step_m < 1e-10, "tick {k}: {r:?}");
                assert!(r.max_violation_m < 1e-12, "tick {k}: {r:?}");
                if k > 5 {
                    let d = (fast.finger_outputs()[0].force_n
                        - reference.finger_outputs()[0].force_n)
                        .norm();
                    worst = worst.max(d);
                }
            }
            if close {
                assert!(worst < 1e-5, "converged fast tick off by {worst:e} N");
            } else {
                assert!(worst > 1e-3, "one gradient step off by only {worst:e} N");
            }
        }
    }
}
