//! What `coordinates = auto` chooses by: a deterministic count of each
//! tick's arithmetic (multiply-adds), from shapes known once the program is
//! built — no timing at construction.
//!
//! **The joint tick** (`reduced`), n joint coordinates, m kept rows (n_L
//! loop rows, m_F finger rows), `iterations` update steps, P = Σ over the
//! joint coordinates of the coordinates on its path to the ground (its
//! depth), D the deepest path, B the tree joints. H's factor, its solves,
//! Y and W follow the tree's branches (`reduced::branch`): F = Σ over
//! coordinates k of the depths of k's ancestors, s_a the nonzeros of Y's
//! row a (at build, q0), d_i the depth of coordinate i:
//!
//! ```text
//! H (composite inertias)       36 n + 6 P
//! H = Lᵀ L                     F
//! Y = L⁻ᵀ (D J_r S)ᵀ, W = YᵀY  Σ_a Σ_{i ∈ s_a} d_i + Σ_{b ≤ a} min(|s_a|, |s_b|)
//! W_LL, Z, Σ_F                 n_L³ / 6 + m_F n_L² / 2 + m_F² n_L
//! J_r S, τ = Sᵀ b, g           6 m D + 7 P + Σ_a |s_a|
//! per step                     2 P + 3 m n + n_L² + 2 m_F n_L + 60 B
//! ```
//!
//! **The augmented tick**: its Eq. 7 factor (nnz stored values over an
//! order N of rows, the factor known at build) refactored each tick and
//! solved once a step and once for the force, the Gram matrix and the
//! evaluation proportional to the Jacobian's nnz, and each row's
//! evaluation once a step (R a row a step: fitted, not counted — without
//! it the chains' augmented ticks, many cheap rows over a thin factor, were
//! estimated 0.7× their measured time and the lattice's 1.4×):
//!
//! ```text
//! factor  nnz² / N,   solves  2 nnz (iterations + 1),   Gram + evaluation  G · nnz(C_q)
//! rows    R · N (iterations + 1)
//! ```
//!
//! Each count is then scaled to microseconds by its path's rate and
//! overhead, fitted to measured ticks of the shipped scenes (BENCHMARKS.md,
//! issue 23): the joint tick's plain loops and the augmented tick's
//! supernodal factor do not run at the same rate.

use crate::reduced::JointTick;

/// Multiply-adds of the augmented Gram matrix and evaluation per stored
/// Jacobian entry.
const GRAM_PER_JACOBIAN_ENTRY: f64 = 12.0;

/// Multiply-adds of the augmented tick's evaluation per constraint row and
/// update step (fitted with the rates below, BENCHMARKS.md issue 23, "auto's
/// cost model refitted").
const EVALUATION_PER_ROW_STEP: f64 = 190.0;

/// Microseconds per joint-tick multiply-add and the joint tick's fixed
/// cost (fitted, BENCHMARKS.md).
const JOINT_US_PER_MADD: f64 = 0.55e-3;
const JOINT_US_FIXED: f64 = 1.5;

/// Microseconds per augmented-tick multiply-add and its fixed cost.
const AUGMENTED_US_PER_MADD: f64 = 0.16e-3;
const AUGMENTED_US_FIXED: f64 = 1.0;

/// Both ticks' estimated arithmetic for one program
/// ([`CoordinatesChoice::estimate`](super::CoordinatesChoice::estimate)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostEstimate {
    /// The joint tick's multiply-adds a tick.
    pub joint_madds: f64,
    /// The augmented tick's multiply-adds a tick.
    pub augmented_madds: f64,
}

impl CostEstimate {
    /// The joint tick's estimated microseconds a tick.
    pub fn joint_us(&self) -> f64 {
        JOINT_US_FIXED + JOINT_US_PER_MADD * self.joint_madds
    }

    /// The augmented tick's estimated microseconds a tick.
    pub fn augmented_us(&self) -> f64 {
        AUGMENTED_US_FIXED + AUGMENTED_US_PER_MADD * self.augmented_madds
    }

    /// Whether the joint tick is estimated cheaper.
    pub fn joint_cheaper(&self) -> bool {
        self.joint_us() < self.augmented_us()
    }

    /// `joint estimate 1.9e6 madd (37 µs) ≥ augmented 2.1e5 madd (21 µs)`.
    pub fn describe(&self) -> String {
        let cmp = if self.joint_cheaper() { "<" } else { "≥" };
        format!(
            "joint estimate {:.1e} madd ({:.0} µs) {cmp} augmented {:.1e} madd ({:.0} µs)",
            self.joint_madds,
            self.joint_us(),
            self.augmented_madds,
            self.augmented_us()
        )
    }
}

/// The joint tick's multiply-adds a tick (module docs).
pub(crate) fn joint_madds(tick: &JointTick, iterations: u32) -> f64 {
    let tree = &tick.space.tree;
    let (_, d) = tree.path_dofs();
    let w = tick.branch_work();
    let (n, m, nl) = (
        tick.dofs() as f64,
        tick.rows.len() as f64,
        tick.n_loop as f64,
    );
    let (p, d, b) = (w.path, d as f64, tree.tree_joints() as f64);
    let mf = m - nl;
    let factors = 36.0 * n + 6.0 * p + w.factor + w.gram;
    let loops = nl.powi(3) / 6.0 + mf * nl * nl / 2.0 + mf * mf * nl;
    let ends = 6.0 * m * d + 7.0 * p + w.rows;
    let step = 2.0 * p + 3.0 * m * n + nl * nl + 2.0 * mf * nl + 60.0 * b;
    factors + loops + ends + f64::from(iterations) * step
}

/// The augmented tick's multiply-adds a tick (module docs): its factor's
/// stored values `factor_nnz` over `order` rows, `jacobian_nnz` stored
/// Jacobian entries.
pub(crate) fn augmented_madds(
    factor_nnz: usize,
    order: usize,
    jacobian_nnz: usize,
    iterations: u32,
) -> f64 {
    let (l, n) = (factor_nnz as f64, order.max(1) as f64);
    let steps = f64::from(iterations + 1);
    let rows = EVALUATION_PER_ROW_STEP * order as f64 * steps;
    l * l / n + 2.0 * l * steps + GRAM_PER_JACOBIAN_ENTRY * jacobian_nnz as f64 + rows
}
