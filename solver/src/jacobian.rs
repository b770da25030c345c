//! The sparse constraint Jacobian C_q with a pattern fixed per model.
//!
//! Storage is CSR (rows sorted by column) held as a faer
//! [`SparseRowMat`](faer::sparse::SparseRowMat), so the same values can be
//! handed to faer without a copy ([`Jacobian::as_faer`]). Each constraint owns a
//! dense `rows × width` row-major block of the values (every row of a
//! constraint touches the same columns: its bodies' 7 columns and its free
//! design variables), so evaluation rewrites values in place. A transposed
//! index (CSC order: per column, its rows and value positions) serves
//! column-wise consumers such as J Jᵀ assembly.
//!
//! The products C_q·v and C_qᵀ·v are hand-owned kernels over those dense blocks
//! (fixed-width column groups of 7, 4, 3 or 1), measured 1.2–1.7× faster than
//! faer's `sparse_dense_matmul` on the same storage (BENCHMARKS.md, solver).
//!
//! Explicit zeros are stored (e.g. the r columns of a perpendicular row), so the
//! pattern depends only on which bodies and design variables each constraint
//! touches, never on q.

use faer::prelude::Reborrow;
use faer::sparse::{SparseRowMat, SparseRowMatRef, SymbolicSparseRowMat};
use nalgebra::DMatrix;

use crate::Model;
use crate::constraint::block::SLOTS;

mod masked;

/// A vector passed to a product has the wrong length.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("vector of length {got} where {expected} was needed")]
pub struct ShapeError {
    /// Required length.
    pub expected: usize,
    /// Given length.
    pub got: usize,
}

fn check(expected: usize, got: usize) -> Result<(), ShapeError> {
    if expected == got {
        Ok(())
    } else {
        Err(ShapeError { expected, got })
    }
}

/// Where one constraint's dense block lives in the values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BlockDesc {
    /// First value of the block (row-major, `rows × width`).
    pub start: usize,
    /// First row of the constraint.
    pub row0: usize,
    /// Number of rows.
    pub rows: usize,
    /// Entries per row.
    pub width: usize,
    /// Position of each slot's first column within a row; `u16::MAX` if absent.
    pub pos: [u16; SLOTS],
    /// The contiguous column groups of a row, ascending: `(first column, width)`.
    pub groups: [(usize, usize); SLOTS],
    /// How many of `groups` are used.
    pub n_groups: usize,
}

impl BlockDesc {
    /// This block's rows of C_q · x into `out` (its `rows` entries), from
    /// the Jacobian's values `val`.
    #[inline(always)]
    pub(crate) fn mul_vec(&self, val: &[f64], x: &[f64], out: &mut [f64]) {
        let block = &val[self.start..self.start + self.rows * self.width];
        for (row, yr) in block.chunks_exact(self.width).zip(out) {
            let mut acc = 0.0;
            let mut col = 0;
            for &(c, w) in self.groups() {
                let (r, xs) = (&row[col..col + w], &x[c..c + w]);
                acc += match w {
                    7 => dot::<7>(r, xs),
                    4 => dot::<4>(r, xs),
                    3 => dot::<3>(r, xs),
                    _ => dot::<1>(r, xs),
                };
                col += w;
            }
            *yr = acc;
        }
    }

    #[inline]
    fn groups(&self) -> &[(usize, usize)] {
        &self.groups[..self.n_groups]
    }
}

/// C_q: `n_rows × n_coords`, fixed pattern, values rewritten by
/// [`Evaluation::evaluate`](crate::Evaluation::evaluate).
#[derive(Debug, Clone)]
pub struct Jacobian {
    mat: SparseRowMat<usize, f64>,
    col_ptr: Vec<usize>,
    col_rows: Vec<usize>,
    col_vals: Vec<usize>,
    pub(crate) blocks: Vec<BlockDesc>,
}

