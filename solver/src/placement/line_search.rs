//! The Newton step's line search (see `newton`'s module docs): backtracking
//! on the two-part merit, with a second-order correction of each trial.

use super::Placement;
use crate::{FingerTarget, Model};

/// Backtracking halvings per step.
const MAX_HALVINGS: u32 = 6;

/// The state a trial is judged against.
#[derive(Debug, Clone, Copy)]
pub(super) struct Merit {
    pub(super) theta: f64,
    pub(super) f: f64,
    pub(super) theta_ok: f64,
}

impl Merit {
    pub(super) fn accepts(&self, alpha: f64, theta_t: f64, f_t: f64) -> bool {
        let feasible = theta_t <= (1.0 - 1e-4 * alpha) * self.theta;
        let tangential = theta_t <= self.theta_ok && f_t < self.f;
        feasible || tangential
    }
}

impl Placement {
    /// Tries α = 1, ½, … on the step in `dq`/`dy`; leaves the accepted trial
    /// in `q_trial`/`y_trial` and returns α.
    pub(super) fn line_search(
        &mut self,
        model: &Model,
        q: &[f64],
        q_ref: &[f64],
        targets: &[FingerTarget],
        m: Merit,
    ) -> Option<f64> {
        let mut alpha = 1.0;
        for _ in 0..=MAX_HALVINGS {
            for ((t, q), d) in self.q_trial.iter_mut().zip(q).zip(&self.dq) {
                *t = q + alpha * d;
            }
            for ((t, y), d) in self.y_trial.iter_mut().zip(&self.y).zip(&self.dy) {
                *t = (y + alpha * d).abs();
            }
            if let Some(theta_t) = self.trial_residual(model, targets) {
                let f_t = self.objective(&self.q_trial, q_ref);
                if m.accepts(alpha, theta_t, f_t) {
                    return Some(alpha);
                }
                // Second-order correction (the Maratos effect: a good
                // tangential step raises θ to second order): project the
                // trial back with the factor already at hand.
                if self.correct_trial()
                    && let Some(theta_c) = self.trial_residual(model, targets)
                {
                    let f_c = self.objective(&self.q_trial, q_ref);
                    if m.accepts(alpha, theta_c, f_c) {
                        return Some(alpha);
                    }
                }
            }
            alpha *= 0.5;
        }
        None
    }

    /// θ at (`q_trial`, `y_trial`), evaluating C there (C_q keeps q's values).
    pub(super) fn trial_residual(
        &mut self,
        model: &Model,
        targets: &[FingerTarget],
    ) -> Option<f64> {
        self.eval
            .evaluate_values(model, &self.q_trial, targets)
            .ok()?;
        let c = self.eval.values();
        let mut t2: f64 = c[..self.m_eq].iter().map(|v| v * v).sum();
        for (c, y) in c[self.m_eq..].iter().zip(&self.y_trial) {
            t2 += (c - y * y).powi(2);
        }
        let theta = t2.sqrt();
        theta.is_finite().then_some(theta)
    }
}
