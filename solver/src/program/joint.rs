//! The tick in joint coordinates (`SolverSettings::coordinates`): a
//! [`Program`] whose settings choose `Joint` (or `Auto`, on a model the
//! joint tick accepts where its cost model, `joint_cost`, estimates the
//! joint tick cheaper than the augmented one; `Joint` runs it regardless)
//! ticks with [`JointTick`] instead of its augmented
//! update and force stage (`reduced`: the projected update on the spanning
//! tree's joint coordinates with forward kinematics, only the loop-closing
//! and finger rows evaluated, Eq. 7 in joint coordinates).
//!
//! What stays the program's: q (copied from the joint tick after every
//! successful tick, so the slow loop and the reports read
//! [`Program::q`], [`Program::finger_outputs`] and
//! [`Program::last_report`] as before), the targets, the report, the
//! divergence limits and the failure paths: bad input (bad targets, a zero
//! time step) fails the tick — q is not moved, every finger output is zero,
//! the joint tick's motion history restarts at rest at q and the status says
//! why, as in the augmented tick; any other failure — among them a tick
//! that ends with its loop rows more open than it started, beyond 1e-2 L
//! (`opens_loops`) — runs the augmented tick for the same call
//! (`joint_fallback`), and the next joint tick first projects q onto the
//! tree. Wherever q
//! changes outside a tick (`set_q`, `shift_q`, `assemble`, `iterate`,
//! `adopt_state`, `refresh_factor`) the joint tick is moved there without
//! allocating (`JointTick::resync`); if the tree rows or the norms are open
//! there beyond 1e-10 L (`joint_report::CLOSED`), the next joint tick
//! first projects q onto the tree.
//!
//! **The report.** Every row is reported as by the augmented tick
//! (`Violation::of`'s rules, `joint_report`): the loop and finger rows at
//! the tick's end, the rows the joint tick never evaluates — tree joints and
//! quaternion norms, which forward kinematics keeps by construction — at
//! their value at the last resync (an augmented evaluation). Their
//! round-off drift over many ticks is measured by a test
//! (`tests/solver/joint_coordinates.rs`), not by the report. No multiplier
//! is updated (λ keeps its value), and no multiplier guard applies.

use std::fmt;

use super::joint_cost::{CostEstimate, augmented_madds, joint_madds};
use super::joint_report::RowStats;
use super::report::max_tracking;
use super::stages::{Ordered, SolverStage, StageMarks};
use super::tick::{max_scaled_change, within};
use super::{Divergence, FingerOutput, Program, ProgramError, TickOutcome, TickReport};
use crate::al::scaling::Role;
use crate::evaluate::EvalError;
use crate::reduced::{History, JointTick, MotionOut, ReducedError};
use crate::{Coordinates, FingerId, FingerTarget, ForceSolver, UpdateRule};

/// Which coordinates a program's tick runs in, and why
/// ([`Program::coordinates`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CoordinatesChoice {
    /// What the settings asked for.
    pub asked: Coordinates,
    /// The tick runs in joint coordinates.
    pub joint: bool,
    /// Why: what the joint tick refused, or what it took.
    pub why: String,
    /// Both ticks' estimated cost, when the joint tick could be built
    /// (`Auto` runs joint only where it is estimated cheaper).
    pub estimate: Option<CostEstimate>,
}

impl fmt::Display for CoordinatesChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ran = if self.joint { "joint" } else { "augmented" };
        write!(f, "{ran} (asked: {}; {})", self.asked.label(), self.why)
    }
}

/// The joint tick of a program, with whether a resync failed since (the
/// next tick then retries it first).
pub(super) struct JointPath {
    pub(super) tick: JointTick,
    pub(super) stale: bool,
    /// The rows each tick evaluates (finger rows dropped), and per model
    /// row whether it is one of them.
    rows: Vec<usize>,
    evaluated: Vec<bool>,
    /// The report's statistics over the other rows, at the last resync.
    fixed: RowStats,
    /// A test's injected failure of the next joint tick
    /// (`Program::fail_next_joint_tick`).
    pub(super) inject: Option<super::joint_fallback::Injected>,
    /// After a fallback, or a resync that found the tree rows or norms
    /// open: the next joint tick first projects q onto the tree
    /// (`joint_fallback`).
    pub(super) project: bool,
    /// After a fallback whose tick left the rows open beyond
    /// `OPENING_FLOOR` × L: the ticks run augmented until they are within
    /// it (`joint_fallback`).
    pub(super) recovering: bool,
    /// Augmented ticks run so (`Program::joint_recovery_ticks`).
    pub(super) recovery_ticks: u64,
}

