//! One right-hand side of A_JJ, by preconditioned conjugate gradients from
//! zero to a relative residual: the tree tick's projected steps
//! (`ForceSolver::Tree`), whose right-hand sides shrink step to step (so a
//! warm start from the previous step's solution would start far off).

use super::super::cg::sym_mul;
use super::super::gram::Gram;

/// Relative residual at which a projected step's solve stops (as the
/// matvec tick's, `pcg::STEP_TOLERANCE`): an inexact Gauss–Newton step is
/// corrected by the next.
pub(crate) const STEP_TOLERANCE: f64 = 1e-6;

/// Buffers of one single-column solve.
#[derive(Debug, Clone)]
pub(crate) struct StepCg {
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    max_iterations: u32,
    /// Iterations of the last solve.
    pub iterations: u32,
    /// Iterations of every solve so far.
    pub total_iterations: u64,
    /// Solves that stopped at the cap above the tolerance.
    pub unconverged: u64,
}

impl StepCg {
    /// Buffers for n unknowns. Allocates.
    pub fn new(n: usize, max_iterations: u32) -> Self {
        Self {
            r: vec![0.0; n],
            z: vec![0.0; n],
            p: vec![0.0; n],
            ap: vec![0.0; n],
            max_iterations,
            iterations: 0,
            total_iterations: 0,
            unconverged: 0,
        }
    }

    /// Solves A_JJ x = b in place (`x`: b in, x out) from x = 0 to a
    /// relative residual of `tolerance`; `precondition` replaces its
    /// argument v by M⁻¹ v. Returns the relative residual reached.
    ///
    /// # Real-time
    /// No allocation; per iteration one product with A_JJ and one
    /// preconditioner application, at most `max_iterations`.
    pub fn solve(
        &mut self,
        gram: &Gram,
        x: &mut [f64],
        tolerance: f64,
        mut precondition: impl FnMut(&mut [f64]),
    ) -> f64 {
        self.iterations = 0;
        self.r.copy_from_slice(x);
        let bnorm = norm(&self.r);
        x.fill(0.0);
        if bnorm == 0.0 || !bnorm.is_finite() {
            return if bnorm == 0.0 { 0.0 } else { f64::NAN };
        }
        self.z.copy_from_slice(&self.r);
        precondition(&mut self.z);
        self.p.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        let mut rel = 1.0;
        while rz > 0.0 && rel > tolerance && self.iterations < self.max_iterations {
            self.iterations += 1;
            sym_mul(gram, &self.p, &mut self.ap);
            let pap = dot(&self.p, &self.ap);
            if pap.is_nan() || pap <= 0.0 {
                break;
            }
            let alpha = rz / pap;
            for (i, xi) in x.iter_mut().enumerate() {
                *xi += alpha * self.p[i];
                self.r[i] -= alpha * self.ap[i];
            }
            rel = norm(&self.r) / bnorm;
            self.z.copy_from_slice(&self.r);
            precondition(&mut self.z);
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for (p, z) in self.p.iter_mut().zip(&self.z) {
                *p = z + beta * *p;
            }
        }
        self.total_iterations += u64::from(self.iterations);
        if rel > tolerance {
            self.unconverged += 1;
        }
        rel
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
