//! The finger multipliers of Eq. 7: joints first, then the smallest finger
//! load that balances the rest.
//!
//! In the scaled normal equations A λ̃ = D C_q M̃⁻¹ b (rows J: joints, norms,
//! active inequalities; rows F: fingers), eliminate J:
//!
//! ```text
//! S = A_FF − A_FJ A_JJ⁻¹ A_JF,   s = r_F − A_FJ A_JJ⁻¹ r_J,   λ̃_F = S⁺ s,   λ_F = D_F λ̃_F
//! ```
//!
//! S⁺ (minimum norm) makes the finger carry only what the joints cannot: the
//! component of −M q̈ + Q along the mechanism's free motions. In directions
//! the mechanism cannot move, the joints hold; the user feels those through
//! the virtual coupling instead.
//!
//! The whole matrix [A_JJ A_JF; A_FJ A_FF] goes to the crate's supernodal
//! sparse Cholesky (`crate::cholesky`) with the finger rows as an unfactored
//! tail: the factorisation of A_JJ (AMD order, symbolic analysis once)
//! carries the finger rows along as L_FJ = A_FJ L_JJ⁻ᵀ and leaves
//! S = A_FF − L_FJ L_FJᵀ in the tail's block. One solve then does everything:
//! the forward substitution leaves s = r_F − L_FJ L_JJ⁻¹ r_J in the finger
//! entries, S⁺ s replaces it, and the backward substitution gives the joint
//! multipliers A_JJ⁻¹ (r_J − A_JF λ̃_F): one right-hand side where solving
//! for A_JJ⁻¹ [r_J A_JF] took 1 + m_f. Sequential, so the result is
//! bit-identical run to run.
//!
//! `ForceSolver::ConjugateGradient` keeps the explicit form: CG solves
//! A_JJ X = [r_J A_JF] and S is formed from X. So does the matvec-only
//! tick (`ForceSolver::Matvec`, `pcg`), whose CG is preconditioned by a
//! factor the slow thread refreshes ([`MultiplierSolve::adopt`]); that
//! factor also serves the projected update.

use std::sync::atomic::{AtomicU64, Ordering};

use super::cg::Cg;
use super::gram::{Gram, Slot};
use super::pcg::{Bordered, Pcg};
use super::precond::Precond;
use super::precond::step::{STEP_TOLERANCE, StepCg};
use super::small::{cholesky_solve, min_norm_solve};
use crate::cholesky::{Cholesky, Superset};

/// The release branch's second solve from the first factor.
mod low_rank;
pub use low_rank::LowRankTally;
pub(crate) use low_rank::{BACK_OFF, LowRank};

/// The numeric factorisation failed (a non-finite or non-positive pivot that
/// the dynamic regularisation could not repair).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct FactorError;

/// Symbolic factor and every buffer of the solve.
#[derive(Clone)]
pub(crate) struct MultiplierSolve {
    llt: Cholesky,
    /// n_J + m_f: the right-hand side in J then F order, solved in place.
    x: Vec<f64>,
    /// Scaled joint multipliers λ̃_J of the last solve.
    lambda_j: Vec<f64>,
    /// CG only: n_J × (1 + m_f), column-major: r_J, then A_JF's columns.
    rhs: Vec<f64>,
    schur: Vec<f64>,
    /// S (full, symmetric) of the last solve (the eigensolve destroys
    /// `schur`), for `project`.
    schur_keep: Vec<f64>,
    schur_rhs: Vec<f64>,
    small: Vec<f64>,
    eig: Vec<f64>,
    /// Scaled finger multipliers λ̃_F.
    pub lambda_f: Vec<f64>,
    /// Numerical rank of S at the last solve.
    pub rank: usize,
    /// `Some`: conjugate gradients instead of the numeric Cholesky.
    pub cg: Option<Cg>,
    /// `Some`: the matvec-only tick (CG preconditioned by a refreshed
    /// factor), and its projected steps' CG.
    pub pcg: Option<Pcg>,
    bordered: Option<Bordered>,
    /// `Some`: the tree tick (`ForceSolver::Tree`): `pcg` preconditioned
    /// by the spanning-tree preconditioner, and its projected steps' solve.
    tree: Option<(Precond, StepCg)>,
    /// The tree tick has solved once (`rhs` holds A_JJ⁻¹ A_JF, `schur_keep`
    /// S of the A the projected steps use).
    tree_solved: bool,
    /// The factor holds a factorisation of this solve's A (made here or
    /// adopted): the matvec-only tick may precondition with it.
    seeded: bool,
    /// Identifies this solve's symbolic factor: a refreshed factor is
    /// adopted only by the solve it was computed for.
    id: u64,
}

