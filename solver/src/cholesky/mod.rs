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

mod dissection;
mod symbolic;

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
    /// through a caller's solve of that block. Allocates.
    pub fn analyze_with_tail(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
        max_rhs: usize,
    ) -> Result<Self, faer::sparse::FaerError> {
        let sym = Symbolic::analyze(n, tail, entries, cliques)?;
        // The solve kernels are specialised up to 8 right-hand sides.
        let max_rhs = max_rhs.clamp(1, 8);
        let widest = sym
            .supernodes
            .iter()
            .map(|s| s.w as usize)
            .max()
            .unwrap_or(0);
        Ok(Self {
            inv: vec![0.0; widest],
            values: vec![0.0; sym.len_values()],
            work: vec![0.0; n * max_rhs],
            max_rhs,
            regularized: 0,
            sym,
        })
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
        Self {
            inv: vec![0.0; widest],
            values: vec![0.0; sym.len_values()],
            work: vec![0.0; n],
            max_rhs: 1,
            regularized: 0,
            sym,
        }
    }

    /// The factor's [`FactorShape`].
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
    pub fn factor(&mut self, a: &[f64], reg: Regularization) -> Result<(), NotPositive> {
        let sym = &self.sym;
        let v = &mut self.values;
        v.fill(0.0);
        for &(src, dst) in &sym.load {
            v[dst as usize] += a[src as usize];
        }
        self.regularized = 0;
        for s in 0..sym.supernodes.len() {
            let sn = &sym.supernodes[s];
            let (before, rest) = v.split_at_mut(sn.val as usize);
            let w = sn.w as usize;
            let block = &mut rest[..(w + sn.nrows as usize) * w];
            for u in &sym.updates[sn.updates.0 as usize..sn.updates.1 as usize] {
                let d = &sym.supernodes[u.src as usize];
                let wd = d.w as usize;
                let (a0, m) = (u.a as usize, u.m as usize);
                let slab = &before[d.val as usize + (wd + a0) * wd..][..m * wd];
                let cols = &sym.rows[d.rows as usize + a0..][..(u.b - u.a) as usize];
                let rel = &sym.rel[u.rel as usize..][..m];
                update(block, w, sn.c0 as usize, slab, wd, cols, rel);
            }
            if s < sym.lead_supernodes {
                self.regularized += dense_factor(block, w, sn.c0 as usize, reg, &mut self.inv)?;
            }
        }
        Ok(())
    }

    /// The tail's t × t block after [`factor`](Self::factor): the Schur
    /// complement A_TT − A_TL A_LL⁻¹ A_LT, row-major, lower triangle (the
    /// upper half is zero).
    pub fn tail_block(&self) -> &[f64] {
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
        self.sym.forward(&self.values, work, 1);
        let t = self.sym.tail;
        let block = match self.sym.supernodes.get(self.sym.lead_supernodes) {
            Some(sn) => &self.values[sn.val as usize..sn.val as usize + t * t],
            None => &[][..],
        };
        let out = tail_solve(block, &mut work[lead..]);
        self.sym.backward(&self.values, work, 1);
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
            self.sym.forward(&self.values, work, kk);
            // A leading-block solve: the tail takes no part.
            work[n * kk..].fill(0.0);
            self.sym.backward(&self.values, work, kk);
            for (t, col) in cols.chunks_exact_mut(n).enumerate() {
                for (i, xi) in col.iter_mut().enumerate() {
                    *xi = work[self.sym.iperm[i] as usize * kk + t];
                }
            }
            first += kk;
        }
    }
}

/// Σ aᵢ bᵢ over the shorter of the two.
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ta, tb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ta.iter().zip(tb) {
        s += x * y;
    }
    s
}

