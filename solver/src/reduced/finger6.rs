//! Rigid (six-row) fingers in the joint tick: the three point rows and the
//! three orientation rows (`constraint::finger`) are kept rows like a point
//! grasp's, their J_r S written from each row's world gradient (`rows`),
//! the orientation rows scaled by L as in the augmented tick (`Scaling`),
//! the pull limit applied per group of three (`tick::residual`), and the
//! torque read from the rows' angular gradients (`outputs_at`, below). What
//! is left is the rigid grasp's angular coupling, added to the felt torque
//! as `Feedback::wrenches` adds it.

use nalgebra::Vector3;

use super::tick::JointTick;
use crate::force::feedback::rigid_coupling_torque;
use crate::{FingerOutput, FingerTarget};

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
    match offset.filter(|_| rows == 6) {
        Some(o) => rigid_coupling_torque(q, o, target, stiffness),
        None => Vector3::zeros(),
    }
}

impl JointTick {
    /// The finger outputs from λ̃_F and the coupling (`Feedback::wrenches`).
    pub(super) fn outputs_at(&mut self, targets: &[FingerTarget], dt_s: f64) {
        let st = &mut self.stage;
        let k = self.settings.coupling_stiffness_n_per_m;
        let c = self.settings.coupling_damping_n_s_per_m;
        for (i, fi) in self.model.fingers().iter().enumerate() {
            let (first, rows, end) = st.fingers[i];
            let first = self.n_loop + first;
            let fr = &self.frames[fi.body.index()];
            let (mut force, mut torque) = (Vector3::zeros(), Vector3::zeros());
            for row in first..first + rows {
                let lam = self.scale[row] * st.lambda_f[row - self.n_loop];
                force += self.grads[row].lin[end] * lam;
                torque += self.grads[row].ang[end] * lam;
            }
            let p = fr.point(&fi.point_m);
            let torque = torque - (p - fr.r).cross(&force);
            let err = p - targets[i].position_m;
            let rate = if st.ticks > 1 {
                (err - st.prev_error[i]) / dt_s
            } else {
                Vector3::zeros()
            };
            st.prev_error[i] = err;
            let coupling = err * k + rate * c;
            let coupling_torque = coupling_torque(
                rows,
                &self.q,
                self.model.layout().body_offset(fi.body),
                &targets[i],
                self.settings.coupling_angular_stiffness_nm_per_rad,
            );
            self.outputs[i] = FingerOutput {
                force_n: force + coupling,
                torque_nm: torque + coupling_torque,
                constraint_force_n: force,
                constraint_torque_nm: torque,
                coupling_force_n: coupling,
                coupling_torque_nm: coupling_torque,
                attachment_m: p,
                target_m: targets[i].position_m,
                tracking_error_m: err.norm(),
            };
        }
    }
}
