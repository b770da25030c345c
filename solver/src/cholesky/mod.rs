//! A supernodal sparse Cholesky factorisation A = L Lᵀ for a pattern fixed
//! once, refactored with new values every tick.
//!
//! The fast loop's Eq. 7 matrix A = D C_q M̃⁻¹ C_qᵀ D keeps its pattern for
//! the life of a program, so everything that depends only on the pattern is
//! done once by [`Cholesky::analyze`] (off the real-time thread):
//!
//! ```text
//!  lower pattern of A ──► fill-reducing order (AMD, faer) ──► elimination tree, postorder
//!        ──► pattern of L ──► supernodes: runs of columns whose rows below the diagonal
//!            are the same (a joint's 3–5 rows always are; a body's clique of rows often)
//!        ──► per supernode a dense row-major block (its columns × its rows), and for
//!            every supernode that updates another, where each updated row lands
//! ```
//!
//! [`Cholesky::factor`] then scatters A's values into the blocks through a
//! precomputed map (the permutation costs nothing per call) and runs a
//! left-looking supernodal factorisation: dense row dot products over
//! contiguous memory with precomputed destinations, no pattern search. faer's
//! simplicial kernel, which the fast loop used before, searches each row's
//! pattern (`ereach`) and copies the permuted matrix on every call.
//! [`Cholesky::solve`] takes several right-hand sides at once, interleaved
//! so that the innermost loops run across them.
//!
//! Pivots follow faer's dynamic regularisation of an LLᵀ ([`Regularization`]):
//! a pivot at or below ε is replaced by δ; a pivot that is then still not
//! positive (or not finite) fails the factorisation.
//!
//! # Real-time
//! `factor` and `solve` allocate nothing, lock nothing, make no syscall, and
//! run in time fixed by the pattern: Σ over supernode updates of their dense
//! products, nnz(L) for each right-hand side.

mod dense;
mod dissection;
mod kernels;
mod symbolic;
mod triangular;

pub(crate) use dense::DENSE_MAX;
use dense::Dense;
use symbolic::Symbolic;

/// Dynamic regularisation of the pivots (faer's LLᵀ rule).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Regularization {
    /// A pivot ≤ this is replaced by `delta`.
    pub epsilon: f64,
    /// The replacement pivot.
    pub delta: f64,
}

/// A pivot was not positive (or not finite) after regularisation; `index` is
/// its column in the factor's (permuted) order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct NotPositive {
    pub index: usize,
}

/// The shape of a symbolic factor: what a numeric factorisation and a solve
/// cost (diagnostics and benchmarks).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct FactorShape {
    /// The fill-reducing order chosen.
    pub ordering: Ordering,
    /// That order is a superset pattern's ([`Superset`]).
    pub induced: bool,
    /// Order of the matrix (tail included).
    pub n: usize,
    /// Rows and columns of the unfactored tail.
    pub tail: usize,
    /// Supernodes of the leading block.
    pub supernodes: usize,
    /// Widest supernode of the leading block.
    pub widest: usize,
    /// Stored values of L (blocks, upper halves of diagonal blocks included).
    pub values: usize,
    /// Multiply-adds of one numeric factorisation (updates and dense
    /// factors, the tail's Schur update included).
    pub factor_flops: usize,
    /// Multiply-adds of one forward plus backward substitution.
    pub solve_flops: usize,
}

impl FactorShape {
    /// What [`Cholesky::analyze_with_tail`] minimises over the orderings:
    /// one factorisation and [`SOLVES_PER_FACTOR`] solves, multiply-adds.
    pub fn cost(&self) -> usize {
        self.factor_flops + SOLVES_PER_FACTOR * self.solve_flops
    }
}

/// Solves per numeric factorisation in a typical tick (three projected
/// steps and the force solve), for choosing the ordering.
pub(crate) const SOLVES_PER_FACTOR: usize = 4;

