//! Dense columns by the modified Schur complement (Choi & Cremer §5.1, after
//! Andersen 1996), written as its equivalent Sherman–Morrison–Woodbury solve.
//!
//! With the dense columns A_d of C_q split off, the normal matrix is
//!
//! ```text
//! N = S + U C Uᵀ,   S = A_s W_s⁻¹ A_sᵀ + D + μI + F Fᵀ,
//! U = [A_d W_d^{-1/2} | F],   C = diag(I, −I)
//! ```
//!
//! where F has one nonzero per column, on each row that has no entry left in a
//! sparse column (Eq. 14: F Fᵀ only modifies the diagonal, so S keeps its
//! sparsity and stays nonsingular). Eliminating γ, ρ of Eq. 13 gives
//! N⁻¹ r = S⁻¹ r − Z K⁻¹ Uᵀ S⁻¹ r with Z = S⁻¹ U and the small dense
//! K = C + Uᵀ Z (k × k, k = dense columns + F columns). K's F block is
//! diagonal (see [`LowRank`]), so it is eliminated first and only the
//! kd × kd Schur complement is LU-factored with partial pivoting (K is
//! symmetric but indefinite). Cost per iteration: one sparse factorisation
//! of S, kd + 1 sparse solves, O(m kd + |F| kd²) + O(kd³).

use super::factor::{NormalFactor, NotPositive};
use crate::Jacobian;

/// Buffers and the split of one structure's dense columns.
///
/// The F columns are never stored as columns: each has one nonzero f_r on
/// its row r, where S is diagonal and decoupled (S_rr = s_r), so Z's F column
/// is (f_r / s_r) e_r and K's F block is diagonal, κ_r = −(s_r − f_r²)/s_r.
/// K is solved by eliminating that diagonal block: the kd × kd Schur
/// complement K̃ = K_dd − Σ_r w_r w_rᵀ / κ_r (w_r[j] = f_r z_j[r]) is
/// LU-factored, and the F unknowns follow row by row. Memory and time are
/// O(m kd + |F| kd²) + O(kd³) instead of O(m k) and O(k³) with
/// k = kd + |F|: rows that touch only dense columns (many joints on one hub)
/// cost linear, not cubic, time.
#[derive(Debug, Clone)]
pub(crate) struct LowRank {
    m: usize,
    /// Dense columns, and for each its (row, value position) entries.
    cols: Vec<usize>,
    entry_ptr: Vec<usize>,
    entries: Vec<(usize, usize)>,
    f_rows: Vec<usize>,
    /// U_d then Z_d = S⁻¹U_d, column-major m × kd.
    u: Vec<f64>,
    z: Vec<f64>,
    /// Per F row: f_r, s_r and κ_r.
    f: Vec<f64>,
    s: Vec<f64>,
    kappa: Vec<f64>,
    /// K̃ (kd × kd, LU in place) and its pivots.
    kmat: Vec<f64>,
    piv: Vec<usize>,
    /// Right-hand side and solution: dense part (kd), F part (|F|).
    t: Vec<f64>,
    tf: Vec<f64>,
}

impl LowRank {
    /// Sizes everything for `dense_cols` and `f_rows` of `jac`'s pattern.
    pub fn new(jac: &Jacobian, dense_cols: &[usize], f_rows: &[usize]) -> Self {
        let (ptr, rows, pos) = (jac.col_ptr(), jac.col_rows(), jac.col_value_index());
        let mut entry_ptr = vec![0];
        let mut entries = Vec::new();
        for &c in dense_cols {
            entries.extend((ptr[c]..ptr[c + 1]).map(|k| (rows[k], pos[k])));
            entry_ptr.push(entries.len());
        }
        let m = jac.nrows();
        let (kd, nf) = (dense_cols.len(), f_rows.len());
        Self {
            m,
            cols: dense_cols.to_vec(),
            entry_ptr,
            entries,
            f_rows: f_rows.to_vec(),
            u: vec![0.0; m * kd],
            z: vec![0.0; m * kd],
            f: vec![0.0; nf],
            s: vec![0.0; nf],
            kappa: vec![0.0; nf],
            kmat: vec![0.0; kd * kd],
            piv: vec![0; kd],
            t: vec![0.0; kd],
            tf: vec![0.0; nf],
        }
    }

    /// Rank k of the correction (0: no dense columns): dense plus F columns.
    pub fn rank(&self) -> usize {
        self.cols.len() + self.f_rows.len()
    }

    /// Number of dense columns: the widest block of right-hand sides the
    /// factor is given.
    pub fn dense_columns(&self) -> usize {
        self.cols.len()
    }

    /// Writes U from the Jacobian values; for each F row, adds f² (the row's
    /// dense-column diagonal + 1) to `diag`, the extra diagonal of S.
    pub fn load(&mut self, vals: &[f64], winv: Option<&[f64]>, diag: &mut [f64]) {
        let (m, kd) = (self.m, self.cols.len());
        self.u.fill(0.0);
        for (j, &c) in self.cols.iter().enumerate() {
            let s = winv.map_or(1.0, |w| w[c].sqrt());
            for &(row, p) in &self.entries[self.entry_ptr[j]..self.entry_ptr[j + 1]] {
                self.u[j * m + row] = vals[p] * s;
            }
        }
        for (i, &row) in self.f_rows.iter().enumerate() {
            let dd: f64 = (0..kd).map(|j| self.u[j * m + row].powi(2)).sum();
            let f2 = dd + 1.0;
            self.f[i] = f2.sqrt();
            diag[row] += f2;
        }
    }

