//! Newton-KKT placement (Choi & Cremer §4.2, §5): the accurate, quadratically
//! convergent solver of the slow thread. It assembles a scene, re-projects it
//! after large jumps and gives the reference q and λ that accuracy figures are
//! measured against.
//!
//! ```text
//!  Model ──► Placement::analyze (symbolic, once per StructureKey; allocates)
//!              │ dense-column split · pattern of J Jᵀ + fill plan · AMD +
//!              │ symbolic Cholesky (faer) · every scratch buffer
//!              ▼
//!  q, q_ref, targets ──► Placement::solve (numeric; no allocation per iteration)
//!              │ per iteration: evaluate C, C_q · fill J W⁻¹ Jᵀ + D + μI in place
//!              │ · LLᵀ (faer, Par::Seq) [+ Woodbury for dense columns]
//!              │ · δ · backtracking on a merit · adaptive damping μ
//!              ▼
//!  q (placed), SolveInfo { status, iterations, residual, step, regularised },
//!  multipliers() (λ, model row order), slacks() (Y per inequality row)
//! ```
//!
//! Problem: min ½‖q − q_ref‖²_W s.t. C_eq(q) = 0 and, per inequality row,
//! C_j(q) − Y_j² = 0 (Eq. 17). The slacks add no rows to the normal matrix,
//! only a diagonal term (see `step.rs`). [`PlacementCache`] keeps analyses by
//! structure.
//!
//! | file | what |
//! |---|---|
//! | `options.rs` | [`PlacementOptions`]: units and defaults |
//! | `outcome.rs` | [`SolveInfo`], [`SolveStatus`], [`PlacementError`], [`PlacementStats`] |
//! | `pattern.rs` | symbolic: J Jᵀ pattern, runs of shared columns, dense-column split |
//! | `factor.rs` | symbolic + numeric faer Cholesky with preallocated scratch |
//! | `lowrank.rs` | dense columns: modified Schur complement (Eq. 13–14) |
//! | `analyze.rs` | [`Placement`], [`StructureKey`], `analyze` |
//! | `step.rs` | one Newton step: normal equations with slacks and damping |
//! | `newton.rs` | the loop: merit, backtracking, damping schedule, outcome |
//! | `least_squares.rs` | conflicting rows: Levenberg–Marquardt gain ratio, stationarity |
//! | `cache.rs` | [`PlacementCache`] |
//! | `probe.rs` | one Newton step in isolation (benchmarks, diagnostics) |

mod analyze;
mod cache;
mod factor;
mod least_squares;
mod line_search;
mod lowrank;
mod newton;
mod options;
mod outcome;
mod pattern;
mod probe;
mod step;

pub use analyze::{Placement, StructureKey};
pub use cache::PlacementCache;
pub use options::PlacementOptions;
pub use outcome::{IterationRecord, PlacementError, PlacementStats, SolveInfo, SolveStatus};
