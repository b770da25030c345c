//! Flexible bodies (Nelson & Cohen §4, Eq. 4, Eq. 6's K_f q_f, Fig. 9 and
//! the creature's belly of Fig. 13): a moving body whose points move with
//! deformation coordinates q_f besides its floating frame (r, e).
//!
//! | file | what |
//! |---|---|
//! | `beam.rs` | the beam: Rayleigh–Ritz bending modes, stiffness K_f, modal mass, gravity load |
//! | `anchor.rs` | a deforming point k + Φ(k) q_f and its Jacobian Φᵀ Rᵀ n |
//! | `body.rs` | the compiled flexible body: its columns and Eq. 7's generalized force |
//!
//! **Coordinates.** A body with `flexible = { … }` keeps its 7 columns; its
//! 2n deformation columns (y modes, then z modes, metres) sit in the
//! auxiliary block at the end of q (`model::auxiliary`), named
//! `<body>.flex`. A model without flexible bodies has no such columns and
//! compiles exactly as before.
//!
//! **Joints and fingers** attach at any point of the span: a point off the
//! clamp (x ≠ x_c) becomes a deforming anchor (`Param3::Flex`), so spherical,
//! distance and point-on-plane joints, point fingers and objectives' points
//! follow the deformation. Axes are the floating frame's, which is the
//! beam's section at the clamp x_c only: a joint that uses axes or a relative
//! orientation (revolute, universal, prismatic, fixed, point-on-plane on the
//! flexible side's plane) or a rigid grasp must sit at the clamp, or the
//! build says so.
//!
//! **The fast update** (`al::projected`) minimises, per tick, the
//! least-astonishment term ½‖q − q₀‖²_M of the rigid columns plus the strain
//! energy U = ½ q_fᵀ K_f q_f (Eq. 4) of the deformation columns, subject to
//! the joints and with the fingers' penalty: the deformation columns have
//! metric K_f and rest value 0 instead of the mass and the previous tick's
//! q. So the deformation is static within every tick (the Gauss–Newton step
//! on a quadratic U is exact): Fig. 9's "inverse kinematics with flexible
//! body degrees of freedom" with Eq. 4 as the objective that "prevents large
//! deformations". U is in joules against the rigid term's kg·m² (a motion
//! over one second): a finger pulls a beam of tip stiffness k to within
//! k / (k + K w m̄) of its target (K the gain, w the finger weight, m̄ the
//! mean mass); a flexible scene gives its fingers the weight that makes that
//! small.
//!
//! **Eq. 7** gets the elastic force in Q: b_f = −K_f q_f − M_f q̈_f + g_f
//! (`body.rs`), and the deformation columns take part in the weighted least
//! squares with weight K_f⁻¹ (the same factor the update uses). Left out:
//! the inertial coupling of deformation with rigid motion (M_rf, M_θf of the
//! floating-frame formulation): the body's rigid mass and inertia are its
//! own, as for any body.

pub(crate) mod anchor;
pub(crate) mod beam;
pub(crate) mod body;
mod query;

pub use beam::{BeamSpec, MAX_MODES};
