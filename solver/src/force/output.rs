//! [`FingerOutput`]: what the force computation hands back per finger after a
//! tick (the program passes it on to the session).

use nalgebra::Vector3;

/// One finger's output after a tick. World frame throughout.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerOutput {
    /// Total force **on the finger** (what the device should render), newtons:
    /// `constraint_force_n + coupling_force_n`. A body hanging from the finger
    /// under gravity gives m g (pointing down); carried with acceleration a it
    /// gives m (g − a).
    pub force_n: Vector3<f64>,
    /// Total torque on the finger about its attachment point, N·m (rigid
    /// grasps; zero for point grasps).
    pub torque_nm: Vector3<f64>,
    /// The Eq. 7–8 part: the load the mechanism's inertia, gravity and
    /// velocity terms put on the finger constraint, N.
    pub constraint_force_n: Vector3<f64>,
    /// The Eq. 7–8 torque about the attachment point, N·m.
    pub constraint_torque_nm: Vector3<f64>,
    /// The virtual-coupling part, k (p − t) + b d(p − t)/dt, N: pulls the
    /// finger toward the attachment point p; the rigidity the user feels in
    /// directions the mechanism cannot follow.
    pub coupling_force_n: Vector3<f64>,
    /// Torsional coupling torque (rigid grasps), N·m.
    pub coupling_torque_nm: Vector3<f64>,
    /// The finger's attachment point on the mechanism, metres.
    pub attachment_m: Vector3<f64>,
    /// The target (device point) this tick, metres.
    pub target_m: Vector3<f64>,
    /// |attachment − target|, metres.
    pub tracking_error_m: f64,
}

impl Default for FingerOutput {
    fn default() -> Self {
        let z = Vector3::zeros();
        Self {
            force_n: z,
            torque_nm: z,
            constraint_force_n: z,
            constraint_torque_nm: z,
            coupling_force_n: z,
            coupling_torque_nm: z,
            attachment_m: z,
            target_m: z,
            tracking_error_m: 0.0,
        }
    }
}

impl FingerOutput {
    /// True when every number is finite and so is every vector's length:
    /// a force of 1e300 N (gravity of −1e300 m/s² on a body) has finite
    /// components but an infinite magnitude, which no safety layer can
    /// clamp to a device's peak; such a tick is a failure, not a 0 N write.
    pub fn is_finite(&self) -> bool {
        [
            &self.force_n,
            &self.torque_nm,
            &self.constraint_force_n,
            &self.constraint_torque_nm,
            &self.coupling_force_n,
            &self.coupling_torque_nm,
            &self.attachment_m,
            &self.target_m,
        ]
        .iter()
        .all(|v| v.iter().map(|x| x * x).sum::<f64>().is_finite())
            && self.tracking_error_m.is_finite()
    }
}