/// A pattern's superset: the same matrix with the entries `extra` (row,
/// column, any value index) that are zero in exact arithmetic kept, and its
/// `cliques`. [`Cholesky::analyze_small_dense`] tries its orders too and
/// keeps the cheapest factor, so leaving structural zeros out of a pattern
/// never makes its factor dearer than the superset's orders give.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Superset<'a> {
    pub extra: &'a [(usize, usize, usize)],
    pub cliques: &'a [Vec<usize>],
}

/// A fill-reducing order of the leading block.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) enum Ordering {
    /// Approximate minimum degree (faer).
    #[default]
    Amd,
    /// Nested dissection (`dissection`), AMD on its small pieces.
    Dissection,
}

/// The factor of one pattern, its numeric values and the solve workspace.
#[derive(Debug, Clone)]
pub(crate) struct Cholesky {
    sym: Symbolic,
    /// The supernodes' dense blocks, in supernode order.
    values: Vec<f64>,
    /// Solve workspace: n × `max_rhs`, interleaved (row i holds every
    /// right-hand side's entry i), in the factor's order.
    work: Vec<f64>,
    max_rhs: usize,
    /// 1 / L_jj of the supernode being factored.
    inv: Vec<f64>,
    /// Pivots replaced by the regularisation in the last factorisation.
    pub regularized: usize,
    /// Run the AVX2 + FMA kernels (`kernels::simd_available`).
    simd: bool,
    /// Per column of the factor's order: its supernode.
    col_supernode: Vec<u32>,
    /// Per supernode: its factor in `values` is diagonal (all its columns
    /// were decoupled in the last factorisation, see
    /// [`factor_decoupled`](Self::factor_decoupled)).
    diagonal: Vec<bool>,
    /// `Some`: the dense path (`dense`) factors and solves, in the same
    /// order and with the same tail; `values` then holds its layout.
    dense: Option<Dense>,
}

/// Each column's supernode (the factor's order) and a cleared per-supernode
/// flag vector. Allocates.
fn supernode_maps(sym: &Symbolic) -> (Vec<u32>, Vec<bool>) {
    let mut col = vec![0u32; sym.n];
    for (s, sn) in sym.supernodes.iter().enumerate() {
        for c in sn.c0..sn.c0 + sn.w {
            col[c as usize] = s as u32;
        }
    }
    (col, vec![false; sym.supernodes.len()])
}

impl Cholesky {
    /// Analyses the pattern of the n × n symmetric matrix whose lower
    /// triangle (diagonal included, every diagonal entry present) is given in
    /// CSC form, for solves of up to `max_rhs` right-hand sides at once.
    /// Allocates. (Tests and the timing comparison; the fast loop analyses
    /// with a tail.)
    #[cfg(test)]
    pub fn analyze(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        max_rhs: usize,
    ) -> Result<Self, faer::sparse::FaerError> {
        let entries: Vec<(usize, usize, usize)> = (0..n)
            .flat_map(|c| (col_ptr[c]..col_ptr[c + 1]).map(move |p| (p, c)))
            .map(|(p, c)| (row_idx[p], c, p))
            .collect();
        Self::analyze_with_tail(n, 0, &entries, &[], max_rhs)
    }

    /// Analyses the n × n symmetric matrix given by the (row, column, value
    /// index) of its lower triangle's entries (row ≥ column, every diagonal
    /// entry present) whose last `tail` rows and columns T are ordered last
    /// and never factored: [`factor`](Self::factor) then leaves the Schur
    /// complement A_TT − L_TL L_TLᵀ in [`tail_block`](Self::tail_block), and
    /// [`solve_with_tail`](Self::solve_with_tail) solves the whole system
    /// through a caller's solve of that block. Allocates. (Tests; the force
    /// solve analyses with [`analyze_grouped`](Self::analyze_grouped).)
    #[cfg(test)]
    pub fn analyze_with_tail(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
        max_rhs: usize,
    ) -> Result<Self, faer::sparse::FaerError> {
        Self::analyze_grouped(n, tail, entries, cliques, &[], max_rhs)
    }

