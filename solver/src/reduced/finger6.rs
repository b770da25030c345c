//! Rigid (six-row) fingers in the joint tick: the three point rows and the
//! three orientation rows (`constraint::finger`) are kept rows like a point
//! grasp's, their J_r S written from each row's world gradient (`rows`),
//! the orientation rows scaled by L as in the augmented tick (`Scaling`),
//! the pull limit applied per group of three (`tick::residual`), and the
//! torque read from the rows' angular gradients (`stage::outputs_at`). What
//! is left is the rigid grasp's angular coupling, added to the felt torque
//! as `Feedback::wrenches` adds it.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::FingerTarget;

/// The angular coupling torque of a finger with `rows` rows on the body at
/// column `offset` of `q` (zero for a point grasp): the body's rotation
/// from the target orientation, as a scaled axis, times `stiffness`.
#[inline]
pub(super) fn coupling_torque(
    rows: usize,
    q: &[f64],
    offset: Option<usize>,
    target: &FingerTarget,
    stiffness: f64,
) -> Vector3<f64> {
    let Some(o) = offset.filter(|_| rows == 6) else {
        return Vector3::zeros();
    };
    let body =
        UnitQuaternion::new_normalize(Quaternion::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]));
    (body * target.orientation.inverse()).scaled_axis() * stiffness
}
