//! Joint limits in the joint tick: the two `≥ 0` rows of a revolute or
//! prismatic limit on a tree joint (x − lo, hi − x) are, along S, a row with
//! a single entry ±1 on the joint's coordinate (written from the row's
//! gradient like every kept row, `rows`). The active set follows the
//! augmented tick's (`Feedback::activate`, `Projected::predict`,
//! `Feedback::release_pulling`):
//!
//! - at a tick's end (and a resync) a limit row is active when its ν > 0,
//!   it is violated by more than `INEQUALITY_ACTIVE_BAND`, or a step of
//!   the tick forced it and no step came after (`pending`);
//! - active rows sit between the kept loop rows and the finger rows, so
//!   they are loop rows to the force stage (W_LL) and to the steps; the
//!   others take no part (their multiplier is exactly 0);
//! - a step that would leave an inactive row below −`ACTIVATE_TOLERANCE_M`
//!   forces it active, the factors are formed again and the step is taken
//!   again (at most [`MAX_ACTIVATIONS`] a tick, then the steps end);
//! - a taken step stores ν = max(0, −y) of each active row;
//! - Eq. 7: an active row whose multiplier pulls (λ > 0) is released for
//!   the finger force, which is solved again without it; the next tick's
//!   steps keep the kinematic active set (its factors are formed again).
//!
//! A limit on a loop-closing joint is refused.

use super::ReducedError;
use super::rows::RowSet;
use super::small::backward;
use super::stage::Stage;
use super::tick::JointTick;
use super::tree::JointTree;
use crate::al::projected::ACTIVATE_TOLERANCE_M;
use crate::constraint::Geometry;
use crate::constraint::block::RowGrad;
use crate::constraint::limit::Limited;
use crate::force::INEQUALITY_ACTIVE_BAND;
use crate::{FingerTarget, Model};

/// Refactorisations per tick for limits a step would cross (as
/// `program::tick::MAX_ACTIVATIONS`).
pub const MAX_ACTIVATIONS: u32 = 3;

/// The limit rows, their D J S rows and the active set.
pub(crate) struct Limits {
    set: RowSet,
    /// Model rows (each limit's lo then hi row, model order) and their ℓ.
    rows: Vec<usize>,
    scale: Vec<f64>,
    /// ℓ J S per limit row at the last tick's end (rows × dofs).
    jr: Vec<f64>,
    grads: Vec<RowGrad>,
    /// Per limit row: in the factors, forced by a step, its ν.
    active: Vec<bool>,
    forced: Vec<bool>,
    nu: Vec<f64>,
    /// The active rows in the kept-row order (after the `base` loop rows).
    order: Vec<usize>,
    /// Kept loop rows (without limits).
    base: usize,
    /// Limit rows placed before the finger rows in the tick's buffers.
    placed: usize,
    /// A step of this tick forced rows and no step was taken after.
    pending: bool,
    activations: u32,
    /// Eq. 7 released a pulling row this tick.
    released: bool,
    /// Ticks whose Eq. 7 released a row.
    releases: u64,
    tau: Vec<f64>,
    lam: Vec<f64>,
    /// The steps' factors kept aside during a release (with limits only).
    spare: Option<Box<Stage>>,
    /// The released rows' kept-row positions.
    gone: Vec<usize>,
}

/// Whether the limit `l` is on the tree joint with constraint geometry `g`.
fn limits_joint(l: &Limited, g: &Geometry) -> bool {
    match (l, g) {
        (Limited::Angle(a), Geometry::Revolute(b)) => a == b,
        (Limited::Displacement(a), Geometry::Prismatic(b)) => a == b,
        _ => false,
    }
}

impl Limits {
    /// The limits of `model` (rows `tree.limit_rows`), none active, with
    /// `base` kept loop rows. Allocates.
    ///
    /// # Errors
    /// A limit on a joint that is not a tree joint.
    pub fn new(
        model: &Model,
        tree: &JointTree,
        ell: &[f64],
        base: usize,
        spare: impl FnOnce(usize) -> Stage,
    ) -> Result<Self, ReducedError> {
        for &r in &tree.limit_rows {
            let k = model.rows()[r].constraint.index();
            let on_tree = match &model.geometry[k] {
                Geometry::Limit(l) => tree
                    .joints
                    .iter()
                    .any(|j| limits_joint(&l.joint, &model.geometry[j.constraint])),
                _ => false,
            };
            if !on_tree {
                return Err(ReducedError::Unsupported(format!(
                    "limits `{}` on a loop-closing joint",
                    model.constraints()[k].name
                )));
            }
        }
        let rows = tree.limit_rows.clone();
        let (m, n) = (rows.len(), tree.dofs);
        Ok(Self {
            set: RowSet::new(model, &rows, &[]),
            scale: rows.iter().map(|&r| ell[r]).collect(),
            jr: vec![0.0; m * n],
            grads: vec![RowGrad::default(); m],
            active: vec![false; m],
            forced: vec![false; m],
            nu: vec![0.0; m],
            order: Vec::with_capacity(m),
            base,
            placed: 0,
            pending: false,
            activations: 0,
            released: false,
            releases: 0,
            tau: vec![0.0; n],
            lam: vec![0.0; base + m],
            spare: (m > 0).then(|| Box::new(spare(m))),
            gone: Vec::with_capacity(m),
            rows,
        })
    }

