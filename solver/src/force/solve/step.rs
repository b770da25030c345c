//! The projected update's solves from the factor and Schur complement of
//! the last [`MultiplierSolve::solve`], and the numeric factorisations they use.

use super::{FactorError, MultiplierSolve, dot};
use crate::force::gram::Gram;
use crate::force::precond::step::STEP_TOLERANCE;
use crate::force::small::cholesky_solve;

impl MultiplierSolve {
    /// Numeric LLᵀ of `gram`'s (assembled, regularised) A_JJ into the
    /// factor's buffers, carrying the finger rows (their block ends as the
    /// Schur complement), with faer's rule of dynamic regularisation: a pivot
    /// below 1e-14 × the largest diagonal entry is replaced by 1e-10 × it.
    /// That keeps the factorisation alive through a round-off pivot; it does
    /// not make a singular A_JJ well-posed (masking redundant rows does, see
    /// `redundancy`).
    ///
    /// # Real-time
    /// No allocation; one numeric sparse Cholesky with the fixed symbolic
    /// factor.
    pub fn factor(&mut self, gram: &Gram) -> Result<(), FactorError> {
        // Whatever this factors (a redundancy test matrix, a refresh), the
        // solve seeds itself again before preconditioning with it.
        self.seeded = false;
        let reg = gram.regularization();
        // Rows the assembly switched off are decoupled: the factor skips them.
        self.llt
            .factor_decoupled(&gram.values, reg, &gram.decoupled)
            .map_err(|_| FactorError)
    }

    /// x ← A_JJ⁻¹ x (n_J entries, J order) with the last [`factor`](Self::factor).
    ///
    /// # Real-time
    /// No allocation; one pair of sparse triangular solves.
    pub fn solve_joint(&mut self, x: &mut [f64]) {
        self.llt.solve(x, 1);
    }

    /// Solves the regularised normal equations of the projected update with
    /// the factor and Schur complement of the last [`solve`](Self::solve):
    ///
    /// ```text
    /// [A_JJ  A_JF             ] [y_J]   [r_J]
    /// [A_FJ  A_FF + diag(k_inv)] [y_F] = [r_F]
    /// ```
    ///
    /// by y_F = (S + diag(k_inv))⁻¹ (r_F − A_FJ A_JJ⁻¹ r_J) and
    /// y_J = A_JJ⁻¹ (r_J − A_JF y_F), in one solve through the factor's tail.
    /// `r`, `y`: one entry per row of C; `k_inv`: one per finger row.
    ///
    /// # Real-time
    /// No allocation; one pair of sparse triangular solves and an m_f × m_f
    /// Cholesky.
    pub fn project(
        &mut self,
        gram: &Gram,
        r: &[f64],
        k_inv: &[f64],
        y: &mut [f64],
    ) -> Result<(), FactorError> {
        let (n, m) = (gram.n_j, gram.m_f);
        if self.cg.is_some() {
            // The projected update needs the factor (checked by Program::new).
            return Err(FactorError);
        }
        if self.tree.is_some() {
            return self.project_tree(gram, r, k_inv, y);
        }
        self.gather(gram, r);
        let Self {
            llt,
            x,
            schur_keep,
            small,
            bordered,
            ..
        } = self;
        let before = bordered.as_ref().map(|b| b.unconverged);
        let ok = match bordered {
            // The matvec-only tick: CG preconditioned by the refreshed
            // factor with its own Schur complement (a consistent one).
            Some(cg) => cg.solve(gram, k_inv, x, |v| {
                llt.solve_with_tail(v, |block, s| {
                    for f in 0..m {
                        for g in 0..=f {
                            small[f * m + g] = block[f * m + g];
                            small[g * m + f] = block[f * m + g];
                        }
                        small[f * m + f] += k_inv[f];
                    }
                    cholesky_solve(small, s)
                })
            }),
            None => llt.solve_with_tail(x, |_, s| {
                small.copy_from_slice(schur_keep);
                for f in 0..m {
                    small[f * m + f] += k_inv[f];
                }
                cholesky_solve(small, s)
            }),
        };
        if !ok {
            return Err(FactorError);
        }
        if before.is_some() && self.bordered.as_ref().map(|b| b.unconverged) != before {
            // CG stopped at the cap: an inexact Gauss–Newton step lets the
            // violation grow tick after tick (the old cap of 4 failed 661
            // of 1000 ticks on Bennett). Factor the step's A here and take
            // the exact chord step with it.
            self.refactor_for_step(gram, r, k_inv)?;
        }
        for (j, &row) in gram.j_rows.iter().enumerate() {
            y[row] = self.x[j];
        }
        for (f, &row) in gram.finger_rows.iter().enumerate() {
            y[row] = self.x[n + f];
        }
        Ok(())
    }

