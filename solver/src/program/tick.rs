//! The fast tick and the warm-up assembly.

use std::cmp::Ordering;
use std::time::Duration;

use super::report::max_tracking;
use super::stages::{Ordered, SolverStage, StageMarks};
use super::{AssemblyReport, Divergence, FingerOutput, Program, TickOutcome, TickReport};
use crate::al::projected::{CouplingStep, Step, StepError};
use crate::al::update::Violation;
use crate::reduced::History;
use crate::{FingerTarget, UpdateRule};

/// A projected step more than this × the previous step of the same tick
/// means the chord iteration diverges (a converging one contracts: ratios
/// 0.1–0.7 measured); it is refused and the tick's iterations stop.
const CHORD_GROWTH: f64 = 2.0;

/// Steps below this (scaled metres) are never judged: round-off at
/// convergence fluctuates freely.
const CHORD_FLOOR_M: f64 = 1e-9;

/// Refactorisations per tick for inequality rows a step would violate (each
/// costs one assembly and numeric factorisation of the joint block).
pub const MAX_ACTIVATIONS: u32 = 3;

/// `x ≤ limit`, false for NaN.
#[inline]
pub(super) fn within(x: f64, limit: f64) -> bool {
    matches!(
        x.partial_cmp(&limit),
        Some(Ordering::Less | Ordering::Equal)
    )
}

/// maxᵢ |xᵢ − rᵢ| wᵢ, or NaN if a term is NaN or infinite: four
/// independent lanes of `max` and of Σ v·0 (NaN iff some v is not finite,
/// as `fused::all_finite`), so the loop vectorises.
pub(super) fn max_scaled_change(x: &[f64], r: &[f64], w: &[f64]) -> f64 {
    let (mut top, mut bad) = ([0.0f64; 4], [0.0f64; 4]);
    let (xc, rc, wc) = (x.chunks_exact(4), r.chunks_exact(4), w.chunks_exact(4));
    let (xt, rt, wt) = (xc.remainder(), rc.remainder(), wc.remainder());
    for ((a, b), c) in xc.zip(rc).zip(wc) {
        for k in 0..4 {
            let v = (a[k] - b[k]).abs() * c[k];
            top[k] = if v > top[k] { v } else { top[k] };
            bad[k] += v * 0.0;
        }
    }
    for (k, ((a, b), c)) in xt.iter().zip(rt).zip(wt).enumerate() {
        let v = (a - b).abs() * c;
        top[k] = if v > top[k] { v } else { top[k] };
        bad[k] += v * 0.0;
    }
    finish(top, bad)
}

/// maxᵢ |xᵢ| wᵢ, or NaN (as [`max_scaled_change`]).
fn max_scaled(x: &[f64], w: &[f64]) -> f64 {
    let (mut top, mut bad) = ([0.0f64; 4], [0.0f64; 4]);
    let (xc, wc) = (x.chunks_exact(4), w.chunks_exact(4));
    let (xt, wt) = (xc.remainder(), wc.remainder());
    for (a, c) in xc.zip(wc) {
        for k in 0..4 {
            let v = a[k].abs() * c[k];
            top[k] = if v > top[k] { v } else { top[k] };
            bad[k] += v * 0.0;
        }
    }
    for (k, (a, c)) in xt.iter().zip(wt).enumerate() {
        let v = a.abs() * c;
        top[k] = if v > top[k] { v } else { top[k] };
        bad[k] += v * 0.0;
    }
    finish(top, bad)
}

#[inline(always)]
fn finish(top: [f64; 4], bad: [f64; 4]) -> f64 {
    if (bad[0] + bad[1] + bad[2] + bad[3]).is_nan() {
        f64::NAN
    } else {
        top[0].max(top[1]).max(top[2].max(top[3]))
    }
}

