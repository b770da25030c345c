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
//! Explicit zeros are stored (e.g. the r columns of a perpendicular row), so the
//! pattern depends only on which bodies and design variables each constraint
//! touches, never on q.

use faer::prelude::Reborrow;
use faer::sparse::{SparseRowMat, SparseRowMatRef, SymbolicSparseRowMat};
use nalgebra::DMatrix;

use crate::Model;
use crate::constraint::block::SLOTS;

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
    pub start: usize,
    pub width: usize,
    /// Position of each slot's first column within a row; `u16::MAX` if absent.
    pub pos: [u16; SLOTS],
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
        for g in &model.geometry {
            let mut groups: Vec<(usize, usize, usize)> = g
                .groups()
                .iter()
                .enumerate()
                .filter_map(|(slot, grp)| grp.map(|(c, w)| (c, w, slot)))
                .collect();
            groups.sort_unstable();
            let mut pos = [u16::MAX; SLOTS];
            let mut width = 0;
            for &(_, w, slot) in &groups {
                pos[slot] = width as u16;
                width += w;
            }
            blocks.push(BlockDesc {
                start: col_idx.len(),
                width,
                pos,
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
    /// # Real-time
    /// No allocation, no locks; O(nnz).
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) -> Result<(), ShapeError> {
        check(self.ncols(), x.len())?;
        check(self.nrows(), y.len())?;
        let (ptr, idx, val) = (self.row_ptr(), self.col_idx(), self.values());
        for (r, out) in y.iter_mut().enumerate() {
            let range = ptr[r]..ptr[r + 1];
            *out = idx[range.clone()]
                .iter()
                .zip(&val[range])
                .map(|(&c, v)| v * x[c])
                .sum();
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
    /// # Real-time
    /// No allocation, no locks; O(nnz).
    pub fn mul_t_vec_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) -> Result<(), ShapeError> {
        check(self.nrows(), x.len())?;
        check(self.ncols(), y.len())?;
        let (ptr, idx, val) = (self.row_ptr(), self.col_idx(), self.values());
        for (r, &xr) in x.iter().enumerate() {
            let a = alpha * xr;
            let range = ptr[r]..ptr[r + 1];
            for (&c, v) in idx[range.clone()].iter().zip(&val[range]) {
                y[c] += a * v;
            }
        }
        Ok(())
    }
}
