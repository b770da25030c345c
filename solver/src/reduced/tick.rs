//! A whole quasi-static tick in joint coordinates (`Program`'s tick with
//! `coordinates = Joint`, `program/joint.rs`): the
//! projected update's problem solved on the tree's joint coordinates θ,
//! then Eq. 7's finger force in joint coordinates (`stage`).
//!
//! **The update** is the augmented projected step (`al::projected`) with
//! Δq = S δθ: each tick, from its start q_s (θ = 0, q₀ = q_s: quasi-static),
//! with the chord J_r S and the factors of the previous tick's force stage
//! (at q_s), `settings.iterations` steps of size `settings.step` of
//!
//! ```text
//! min_δ  ½ (θ + δ)ᵀ H (θ + δ) + ½ K m̄ Σ_F (ℓ (C_F + J_F S δ))²
//! s.t.   C_L + J_L S δ = 0                            (kept loop rows)
//! δ = −θ − H⁻¹ S ᵀJ_rᵀ y,   [W_LL W_LF; W_FL W_FF + 1/(K m̄)] y = D (C − J_r S θ)
//! ```
//!
//! (W = D J_r S H⁻¹ Sᵀ J_rᵀ D, D the rows' ℓ): the augmented step's KKT
//! system after the tree and quaternion-norm rows are eliminated, with the
//! same finger weight, the same pull limit on far targets, and the chord
//! guard (a step more than twice the tick's previous one ends the tick's
//! steps). The tree joints and the quaternion norms hold by construction
//! (forward kinematics from q_s, `kinematics::displace_with`), so only the
//! loop and finger rows are evaluated (`rows`). Solving W's system reuses
//! the force stage's L_L (W_LL's factor), Z = L_L⁻¹ W_LF and the Cholesky
//! of Σ_F + 1/(K m̄), formed once a tick instead of once a step.
//!
//! Differences from the augmented `Program::tick` on the same model: the
//! chord guard measures a step by its largest joint coordinate change
//! (rotations times L) instead of the augmented metric; ½ θᵀHθ replaces
//! ½ dᵀ M̃ d (equal to second order in the tick's motion); no multipliers
//! but the limits' ν (`limits`: revolute and prismatic limits on tree
//! joints, with the augmented tick's active set); proxies (contact
//! fingers), other inequality rows, contact, design columns and inertial
//! motion are refused at construction. `Program` adds the
//! divergence limits, the failed-tick restore, the report over every row
//! and the resync wherever q moves outside a tick (`program/joint.rs`).
//! Not done: a fallback to the augmented tick at a singular pose where the
//! tree's coordinates or the loop block lose rank (the tick fails there).

use std::sync::Arc;

use nalgebra::Vector3;

use super::kinematics::{Kinematics, Rigid, displace_with};
use super::limits::Limits;
use super::rows::RowSet;
use super::small::{backward, dot, forward};
use super::stage::Stage;
use super::{JointSpace, ReducedError};
use crate::al::scaling::Scaling;
use crate::constraint::block::RowGrad;
use crate::force::small::substitute;
use crate::rotation::BodyFrame;
use crate::{FingerOutput, FingerTarget, Model, SolverSettings};

/// As `program::tick`: a step more than this × the tick's previous one is
/// refused and ends the tick's steps.
const CHORD_GROWTH: f64 = 2.0;

/// Steps below this (metres) are never judged.
const CHORD_FLOOR_M: f64 = 1e-9;

