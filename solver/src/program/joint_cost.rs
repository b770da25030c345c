//! What `coordinates = auto` chooses by: a deterministic count of each
//! tick's arithmetic (multiply-adds), from shapes known once the program is
//! built — no timing at construction.
//!
//! **The joint tick** (`reduced`), n joint coordinates, m kept rows (n_L
//! loop rows, m_F finger rows), `iterations` update steps, P = Σ over the
//! joint coordinates of the coordinates on its path to the ground, D the
//! deepest path, B the tree joints:
//!
//! ```text
//! H (composite inertias)       36 n + 6 P
//! H = L Lᵀ                     n³ / 6
//! Y = L⁻¹ (D J_r S)ᵀ, W = YᵀY  m n² / 2 + m² n / 2
//! W_LL, Z, Σ_F                 n_L³ / 6 + m_F n_L² / 2 + m_F² n_L
//! J_r S, τ = Sᵀ b              6 m D + 6 P
//! per step                     n² + 3 m n + n_L² + 2 m_F n_L + 60 B
//! ```
//!
//! **The augmented tick**: its Eq. 7 factor (nnz stored values over an
//! order N of rows, the factor known at build) refactored each tick and
//! solved once a step and once for the force, the Gram matrix and the
//! evaluation proportional to the Jacobian's nnz:
//!
//! ```text
//! factor  nnz² / N,   solves  2 nnz (iterations + 1),   Gram + evaluation  G · nnz(C_q)
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

/// Microseconds per joint-tick multiply-add and the joint tick's fixed
/// cost (fitted, BENCHMARKS.md).
const JOINT_US_PER_MADD: f64 = 0.36e-3;
const JOINT_US_FIXED: f64 = 1.0;

/// Microseconds per augmented-tick multiply-add and its fixed cost.
const AUGMENTED_US_PER_MADD: f64 = 0.5e-3;
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
    let (p, d) = tree.path_dofs();
    let (n, m, nl) = (
        tick.dofs() as f64,
        tick.rows.len() as f64,
        tick.n_loop as f64,
    );
    let (p, d, b) = (p as f64, d as f64, tree.tree_joints() as f64);
    let mf = m - nl;
    let factors = 36.0 * n + 6.0 * p + n.powi(3) / 6.0 + m * n * n / 2.0 + m * m * n / 2.0;
    let loops = nl.powi(3) / 6.0 + mf * nl * nl / 2.0 + mf * mf * nl;
    let ends = 6.0 * m * d + 6.0 * p;
    let step = n * n + 3.0 * m * n + nl * nl + 2.0 * mf * nl + 60.0 * b;
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
    l * l / n + 2.0 * l * f64::from(iterations + 1) + GRAM_PER_JACOBIAN_ENTRY * jacobian_nnz as f64
}
