//! The quaternion-norm rows out of the force factor, and the coupled
//! pattern kept for the assemblies where that is not exact.
//!
//! A body's norm row 2eᵀ and any other row on the body (its e columns
//! Ω(e)ᵀ g, `Geometry::scale_free_in_e`) meet in A = C_q M̃⁻¹ C_qᵀ in
//! 2 eᵀ M̃_e⁻¹ Ω(e)ᵀ g, which is zero when M̃_e⁻¹ is evaluated at the same e
//! as the Jacobian: M̃_e⁻¹ e = (|e|²/4c′) e and Ω(e) e = 0
//! (`force::inertia`, `crate::rotation`). So the force factor's pattern
//! (`Gram::new`) leaves those entries out and the norm rows are a diagonal
//! block: the lattice's factor loses a fifth of its work.
//!
//! That holds for every assembly whose mass metric is taken where C_q was:
//! each tick's force solve (the factor the next tick's projected steps
//! use), the slow thread's refresh, the redundancy check at q0. It does
//! not hold where the metric stays at the tick start's configuration while
//! C_q is the iterate's (a mid-tick activation's refactorisation, the
//! refresh after a jump, the converged reference's iterations): there the
//! dropped entries are of the order of the rotation since the tick start,
//! and leaving them out makes the Newton step inexact in |e| (the converged
//! replay then stopped on a step too small to see |e| with the norm still
//! off by 7e-9). Those assemblies swap in the coupled pattern and its own
//! factor, which is today's; the check is exact, per body: the norm row's
//! Jacobian values are 2e of C_q's configuration, bit for bit.

use super::*;
use crate::cholesky::Cholesky;

/// The coupled pattern (norm rows in their bodies' cliques) and its factor,
/// swapped with the feedback's own while an assembly needs it.
#[derive(Debug, Clone)]
pub(crate) struct CoupledPattern {
    gram: Gram,
    llt: Cholesky,
    /// The feedback's `gram` and factor are the coupled ones now (the
    /// decoupled ones wait here).
    in_use: bool,
    /// Per decoupled norm row: (column of its body's r, value index of its
    /// first Jacobian value).
    checks: Vec<(usize, usize)>,
    /// Assemblies that took the coupled pattern.
    pub assemblies: u64,
}

impl CoupledPattern {
    /// For `gram` (the decoupled pattern) of `model` whose rows `excluded`
    /// are out of A, and `solve` built for it; `None` when no norm row is
    /// decoupled. Allocates.
    pub fn new(
        model: &Model,
        jac: &crate::Jacobian,
        masses: &[BodyMass],
        excluded: &[bool],
        gram: &Gram,
        solve: &MultiplierSolve,
        dense_max: usize,
    ) -> Result<Option<Self>, faer::sparse::FaerError> {
        let checks = gram.norm_checks(masses);
        if checks.is_empty() {
            return Ok(None);
        }
        let coupled = Gram::with_norms(model, jac, masses, excluded, false);
        let groups = contact_groups(model, &coupled);
        let llt = solve.factor_for(&coupled, &groups, dense_max)?;
        Ok(Some(Self {
            gram: coupled,
            llt,
            in_use: false,
            checks,
            assemblies: 0,
        }))
    }
}

impl CoupledPattern {
    /// Rebuilds the coupled factor with the dense path up to `dense_max`
    /// (comparisons; the decoupled pattern must be in use).
    #[cfg(test)]
    pub fn set_dense(&mut self, model: &Model, solve: &MultiplierSolve, dense_max: usize) {
        let groups = contact_groups(model, &self.gram);
        self.llt = (solve.factor_for(&self.gram, &groups, dense_max))
            .expect("the pattern analysed once already");
    }
}

impl Feedback {
    /// Makes `gram` and the factor the decoupled pattern's when the mass
    /// metric's configuration `q` is C_q's (`jac`) on every body with a
    /// decoupled norm row, the coupled pattern's otherwise (module docs).
    ///
    /// # Real-time
    /// No allocation; 4 comparisons per body, and two swaps when the
    /// pattern changes.
    pub(super) fn pick_pattern(&mut self, jac: &crate::Jacobian) {
        let Some(c) = &mut self.coupled else {
            return;
        };
        let (q, vals) = (&self.motion.q_prev, jac.values());
        let exact =
            (c.checks.iter()).all(|&(o, p)| (0..4).all(|k| vals[p + k] == 2.0 * q[o + 3 + k]));
        if exact == c.in_use {
            std::mem::swap(&mut self.gram, &mut c.gram);
            self.solve.swap_factor(&mut c.llt);
            c.in_use = !c.in_use;
        }
        c.assemblies += u64::from(c.in_use);
    }

    /// Puts the decoupled pattern back in use (before a rebuild of the
    /// solve).
    #[cfg(test)]
    pub(super) fn decoupled_in_use(&mut self) {
        if let Some(c) = &mut self.coupled
            && c.in_use
        {
            std::mem::swap(&mut self.gram, &mut c.gram);
            self.solve.swap_factor(&mut c.llt);
            c.in_use = false;
        }
    }

    /// Uses the coupled pattern from now on, whatever the assemblies
    /// (the comparison tests' reference: today's force factor).
    #[cfg(test)]
    pub fn keep_coupled(&mut self) {
        if let Some(mut c) = self.coupled.take()
            && !c.in_use
        {
            std::mem::swap(&mut self.gram, &mut c.gram);
            self.solve.swap_factor(&mut c.llt);
        }
    }

    /// The last Eq. 7 solve's scaled multipliers λ̃_J then λ̃_F (tests).
    #[cfg(test)]
    pub fn eq7_multipliers(&self) -> Vec<f64> {
        (0..self.gram.n_j)
            .map(|j| self.solve.joint_multiplier(j))
            .chain(self.solve.lambda_f.iter().copied())
            .collect()
    }

    /// Assemblies that took the coupled pattern, and whether the
    /// decoupled one exists (tests).
    #[cfg(test)]
    pub fn coupled_assemblies(&self) -> (u64, bool) {
        (self.coupled.as_ref()).map_or((0, false), |c| (c.assemblies, true))
    }
}