impl fmt::Debug for JointPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("JointPath")
            .field("dofs", &self.tick.dofs())
            .field("stale", &self.stale)
            .finish()
    }
}

/// What the joint tick does not cover in `p`'s model and settings, checked
/// before it is built.
fn refusal(p: &Program) -> Option<String> {
    let (m, s) = (&*p.model, &p.settings);
    let why = if s.update == UpdateRule::Gradient {
        "the gradient update (Eq. 1–3): the joint tick takes projected steps".into()
    } else if s.force_solver != ForceSolver::Cholesky {
        format!(
            "force solver `{}`: the joint tick solves Eq. 7 with its own dense factors \
             (use the default `cholesky`)",
            s.force_solver.label()
        )
    } else if s.dynamics {
        "inertial motion (`dynamics`)".into()
    } else if !m.torque_joints().is_empty() {
        "joint torque outputs: not computed in joint coordinates".into()
    } else if m.contact().slots > 0 {
        "contact rows".into()
    } else if !m.layout().design_vars().is_empty() || p.objective.is_some() {
        "design variables or objectives".into()
    } else if !m.layout().aux_blocks().is_empty() || !m.rolling.is_empty() {
        "flexible bodies, surfaces or rolling rows".into()
    } else if p.semantic.is_some() {
        "semantic rows (snaps, carried groups)".into()
    } else {
        return None;
    };
    Some(why)
}

/// The tick outcome of a joint tick's error.
fn outcome(e: &ReducedError) -> TickOutcome {
    match e {
        ReducedError::NotPositive(_) => TickOutcome::ForceSolve,
        ReducedError::Degenerate(_) | ReducedError::RawEntry | ReducedError::Unsupported(_) => {
            TickOutcome::NonFinite
        }
    }
}

/// Why `targets` cannot be ticked toward (as the evaluation would say).
fn bad_targets(fingers: usize, targets: &[FingerTarget]) -> Option<EvalError> {
    if targets.len() != fingers {
        return Some(EvalError::TargetCount {
            expected: fingers,
            got: targets.len(),
        });
    }
    let bad = targets
        .iter()
        .position(|t| !t.position_m.iter().all(|v| v.is_finite()))?;
    Some(EvalError::NonFiniteTarget {
        finger: FingerId(bad as u32),
    })
}

impl Program {
    /// Builds the joint tick if the settings ask for it and the model
    /// allows it (after the augmented construction, at q).
    ///
    /// # Errors
    /// `Joint` asked on a model or settings the joint tick refuses.
    pub(super) fn choose_coordinates(&mut self) -> Result<(), ProgramError> {
        let asked = self.settings.coordinates;
        self.choice = CoordinatesChoice {
            asked,
            joint: false,
            why: "the default".into(),
            estimate: None,
        };
        if asked == Coordinates::Augmented {
            return Ok(());
        }
        let built = match refusal(self) {
            Some(why) => Err(why),
            None => JointTick::new(
                self.model.clone(),
                self.settings,
                &self.q,
                &self.last_targets,
            )
            .map_err(|e| e.to_string()),
        };
        match built {
            Ok(tick) => {
                let est = self.estimate(&tick);
                self.choice.estimate = Some(est);
                if asked == Coordinates::Auto && !est.joint_cheaper() {
                    self.choice.why = est.describe();
                    return Ok(());
                }
                self.choice.joint = true;
                self.choice.why = format!(
                    "{} joint coordinates, {} loop rows kept; {}",
                    tick.dofs(),
                    tick.n_loop,
                    est.describe()
                );
                let mut evaluated = vec![false; self.model.n_rows()];
                let all = tick.evaluated_rows();
                for &r in &all {
                    evaluated[r] = true;
                }
                let finger = |&r: &usize| matches!(self.scaling.role[r], Role::Finger);
                let rows = all.into_iter().filter(|r| !finger(r)).collect();
                self.joint = Some(Box::new(JointPath {
                    tick,
                    stale: false,
                    rows,
                    evaluated,
                    fixed: RowStats::default(),
                    inject: None,
                    project: false,
                    recovering: false,
                    recovery_ticks: 0,
                }));
                self.joint_resync(History::Rest);
                Ok(())
            }
            Err(why) if asked == Coordinates::Joint => Err(ProgramError::Coordinates(why)),
            Err(why) => {
                self.choice.why = format!("the joint tick refused: {why}");
                Ok(())
            }
        }
    }

