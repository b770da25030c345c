//! Rolling without slipping (Nelson & Cohen App. E: "nonholonomic …
//! rolling contact velocity constraints"): a ball of radius ρ (body i, its
//! centre at an anchor) on a surface of a fixed body j, whose contact
//! (u, v) a surface contact (`contact`) tracks. The continuous constraint
//! is that the contact point of the ball has no velocity:
//! v + ω × ρ_c = 0 (ρ_c = −ρ n from the centre to the contact); its normal
//! part is the surface contact's own (holonomic) row, so two rows remain.
//!
//! **Discretisation** (a position-based fast loop steps displacements, not
//! velocities): over one tick, with the centre c_s, the orientation R_s,
//! the normal n_s and two unit tangents t_1, t_2 taken at the tick's start
//! (the anchor, [`RollAnchor`]),
//!
//! ```text
//! C_a = t_a · (Δc + θ × ρ_s) = 0,   a = 1, 2,   Δc = c − c_s,
//! θ = log(R R_sᵀ) (the tick's rotation vector, world),   ρ_s = −ρ n_s
//! ```
//!
//! i.e. the contact point's mean velocity over the tick, with the tick's
//! mean linear velocity Δc/dt and angular velocity θ/dt, has no tangential
//! part. For a ball rolling straight on a plane it is exact (|Δc| = ρ |θ|
//! every tick); a curving path or surface makes it first-order accurate in
//! the tick. ∂θ/∂δθ = J_l⁻¹(θ), the inverse left Jacobian of SO(3), so
//! ∂C_a/∂δθ = J_l⁻ᵀ (ρ_s × t_a) plus the centre's lever term.
//!
//! An anchor that is off (never set: a placement's evaluation) makes the
//! rows 0 with no gradient: a rolling constraint says nothing about a
//! position projection.

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::constraint::block::{Ctx, Pair, RowGrad, Sink};

/// The tick-start state of one rolling constraint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RollAnchor {
    /// False: the rows are 0 (no anchor set).
    pub on: bool,
    /// c_s, world, metres.
    pub centre: Vector3<f64>,
    /// R_sᵀ.
    pub rot_t: Matrix3<f64>,
    /// ρ_s = −ρ n_s, world, metres.
    pub rho: Vector3<f64>,
    /// t_1, t_2, world, unit, ⟂ n_s.
    pub tangents: [Vector3<f64>; 2],
}

impl RollAnchor {
    /// No anchor.
    pub const OFF: Self = Self {
        on: false,
        centre: Vector3::new(0.0, 0.0, 0.0),
        rot_t: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        rho: Vector3::new(0.0, 0.0, 0.0),
        tangents: [Vector3::new(0.0, 0.0, 0.0); 2],
    };
}

/// The rolling rows of a ball: end 0 the ball (its anchor the centre), end
/// 1 the fixed body of the surface; `contact` indexes the model's surface
/// contacts (the one that tracks this ball), `slot` the anchor table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rolling {
    pub pair: Pair,
    pub contact: u32,
    pub slot: u32,
}

/// The rotation vector of a rotation matrix: θ = atan2(s, c) along the
/// skew part's axis (s = |skew|, c = (tr − 1)/2), robust at θ = 0 where
/// `acos((tr − 1)/2)` of a matrix rounded to a trace of 3 + ε is NaN.
pub fn log_rotation(m: &Matrix3<f64>) -> Vector3<f64> {
    let w = Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5;
    let (s, c) = (w.norm(), 0.5 * (m.trace() - 1.0));
    let theta = s.atan2(c);
    if s == 0.0 {
        Vector3::zeros()
    } else if theta < 3.0 {
        w * (theta / s)
    } else {
        // Near π the skew part carries no axis: nalgebra's symmetric form.
        Rotation3::from_matrix_unchecked(*m).scaled_axis()
    }
}

/// J_l⁻¹(θ) = I − ½[θ]× + (1/|θ|² − (1 + cos|θ|)/(2|θ| sin|θ|)) [θ]×².
pub(crate) fn inv_left_jacobian(theta: &Vector3<f64>) -> Matrix3<f64> {
    let a = theta.norm();
    let k = theta.cross_matrix();
    let c = if a < 1e-4 {
        1.0 / 12.0 + a * a / 720.0
    } else {
        1.0 / (a * a) - (1.0 + a.cos()) / (2.0 * a * a.sin())
    };
    Matrix3::identity() - k * 0.5 + k * k * c
}

impl Rolling {
    pub const ROWS: usize = 2;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let a = match x.rolling.get(self.slot as usize) {
            Some(a) if a.on => *a,
            _ => {
                c[..2].fill(0.0);
                sink.row(0, &RowGrad::default());
                sink.row(1, &RowGrad::default());
                return;
            }
        };
        let pts = self.pair.points(x);
        let rot = x.frame(self.pair.frame[0]).rot * a.rot_t;
        let theta = log_rotation(&rot);
        let jt = inv_left_jacobian(&theta).transpose();
        let d = pts[0].p - a.centre;
        for (k, t) in a.tangents.iter().enumerate() {
            let arm = a.rho.cross(t);
            c[k] = t.dot(&d) + arm.dot(&theta);
            let mut g = RowGrad::default();
            g.point(0, &pts[0].lever, t);
            g.ang[0] += jt * arm;
            sink.row(k, &g);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The log of R Rᵀ (identity up to rounding) is 0, not NaN; elsewhere
    /// it is nalgebra's.
    #[test]
    fn log_rotation_is_finite_at_identity() {
        let r = Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner();
        assert!(log_rotation(&(r * r.transpose())).norm() < 1e-15);
        for v in [Vector3::new(0.3, -0.2, 0.5), Vector3::new(1e-9, 0.0, 2e-9)] {
            let m = Rotation3::from_scaled_axis(v).into_inner();
            assert!((log_rotation(&m) - v).norm() < 1e-15 * (1.0 + v.norm()) + 1e-24);
        }
    }

    /// log(exp(δθ) exp(θ)) − θ ≈ J_l⁻¹(θ) δθ, by central differences.
    #[test]
    fn inverse_left_jacobian_matches_finite_differences() {
        for theta in [
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(1e-6, 2e-6, -1e-6),
            Vector3::new(2.0, 0.5, -1.0),
        ] {
            let r = Rotation3::from_scaled_axis(theta);
            let j = inv_left_jacobian(&theta);
            let h = 1e-6;
            for k in 0..3 {
                let d = Vector3::ith(k, h);
                // nalgebra's `scaled_axis` (an acos) loses ~1e-5 of a
                // 1e-6 rad rotation; `log_rotation` does not.
                let plus = log_rotation((Rotation3::from_scaled_axis(d) * r).matrix());
                let minus = log_rotation((Rotation3::from_scaled_axis(-d) * r).matrix());
                let fd = (plus - minus) / (2.0 * h);
                assert!(
                    (fd - j.column(k)).norm() < 1e-8,
                    "{theta}: {fd} vs {}",
                    j.column(k)
                );
            }
        }
    }
}
