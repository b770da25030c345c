//! The release branch of `Feedback::compute` without re-assembling or
//! re-factoring what it already has.
//!
//! When an active inequality pulls (or a sticking pair slips), `compute`
//! solves again without those rows, and under the projected update a third
//! time with the kinematic active set, for the next tick's steps. Against a
//! stop that is every tick (Stewart's stroke limits: 1000 releases a
//! second), and each solve was a full assembly, numeric factorisation and
//! finger solve. Two facts make most of that work redundant:
//!
//! - The second solve's A is the first's with the released rows and
//!   columns zeroed: each entry of A is a sum over bodies of products of
//!   two rows, in a fixed order that does not depend on which other rows
//!   take part, and a dropped row's entries get no products at all. So
//!   masking the first A (and putting back its diagonal before the
//!   Tikhonov term, which depends on the rows taking part) gives the
//!   assembly's values bit for bit.
//! - The third solve's active set is usually the first's again, and then
//!   its A, right-hand side, factor and multipliers are the first's: the
//!   first solve is kept aside, not recomputed.
//!
//! Both are exact: a test runs Stewart into its stops with and without
//! the spare and compares every output bit for bit.

use super::*;

/// The first solve of a tick kept aside while the release branch solves
/// again, and the raw diagonal of the last assembly.
#[derive(Debug, Clone)]
pub(super) struct Spare {
    /// A second factor with the same symbolic analysis.
    solve: MultiplierSolve,
    values: Vec<f64>,
    decoupled: Vec<bool>,
    cy: Vec<f64>,
    /// The row scales of the last full assembly.
    pub(super) scale: Vec<f64>,
    /// A_JJ's diagonal as assembled, before the regularisation.
    raw_diag: Vec<f64>,
    /// The spare holds the first solve of this tick's release branch.
    holds_first: bool,
    /// The low-rank release's buffers (`low_rank`), where it may be taken.
    pub(super) low_rank: Option<crate::force::solve::LowRank>,
    /// The last release was solved by the low-rank correction: the first
    /// solve's factor is still the solve's, its multipliers in `low_rank`.
    pub(super) low_rank_holds: bool,
}

impl Spare {
    /// A spare for a Cholesky solve of a model with rows that can be
    /// released (inequalities, contacts, friction); `None` otherwise.
    /// Allocates.
    pub(super) fn for_model(
        model: &Model,
        settings: &SolverSettings,
        gram: &Gram,
        solve: &MultiplierSolve,
    ) -> Option<Box<Spare>> {
        let releasable = model
            .rows()
            .iter()
            .any(|r| r.sense != crate::constraint::Sense::Equality);
        if !releasable || settings.force_solver != ForceSolver::Cholesky {
            return None;
        }
        Some(Box::new(Spare {
            solve: solve.clone(),
            values: gram.values.clone(),
            decoupled: gram.decoupled.clone(),
            cy: vec![0.0; model.n_rows()],
            scale: vec![0.0; model.n_rows()],
            raw_diag: vec![0.0; gram.n_j],
            holds_first: false,
            low_rank: None,
            low_rank_holds: false,
        }))
    }
}

impl Feedback {
    /// Called by every assembly between the products and the
    /// regularisation: keeps the row scales and the raw diagonal.
    pub(super) fn note_assembly(&mut self) {
        if let Some(sp) = &mut self.spare {
            sp.scale.copy_from_slice(&self.scale);
            for (r, &d) in sp.raw_diag.iter_mut().zip(&self.gram.diag) {
                *r = self.gram.values[d];
            }
            sp.holds_first = false;
            sp.low_rank_holds = false;
        }
    }

