//! The spanning-tree preconditioner of A_JJ = D C_q M̃⁻¹ C_qᵀ D
//! (`ForceSolver::Tree`).
//!
//! Bodies are the nodes of the mechanism's graph and each constraint that
//! touches two moving bodies is an edge (ground is not a node: rows only
//! couple through moving bodies). A breadth-first spanning forest of that
//! graph splits the J rows in two:
//!
//! - **tree rows**: the spanning forest's joints and every row touching a
//!   single body (quaternion norms, joints to ground);
//! - **loop rows**: the other joints (the loop closures, and any constraint
//!   touching more than two bodies).
//!
//! The preconditioner is P = A_TT ⊕ blockdiag(A_ℓℓ over the loop
//! constraints ℓ): the exact Gram block of the tree mechanism, plus each loop
//! closure's own diagonal block. A_TT's graph is a tree of per-body cliques
//! glued along the tree joints' rows (a chordal graph), so a perfect
//! elimination order gives a factor without fill: nnz(L_P) ≈ nnz(P) ≤
//! nnz(A), and one application (a triangular-solve pair) costs
//! O(nnz(C_q)). The preconditioner is factored from the tick's own A, once
//! per force solve (O(nnz) too, each body's clique dense), so on a mechanism
//! without loops P = A and conjugate gradients converge in one iteration;
//! with loops, A − P has rank at most twice the loop rows and CG resolves
//! the loop closures.

use std::collections::VecDeque;

use super::super::gram::Gram;
use super::super::solve::FactorError;
use crate::cholesky::Cholesky;

/// The symbolic factor of P, where its values come from in A, and its shape.
#[derive(Debug, Clone)]
pub(crate) struct TreePrecond {
    llt: Cholesky,
    /// Per value of P (lower CSC): its row and column (J indices).
    rc: Vec<(u32, u32)>,
    /// Per value of P: its index in `Gram::values`.
    src: Vec<usize>,
    /// P's values at the last factorisation (the factor's input).
    values: Vec<f64>,
    /// Per J row: a tree row (false: a loop row).
    pub tree_row: Vec<bool>,
    /// A factorisation of the current A is held.
    pub factored: bool,
}

/// The tree tick's preconditioner and what its solves did
/// ([`Program::tree_stats`](crate::Program::tree_stats)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TreeStats {
    /// Stored values of A_JJ's lower triangle.
    pub a_nnz: usize,
    /// Stored values of P's lower triangle.
    pub p_nnz: usize,
    /// Stored values of P's factor (supernodal blocks, the unused upper
    /// halves of their diagonal parts included).
    pub factor_values: usize,
    /// J rows in the loop set (loop-closing constraints).
    pub loop_rows: usize,
    /// Conjugate-gradient iterations of every projected step so far.
    pub step_iterations: u64,
}

/// How the J rows split (see the module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Split {
    /// Per J row: a tree row.
    pub tree_row: Vec<bool>,
    /// Constraints that close a loop (or touch more than two bodies).
    pub loop_constraints: usize,
}

/// Splits the J rows of `gram` into tree and loop rows; `group[j]`: the
/// constraint of J row j (rows of one constraint go together). Allocates.
pub(crate) fn split(gram: &Gram, group: &[usize]) -> Split {
    let n = gram.n_j;
    let cliques = gram.cliques();
    let n_groups = group.iter().map(|&g| g + 1).max().unwrap_or(0);
    // Bodies each constraint touches (deduplicated, at most 3 recorded).
    let mut touches: Vec<Vec<usize>> = vec![Vec::new(); n_groups];
    for (b, rows) in cliques.iter().enumerate() {
        for &j in rows {
            let t = &mut touches[group[j]];
            if !t.contains(&b) && t.len() < 3 {
                t.push(b);
            }
        }
    }
    let mut adjacent: Vec<Vec<(usize, usize)>> = vec![Vec::new(); cliques.len()];
    for (g, t) in touches.iter().enumerate() {
        if let [a, b] = t[..] {
            adjacent[a].push((b, g));
            adjacent[b].push((a, g));
        }
    }
    let mut in_tree: Vec<bool> = touches.iter().map(|t| t.len() <= 1).collect();
    let mut seen = vec![false; cliques.len()];
    let mut queue = VecDeque::new();
    for root in 0..cliques.len() {
        if seen[root] {
            continue;
        }
        seen[root] = true;
        queue.push_back(root);
        while let Some(b) = queue.pop_front() {
            for &(c, g) in &adjacent[b] {
                if !seen[c] {
                    seen[c] = true;
                    in_tree[g] = true;
                    queue.push_back(c);
                }
            }
        }
    }
    let loop_constraints = touches
        .iter()
        .zip(&in_tree)
        .filter(|(t, tr)| !t.is_empty() && !**tr)
        .count();
    Split {
        tree_row: (0..n).map(|j| in_tree[group[j]]).collect(),
        loop_constraints,
    }
}

