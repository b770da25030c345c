//! Kinematics of the 3-actuated-joint PHANToM arm (Cavusoglu et al. model).
//!
//! Joint 1 turns the whole arm about the vertical axis; joint 2 lifts the upper
//! link (angle θ2 from horizontal); joint 3 is the forearm angle θ3 measured from
//! the vertical, absolute (not relative to link 1) because the forearm is driven
//! through a parallelogram / second capstan from the base. With l1, l2 the link
//! lengths, the tip (gimbal centre) in the device frame is
//!
//! ```text
//! R = l1 cos θ2 + l2 sin θ3
//! x = sin θ1 · R
//! y = l2 − l2 cos θ3 + l1 sin θ2
//! z = cos θ1 · R − l1
//! ```
//!
//! so θ = 0 is the home pose at the origin (upper link horizontal toward the
//! user, forearm vertical down). The frame matches OpenHaptics: y up, z toward
//! the user.
//!
//! # Real-time
//! Every function here is a handful of trigonometric calls on stack values: no
//! allocation, no locks, constant time.

use nalgebra::{Matrix3, Vector3};

/// Link lengths of the arm, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmGeometry {
    /// Upper link (shoulder to elbow), metres.
    pub link1_m: f64,
    /// Forearm (elbow to gimbal centre), metres.
    pub link2_m: f64,
}

impl ArmGeometry {
    /// Tip position, metres, device frame, for joint angles θ (radians).
    pub fn forward(&self, theta: &Vector3<f64>) -> Vector3<f64> {
        let (l1, l2) = (self.link1_m, self.link2_m);
        let (s1, c1) = theta[0].sin_cos();
        let (s2, c2) = theta[1].sin_cos();
        let (s3, c3) = theta[2].sin_cos();
        let r = l1 * c2 + l2 * s3;
        Vector3::new(s1 * r, l2 - l2 * c3 + l1 * s2, c1 * r - l1)
    }

    /// Jacobian ∂p/∂θ (metres per radian), column j = joint j.
    pub fn jacobian(&self, theta: &Vector3<f64>) -> Matrix3<f64> {
        let (l1, l2) = (self.link1_m, self.link2_m);
        let (s1, c1) = theta[0].sin_cos();
        let (s2, c2) = theta[1].sin_cos();
        let (s3, c3) = theta[2].sin_cos();
        let r = l1 * c2 + l2 * s3;
        #[rustfmt::skip]
        let j = Matrix3::new(
            c1 * r,  -s1 * l1 * s2, s1 * l2 * c3,
            0.0,      l1 * c2,      l2 * s3,
            -s1 * r, -c1 * l1 * s2, c1 * l2 * c3,
        );
        j
    }

    /// Joint angles for a tip position (the elbow-down branch the arm is built
    /// in). Points out of reach are projected onto the reachable shell (arm
    /// straight); the return value says whether that happened.
    pub fn inverse(&self, p: &Vector3<f64>) -> (Vector3<f64>, bool) {
        let (l1, l2) = (self.link1_m, self.link2_m);
        let zs = p.z + l1;
        let theta1 = p.x.atan2(zs);
        let r = (p.x * p.x + zs * zs).sqrt();
        let h = p.y - l2;
        // Planar two-link arm in (r, h): link 1 at angle θ2, link 2 at φ = θ3 − π/2.
        let d2 = r * r + h * h;
        let c = (d2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
        let clamped = !(-1.0..=1.0).contains(&c);
        let gamma = -c.clamp(-1.0, 1.0).acos(); // φ − θ2, elbow down: in [−π, 0]
        let theta2 = h.atan2(r) - (l2 * gamma.sin()).atan2(l1 + l2 * gamma.cos());
        let theta3 = theta2 + gamma + std::f64::consts::FRAC_PI_2;
        (Vector3::new(theta1, theta2, theta3), clamped)
    }

    /// Distance from the shoulder (joint 2 axis) to the tip, metres; the arm
    /// is straight (singular) at `link1_m + link2_m`.
    pub fn reach(&self, p: &Vector3<f64>) -> f64 {
        let zs = p.z + self.link1_m;
        let h = p.y - self.link2_m;
        (p.x * p.x + zs * zs + h * h).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::{OMNI, PREMIUM_1_5};
    use proptest::prelude::*;

    fn angles() -> impl Strategy<Value = Vector3<f64>> {
        // The usable joint range around home, away from the straight-arm singularity.
        (-0.9..0.9f64, -0.6..0.8f64, -0.5..0.7f64).prop_map(|(a, b, c)| Vector3::new(a, b, c))
    }

    #[test]
    fn home_pose_is_origin() {
        let p = PREMIUM_1_5.geometry.forward(&Vector3::zeros());
        assert!(p.norm() < 1e-15, "{p}");
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(7), ..ProptestConfig::default() })]

        /// Central differences with step 1e-6 rad have truncation error
        /// ~ l·h²/6 ≈ 4e-14 m and round-off ~ 1e-16/1e-6 = 1e-10: 1e-8 m/rad is a
        /// tolerance that a wrong sign or factor (≥ 1e-2) cannot pass.
        #[test]
        fn jacobian_matches_central_differences(theta in angles()) {
            for g in [PREMIUM_1_5.geometry, OMNI.geometry] {
                let j = g.jacobian(&theta);
                let h = 1e-6;
                for col in 0..3 {
                    let mut tp = theta; tp[col] += h;
                    let mut tm = theta; tm[col] -= h;
                    let fd = (g.forward(&tp) - g.forward(&tm)) / (2.0 * h);
                    prop_assert!((fd - j.column(col)).norm() < 1e-8, "col {col}: fd {fd} vs {}", j.column(col));
                }
            }
        }

        /// IK inverts FK on the elbow-down branch to round-off (1e-9 rad).
        #[test]
        fn inverse_inverts_forward(theta in angles()) {
            for g in [PREMIUM_1_5.geometry, OMNI.geometry] {
                let (back, clamped) = g.inverse(&g.forward(&theta));
                prop_assert!(!clamped);
                prop_assert!((back - theta).norm() < 1e-9, "{theta} -> {back}");
            }
        }

        /// Virtual work: τ = Jᵀ F does the same work on a small joint motion δθ
        /// as F does on the tip motion J δθ (exact identity up to round-off), and
        /// to first order on the true displacement p(θ+δθ) − p(θ).
        #[test]
        fn transpose_jacobian_torque_by_virtual_work(theta in angles(), fx in -5.0..5.0f64, fy in -5.0..5.0f64, fz in -5.0..5.0f64) {
            let g = PREMIUM_1_5.geometry;
            let f = Vector3::new(fx, fy, fz);
            let tau = crate::phantom::motors::torques_for_force(&g, &theta, &f);
            let dtheta = Vector3::new(1e-7, -2e-7, 1.5e-7);
            let work_joint = tau.dot(&dtheta);
            let work_tip = f.dot(&(g.forward(&(theta + dtheta)) - g.forward(&theta)));
            // Second-order remainder: |F|·l·|δθ|² ≈ 9·0.42·1e-13 ≈ 4e-13 J.
            prop_assert!((work_joint - work_tip).abs() < 1e-12, "{work_joint} vs {work_tip}");
        }
    }
}