impl Jacobian {
    /// The pattern of `model`'s Jacobian with all values zero. Allocates.
    pub fn new(model: &Model) -> Self {
        let (nrows, ncols) = (model.n_rows(), model.n_coords());
        let mut row_ptr = Vec::with_capacity(nrows + 1);
        let mut col_idx = Vec::new();
        let mut blocks = Vec::with_capacity(model.geometry.len());
        row_ptr.push(0);
        for (k, g) in model.geometry.iter().enumerate() {
            let mut groups: Vec<(usize, usize, usize)> = model
                .constraint_groups(k)
                .iter()
                .enumerate()
                .filter_map(|(slot, grp)| grp.map(|(c, w)| (c, w, slot)))
                .collect();
            groups.sort_unstable();
            let mut pos = [u16::MAX; SLOTS];
            let mut cols = [(0, 0); SLOTS];
            let mut width = 0;
            for (k, &(c, w, slot)) in groups.iter().enumerate() {
                pos[slot] = width as u16;
                cols[k] = (c, w);
                width += w;
            }
            blocks.push(BlockDesc {
                start: col_idx.len(),
                row0: row_ptr.len() - 1,
                rows: g.rows(),
                width,
                pos,
                groups: cols,
                n_groups: groups.len(),
            });
            for _ in 0..g.rows() {
                for &(c, w, _) in &groups {
                    col_idx.extend(c..c + w);
                }
                row_ptr.push(col_idx.len());
            }
        }
        let nnz = col_idx.len();
        let mut col_ptr = vec![0usize; ncols + 1];
        for &c in &col_idx {
            col_ptr[c + 1] += 1;
        }
        for c in 0..ncols {
            col_ptr[c + 1] += col_ptr[c];
        }
        let mut next = col_ptr.clone();
        let (mut col_rows, mut col_vals) = (vec![0; nnz], vec![0; nnz]);
        for r in 0..nrows {
            for k in row_ptr[r]..row_ptr[r + 1] {
                let slot = &mut next[col_idx[k]];
                col_rows[*slot] = r;
                col_vals[*slot] = k;
                *slot += 1;
            }
        }
        let symbolic = SymbolicSparseRowMat::new_checked(nrows, ncols, row_ptr, None, col_idx);
        let mat = SparseRowMat::new(symbolic, vec![0.0; nnz]);
        Self {
            mat,
            col_ptr,
            col_rows,
            col_vals,
            blocks,
        }
    }

    /// Number of rows (constraint rows).
    pub fn nrows(&self) -> usize {
        self.mat.nrows()
    }

    /// Number of columns (coordinates).
    pub fn ncols(&self) -> usize {
        self.mat.ncols()
    }

    /// Number of stored entries (explicit zeros included).
    pub fn nnz(&self) -> usize {
        self.mat.val().len()
    }

    /// CSR row pointers (`nrows + 1` entries).
    pub fn row_ptr(&self) -> &[usize] {
        self.mat.symbolic().row_ptr()
    }

    /// CSR column indices, sorted within each row.
    pub fn col_idx(&self) -> &[usize] {
        self.mat.symbolic().col_idx()
    }

    /// CSR values, aligned with [`col_idx`](Self::col_idx).
    pub fn values(&self) -> &[f64] {
        self.mat.val()
    }

    pub(crate) fn blocks_and_values_mut(&mut self) -> (&[BlockDesc], &mut [f64]) {
        (&self.blocks, self.mat.val_mut())
    }

    /// Transposed index: column `c`'s entries are `col_ptr()[c]..col_ptr()[c + 1]`
    /// of [`col_rows`](Self::col_rows) and [`col_value_index`](Self::col_value_index).
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Transposed index: the row of each entry, ascending within a column.
    pub fn col_rows(&self) -> &[usize] {
        &self.col_rows
    }

    /// Transposed index: the position of each entry in [`values`](Self::values).
    pub fn col_value_index(&self) -> &[usize] {
        &self.col_vals
    }