impl TreePrecond {
    /// P's pattern from `gram`'s (A_JJ's) and its symbolic factor, for up
    /// to `max_rhs` right-hand sides a solve. Allocates.
    pub fn new(
        gram: &Gram,
        group: &[usize],
        max_rhs: usize,
    ) -> Result<Self, faer::sparse::FaerError> {
        let n = gram.n_j;
        let tree_row = split(gram, group).tree_row;
        let keep = |r: usize, c: usize| {
            (tree_row[r] && tree_row[c]) || (!tree_row[r] && !tree_row[c] && group[r] == group[c])
        };
        let (cp, ri) = (gram.pattern.col_ptr(), gram.pattern.row_idx());
        let (mut entries, mut rc, mut src) = (Vec::new(), Vec::new(), Vec::new());
        for c in 0..n {
            for (p, &r) in ri.iter().enumerate().take(cp[c + 1]).skip(cp[c]) {
                if keep(r, c) {
                    entries.push((r, c, rc.len()));
                    rc.push((r as u32, c as u32));
                    src.push(p);
                }
            }
        }
        let llt = Cholesky::analyze_grouped(n, 0, &entries, &[], &[], max_rhs)?;
        Ok(Self {
            llt,
            values: vec![0.0; rc.len()],
            rc,
            src,
            tree_row,
            factored: false,
        })
    }

    /// Its shape; `a_nnz` and `step_iterations` from the caller.
    pub fn stats(&self, a_nnz: usize, step_iterations: u64) -> TreeStats {
        TreeStats {
            a_nnz,
            p_nnz: self.rc.len(),
            factor_values: self.llt.len_values(),
            loop_rows: self.tree_row.iter().filter(|t| !**t).count(),
            step_iterations,
        }
    }

    /// Factors P from `gram`'s assembled A (rows the assembly switched off
    /// become unit rows), with the force solve's dynamic regularisation.
    ///
    /// # Real-time
    /// No allocation; one numeric factorisation of a fill-free pattern.
    pub fn factor(&mut self, gram: &Gram) -> Result<(), FactorError> {
        self.factored = false;
        let off = &gram.decoupled;
        for ((v, &(r, c)), &s) in self.values.iter_mut().zip(&self.rc).zip(&self.src) {
            let (r, c) = (r as usize, c as usize);
            *v = if off[r] || off[c] {
                if r == c { 1.0 } else { 0.0 }
            } else {
                gram.values[s]
            };
        }
        let reg = gram.regularization();
        (self.llt)
            .factor_decoupled(&self.values, reg, &[])
            .map_err(|_| FactorError)?;
        self.factored = true;
        Ok(())
    }

    /// x ← P⁻¹ x for `k` columns of n_J entries (column-major).
    ///
    /// # Real-time
    /// No allocation; one triangular-solve pair per column, O(nnz(P)).
    pub fn apply(&mut self, x: &mut [f64], k: usize) {
        self.llt.solve(x, k);
    }

    /// y = P x (one column; comparisons).
    #[cfg(test)]
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (&(r, c), &v) in self.rc.iter().zip(&self.values) {
            let (r, c) = (r as usize, c as usize);
            y[r] += v * x[c];
            if r != c {
                y[c] += v * x[r];
            }
        }
    }
}
