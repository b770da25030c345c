//! Geometry awareness (Choi & Cremer §3): shapes, the broad and narrow
//! phases, nearest-feature witnesses turned into constraint primitives, and
//! the active set that the slow loop maintains. Built on parry3d-f64.
//!
//! | file | what it computes |
//! |---|---|
//! | `shape.rs` | [`Shape`] (scene vocabulary), mass from density, [`Collider`] (core + margin) |
//! | `simplify.rs` | hulls cut to a vertex budget at load, with the distance they moved |
//! | `polyhedron.rs` | hull topology, Voronoi prisms, the support-set feature classifier |
//! | `convert.rs` | nalgebra ↔ parry (glam) conversions, [`Pose3`] |
//! | `broad.rs` | BVH broad phase (no all-pairs scan) |
//! | `narrow.rs` | warm-started GJK on cores: distance, closest points, nearest features |
//! | `sat.rs` | the separating-axis test of two polyhedra (touching and overlapping pairs) |
//! | `pair.rs` | a pair at its poses: frame changes |
//! | `primitives.rs` | feature pair → witness primitives, pre-emptive expansion, slot choice |
//! | `guards.rs` | the pre-emptive edge–edge guards (edges that could cross, corners no vertex guard holds; with `edge_cones`, only pairs that can meet edge on edge) |
//! | `expansion.rs` | subsequent penetration (§3.2.1): a held vertex's neighbours below its face expand the witness to the edge or face |
//! | `active_set.rs` | the slow loop's cycle: add, replace, drop, expand, back up |
//!
//! The witness rows themselves (values and analytic Jacobians) live in
//! `constraint/witness/`, one witness kind per file.

pub mod active_set;
pub mod broad;
pub mod convert;
mod expansion;
mod guards;
pub mod narrow;
pub mod pair;
pub mod polyhedron;
pub mod primitives;
pub mod sat;
pub mod shape;
pub mod simplify;

pub use active_set::{
    ActiveSet, ContactBody, ContactSettings, Cycle, MAX_PAIRS_PER_BODY, PairSpec,
};
pub use convert::Pose3;
pub use polyhedron::{Feature, Polyhedron};
pub use shape::{Collider, DEFAULT_DENSITY_KG_M3, MassProps, Shape, ShapeError};
pub use simplify::{HullSimplification, MAX_HULL_VERTICES};