/// Source of [`MultiplierSolve`] ids.
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

impl std::fmt::Debug for MultiplierSolve {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MultiplierSolve")
            .field("n", &self.x.len())
            .field("factor_nnz", &self.llt.len_values())
            .field("rank", &self.rank)
            .finish_non_exhaustive()
    }
}

impl MultiplierSolve {
    /// Symbolic analysis of `gram`'s pattern (A_JJ and the finger rows as
    /// the tail); with `cg_iterations`, a capped conjugate-gradient solve
    /// replaces the numeric Cholesky in [`solve`](Self::solve); with
    /// `matvec_iterations`, the matvec-only tick's preconditioned one does
    /// once the factor is seeded; `groups` as `Cholesky::analyze_grouped`
    /// (empty: none). Allocates.
    pub fn new(
        gram: &Gram,
        cg_iterations: Option<u32>,
        matvec_iterations: Option<u32>,
        groups: &[u32],
    ) -> Result<Self, faer::sparse::FaerError> {
        Self::with_path(
            gram,
            cg_iterations,
            matvec_iterations,
            groups,
            crate::cholesky::DENSE_MAX,
        )
    }

    /// [`new`](Self::new) with the small-matrix dense path (`cholesky`'s
    /// `dense`) taken up to order `dense_max` (0: never, every order takes
    /// the supernodal kernels).
    pub fn with_path(
        gram: &Gram,
        cg_iterations: Option<u32>,
        matvec_iterations: Option<u32>,
        groups: &[u32],
        dense_max: usize,
    ) -> Result<Self, faer::sparse::FaerError> {
        let (n, m) = (gram.n_j, gram.m_f);
        // The matvec-only tick preconditions all 1 + m_f columns at once;
        // the low-rank release solves its k columns at once (`low_rank`).
        let max_rhs = if matvec_iterations.is_some() {
            1 + m
        } else {
            low_rank::MAX_RANK
        };
        let llt = Self::analyze(gram, groups, max_rhs, dense_max)?;
        let cg = cg_iterations.map(|it| Cg::new(n, 1 + m, it));
        let pcg = matvec_iterations.map(|it| Pcg::new(n, 1 + m, it));
        let bordered = matvec_iterations.map(|it| Bordered::new(n + m, it));
        Ok(Self {
            llt,
            x: vec![0.0; n + m],
            lambda_j: vec![0.0; n],
            rhs: if cg.is_some() || pcg.is_some() {
                vec![0.0; n * (1 + m)]
            } else {
                Vec::new()
            },
            schur: vec![0.0; m * m],
            schur_keep: vec![0.0; m * m],
            schur_rhs: vec![0.0; m],
            small: vec![0.0; m * m],
            eig: vec![0.0; m * m],
            lambda_f: vec![0.0; m],
            rank: 0,
            cg,
            pcg,
            bordered,
            tree: None,
            tree_solved: false,
            seeded: false,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        })
    }

    /// The symbolic factor of `gram`'s pattern (A_JJ and the finger rows
    /// as the tail). With quaternion-norm rows out of their cliques, the
    /// coupled pattern's orders are candidates too, so the decoupled factor
    /// never costs more than the coupled one's orders give. Allocates.
    fn analyze(
        gram: &Gram,
        groups: &[u32],
        max_rhs: usize,
        dense_max: usize,
    ) -> Result<Cholesky, faer::sparse::FaerError> {
        let (n, m) = (gram.n_j, gram.m_f);
        let (extra, coupled) = (gram.dropped_entries(), gram.coupled_cliques());
        let superset = (!extra.is_empty()).then_some(Superset {
            extra: &extra,
            cliques: &coupled,
        });
        Cholesky::analyze_small_dense(
            n + m,
            m,
            &gram.factor_entries(),
            &gram.cliques(),
            groups,
            max_rhs,
            dense_max,
            superset,
        )
    }