    /// Both ticks' estimated arithmetic (`joint_cost`): the joint tick's
    /// from its tree and rows, the augmented tick's from its Eq. 7 factor's
    /// stored values and the Jacobian's.
    fn estimate(&self, tick: &JointTick) -> CostEstimate {
        let it = self.settings.iterations;
        CostEstimate {
            joint_madds: joint_madds(tick, it),
            augmented_madds: augmented_madds(
                self.force_factor_nnz(),
                self.model.n_rows(),
                self.ev.jacobian().nnz(),
                it,
            ),
        }
    }

    /// Ticks on which the joint tick's Eq. 7 released a limit that would
    /// have pulled.
    pub(super) fn joint_releases(&self) -> u64 {
        self.joint.as_ref().map_or(0, |j| j.tick.limit_releases())
    }

    /// Which coordinates the tick runs in, and why.
    pub fn coordinates(&self) -> &CoordinatesChoice {
        &self.choice
    }

    /// Moves the joint tick (if any) to q: every row's value at q (an
    /// augmented value evaluation toward the last targets), then
    /// `JointTick::resync`. A failure leaves it stale: the next tick
    /// retries, and fails if it cannot.
    ///
    /// # Real-time
    /// No allocation; one value evaluation and one joint end-of-tick.
    pub(super) fn joint_resync(&mut self, history: History) {
        let Some(j) = self.joint.as_mut() else {
            return;
        };
        let ok = self
            .ev
            .evaluate_values(&self.model, &self.q, &self.last_targets)
            .is_ok()
            && j.tick
                .resync(&self.q, self.ev.values(), &self.last_targets, history)
                .is_ok();
        j.stale = !ok;
        j.fixed = RowStats::fixed(&self.model, &self.scaling, &j.evaluated, self.ev.values());
        j.project |= !j.fixed.closed(self.scaling.length_m);
    }

    /// The tick in joint coordinates ([`tick_marked`](Self::tick_marked)
    /// with a joint tick).
    pub(super) fn joint_tick<M: StageMarks>(
        &mut self,
        targets: &[FingerTarget],
        dt_s: f64,
        marks: &mut Ordered<'_, M>,
    ) -> TickReport {
        if self.joint.as_ref().is_some_and(|j| j.recovering) {
            return self.joint_recovery(targets, dt_s, marks);
        }
        if dt_s > 0.0 && self.joint.as_ref().is_some_and(|j| j.project) {
            self.joint_project();
        }
        let Some(mut j) = self.joint.take() else {
            return self.joint_failed(TickOutcome::NonFinite, 0);
        };
        let done = if dt_s > 0.0 {
            self.joint_steps(&mut j, targets, dt_s, marks)
        } else {
            Err((TickOutcome::ZeroDt, 0))
        };
        self.joint = Some(j);
        match done {
            Ok(r) => r,
            Err((status, _)) if super::joint_fallback::falls_back(&status) => {
                self.joint_fallback(targets, dt_s, marks)
            }
            Err((status, k)) => self.joint_failed(status, k),
        }
    }

