//! The fast update that keeps a mechanism assembled around the user's fingers:
//! Nelson & Cohen's augmented-Lagrangian iteration (Eq. 1–3,
//! [`UpdateRule::Gradient`]) and a Gauss–Newton projection that reuses the
//! force solve's factor ([`UpdateRule::Projected`], the default; see
//! `projected`). This page documents the first; the second shares its
//! finger formulation and pull limit.
//!
//! ```text
//! Δq = −W⁻¹ (f_qᵀ + C_qᵀ (λ + K C)),   q ← q + h Δq,   λ ← λ + k₂ C
//! ```
//!
//! - **Objective** f = ½‖q − q₀‖²_W (least astonishment, q₀ the previous
//!   tick's q), W = diag(1 on r and design variables, L² on Euler parameters).
//! - **K rule** (details in `scaling`): every row is measured in metres (angle
//!   and quaternion-norm rows times L, the model's largest lever arm) and so is
//!   every column (Euler parameters times L); K_i = K ℓ_i², k₂_i = k₂ ℓ_i². It
//!   is Eq. 3 verbatim in those scaled coordinates. Without it (L = 1) the
//!   rotational rows of a 5 cm mechanism converge tens of times slower than the
//!   translational ones (tested, and in the trade-off table).
//! - **Step**: h = step / (1 + K σ_max), σ_max the largest eigenvalue of the
//!   scaled Gram matrix, measured once per program; `step` ≤ 1 keeps every
//!   mode contracting (stability analysis in `scaling`).
//! - **One pass** (`fused`): C and C_qᵀ w are formed together, per body in
//!   world form, without writing the Jacobian: 2.0–2.3× faster than
//!   evaluating C_q and multiplying (BENCHMARKS.md).
//! - **Inequalities** (joint limits, contact witnesses, C ≥ 0) use the
//!   projected multiplier ν ≥ 0; an inactive row contributes nothing.
//! - **Redundant rows** (linearly dependent on the others at q0, e.g. the
//!   repeated out-of-plane rows of a planar loop of spatial revolutes) are
//!   found once by `Program::new` (`force::redundancy`) and masked in both
//!   rules: gain 0, multiplier 0, still evaluated and reported.
//! - **Fingers are penalty rows** (a weighted finger-distance objective term,
//!   Nelson & Cohen §4), not multiplier rows. A finger the mechanism cannot
//!   follow (a 1-DOF four-bar and a 3-D target) would wind an AL multiplier up
//!   without bound; as a penalty it pulls with K·ℓ²·error, the joints'
//!   multipliers settle at the opposing load (bounded), and the mechanism
//!   takes the closest configuration it can reach. The user feels the rest
//!   through the virtual coupling (see [`crate::force`]). The price is a lag of
//!   order 1/K of a tick's motion at a tick's fixed point, negligible at the
//!   default K = 1000; the real lag comes from the iteration's linear
//!   convergence and is what the trade-off table measures.
//!
//! Multipliers here are the optimisation's λ, not physical forces: the
//! physical load on a finger comes from Eq. 7 ([`crate::force`]).

pub(crate) mod design;
mod design_closure;
pub(crate) mod fused;
mod moved;
mod prediction;
pub(crate) mod projected;
pub(crate) mod scaling;
mod settings;
pub(crate) mod update;

pub use settings::{
    Coordinates, ForceSolver, InvalidSetting, RedundancyCheck, SolverSettings, UpdateRule,
};
