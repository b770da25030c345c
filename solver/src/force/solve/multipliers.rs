//! The multipliers of Eq. 7 from the factor (or CG): [`MultiplierSolve::solve`].

use super::known::{put_known_in, take_known_out};
use super::{FactorError, MultiplierSolve, dot};
use crate::force::gram::{Gram, Slot};
use crate::force::small::min_norm_solve;

impl MultiplierSolve {
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
    pub(super) fn gather(&mut self, gram: &Gram, r: &[f64]) {
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