    /// Solves again after a release with the current row scales: the last
    /// assembly's A masked (without a spare: assembled afresh). The last
    /// solve is kept in the spare for [`restore_first`](Self::restore_first).
    pub(super) fn solve_released(
        &mut self,
        ev: &Evaluation,
        settings: &SolverSettings,
    ) -> Result<(), FactorError> {
        // Masking only drops rows: a row taking part now must have taken
        // part, at the same scale, in the assembly being masked.
        let maskable = self.spare.as_ref().is_some_and(|sp| {
            (self.scale.iter().zip(&sp.scale)).all(|(&now, &then)| now == 0.0 || now == then)
        });
        if !maskable {
            return self.solve_multipliers(ev, settings);
        }
        let Some(mut sp) = self.spare.take() else {
            return self.solve_multipliers(ev, settings);
        };
        if self.solve_released_low_rank(&mut sp) {
            self.spare = Some(sp);
            self.generation = self.generation.wrapping_add(1);
            return Ok(());
        }
        sp.values.copy_from_slice(&self.gram.values);
        sp.decoupled.copy_from_slice(&self.gram.decoupled);
        sp.cy.copy_from_slice(&self.cy);
        std::mem::swap(&mut sp.solve, &mut self.solve);
        sp.holds_first = true;
        self.mask_released(&sp.raw_diag);
        self.spare = Some(sp);
        self.generation = self.generation.wrapping_add(1);
        self.regularize(settings);
        self.solve_assembled(ev)
    }

    /// Zeroes the rows and columns of A whose scale is now 0 and puts back
    /// the raw diagonal: the values the assembly would give.
    fn mask_released(&mut self, raw_diag: &[f64]) {
        let g = &mut self.gram;
        for (d, &row) in g.decoupled.iter_mut().zip(&g.j_rows) {
            *d = self.scale[row] == 0.0;
        }
        let (cp, ri) = (g.pattern.col_ptr(), g.pattern.row_idx());
        let (nnz, n_j) = (cp[g.n_j], g.n_j);
        for j in 0..n_j {
            let span = cp[j]..cp[j + 1];
            for (v, &i) in g.values[span.clone()].iter_mut().zip(&ri[span]) {
                if g.decoupled[j] || g.decoupled[i] {
                    *v = 0.0;
                }
            }
        }
        for f in 0..g.m_f {
            for j in 0..n_j {
                if g.decoupled[j] {
                    g.values[nnz + f * n_j + j] = 0.0;
                }
            }
        }
        for ((&d, &off), &raw) in g.diag.iter().zip(&g.decoupled).zip(raw_diag) {
            if !off {
                g.values[d] = raw;
            }
        }
    }

    /// After [`solve_released`](Self::solve_released): if the row scales are
    /// the first solve's again, that solve (A, right-hand side, factor and
    /// multipliers) comes back from the spare and `true` is returned;
    /// otherwise nothing changes.
    pub(super) fn restore_first(&mut self) -> bool {
        let Some(sp) = &mut self.spare else {
            return false;
        };
        if sp.low_rank_holds && sp.scale == self.scale {
            if let Some(lr) = &sp.low_rank {
                self.solve.restore_low_rank(lr);
            }
            sp.low_rank_holds = false;
            self.generation = self.generation.wrapping_add(1);
            self.first_kept += 1;
            return true;
        }
        if !sp.holds_first || sp.scale != self.scale {
            return false;
        }
        std::mem::swap(&mut sp.solve, &mut self.solve);
        std::mem::swap(&mut sp.values, &mut self.gram.values);
        std::mem::swap(&mut sp.decoupled, &mut self.gram.decoupled);
        std::mem::swap(&mut sp.cy, &mut self.cy);
        sp.holds_first = false;
        self.generation = self.generation.wrapping_add(1);
        self.first_kept += 1;
        true
    }

    /// Without the spare, every solve of the release branch assembles and
    /// factors afresh (the comparison the exactness test makes).
    pub fn drop_spare(&mut self) {
        self.spare = None;
    }

    /// Ticks whose last solve was the first one kept, not a third
    /// factorisation.
    pub fn first_solves_kept(&self) -> u64 {
        self.first_kept
    }
}