impl Program {
    /// One fast tick: `settings.iterations` update steps (projected or Eq. 1–3,
    /// per `settings.update`) toward `targets` (one per finger, model order),
    /// then the finger outputs (Eq. 7–8 plus coupling) with velocities from q
    /// one `dt` ago; the force solve's factor is kept for the next tick.
    ///
    /// With the projected rule, a step more than twice the size of the tick's
    /// previous one (a diverging chord iteration, near a singular pose) is
    /// refused and the tick continues with the steps before it; the report's
    /// `iterations` counts the steps kept.
    ///
    /// On any failure the status says why, q and the multipliers are restored
    /// to their values before the call, the motion history restarts at rest,
    /// and every finger output is zero: nothing non-finite ever leaves, and
    /// nothing absurd either ([`TickOutcome::Diverged`]: a step, multiplier
    /// or violation beyond [`Program::divergence_limits`]).
    ///
    /// # Real-time
    /// No allocation, locks or syscalls; bounded time (see the
    /// [module docs](super)): (iterations + 1) evaluations, a fixed-pattern
    /// sparse Cholesky, no tolerance-driven loops.
    pub fn tick(&mut self, targets: &[FingerTarget], dt: Duration) -> TickReport {
        self.tick_marked(targets, dt, &mut ())
    }

    /// [`tick`](Self::tick), telling `marks` when each [`SolverStage`] ends
    /// (for a caller that times them; the solver reads no clock).
    ///
    /// # Real-time
    /// As `tick`, plus one `marks.end` per stage.
    pub fn tick_marked<M: StageMarks>(
        &mut self,
        targets: &[FingerTarget],
        dt: Duration,
        marks: &mut M,
    ) -> TickReport {
        let n = self.settings.iterations;
        let dt_s = dt.as_secs_f64();
        let mut marks = Ordered::new(marks);
        self.report = if self.joint.is_some() {
            self.joint_tick(targets, dt_s, &mut marks)
        } else if dt_s > 0.0 {
            self.run_tick(targets, dt_s, n, &mut marks)
        } else {
            self.failed(TickOutcome::ZeroDt, 0)
        };
        marks.finish();
        self.report
    }

    /// `iterations` update steps toward `targets` from the current q, as the
    /// first part of a tick (q₀ = q at the call), without evaluating at the
    /// result, forces or history. For extra work between ticks and for
    /// timing one iteration. The projected rule steps with the factor of the
    /// last tick (or `set_q`, `assemble`): a few calls per tick are fine; to
    /// converge from far away use [`assemble`](Self::assemble), which
    /// refactors. The step and multiplier guards of `tick` apply. On failure
    /// q and the multipliers are restored.
    ///
    /// # Real-time
    /// No allocation; `iterations` update steps.
    pub fn iterate(&mut self, targets: &[FingerTarget], iterations: u32) -> TickOutcome {
        self.q_ref.copy_from_slice(&self.q);
        self.q_goal.copy_from_slice(&self.q);
        self.rest_aux();
        self.anchor_rolling();
        self.saved_lambda.copy_from_slice(&self.lambda);
        let status = match self.iterations(targets, iterations) {
            Ok(_) => match self.diverged_state() {
                None => {
                    self.joint_resync(History::Keep);
                    return TickOutcome::Ok;
                }
                Some(d) => TickOutcome::Diverged(d),
            },
            Err((status, _)) => status,
        };
        self.q.copy_from_slice(&self.q_ref);
        self.lambda.copy_from_slice(&self.saved_lambda);
        status
    }

    /// The divergence guard on a tick's iterations: the largest scaled
    /// coordinate change since `q_ref` and the largest |λ_i| / ℓ_i against
    /// [`DivergenceLimits`](super::DivergenceLimits). NaN counts as absurd.
    ///
    /// # Real-time
    /// No allocation; O(coordinates + rows).
    fn diverged_state(&self) -> Option<Divergence> {
        let step = max_scaled_change(&self.q, &self.q_ref, &self.scaling.sqrt_metric);
        if !within(step, self.limits.step_m) {
            return Some(Divergence::Step);
        }
        let lambda = max_scaled(&self.lambda, &self.scaling.inv_ell);
        if !within(lambda, self.limits.multiplier) {
            return Some(Divergence::Multiplier);
        }
        None
    }

