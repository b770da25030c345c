//! One Newton step in isolation, for benchmarks and diagnostics: the
//! per-iteration numeric work of [`Placement::solve`] without its loop.

use super::step::H_MIN;
use super::{Placement, PlacementError};
use crate::{FingerTarget, Model};

impl Placement {
    /// Evaluates C and C_q at `q` and resets the iteration state (λ = 0,
    /// slacks from C, damping `options.damping`), as `solve` does before its
    /// first step. No allocation (after a first call with a new model object).
    pub fn prepare(
        &mut self,
        model: &Model,
        q: &[f64],
        targets: &[FingerTarget],
    ) -> Result<(), PlacementError> {
        self.bind(model)?;
        if q.len() != self.n {
            let (expected, got) = (self.n, q.len());
            return Err(PlacementError::CoordinateCount { expected, got });
        }
        self.eval
            .evaluate(model, q, targets)
            .map_err(PlacementError::Eval)?;
        for (y, c) in self.y.iter_mut().zip(&self.eval.values()[self.m_eq..]) {
            *y = c.max(0.0).sqrt().max(1e-6);
        }
        self.lambda.fill(0.0);
        self.hy.fill(H_MIN);
        self.update_residual();
        Ok(())
    }

    /// The numeric phase of one iteration at the prepared evaluation: fill
    /// J H⁻¹ Jᵀ + D + μI in place, numeric LLᵀ (plus the dense-column
    /// correction), solve, form δq, which is returned. `None` if the
    /// factorisation failed. No allocation.
    pub fn numeric_step(&mut self, q: &[f64], q_ref: &[f64]) -> Option<&[f64]> {
        if q.len() != self.n || q_ref.len() != self.n {
            return None;
        }
        let mu = self.options.damping;
        self.newton_step(q, q_ref, mu, 1.0).ok()?;
        Some(&self.dq)
    }
}
