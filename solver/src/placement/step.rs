//! Numeric phase of one Newton iteration: assemble the normal matrix in place,
//! factor it, solve for the multipliers and form the step. No allocation.
//!
//! With L = ½‖q − q_ref‖²_W + λᵀg over x = (q, Y), g = (C_eq, C_in − Y²), the
//! Newton-KKT step with the objective's Hessian W on q (Choi & Cremer Eq. 8)
//! and the exact, diagonal Hessian −2λ_j on each slack Y_j (floored at
//! `H_MIN`) reduces to the normal equations
//!
//! ```text
//! (J W⁻¹ Jᵀ + D + μI) λ⁺ = g − J (q − q_ref),   D = diag(0, 4Y²/H_Y)
//! δq = −(q − q_ref) − W⁻¹ Jᵀ λ⁺,   δY = 2 Y λ⁺ / H_Y
//! ```
//!
//! μ > 0 keeps the matrix positive definite when J loses rank; the step is
//! then the Gauss–Newton step of ½‖g‖² + (μ/2)‖q − q_ref‖²_W, whose stationary
//! point has g = μλ. The loop (`newton.rs`) therefore lets μ follow θ² down to
//! 1e-4·`damping`, so the bias μ|λ| vanishes with the residual. (A proximal
//! μ(λ⁺ − λ_k) term would remove the bias exactly, but with redundant rows —
//! the four-bar's point finger on a 1-DOF loop — λ then grows along the left
//! null space of J by g/μ per step and pollutes δq; measured: divergence at
//! μ = 1e-14.)

use super::Placement;
use super::factor::NotPositive;

/// Floor of the slack Hessian H_Y = max(−2λ_j, H_MIN). An inactive row gets
/// D_j = 4Y²/H_MIN ≫ 1, which decouples it (λ_j → 0) and makes δY the Newton
/// step of Y² = C_j; an active row gets H_Y = −2λ_j, the exact Hessian, so Y_j
/// converges quadratically to 0.
pub(super) const H_MIN: f64 = 1e-6;

/// Iterative-refinement steps at most after a low-rank (dense-column) solve.
const REFINE: usize = 6;

impl Placement {
    /// g from the current evaluation and slacks.
    pub(super) fn update_residual(&mut self) {
        let c = self.eval.values();
        self.g.copy_from_slice(c);
        for (g, y) in self.g[self.m_eq..].iter_mut().zip(&self.y) {
            *g -= y * y;
        }
    }

