//! Products with C_q that leave out constraints known to contribute
//! nothing (the projected step on a scene where few bodies move).

use super::{Jacobian, ShapeError, check};

impl Jacobian {
    /// y = C_q · x over the constraints `k` with `skip[k]` false; the rows
    /// of the skipped ones get 0, which is their product when x is zero on
    /// every column they touch (the caller's guarantee).
    ///
    /// # Real-time
    /// No allocation; O(nnz of the constraints kept + rows).
    pub(crate) fn mul_vec_where(
        &self,
        x: &[f64],
        y: &mut [f64],
        skip: &[bool],
    ) -> Result<(), ShapeError> {
        check(self.ncols(), x.len())?;
        check(self.nrows(), y.len())?;
        let val = self.values();
        for (k, b) in self.blocks.iter().enumerate() {
            let out = &mut y[b.row0..b.row0 + b.rows];
            if skip.get(k).copied().unwrap_or(false) {
                out.fill(0.0);
                continue;
            }
            b.mul_vec(val, x, out);
        }
        Ok(())
    }

    /// y = C_qᵀ · x, skipping the constraints whose entries of x are all
    /// zero (they add nothing): the same y as
    /// [`mul_t_vec`](Self::mul_t_vec) up to the sign of a zero.
    ///
    /// # Real-time
    /// No allocation; O(nnz of the constraints with a nonzero x + rows).
    pub(crate) fn mul_t_vec_sparse(&self, x: &[f64], y: &mut [f64]) -> Result<(), ShapeError> {
        check(self.nrows(), x.len())?;
        check(self.ncols(), y.len())?;
        y.fill(0.0);
        let val = self.values();
        for b in &self.blocks {
            let xs = &x[b.row0..b.row0 + b.rows];
            if xs.iter().all(|&v| v == 0.0) {
                continue;
            }
            let block = &val[b.start..b.start + b.rows * b.width];
            let mut col = 0;
            for &(c, w) in b.groups() {
                let ys = &mut y[c..c + w];
                match w {
                    7 => super::add_columns::<7>(1.0, block, b.width, col, xs, ys),
                    4 => super::add_columns::<4>(1.0, block, b.width, col, xs, ys),
                    3 => super::add_columns::<3>(1.0, block, b.width, col, xs, ys),
                    _ => super::add_columns::<1>(1.0, block, b.width, col, xs, ys),
                }
                col += w;
            }
        }
        Ok(())
    }
}