    /// Limit rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// The model rows of the limits.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// A tick's steps begin.
    pub fn begin(&mut self) {
        self.activations = 0;
    }
}

impl JointTick {
    /// The limit rows' values at q (each step).
    pub(crate) fn limit_values(&mut self, targets: &[FingerTarget]) {
        if self.limits.len() > 0 {
            let l = &mut self.limits;
            l.set.values(
                &self.model,
                &self.q,
                &self.frames,
                targets,
                &mut self.values,
            );
        }
    }

    /// The limit rows' values and D J S at the tick's end (after the kept
    /// rows', which put the finger rows right after the loop rows). False
    /// if a row has no joint-space form.
    pub(crate) fn limit_jacobian(&mut self, targets: &[FingerTarget]) -> bool {
        self.limits.placed = 0;
        if self.limits.len() == 0 {
            return true;
        }
        let l = &mut self.limits;
        l.set.jacobian(
            &self.model,
            &self.space.tree,
            &self.q,
            &self.frames,
            &self.kin.twists,
            targets,
            &l.scale,
            &mut self.values,
            &mut l.jr,
            &mut l.grads,
        )
    }

    /// Whether the step (θ ← θ − step (θ + u)) would leave an inactive
    /// limit row below −`ACTIVATE_TOLERANCE_M`; those are forced.
    pub(crate) fn predict_limits(&mut self, step: f64) -> bool {
        let n = self.theta.len();
        let l = &mut self.limits;
        let mut any = false;
        for (i, &r) in l.rows.iter().enumerate() {
            if l.active[i] {
                continue;
            }
            let row = &l.jr[i * n..(i + 1) * n];
            let change: f64 = row
                .iter()
                .zip(self.theta.iter().zip(&self.u))
                .map(|(j, (t, u))| j * (t + u))
                .sum();
            if self.values[r] - step * change / l.scale[i] < -ACTIVATE_TOLERANCE_M {
                l.forced[i] = true;
                any = true;
            }
        }
        any
    }

    /// The forced rows join the active set and the factors are formed
    /// again; false (the tick's steps end) when this tick is out of
    /// activations.
    ///
    /// # Errors
    /// A factor that is not positive definite.
    pub(crate) fn activate_limits(&mut self) -> Result<bool, ReducedError> {
        self.limits.pending = true;
        if self.limits.activations >= MAX_ACTIVATIONS {
            return Ok(false);
        }
        self.limits.activations += 1;
        self.decide_limits();
        self.arrange_limits();
        self.factor_stage()?;
        Ok(true)
    }

    /// ν = max(0, −y) of the active rows after a taken step, 0 for the
    /// others.
    pub(crate) fn store_nu(&mut self) {
        let l = &mut self.limits;
        l.pending = false;
        l.nu.fill(0.0);
        for (j, &i) in l.order.iter().enumerate() {
            l.nu[i] = (-self.y[l.base + j]).max(0.0);
        }
    }

    /// The active set from ν, the values and the forced rows.
    fn decide_limits(&mut self) {
        let l = &mut self.limits;
        for (i, &r) in l.rows.iter().enumerate() {
            l.active[i] = l.nu[i] > 0.0 || self.values[r] < -INEQUALITY_ACTIVE_BAND || l.forced[i];
        }
    }

