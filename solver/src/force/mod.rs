//! Force feedback: the load the mechanism puts on each finger (Nelson & Cohen
//! Eq. 5–8), plus a virtual coupling.
//!
//! **Sign convention (everywhere in this crate):** outputs are the force and
//! torque **on the finger**, world frame, i.e. what the device should render.
//! A body of mass m hanging from a point finger under gravity g = (0, 0, −9.81)
//! gives F = m g (pulls the finger down); carried with acceleration a it gives
//! F = m (g − a), the opposite of the force m (a − g) the finger applies.
//!
//! Pipeline per tick (`feedback`), at the tick's final q:
//! 1. **Motion** (`motion`): body velocities and accelerations by backward
//!    differences of q over ticks, optionally low-pass filtered.
//! 2. **Right-hand side** (`inertia`): b = Q_e + Q_v − M q̈ per body, with
//!    M and Q_v derived for the rational rotation R(e) = A_h(e)/|e|².
//! 3. **Multipliers** (`gram`, `solve`): Eq. 7, C_qᵀλ = b, solved in the
//!    least-squares sense through the normal equations of C_q M⁻¹ C_qᵀ. The
//!    AL multipliers cannot be used: they pull q toward q₀, they are not loads.
//!    Joints first, then the smallest finger load that balances the rest
//!    (Schur complement, pseudo-inverse): a finger feels only what the joints
//!    cannot carry, the component of b along the mechanism's free motions.
//!    Minimum norm over *all* rows would instead split a statically
//!    indeterminate load between rigid joints and the finger in proportions
//!    that depend on the rows' units. Rows masked as redundant (below) are
//!    left out of A's pattern: multiplier exactly 0.
//! 4. **Wrench** (`wrench`): Eq. 8, W = (|e|²/4) Ω W_c (¼ G W_c for unit e),
//!    the finger's world force and its torque about the attachment point.
//! 5. **Virtual coupling**: F_c = k (p − t) + b d(p − t)/dt between the
//!    attachment point p and the device point t, reported separately. In
//!    directions the mechanism follows, p ≈ t and F_c is negligible; in
//!    directions it cannot move (a 1-DOF linkage, a joint at its limit) the
//!    error grows and F_c is the wall the user feels.
//!
//! Joint torques (`torque`, §5.2): for the joints a scene names, the
//! torque a motor on each axis would need to make the motion in place of the
//! fingers, from the same factor and right-hand side.
//!
//! Contact rows (`friction`): witness rows are inequality rows of the joint
//! block (active while pushing or penetrating, released when they would
//! pull); a fingertip's friction stick rows take part while the Coulomb cone
//! holds and are released (slip) when it does not.
//!
//! Once per program (`redundancy`, on the slow thread): rows linearly
//! dependent on the others at q0 ([`Redundancy`]) are found by a cheap
//! conditioning test and, when it fails, a dense ordered QR; they are masked
//! from every solve so that C_q M⁻¹ C_qᵀ stays positive definite.
//!
//! [`reference_finger_wrenches`] solves the same physics densely by the
//! null-space method (tests, and the slow thread's force-error measurement):
//! an SVD null space of the joint rows and a minimum-norm (pseudo-inverse)
//! finger load, so it needs no masking and checks the masked fast path.

mod cg;
pub(crate) mod feedback;
pub mod friction;
mod gram;
pub(crate) mod inertia;
mod motion;
/// The acceleration filter's time constant over the velocity filter's
/// (`reduced/` differences the motion the same way).
pub(crate) use motion::ACCELERATION_FILTER_FRACTION;
mod output;
mod pcg;
mod pivoted;
mod precond;
mod rank_one;
mod redundancy;
mod reference;
pub(crate) mod small;
mod small_fixed;
mod solve;
mod torque;
mod wrench;

#[cfg(test)]
mod tests_dense;
#[cfg(test)]
mod tests_pivoted;

pub use output::FingerOutput;
pub use pivoted::{PivotedTally, eigensolve_only, pivoted_solves, pivoted_tally};
pub use precond::multilevel::MultilevelStats;
pub use precond::tree::TreeStats;
pub use redundancy::{PRETEST_RATIO, REDUNDANCY_TOLERANCE, Redundancy};
pub use reference::{
    FingerWrench, INEQUALITY_ACTIVE_BAND, ReferenceError, reference_finger_wrenches,
};
pub use solve::LowRankTally;
pub use wrench::body_wrench;
