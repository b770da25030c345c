//! The tick's first force solve, kept through the release re-solve.
//!
//! When an active inequality pulls, `compute` releases it and solves again
//! (the second factorisation), then activates the kinematic set again for
//! the projected steps of the next tick and solves a third time. That third
//! set is nearly always the first one (a stop that halted a rebound pulls
//! for a tick, is released for the force, and is active again for the
//! motion): its assembly, factor and solve then compute the first solve's
//! numbers again, bit for bit (the same q, Jacobian, b, scales and known
//! multipliers). On Stewart held against a stroke limit those three were
//! two thirds of the tick. So the second solve runs in a spare pair of
//! buffers, and when the third set equals the first bit for bit the first
//! solve's pair is swapped back instead of recomputed.
//!
//! Only with the Cholesky force solver (the conjugate-gradient solvers
//! warm-start from the previous solve, so a repeat is not a copy) and on
//! models with limit rows and no contact rows (a contact scene's pair of
//! buffers would double a large program for a path it rarely takes).

use super::Feedback;
use crate::SolverSettings;
use crate::al::ForceSolver;
use crate::constraint::Geometry;
use crate::force::gram::Gram;
use crate::force::solve::{FactorError, MultiplierSolve};
use crate::{Evaluation, Model};

/// The spare pair and the first solve's row scales.
#[derive(Debug, Clone)]
pub(super) struct Kept {
    gram: Gram,
    solve: MultiplierSolve,
    /// The row scales of the tick's first solve.
    scale: Vec<f64>,
    /// `gram` and `solve` hold the first solve, at `scale`.
    first: bool,
    /// Tests: third solves that swapped the first back.
    #[cfg(test)]
    reused: u64,
}

impl Kept {
    /// A spare pair for `gram` and `solve` where this model and solver can
    /// use one (see the module docs). Allocates.
    pub fn new(
        model: &Model,
        settings: &SolverSettings,
        gram: &Gram,
        solve: &MultiplierSolve,
    ) -> Option<Box<Self>> {
        let limits = model
            .geometry
            .iter()
            .any(|g| matches!(g, Geometry::Limit(_)));
        let contacts = model.contact.slots > 0
            || model
                .geometry
                .iter()
                .any(|g| matches!(g, Geometry::Contact(_)));
        let usable = settings.force_solver == ForceSolver::Cholesky && limits && !contacts;
        usable.then(|| {
            Box::new(Self {
                gram: gram.clone(),
                solve: solve.clone(),
                scale: vec![0.0; model.n_rows()],
                first: false,
                #[cfg(test)]
                reused: 0,
            })
        })
    }

    /// Replaces the spare solve (a test switched the path or kernels of
    /// the main one).
    #[cfg(test)]
    pub fn set_solve(&mut self, solve: &MultiplierSolve) {
        self.solve = solve.clone();
    }
}

impl Feedback {
    /// Tests: drop the spare pair (every release tick solves three times,
    /// the old path).
    #[cfg(test)]
    pub(crate) fn drop_kept(&mut self) {
        self.kept = None;
    }

    /// Tests: third solves that swapped the first back.
    #[cfg(test)]
    pub(crate) fn kept_reused(&self) -> u64 {
        self.kept.as_ref().map_or(0, |k| k.reused)
    }

    /// Before the release re-solve: the first solve (at `scale_first`, the
    /// scales before the release) moves to the spare pair and the spare
    /// becomes the working one.
    ///
    /// # Real-time
    /// No allocation; O(rows).
    pub(super) fn keep_first(&mut self, scale_first: &[f64]) {
        let Some(k) = self.kept.as_deref_mut() else {
            return;
        };
        if self.solve.cg.is_some() || self.solve.pcg.is_some() {
            k.first = false;
            return;
        }
        std::mem::swap(&mut self.gram, &mut k.gram);
        std::mem::swap(&mut self.solve, &mut k.solve);
        k.scale.copy_from_slice(scale_first);
        k.first = true;
    }

    /// The third solve of a release tick, at the current scales: the kept
    /// first solve swapped back when its scales are these bit for bit,
    /// else a solve.
    ///
    /// # Real-time
    /// No allocation; O(rows + nnz(C_q)) when the first solve is reused,
    /// else one assembly, factorisation and solve.
    pub(super) fn solve_again(
        &mut self,
        ev: &Evaluation,
        settings: &SolverSettings,
    ) -> Result<(), FactorError> {
        let same = self.kept.as_deref().is_some_and(|k| {
            k.first
                && (k.scale.iter())
                    .zip(&self.scale)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
        });
        let Some(k) = self.kept.as_deref_mut().filter(|_| same) else {
            if let Some(k) = self.kept.as_deref_mut() {
                k.first = false;
            }
            return self.solve_multipliers(ev, settings);
        };
        std::mem::swap(&mut self.gram, &mut k.gram);
        std::mem::swap(&mut self.solve, &mut k.solve);
        k.first = false;
        #[cfg(test)]
        {
            k.reused += 1;
        }
        // As `solve_multipliers` leaves them: one more factorisation
        // counted, and the scaled right-hand side of this set (y = M̃⁻¹ b
        // does not depend on the scales).
        self.generation = self.generation.wrapping_add(1);
        ev.jacobian()
            .mul_vec(&self.y, &mut self.cy)
            .map_err(|_| FactorError)?;
        for (v, sc) in self.cy.iter_mut().zip(&self.scale) {
            *v *= sc;
        }
        Ok(())
    }
}
