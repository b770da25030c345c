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

    /// Tip position and Jacobian together, sharing the trigonometry (one
    /// `sin_cos` per joint for both).
    pub fn forward_and_jacobian(&self, theta: &Vector3<f64>) -> (Vector3<f64>, Matrix3<f64>) {
        let (l1, l2) = (self.link1_m, self.link2_m);
        let (s1, c1) = theta[0].sin_cos();
        let (s2, c2) = theta[1].sin_cos();
        let (s3, c3) = theta[2].sin_cos();
        let r = l1 * c2 + l2 * s3;
        let p = Vector3::new(s1 * r, l2 - l2 * c3 + l1 * s2, c1 * r - l1);
        (p, self.jacobian_from_trig([s1, c1, s2, c2, s3, c3]))
    }

    /// Jacobian ∂p/∂θ (metres per radian), column j = joint j.
    pub fn jacobian(&self, theta: &Vector3<f64>) -> Matrix3<f64> {
        let (s1, c1) = theta[0].sin_cos();
        let (s2, c2) = theta[1].sin_cos();
        let (s3, c3) = theta[2].sin_cos();
        self.jacobian_from_trig([s1, c1, s2, c2, s3, c3])
    }

    /// Sines and cosines `[s1, c1, s2, c2, s3, c3]` of the joint angles that
    /// put the tip at `p` (elbow-down branch), from the inverse-kinematics
    /// geometry with three square roots and no trigonometric calls — for the
    /// physics sub-steps. `None` when `p` is on the joint-1 axis or out of
    /// reach (singular).
    pub fn joint_trig_at_position(&self, p: &Vector3<f64>) -> Option<[f64; 6]> {
        let (l1, l2) = (self.link1_m, self.link2_m);
        let zs = p.z + l1;
        let r2 = p.x * p.x + zs * zs;
        let h = p.y - l2;
        let d2 = r2 + h * h;
        let c = (d2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
        if r2 < 1e-18 || !(-1.0..1.0).contains(&c) {
            return None;
        }
        let (r, d) = (r2.sqrt(), d2.sqrt());
        let (s1, c1) = (p.x / r, zs / r);
        // γ = φ − θ2 in (−π, 0): cos γ = c, sin γ = −√(1 − c²).
        let (cg, sg) = (c, -(1.0 - c * c).sqrt());
        // θ2 = α − β with α the angle of the shoulder→tip line and β that of
        // (l1 + l2 cos γ, l2 sin γ), whose length is d (law of cosines).
        let (ca, sa) = (r / d, h / d);
        let (cb, sb) = ((l1 + l2 * cg) / d, l2 * sg / d);
        let (c2, s2) = (ca * cb + sa * sb, sa * cb - ca * sb);
        // θ3 = θ2 + γ + π/2: sin θ3 = cos(θ2 + γ), cos θ3 = −sin(θ2 + γ).
        let (c2g, s2g) = (c2 * cg - s2 * sg, s2 * cg + c2 * sg);
        Some([s1, c1, s2, c2, c2g, -s2g])
    }

    /// The Jacobian at the joint angles that put the tip at `p` (see
    /// [`ArmGeometry::joint_trig_at_position`]).
    pub fn jacobian_at_position(&self, p: &Vector3<f64>) -> Option<Matrix3<f64>> {
        self.joint_trig_at_position(p)
            .map(|t| self.jacobian_from_trig(t))
    }

    /// Tip force F = J⁻ᵀ τ (newtons, device frame) at joint sines/cosines
    /// `trig`, using the arm's structure instead of a general 3×3 inverse: in
    /// the frame turned by θ1 (e1 = (c1, 0, −s1), e2 = y, e3 = (s1, 0, c1)),
    /// τ1 = R f1, τ2 = l1(c2 f2 − s2 f3), τ3 = l2(s3 f2 + c3 f3), whose 2×2
    /// part has determinant cos(θ2 − θ3). `None` when R or that determinant
    /// is below 1e-6 (relative): the arm is singular.
    pub fn force_for_torques_from_trig(
        &self,
        [s1, c1, s2, c2, s3, c3]: [f64; 6],
        torque_nm: &Vector3<f64>,
    ) -> Option<Vector3<f64>> {
        let (l1, l2) = (self.link1_m, self.link2_m);
        let r = l1 * c2 + l2 * s3;
        let det = c2 * c3 + s2 * s3;
        if r.abs() < 1e-6 * l1 || det.abs() < 1e-6 || det.is_nan() {
            return None;
        }
        let f1 = torque_nm[0] / r;
        let (a, b) = (torque_nm[1] / l1, torque_nm[2] / l2);
        let f2 = (c3 * a + s2 * b) / det;
        let f3 = (c2 * b - s3 * a) / det;
        Some(Vector3::new(f1 * c1 + f3 * s1, f2, f3 * c1 - f1 * s1))
    }

    fn jacobian_from_trig(&self, [s1, c1, s2, c2, s3, c3]: [f64; 6]) -> Matrix3<f64> {
        let (l1, l2) = (self.link1_m, self.link2_m);
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

        /// The trig-free Jacobian at a position equals the Jacobian at the
        /// angles that reach it (to round-off, 1e-12 m/rad).
        #[test]
        fn jacobian_at_position_matches_jacobian_at_angles(theta in angles()) {
            for g in [PREMIUM_1_5.geometry, OMNI.geometry] {
                let j = g.jacobian_at_position(&g.forward(&theta)).unwrap();
                prop_assert!((j - g.jacobian(&theta)).norm() < 1e-12, "{j} vs {}", g.jacobian(&theta));
            }
        }

        /// The structured J⁻ᵀ equals the general inverse (relative 1e-12).
        #[test]
        fn structured_force_for_torques_matches_general_inverse(theta in angles(), t1 in -1.0..1.0f64, t2 in -1.0..1.0f64, t3 in -1.0..1.0f64) {
            let g = PREMIUM_1_5.geometry;
            let tau = Vector3::new(t1, t2, t3);
            let trig = g.joint_trig_at_position(&g.forward(&theta)).unwrap();
            let fast = g.force_for_torques_from_trig(trig, &tau).unwrap();
            let general = crate::phantom::motors::force_for_torques(&g, &theta, &tau).unwrap();
            prop_assert!((fast - general).norm() <= 1e-12 * general.norm().max(1.0), "{fast} vs {general}");
        }

        /// The fused routine returns exactly what the separate ones do.
        #[test]
        fn forward_and_jacobian_agree_with_separate_calls(theta in angles()) {
            let g = PREMIUM_1_5.geometry;
            let (p, j) = g.forward_and_jacobian(&theta);
            prop_assert_eq!(p, g.forward(&theta));
            prop_assert_eq!(j, g.jacobian(&theta));
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