    /// Places the active limit rows between the loop and finger rows of
    /// the kept rows (rows, scale, D J S, gradients). No allocation.
    fn arrange_limits(&mut self) {
        let n = self.theta.len();
        let l = &mut self.limits;
        let (base, mf) = (l.base, self.space.tree.finger_rows.len());
        l.order.clear();
        l.order.extend((0..l.rows.len()).filter(|&i| l.active[i]));
        let k = l.order.len();
        let from = base + l.placed;
        self.jr
            .copy_within(from * n..(from + mf) * n, (base + k) * n);
        self.grads.copy_within(from..from + mf, base + k);
        for (j, &i) in l.order.iter().enumerate() {
            let dst = (base + j) * n;
            self.jr[dst..dst + n].copy_from_slice(&l.jr[i * n..(i + 1) * n]);
        }
        self.rows.truncate(base);
        self.rows.extend(l.order.iter().map(|&i| l.rows[i]));
        self.rows.extend(&self.space.tree.finger_rows);
        self.scale.truncate(base);
        self.scale
            .extend(self.rows[base..].iter().map(|&r| self.ell[r]));
        self.n_loop = base + k;
        l.placed = k;
    }

    /// The force stage's factors for the kept rows in place.
    fn factor_stage(&mut self) -> Result<(), ReducedError> {
        let m = self.rows.len() * self.theta.len();
        let tree = &self.space.tree;
        self.stage
            .factor(tree, &self.kin, &self.jr[..m], self.n_loop, &self.k_inv)
    }

    /// The active set at a tick's end (or a resync) and the factors: the
    /// rows forced by a step stay only if no step came after.
    pub(crate) fn limit_factors(&mut self) -> Result<(), ReducedError> {
        if self.limits.len() > 0 {
            if !std::mem::take(&mut self.limits.pending) {
                self.limits.forced.fill(false);
            }
            self.decide_limits();
            self.arrange_limits();
        }
        self.limits.released = false;
        self.factor_stage()
    }

    /// λ̃_F (after `limit_factors` and the load); an active limit that
    /// pulls is released and λ̃_F solved again without it.
    ///
    /// # Errors
    /// A factor that is not positive definite.
    pub(crate) fn solve_fingers(&mut self) -> Result<(), ReducedError> {
        let n = self.theta.len();
        if self.limits.placed == 0 {
            self.stage.finger_solve(n, self.n_loop);
            return Ok(());
        }
        self.limits.tau.copy_from_slice(&self.stage.tau);
        self.stage.finger_solve(n, self.n_loop);
        self.loop_multipliers();
        let l = &mut self.limits;
        l.gone.clear();
        for (j, &i) in l.order.iter().enumerate() {
            if l.lam[l.base + j] > 0.0 {
                l.active[i] = false;
                l.gone.push(l.base + j);
            }
        }
        if l.gone.is_empty() {
            return Ok(());
        }
        l.released = true;
        l.releases += 1;
        let (m, nl) = (self.rows.len(), self.n_loop);
        match l.spare.as_mut() {
            Some(spare) => {
                // Y and W of the kept rows are those of the steps' factors.
                self.stage.copy_factors(spare);
                self.stage.drop_loop_rows(n, m, nl, &l.gone)?;
                self.arrange_limits();
            }
            None => {
                self.arrange_limits();
                self.factor_stage()?;
            }
        }
        self.stage.tau.copy_from_slice(&self.limits.tau);
        self.stage.finger_solve(n, self.n_loop);
        Ok(())
    }

    /// λ̃_L = L_L⁻ᵀ (L_L⁻¹ g_L − Z λ̃_F) into `limits.lam` (after
    /// `finger_solve`, which leaves L_L⁻¹ g_L in g).
    fn loop_multipliers(&mut self) {
        let nl = self.n_loop;
        let st = &self.stage;
        let lam = &mut self.limits.lam[..nl];
        lam.copy_from_slice(&st.g[..nl]);
        for (f, &lf) in st.lambda_f.iter().enumerate() {
            for (a, z) in lam.iter_mut().zip(&st.z[f * nl..(f + 1) * nl]) {
                *a -= z * lf;
            }
        }
        backward(&st.wll, lam);
    }

    /// After a release: the next tick's steps keep the kinematic active
    /// set, whose factors were kept aside.
    ///
    /// # Errors
    /// A factor that is not positive definite (without a spare).
    pub(crate) fn restore_limits(&mut self) -> Result<(), ReducedError> {
        if !self.limits.released {
            return Ok(());
        }
        self.decide_limits();
        self.arrange_limits();
        match self.limits.spare.as_ref() {
            Some(spare) => {
                spare.copy_factors(&mut self.stage);
                Ok(())
            }
            None => self.factor_stage(),
        }
    }

    /// Limit rows in the factors.
    pub fn active_limits(&self) -> usize {
        self.limits.placed
    }

    /// Ticks whose Eq. 7 released a pulling limit.
    pub fn limit_releases(&self) -> u64 {
        self.limits.releases
    }

    /// In-tick activations of the last tick's steps.
    pub fn limit_activations(&self) -> u32 {
        self.limits.activations
    }
}