/// The four dot products of rows a0, a1 with rows b0, b1 (all of length
/// `b0.len()`): [a0·b0, a0·b1, a1·b0, a1·b1], two lanes each.
#[inline(always)]
fn dot2x2(a0: &[f64], a1: &[f64], b0: &[f64], b1: &[f64]) -> [f64; 4] {
    let n = b0.len();
    let (a0, a1, b1) = (&a0[..n], &a1[..n], &b1[..n]);
    let mut s = [[0.0f64; 2]; 4];
    let pairs = n / 2;
    for p in 0..pairs {
        let k = 2 * p;
        for l in 0..2 {
            s[0][l] += a0[k + l] * b0[k + l];
            s[1][l] += a0[k + l] * b1[k + l];
            s[2][l] += a1[k + l] * b0[k + l];
            s[3][l] += a1[k + l] * b1[k + l];
        }
    }
    let mut out = [
        s[0][0] + s[0][1],
        s[1][0] + s[1][1],
        s[2][0] + s[2][1],
        s[3][0] + s[3][1],
    ];
    if n % 2 == 1 {
        let k = n - 1;
        out[0] += a0[k] * b0[k];
        out[1] += a0[k] * b1[k];
        out[2] += a1[k] * b0[k];
        out[3] += a1[k] * b1[k];
    }
    out
}

