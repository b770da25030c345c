//! `Feedback`'s accessors and the solves and re-factorisations the
//! projected update and the slow thread call between force computations
//! (the pipeline itself is in `feedback.rs`).

use super::*;

impl Feedback {
    /// The projected update's solve (see `MultiplierSolve::project`) with the
    /// factor of the last `compute`.
    pub fn project(&mut self, r: &[f64], k_inv: &[f64], y: &mut [f64]) -> Result<(), FactorError> {
        self.solve.project(&self.gram, r, k_inv, y)
    }

    /// out = M̃⁻¹ g at the configuration of the last `compute`.
    pub fn apply_inverse_mass(&self, g: &[f64], out: &mut [f64]) {
        self.gram.apply_inverse_mass(&self.masses, g, out);
    }

    /// The model row of each row of A_JJ (the joint rows, fingers left
    /// out), in A_JJ's order.
    pub fn joint_rows(&self) -> &[usize] {
        &self.gram.j_rows
    }

    /// x ← A_JJ⁻¹ x (one entry per row of [`joint_rows`](Self::joint_rows))
    /// with the factor of the last `compute`.
    ///
    /// # Real-time
    /// No allocation; one pair of sparse triangular solves.
    pub fn solve_joint(&mut self, x: &mut [f64]) {
        self.solve.solve_joint(x);
    }

    /// Per row: ℓ_i if the row took part in the last `compute`, else 0.
    pub fn row_scale(&self) -> &[f64] {
        &self.scale
    }

    /// Mean mass of the moving bodies, kilograms.
    pub fn mean_mass_kg(&self) -> f64 {
        self.masses.iter().map(|m| m.mass).sum::<f64>() / self.masses.len().max(1) as f64
    }

    /// Each finger's p − t at the last force solve (model finger order).
    pub fn prev_errors_snapshot(&self) -> &[Vector3<f64>] {
        &self.prev_error
    }

    /// Replaces every finger's coupling history (a replayed tick, see
    /// `program::converged`).
    pub fn set_prev_errors(&mut self, e: &[Vector3<f64>]) {
        self.prev_error.copy_from_slice(e);
    }

    /// Carries finger `from` of `old`'s coupling history into finger `to`.
    pub fn copy_finger(&mut self, to: usize, old: &Feedback, from: usize) {
        self.prev_error[to] = old.prev_error[from];
    }

    /// Ticks on which an active inequality was released and the solve ran
    /// again.
    pub fn releases(&self) -> u64 {
        self.releases
    }

    /// Times a sticking friction pair left the Coulomb cone and slipped.
    pub fn slips(&self) -> u64 {
        self.slips
    }

    /// Counts a slip decided outside the force solve (inertial motion
    /// judges the cone on the step's own forces).
    pub fn count_slip(&mut self) {
        self.slips += 1;
    }

    /// Refactors the joint block at the tick's chord Jacobian with the
    /// inequality rows `rows` forced active on top of the usual set (a step
    /// predicted they would be violated): the projected update's own
    /// activation within a tick, before the force solve at its end.
    ///
    /// # Real-time
    /// No allocation; one assembly and numeric factorisation.
    pub fn force_active(
        &mut self,
        s: &Scaling,
        settings: &SolverSettings,
        ev: &Evaluation,
        lambda: &[f64],
    ) -> Result<(), FactorError> {
        self.activate(s, ev.values(), lambda);
        self.solve_multipliers(ev, settings)
    }

    /// Refactors at `ev` with the rows active by C and `lambda` (as
    /// [`compute`](Self::compute)'s activation) for the projected steps,
    /// without solving for multipliers: the factor and row scales a
    /// `compute` at the same state leaves when nothing slips (a pulling
    /// row's release is undone by its last activation). The last solve's
    /// multipliers and outputs stay as they were. Cholesky solver only.
    ///
    /// # Real-time
    /// No allocation; one assembly and numeric factorisation.
    pub fn refactor_for_steps(
        &mut self,
        s: &Scaling,
        settings: &SolverSettings,
        ev: &Evaluation,
        lambda: &[f64],
    ) -> Result<(), FactorError> {
        self.activate(s, ev.values(), lambda);
        self.generation = self.generation.wrapping_add(1);
        self.assemble_regularized(ev, settings);
        self.solve.factor_for_steps(&self.gram)
    }

    /// See `MultiplierSolve::multilevel_stats`.
    pub fn multilevel_stats(&self) -> Option<crate::force::precond::multilevel::MultilevelStats> {
        self.solve.multilevel_stats()
    }

    /// See `MultiplierSolve::tree_stats`.
    pub fn tree_stats(&self) -> Option<crate::force::precond::tree::TreeStats> {
        self.solve.tree_stats(&self.gram)
    }

    /// Conjugate-gradient iterations of the last solve (0 with the Cholesky).
    pub fn cg_iterations(&self) -> u32 {
        self.solve.cg_iterations()
    }

    /// See `MultiplierSolve::matvec_unconverged`.
    pub fn matvec_unconverged(&self) -> u64 {
        self.solve.matvec_unconverged()
    }

