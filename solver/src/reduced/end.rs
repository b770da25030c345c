//! The end of a joint tick in two stages (the stage marks of
//! `Program::tick_marked` fall between them): the evaluation at the last
//! iterate, then the force stage (`stage`).

use super::ReducedError;
use super::tick::JointTick;
use crate::FingerTarget;

impl JointTick {
    /// Forward kinematics at θ (`advance`), J_r S there, the factors and
    /// the finger outputs; the chord point moves to the result.
    pub(crate) fn end_of_tick(
        &mut self,
        targets: &[FingerTarget],
        dt_s: f64,
        advance: bool,
    ) -> Result<(), ReducedError> {
        self.evaluate_end(targets, advance)?;
        self.force_end(targets, dt_s, advance)
    }

    /// The end of a tick's evaluation: forward kinematics at θ
    /// (`advance`), the loop and finger rows' values and J_r S there, the
    /// loop violation.
    pub(crate) fn evaluate_end(
        &mut self,
        targets: &[FingerTarget],
        advance: bool,
    ) -> Result<(), ReducedError> {
        if advance {
            self.pose()?;
        }
        let nb = self.model.bodies().len();
        self.kin.frames[..nb].copy_from_slice(&self.frames[..nb]);
        self.kin.set_twists(&self.space.tree);
        let ok = self.set.jacobian(
            &self.model,
            &self.space.tree,
            &self.q,
            &self.frames,
            &self.kin.twists,
            targets,
            &self.scale,
            &mut self.values,
            &mut self.jr,
            &mut self.grads,
        );
        if !ok || !self.limit_jacobian(targets) {
            return Err(ReducedError::RawEntry);
        }
        self.max_violation = self.violation();
        Ok(())
    }

    /// The force stage after [`evaluate_end`](Self::evaluate_end): the
    /// factors and (`advance`: the motion history advanced) the finger
    /// outputs; the chord point moves to q.
    pub(crate) fn force_end(
        &mut self,
        targets: &[FingerTarget],
        dt_s: f64,
        advance: bool,
    ) -> Result<(), ReducedError> {
        self.limit_factors()?;
        if advance {
            let tau_s = self.settings.velocity_filter.as_secs_f64();
            let (model, kin, q) = (&self.model, &self.kin, &self.q);
            self.stage
                .load(model, &self.space.tree, kin, q, dt_s, tau_s);
            self.solve_fingers()?;
            self.outputs_at(targets, dt_s);
            self.restore_limits()?;
        }
        self.q_s.copy_from_slice(&self.q);
        Ok(())
    }
}
