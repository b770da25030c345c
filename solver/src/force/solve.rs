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
//! the virtual coupling instead. A_JJ is factored by a faer sparse Cholesky
//! (LLᵀ) whose symbolic analysis (AMD ordering, elimination tree, supernodes)
//! is done once; each tick refactors the values and solves 1 + m_f
//! right-hand sides. Sequential (`Par::Seq`), so the result is bit-identical
//! run to run.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};

use super::cg::Cg;
use super::gram::Gram;
use super::small::{cholesky_solve, min_norm_solve};

/// The numeric factorisation failed (a non-finite or non-positive pivot that
/// the dynamic regularisation could not repair).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct FactorError;

/// Symbolic factor and every buffer of the solve.
pub(crate) struct MultiplierSolve {
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    mem: MemBuffer,
    /// n_J × (1 + m_f), column-major: r_J, then A_JF's columns; solved in place.
    rhs: Vec<f64>,
    schur: Vec<f64>,
    /// S as assembled (the eigensolve destroys `schur`), for `project`.
    schur_keep: Vec<f64>,
    schur_rhs: Vec<f64>,
    /// Scratch of `project`: A_JJ⁻¹ r_J, then (S + K⁻¹) and its right-hand side.
    proj: Vec<f64>,
    small: Vec<f64>,
    small_rhs: Vec<f64>,
    eig: Vec<f64>,
    /// Scaled finger multipliers λ̃_F.
    pub lambda_f: Vec<f64>,
    /// Numerical rank of S at the last solve.
    pub rank: usize,
    /// `Some`: conjugate gradients instead of the numeric Cholesky.
    pub cg: Option<Cg>,
}

impl std::fmt::Debug for MultiplierSolve {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MultiplierSolve")
            .field("n", &self.symbolic.nrows())
            .field("factor_nnz", &self.l_values.len())
            .field("rank", &self.rank)
            .finish_non_exhaustive()
    }
}

