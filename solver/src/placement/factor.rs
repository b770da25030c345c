//! Symbolic phase, part 2, and the numeric phase: faer's sparse Cholesky of
//! the normal matrix S with an approximate-minimum-degree ordering.
//!
//! [`NormalFactor::analyze`] runs faer's symbolic analysis once per structure
//! and sizes every buffer (the permuted matrix, L's values, one `MemBuffer`
//! for the largest numeric call); [`NormalFactor::factorize`] and
//! [`NormalFactor::solve`] then allocate nothing. The matrix is stored already
//! permuted, in the triangle faer's low-level kernel reads (upper for the
//! simplicial kernel, lower for the supernodal one), so no per-iteration
//! permutation copy is made.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::prelude::Reborrow;
use faer::sparse::SparseColMat;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky, simplicial, supernodal,
};
use faer::{Conj, MatMut, Par, Side};

use super::pattern::{NormalPattern, Unpermuted};

/// A numerically non-positive pivot: S is not (numerically) positive definite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct NotPositive;

/// The factorisation of one normal-matrix structure.
pub(crate) struct NormalFactor {
    symbolic: SymbolicCholesky<usize>,
    /// S, permuted, in the kernel's triangle; values rewritten per iteration.
    pub mat: SparseColMat<usize, f64>,
    pub plan: NormalPattern,
    l_vals: Vec<f64>,
    mem: MemBuffer,
    /// Right-hand sides `solve_many` may take at once.
    max_rhs: usize,
}

impl std::fmt::Debug for NormalFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NormalFactor")
            .field("rows", &self.mat.nrows())
            .field("normal_nnz", &self.mat.val().len())
            .field("factor_nnz", &self.l_vals.len())
            .field("supernodal", &self.supernodal())
            .finish_non_exhaustive()
    }
}

impl NormalFactor {
    /// Symbolic analysis (AMD ordering, elimination tree, supernodes) and all
    /// allocation. `max_rhs` is the widest block [`solve_many`](Self::solve_many)
    /// will be given.
    pub fn analyze(raw: &Unpermuted, max_rhs: usize) -> Option<Self> {
        let params = CholeskySymbolicParams::default();
        let symbolic = factorize_symbolic_cholesky(
            raw.lower.rb(),
            Side::Lower,
            SymmetricOrdering::Amd,
            params,
        )
        .ok()?;
        let m = raw.lower.nrows();
        let identity: Vec<usize>;
        let perm_inv = match symbolic.perm() {
            Some(p) => p.arrays().1,
            None => {
                identity = (0..m).collect();
                &identity
            }
        };
        let upper = matches!(symbolic.raw(), SymbolicCholeskyRaw::Simplicial(_));
        let (sym, plan) = raw.permute(perm_inv, upper);
        let nnz = sym.row_idx().len();
        let mat = SparseColMat::new(sym, vec![0.0; nnz]);
        let par = Par::Seq;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(max_rhs.max(1), par),
        ]);
        let l_vals = vec![0.0; symbolic.len_val()];
        Some(Self {
            symbolic,
            mat,
            plan,
            l_vals,
            mem: MemBuffer::new(req),
            max_rhs: max_rhs.max(1),
        })
    }

    /// Stored entries of L.
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Whether faer chose the supernodal kernel.
    pub fn supernodal(&self) -> bool {
        matches!(self.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// Σ over L's columns of (column count)²: flops of one factorisation, up
    /// to a constant factor.
    pub fn factor_flops(&self) -> u64 {
        let sq = |c: usize| (c as u64) * (c as u64);
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                s.col_ptr().windows(2).map(|w| sq(w[1] - w[0])).sum()
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let (begin, end) = (s.supernode_begin(), s.supernode_end());
                let rows = s.col_ptr_for_row_idx();
                (0..s.n_supernodes())
                    .map(|k| {
                        let width = end[k] - begin[k];
                        let below = rows[k + 1] - rows[k];
                        (0..width).map(|t| sq(width - t + below)).sum::<u64>()
                    })
                    .sum()
            }
        }
    }

    /// Numeric LLᵀ of the current `mat` values. No allocation.
    pub fn factorize(&mut self) -> Result<(), NotPositive> {
        let par = Par::Seq;
        let stack = MemStack::new(&mut self.mem);
        let reg = LltRegularization {
            dynamic_regularization_delta: 0.0,
            dynamic_regularization_epsilon: 0.0,
        };
        let a = self.mat.rb();
        let ok = match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                simplicial::factorize_simplicial_numeric_llt(&mut self.l_vals, a, reg, s, stack)
                    .is_ok()
            }
            SymbolicCholeskyRaw::Supernodal(s) => supernodal::factorize_supernodal_numeric_llt(
                &mut self.l_vals,
                a,
                reg,
                s,
                par,
                stack,
                Default::default(),
            )
            .is_ok(),
        };
        if ok && self.l_vals.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(NotPositive)
        }
    }

    /// x ← S⁻¹ x (original row order) with the last factorisation. No allocation.
    pub fn solve(&mut self, x: &mut [f64]) {
        let m = x.len();
        self.solve_many(x, m, 1);
    }

    /// Solves S X = B in place for `k ≤ max_rhs` columns stored column-major
    /// in `x` (`nrows × k`). No allocation.
    pub fn solve_many(&mut self, x: &mut [f64], nrows: usize, k: usize) {
        debug_assert!(k <= self.max_rhs);
        let stack = MemStack::new(&mut self.mem);
        let llt = LltRef::new(&self.symbolic, &self.l_vals);
        let rhs = MatMut::from_column_major_slice_mut(x, nrows, k);
        llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
    }
}
