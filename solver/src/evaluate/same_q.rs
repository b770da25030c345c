//! A value-only evaluation at the q of the last whole evaluation: only the
//! finger rows, which read the targets, are evaluated again.
//!
//! A quasi-static tick starts where the previous one ended: its first
//! projected step evaluates C at the q the previous tick's last (whole)
//! evaluation used, with new targets. On a model whose rows read nothing
//! but q, the frames built from q and the targets (no contact or semantic
//! witness slots, rolling anchors, flexible anchors, surface contacts or
//! freed origins: disjoint from the contact models `since` serves), every
//! other row's value is then the one already stored,
//! bit for bit: the same functions of the same numbers. q is compared bit
//! for bit, so anything that moved it (a step, a prediction, `set_q`, an
//! adopted state) evaluates as before.

use super::{EvalError, Evaluation, all_finite};
use crate::constraint::Geometry;
use crate::constraint::block::{Ctx, NoJacobian};
use crate::{FingerTarget, Model};

/// Whether the stored values are those of a whole evaluation at `q`.
#[derive(Debug, Clone)]
pub(crate) struct SameQ {
    /// The model's rows read only q, frames and targets.
    enabled: bool,
    /// `q` holds the coordinates of the last whole evaluation, and no
    /// evaluation at another q came since.
    valid: bool,
    q: Vec<f64>,
    /// The finger constraints (the rows that read the targets).
    fingers: Vec<usize>,
    /// Tests: value-only evaluations that took this path.
    #[cfg(test)]
    pub(crate) test_taken: u64,
}

impl SameQ {
    /// The bookkeeping of `model` (off where rows read anything else).
    /// Allocates.
    pub fn new(model: &Model) -> Self {
        let enabled = model.contact.slots == 0
            && !model
                .geometry
                .iter()
                .any(|g| matches!(g, Geometry::Contact(_)))
            && model.semantic.slots.is_empty()
            && model.rolling.is_empty()
            && model.flex_anchors.is_empty()
            && model.surfaces.is_empty()
            && model.layout.origin_cols.iter().all(Option::is_none);
        Self {
            enabled,
            valid: false,
            q: if enabled {
                vec![0.0; model.n_coords()]
            } else {
                Vec::new()
            },
            fingers: model
                .geometry
                .iter()
                .enumerate()
                .filter(|(_, g)| matches!(g, Geometry::Finger(_)))
                .map(|(k, _)| k)
                .collect(),
            #[cfg(test)]
            test_taken: 0,
        }
    }

    /// Tests: never take this path (the old one).
    #[cfg(test)]
    pub fn disable(&mut self) {
        self.enabled = false;
        self.valid = false;
    }

    /// The stored values (but the finger rows') are those at `q`.
    ///
    /// # Real-time
    /// No allocation; O(coordinates).
    pub fn holds(&self, q: &[f64]) -> bool {
        self.valid
            && q.len() == self.q.len()
            && q.iter()
                .zip(&self.q)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }

    /// An evaluation at another q follows: the stored values no longer
    /// hold.
    pub fn forget(&mut self) {
        self.valid = false;
    }

    /// A whole evaluation at `q` succeeded.
    pub fn remember(&mut self, q: &[f64]) {
        if self.enabled {
            self.q.copy_from_slice(q);
            self.valid = true;
        }
    }
}

impl Evaluation {
    /// The finger rows' values at `q` (= the stored q) toward `targets`;
    /// every other value stays. Inputs already checked.
    ///
    /// # Real-time
    /// No allocation; O(finger rows + rows).
    pub(super) fn finger_values(
        &mut self,
        model: &Model,
        q: &[f64],
        targets: &[FingerTarget],
    ) -> Result<(), EvalError> {
        let Self {
            frames,
            values,
            witnesses,
            rolling,
            same_q,
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
        #[cfg(test)]
        {
            same_q.test_taken += 1;
        }
        for &k in &same_q.fingers {
            let rows = model.constraints[k].rows.clone();
            model.geometry[k].eval(&x, &mut values[rows], &mut NoJacobian);
        }
        if all_finite(values) {
            return Ok(());
        }
        same_q.forget();
        let row = values.iter().position(|v| !v.is_finite()).unwrap_or(0);
        Err(EvalError::NonFiniteValue { row })
    }
}
