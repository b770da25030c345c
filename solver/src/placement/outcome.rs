//! What a placement returns: [`SolveInfo`] (always, for every numerical
//! outcome), [`PlacementError`] (only for inputs that cannot be solved), the
//! per-iteration [`IterationRecord`] and the structural [`PlacementStats`].

use crate::EvalError;

/// How a [`Placement::solve`](super::Placement::solve) ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SolveStatus {
    /// Residual ≤ `tolerance` and the last step ≤ `step_tolerance`: C = 0 (and
    /// every inequality ≥ 0) to tolerance at a KKT point of ½‖q − q_ref‖²_W.
    Converged,
    /// The iteration cap was reached first; q is the best iterate (finite).
    MaxIterations,
    /// No step (at any damping up to the cap, any backtracking) reduced the
    /// merit, and the point is not a least-squares stationary point.
    Stalled,
    /// The constraints cannot all hold (conflicting or unreachable goals, a
    /// singular configuration): q is a finite damped least-squares compromise,
    /// a stationary point of ½‖C‖² + (μ/2)‖q − q_ref‖²_W, residual > tolerance.
    LeastSquares,
}

/// Diagnostics of one solve. `Copy`; every float is finite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveInfo {
    /// How it ended.
    pub status: SolveStatus,
    /// Newton iterations taken (accepted steps).
    pub iterations: u32,
    /// 2-norm of the equality rows and of `min(C_j, 0)` over inequality rows
    /// at the returned q (mixed units).
    pub residual: f64,
    /// The same over rows in metres only.
    pub residual_length_m: f64,
    /// The same over rows that are angles (radians) only.
    pub residual_angle_rad: f64,
    /// ∞-norm of the last Newton step (q and slacks).
    pub step: f64,
    /// True if the damping had to rise above `options.damping` (a rejected
    /// step or a failed Cholesky pivot) at any point of this solve.
    pub regularised: bool,
    /// The damping μ of the last step.
    pub damping: f64,
}

/// One accepted Newton iteration, recorded without allocation (see
/// [`Placement::history`](super::Placement::history)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IterationRecord {
    /// 2-norm of the extended residual (equalities and Φ_j − Y_j²) after the step.
    pub residual: f64,
    /// ∞-norm of the step taken (before scaling by `alpha`).
    pub step: f64,
    /// The backtracking factor accepted (1 = full Newton step).
    pub alpha: f64,
    /// Damping μ used.
    pub damping: f64,
}

/// Why a placement could not be analysed or run. Heap-free and `Copy`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PlacementError {
    /// An option is out of range.
    #[error("placement option `{field}` is out of range")]
    InvalidOption {
        /// The field.
        field: &'static str,
    },
    /// `weights` has the wrong length.
    #[error("{got} weights given; the model has {expected} coordinates")]
    WeightCount {
        /// Coordinates of the model.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A weight is not a finite positive number.
    #[error("weight {index} is not a finite positive number")]
    NonPositiveWeight {
        /// Its coordinate.
        index: usize,
    },
    /// The model has no constraint rows or no coordinates.
    #[error("the model has no constraint rows or no coordinates to place")]
    Empty,
    /// The model's constraint structure differs from the analysed one.
    #[error("the model's constraint structure differs from the analysed one")]
    StructureMismatch,
    /// q or q_ref has the wrong length.
    #[error("a vector of length {got} where {expected} coordinates were needed")]
    CoordinateCount {
        /// Coordinates of the model.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// q_ref has a NaN or infinite entry.
    #[error("q_ref[{index}] is not finite")]
    NonFiniteReference {
        /// Its index.
        index: usize,
    },
    /// The start could not be evaluated (non-finite q or target, degenerate
    /// quaternion, wrong target count).
    #[error("the start cannot be evaluated: {0}")]
    Eval(EvalError),
    /// faer's symbolic analysis failed (out of memory or index overflow).
    #[error("the symbolic analysis of J Jᵀ failed")]
    Symbolic,
}

/// Structure and cost of an analysis (what the dense-column test asserts).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlacementStats {
    /// Rows of C (= size of the normal matrix).
    pub rows: usize,
    /// Coordinates.
    pub coords: usize,
    /// Stored nonzeros of C_q.
    pub jacobian_nnz: usize,
    /// Stored entries of the lower triangle of the sparse normal matrix.
    pub normal_nnz: usize,
    /// Stored entries of the Cholesky factor L.
    pub factor_nnz: usize,
    /// Σ over columns of L of (entries in that column)²: the flop count of
    /// one numeric factorisation, up to a constant.
    pub factor_flops: u64,
    /// faer chose its supernodal (not simplicial) kernel.
    pub supernodal: bool,
    /// Columns of C_q split off as dense.
    pub dense_columns: usize,
    /// Rank of the low-rank Schur correction (dense columns + F columns).
    pub low_rank: usize,
}
