//! A value-only evaluation that skips the contact rows whose two bodies
//! have not moved since the last evaluation (`al::moved` decides which).
//!
//! A contact row (`constraint::witness`) reads only its two frames and its
//! witness slot, so while neither body's coordinates and the witness table
//! are unchanged, its value is bit for bit the one the last evaluation
//! wrote. On a cluttered table the tick's steps move a handful of bodies:
//! the other ~95 % of the witness slots keep their values.

use super::{Evaluation, all_finite, check_inputs};
use crate::constraint::Geometry;
use crate::constraint::block::{Ctx, NoJacobian};
use crate::{EvalError, FingerTarget, Model};

impl Evaluation {
    /// Fills C(q) as [`evaluate_values`](Self::evaluate_values), except
    /// the contact rows of constraints `k` with `skip[k]` true, which keep
    /// their values (the caller guarantees that neither of their bodies
    /// moved since those values were written, and that the witness table
    /// is the same). Only the frames of bodies with `moved[body]` are
    /// rebuilt; the others must hold their coordinates of the last
    /// evaluation.
    ///
    /// # Real-time
    /// No allocation; O(moved bodies + rows evaluated + rows).
    pub(crate) fn evaluate_values_where(
        &mut self,
        model: &Model,
        q: &[f64],
        targets: &[FingerTarget],
        moved: &[bool],
        skip: &[bool],
    ) -> Result<(), EvalError> {
        if model.id != self.model_id {
            return Err(EvalError::ModelMismatch);
        }
        check_inputs(model, q, targets)?;
        self.set_frames(model, q, moved)?;
        let Self {
            frames,
            values,
            witnesses,
            rolling,
            since,
            ..
        } = self;
        let x = Ctx {
            q,
            frames,
            targets,
            witnesses,
            flex: &model.flex_anchors,
            surfaces: &model.surfaces,
            rolling,
        };
        for (k, (g, info)) in model.geometry.iter().zip(&model.constraints).enumerate() {
            let kept = matches!(g, Geometry::Contact(_)) && skip.get(k).copied().unwrap_or(false);
            if !kept {
                g.eval(&x, &mut values[info.rows.clone()], &mut NoJacobian);
                // Written at q, not at the Jacobian's inputs (`since`).
                since.unsync(k);
            }
        }
        if all_finite(values) {
            return Ok(());
        }
        let row = values.iter().position(|v| !v.is_finite()).unwrap_or(0);
        Err(EvalError::NonFiniteValue { row })
    }
}
