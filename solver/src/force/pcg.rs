//! The matvec-only tick's Eq. 7 solve (`ForceSolver::Matvec`): conjugate
//! gradients on the assembled A_JJ for all right-hand sides [r_J A_JF] in
//! lockstep, preconditioned by a Cholesky factor of A_JJ that the slow
//! thread refreshed at a recent configuration, warm-started from the
//! previous solve's solutions.
//!
//! With the factor of A_JJ at q_s, the preconditioned matrix is
//! (L_s L_sᵀ)⁻¹ A_JJ(q) = I + O(|q − q_s|): its eigenvalues cluster at 1
//! and CG gains several decades per iteration while the factor is recent
//! (measured: BENCHMARKS.md), whatever the matrix's own condition. The
//! right-hand sides step together so that each iteration applies the
//! preconditioner once to all of them (one pass over L for up to 8
//! interleaved columns) and each product A p is one pass over A per column.
//!
//! # Real-time
//! No allocation; per iteration k products with A_JJ (O(nnz A) each) and
//! one k-column solve with the factor (O(nnz L)); at most `max_iterations`.

use super::cg::sym_mul;
use super::gram::Gram;
use crate::cholesky::Cholesky;

/// Relative residual at which a column of the force solve stops.
const TOLERANCE: f64 = 1e-12;

/// Relative residual at which a projected step's solve stops: an inexact
/// Gauss–Newton step that leaves 1e-6 of the step's residual is corrected
/// by the next step (each contracts the violation by about that factor),
/// where solving to 1e-12 from 0 cost the lattice 3× the iterations.
const STEP_TOLERANCE: f64 = 1e-6;

/// Buffers of the block solve and the previous solutions.
#[derive(Debug, Clone)]
pub(crate) struct Pcg {
    /// Columns.
    k: usize,
    /// n × k previous solutions (column-major), the warm start.
    prev: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    rz: Vec<f64>,
    bnorm: Vec<f64>,
    done: Vec<bool>,
    max_iterations: u32,
    /// Iterations of the last solve (all columns step together).
    pub iterations: u32,
    /// Largest relative residual ‖b − A x‖ / ‖b‖ over the columns after
    /// the last solve.
    pub residual: f64,
    /// Solves that stopped at the cap with a column above the tolerance.
    pub unconverged: u64,
}

impl Pcg {
    /// Buffers for n unknowns and k right-hand sides. Allocates.
    pub fn new(n: usize, k: usize, max_iterations: u32) -> Self {
        Self {
            k,
            prev: vec![0.0; n * k],
            r: vec![0.0; n * k],
            z: vec![0.0; n * k],
            p: vec![0.0; n * k],
            ap: vec![0.0; n * k],
            rz: vec![0.0; k],
            bnorm: vec![0.0; k],
            done: vec![false; k],
            max_iterations,
            iterations: 0,
            residual: 0.0,
            unconverged: 0,
        }
    }

    /// Solves A_JJ X = B in place (`rhs`: n × k column-major, B in, X out),
    /// A_JJ from `gram`'s values, M⁻¹ by `llt`'s leading block.
    ///
    /// # Real-time
    /// No allocation; see the module docs.
    pub fn solve(&mut self, gram: &Gram, llt: &mut Cholesky, rhs: &mut [f64]) {
        self.solve_with(gram, rhs, |z, k| llt.solve(z, k));
    }

