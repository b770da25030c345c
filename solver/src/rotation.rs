//! The rotation form used everywhere: the **rational** rotation matrix of a
//! (not necessarily unit) Euler-parameter vector e = [w, x, y, z],
//!
//! ```text
//! R(e) = A_h(e) / |e|²,   A_h(e) = (w² − v·v) I + 2 v vᵀ + 2 w [v]×,   v = (x, y, z)
//! ```
//!
//! Why this form and not the homogeneous A_h(e) = |e|² R or Haug's
//! (2w² − 1) I + …: R(e) is an exact rotation for every e ≠ 0, so a body never
//! shrinks or grows when the fast loop lets |e| drift between norm corrections,
//! world points stay rigid, and finger positions and forces read from q mean what
//! they say. Its derivative has e in its null space, so the joint rows are
//! orthogonal to the norm row 2eᵀ (the norm constraint alone sets the scale).
//! The price is one division per body per evaluation.
//!
//! Derivatives are exact for any e ≠ 0 (no unit-norm assumption): for a body-fixed
//! vector c, with u = R(e) c in the world frame,
//!
//! ```text
//! ∂u/∂e = −[u]× Ω(e),    Ω(e) = (2 / |e|²) [ −v | w I + [v]× ]   (3 × 4, columns w, x, y, z)
//! ```
//!
//! Ω maps ė to the world-frame angular velocity, so every constraint first writes
//! its derivative with respect to a world-frame virtual rotation δθ of each body
//! (3 numbers) and one shared helper multiplies by Ω. For unit e, Ω = 2 G_w(e)
//! with the usual G of Eq. 8.

use nalgebra::{Matrix3, Matrix3x4, Quaternion, Vector3};

/// Below this |e|², a quaternion is treated as degenerate (its rotation is
/// undefined). The norm constraint keeps |e| ≈ 1, so this is only reached by
/// corrupted input.
pub const MIN_QUATERNION_NORM_SQUARED: f64 = 1e-12;

/// World-frame pose and derivative map of one body at one configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BodyFrame {
    /// Position of the body origin, metres, world frame.
    pub r: Vector3<f64>,
    /// Rational rotation R(e): body frame → world frame.
    pub rot: Matrix3<f64>,
    /// Ω(e): ∂(world rotation vector)/∂e, 3 × 4, columns ordered w, x, y, z.
    pub omega: Matrix3x4<f64>,
}

impl BodyFrame {
    /// The world frame itself (identity pose).
    pub const IDENTITY: Self = Self {
        r: Vector3::new(0.0, 0.0, 0.0),
        rot: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        omega: Matrix3x4::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    /// Frame of a body with origin `r` and Euler parameters `e = [w, x, y, z]`.
    /// `None` when |e|² is below [`MIN_QUATERNION_NORM_SQUARED`] or not finite.
    #[inline(always)]
    pub fn new(r: Vector3<f64>, e: [f64; 4]) -> Option<Self> {
        let [w, x, y, z] = e;
        let s = w * w + x * x + y * y + z * z;
        if !(s >= MIN_QUATERNION_NORM_SQUARED && s.is_finite()) {
            return None;
        }
        let inv = 1.0 / s;
        let (ww, xx, yy, zz) = (w * w, x * x, y * y, z * z);
        let (xy, xz, yz, wx, wy, wz) = (x * y, x * z, y * z, w * x, w * y, w * z);
        #[rustfmt::skip]
        let rot = Matrix3::new(
            ww + xx - yy - zz, 2.0 * (xy - wz),   2.0 * (xz + wy),
            2.0 * (xy + wz),   ww - xx + yy - zz, 2.0 * (yz - wx),
            2.0 * (xz - wy),   2.0 * (yz + wx),   ww - xx - yy + zz,
        ) * inv;
        let k = 2.0 * inv;
        #[rustfmt::skip]
        let omega = Matrix3x4::new(
            -x * k,  w * k, -z * k,  y * k,
            -y * k,  z * k,  w * k, -x * k,
            -z * k, -y * k,  x * k,  w * k,
        );
        Some(Self { r, rot, omega })
    }

    /// World position of the body-fixed point `c` (metres).
    #[inline]
    pub fn point(&self, c: &Vector3<f64>) -> Vector3<f64> {
        self.r + self.rot * c
    }
}

/// Ω(e) = (2/|e|²) (−v | w I + \[v\]×) (3 × 4, columns w, x, y, z): the map from
/// ė to the world-frame angular velocity, and the map every constraint uses
/// from δθ to its four e columns. `None` for a degenerate quaternion.
///
/// Generalized forces: a world torque τ does virtual work τ·δθ = (Ωᵀτ)·δe, so
/// its generalized force on e is Q_e = Ωᵀτ; back from Q_e (e.g. the e block of
/// C_qᵀλ), τ = (|e|²/4) Ω Q_e, because Ω Ωᵀ = (4/|e|²) I and Ω e = 0. For unit e
/// this is Eq. 8's W = ¼ G W_c with G = Ω.
pub fn angular_map(e: [f64; 4]) -> Option<Matrix3x4<f64>> {
    BodyFrame::new(Vector3::zeros(), e).map(|f| f.omega)
}

/// Rotation matrix of a quaternion given as `[w, x, y, z]` (need not be unit).
/// `None` for a degenerate quaternion.
pub fn rotation_wxyz(e: [f64; 4]) -> Option<Matrix3<f64>> {
    BodyFrame::new(Vector3::zeros(), e).map(|f| f.rot)
}

/// `[w, x, y, z]` of a nalgebra quaternion (whose `coords` are stored `[i, j, k, w]`).
#[inline]
pub fn wxyz(q: &Quaternion<f64>) -> [f64; 4] {
    [q.w, q.i, q.j, q.k]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    #[test]
    fn rotation_matches_nalgebra_and_ignores_scale() {
        let q = UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0);
        let e = wxyz(q.quaternion());
        let r = q.to_rotation_matrix().into_inner();
        let scaled = e.map(|v| v * 1.7);
        assert!((rotation_wxyz(e).unwrap() - r).abs().max() < 1e-15);
        assert!((rotation_wxyz(scaled).unwrap() - r).abs().max() < 1e-15);
        assert!(rotation_wxyz([0.0; 4]).is_none());
    }

    #[test]
    fn torque_round_trips_through_generalized_force() {
        let e = [0.9, -0.3, 0.5, 0.2];
        let s: f64 = e.iter().map(|v| v * v).sum();
        let omega = angular_map(e).unwrap();
        let tau = Vector3::new(0.4, -1.2, 0.7);
        let q_e = omega.transpose() * tau;
        let back = omega * q_e * (s / 4.0);
        assert!((back - tau).norm() < 1e-14);
        let e_vec = nalgebra::Vector4::from(e);
        assert!((omega * e_vec).norm() < 1e-15, "Ω e = 0");
    }
}
