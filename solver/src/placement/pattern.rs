//! Symbolic phase, part 1: the pattern of the normal matrix S = A_s W⁻¹ A_sᵀ
//! (+ diagonal) from the fixed pattern of C_q, computed once per structure.
//!
//! Each lower entry (r, s) of S is a sum over the sparse columns c that rows r
//! and s share: Σ_c J_rc J_sc / w_c. A constraint's row stores each body's 7
//! columns contiguously (see [`crate::Jacobian`]), so the shared columns come
//! in *runs* of consecutive value positions; the numeric phase
//! ([`NormalPattern::fill`]) is one short dot product per run, written straight
//! into the permuted matrix faer factors (no per-iteration permutation copy).
//!
//! Columns with more than `dense_column_threshold` entries are *dense*
//! (Choi & Cremer §5.1): they are left out of S and handled as a low-rank
//! correction (see `lowrank.rs`). Rows with no entry left in a sparse column
//! get an F column (Eq. 14) so S stays nonsingular.

use faer::sparse::SymbolicSparseColMat;

use crate::Jacobian;

/// One run of shared consecutive columns: Σ_k v[a + k]·v[b + k]·winv[c + k].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Run {
    pub a: u32,
    pub b: u32,
    pub c: u32,
    pub w: u32,
}

/// The unpermuted lower pattern of S and the raw terms, before ordering.
pub(crate) struct Unpermuted {
    /// Lower triangle of S, column-major (column s, rows r ≥ s), diagonal included.
    pub lower: SymbolicSparseColMat<usize>,
    /// (entry index in `lower`, value position of row r, of row s, column).
    terms: Vec<(usize, u32, u32, u32)>,
    /// Index in `lower` of each diagonal entry.
    diag: Vec<usize>,
    /// Dense columns, ascending.
    pub dense_cols: Vec<usize>,
    /// Rows with no entry in a sparse column.
    pub f_rows: Vec<usize>,
}

/// The normal matrix pattern in faer's permuted order, with its fill plan.
#[derive(Debug, Clone)]
pub(crate) struct NormalPattern {
    /// Per permuted stored entry, its runs: `runs[run_ptr[k]..run_ptr[k + 1]]`.
    runs: Vec<Run>,
    run_ptr: Vec<u32>,
    /// Permuted stored position of each original row's diagonal.
    pub diag_slot: Vec<usize>,
}

/// Which columns of `jac` are dense.
fn dense_columns(jac: &Jacobian, threshold: usize) -> Vec<bool> {
    let ptr = jac.col_ptr();
    (0..jac.ncols())
        .map(|c| ptr[c + 1] - ptr[c] > threshold)
        .collect()
}

/// Builds the lower pattern of S and its terms from the pattern of `jac`.
pub(crate) fn analyse(jac: &Jacobian, threshold: usize) -> Unpermuted {
    let m = jac.nrows();
    let dense = dense_columns(jac, threshold);
    let (ptr, rows, pos) = (jac.col_ptr(), jac.col_rows(), jac.col_value_index());
    // (column s, row r, pos r, pos s, column c): sorted, it gives the pattern.
    let mut raw: Vec<(u32, u32, u32, u32, u32)> = Vec::new();
    for c in (0..jac.ncols()).filter(|&c| !dense[c]) {
        let range = ptr[c]..ptr[c + 1];
        for a in range.clone() {
            for b in range.start..=a {
                let (r, s) = (rows[a], rows[b]);
                raw.push((s as u32, r as u32, pos[a] as u32, pos[b] as u32, c as u32));
            }
        }
    }
    for i in 0..m as u32 {
        raw.push((i, i, u32::MAX, u32::MAX, u32::MAX));
    }
    raw.sort_unstable();
    let mut col_ptr = vec![0usize; m + 1];
    let mut row_idx = Vec::new();
    let mut terms = Vec::with_capacity(raw.len());
    let mut diag = vec![0usize; m];
    let mut last = None;
    for &(s, r, pa, pb, c) in &raw {
        if last != Some((s, r)) {
            last = Some((s, r));
            if r == s {
                diag[r as usize] = row_idx.len();
            }
            row_idx.push(r as usize);
            col_ptr[s as usize + 1] += 1;
        }
        if c != u32::MAX {
            terms.push((row_idx.len() - 1, pa, pb, c));
        }
    }
    for s in 0..m {
        col_ptr[s + 1] += col_ptr[s];
    }
    let lower = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
    let row_ptr = jac.row_ptr();
    let col_idx = jac.col_idx();
    let f_rows = (0..m)
        .filter(|&r| (row_ptr[r]..row_ptr[r + 1]).all(|k| dense[col_idx[k]]))
        .collect();
    let dense_cols = (0..jac.ncols()).filter(|&c| dense[c]).collect();
    Unpermuted {
        lower,
        terms,
        diag,
        dense_cols,
        f_rows,
    }
}