    /// A symbolic factor for `other`, a pattern of the same rows (the
    /// coupled one, `force::feedback::norms`), to swap in with
    /// [`swap_factor`](Self::swap_factor). Allocates.
    pub fn factor_for(
        &self,
        other: &Gram,
        groups: &[u32],
        dense_max: usize,
    ) -> Result<Cholesky, faer::sparse::FaerError> {
        Self::analyze(other, groups, 1, dense_max)
    }

    /// Swaps this solve's factor with `other` (the factor of the pattern
    /// swapped in with it).
    ///
    /// # Real-time
    /// No allocation.
    pub fn swap_factor(&mut self, other: &mut Cholesky) {
        std::mem::swap(&mut self.llt, other);
        self.seeded = false;
    }

    /// Switches this solve (made with `matvec_iterations`) to the tree
    /// tick: `tree` preconditions the force solve's conjugate gradients,
    /// and the projected steps solve with it (at most `max_iterations`).
    pub fn set_tree(&mut self, tree: Precond, max_iterations: u32) {
        let n = self.lambda_j.len();
        self.tree = Some((tree, StepCg::new(n, max_iterations)));
    }

    /// The tree tick's preconditioner's shape and step iterations (`None`
    /// for the other solvers).
    pub fn tree_stats(&self, gram: &Gram) -> Option<super::precond::tree::TreeStats> {
        match self.tree.as_ref()? {
            (Precond::Tree(t), s) => Some(t.stats(gram.nnz(), s.total_iterations)),
            _ => None,
        }
    }

    /// The multilevel tick's preconditioner's shape and step iterations
    /// (`None` for the other solvers).
    pub fn multilevel_stats(&self) -> Option<super::precond::multilevel::MultilevelStats> {
        match self.tree.as_ref()? {
            (Precond::Multilevel(m), s) => Some(m.stats(s.total_iterations)),
            _ => None,
        }
    }

    /// The id a refreshed factor must carry to be adopted.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Replaces the factor's values by `values` (a factorisation of this
    /// solve's A computed elsewhere, see [`refreshed`](Self::refreshed)),
    /// handing the old ones back in `values`. False (nothing changed) on a
    /// length mismatch.
    ///
    /// # Real-time
    /// No allocation: the two buffers swap.
    pub fn adopt(&mut self, values: &mut Vec<f64>) -> bool {
        if self.llt.swap_values(values) {
            self.seeded = true;
            true
        } else {
            false
        }
    }

    /// Factors `gram`'s assembled, regularised A into `out` (resized to
    /// the factor's length), leaving this solve's own factor as it was: the
    /// slow thread's refresh of a matvec-only program's factor.
    pub fn refreshed(&mut self, gram: &Gram, out: &mut Vec<f64>) -> Result<(), FactorError> {
        out.resize(self.llt.len_values(), 0.0);
        let seeded = self.seeded;
        self.llt.swap_values(out);
        let done = self.factor(gram);
        self.llt.swap_values(out);
        self.seeded = seeded;
        done
    }

    /// Conjugate-gradient iterations of the last solve (0 with the
    /// Cholesky).
    pub fn cg_iterations(&self) -> u32 {
        match (&self.cg, &self.pcg) {
            (Some(c), _) => c.iterations,
            (None, Some(p)) if self.seeded || self.tree.is_some() => p.iterations,
            _ => 0,
        }
    }

    /// Matvec-only tick: conjugate-gradient solves (force and projected
    /// steps) that stopped at the cap above their tolerance, so far; each
    /// was redone with a numeric factorisation in the tick.
    pub fn matvec_unconverged(&self) -> u64 {
        self.pcg.as_ref().map_or(0, |p| p.unconverged)
            + self.bordered.as_ref().map_or(0, |b| b.unconverged)
            + self.tree.as_ref().map_or(0, |t| t.1.unconverged)
    }

    /// Number of stored values of the Cholesky factor L (its supernodes'
    /// dense blocks).
    pub fn factor_nnz(&self) -> usize {
        self.llt.len_values()
    }

    /// Switches the factor's AVX2 + FMA kernels off or on (comparisons).
    #[cfg(test)]
    pub fn set_simd(&mut self, on: bool) {
        self.llt.set_simd(on);
    }

    /// Whether the factor takes the small-matrix dense path.
    #[cfg(test)]
    pub fn is_dense(&self) -> bool {
        self.llt.is_dense()
    }

