//! The inactive inequality rows' prediction C_q M̃⁻¹ g of a projected step,
//! and what a tick's last step can leave out of it.
//!
//! Each projected step forms jm = C_q M̃⁻¹ g for two uses: the inactive
//! inequality and contact rows' predicted values after the step (the
//! activation test), and the update of C_q (q − q_ref) for the next step of
//! the tick. The last step of a tick has no next step, so only the first
//! use remains, and it reads jm on the rows of the constraints that hold an
//! inequality or contact row whose scale is 0: the product runs over those
//! constraints alone (none on a linkage without limits, where the last
//! step's product was a tenth of the update). Every row it does form is the
//! same block kernel's, so the activation test sees the same numbers bit
//! for bit.

use std::ops::Range;

use super::scaling::Role;
use crate::Model;
use crate::jacobian::{Jacobian, ShapeError};

/// The constraints with an inequality or contact row and the buffers of the
/// last step's masked product (allocated once per program).
#[derive(Debug, Clone)]
pub(crate) struct Prediction {
    /// Constraints holding an inequality or contact row at construction
    /// (masking only turns rows redundant, so this stays a superset), with
    /// their rows.
    constraints: Vec<(usize, Range<usize>)>,
    /// Their rows, in model order.
    rows: Vec<usize>,
    /// Per constraint: left out of the last step's product.
    skip: Vec<bool>,
}

impl Prediction {
    /// The inequality and contact constraints of `model` by `role` (one
    /// per row). Allocates.
    pub fn new(model: &Model, role: &[Role]) -> Self {
        let mut constraints = Vec::new();
        let mut rows = Vec::new();
        for (k, info) in model.constraints().iter().enumerate() {
            let own = info.rows.clone().filter(|&i| is_inequality(role, i));
            let before = rows.len();
            rows.extend(own);
            if rows.len() > before {
                constraints.push((k, info.rows.clone()));
            }
        }
        Self {
            constraints,
            rows,
            skip: vec![true; model.constraints().len()],
        }
    }

    /// The rows that can be inequality or contact rows: the activation
    /// test's candidates (every other row's role is neither).
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// jm = C_q x on the rows of the constraints that hold an inactive
    /// (scale 0) inequality or contact row, 0 on every other row.
    ///
    /// # Real-time
    /// No allocation; O(inequality rows + nnz of the constraints kept +
    /// rows).
    pub fn last_step_product(
        &mut self,
        jac: &Jacobian,
        role: &[Role],
        scale: &[f64],
        x: &[f64],
        jm: &mut [f64],
    ) -> Result<(), ShapeError> {
        for (k, rows) in &self.constraints {
            self.skip[*k] = !rows
                .clone()
                .any(|i| is_inequality(role, i) && scale.get(i) == Some(&0.0));
        }
        jac.mul_vec_where(x, jm, &self.skip)
    }
}

fn is_inequality(role: &[Role], i: usize) -> bool {
    matches!(role.get(i), Some(Role::Inequality | Role::Contact))
}