    /// Computes λ⁺ (into `lambda_new`), δq (`dq`) and δY (`dy`) at the current
    /// evaluation of `q` with damping `mu`. `pull` = 1 is the step above; in
    /// least-squares mode `mu` = μ₀ + ν and `pull` = μ₀/(μ₀ + ν) give the
    /// Levenberg–Marquardt step (JᵀJ + (μ₀ + ν)W) δ = −(Jᵀg + μ₀W(q − q_ref))
    /// of ψ = ½‖g‖² + μ₀·½‖q − q_ref‖²_W (push-through identity).
    pub(super) fn newton_step(
        &mut self,
        q: &[f64],
        q_ref: &[f64],
        mu: f64,
        pull: f64,
    ) -> Result<(), NotPositive> {
        for ((d, q), r) in self.d.iter_mut().zip(q).zip(q_ref) {
            *d = q - r;
        }
        for (((s, d), w), h) in self.sd.iter_mut().zip(&self.d).zip(&self.w).zip(&self.hinv) {
            *s = pull * h * w * d;
        }
        let jac = self.eval.jacobian();
        let winv = self.weighted.then_some(&self.hinv[..]);
        // rhs = g − J H⁻¹W d
        if jac.mul_vec(&self.sd, &mut self.rhs).is_err() {
            return Err(NotPositive);
        }
        for (r, g) in self.rhs.iter_mut().zip(&self.g) {
            *r = g - *r;
        }
        // Extra diagonal: μ, the slack term, the F columns of dense rows.
        self.diag.fill(mu);
        for ((d, y), h) in self.diag[self.m_eq..].iter_mut().zip(&self.y).zip(&self.hy) {
            *d += 4.0 * y * y / h;
        }
        self.diag_n.copy_from_slice(&self.diag);
        self.low.load(jac.values(), winv, &mut self.diag);
        let f = &mut self.factor;
        f.plan.fill(jac.values(), winv, f.mat.val_mut());
        let vals = f.mat.val_mut();
        for (&slot, d) in f.plan.diag_slot.iter().zip(&self.diag) {
            vals[slot] += d;
        }
        f.factorize()?;
        self.low.prepare(f, &self.diag)?;
        self.lambda_new.copy_from_slice(&self.rhs);
        self.low.solve(f, &mut self.lambda_new);
        // The Woodbury solve loses digits when S is nearly singular (μ → 0 on
        // the F rows); iterative refinement on N restores them.
        let rhs_norm = self.rhs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut last = f64::INFINITY;
        for _ in 0..REFINE * usize::from(self.low.rank() > 0) {
            // r = rhs − N λ, N λ = J H⁻¹ Jᵀ λ + (D + μ) λ
            let _ = jac.mul_t_vec(&self.lambda_new, &mut self.tmp_n);
            for (t, h) in self.tmp_n.iter_mut().zip(&self.hinv) {
                *t *= h;
            }
            let _ = jac.mul_vec(&self.tmp_n, &mut self.tmp_m);
            let lam = self.lambda_new.iter().zip(&self.diag_n);
            for ((r, b), (l, d)) in self.tmp_m.iter_mut().zip(&self.rhs).zip(lam) {
                *r = b - (*r + d * l);
            }
            let r_norm = self.tmp_m.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            // Done at 1e-12 relative, or once rounding stops the progress.
            if r_norm <= 1e-12 * rhs_norm || r_norm > 0.5 * last {
                break;
            }
            last = r_norm;
            self.low.solve(f, &mut self.tmp_m);
            for (l, c) in self.lambda_new.iter_mut().zip(&self.tmp_m) {
                *l += c;
            }
        }
        if !self.lambda_new.iter().all(|v| v.is_finite()) {
            return Err(NotPositive);
        }
        // δq = −H⁻¹W d − H⁻¹ Jᵀ λ⁺
        if jac.mul_t_vec(&self.lambda_new, &mut self.dq).is_err() {
            return Err(NotPositive);
        }
        for ((dq, s), h) in self.dq.iter_mut().zip(&self.sd).zip(&self.hinv) {
            *dq = -s - h * *dq;
        }
        let lam_in = &self.lambda_new[self.m_eq..];
        for (((dy, y), h), l) in self.dy.iter_mut().zip(&self.y).zip(&self.hy).zip(lam_in) {
            *dy = 2.0 * y * l / h;
        }
        Ok(())
    }

    /// Second-order correction: with C at the trial point in the evaluation
    /// and the last factorisation, moves the trial by the least-norm step
    /// −H⁻¹Jᵀ N⁻¹ g_t that removes its residual to first order. No allocation.
    pub(super) fn correct_trial(&mut self) -> bool {
        let c = self.eval.values();
        self.tmp_m.copy_from_slice(c);
        for (g, y) in self.tmp_m[self.m_eq..].iter_mut().zip(&self.y_trial) {
            *g -= y * y;
        }
        self.low.solve(&mut self.factor, &mut self.tmp_m);
        let jac = self.eval.jacobian();
        if jac.mul_t_vec(&self.tmp_m, &mut self.tmp_n).is_err() {
            return false;
        }
        for ((t, j), h) in self.q_trial.iter_mut().zip(&self.tmp_n).zip(&self.hinv) {
            *t -= h * j;
        }
        let lam_in = &self.tmp_m[self.m_eq..];
        for (((t, y), h), l) in self
            .y_trial
            .iter_mut()
            .zip(&self.y)
            .zip(&self.hy)
            .zip(lam_in)
        {
            *t = (*t + 2.0 * y * l / h).abs();
        }
        self.q_trial.iter().all(|v| v.is_finite())
    }
}