    /// The iterations of a tick from q with q₀ = `q_ref` (already set).
    /// Returns the number of steps applied: the projected rule stops early
    /// (refusing the offending step) when its chord iteration diverges.
    fn iterations(&mut self, targets: &[FingerTarget], n: u32) -> Result<u32, (TickOutcome, u32)> {
        let mut pending = false;
        let done = self.iterations_inner(targets, n, &mut pending);
        // Rows activated after the last step taken have no multiplier from
        // a step: the tick's force solve keeps them (`Feedback::carry_forced`).
        self.feedback.carry_forced = pending;
        done
    }

    /// [`iterations`](Self::iterations); `pending` tells whether rows were
    /// activated after the last step taken.
    fn iterations_inner(
        &mut self,
        targets: &[FingerTarget],
        n: u32,
        pending: &mut bool,
    ) -> Result<u32, (TickOutcome, u32)> {
        let mut allowed = f64::INFINITY;
        self.activations = 0;
        // The contact speed limit is a budget for the whole tick: a
        // fraction of each shaped body's allowance (`set_allowances`).
        // ... and at most what the caller's budget leaves (the session
        // counts it from the age of the witness data: `set_contact_budget`).
        self.step_budget_m = if self.contact_step_m.is_finite() {
            self.contact_budget.clamp(0.0, 1.0)
        } else {
            f64::INFINITY
        };
        self.tick_budget = self.step_budget_m;
        self.speed_limited = false;
        self.projected.begin();
        if self.step_budget_m <= 0.0 {
            // No motion left for the witness rows this program runs on.
            self.speed_limited = true;
            return Ok(0);
        }
        let mut k = 0;
        while k < n {
            self.projected
                .set_last(k + 1 == n && self.settings.update == UpdateRule::Projected);
            let done = match self.settings.update {
                UpdateRule::Gradient => self.gradient_step(targets).map(|()| {
                    self.hold_design_off();
                    Step::Taken(0.0)
                }),
                // Inertial motion takes the first step whole: a relaxed
                // step would leave (1 − step)^n of every tick's motion
                // behind, a drag (10 % of a 1 s free fall at 0.9 and four
                // steps). The later steps only mend the linearisation.
                UpdateRule::Projected if k == 0 && self.settings.dynamics => {
                    self.projected_step(targets, 1.0, allowed)
                }
                UpdateRule::Projected => self.projected_step(targets, self.settings.step, allowed),
            };
            match done {
                Ok(Step::Taken(size)) => {
                    *pending = false;
                    allowed = (CHORD_GROWTH * size).max(CHORD_FLOOR_M);
                    k += 1;
                    self.speed_limited |= self.projected.last_speed_limited();
                    self.step_budget_m -= self.projected.last_moved_m();
                    if self.step_budget_m <= 0.0 {
                        self.speed_limited |= k < n;
                        return Ok(k);
                    }
                }
                Ok(Step::Activate) if self.activations < MAX_ACTIVATIONS => {
                    self.activations += 1;
                    *pending = true;
                    if !self.activate_in_tick() {
                        return Err((TickOutcome::ForceSolve, k));
                    }
                }
                Ok(Step::Activate) => {
                    // Out of refactorisations this tick: stop stepping rather
                    // than step through the contact; the force solve at the
                    // end of the tick activates the rows for the next one.
                    *pending = true;
                    return Ok(k);
                }
                Ok(Step::Refused) => return Ok(k),
                Err(status) => {
                    let status = match status {
                        TickOutcome::Eval(_) if k > 0 => TickOutcome::NonFinite,
                        s => s,
                    };
                    return Err((status, k));
                }
            }
        }
        Ok(n)
    }

    /// Re-evaluates C_q and refactors the Eq. 7 matrix at the current q and the
    /// last targets without advancing the motion history (the projected
    /// update's factor must match q after a jump). Outputs are untouched.
    ///
    /// # Real-time
    /// No allocation; one evaluation and one force solve.
    pub(crate) fn refresh(&mut self) -> TickOutcome {
        if let Err(e) = self.ev.evaluate(&self.model, &self.q, &self.last_targets) {
            return TickOutcome::Eval(e);
        }
        match self.feedback.compute(
            &self.model,
            &self.scaling,
            &self.settings,
            &self.q,
            &self.ev,
            &self.lambda,
            &self.last_targets,
            1e-3,
            false,
            &mut self.spare_outputs,
        ) {
            Ok(()) => TickOutcome::Ok,
            Err(_) => TickOutcome::ForceSolve,
        }
    }