    /// The Cholesky factor's shape and operation counts.
    #[cfg(test)]
    pub fn factor_shape(&self) -> crate::cholesky::FactorShape {
        self.llt.shape()
    }

    /// Factors `gram`'s (already assembled and regularised) A_JJ and solves for
    /// λ̃_F and λ̃_J given the scaled right-hand side `r` (one entry per row
    /// of C); `known` (F order): finger multipliers fixed in advance
    /// (proxies' coupling forces), the others solved for.
    ///
    /// # Real-time
    /// No allocation, no locks; time bounded by the symbolic factor: one
    /// numeric LLᵀ, one triangular solve pair, and an m_f × m_f Cholesky
    /// (closed form when S is rank one, a Jacobi eigensolve when it is
    /// otherwise rank deficient).
    pub fn solve(
        &mut self,
        gram: &Gram,
        r: &[f64],
        known: &[Option<f64>],
    ) -> Result<(), FactorError> {
        if self.cg.is_some() {
            return self.solve_cg(gram, r, known);
        }
        if let Some((tree, _)) = &mut self.tree {
            // The tick's own A: O(nnz) for a fill-free pattern.
            tree.factor(gram)?;
            self.tree_solved = false;
            self.solve_cg(gram, r, known)?;
            self.tree_solved = true;
            return Ok(());
        }
        if self.seeded
            && let Some(before) = self.pcg.as_ref().map(|p| p.unconverged)
        {
            self.solve_cg(gram, r, known)?;
            if self.pcg.as_ref().is_some_and(|p| p.unconverged == before) {
                return Ok(());
            }
            // The refreshed factor no longer preconditions A well enough
            // for the cap: factor A itself (then the preconditioner is
            // exact until the next refresh) rather than render an
            // unconverged force.
        }
        let (n, m, nnz) = (gram.n_j, gram.m_f, gram.nnz());
        self.factor_keeping_schur(gram)?;
        self.gather(gram, r);
        let a_ff = &gram.values[nnz + m * n..];
        let reference = (0..m).map(|f| a_ff[f * m + f]).fold(0.0, f64::max);
        let Self {
            llt,
            x,
            schur,
            schur_keep,
            lambda_f,
            eig,
            ..
        } = self;
        let rank = llt.solve_with_tail(x, |_, s| {
            schur.copy_from_slice(schur_keep);
            let n_known = take_known_out(schur, s, known, reference);
            let rank = min_norm_solve(schur, s, lambda_f, eig, reference).saturating_sub(n_known);
            put_known_in(lambda_f, known);
            s.copy_from_slice(lambda_f);
            rank
        });
        self.rank = rank;
        self.lambda_j.copy_from_slice(&self.x[..n]);
        if self.lambda_f.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(FactorError)
        }
    }

    /// x ← r in J then F order.
    fn gather(&mut self, gram: &Gram, r: &[f64]) {
        let n = gram.n_j;
        for (row, slot) in r.iter().zip(&gram.slot) {
            match *slot {
                Slot::J(j) => self.x[j] = *row,
                Slot::F(f) => self.x[n + f] = *row,
                Slot::Out => {}
            }
        }
    }

    /// [`solve`](Self::solve) with conjugate gradients on A_JJ X = [r_J A_JF].
    fn solve_cg(
        &mut self,
        gram: &Gram,
        r: &[f64],
        known: &[Option<f64>],
    ) -> Result<(), FactorError> {
        let (n, m, nnz) = (gram.n_j, gram.m_f, gram.nnz());
        let a_fj = &gram.values[nnz..nnz + m * n];
        let a_ff = &gram.values[nnz + m * n..];
        for (row, slot) in r.iter().zip(&gram.slot) {
            if let Slot::J(j) = *slot {
                self.rhs[j] = *row;
            }
        }
        self.rhs[n..].copy_from_slice(a_fj);
        if let Some(cg) = &mut self.cg {
            cg.solve(gram, &mut self.rhs);
        } else if let Some(pcg) = &mut self.pcg {
            match &mut self.tree {
                Some((tree, _)) => pcg.solve_with(gram, &mut self.rhs, |z, k| tree.apply(z, k)),
                None => pcg.solve(gram, &mut self.llt, &mut self.rhs),
            }
        }
        for f in 0..m {
            let a_f = &a_fj[f * n..(f + 1) * n];
            self.schur_rhs[f] = r[gram.finger_rows[f]] - dot(a_f, &self.rhs[..n]);
            for g in 0..m {
                let x = &self.rhs[(1 + g) * n..(2 + g) * n];
                self.schur[f * m + g] = a_ff[f * m + g] - dot(a_f, x);
            }
        }
        // Symmetrise away round-off before the eigensolve.
        for f in 0..m {
            for g in 0..f {
                let avg = 0.5 * (self.schur[f * m + g] + self.schur[g * m + f]);
                self.schur[f * m + g] = avg;
                self.schur[g * m + f] = avg;
            }
        }
        self.schur_keep.copy_from_slice(&self.schur);
        let reference = (0..m).map(|f| a_ff[f * m + f]).fold(0.0, f64::max);
        let n_known = take_known_out(&mut self.schur, &mut self.schur_rhs, known, reference);
        self.rank = min_norm_solve(
            &mut self.schur,
            &self.schur_rhs,
            &mut self.lambda_f,
            &mut self.eig,
            reference,
        )
        .saturating_sub(n_known);
        put_known_in(&mut self.lambda_f, known);
        for j in 0..n {
            let mut v = self.rhs[j];
            for (f, l) in self.lambda_f.iter().enumerate() {
                v -= self.rhs[(1 + f) * n + j] * l;
            }
            self.lambda_j[j] = v;
        }
        if self.lambda_f.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(FactorError)
        }
    }
}

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
    fn factor_keeping_schur(&mut self, gram: &Gram) -> Result<(), FactorError> {
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

/// Rows whose multiplier is known (a proxy's coupling force): their part
/// moves to the right-hand side of the unknown rows, and each becomes the
/// decoupled row `reference · λ = 0` (so S stays full rank and takes the
/// Cholesky path; [`put_known_in`] then writes the known value). Returns how
/// many rows were known.
fn take_known_out(
    schur: &mut [f64],
    rhs: &mut [f64],
    known: &[Option<f64>],
    reference: f64,
) -> usize {
    let m = rhs.len();
    let mut n_known = 0;
    for (f, k) in known.iter().enumerate() {
        let Some(v) = *k else { continue };
        n_known += 1;
        for (g, kg) in known.iter().enumerate() {
            if kg.is_none() {
                rhs[g] -= schur[g * m + f] * v;
            }
            schur[g * m + f] = 0.0;
            schur[f * m + g] = 0.0;
        }
        schur[f * m + f] = if reference > 0.0 { reference } else { 1.0 };
        rhs[f] = 0.0;
    }
    n_known
}

/// Writes the known multipliers over the solved ones.
fn put_known_in(lambda_f: &mut [f64], known: &[Option<f64>]) {
    for (l, k) in lambda_f.iter_mut().zip(known) {
        if let Some(v) = *k {
            *l = v;
        }
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod timing {
    //! `cargo test --release -p haptloop-solver --lib force::solve::timing -- --ignored --nocapture`:
    //! the supernodal factor against faer's on the built-in mechanisms'
    //! Eq. 7 matrices, interleaved. Prints; asserts only agreement.
    use super::super::gram::Gram;
    use super::super::inertia::BodyMass;
    use crate::cholesky::Cholesky;
    use crate::mechanisms::{four_bar, sphere_toy, stewart};
    use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
    use faer::linalg::cholesky::llt::factor::LltRegularization;
    use faer::sparse::SparseColMatRef;
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, SymmetricOrdering, factorize_symbolic_cholesky,
    };
    use faer::{Conj, MatMut, Par, Side};
    use std::time::Instant;

    #[test]
    #[ignore]
    fn supernodal_against_faer() {
        for (name, model) in [
            ("four-bar", four_bar()),
            ("stewart", stewart()),
            ("sphere-toy", sphere_toy()),
        ] {
            let mut ev = model.evaluation();
            ev.evaluate(&model, model.q0(), &model.initial_targets())
                .unwrap();
            let masses = BodyMass::of_model(&model);
            let mut gram = Gram::new(&model, ev.jacobian(), &masses, &[]);
            let scale = vec![1.0; model.n_rows()];
            let b = vec![0.1; model.n_coords()];
            let mut y = vec![0.0; model.n_coords()];
            gram.assemble(model.q0(), ev.jacobian(), &scale, &masses, &b, &mut y);
            let (n, k) = (gram.n_j, 1 + gram.m_f);
            let a = &gram.values[..gram.nnz()];
            let reg = gram.regularization();
            let mut ours =
                Cholesky::analyze(n, gram.pattern.col_ptr(), gram.pattern.row_idx(), k).unwrap();
            let sym = factorize_symbolic_cholesky(
                gram.pattern.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                CholeskySymbolicParams::default(),
            )
            .unwrap();
            let mut l = vec![0.0; sym.len_val()];
            let mut mem = MemBuffer::new(StackReq::any_of(&[
                sym.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
                sym.solve_in_place_scratch::<f64>(k, Par::Seq),
            ]));
            let rhs: Vec<f64> = (0..n * k).map(|i| (i % 7) as f64 - 3.0).collect();
            let (mut x1, mut x2) = (rhs.clone(), rhs.clone());
            let reps = (20_000 / n).max(20);
            let mut t = [[0f64; 2]; 4];
            for _round in 0..6 {
                let s = Instant::now();
                for _ in 0..reps {
                    ours.factor(a, reg).unwrap();
                }
                t[0][0] += s.elapsed().as_secs_f64();
                let s = Instant::now();
                for _ in 0..reps {
                    x1.copy_from_slice(&rhs);
                    ours.solve(&mut x1, k);
                }
                t[1][0] += s.elapsed().as_secs_f64();
                let s = Instant::now();
                for _ in 0..reps {
                    sym.factorize_numeric_llt::<f64>(
                        &mut l,
                        SparseColMatRef::new(gram.pattern.as_ref(), a),
                        Side::Lower,
                        LltRegularization {
                            dynamic_regularization_delta: reg.delta,
                            dynamic_regularization_epsilon: reg.epsilon,
                        },
                        Par::Seq,
                        MemStack::new(&mut mem),
                        Default::default(),
                    )
                    .unwrap();
                }
                t[0][1] += s.elapsed().as_secs_f64();
                let s = Instant::now();
                for _ in 0..reps {
                    x2.copy_from_slice(&rhs);
                    faer::sparse::linalg::cholesky::LltRef::new(&sym, &l).solve_in_place_with_conj(
                        Conj::No,
                        MatMut::from_column_major_slice_mut(&mut x2, n, k),
                        Par::Seq,
                        MemStack::new(&mut mem),
                    );
                }
                t[1][1] += s.elapsed().as_secs_f64();
                let s = Instant::now();
                for _ in 0..reps {
                    x1[..n].copy_from_slice(&rhs[..n]);
                    ours.solve(&mut x1[..n], 1);
                }
                t[2][0] += s.elapsed().as_secs_f64();
                let s = Instant::now();
                for _ in 0..reps {
                    x2[..n].copy_from_slice(&rhs[..n]);
                    faer::sparse::linalg::cholesky::LltRef::new(&sym, &l).solve_in_place_with_conj(
                        Conj::No,
                        MatMut::from_column_major_slice_mut(&mut x2[..n], n, 1),
                        Par::Seq,
                        MemStack::new(&mut mem),
                    );
                }
                t[2][1] += s.elapsed().as_secs_f64();
            }
            let per = |x: f64| x / (6 * reps) as f64 * 1e6;
            x1.copy_from_slice(&rhs);
            ours.solve(&mut x1, k);
            x2.copy_from_slice(&rhs);
            faer::sparse::linalg::cholesky::LltRef::new(&sym, &l).solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut x2, n, k),
                Par::Seq,
                MemStack::new(&mut mem),
            );
            let diff = x1
                .iter()
                .zip(&x2)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let big = x2.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(diff <= 1e-9 * big, "{name}: {diff:e} vs {big:e}");
            println!(
                "{name}: n {n}, k {k}: factor ours {:.2} µs faer {:.2} µs ({:.2}×); solve×{k} ours {:.2} faer {:.2} ({:.2}×); solve×1 ours {:.2} faer {:.2} ({:.2}×)",
                per(t[0][0]),
                per(t[0][1]),
                t[0][1] / t[0][0],
                per(t[1][0]),
                per(t[1][1]),
                t[1][1] / t[1][0],
                per(t[2][0]),
                per(t[2][1]),
                t[2][1] / t[2][0],
            );
        }
    }
}
