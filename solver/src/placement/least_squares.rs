//! Least-squares mode of the Newton loop: Levenberg–Marquardt trials on
//! ψ = ½‖g‖² + μ·½‖q − q_ref‖²_W judged by their gain ratio, and the
//! stationarity measure that tells a conflict from slow progress.

use super::Placement;
use crate::{FingerTarget, Model};

/// The new damping after an accepted step of gain ratio ρ (Nielsen's rule:
/// ×1/3 for a model that predicts well, up to ×2 for a poor one).
pub(super) fn lm_update(mu: f64, rho: f64) -> f64 {
    mu * (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0)
}

impl Placement {
    /// Tries the full step in `dq`/`dy` against ψ = ½θ² + μ₀f, given
    /// `(θ, f, μ₀)` at the current point: returns the gain ratio
    /// (actual / predicted decrease of ψ) if ψ decreased, leaving the trial in
    /// `q_trial`/`y_trial`; `None` rejects it.
    pub(super) fn lm_trial(
        &mut self,
        model: &Model,
        q: &[f64],
        q_ref: &[f64],
        targets: &[FingerTarget],
        (theta, f, mu): (f64, f64, f64),
    ) -> Option<f64> {
        // The linear model g + Aδ of the extended residual.
        let jac = self.eval.jacobian();
        jac.mul_vec(&self.dq, &mut self.tmp_m).ok()?;
        let m_eq = self.m_eq;
        let mut lin2 = 0.0;
        for (k, (a, g)) in self.tmp_m.iter().zip(&self.g).enumerate() {
            let mut v = g + a;
            if k >= m_eq {
                v -= 2.0 * self.y[k - m_eq] * self.dy[k - m_eq];
            }
            lin2 += v * v;
        }
        for ((t, q), d) in self.q_trial.iter_mut().zip(q).zip(&self.dq) {
            *t = q + d;
        }
        for ((t, y), d) in self.y_trial.iter_mut().zip(&self.y).zip(&self.dy) {
            *t = (y + d).abs();
        }
        let f_t = self.objective(&self.q_trial, q_ref);
        self.eval
            .evaluate_values(model, &self.q_trial, targets)
            .ok()?;
        let c = self.eval.values();
        let mut t2: f64 = c[..m_eq].iter().map(|v| v * v).sum();
        for (c, y) in c[m_eq..].iter().zip(&self.y_trial) {
            t2 += (c - y * y).powi(2);
        }
        let psi = 0.5 * theta * theta + mu * f;
        let predicted = psi - (0.5 * lin2 + mu * f_t);
        let actual = psi - (0.5 * t2 + mu * f_t);
        (predicted > 0.0 && actual.is_finite() && actual > 1e-4 * predicted)
            .then(|| actual / predicted)
    }

    /// ‖Jᵀg‖ / (‖J‖_max · ‖g‖ · √n) at the current evaluation: near 0 when
    /// the residual lies in the left null space of J (a least-squares
    /// stationary point). Uses `tmp_n` as scratch.
    pub(super) fn gradient_ratio(&mut self) -> f64 {
        let jac = self.eval.jacobian();
        if jac.mul_t_vec(&self.g, &mut self.tmp_n).is_err() {
            return f64::INFINITY;
        }
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let jmax = jac.values().iter().fold(1.0f64, |m, v| m.max(v.abs()));
        let scale = jmax * norm(&self.g) * (self.n as f64).sqrt();
        if scale > 0.0 {
            norm(&self.tmp_n) / scale
        } else {
            0.0
        }
    }
}