    /// A zero-copy faer view (CSR). `as_faer().transpose()` is Jᵀ in CSC form.
    pub fn as_faer(&self) -> SparseRowMatRef<'_, usize, f64> {
        self.mat.rb()
    }

    /// A dense copy (tests, debugging). Allocates.
    pub fn to_dense(&self) -> DMatrix<f64> {
        let mut d = DMatrix::zeros(self.nrows(), self.ncols());
        let (ptr, idx, val) = (self.row_ptr(), self.col_idx(), self.values());
        for r in 0..self.nrows() {
            for k in ptr[r]..ptr[r + 1] {
                d[(r, idx[k])] = val[k];
            }
        }
        d
    }

    /// y = C_q · x (x: one entry per coordinate, y: one per row).
    ///
    /// Runs over the constraints' dense blocks: each row is a few fixed-width
    /// dot products with contiguous slices of x (no per-entry column index).
    ///
    /// # Real-time
    /// No allocation, no locks; O(nnz).
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) -> Result<(), ShapeError> {
        check(self.ncols(), x.len())?;
        check(self.nrows(), y.len())?;
        let val = self.values();
        for b in &self.blocks {
            b.mul_vec(val, x, &mut y[b.row0..b.row0 + b.rows]);
        }
        Ok(())
    }

    /// y = C_qᵀ · x (x: one entry per row, y: one per coordinate).
    ///
    /// # Real-time
    /// No allocation, no locks; O(nnz).
    pub fn mul_t_vec(&self, x: &[f64], y: &mut [f64]) -> Result<(), ShapeError> {
        check(self.ncols(), y.len())?;
        y.fill(0.0);
        self.mul_t_vec_add(1.0, x, y)
    }

    /// y += α · C_qᵀ · x, e.g. Δq = −f_qᵀ − C_qᵀ(λ + K C) in one pass.
    ///
    /// Runs over the constraints' dense blocks: each y entry a block touches is
    /// read and written once per block, after a short sum over the block's rows.
    ///
    /// # Real-time
    /// No allocation, no locks; O(nnz).
    pub fn mul_t_vec_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) -> Result<(), ShapeError> {
        check(self.nrows(), x.len())?;
        check(self.ncols(), y.len())?;
        let val = self.values();
        for b in &self.blocks {
            let block = &val[b.start..b.start + b.rows * b.width];
            let xs = &x[b.row0..b.row0 + b.rows];
            let mut col = 0;
            for &(c, w) in b.groups() {
                let ys = &mut y[c..c + w];
                match w {
                    7 => add_columns::<7>(alpha, block, b.width, col, xs, ys),
                    4 => add_columns::<4>(alpha, block, b.width, col, xs, ys),
                    3 => add_columns::<3>(alpha, block, b.width, col, xs, ys),
                    _ => add_columns::<1>(alpha, block, b.width, col, xs, ys),
                }
                col += w;
            }
        }
        Ok(())
    }
}

/// Σ a_k b_k over W-wide chunks, summed in four lanes (a short dependency
/// chain; the fixed width lets the compiler unroll and vectorise).
#[inline(always)]
fn dot<const W: usize>(a: &[f64], b: &[f64]) -> f64 {
    let mut lanes = [0.0; 4];
    for (a, b) in a.chunks_exact(W).zip(b.chunks_exact(W)) {
        if let (Some(a), Some(b)) = (a.first_chunk::<W>(), b.first_chunk::<W>()) {
            for k in 0..W {
                lanes[k % 4] += a[k] * b[k];
            }
        }
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// y[..W·k] += α Σ_r x_r · block[r][col..col + W] for each W-wide chunk of the
/// group (a fixed width lets the compiler keep W lane sums in registers).
#[inline(always)]
fn add_columns<const W: usize>(
    alpha: f64,
    block: &[f64],
    width: usize,
    col: usize,
    xs: &[f64],
    ys: &mut [f64],
) {
    for (k, y) in ys.chunks_exact_mut(W).enumerate() {
        let mut s = [0.0; W];
        for (xr, row) in xs.iter().zip(block.chunks_exact(width)) {
            if let Some(seg) = row[col + k * W..].first_chunk::<W>() {
                for (s, v) in s.iter_mut().zip(seg) {
                    *s += xr * v;
                }
            }
        }
        for (y, s) in y.iter_mut().zip(s) {
            *y += alpha * s;
        }
    }
}
