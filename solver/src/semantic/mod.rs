//! Semantic constraints (Gösele & Stuerzlinger, DESIGN §4.7): offer and
//! binding areas with labels, the label order, satisfying a constraint
//! (snapping, Algorithm 1), restricting moves (checkMove, Algorithm 2), the
//! grouping graph, breaking, and the consistency predicate. This is the
//! paper's discrete model, run on the slow loop; what the fast loop feels is
//! the rows each satisfied constraint becomes (`rows.rs` →
//! [`Model::with_semantic`](crate::Model::with_semantic) →
//! `constraint/surface.rs`, ramped and carried by `program/semantic.rs`).
//!
//! | file | what it owns |
//! |---|---|
//! | `labels.rs` | [`LabelOrder`]: the partial order ≤_L, fits(b, a) ⇔ l(b) ≤_L l(a), cycles refused |
//! | `spec.rs` | [`SemanticSpec`]: areas, order and `[semantic]` settings as a scene declares them |
//! | `area.rs` | [`Area`]: polygon, orientation vector, plane and edge data; [`relation`] of a binding to an offer |
//! | `motion.rs` | [`Move`]: (t, r) about a centre |
//! | `scene.rs` | [`SemanticScene`]: objects, areas, satisfied constraints, exception list, spatial indices |
//! | `grid.rs` | [`Grid`]: the hash grid that keeps every query local |
//! | `graph.rs` | the grouping graph: children, parents, groups, directed-cycle test |
//! | `collide.rs` | collisions with parry (bound, excepted and ignored pairs exempt) |
//! | `check_move.rs` | Algorithm 2 and the interactive move |
//! | `satisfy.rs` | searchCloseBindings and Algorithm 1; the loader's pass over aligned bindings |
//! | `breaking.rs` | breaking a constraint, the exception list and separation |
//! | `consistency.rs` | consistent(s) |
//! | `presence.rs` | adding and removing objects (§3.3): a valid place, bonds broken and released |
//! | `rows.rs` | a satisfied constraint as solver rows |
//!
//! ```text
//!  SemanticSpec + Model (+ q) ──► SemanticScene::from_model ──► satisfy_aligned (loading)
//!                                                             └► consistent()?  (a loaded scene is checked)
//!  each slow-loop cycle: set_pose (mirror the fast loop) → break_bond / update_exceptions
//!                        → satisfy (snap) → surface_specs ──► Model::with_semantic ──► Program
//! ```
//!
//! Nothing here allocates per fast tick or knows about threads; every query
//! goes through the grids, so its cost depends on the objects near the one
//! moved, not on the scene's size (BENCHMARKS.md, "Issue 13").

mod area;
mod breaking;
mod check_move;
mod collide;
mod consistency;
mod graph;
mod grid;
mod labels;
mod motion;
mod presence;
mod rows;
mod satisfy;
mod scene;
mod spec;

pub use area::{Area, AreaId, Relation, relation};
pub use check_move::PARALLEL_RAD;
pub use collide::Collision;
pub use consistency::Inconsistency;
pub use grid::Grid;
pub use labels::{Label, LabelCycle, LabelOrder};
pub use motion::Move;
pub use presence::{ADD_SPOTS, Addition, PresenceError, Removal};
pub use satisfy::{Candidate, Snap};
pub use scene::{Bond, Object, SemanticError, SemanticScene};
pub use spec::{AreaKind, AreaSpec, SemanticSettings, SemanticSpec};