/// Subtracts from the target `block` (width `w`, first column `c0`) the
/// update of one earlier supernode: `slab` holds that supernode's rows from
/// its first row in the target's columns on (row-major, width `wd`); the
/// first `cols.len()` of them fall in the target's columns `cols`, and row
/// `ri` lands at the target's local row `rel[ri]`. Lower triangle only,
/// two rows by two columns at a time.
#[inline]
fn update(
    block: &mut [f64],
    w: usize,
    c0: usize,
    slab: &[f64],
    wd: usize,
    cols: &[u32],
    rel: &[u32],
) {
    // A source supernode's width is its rows' length: with it known at
    // compile time the dot products unroll (widths 1–16 cover the built-in
    // mechanisms' supernodes but the sphere toys' largest few).
    macro_rules! fixed {
        ($($n:literal)*) => {
            match wd {
                $($n => update_fixed::<$n>(block, w, c0, slab, cols, rel),)*
                _ => update_any(block, w, c0, slab, wd, cols, rel),
            }
        };
    }
    fixed!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// [`update`] for a source of width `W`.
#[inline(always)]
fn update_fixed<const W: usize>(
    block: &mut [f64],
    w: usize,
    c0: usize,
    slab: &[f64],
    cols: &[u32],
    rel: &[u32],
) {
    let rows: &[[f64; W]] = as_rows(slab);
    let (nb, m) = (cols.len(), rel.len());
    let dot = |a: &[f64; W], b: &[f64; W]| {
        let mut s = 0.0;
        for k in 0..W {
            s += a[k] * b[k];
        }
        s
    };
    for ci in 0..nb {
        let col = cols[ci] as usize - c0;
        let b = &rows[ci];
        let mut ri = ci;
        while ri + 2 <= m {
            let (r0, r1) = (&rows[ri], &rows[ri + 1]);
            let (mut s0, mut s1) = (0.0, 0.0);
            for k in 0..W {
                s0 += r0[k] * b[k];
                s1 += r1[k] * b[k];
            }
            block[rel[ri] as usize * w + col] -= s0;
            block[rel[ri + 1] as usize * w + col] -= s1;
            ri += 2;
        }
        if ri < m {
            block[rel[ri] as usize * w + col] -= dot(&rows[ri], b);
        }
    }
}

/// `slab` (a whole number of rows of `W`) as rows.
#[inline(always)]
fn as_rows<const W: usize>(slab: &[f64]) -> &[[f64; W]] {
    let (rows, rest) = slab.as_chunks::<W>();
    debug_assert!(rest.is_empty());
    rows
}

/// [`update`] for any width.
#[inline]
fn update_any(
    block: &mut [f64],
    w: usize,
    c0: usize,
    slab: &[f64],
    wd: usize,
    cols: &[u32],
    rel: &[u32],
) {
    let (nb, m) = (cols.len(), rel.len());
    let row = |i: usize| &slab[i * wd..i * wd + wd];
    let mut ci = 0;
    while ci < nb {
        let two = ci + 1 < nb;
        let col0 = cols[ci] as usize - c0;
        let col1 = if two {
            cols[ci + 1] as usize - c0
        } else {
            col0
        };
        let (b0, b1) = (row(ci), if two { row(ci + 1) } else { row(ci) });
        let mut ri = ci;
        while ri + 1 < m {
            let t = dot2x2(row(ri), row(ri + 1), b0, b1);
            let (d0, d1) = (rel[ri] as usize * w, rel[ri + 1] as usize * w);
            block[d0 + col0] -= t[0];
            if two && ri > ci {
                block[d0 + col1] -= t[1];
            }
            block[d1 + col0] -= t[2];
            if two {
                block[d1 + col1] -= t[3];
            }
            ri += 2;
        }
        if ri < m {
            let r = row(ri);
            let d0 = rel[ri] as usize * w;
            block[d0 + col0] -= dot(r, b0);
            if two && ri > ci {
                block[d0 + col1] -= dot(r, b1);
            }
        }
        ci += 2;
    }
}

/// Factors one supernode's block in place (its updates already applied):
/// the w × w diagonal part row by row, then the rows below it two at a time
/// (independent rows, so their dependency chains interleave). Returns the
/// number of regularised pivots. `c0`: the block's first column (for the
/// error's index); `inv`: scratch of at least w.
#[inline]
fn dense_factor(
    block: &mut [f64],
    w: usize,
    c0: usize,
    reg: Regularization,
    inv: &mut [f64],
) -> Result<usize, NotPositive> {
    let mut replaced = 0;
    let inv = &mut inv[..w];
    for i in 0..w {
        let (done, row) = block.split_at_mut(i * w);
        let row = &mut row[..w];
        for j in 0..i {
            let rj = &done[j * w..j * w + w];
            row[j] = (row[j] - dot(&row[..j], &rj[..j])) * inv[j];
        }
        let mut d = row[i] - dot(&row[..i], &row[..i]);
        if d <= reg.epsilon {
            d = reg.delta;
            replaced += 1;
        }
        if !(d > 0.0 && d.is_finite()) {
            return Err(NotPositive { index: c0 + i });
        }
        row[i] = d.sqrt();
        inv[i] = 1.0 / row[i];
    }
    let (diag, below) = block.split_at_mut(w * w);
    macro_rules! fixed {
        ($($n:literal)*) => {
            match w {
                $($n => below_fixed::<$n>(diag, below, inv),)*
                _ => below_any(diag, below, w, inv),
            }
        };
    }
    fixed!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
    Ok(replaced)
}

/// The rows below a factored diagonal block: each row x ← x L⁻ᵀ, two rows
/// at a time, width `W` known at compile time.
#[inline(always)]
fn below_fixed<const W: usize>(diag: &[f64], below: &mut [f64], inv: &[f64]) {
    let l: &[[f64; W]] = as_rows(diag);
    let (rows, _) = below.as_chunks_mut::<W>();
    let mut pairs = rows.chunks_exact_mut(2);
    for pair in &mut pairs {
        let (ra, rb) = pair.split_at_mut(1);
        let (ra, rb) = (&mut ra[0], &mut rb[0]);
        for j in 0..W {
            let (mut sa, mut sb) = (ra[j], rb[j]);
            for k in 0..j {
                sa -= ra[k] * l[j][k];
                sb -= rb[k] * l[j][k];
            }
            ra[j] = sa * inv[j];
            rb[j] = sb * inv[j];
        }
    }
    for r in pairs.into_remainder() {
        for j in 0..W {
            let mut s = r[j];
            for k in 0..j {
                s -= r[k] * l[j][k];
            }
            r[j] = s * inv[j];
        }
    }
}

/// [`below_fixed`] for any width.
#[inline]
fn below_any(diag: &[f64], below: &mut [f64], w: usize, inv: &[f64]) {
    let mut pairs = below.chunks_exact_mut(2 * w);
    for pair in &mut pairs {
        let (ra, rb) = pair.split_at_mut(w);
        for j in 0..w {
            let rj = &diag[j * w..j * w + j];
            let t = dot2x2(&ra[..j], &rb[..j], rj, rj);
            ra[j] = (ra[j] - t[0]) * inv[j];
            rb[j] = (rb[j] - t[2]) * inv[j];
        }
    }
    let rest = pairs.into_remainder();
    if !rest.is_empty() {
        for j in 0..w {
            let rj = &diag[j * w..j * w + j];
            rest[j] = (rest[j] - dot(&rest[..j], rj)) * inv[j];
        }
    }
}

#[cfg(test)]
mod tests;
