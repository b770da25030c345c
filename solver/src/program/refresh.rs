//! The matvec-only tick's factor (`ForceSolver::Matvec`): the fast thread
//! never factors; the slow thread refreshes a Cholesky factor of the Eq. 7
//! matrix at a recent configuration and hands it over, and the fast tick
//! preconditions its conjugate gradients and takes its projected steps with
//! it.
//!
//! ```text
//!  slow thread:  Program::factor_refresher() (a copy of the force machinery, once per program)
//!                FactorRefresher::refresh(q of a recent snapshot, &mut RefreshedFactor)
//!                   evaluate C_q at q, assemble A, factor ──► RefreshedFactor { id, values }
//!                ──► program channel (boxes come back and are reused) ──►
//!  fast thread:  Program::adopt_factor(&mut RefreshedFactor): swap the values in if the id
//!                is this program's (the old values go back in the box), no allocation
//! ```
//!
//! A factor refreshed for another program (one replaced since) carries
//! another id and is ignored.

use std::sync::Arc;

use super::Program;
use crate::al::scaling::Scaling;
use crate::force::feedback::Feedback;
use crate::{Evaluation, FingerTarget, ForceSolver, Model, SolverSettings};

/// A factor of one program's Eq. 7 matrix, refreshed on the slow thread.
#[derive(Debug, Clone, Default)]
pub struct RefreshedFactor {
    id: u64,
    values: Vec<f64>,
    fresh: bool,
}

impl RefreshedFactor {
    /// Holds a factor not yet adopted (the fast side's swap leaves the
    /// program's previous values here, marked not fresh).
    pub fn is_fresh(&self) -> bool {
        self.fresh
    }
}

/// Refreshes one matvec-only program's force factor (slow thread).
#[derive(Debug, Clone)]
pub struct FactorRefresher {
    model: Arc<Model>,
    settings: SolverSettings,
    scaling: Scaling,
    ev: Evaluation,
    feedback: Feedback,
    targets: Vec<FingerTarget>,
    /// Refreshes computed.
    pub refreshes: u64,
}

impl FactorRefresher {
    /// Id of the program whose factor this refreshes.
    pub fn id(&self) -> u64 {
        self.feedback.factor_id()
    }

    /// A buffer for [`refresh`](Self::refresh), sized. Allocates.
    pub fn buffer(&self) -> RefreshedFactor {
        RefreshedFactor {
            id: self.id(),
            values: Vec::new(),
            fresh: false,
        }
    }

    /// Factors the program's Eq. 7 matrix at `q` (its layout) into `into`:
    /// C_q at q, the rows active there (equalities, fingers; inequality
    /// rows violated beyond the active band), assembled and regularised as
    /// the fast tick's force solve does. False (nothing usable in `into`)
    /// if q cannot be evaluated or the factorisation fails.
    ///
    /// Allocates only to size `into` the first time; one evaluation, one
    /// assembly and one numeric factorisation.
    pub fn refresh(&mut self, q: &[f64], into: &mut RefreshedFactor) -> bool {
        into.fresh = false;
        into.id = self.id();
        if q.len() != self.model.n_coords()
            || self.ev.evaluate(&self.model, q, &self.targets).is_err()
        {
            return false;
        }
        let ok = self
            .feedback
            .refactor_into(&self.scaling, &self.settings, q, &self.ev, &mut into.values)
            .is_ok();
        into.fresh = ok;
        self.refreshes += u64::from(ok);
        ok
    }
}

impl Program {
    /// The slow thread's refresher of this program's force factor, or
    /// `None` unless it runs the matvec-only tick (`ForceSolver::Matvec`).
    /// Allocates (a copy of the force machinery).
    pub fn factor_refresher(&self) -> Option<FactorRefresher> {
        if !matches!(self.settings.force_solver, ForceSolver::Matvec { .. }) {
            return None;
        }
        Some(FactorRefresher {
            model: Arc::clone(&self.model),
            settings: self.settings,
            scaling: self.scaling.clone(),
            ev: self.ev.clone(),
            feedback: self.feedback.clone(),
            targets: self.last_targets.clone(),
            refreshes: 0,
        })
    }

    /// Takes a factor refreshed for this program (fast thread): swaps its
    /// values in and leaves the previous ones in `f` (no longer fresh).
    /// False, changing nothing, for a factor of another program or one
    /// already adopted.
    ///
    /// # Real-time
    /// No allocation: two buffers swap.
    pub fn adopt_factor(&mut self, f: &mut RefreshedFactor) -> bool {
        if !f.fresh || f.id != self.feedback.factor_id() {
            return false;
        }
        let adopted = self.feedback.adopt_factor(&mut f.values);
        f.fresh = false;
        self.factor_adoptions += u64::from(adopted);
        adopted
    }

    /// Refreshed factors adopted so far (matvec-only tick).
    pub fn factor_adoptions(&self) -> u64 {
        self.factor_adoptions
    }
}
