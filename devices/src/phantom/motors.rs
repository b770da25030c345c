//! Motor stage: Cartesian force → joint torques (τ = Jᵀ F), torque saturation,
//! and the force those torques produce at the true configuration.
//!
//! Saturation follows libnifalcon and the vendor drivers: when any joint torque
//! exceeds its limit, **all** torques are scaled by the same factor so the force
//! keeps its direction. Each joint's limit is the peak force times its lever arm
//! at the home pose (l1 for joints 1 and 2, l2 for joint 3), so the peak force is
//! reachable in every direction at home.
//!
//! # Real-time
//! Stack arithmetic and one 3×3 inverse: no allocation, constant time.

use nalgebra::{Matrix3, Vector3};

use super::kinematics::ArmGeometry;

/// Joint torques (N·m) that produce the tip force `force_n` (device frame) at
/// joint angles `theta`: τ = Jᵀ F.
pub fn torques_for_force(
    geometry: &ArmGeometry,
    theta: &Vector3<f64>,
    force_n: &Vector3<f64>,
) -> Vector3<f64> {
    geometry.jacobian(theta).transpose() * force_n
}

/// Tip force (N, device frame) produced by joint torques τ at joint angles θ:
/// F = J⁻ᵀ τ. Returns `None` at a singular configuration (|det J| tiny).
pub fn force_for_torques(
    geometry: &ArmGeometry,
    theta: &Vector3<f64>,
    torque_nm: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    force_for_torques_with(geometry, &geometry.jacobian(theta), torque_nm)
}

/// F = J⁻ᵀ τ for a given Jacobian (solves Jᵀ F = τ by Cramer's rule); `None`
/// when |det J| is below 1e-9 of its scale l1·l2·(l1 + l2).
pub fn force_for_torques_with(
    geometry: &ArmGeometry,
    jacobian: &Matrix3<f64>,
    torque_nm: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    let jt = jacobian.transpose();
    let (c0, c1, c2) = (jt.column(0), jt.column(1), jt.column(2));
    let det = c0.dot(&c1.cross(&c2));
    let scale = geometry.link1_m * geometry.link2_m * (geometry.link1_m + geometry.link2_m);
    if det.is_nan() || det.abs() < 1e-9 * scale {
        return None;
    }
    let inv_det = 1.0 / det;
    Some(Vector3::new(
        torque_nm.dot(&c1.cross(&c2)) * inv_det,
        c0.dot(&torque_nm.cross(&c2)) * inv_det,
        c0.dot(&c1.cross(torque_nm)) * inv_det,
    ))
}

/// Per-joint torque limits and the saturation rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorLimits {
    /// Maximum |τ_j|, N·m.
    pub max_torque_nm: Vector3<f64>,
}

impl MotorLimits {
    /// Limits giving `peak_force_n` at the home pose in any direction.
    pub fn for_peak_force(geometry: &ArmGeometry, peak_force_n: f64) -> Self {
        Self {
            max_torque_nm: Vector3::new(
                peak_force_n * geometry.link1_m,
                peak_force_n * geometry.link1_m,
                peak_force_n * geometry.link2_m,
            ),
        }
    }

    /// The factor (≤ 1) that brings every joint of τ within its limit.
    pub fn ratio(&self, torque_nm: &Vector3<f64>) -> f64 {
        let mut ratio: f64 = 1.0;
        for j in 0..3 {
            let t = torque_nm[j].abs();
            if t > self.max_torque_nm[j] {
                ratio = ratio.min(self.max_torque_nm[j] / t);
            }
        }
        ratio
    }

    /// Scales τ uniformly so every joint is within its limit. Returns the
    /// scaled torques and whether scaling happened.
    pub fn saturate(&self, torque_nm: Vector3<f64>) -> (Vector3<f64>, bool) {
        let ratio = self.ratio(&torque_nm);
        if ratio < 1.0 {
            (torque_nm * ratio, true)
        } else {
            (torque_nm, false)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::PREMIUM_1_5;

    #[test]
    fn force_round_trips_through_torques() {
        let g = PREMIUM_1_5.geometry;
        let theta = Vector3::new(0.3, -0.2, 0.4);
        let f = Vector3::new(1.0, -2.0, 0.5);
        let tau = torques_for_force(&g, &theta, &f);
        let back = force_for_torques(&g, &theta, &tau).unwrap();
        assert!((back - f).norm() < 1e-12, "{back}");
    }

    #[test]
    fn saturation_keeps_direction_and_peak_is_reachable_at_home() {
        let g = PREMIUM_1_5.geometry;
        let lim = MotorLimits::for_peak_force(&g, 8.5);
        let home = Vector3::zeros();
        for dir in [
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            Vector3::new(1.0, 1.0, 1.0).normalize(),
        ] {
            let (t, sat) = lim.saturate(torques_for_force(&g, &home, &(dir * 8.5)));
            assert!(!sat, "peak force along {dir} must not saturate at home");
            let f = force_for_torques(&g, &home, &t).unwrap();
            assert!((f.norm() - 8.5).abs() < 1e-9);
        }
        let (t, sat) = lim.saturate(torques_for_force(&g, &home, &Vector3::new(0.0, 20.0, 5.0)));
        assert!(sat);
        let f = force_for_torques(&g, &home, &t).unwrap();
        assert!(f.normalize().dot(&Vector3::new(0.0, 20.0, 5.0).normalize()) > 1.0 - 1e-12);
    }
}