/// The joint tick of one model: state, factors and every buffer.
pub struct JointTick {
    pub(crate) model: Arc<Model>,
    pub(crate) space: JointSpace,
    pub(crate) settings: SolverSettings,
    pub(crate) set: RowSet,
    /// The kept rows (loop rows first), their scale ℓ, kept loop rows.
    pub(crate) rows: Vec<usize>,
    pub(crate) scale: Vec<f64>,
    pub(crate) n_loop: usize,
    /// Every loop row (masked ones too): the violation is theirs.
    loop_rows: Vec<usize>,
    /// 1 / (K w m̄) per finger row.
    pub(crate) k_inv: Vec<f64>,
    /// ℓ of the rows and the pull limit (`Scaling`).
    pub(crate) ell: Vec<f64>,
    finger_limit_m: f64,
    /// Per joint coordinate: metres per unit (L for rotations, 1 for slides).
    dof_len: Vec<f64>,
    /// q at the tick's start (the chord point) and at the current iterate.
    pub(crate) q_s: Vec<f64>,
    pub(crate) q: Vec<f64>,
    /// Frames at q (bodies, then the world).
    pub(crate) frames: Vec<BodyFrame>,
    /// Frames and twists at q_s.
    pub(crate) kin: Kinematics,
    rigid: Vec<Rigid>,
    pub(crate) values: Vec<f64>,
    /// D J_r S at q_s (kept rows × dofs) and the kept rows' gradients.
    pub(crate) jr: Vec<f64>,
    pub(crate) grads: Vec<RowGrad>,
    /// The force stage's factors and buffers.
    pub(crate) stage: Stage,
    /// The joint limits' active set (`limits`).
    pub(crate) limits: Limits,
    pub(crate) theta: Vec<f64>,
    r: Vec<f64>,
    pub(crate) y: Vec<f64>,
    pub(crate) u: Vec<f64>,
    /// The finger outputs of the last tick.
    pub outputs: Vec<FingerOutput>,
    /// Largest |C| of the loop rows at the last tick's end (metres for
    /// length rows, radians for angle rows, both counted).
    pub max_violation: f64,
    /// Update steps the last tick applied.
    pub steps: u32,
}

impl JointTick {
    /// The joint tick of `model` at `q` (assembled) under `settings`, the
    /// force stage's factors formed at `q` toward `targets`, the motion
    /// history at rest. Allocates.
    ///
    /// # Errors
    /// What [`JointSpace::new`] refuses; inertial motion, contact
    /// fingers; a degenerate q.
    pub fn new(
        model: Arc<Model>,
        settings: SolverSettings,
        q: &[f64],
        targets: &[FingerTarget],
    ) -> Result<Self, ReducedError> {
        if settings.dynamics {
            return Err(ReducedError::Unsupported("inertial motion".into()));
        }
        if model.fingers().iter().any(|f| f.tip.is_some()) {
            return Err(ReducedError::Unsupported("contact fingers".into()));
        }
        let mut ev = model.evaluation();
        ev.evaluate(&model, q, targets)
            .map_err(|e| ReducedError::Unsupported(format!("evaluation: {e}")))?;
        let space = JointSpace::new(&model, q, &ev)?;
        let scaling = Scaling::new(&model, &settings);
        let rows = space.rows().to_vec();
        let n_loop = rows.len() - space.tree.finger_rows().len();
        let scale: Vec<f64> = rows.iter().map(|&r| scaling.ell[r]).collect();
        let loop_rows = space.tree.loop_rows().to_vec();
        let set = RowSet::new(&model, &rows, &loop_rows);
        let masses = crate::force::inertia::BodyMass::of_model(&model);
        let mean = masses.iter().map(|m| m.mass).sum::<f64>() / masses.len().max(1) as f64;
        let mf = space.tree.finger_rows().len();
        let k_inv = vec![1.0 / (settings.gain * settings.finger_weight * mean); mf];
        let mut dof_len = vec![scaling.length_m; space.tree.dofs()];
        for j in &space.tree.joints {
            if matches!(j.freedom, super::tree::Freedom::Prismatic { .. }) {
                dof_len[j.dof] = 1.0;
            }
        }
        let (n, m0) = (space.tree.dofs(), rows.len());
        let limits = Limits::new(&model, &space.tree, &scaling.ell, n_loop, |k| {
            Stage::new(&model, &space.tree, n, m0 + k, n_loop + k, q)
        })?;
        let m = m0 + limits.len();
        let mut rows = rows;
        rows.reserve_exact(limits.len());
        let mut scale = scale;
        scale.reserve_exact(limits.len());
        let frames = ev.frames().to_vec();
        let mut kin = Kinematics::new(&model, &space.tree);
        kin.frames.clone_from(&frames);
        let stage = Stage::new(&model, &space.tree, n, m, n_loop + limits.len(), q);
        let mut t = Self {
            limits,
            rigid: vec![Rigid::IDENTITY; space.tree.joints.len()],
            set,
            rows,
            scale,
            n_loop,
            loop_rows,
            k_inv,
            ell: scaling.ell.clone(),
            finger_limit_m: scaling.finger_limit_m,
            dof_len,
            q_s: q.to_vec(),
            q: q.to_vec(),
            frames,
            kin,
            values: vec![0.0; model.n_rows()],
            jr: vec![0.0; m * n],
            grads: vec![RowGrad::default(); m],
            stage,
            theta: vec![0.0; n],
            r: vec![0.0; m],
            y: vec![0.0; m],
            u: vec![0.0; n],
            outputs: vec![FingerOutput::default(); model.fingers().len()],
            max_violation: 0.0,
            steps: 0,
            space,
            settings,
            model,
        };
        t.end_of_tick(targets, 1e-3, false)?;
        Ok(t)
    }