    pub(super) fn run_tick<M: StageMarks>(
        &mut self,
        targets: &[FingerTarget],
        dt_s: f64,
        n: u32,
        marks: &mut Ordered<'_, M>,
    ) -> TickReport {
        self.last_dt_s = dt_s;
        self.q_ref.copy_from_slice(&self.q);
        self.anchor_rolling();
        self.saved_lambda.copy_from_slice(&self.lambda);
        self.set_allowances(dt_s);
        self.predict(dt_s);
        self.rest_aux();
        self.carry_groups();
        self.ramp_snaps(dt_s);
        self.pull_objectives();
        let n = match self.solve_steps(targets, n, dt_s) {
            Ok(applied) => applied,
            Err((status, k)) => return self.failed(status, k),
        };
        marks.end(SolverStage::Update);
        if self.ev.evaluate(&self.model, &self.q, targets).is_err() {
            return self.failed(TickOutcome::NonFinite, n);
        }
        if !self.settings.dynamics
            && self.anchor_friction(dt_s)
            && self.ev.evaluate(&self.model, &self.q, targets).is_err()
        {
            return self.failed(TickOutcome::NonFinite, n);
        }
        self.finish_motion(dt_s);
        let v = Violation::of(&self.model, &self.scaling, self.ev.values());
        if !within(v.max_scaled_m, self.limits.violation_m) {
            return self.failed(TickOutcome::Diverged(Divergence::Violation), n);
        }
        marks.end(SolverStage::Evaluation);
        let solved = self.feedback.compute(
            &self.model,
            &self.scaling,
            &self.settings,
            &self.q,
            &self.ev,
            &self.lambda,
            targets,
            dt_s,
            true,
            &mut self.outputs,
        );
        if solved.is_err() {
            return self.failed(TickOutcome::ForceSolve, n);
        }
        if !self.outputs.iter().all(FingerOutput::is_finite) {
            return self.failed(TickOutcome::NonFinite, n);
        }
        if self.last_targets.len() == targets.len() {
            self.last_targets.copy_from_slice(targets);
        }
        self.measure_objectives();
        TickReport {
            iterations: n,
            max_violation_m: v.max_m,
            max_violation_rad: v.max_rad,
            max_norm_violation: v.max_norm,
            rms_violation_m: v.rms_m,
            max_tracking_error_m: max_tracking(&self.outputs),
            max_penetration_m: v.max_penetration_m.max(0.0),
            active_contacts: self.active_contacts(),
            activations: self.activations,
            sticking: self.sticking(),
            speed_limited: self.speed_limited,
            energy: self.inertial.energy,
            status: TickOutcome::Ok,
        }
    }

    /// The tick's steps from q = `q_ref` toward the prediction, guarded;
    /// with inertial motion, solved again (from `q_ref`, with the new
    /// friction states and without the contacts that pulled) while a
    /// friction pair changes between sticking and slipping or a contact
    /// opens, at most [`MAX_RESOLVES`](crate::dynamics::MAX_RESOLVES)
    /// times. Returns the steps of the last solve.
    fn solve_steps(
        &mut self,
        targets: &[FingerTarget],
        n: u32,
        dt_s: f64,
    ) -> Result<u32, (TickOutcome, u32)> {
        let mut resolves = 0;
        self.released.begin();
        loop {
            let done = self.iterations(targets, n)?;
            if let Some(d) = self.diverged_state() {
                return Err((TickOutcome::Diverged(d), done));
            }
            if !self.settings.dynamics {
                return Ok(done);
            }
            // A step that held a contact shut by pulling is solved again
            // before friction is judged on it; a friction change takes the
            // released rows back (`release.rs`). One more solve, beyond the
            // bound, only if a row taken back pulls again.
            let released = self.release_pulling();
            let changed = released || self.decide_friction(dt_s);
            let bound = crate::dynamics::MAX_RESOLVES;
            let spare = resolves == bound && self.released.repulled();
            if !changed || (resolves >= bound && !spare) {
                self.arm_slow_slips();
                return Ok(done);
            }
            if !released {
                self.readmit_released();
            }
            resolves += 1;
            self.inertial.resolves += 1;
            self.q.copy_from_slice(&self.q_ref);
            self.lambda.copy_from_slice(&self.saved_lambda);
            // The chord Jacobian is still the tick's; the values and the
            // active set are those of its start, with the new stick rows.
            if self
                .ev
                .evaluate_values(&self.model, &self.q, targets)
                .is_err()
                || self
                    .feedback
                    .force_active(&self.scaling, &self.settings, &self.ev, &self.lambda)
                    .is_err()
            {
                return Err((TickOutcome::ForceSolve, done));
            }
            self.predict(dt_s);
            self.pull_objectives();
        }
    }

