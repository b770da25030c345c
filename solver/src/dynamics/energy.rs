//! Energy accounting of inertial motion: the mechanical energy of the moving
//! bodies and the work the fingers did on them.
//!
//! At the start t_n of each tick the program knows the velocity of the two
//! steps around it (a tick's step ends at t_{n+1}), so it reports
//!
//! ```text
//! E_n = Σ_b ½ m |v̄|² + ½ ω̄ᵀ J_w ω̄ − m g·r,     v̄ = (v_{n−½} + v_{n+½}) / 2
//! ```
//!
//! (second-order accurate at t_n; fingertips carry no weight), and the work
//! of the finger rows up to t_n: Σ over ticks of their force in the step,
//! −y_i / dt² (the constraint force M (q − q̂)/dt² of row i), times the
//! row's motion J_i Δq. A simulation that adds energy the fingers did not
//! put in shows as E − W rising: the session reports the largest such rise
//! (`max_injected_j`).

use nalgebra::Vector3;

use super::velocity::{Velocities, frame};
use crate::Jacobian;
use crate::force::inertia::BodyMass;

/// The energy figures of one tick (all NaN-free when `valid`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnergySample {
    /// False: no figure this tick (inertial motion off, or the tick failed).
    pub valid: bool,
    /// Kinetic + potential energy of the moving bodies at the tick's start,
    /// J (potential: −m g·r, zero at the world origin).
    pub energy_j: f64,
    /// Work the fingers did on the bodies from the program's start up to the
    /// tick's start, J.
    pub finger_work_j: f64,
}

/// E_n of the bodies at `q_ref` with the velocities around it (module docs).
///
/// # Real-time
/// No allocation; O(bodies).
pub(crate) fn mechanical(
    masses: &[BodyMass],
    vel: &Velocities,
    q_ref: &[f64],
    g: &Vector3<f64>,
) -> f64 {
    let mut e = 0.0;
    for (k, m) in masses.iter().enumerate() {
        let Some(f) = frame(q_ref, m.offset) else {
            continue;
        };
        let (v, w) = vel.at_start(k);
        e += 0.5 * m.mass * v.norm_squared() + 0.5 * w.dot(&(m.world_inertia(&f) * w));
        if m.weighs {
            e -= m.mass * g.dot(&f.r);
        }
    }
    e
}

/// The work of the finger rows `rows` over a step that moved q by `dq`,
/// with the step's multipliers `y` (scaled as the step applied them), J.
///
/// # Real-time
/// No allocation; O(nonzeros of the finger rows).
pub(crate) fn finger_work(jac: &Jacobian, rows: &[usize], y: &[f64], dq: &[f64], dt_s: f64) -> f64 {
    let (ptr, cols, vals) = (jac.row_ptr(), jac.col_idx(), jac.values());
    let mut w = 0.0;
    for &i in rows {
        let motion: f64 = (ptr[i]..ptr[i + 1]).map(|p| vals[p] * dq[cols[p]]).sum();
        w -= y[i] * motion;
    }
    w / (dt_s * dt_s)
}
