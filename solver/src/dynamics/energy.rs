//! Energy accounting of inertial motion: the mechanical energy of the moving
//! bodies and the work the fingers did on them.
//!
//! Each tick's step carries the bodies from t_n to t_{n+1} at the step's
//! velocity (the secant, the velocity of the step's middle), so the program
//! reports the energy of the middle of the step:
//!
//! ```text
//! E_{n+½} = Σ_b ½ m |v|² + ½ ω·l − m g·(r_n + r_{n+1})/2,   l = J_w ω
//! ```
//!
//! (second-order accurate; fingertips carry no weight), after restitution
//! has acted (a bounce is then a drop of E, never a dip and a rise), and
//! the work the finger rows did up to the same instant: Σ over ticks of
//! their force in the step, −y_i / dt² (the constraint force M (q − q̂)/dt²
//! of row i), times the row's motion J_i Δq, half of this tick's. A
//! simulation that adds energy the fingers did not put in shows as E − W
//! rising: the session reports the largest such rise (`max_injected_j`).

use nalgebra::Vector3;

use super::velocity::Velocities;
use crate::Jacobian;
use crate::force::inertia::BodyMass;

/// The energy figures of one tick (all NaN-free when `valid`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnergySample {
    /// False: no figure this tick (inertial motion off, or the tick failed).
    pub valid: bool,
    /// Kinetic + potential energy of the moving bodies in the middle of the
    /// tick's step, J (potential: −m g·r, zero at the world origin).
    pub energy_j: f64,
    /// Work the fingers did on the bodies from the program's start up to the
    /// middle of the tick's step, J.
    pub finger_work_j: f64,
}

/// E_{n+½} of the bodies over the step from `q_ref` to `q` (module docs).
///
/// # Real-time
/// No allocation; O(bodies).
pub(crate) fn mechanical(
    masses: &[BodyMass],
    vel: &Velocities,
    q_ref: &[f64],
    q: &[f64],
    g: &Vector3<f64>,
) -> f64 {
    let mut e = 0.0;
    for (k, m) in masses.iter().enumerate() {
        let o = m.offset;
        e += 0.5 * m.mass * vel.v[k].norm_squared() + 0.5 * vel.w[k].dot(&vel.l[k]);
        if m.weighs {
            let mid = Vector3::new(
                q_ref[o] + q[o],
                q_ref[o + 1] + q[o + 1],
                q_ref[o + 2] + q[o + 2],
            ) * 0.5;
            e -= m.mass * g.dot(&mid);
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