    /// After S is factored: Z_d = S⁻¹U_d, the Schur complement K̃ of K's
    /// diagonal F block, LU of K̃. No allocation.
    ///
    /// An F row has no sparse entry, so S is diagonal and decoupled there:
    /// S_rr = `s_diag[r]` exactly. Its κ is computed in closed form,
    /// −(S_rr − f²)/S_rr, not as −1 + f²/S_rr, whose cancellation would lose
    /// every digit when μ → 0.
    pub fn prepare(
        &mut self,
        factor: &mut NormalFactor,
        s_diag: &[f64],
    ) -> Result<(), NotPositive> {
        let (m, kd) = (self.m, self.cols.len());
        if self.rank() == 0 {
            return Ok(());
        }
        self.z.copy_from_slice(&self.u);
        if kd > 0 {
            factor.solve_many(&mut self.z, m, kd);
        }
        for j in 0..kd {
            for i in j..kd {
                let ui = &self.u[i * m..(i + 1) * m];
                let zj = &self.z[j * m..(j + 1) * m];
                let v = ui.iter().zip(zj).map(|(a, b)| a * b).sum::<f64>() + f64::from(i == j);
                self.kmat[i + j * kd] = v;
                self.kmat[j + i * kd] = v;
            }
        }
        for (i, &r) in self.f_rows.iter().enumerate() {
            let (f, s) = (self.f[i], s_diag[r]);
            let kappa = -(s - f * f) / s;
            if !(kappa != 0.0 && kappa.is_finite()) {
                return Err(NotPositive);
            }
            self.s[i] = s;
            self.kappa[i] = kappa;
            // K̃ −= w wᵀ / κ with w[j] = f z_j[r].
            for j in 0..kd {
                let wj = f * self.z[j * m + r] / kappa;
                if wj == 0.0 {
                    continue;
                }
                for l in 0..kd {
                    self.kmat[l + j * kd] -= f * self.z[l * m + r] * wj;
                }
            }
        }
        lu_in_place(&mut self.kmat, kd, &mut self.piv)
    }

    /// x ← N⁻¹ x = S⁻¹x − Z K⁻¹ Uᵀ S⁻¹x. No allocation.
    pub fn solve(&mut self, factor: &mut NormalFactor, x: &mut [f64]) {
        factor.solve(x);
        let (m, kd) = (self.m, self.cols.len());
        if self.rank() == 0 {
            return;
        }
        // Right-hand side Uᵀ S⁻¹x: dense part t, F part tf.
        for (j, t) in self.t.iter_mut().enumerate() {
            *t = self.u[j * m..(j + 1) * m]
                .iter()
                .zip(x.iter())
                .map(|(a, b)| a * b)
                .sum();
        }
        for (i, &r) in self.f_rows.iter().enumerate() {
            self.tf[i] = self.f[i] * x[r];
        }
        // Dense unknowns: K̃ a = t − Σ_r w_r tf_r / κ_r.
        for (i, &r) in self.f_rows.iter().enumerate() {
            let c = self.f[i] * self.tf[i] / self.kappa[i];
            for (j, t) in self.t.iter_mut().enumerate() {
                *t -= self.z[j * m + r] * c;
            }
        }
        lu_solve(&self.kmat, kd, &self.piv, &mut self.t);
        // F unknowns: b_r = (tf_r − w_r · a) / κ_r.
        for (i, &r) in self.f_rows.iter().enumerate() {
            let wa: f64 = (0..kd)
                .map(|j| self.f[i] * self.z[j * m + r] * self.t[j])
                .sum();
            self.tf[i] = (self.tf[i] - wa) / self.kappa[i];
        }
        // x −= Z_d a + Z_F b, Z_F's column for row r being (f_r / s_r) e_r.
        for (j, t) in self.t.iter().enumerate() {
            for (xi, zi) in x.iter_mut().zip(&self.z[j * m..(j + 1) * m]) {
                *xi -= zi * t;
            }
        }
        for (i, &r) in self.f_rows.iter().enumerate() {
            x[r] -= self.f[i] / self.s[i] * self.tf[i];
        }
    }
}

/// LU with partial pivoting of the column-major k × k `a`, in place.
fn lu_in_place(a: &mut [f64], k: usize, piv: &mut [usize]) -> Result<(), NotPositive> {
    for col in 0..k {
        let p = (col..k)
            .max_by(|&i, &j| a[i + col * k].abs().total_cmp(&a[j + col * k].abs()))
            .unwrap_or(col);
        piv[col] = p;
        // Partial pivoting is backward stable; small pivots are the problem's
        // conditioning (refined by the caller), only an exact zero fails.
        if !(a[p + col * k].abs() > 0.0 && a[p + col * k].is_finite()) {
            return Err(NotPositive);
        }
        if p != col {
            for j in 0..k {
                a.swap(col + j * k, p + j * k);
            }
        }
        let d = a[col + col * k];
        for i in col + 1..k {
            a[i + col * k] /= d;
        }
        for j in col + 1..k {
            let f = a[col + j * k];
            for i in col + 1..k {
                a[i + j * k] -= a[i + col * k] * f;
            }
        }
    }
    Ok(())
}

/// Solves with the factors of [`lu_in_place`], in place.
fn lu_solve(a: &[f64], k: usize, piv: &[usize], b: &mut [f64]) {
    // The factorisation swapped whole rows, so apply every swap first.
    for (col, &p) in piv.iter().enumerate().take(k) {
        b.swap(col, p);
    }
    for col in 0..k {
        for i in col + 1..k {
            b[i] -= a[i + col * k] * b[col];
        }
    }
    for col in (0..k).rev() {
        b[col] /= a[col + col * k];
        for i in 0..col {
            b[i] -= a[i + col * k] * b[col];
        }
    }
}
