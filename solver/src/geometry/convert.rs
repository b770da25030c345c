//! Conversions between the solver's nalgebra values and parry's glam types.
//! parry3d-f64 works in `DVec3` / `DPose3` (`f64`); the solver in nalgebra.

use nalgebra::{Matrix3, Vector3};
use parry3d_f64::glamx::{DMat3, DQuat};
use parry3d_f64::math::{Pose, Vector};

/// nalgebra → glam.
#[inline]
pub(crate) fn to_glam(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

/// glam → nalgebra.
#[inline]
pub(crate) fn to_na(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

/// A rigid pose in the world frame: origin `r` (metres) and rotation `rot`
/// (body → world, orthonormal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose3 {
    /// Origin, metres, world frame.
    pub r: Vector3<f64>,
    /// Body → world rotation.
    pub rot: Matrix3<f64>,
}

impl Pose3 {
    /// The identity pose.
    pub const IDENTITY: Self = Self {
        r: Vector3::new(0.0, 0.0, 0.0),
        rot: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    };

    /// World position of the body-frame point `p`.
    #[inline]
    pub fn point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.r + self.rot * p
    }

    /// World direction of the body-frame vector `v`.
    #[inline]
    pub fn dir(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.rot * v
    }

    /// Body-frame coordinates of the world point `p`.
    #[inline]
    pub fn local_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rot.tr_mul(&(p - self.r))
    }

    /// Body-frame coordinates of the world vector `v`.
    #[inline]
    pub fn local_dir(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.rot.tr_mul(v)
    }

    /// The same pose as parry's `Pose`.
    pub fn to_parry(&self) -> Pose {
        let m = &self.rot;
        let mat = DMat3::from_cols(
            to_glam(&m.column(0).into_owned()),
            to_glam(&m.column(1).into_owned()),
            to_glam(&m.column(2).into_owned()),
        );
        Pose::from_parts(to_glam(&self.r), DQuat::from_mat3(&mat).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{UnitQuaternion, Vector3};

    #[test]
    fn parry_pose_maps_points_like_the_rotation_matrix() {
        let q = UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0);
        let pose = Pose3 {
            r: Vector3::new(0.1, -0.2, 0.3),
            rot: q.to_rotation_matrix().into_inner(),
        };
        let p = Vector3::new(0.4, 0.5, -0.6);
        let a = pose.point(&p);
        let b = to_na(pose.to_parry().transform_point(to_glam(&p)));
        assert!((a - b).norm() < 1e-14, "{a} vs {b}");
        assert!((pose.local_point(&a) - p).norm() < 1e-14);
    }
}