    /// [`solve`](Self::solve) with the preconditioner `precondition`, which
    /// replaces its argument's k columns v by M⁻¹ v (the tree
    /// preconditioner, `precond::tree`).
    ///
    /// # Real-time
    /// No allocation; see the module docs.
    pub fn solve_with(
        &mut self,
        gram: &Gram,
        rhs: &mut [f64],
        mut precondition: impl FnMut(&mut [f64], usize),
    ) {
        let (n, k) = (gram.n_j, self.k);
        self.iterations = 0;
        // A failed solve (a non-finite A) must not poison the warm start.
        if !self.prev.iter().all(|v| v.is_finite()) {
            self.prev.fill(0.0);
        }
        // x = prev; r = b − A x.
        for c in 0..k {
            let col = c * n..(c + 1) * n;
            sym_mul(gram, &self.prev[col.clone()], &mut self.ap[col.clone()]);
            let b = &rhs[col.clone()];
            self.bnorm[c] = b.iter().map(|v| v * v).sum::<f64>().sqrt();
            for ((r, &bi), &ai) in self.r[col.clone()]
                .iter_mut()
                .zip(b)
                .zip(&self.ap[col.clone()])
            {
                *r = bi - ai;
            }
        }
        rhs.copy_from_slice(&self.prev);
        self.z.copy_from_slice(&self.r);
        precondition(&mut self.z, k);
        self.p.copy_from_slice(&self.z);
        for c in 0..k {
            let col = c * n..(c + 1) * n;
            self.rz[c] = dot(&self.r[col.clone()], &self.z[col]);
        }
        self.done.fill(false);
        loop {
            let mut all = true;
            let mut worst: f64 = 0.0;
            for c in 0..k {
                let rn = norm(&self.r[c * n..(c + 1) * n]);
                let rel = if self.bnorm[c] > 0.0 {
                    rn / self.bnorm[c]
                } else {
                    rn
                };
                worst = worst.max(rel);
                if rn <= TOLERANCE * self.bnorm[c] || self.rz[c].is_nan() || self.rz[c] <= 0.0 {
                    self.done[c] = true;
                }
                all &= self.done[c];
            }
            self.residual = worst;
            if all {
                break;
            }
            if self.iterations >= self.max_iterations {
                self.unconverged += 1;
                break;
            }
            self.iterations += 1;
            for c in 0..k {
                let col = c * n..(c + 1) * n;
                if self.done[c] {
                    // A finished column keeps its x; its residual and search
                    // direction stop moving.
                    self.r[col].fill(0.0);
                    continue;
                }
                sym_mul(gram, &self.p[col.clone()], &mut self.ap[col.clone()]);
                let pap = dot(&self.p[col.clone()], &self.ap[col.clone()]);
                if pap.is_nan() || pap <= 0.0 {
                    self.done[c] = true;
                    self.r[col].fill(0.0);
                    continue;
                }
                let alpha = self.rz[c] / pap;
                let x = &mut rhs[col.clone()];
                for (i, xi) in x.iter_mut().enumerate() {
                    *xi += alpha * self.p[c * n + i];
                    self.r[c * n + i] -= alpha * self.ap[c * n + i];
                }
            }
            self.z.copy_from_slice(&self.r);
            precondition(&mut self.z, k);
            for c in 0..k {
                if self.done[c] {
                    continue;
                }
                let col = c * n..(c + 1) * n;
                let rz_new = dot(&self.r[col.clone()], &self.z[col.clone()]);
                let beta = rz_new / self.rz[c];
                self.rz[c] = rz_new;
                for i in col {
                    self.p[i] = self.z[i] + beta * self.p[i];
                }
            }
        }
        self.prev.copy_from_slice(rhs);
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[inline]
fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// The matvec-only tick's projected step: conjugate gradients on the
/// bordered system of the step,
///
/// ```text
/// [A_JJ  A_JF             ] [y_J]   [r_J]
/// [A_FJ  A_FF + diag(k_inv)] [y_F] = [r_F]
/// ```
///
/// (SPD: the fingers are penalty rows, k_inv > 0), A as last assembled,
/// preconditioned by a solve with the refreshed factor and its own Schur
/// complement. A chord step with that factor alone (one preconditioner
/// application) contracts by ‖I − A A_s⁻¹‖, which a few ticks' motion makes
/// useless on an ill-conditioned A (the sphere toy: 1e-5 m violations two
/// ticks after a refresh); the Krylov iteration handles the few eigenvalues
/// the motion moves away from 1.
#[derive(Debug, Clone)]
pub(crate) struct Bordered {
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    max_iterations: u32,
    /// Iterations of the last solve.
    pub iterations: u32,
    /// Solves that stopped at the cap above the tolerance.
    pub unconverged: u64,
}

impl Bordered {
    /// Buffers for n_J + m_f unknowns. Allocates.
    pub fn new(n: usize, max_iterations: u32) -> Self {
        Self {
            r: vec![0.0; n],
            z: vec![0.0; n],
            p: vec![0.0; n],
            ap: vec![0.0; n],
            max_iterations,
            iterations: 0,
            unconverged: 0,
        }
    }

    /// Solves the bordered system in place (`x`: the right-hand side in J
    /// then F order in, the solution out), starting from 0; `precondition`
    /// replaces its argument v by M⁻¹ v (false: failed). False if a
    /// preconditioner solve failed.
    ///
    /// # Real-time
    /// No allocation; per iteration one product with the bordered matrix
    /// and one preconditioner solve, at most `max_iterations`.
    pub fn solve(
        &mut self,
        gram: &Gram,
        k_inv: &[f64],
        x: &mut [f64],
        mut precondition: impl FnMut(&mut [f64]) -> bool,
    ) -> bool {
        self.iterations = 0;
        self.r.copy_from_slice(x);
        let bnorm = norm(&self.r);
        x.fill(0.0);
        self.z.copy_from_slice(&self.r);
        if !precondition(&mut self.z) {
            return false;
        }
        self.p.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        while self.iterations < self.max_iterations
            && rz > 0.0
            && norm(&self.r) > STEP_TOLERANCE * bnorm
        {
            self.iterations += 1;
            bordered_mul(gram, k_inv, &self.p, &mut self.ap);
            let pap = dot(&self.p, &self.ap);
            if pap.is_nan() || pap <= 0.0 {
                break;
            }
            let alpha = rz / pap;
            for (i, xi) in x.iter_mut().enumerate() {
                *xi += alpha * self.p[i];
                self.r[i] -= alpha * self.ap[i];
            }
            self.z.copy_from_slice(&self.r);
            if !precondition(&mut self.z) {
                return false;
            }
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..x.len() {
                self.p[i] = self.z[i] + beta * self.p[i];
            }
        }
        if rz > 0.0 && norm(&self.r) > STEP_TOLERANCE * bnorm {
            self.unconverged += 1;
        }
        true
    }
}

/// y = [A_JJ A_JF; A_FJ A_FF + diag(k_inv)] x, J then F order.
fn bordered_mul(gram: &Gram, k_inv: &[f64], x: &[f64], y: &mut [f64]) {
    let (n, m, nnz) = (gram.n_j, gram.m_f, gram.nnz());
    let (xj, xf) = x.split_at(n);
    let (yj, yf) = y.split_at_mut(n);
    sym_mul(gram, xj, yj);
    let a_fj = &gram.values[nnz..nnz + m * n];
    let a_ff = &gram.values[nnz + m * n..];
    for f in 0..m {
        let row = &a_fj[f * n..(f + 1) * n];
        let xf_f = xf[f];
        let mut acc = 0.0;
        for j in 0..n {
            yj[j] += row[j] * xf_f;
            acc += row[j] * xj[j];
        }
        for g in 0..m {
            acc += a_ff[f * m + g] * xf[g];
        }
        yf[f] = acc + k_inv[f] * xf_f;
    }
}
