//! The goal and the straight path to it: the goal point moves on the line
//! from where the body is to the goal, its orientation by slerp.

use nalgebra::{UnitQuaternion, Vector3};

use super::PlaceError;

/// Where the body's origin should go, and optionally how it should be
/// oriented (body → world).
#[derive(Debug, Clone, PartialEq)]
pub struct Goal {
    /// The goal of the body's origin, metres, world frame.
    pub position_m: Vector3<f64>,
    /// The goal orientation; `None` leaves it free (a point goal).
    pub orientation: Option<UnitQuaternion<f64>>,
}

impl Goal {
    pub(super) fn check(&self) -> Result<(), PlaceError> {
        let finite = self.position_m.iter().all(|v| v.is_finite())
            && self
                .orientation
                .is_none_or(|q| q.coords.iter().all(|v| v.is_finite()));
        match finite {
            true => Ok(()),
            false => Err(PlaceError::Invalid("the goal has a non-finite number")),
        }
    }
}

/// The path from the body's assembled pose to the goal.
#[derive(Debug, Clone)]
pub struct GoalPath {
    p0: Vector3<f64>,
    r0: UnitQuaternion<f64>,
    p1: Vector3<f64>,
    r1: Option<UnitQuaternion<f64>>,
}

impl GoalPath {
    /// From `p0`, `r0` to `goal`.
    pub fn new(p0: Vector3<f64>, r0: UnitQuaternion<f64>, goal: &Goal) -> Self {
        Self {
            p0,
            r0,
            p1: goal.position_m,
            r1: goal.orientation,
        }
    }

    /// The goal point and orientation at fraction `t` ∈ [0, 1] (exactly the
    /// goal at 1).
    pub fn at(&self, t: f64) -> (Vector3<f64>, UnitQuaternion<f64>) {
        if t >= 1.0 {
            return (self.p1, self.r1.unwrap_or(self.r0));
        }
        let p = self.p0 + (self.p1 - self.p0) * t;
        let r = match self.r1 {
            Some(r1) => self.r0.try_slerp(&r1, t, 1e-12).unwrap_or(r1),
            None => self.r0,
        };
        (p, r)
    }

    /// Segments so that none moves the point more than `step_m` or turns
    /// more than `step_rad` (at least one).
    pub fn segments(&self, step_m: f64, step_rad: f64) -> usize {
        let length = (self.p1 - self.p0).norm();
        let angle = self.r1.map_or(0.0, |r1| self.r0.angle_to(&r1));
        let n = (length / step_m).max(angle / step_rad).ceil();
        (n as usize).max(1)
    }

    /// Whether the goal has an orientation (a rigid goal).
    pub fn turns(&self) -> bool {
        self.r1.is_some()
    }

    /// Length of the point's path, metres.
    pub fn length_m(&self) -> f64 {
        (self.p1 - self.p0).norm()
    }
}
