//! The alternative to the sparse Cholesky for Eq. 7's joint block: warm-started,
//! Jacobi-preconditioned conjugate gradients on the assembled A_JJ, capped at a
//! fixed number of iterations per right-hand side so a tick's time is bounded.
//! Each tick starts from the previous tick's solutions (q moves little between
//! ticks). BENCHMARKS.md compares it with the Cholesky on all three
//! mechanisms; the Cholesky won and is the default.

use super::gram::Gram;

/// PCG buffers and the previous tick's solutions.
#[derive(Debug, Clone)]
pub(crate) struct Cg {
    /// n × k previous solutions (column-major), the warm start.
    prev: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    inv_diag: Vec<f64>,
    max_iterations: u32,
    /// Iterations used by the last solve, summed over right-hand sides.
    pub iterations: u32,
}

/// Relative residual at which an iteration stops early.
const TOLERANCE: f64 = 1e-12;

impl Cg {
    /// Buffers for n unknowns and k right-hand sides. Allocates.
    pub fn new(n: usize, k: usize, max_iterations: u32) -> Self {
        Self {
            prev: vec![0.0; n * k],
            r: vec![0.0; n],
            z: vec![0.0; n],
            p: vec![0.0; n],
            ap: vec![0.0; n],
            inv_diag: vec![0.0; n],
            max_iterations,
            iterations: 0,
        }
    }

    /// Solves A_JJ X = B in place (`rhs`: n × k column-major, B in, X out).
    ///
    /// # Real-time
    /// No allocation; at most `max_iterations` symmetric products per column,
    /// each O(nnz(A_JJ)).
    pub fn solve(&mut self, gram: &Gram, rhs: &mut [f64]) {
        let n = gram.n_j;
        let vals = &gram.values[..gram.nnz()];
        for (d, &k) in self.inv_diag.iter_mut().zip(&gram.diag) {
            *d = 1.0 / vals[k];
        }
        self.iterations = 0;
        for (col, prev) in rhs.chunks_exact_mut(n).zip(self.prev.chunks_exact_mut(n)) {
            // x = prev; r = b − A x.
            sym_mul(gram, prev, &mut self.ap);
            let bnorm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
            for (i, b) in col.iter().enumerate() {
                self.r[i] = b - self.ap[i];
                self.z[i] = self.r[i] * self.inv_diag[i];
            }
            col.copy_from_slice(prev);
            self.p.copy_from_slice(&self.z);
            let mut rz: f64 = self.r.iter().zip(&self.z).map(|(a, b)| a * b).sum();
            for _ in 0..self.max_iterations {
                let rnorm = self.r.iter().map(|v| v * v).sum::<f64>().sqrt();
                if rnorm <= TOLERANCE * bnorm || rz == 0.0 {
                    break;
                }
                self.iterations += 1;
                sym_mul(gram, &self.p, &mut self.ap);
                let pap: f64 = self.p.iter().zip(&self.ap).map(|(a, b)| a * b).sum();
                if pap.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                    break;
                }
                let alpha = rz / pap;
                for (i, x) in col.iter_mut().enumerate() {
                    *x += alpha * self.p[i];
                    self.r[i] -= alpha * self.ap[i];
                    self.z[i] = self.r[i] * self.inv_diag[i];
                }
                let rz_new: f64 = self.r.iter().zip(&self.z).map(|(a, b)| a * b).sum();
                let beta = rz_new / rz;
                rz = rz_new;
                for i in 0..n {
                    self.p[i] = self.z[i] + beta * self.p[i];
                }
            }
            prev.copy_from_slice(col);
        }
    }
}

/// y = A x for the symmetric A_JJ stored as its lower triangle (CSC).
pub(super) fn sym_mul(gram: &Gram, x: &[f64], y: &mut [f64]) {
    let (cp, ri) = (gram.pattern.col_ptr(), gram.pattern.row_idx());
    let vals = &gram.values;
    y.fill(0.0);
    for j in 0..x.len() {
        let xj = x[j];
        let mut acc = 0.0;
        for k in cp[j]..cp[j + 1] {
            let (i, v) = (ri[k], vals[k]);
            y[i] += v * xj;
            if i != j {
                acc += v * x[i];
            }
        }
        y[j] += acc;
    }
}