    /// Factors `gram` and keeps its Schur complement for
    /// [`project`](Self::project), without solving for multipliers: the
    /// factor a [`solve`](Self::solve) of the same A leaves for the steps
    /// (Cholesky solver; the conjugate-gradient solver has no factor).
    ///
    /// # Real-time
    /// No allocation; one numeric factorisation.
    pub fn factor_for_steps(&mut self, gram: &Gram) -> Result<(), FactorError> {
        if self.cg.is_some() || self.pcg.is_some() {
            return Err(FactorError);
        }
        self.factor_keeping_schur(gram)
    }

    /// Factors `gram` (seeding the preconditioner) and keeps S, the tail
    /// block's lower triangle mirrored to a full m × m.
    pub(super) fn factor_keeping_schur(&mut self, gram: &Gram) -> Result<(), FactorError> {
        let m = gram.m_f;
        self.factor(gram)?;
        self.seeded = true;
        let block = self.llt.tail_block();
        for f in 0..m {
            for g in 0..=f {
                let v = block[f * m + g];
                self.schur_keep[f * m + g] = v;
                self.schur_keep[g * m + f] = v;
            }
        }
        Ok(())
    }

    /// The matvec-only tick's fallback for a projected step whose CG hit
    /// the cap: factors `gram`'s A (seeding the preconditioner with it) and
    /// solves the step directly, as the Cholesky tick does.
    fn refactor_for_step(
        &mut self,
        gram: &Gram,
        r: &[f64],
        k_inv: &[f64],
    ) -> Result<(), FactorError> {
        let m = gram.m_f;
        self.factor_keeping_schur(gram)?;
        self.gather(gram, r);
        let Self {
            llt,
            x,
            schur_keep,
            small,
            ..
        } = self;
        let ok = llt.solve_with_tail(x, |_, s| {
            small.copy_from_slice(schur_keep);
            for f in 0..m {
                small[f * m + f] += k_inv[f];
            }
            cholesky_solve(small, s)
        });
        if ok { Ok(()) } else { Err(FactorError) }
    }

    /// [`project`](Self::project) for the tree tick, with the last force
    /// solve's A_JJ⁻¹ A_JF (`rhs`) and S: y_F = (S + diag(k_inv))⁻¹
    /// (r_F − A_FJ t) and y_J = t − A_JJ⁻¹ A_JF y_F, t = A_JJ⁻¹ r_J by
    /// conjugate gradients with the tree preconditioner (one column).
    fn project_tree(
        &mut self,
        gram: &Gram,
        r: &[f64],
        k_inv: &[f64],
        y: &mut [f64],
    ) -> Result<(), FactorError> {
        let (n, m, nnz) = (gram.n_j, gram.m_f, gram.nnz());
        if !self.tree_solved {
            // No force solve yet on this A: it leaves A_JJ⁻¹ A_JF and S
            // (its multipliers are the next force solve's to set).
            self.solve(gram, r, &[])?;
        }
        self.gather(gram, r);
        let Self {
            x,
            rhs,
            schur_keep,
            small,
            tree,
            ..
        } = self;
        let Some((tree, step)) = tree else {
            return Err(FactorError);
        };
        let (xj, xf) = x.split_at_mut(n);
        let rel = step.solve(gram, xj, STEP_TOLERANCE, |v| tree.apply(v, 1));
        if !rel.is_finite() {
            return Err(FactorError);
        }
        let a_fj = &gram.values[nnz..nnz + m * n];
        for f in 0..m {
            xf[f] -= dot(&a_fj[f * n..(f + 1) * n], xj);
        }
        small.copy_from_slice(schur_keep);
        for (f, k) in k_inv.iter().enumerate() {
            small[f * m + f] += k;
        }
        if !cholesky_solve(small, xf) {
            return Err(FactorError);
        }
        for (f, &yf) in xf.iter().enumerate() {
            for (xj, a) in xj.iter_mut().zip(&rhs[(1 + f) * n..(2 + f) * n]) {
                *xj -= a * yf;
            }
        }
        for (j, &row) in gram.j_rows.iter().enumerate() {
            y[row] = xj[j];
        }
        for (f, &row) in gram.finger_rows.iter().enumerate() {
            y[row] = xf[f];
        }
        Ok(())
    }

    /// Scaled multiplier λ̃_J of the j-th joint row at the last solve:
    /// A_JJ⁻¹ (r_J − A_JF λ̃_F).
    pub fn joint_multiplier(&self, j: usize) -> f64 {
        self.lambda_j[j]
    }
}