    /// `analyze_with_tail` (the whole matrix given as its lower triangle's
    /// entries, the last `tail` rows never factored) keeping columns of
    /// different `groups` keys (one per leading column, original order) in
    /// different supernodes: rows that are switched off together then form
    /// supernodes [`factor_decoupled`](Self::factor_decoupled) skips whole.
    /// Allocates.
    pub fn analyze_grouped(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
        groups: &[u32],
        max_rhs: usize,
    ) -> Result<Self, faer::sparse::FaerError> {
        Self::analyze_superset(n, tail, entries, cliques, groups, max_rhs, None)
    }

    /// [`analyze_grouped`](Self::analyze_grouped), trying the orders of
    /// `superset` too. Allocates.
    fn analyze_superset(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
        groups: &[u32],
        max_rhs: usize,
        superset: Option<Superset>,
    ) -> Result<Self, faer::sparse::FaerError> {
        let sym = Symbolic::analyze(n, tail, entries, cliques, groups, superset)?;
        // The solve kernels are specialised up to 8 right-hand sides.
        let max_rhs = max_rhs.clamp(1, 8);
        let widest = sym
            .supernodes
            .iter()
            .map(|s| s.w as usize)
            .max()
            .unwrap_or(0);
        let (col_supernode, diagonal) = supernode_maps(&sym);
        Ok(Self {
            inv: vec![0.0; widest],
            values: vec![0.0; sym.len_values()],
            work: vec![0.0; n * max_rhs],
            max_rhs,
            regularized: 0,
            simd: kernels::simd_available(),
            col_supernode,
            diagonal,
            dense: None,
            sym,
        })
    }

    /// [`analyze_grouped`](Self::analyze_grouped), factored and solved on
    /// the dense path (`dense`) when the whole order n is at most
    /// `dense_max` ([`DENSE_MAX`] in the fast loop, 0: never): same order,
    /// same tail, same pivot rule, the same factor up to each entry's
    /// summation order; the orders of `superset` are candidates too.
    /// Allocates.
    #[allow(clippy::too_many_arguments)]
    pub fn analyze_small_dense(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
        groups: &[u32],
        max_rhs: usize,
        dense_max: usize,
        superset: Option<Superset>,
    ) -> Result<Self, faer::sparse::FaerError> {
        let mut llt = Self::analyze_superset(n, tail, entries, cliques, groups, max_rhs, superset)?;
        if n <= dense_max {
            let d = Dense::new(n, tail, &llt.sym.iperm, entries);
            llt.values = vec![0.0; d.len_values()];
            llt.dense = Some(d);
        }
        Ok(llt)
    }

    /// Whether this factor takes the dense path.
    #[cfg(test)]
    pub fn is_dense(&self) -> bool {
        self.dense.is_some()
    }

    /// Stored values of L (the blocks, including the unused upper halves of
    /// their diagonal parts).
    pub fn len_values(&self) -> usize {
        self.values.len()
    }

    /// The shapes of the factor of this pattern under AMD and under the
    /// nested dissection (comparisons; see `analyze_with_tail`).
    #[cfg(test)]
    pub fn both_shapes(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
    ) -> (FactorShape, FactorShape) {
        Symbolic::both_shapes(n, tail, entries, cliques)
    }

    /// [`analyze_with_tail`](Self::analyze_with_tail) with the nested
    /// dissection forced, leaves of `leaf_rows` (tests).
    #[cfg(test)]
    pub fn dissected(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
        leaf_rows: usize,
    ) -> Self {
        let sym = Symbolic::dissected(n, tail, entries, cliques, leaf_rows);
        let widest = sym
            .supernodes
            .iter()
            .map(|s| s.w as usize)
            .max()
            .unwrap_or(0);
        let (col_supernode, diagonal) = supernode_maps(&sym);
        Self {
            inv: vec![0.0; widest],
            values: vec![0.0; sym.len_values()],
            work: vec![0.0; n],
            max_rhs: 1,
            regularized: 0,
            simd: kernels::simd_available(),
            col_supernode,
            diagonal,
            dense: None,
            sym,
        }
    }

    /// Switches the AVX2 + FMA kernels off (or back on where the CPU has
    /// them), to compare the two.
    #[cfg(test)]
    pub fn set_simd(&mut self, on: bool) {
        self.simd = on && kernels::simd_available();
    }