impl MultiplierSolve {
    /// Symbolic analysis of `gram`'s A_JJ pattern; with `cg_iterations`, a
    /// capped conjugate-gradient solve replaces the numeric Cholesky.
    /// Allocates.
    pub fn new(gram: &Gram, cg_iterations: Option<u32>) -> Result<Self, faer::sparse::FaerError> {
        let symbolic = factorize_symbolic_cholesky(
            gram.pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )?;
        let (n, m) = (gram.n_j, gram.m_f);
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1 + m, Par::Seq),
        ]);
        Ok(Self {
            l_values: vec![0.0; symbolic.len_val()],
            symbolic,
            mem: MemBuffer::new(req),
            rhs: vec![0.0; n * (1 + m)],
            schur: vec![0.0; m * m],
            schur_keep: vec![0.0; m * m],
            schur_rhs: vec![0.0; m],
            proj: vec![0.0; n],
            small: vec![0.0; m * m],
            small_rhs: vec![0.0; m],
            eig: vec![0.0; m * m],
            lambda_f: vec![0.0; m],
            rank: 0,
            cg: cg_iterations.map(|it| Cg::new(n, 1 + m, it)),
        })
    }

    /// Number of stored values of the Cholesky factor L.
    pub fn factor_nnz(&self) -> usize {
        self.l_values.len()
    }

    /// Factors `gram`'s (already assembled and regularised) A_JJ and solves for
    /// λ̃_F given the scaled right-hand side `r` (one entry per row of C);
    /// `known` (F order): finger multipliers fixed in advance (proxies'
    /// coupling forces), the others solved for.
    ///
    /// # Real-time
    /// No allocation (faer runs in the preallocated `MemBuffer`), no locks;
    /// time bounded by the symbolic factor: one numeric LLᵀ, 1 + m_f
    /// triangular solve pairs, and an m_f × m_f Jacobi eigensolve.
    pub fn solve(
        &mut self,
        gram: &Gram,
        r: &[f64],
        known: &[Option<f64>],
    ) -> Result<(), FactorError> {
        let (n, m, nnz) = (gram.n_j, gram.m_f, gram.nnz());
        let a_fj = &gram.values[nnz..nnz + m * n];
        let a_ff = &gram.values[nnz + m * n..];
        for (row, slot) in r.iter().zip(&gram.slot) {
            if let super::gram::Slot::J(j) = *slot {
                self.rhs[j] = *row;
            }
        }
        self.rhs[n..].copy_from_slice(a_fj);
        if let Some(cg) = &mut self.cg {
            cg.solve(gram, &mut self.rhs);
        } else {
            self.factor(gram)?;
            LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut self.rhs, n, 1 + m),
                Par::Seq,
                MemStack::new(&mut self.mem),
            );
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
        // Rows whose multiplier is known (a proxy's coupling force): move
        // their part to the right-hand side and take them out of S.
        for (f, k) in known.iter().enumerate() {
            let Some(v) = *k else { continue };
            for (g, kg) in known.iter().enumerate() {
                if kg.is_none() {
                    self.schur_rhs[g] -= self.schur[g * m + f] * v;
                }
                self.schur[g * m + f] = 0.0;
                self.schur[f * m + g] = 0.0;
            }
            self.schur_rhs[f] = 0.0;
        }
        let reference = (0..m).map(|f| a_ff[f * m + f]).fold(0.0, f64::max);
        self.rank = min_norm_solve(
            &mut self.schur,
            &self.schur_rhs,
            &mut self.lambda_f,
            &mut self.eig,
            reference,
        );
        for (f, k) in known.iter().enumerate() {
            if let Some(v) = *k {
                self.lambda_f[f] = v;
            }
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
    /// factor's buffers, with faer's dynamic regularisation: a pivot below
    /// 1e-14 × the largest diagonal entry is replaced by 1e-10 × it. That
    /// keeps the factorisation alive through a round-off pivot; it does not
    /// make a singular A_JJ well-posed (masking redundant rows does, see
    /// `redundancy`).
    ///
    /// # Real-time
    /// No allocation; one numeric sparse Cholesky with the fixed symbolic
    /// factor.
    pub fn factor(&mut self, gram: &Gram) -> Result<(), FactorError> {
        let nnz = gram.nnz();
        let a = SparseColMatRef::new(gram.pattern.as_ref(), &gram.values[..nnz]);
        let max_diag = gram
            .diag
            .iter()
            .map(|&d| gram.values[d])
            .fold(0.0, f64::max);
        let reg = LltRegularization {
            dynamic_regularization_delta: 1e-10 * max_diag,
            dynamic_regularization_epsilon: 1e-14 * max_diag,
        };
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                a,
                Side::Lower,
                reg,
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .map(|_| ())
            .map_err(|_| FactorError)
    }

    /// x ← A_JJ⁻¹ x (n_J entries, J order) with the last [`factor`](Self::factor).
    ///
    /// # Real-time
    /// No allocation; one pair of sparse triangular solves.
    pub fn solve_joint(&mut self, x: &mut [f64]) {
        let n = x.len();
        LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
    }

    /// Solves the regularised normal equations of the projected update with
    /// the factor and Schur data of the last [`solve`](Self::solve):
    ///
    /// ```text
    /// [A_JJ  A_JF             ] [y_J]   [r_J]
    /// [A_FJ  A_FF + diag(k_inv)] [y_F] = [r_F]
    /// ```
    ///
    /// by y_F = (S + diag(k_inv))⁻¹ (r_F − A_FJ A_JJ⁻¹ r_J), y_J = A_JJ⁻¹ r_J −
    /// X y_F. `r`, `y`: one entry per row of C; `k_inv`: one per finger row.
    ///
    /// # Real-time
    /// No allocation; one pair of sparse triangular solves, an m_f × m_f
    /// Cholesky, O(n_J m_f).
    pub fn project(
        &mut self,
        gram: &Gram,
        r: &[f64],
        k_inv: &[f64],
        y: &mut [f64],
    ) -> Result<(), FactorError> {
        let (n, m, nnz) = (gram.n_j, gram.m_f, gram.nnz());
        if self.cg.is_some() {
            // The projected update needs the factor (checked by Program::new).
            return Err(FactorError);
        }
        for (j, &row) in gram.j_rows.iter().enumerate() {
            self.proj[j] = r[row];
        }
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.proj, n, 1),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
        let a_fj = &gram.values[nnz..nnz + m * n];
        self.small.copy_from_slice(&self.schur_keep);
        for f in 0..m {
            self.small[f * m + f] += k_inv[f];
            self.small_rhs[f] = r[gram.finger_rows[f]] - dot(&a_fj[f * n..(f + 1) * n], &self.proj);
        }
        if !cholesky_solve(&mut self.small, &mut self.small_rhs) {
            return Err(FactorError);
        }
        for (j, &row) in gram.j_rows.iter().enumerate() {
            let mut v = self.proj[j];
            for (f, yf) in self.small_rhs.iter().enumerate() {
                v -= self.rhs[(1 + f) * n + j] * yf;
            }
            y[row] = v;
        }
        for (f, &row) in gram.finger_rows.iter().enumerate() {
            y[row] = self.small_rhs[f];
        }
        Ok(())
    }

    /// Scaled multiplier λ̃_J of the j-th joint row at the last solve:
    /// A_JJ⁻¹ (r_J − A_JF λ̃_F) = z_j − Σ_f X_jf λ̃_f.
    pub fn joint_multiplier(&self, n_j: usize, j: usize) -> f64 {
        let mut v = self.rhs[j];
        for (f, l) in self.lambda_f.iter().enumerate() {
            v -= self.rhs[(1 + f) * n_j + j] * l;
        }
        v
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