    /// Restores the state of the start of the call and zeroes the outputs.
    pub(super) fn failed(&mut self, status: TickOutcome, iterations: u32) -> TickReport {
        self.q.copy_from_slice(&self.q_ref);
        self.lambda.copy_from_slice(&self.saved_lambda);
        self.feedback.motion.reset(&self.q);
        self.reset_velocities();
        // The stored Jacobian and factor may come from the failed state.
        let _ = self.refresh();
        self.outputs.fill(FingerOutput::default());
        self.feedback.clear_torques();
        TickReport {
            iterations,
            status,
            ..TickReport::default()
        }
    }

    /// Warm-up before the clock starts: AL iterations with frozen `targets`
    /// (each iteration a tick: q₀ is the previous iterate) until the scaled
    /// violation of the mechanism's rows is below `tolerance_m` and the last
    /// step moved no scaled coordinate more than `tolerance_m / 100`, or
    /// `max_iterations` ran. Finger rows are penalties: an unreachable target
    /// leaves a tracking error, reported, without blocking convergence. The
    /// motion history restarts at rest at the result; outputs are zeroed.
    ///
    /// # Real-time
    /// No allocation, but up to `max_iterations` evaluations: meant for
    /// before the clock starts.
    pub fn assemble(
        &mut self,
        targets: &[FingerTarget],
        max_iterations: u32,
        tolerance_m: f64,
    ) -> AssemblyReport {
        let mut r = AssemblyReport::default();
        self.saved_lambda.copy_from_slice(&self.lambda);
        let mut last_step = f64::INFINITY;
        if self.last_targets.len() == targets.len() {
            self.last_targets.copy_from_slice(targets);
        }
        for k in 0..max_iterations {
            self.q_ref.copy_from_slice(&self.q);
            self.q_goal.copy_from_slice(&self.q);
            self.rest_aux();
            self.anchor_rolling();
            if let Err(status) = self.assembly_step(targets) {
                self.q.copy_from_slice(&self.q_ref);
                self.lambda.copy_from_slice(&self.saved_lambda);
                r.status = match status {
                    TickOutcome::Eval(_) if k > 0 => TickOutcome::NonFinite,
                    s => s,
                };
                break;
            }
            r.iterations = k + 1;
            last_step = self
                .q
                .iter()
                .zip(&self.q_ref)
                .zip(&self.scaling.inv_metric)
                .map(|((a, b), &wi)| (a - b).abs() / wi.sqrt())
                .fold(0.0, f64::max);
            let c = match self.settings.update {
                UpdateRule::Gradient => &self.fused.values[..],
                UpdateRule::Projected => self.ev.values(),
            };
            let v = Violation::of(&self.model, &self.scaling, c);
            if v.max_scaled_m < tolerance_m && last_step < 0.01 * tolerance_m {
                break;
            }
        }
        r.last_step_m = if r.iterations > 0 { last_step } else { 0.0 };
        if let Err(e) = self.ev.evaluate(&self.model, &self.q, targets) {
            if r.status == TickOutcome::Ok {
                r.status = TickOutcome::Eval(e);
            }
        } else {
            let v = Violation::of(&self.model, &self.scaling, self.ev.values());
            r.max_scaled_violation_m = v.max_scaled_m;
            r.max_violation_m = v.max_m;
            r.max_violation_rad = v.max_rad;
            r.converged = r.status == TickOutcome::Ok
                && v.max_scaled_m < tolerance_m
                && r.last_step_m < 0.01 * tolerance_m;
        }
        self.q_ref.copy_from_slice(&self.q);
        self.feedback.motion.reset(&self.q);
        self.reset_velocities();
        let _ = self.refresh();
        self.outputs.fill(FingerOutput::default());
        self.joint_resync(History::Rest);
        r.max_tracking_error_m = self.tracking_errors(targets);
        r
    }