    /// Identifies the force factor's pattern (see `MultiplierSolve::id`).
    pub fn factor_id(&self) -> u64 {
        self.solve.id()
    }

    /// Adopts a factor refreshed for this program (`MultiplierSolve::adopt`).
    ///
    /// # Real-time
    /// No allocation.
    pub fn adopt_factor(&mut self, values: &mut Vec<f64>) -> bool {
        let adopted = self.solve.adopt(values);
        if adopted {
            self.generation = self.generation.wrapping_add(1);
        }
        adopted
    }

    /// The slow thread's refresh of the force factor: activates the rows at
    /// `ev` (evaluated at `q`; inequalities by their values, multipliers
    /// unknown), assembles and regularises A as a force solve does, and
    /// factors it into `out`. This feedback's own factor is left as it was.
    pub fn refactor_into(
        &mut self,
        s: &Scaling,
        settings: &SolverSettings,
        q: &[f64],
        ev: &Evaluation,
        out: &mut Vec<f64>,
    ) -> Result<(), FactorError> {
        self.forced.fill(false);
        self.carry_forced = false;
        // cy is scratch here: zero multipliers.
        self.cy.fill(0.0);
        let zero = std::mem::take(&mut self.cy);
        self.activate(s, ev.values(), &zero);
        self.cy = zero;
        self.motion.q_prev.copy_from_slice(q);
        self.assemble_regularized(ev, settings);
        self.solve.refreshed(&self.gram, out)
    }

    /// Stored values of the sparse Cholesky factor (diagnostics).
    pub fn factor_nnz(&self) -> usize {
        self.solve.factor_nnz()
    }

    /// The sparse Cholesky factor's shape and operation counts.
    #[cfg(test)]
    pub fn factor_shape(&self) -> crate::cholesky::FactorShape {
        self.solve.factor_shape()
    }

    /// Rows of A's joint block, finger rows, and stored values of A_JJ's
    /// lower triangle.
    #[cfg(test)]
    pub fn gram_size(&self) -> (usize, usize, usize) {
        (self.gram.n_j, self.gram.m_f, self.gram.nnz())
    }

    /// The Eq. 7 matrix's pattern as the factor gets it (comparisons).
    #[cfg(test)]
    #[allow(clippy::type_complexity)]
    pub fn factor_entries(&self) -> (usize, usize, Vec<(usize, usize, usize)>, Vec<Vec<usize>>) {
        (
            self.gram.n_j + self.gram.m_f,
            self.gram.m_f,
            self.gram.factor_entries(),
            self.gram.cliques(),
        )
    }

    /// The coupled pattern (the quaternion-norm rows back in their bodies'
    /// cliques) as [`factor_entries`](Self::factor_entries) gives the
    /// decoupled one, and how many norm rows are decoupled (comparisons).
    #[cfg(test)]
    #[allow(clippy::type_complexity)]
    pub fn coupled_entries(&self) -> (Vec<(usize, usize, usize)>, Vec<Vec<usize>>, usize) {
        let mut e = self.gram.factor_entries();
        e.extend(self.gram.dropped_entries());
        (e, self.gram.coupled_cliques(), self.gram.decoupled_norms())
    }

    /// Switches the factor's AVX2 + FMA kernels off or on (comparisons).
    #[cfg(test)]
    pub fn set_simd(&mut self, on: bool) {
        self.solve.set_simd(on);
    }

    /// Builds the multiplier solve again with the small-matrix dense path
    /// up to order `dense_max` (0: off; comparisons, the Cholesky force
    /// solver).
    #[cfg(test)]
    pub fn set_dense(&mut self, model: &Model, dense_max: usize) {
        self.decoupled_in_use();
        let groups = contact_groups(model, &self.gram);
        self.solve = MultiplierSolve::with_path(&self.gram, None, None, &groups, dense_max)
            .expect("the pattern analysed once already");
        if let Some(c) = &mut self.coupled {
            c.set_dense(model, &self.solve, dense_max);
        }
    }

    /// Whether the multiplier solve takes the dense path.
    #[cfg(test)]
    pub fn is_dense(&self) -> bool {
        self.solve.is_dense()
    }

    /// A, the scaled right-hand side and the known finger multipliers of
    /// the last force solve (comparisons).
    #[cfg(test)]
    pub(crate) fn last_system(&self) -> (&Gram, &[f64], &[Option<f64>]) {
        (&self.gram, &self.cy, &self.known)
    }

    /// One assembly of A at the last force solve's state (timing).
    #[cfg(test)]
    pub fn reassemble(&mut self, ev: &Evaluation) {
        let q = &self.motion.q_prev;
        self.gram.assemble(
            q,
            ev.jacobian(),
            &self.scale,
            &self.masses,
            &self.b,
            &mut self.y,
        );
    }

    /// One numeric factorisation of the last assembled A (timing).
    #[cfg(test)]
    pub fn refactor(&mut self) -> Result<(), FactorError> {
        self.solve.factor(&self.gram)
    }
}
