//! Preconditioners for the conjugate-gradient Eq. 7 solves whose
//! application costs O(nnz(C_q)), not the full factor's fill.
//!
//! - [`tree`]: a spanning-tree ("subgraph", Vaidya's support-graph sense)
//!   preconditioner: the exact Gram block of a spanning tree of the
//!   mechanism's body graph, whose factor is fill-free, with the
//!   loop-closing joints' own diagonal blocks (`ForceSolver::Tree`).

pub(crate) mod step;
pub(crate) mod tree;

#[cfg(test)]
mod tests;
