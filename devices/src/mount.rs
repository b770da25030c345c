//! [`Mount`]: where a device sits in the scene (origin, orientation, workspace
//! scale) and how positions, offsets, forces and stiffnesses map between the
//! device frame and the scene frame.
//!
//! With R the orientation and s the scale (scene metres per device metre):
//!
//! ```text
//! p_scene = origin + s R p_device        (points)
//! d_scene = s R d_device                 (offsets, velocities)
//! F_device = s Rᵀ F_scene                (forces)
//! ```
//!
//! The force map is the one that keeps power equal in both frames:
//! F_scene · v_scene = F_scene · (s R v_device) = (s Rᵀ F_scene) · v_device. A
//! scene stiffness K therefore feels like s²K at the device: scaling the
//! workspace up (s > 1) makes walls stiffer for the arm, which matters for
//! stability (compare [`Mount::stiffness_to_device`] with the device's stable
//! stiffness).
//!
//! # Real-time
//! All maps are a quaternion rotation and a scale: no allocation.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::error::DeviceError;
use crate::hand::Trajectory;

/// Placement of one device in the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mount {
    /// Scene position of the device frame's origin, metres.
    pub origin_m_scene: Vector3<f64>,
    /// Orientation of the device frame in the scene.
    pub orientation: UnitQuaternion<f64>,
    /// Workspace scale: scene metres per device metre (> 0).
    pub scale: f64,
}

impl Default for Mount {
    fn default() -> Self {
        Self {
            origin_m_scene: Vector3::zeros(),
            orientation: UnitQuaternion::identity(),
            scale: 1.0,
        }
    }
}

impl Mount {
    /// A mount from scene-file values: quaternion `[w, x, y, z]` (normalised
    /// here), scale > 0. Non-finite values and a zero quaternion are errors.
    pub fn new(
        origin_m_scene: Vector3<f64>,
        orientation_wxyz: [f64; 4],
        scale: f64,
    ) -> Result<Self, DeviceError> {
        if !origin_m_scene.iter().all(|v| v.is_finite()) {
            return Err(DeviceError::InvalidConfig {
                what: "mount origin",
                value: format!("{origin_m_scene:?}"),
                reason: "must be finite",
            });
        }
        let [w, x, y, z] = orientation_wxyz;
        let q = Quaternion::new(w, x, y, z);
        let n = q.norm();
        if !n.is_finite() || n < 1e-12 {
            return Err(DeviceError::InvalidConfig {
                what: "mount orientation",
                value: format!("{orientation_wxyz:?}"),
                reason: "quaternion [w, x, y, z] must be finite and non-zero",
            });
        }
        if !(scale.is_finite() && scale > 0.0) {
            return Err(DeviceError::InvalidConfig {
                what: "workspace scale",
                value: scale.to_string(),
                reason: "scene metres per device metre, finite and > 0",
            });
        }
        Ok(Self {
            origin_m_scene,
            orientation: UnitQuaternion::from_quaternion(q),
            scale,
        })
    }

    /// Registers ("clutches") the device: sets the origin so that the device
    /// point `tip_m_device` maps onto `finger_m_scene`.
    pub fn register(&mut self, tip_m_device: &Vector3<f64>, finger_m_scene: &Vector3<f64>) {
        self.origin_m_scene = finger_m_scene - self.orientation * (tip_m_device * self.scale);
    }

    /// Device point → scene point.
    pub fn point_to_scene(&self, p_device: &Vector3<f64>) -> Vector3<f64> {
        self.origin_m_scene + self.orientation * (p_device * self.scale)
    }

    /// Scene point → device point.
    pub fn point_to_device(&self, p_scene: &Vector3<f64>) -> Vector3<f64> {
        self.orientation
            .inverse_transform_vector(&(p_scene - self.origin_m_scene))
            / self.scale
    }

    /// Device offset or velocity → scene.
    pub fn offset_to_scene(&self, d_device: &Vector3<f64>) -> Vector3<f64> {
        self.orientation * (d_device * self.scale)
    }

    /// Scene offset or velocity → device.
    pub fn offset_to_device(&self, d_scene: &Vector3<f64>) -> Vector3<f64> {
        self.orientation.inverse_transform_vector(d_scene) / self.scale
    }

    /// Scene force → device force (power-preserving: s Rᵀ F).
    pub fn force_to_device(&self, f_scene: &Vector3<f64>) -> Vector3<f64> {
        self.orientation.inverse_transform_vector(f_scene) * self.scale
    }

    /// Device force → scene force (R F / s).
    pub fn force_to_scene(&self, f_device: &Vector3<f64>) -> Vector3<f64> {
        (self.orientation * f_device) / self.scale
    }

    /// Device orientation → scene orientation.
    pub fn orientation_to_scene(&self, q_device: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
        self.orientation * q_device
    }

    /// A scene-frame stiffness as felt by the device, N/m: s²·K.
    pub fn stiffness_to_device(&self, k_scene_n_per_m: f64) -> f64 {
        self.scale * self.scale * k_scene_n_per_m
    }

    /// A scene-frame hand trajectory (offsets) in the device frame.
    pub fn trajectory_to_device(&self, trajectory: &Trajectory) -> Trajectory {
        trajectory.map_offsets(|o| self.offset_to_device(&o))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mount() -> Mount {
        Mount::new(Vector3::new(0.1, -0.2, 0.3), [0.9, 0.1, -0.3, 0.2], 2.5).unwrap()
    }

    #[test]
    fn points_round_trip_and_registration_maps_tip_to_finger() {
        let mut m = mount();
        let p = Vector3::new(0.01, 0.02, -0.03);
        assert!((m.point_to_device(&m.point_to_scene(&p)) - p).norm() < 1e-15);
        let finger = Vector3::new(1.0, 2.0, 3.0);
        m.register(&p, &finger);
        assert!((m.point_to_scene(&p) - finger).norm() < 1e-14);
    }

    #[test]
    fn force_map_preserves_power_and_scales_stiffness() {
        let m = mount();
        let v_dev = Vector3::new(0.1, -0.05, 0.2);
        let f_scene = Vector3::new(1.0, 2.0, -0.5);
        let p_scene = f_scene.dot(&m.offset_to_scene(&v_dev));
        let p_dev = m.force_to_device(&f_scene).dot(&v_dev);
        assert!((p_scene - p_dev).abs() < 1e-14, "{p_scene} vs {p_dev}");
        // A scene spring K displaced by d_scene = s R d_dev pushes back with
        // −K d_scene; at the device that is −s²K d_dev.
        let k = 300.0;
        let d_dev = Vector3::new(0.001, 0.0, 0.0);
        let f_dev = m.force_to_device(&(-m.offset_to_scene(&d_dev) * k));
        assert!((f_dev + d_dev * m.stiffness_to_device(k)).norm() < 1e-12);
        assert!((m.force_to_scene(&m.force_to_device(&f_scene)) - f_scene).norm() < 1e-14);
    }

    #[test]
    fn invalid_values_are_errors() {
        assert!(Mount::new(Vector3::zeros(), [0.0; 4], 1.0).is_err());
        assert!(Mount::new(Vector3::zeros(), [1.0, 0.0, 0.0, 0.0], 0.0).is_err());
        assert!(Mount::new(Vector3::new(f64::NAN, 0.0, 0.0), [1.0, 0.0, 0.0, 0.0], 1.0).is_err());
    }
}
