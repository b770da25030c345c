//! The loop rows' redundancy in joint coordinates, found once: a
//! left-looking Cholesky of W_LL = J_L H⁻¹ J_Lᵀ in row order that drops a
//! row whose pivot is below [`PIVOT_RATIO`] of its diagonal (the squared
//! sine of its angle to the rows kept before it, in the H⁻¹ metric), the
//! diagonal floored at [`ZERO_ROW`] of the largest — the joint-space
//! counterpart of `force::redundancy`'s ordered test.

use faer::Mat;
use nalgebra::{DMatrix, DVector};

use super::ReducedError;
use super::core::{JointSpace, PIVOT_RATIO, ZERO_ROW};
use crate::{Evaluation, Model};

impl JointSpace {
    /// Drops the dependent loop rows (module docs) and sizes the buffers.
    pub(super) fn mask(
        &mut self,
        model: &Model,
        q: &[f64],
        ev: &Evaluation,
    ) -> Result<(), ReducedError> {
        self.assemble(model, q, ev)?;
        self.factor_h()?;
        let w = self.gram();
        let nl = self.n_loop;
        let mut kept: Vec<usize> = Vec::new();
        let top = (0..nl).map(|a| w[(a, a)]).fold(0.0, f64::max);
        // Left-looking Cholesky of W_LL in row order with dropping.
        let mut l = DMatrix::<f64>::zeros(nl, nl);
        for a in 0..nl {
            let mut col = DVector::from_fn(nl, |i, _| w[(i, a)]);
            for &k in &kept {
                let f = l[(a, k)];
                for i in a..nl {
                    col[i] -= l[(i, k)] * f;
                }
            }
            if col[a] > PIVOT_RATIO * w[(a, a)].max(ZERO_ROW * top) {
                let d = col[a].sqrt();
                for i in a..nl {
                    l[(i, a)] = col[i] / d;
                }
                kept.push(a);
            }
        }
        let mut rows: Vec<usize> = kept.iter().map(|&k| self.rows[k]).collect();
        self.n_loop = rows.len();
        rows.extend(&self.tree.finger_rows);
        self.rows = rows;
        let (n, m) = (self.tree.dofs, self.rows.len());
        self.gt = Mat::zeros(n, m);
        self.w = Mat::zeros(m, m);
        self.rhs = Mat::zeros(m, 1);
        self.lambda_f = vec![0.0; self.tree.finger_rows.len()];
        Ok(())
    }
}