    /// Joint coordinates.
    pub fn dofs(&self) -> usize {
        self.theta.len()
    }

    /// q (augmented layout) at the last tick's end.
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// One tick toward `targets` (one per finger), `dt_s` after the last:
    /// the update's steps, forward kinematics, the loop and finger rows'
    /// values and J_r S at the result, and the force stage. No allocation.
    ///
    /// # Errors
    /// A bad targets slice, a degenerate pose, a factor that is not
    /// positive definite.
    pub fn tick(&mut self, targets: &[FingerTarget], dt_s: f64) -> Result<(), ReducedError> {
        let ok = targets.len() == self.model.fingers().len()
            && targets
                .iter()
                .all(|t| t.position_m.iter().all(|v| v.is_finite()));
        if !ok || dt_s.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(ReducedError::Unsupported("targets or dt".into()));
        }
        self.steps = self.update(targets)?;
        self.end_of_tick(targets, dt_s, true)
    }

    /// The tick's steps from q_s; returns the number applied. q and the
    /// frames are those of the last step's start (the step's result is
    /// posed by [`evaluate_end`](Self::evaluate_end)).
    pub(crate) fn update(&mut self, targets: &[FingerTarget]) -> Result<u32, ReducedError> {
        self.theta.fill(0.0);
        let step = self.settings.step;
        let mut allowed = f64::INFINITY;
        self.limits.begin();
        let mut k = 0;
        while k < self.settings.iterations {
            if k > 0 {
                self.pose()?;
            }
            self.set.values(
                &self.model,
                &self.q,
                &self.frames,
                targets,
                &mut self.values,
            );
            self.limit_values(targets);
            self.residual();
            self.solve_step();
            // δ = −θ − H⁻¹ (D J_r S)ᵀ y; u holds H⁻¹ (D J_r S)ᵀ y.
            let mut size: f64 = 0.0;
            for d in 0..self.theta.len() {
                size = size.max((step * (self.theta[d] + self.u[d])).abs() * self.dof_len[d]);
            }
            // NaN-safe: a NaN size is refused too.
            if size
                .partial_cmp(&allowed)
                .is_none_or(|o| o == std::cmp::Ordering::Greater)
            {
                return Ok(k);
            }
            if self.limits.len() > 0 && self.predict_limits(step) {
                // Inactive limits the step would cross join the active set
                // and the step is taken again (`limits`), or the tick's
                // steps end here.
                if !self.activate_limits()? {
                    return Ok(k);
                }
                continue;
            }
            allowed = (CHORD_GROWTH * size).max(CHORD_FLOOR_M);
            for (t, u) in self.theta.iter_mut().zip(&self.u) {
                *t -= step * (*t + u);
            }
            self.store_nu();
            k += 1;
        }
        Ok(self.settings.iterations)
    }

    /// q and the frames at θ from q_s (forward kinematics).
    pub(crate) fn pose(&mut self) -> Result<(), ReducedError> {
        let tree = &self.space.tree;
        displace_with(
            &self.model,
            tree,
            &self.kin,
            &self.q_s,
            &self.theta,
            &mut self.q,
            &mut self.rigid,
        );
        for j in &tree.joints {
            let (b, q) = (j.child, &self.q);
            let Some(o) = self.model.layout().body_offset(b) else {
                continue;
            };
            let r = Vector3::new(q[o], q[o + 1], q[o + 2]);
            self.frames[b.index()] = BodyFrame::new(r, [q[o + 3], q[o + 4], q[o + 5], q[o + 6]])
                .ok_or(ReducedError::Degenerate(b.index()))?;
        }
        Ok(())
    }

    /// r = D (C − J_r S θ) with the pull limit on far finger targets.
    fn residual(&mut self) {
        let n = self.theta.len();
        for (i, &row) in self.rows.iter().enumerate() {
            let jt = dot(&self.jr[i * n..(i + 1) * n], &self.theta);
            self.r[i] = self.scale[i] * self.values[row] - jt;
        }
        let nl = self.n_loop;
        for g0 in (nl..self.rows.len()).step_by(3) {
            let end = (g0 + 3).min(self.rows.len());
            let norm = (g0..end)
                .map(|i| (self.ell[self.rows[i]] * self.values[self.rows[i]]).powi(2))
                .sum::<f64>()
                .sqrt();
            if norm > self.finger_limit_m {
                let f = self.finger_limit_m / norm;
                for i in g0..end {
                    let jt = dot(&self.jr[i * n..(i + 1) * n], &self.theta);
                    self.r[i] = self.scale[i] * f * self.values[self.rows[i]] - jt;
                }
            }
        }
    }

    /// y from r with the stage's factors, then u = H⁻¹ (D J_r S)ᵀ y.
    fn solve_step(&mut self) {
        let (nl, m, n) = (self.n_loop, self.rows.len(), self.theta.len());
        let st = &mut self.stage;
        let (yl, yf) = self.y[..m].split_at_mut(nl);
        yl.copy_from_slice(&self.r[..nl]);
        forward(&st.wll, yl);
        for (f, v) in yf.iter_mut().enumerate() {
            *v = self.r[nl + f] - dot(&st.z[f * nl..(f + 1) * nl], yl);
        }
        substitute(&st.sk, yf);
        for (f, &v) in yf.iter().enumerate() {
            for (a, zv) in yl.iter_mut().zip(&st.z[f * nl..(f + 1) * nl]) {
                *a -= zv * v;
            }
        }
        backward(&st.wll, yl);
        self.u.fill(0.0);
        for i in 0..m {
            let yi = self.y[i];
            for (u, j) in self.u.iter_mut().zip(&self.jr[i * n..(i + 1) * n]) {
                *u += j * yi;
            }
        }
        st.solve_h(&mut self.u);
    }

    /// The update alone from q_s (the probe: repeatable, q_s unchanged).
    #[cfg(test)]
    pub(crate) fn update_for_probe(&mut self, targets: &[FingerTarget]) {
        self.update(targets).unwrap();
    }

    /// One evaluation of the loop and finger rows' values (the probe).
    #[cfg(test)]
    pub(crate) fn values_for_probe(&mut self, targets: &[FingerTarget]) {
        self.set.values(
            &self.model,
            &self.q,
            &self.frames,
            targets,
            &mut self.values,
        );
    }

    /// The loop rows' largest |C| at the current values.
    pub(crate) fn violation(&self) -> f64 {
        self.loop_rows
            .iter()
            .map(|&r| self.values[r].abs())
            .fold(0.0, f64::max)
    }
}
