//! Preconditioners for the conjugate-gradient Eq. 7 solves whose
//! application costs O(nnz(C_q)), not the full factor's fill.
//!
//! - [`tree`]: a spanning-tree ("subgraph", Vaidya's support-graph sense)
//!   preconditioner: the exact Gram block of a spanning tree of the
//!   mechanism's body graph, whose factor is fill-free, with the
//!   loop-closing joints' own diagonal blocks (`ForceSolver::Tree`).
//! - [`multilevel`]: an aggregation (algebraic-multigrid style) V-cycle:
//!   block Gauss–Seidel per constraint, coarse levels from clusters of
//!   neighbouring joints, a dense coarsest factor
//!   (`ForceSolver::Multilevel`).

pub(crate) mod block;
pub(crate) mod coarsen;
pub(crate) mod multilevel;
pub(crate) mod step;
pub(crate) mod tree;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_multilevel;

use super::gram::Gram;
use super::solve::FactorError;

/// The preconditioner of a conjugate-gradient tick without the full
/// factor: the tree tick's or the multilevel tick's.
#[derive(Debug, Clone)]
pub(crate) enum Precond {
    Tree(Box<tree::TreePrecond>),
    Multilevel(Box<multilevel::Multilevel>),
}

impl Precond {
    /// Forms the preconditioner from `gram`'s assembled A.
    ///
    /// # Real-time
    /// No allocation.
    pub fn factor(&mut self, gram: &Gram) -> Result<(), FactorError> {
        match self {
            Precond::Tree(t) => t.factor(gram),
            Precond::Multilevel(m) => m.factor(gram),
        }
    }

    /// x ← M⁻¹ x for `k` columns of n_J entries.
    ///
    /// # Real-time
    /// No allocation.
    pub fn apply(&mut self, x: &mut [f64], k: usize) {
        match self {
            Precond::Tree(t) => t.apply(x, k),
            Precond::Multilevel(m) => m.apply(x, k),
        }
    }
}
