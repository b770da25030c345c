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
use super::gram::Gram;
use super::pcg::{Bordered, Pcg};
use super::precond::Precond;
use super::precond::step::StepCg;
use crate::cholesky::{Cholesky, Superset};

/// Rows whose multiplier is fixed in advance.
mod known;
/// The release branch's second solve from the first factor.
mod low_rank;
/// The multipliers of Eq. 7: [`MultiplierSolve::solve`].
mod multipliers;
/// The projected update's solves from the same factor.
mod step;
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
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod timing;