    /// One step of Nelson & Cohen Eq. 1–3 (the fused gradient pass) from q.
    fn gradient_step(&mut self, targets: &[FingerTarget]) -> Result<(), TickOutcome> {
        self.fused
            .iterate(
                &self.model,
                &self.scaling,
                self.h,
                &mut self.q,
                &self.q_goal,
                targets,
                &mut self.lambda,
                &mut self.g,
                self.ev.witnesses(),
            )
            .map_err(TickOutcome::Eval)
    }

    /// One projected (Gauss–Newton) step of length `step` from q with the
    /// current factor, refused above `allowed` (see `Projected::step`).
    fn projected_step(
        &mut self,
        targets: &[FingerTarget],
        step: f64,
        allowed: f64,
    ) -> Result<Step, TickOutcome> {
        let prev = self.feedback.prev_errors_snapshot();
        self.prev_error_buf.copy_from_slice(prev);
        let coupling = CouplingStep {
            dt_s: self.last_dt_s,
            stiffness_n_per_m: self.settings.coupling_stiffness_n_per_m,
            damping_n_s_per_m: self.settings.coupling_damping_n_s_per_m,
            prev_error: &self.prev_error_buf,
        };
        let outcome = self.projected.step(
            &self.model,
            &self.scaling,
            &mut self.ev,
            &mut self.feedback,
            &mut self.q,
            &self.q_goal,
            targets,
            step,
            allowed,
            self.step_budget_m,
            &coupling,
            &mut self.lambda,
        );
        outcome.map_err(|e| match e {
            StepError::Eval(e) => TickOutcome::Eval(e),
            StepError::NonFinite => TickOutcome::NonFinite,
            StepError::Solve => TickOutcome::ForceSolve,
        })
    }

    /// One assembly iteration from q (= `q_ref`): a gradient step, or a full
    /// Gauss–Newton step with the factor refreshed at q (an assembly may start
    /// far from the last factorisation).
    fn assembly_step(&mut self, targets: &[FingerTarget]) -> Result<(), TickOutcome> {
        match self.settings.update {
            UpdateRule::Gradient => self.gradient_step(targets),
            UpdateRule::Projected => {
                match self.refresh() {
                    TickOutcome::Ok => {}
                    status => return Err(status),
                }
                // Assembly is not a motion: no speed limit.
                self.step_budget_m = f64::INFINITY;
                self.projected.begin();
                for _ in 0..=MAX_ACTIVATIONS {
                    match self.projected_step(targets, 1.0, f64::INFINITY)? {
                        Step::Activate => {
                            self.feedback
                                .force_active(&self.scaling, &self.settings, &self.ev, &self.lambda)
                                .map_err(|_| TickOutcome::ForceSolve)?;
                        }
                        Step::Taken(_) | Step::Refused => return Ok(()),
                    }
                }
                Ok(())
            }
        }
    }

    /// Largest finger |attachment − target| at the current q (0 on a bad
    /// targets slice).
    fn tracking_errors(&self, targets: &[FingerTarget]) -> f64 {
        (0..self.model.fingers().len())
            .zip(targets)
            .filter_map(|(k, t)| {
                self.model
                    .finger_point(&self.q, crate::FingerId(k as u32))
                    .map(|p| (p - t.position_m).norm())
            })
            .fold(0.0, f64::max)
    }
}