impl Unpermuted {
    /// Orders everything for faer's kernel: `perm_inv[old] = new`; `upper`
    /// stores each entry in the upper triangle (simplicial kernel) instead of
    /// the lower one (supernodal). Returns the permuted pattern and fill plan.
    pub fn permute(
        &self,
        perm_inv: &[usize],
        upper: bool,
    ) -> (SymbolicSparseColMat<usize>, NormalPattern) {
        let m = self.lower.nrows();
        let (cp, ri) = (self.lower.col_ptr(), self.lower.row_idx());
        // (new column, new row, old entry index)
        let mut entries = Vec::with_capacity(ri.len());
        for s in 0..m {
            for (k, &r) in ri.iter().enumerate().take(cp[s + 1]).skip(cp[s]) {
                let (a, b) = (perm_inv[r], perm_inv[s]);
                let (row, col) = match (upper, a <= b) {
                    (true, true) | (false, false) => (a, b),
                    _ => (b, a),
                };
                entries.push((col, row, k));
            }
        }
        entries.sort_unstable();
        let mut col_ptr = vec![0usize; m + 1];
        let mut row_idx = Vec::with_capacity(entries.len());
        let mut slot_of = vec![0usize; entries.len()];
        for (slot, &(col, row, k)) in entries.iter().enumerate() {
            col_ptr[col + 1] += 1;
            row_idx.push(row);
            slot_of[k] = slot;
        }
        for s in 0..m {
            col_ptr[s + 1] += col_ptr[s];
        }
        let sym = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let mut keyed: Vec<(usize, Run)> = self
            .terms
            .iter()
            .map(|&(k, a, b, c)| (slot_of[k], Run { a, b, c, w: 1 }))
            .collect();
        keyed.sort_unstable_by_key(|&(slot, run)| (slot, run.c));
        let mut runs: Vec<Run> = Vec::new();
        let mut run_ptr = vec![0u32; entries.len() + 1];
        let mut prev_slot = usize::MAX;
        for (slot, t) in keyed {
            if let Some(last) = runs.last_mut().filter(|_| slot == prev_slot)
                && last.a + last.w == t.a
                && last.b + last.w == t.b
                && last.c + last.w == t.c
            {
                last.w += 1;
                continue;
            }
            runs.push(t);
            run_ptr[slot + 1] += 1;
            prev_slot = slot;
        }
        for s in 0..entries.len() {
            run_ptr[s + 1] += run_ptr[s];
        }
        let diag_slot = self.diag.iter().map(|&k| slot_of[k]).collect();
        let plan = NormalPattern {
            runs,
            run_ptr,
            diag_slot,
        };
        (sym, plan)
    }
}

impl NormalPattern {
    /// out[k] = Σ over the runs of permuted entry k of v[a..]·v[b..]·winv[c..];
    /// `winv = None` is W = I. Diagonal extras are added by the caller.
    ///
    /// No allocation; O(terms).
    pub fn fill(&self, v: &[f64], winv: Option<&[f64]>, out: &mut [f64]) {
        for (k, o) in out.iter_mut().enumerate() {
            let runs = &self.runs[self.run_ptr[k] as usize..self.run_ptr[k + 1] as usize];
            let mut acc = 0.0;
            for r in runs {
                let (a, b, w) = (r.a as usize, r.b as usize, r.w as usize);
                let (x, y) = (&v[a..a + w], &v[b..b + w]);
                acc += match winv {
                    None => x.iter().zip(y).map(|(x, y)| x * y).sum::<f64>(),
                    Some(wi) => {
                        let wi = &wi[r.c as usize..r.c as usize + w];
                        x.iter().zip(y).zip(wi).map(|((x, y), z)| x * y * z).sum()
                    }
                };
            }
            *o = acc;
        }
    }
}