    /// The joint tick's stages, guarded; on success q, the outputs and the
    /// last targets are the program's.
    fn joint_steps<M: StageMarks>(
        &mut self,
        j: &mut JointPath,
        targets: &[FingerTarget],
        dt_s: f64,
        marks: &mut Ordered<'_, M>,
    ) -> Result<TickReport, (TickOutcome, u32)> {
        self.last_dt_s = dt_s;
        if let Some(e) = bad_targets(self.model.fingers().len(), targets) {
            return Err((TickOutcome::Eval(e), 0));
        }
        if j.stale {
            return Err((TickOutcome::NonFinite, 0));
        }
        if j.inject.is_some() {
            return Err((TickOutcome::ForceSolve, 0));
        }
        let t = &mut j.tick;
        let (fixed, rows) = (j.fixed, &j.rows);
        let open_before = t.max_violation;
        let n = t.update(targets).map_err(|e| (outcome(&e), 0))?;
        t.steps = n;
        marks.end(SolverStage::Update);
        t.evaluate_end(targets, true)
            .map_err(|e| (outcome(&e), n))?;
        if super::joint_fallback::opens_loops(open_before, t.max_violation, self.scaling.length_m) {
            return Err((TickOutcome::Diverged(Divergence::Violation), n));
        }
        let step = max_scaled_change(t.q(), &self.q, &self.scaling.sqrt_metric);
        if step.is_nan() {
            return Err((TickOutcome::NonFinite, n));
        }
        if !within(step, self.limits.step_m) {
            return Err((TickOutcome::Diverged(Divergence::Step), n));
        }
        let v = fixed.with(&self.model, &self.scaling, rows, t.values());
        if !within(v.max_scaled_m, self.limits.violation_m) {
            return Err((TickOutcome::Diverged(Divergence::Violation), n));
        }
        marks.end(SolverStage::Evaluation);
        t.force_end(targets, dt_s, true)
            .map_err(|e| (outcome(&e), n))?;
        if !t.outputs.iter().all(FingerOutput::is_finite) {
            return Err((TickOutcome::NonFinite, n));
        }
        self.q.copy_from_slice(t.q());
        self.q_ref.copy_from_slice(t.q());
        self.outputs.copy_from_slice(&t.outputs);
        self.last_targets.copy_from_slice(targets);
        Ok(TickReport {
            iterations: n,
            max_violation_m: v.max_m,
            max_violation_rad: v.max_rad,
            max_norm_violation: v.max_norm,
            rms_violation_m: v.rms_m,
            max_tracking_error_m: max_tracking(&self.outputs),
            max_penetration_m: v.max_penetration_m.max(0.0),
            activations: t.limit_activations(),
            status: TickOutcome::Ok,
            ..TickReport::default()
        })
    }

    /// A failed joint tick (q was not moved): outputs zero, the joint tick back
    /// at q with its motion history at rest.
    pub(super) fn joint_failed(&mut self, status: TickOutcome, iterations: u32) -> TickReport {
        self.outputs.fill(FingerOutput::default());
        self.joint_resync(History::Rest);
        TickReport {
            iterations,
            status,
            ..TickReport::default()
        }
    }

    /// A hand-over's joint tick: moved to the adopted q, with the motion
    /// history of `old`'s joint tick when it has one of the same bodies
    /// (else at rest).
    ///
    /// # Real-time
    /// No allocation.
    pub(super) fn joint_adopt(&mut self, old: &Program) {
        self.joint_resync(History::Rest);
        if let (Some(new), Some(old)) = (self.joint.as_mut(), old.joint.as_ref()) {
            new.tick.adopt_history(&old.tick);
        }
    }

    /// A saved state's motion history from the joint tick (whose history
    /// the augmented force stage's does not follow), so that a replay of
    /// the tick (`converged_tick`) starts from the motion the joint tick
    /// saw.
    ///
    /// # Real-time
    /// No allocation.
    pub(super) fn joint_history(&self, out: &mut super::TickState) {
        let Some(j) = self.joint.as_ref() else {
            return;
        };
        let masses = &self.feedback.masses;
        let slot = |o: usize| masses.iter().position(|m| m.offset == o);
        if out.prev_error.len() != self.model.fingers().len() {
            return;
        }
        out.ticks = j.tick.export_history(
            slot,
            MotionOut {
                q_prev: &mut out.q_prev,
                v: &mut out.v,
                a: &mut out.a,
                w: &mut out.w,
                alpha: &mut out.alpha,
                prev_error: &mut out.prev_error,
            },
        );
    }
}
