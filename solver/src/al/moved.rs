//! Which bodies a projected step moves, so that it evaluates and multiplies
//! only the contact rows that can change.
//!
//! Each step of a tick needs C at q (for the active rows' right-hand side
//! and the inactive rows' activation test) and C_q M̃⁻¹ g (the inactive
//! rows' prediction). A contact row reads only its two bodies (and its
//! witness slot, fixed within a tick): when neither body's coordinates
//! changed since the previous step's evaluation, its value is the same bit
//! for bit; when M̃⁻¹ g is zero on both bodies' columns, its prediction
//! term is exactly zero. On `cluttered` a step moves the dragged box and
//! the few objects it pushes: the other ~840 witness slots are left alone.
//! Every other constraint (joints, fingers, norms, limits) is evaluated as
//! before. The first step of a sequence (`Projected::begin`) evaluates
//! everything.

use crate::jacobian::{Jacobian, ShapeError};
use crate::{EvalError, Evaluation, FingerTarget, Model};

/// The per-step bookkeeping (allocated once per program).
#[derive(Debug, Clone)]
pub(crate) struct Moved {
    /// Off: every step evaluates and multiplies everything (models without
    /// contact rows, with design variables, freed origins or flexible
    /// anchors, and the comparison runs of the tests).
    enabled: bool,
    /// `q_eval` holds q at the last evaluation of the sequence.
    valid: bool,
    q_eval: Vec<f64>,
    /// Per frame (bodies, then the world): changed since the last
    /// evaluation, or moved by this step.
    flag: Vec<bool>,
    /// Per constraint: left out (contact constraints only; others never).
    skip: Vec<bool>,
    /// Moving bodies: frame index and first column.
    bodies: Vec<(usize, usize)>,
    /// Contact constraints: index and the two frames.
    contacts: Vec<(usize, usize, usize)>,
    /// Contact constraints left out of the last product or evaluation.
    kept: usize,
    /// Contact constraints left out of evaluations, summed (diagnostics).
    skipped: u64,
}

impl Moved {
    /// The bookkeeping of `model`. Allocates.
    pub fn new(model: &Model) -> Self {
        let contacts: Vec<(usize, usize, usize)> = model
            .geometry
            .iter()
            .enumerate()
            .filter_map(|(k, g)| match g {
                crate::constraint::Geometry::Contact(c) => {
                    Some((k, c.pair.frame[0], c.pair.frame[1]))
                }
                _ => None,
            })
            .collect();
        let layout = model.layout();
        let enabled = !contacts.is_empty()
            && layout.design_vars().is_empty()
            && layout.origin_cols.iter().all(Option::is_none)
            && model.flex_anchors.is_empty();
        Self {
            enabled,
            valid: false,
            q_eval: vec![0.0; model.n_coords()],
            flag: vec![false; model.bodies().len() + 1],
            skip: vec![false; model.geometry.len()],
            bodies: layout
                .moving_bodies()
                .map(|(b, o)| (b.index(), o))
                .collect(),
            contacts,
            kept: 0,
            skipped: 0,
        }
    }

    /// Evaluates and multiplies everything from now on (`full`), or only
    /// what can change (the default where the model allows it).
    pub fn set_full(&mut self, full: bool, model: &Model) {
        self.enabled = !full && Self::new(model).enabled;
        self.valid = false;
    }

    /// Whether steps leave unchanged contact rows out.
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// Starts a sequence: the next evaluation is whole.
    pub fn begin(&mut self) {
        self.valid = false;
    }

    /// Contact constraints the evaluations left out, summed over the
    /// program's life.
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    /// C at `q` into `ev`: whole at the start of a sequence, else all but
    /// the contact rows of bodies whose coordinates are unchanged since the
    /// last call.
    ///
    /// # Real-time
    /// No allocation; O(coordinates + constraints + rows evaluated).
    pub fn evaluate(
        &mut self,
        model: &Model,
        ev: &mut Evaluation,
        q: &[f64],
        targets: &[FingerTarget],
    ) -> Result<(), EvalError> {
        if !self.enabled || !self.valid || q.len() != self.q_eval.len() {
            self.kept = 0;
            let done = ev.evaluate_values(model, q, targets);
            self.remember(q, done.is_ok());
            return done;
        }
        for &(f, o) in &self.bodies {
            self.flag[f] = q[o..o + 7] != self.q_eval[o..o + 7];
        }
        self.mark_skips();
        self.skipped += self.kept as u64;
        let done = ev.evaluate_values_where(model, q, targets, &self.flag, &self.skip);
        self.remember(q, done.is_ok());
        done
    }

    /// y = C_q · x (x = M̃⁻¹ g of the step), the contact rows of bodies
    /// where x is zero set to 0 without a product.
    ///
    /// # Real-time
    /// No allocation; O(coordinates + constraints + nnz multiplied).
    pub fn mul_vec(&mut self, jac: &Jacobian, x: &[f64], y: &mut [f64]) -> Result<(), ShapeError> {
        if !self.enabled || x.len() != self.q_eval.len() {
            return jac.mul_vec(x, y);
        }
        for &(f, o) in &self.bodies {
            self.flag[f] = x[o..o + 7].iter().any(|&v| v != 0.0);
        }
        self.mark_skips();
        jac.mul_vec_where(x, y, &self.skip)
    }

    /// y = C_qᵀ · x, skipping the constraints whose x is zero.
    ///
    /// # Real-time
    /// No allocation; O(rows + nnz multiplied).
    pub fn mul_t_vec(&self, jac: &Jacobian, x: &[f64], y: &mut [f64]) -> Result<(), ShapeError> {
        if self.enabled {
            jac.mul_t_vec_sparse(x, y)
        } else {
            jac.mul_t_vec(x, y)
        }
    }

    /// `skip` from `flag`: a contact constraint is left out when neither
    /// of its frames is flagged.
    fn mark_skips(&mut self) {
        self.kept = 0;
        for &(k, f0, f1) in &self.contacts {
            let skip = !self.flag[f0] && !self.flag[f1];
            self.skip[k] = skip;
            self.kept += usize::from(skip);
        }
    }

    fn remember(&mut self, q: &[f64], ok: bool) {
        self.valid = ok && self.enabled;
        if self.valid {
            self.q_eval.copy_from_slice(q);
        }
    }
}