    /// Swaps the factor's values with `values` when the lengths agree
    /// (returns whether it did).
    ///
    /// # Real-time
    /// No allocation.
    pub fn swap_values(&mut self, values: &mut Vec<f64>) -> bool {
        if values.len() != self.values.len() {
            return false;
        }
        std::mem::swap(&mut self.values, values);
        // Values factored elsewhere: nothing known of their shape.
        self.diagonal.fill(false);
        true
    }

    /// The factor's [`FactorShape`].
    #[cfg(test)]
    pub fn shape(&self) -> FactorShape {
        self.sym.shape()
    }

    /// Numeric factorisation of the matrix whose values are `a` (indexed by
    /// the value indices given to `analyze`: the CSC order with
    /// [`analyze`](Self::analyze)). With a tail, its block is updated but not
    /// factored: it ends as the Schur complement.
    ///
    /// # Real-time
    /// No allocation; time fixed by the pattern.
    #[cfg(test)]
    pub fn factor(&mut self, a: &[f64], reg: Regularization) -> Result<(), NotPositive> {
        self.diagonal.fill(false);
        self.numeric(a, reg)
    }

    /// [`factor`](Self::factor) of a matrix whose leading-block columns with
    /// `decoupled[i]` (original order, one per leading column; a slice of
    /// another length is ignored) have every entry off the diagonal zero,
    /// in their row and their column: rows switched off, as the force
    /// solve's inactive contact rows are. Such a column's L is √A_ii alone,
    /// so a supernode of them only takes its square roots, no supernode
    /// updates from it or into it, and the solves only scale its entries.
    /// The result is the same factor: the work skipped multiplies zeros.
    ///
    /// # Real-time
    /// No allocation; O(n) to mark the supernodes, then the factorisation
    /// without the skipped work.
    pub fn factor_decoupled(
        &mut self,
        a: &[f64],
        reg: Regularization,
        decoupled: &[bool],
    ) -> Result<(), NotPositive> {
        let lead = self.sym.n - self.sym.tail;
        self.diagonal.fill(false);
        if decoupled.len() == lead {
            self.diagonal[..self.sym.lead_supernodes].fill(true);
            for (i, &d) in decoupled.iter().enumerate() {
                if !d {
                    let s = self.col_supernode[self.sym.iperm[i] as usize];
                    self.diagonal[s as usize] = false;
                }
            }
        }
        self.numeric(a, reg)
    }

    fn numeric(&mut self, a: &[f64], reg: Regularization) -> Result<(), NotPositive> {
        if let Some(d) = &self.dense {
            self.diagonal.fill(false);
            self.regularized = d.factor(&mut self.values, a, reg, self.simd)?;
            return Ok(());
        }
        let done = kernels::numeric(
            &self.sym,
            &mut self.values,
            &mut self.inv,
            a,
            reg,
            self.simd,
            &self.diagonal,
        );
        if done.is_err() {
            self.diagonal.fill(false);
        }
        self.regularized = done?;
        Ok(())
    }

    /// Supernodes whose factor is diagonal after the last factorisation
    /// (tests).
    #[cfg(test)]
    pub fn diagonal_supernodes(&self) -> usize {
        self.diagonal.iter().filter(|&&d| d).count()
    }

    /// The tail's t × t block after [`factor`](Self::factor): the Schur
    /// complement A_TT − A_TL A_LL⁻¹ A_LT, row-major, lower triangle (the
    /// upper half is zero).
    pub fn tail_block(&self) -> &[f64] {
        if let Some(d) = &self.dense {
            return d.tail_block(&self.values);
        }
        match self.sym.supernodes.get(self.sym.lead_supernodes) {
            Some(sn) => {
                let t = sn.w as usize;
                &self.values[sn.val as usize..sn.val as usize + t * t]
            }
            None => &[],
        }
    }

