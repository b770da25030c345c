//! A rigid motion of an object and its group: a rotation r (axis × angle,
//! world frame) about a centre c, then a translation t:
//! p ↦ c + R(r)(p − c) + t. §5's (t, r) pairs, with the centre made explicit
//! (the snap of §5.1 rotates about the binding area's centroid; an
//! interactive move about the object's origin).

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::geometry::Pose3;

/// See the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    /// Centre of the rotation, world frame, m.
    pub center: Vector3<f64>,
    /// Translation after the rotation, world frame, m.
    pub t: Vector3<f64>,
    /// Rotation vector (unit axis × angle), world frame, rad.
    pub r: Vector3<f64>,
}

impl Move {
    /// No motion (t ← 0, r ← 0 of Algorithm 2) about `center`.
    pub fn none(center: Vector3<f64>) -> Self {
        Self {
            center,
            t: Vector3::zeros(),
            r: Vector3::zeros(),
        }
    }

    /// True for the identical transformation.
    pub fn is_none(&self) -> bool {
        self.t == Vector3::zeros() && self.r == Vector3::zeros()
    }

    /// The rotation matrix R(r).
    pub fn rotation(&self) -> Matrix3<f64> {
        Rotation3::from_scaled_axis(self.r).into_inner()
    }

    /// `pose` moved.
    pub fn apply(&self, pose: &Pose3) -> Pose3 {
        let rot = self.rotation();
        Pose3 {
            r: self.center + rot * (pose.r - self.center) + self.t,
            rot: rot * pose.rot,
        }
    }

    /// Whether `other` is this motion (Algorithm 1, line 6: checkMove "does
    /// not change (t, r)"), to round-off: translations within 1e-9 m,
    /// rotations within 1e-9 rad.
    pub fn same_as(&self, other: &Move) -> bool {
        (self.t - other.t).norm() <= 1e-9 && (self.r - other.r).norm() <= 1e-9
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_centre_stays_put_under_the_rotation() {
        let m = Move {
            center: Vector3::new(1.0, 2.0, 3.0),
            t: Vector3::new(0.0, 0.0, 0.5),
            r: Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        };
        let p = m.apply(&Pose3 {
            r: Vector3::new(2.0, 2.0, 3.0),
            rot: Matrix3::identity(),
        });
        assert!((p.r - Vector3::new(1.0, 3.0, 3.5)).norm() < 1e-12);
        assert!((p.rot * Vector3::x() - Vector3::y()).norm() < 1e-12);
    }
}