    /// Solves the whole system A x = b in place (`x`: n entries, original
    /// order, the tail last) with the last factorisation: a forward
    /// substitution over the leading block, which leaves s = b_T − L_TL w in
    /// the tail's entries; `tail_solve(S, s)` replaces s by the tail's
    /// solution x_T (S: [`tail_block`](Self::tail_block)); a backward
    /// substitution gives the leading block's x = L⁻ᵀ (w − L_TLᵀ x_T).
    /// Whatever `tail_solve` returns is returned. Without a tail this is a
    /// plain solve and `tail_solve` gets two empty slices.
    ///
    /// # Real-time
    /// No allocation; 2 nnz(L) multiply-adds plus `tail_solve`.
    pub fn solve_with_tail<R>(
        &mut self,
        x: &mut [f64],
        tail_solve: impl FnOnce(&[f64], &mut [f64]) -> R,
    ) -> R {
        let (n, lead) = (self.sym.n, self.sym.n - self.sym.tail);
        let work = &mut self.work[..n];
        for (i, &xi) in x.iter().enumerate() {
            work[self.sym.iperm[i] as usize] = xi;
        }
        if let Some(d) = &self.dense {
            d.forward(&self.values, work, self.simd);
            let out = tail_solve(d.tail_block(&self.values), &mut work[lead..]);
            d.backward(&self.values, work, self.simd);
            for (i, xi) in x.iter_mut().enumerate() {
                *xi = work[self.sym.iperm[i] as usize];
            }
            return out;
        }
        triangular::forward(&self.sym, &self.values, work, 1, self.simd, &self.diagonal);
        let t = self.sym.tail;
        let block = match self.sym.supernodes.get(self.sym.lead_supernodes) {
            Some(sn) => &self.values[sn.val as usize..sn.val as usize + t * t],
            None => &[][..],
        };
        let out = tail_solve(block, &mut work[lead..]);
        triangular::backward(&self.sym, &self.values, work, 1, self.simd, &self.diagonal);
        for (i, xi) in x.iter_mut().enumerate() {
            *xi = work[self.sym.iperm[i] as usize];
        }
        out
    }

    /// Solves A_LL X = B in place for `k` right-hand sides of the leading
    /// block (`x`: n_L × k, column-major, in the original order; n_L = n
    /// without a tail), with the last factorisation. `k` above the `max_rhs`
    /// of `analyze` (at most 8) is done in several passes.
    ///
    /// # Real-time
    /// No allocation; 2 nnz(L) multiply-adds per right-hand side.
    pub fn solve(&mut self, x: &mut [f64], k: usize) {
        let n = self.sym.n - self.sym.tail;
        let full = self.sym.n;
        if let Some(d) = &self.dense {
            let work = &mut self.work[..full];
            for col in x[..k * n].chunks_exact_mut(n) {
                for (i, &xi) in col.iter().enumerate() {
                    work[self.sym.iperm[i] as usize] = xi;
                }
                d.forward(&self.values, work, self.simd);
                // A leading-block solve: the tail takes no part.
                work[n..].fill(0.0);
                d.backward(&self.values, work, self.simd);
                for (i, xi) in col.iter_mut().enumerate() {
                    *xi = work[self.sym.iperm[i] as usize];
                }
            }
            return;
        }
        let mut first = 0;
        while first < k {
            let kk = (k - first).min(self.max_rhs);
            let cols = &mut x[first * n..(first + kk) * n];
            let work = &mut self.work[..full * kk];
            for (t, col) in cols.chunks_exact(n).enumerate() {
                for (i, &xi) in col.iter().enumerate() {
                    work[self.sym.iperm[i] as usize * kk + t] = xi;
                }
            }
            triangular::forward(&self.sym, &self.values, work, kk, self.simd, &self.diagonal);
            // A leading-block solve: the tail takes no part.
            work[n * kk..].fill(0.0);
            triangular::backward(&self.sym, &self.values, work, kk, self.simd, &self.diagonal);
            for (t, col) in cols.chunks_exact_mut(n).enumerate() {
                for (i, xi) in col.iter_mut().enumerate() {
                    *xi = work[self.sym.iperm[i] as usize * kk + t];
                }
            }
            first += kk;
        }
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_decoupled;
#[cfg(test)]
mod tests_dense;
#[cfg(test)]
mod tests_kernels;
