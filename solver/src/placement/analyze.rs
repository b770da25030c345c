//! [`Placement`]: everything one constraint structure needs, built by the
//! symbolic phase [`Placement::analyze`] and reused by every
//! [`Placement::solve`].

use std::hash::{DefaultHasher, Hash, Hasher};

use super::factor::NormalFactor;
use super::lowrank::LowRank;
use super::pattern;
use super::{IterationRecord, PlacementError, PlacementOptions, PlacementStats};
use crate::{Evaluation, Model};

/// Identifies a constraint structure: coordinates, rows, equality/inequality
/// split and the column groups of every constraint, i.e. everything the
/// pattern of C_q and therefore of J Jᵀ depends on (not q, targets, anchors or
/// lengths). Two models with equal keys share an analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StructureKey(pub u64);

impl StructureKey {
    /// The key of `model`'s structure. O(constraints), no allocation.
    pub fn of(model: &Model) -> Self {
        let mut h = DefaultHasher::new();
        (model.n_coords(), model.n_rows(), model.equality_rows).hash(&mut h);
        for (k, g) in model.geometry.iter().enumerate() {
            g.rows().hash(&mut h);
            model.constraint_groups(k).hash(&mut h);
        }
        Self(h.finish())
    }
}

/// The symbolic analysis of one constraint structure (the AMD ordering and
/// Cholesky structure of J Jᵀ, its fill plan, the dense-column split) and all
/// scratch of the Newton iteration, so a [`solve`](Placement::solve)
/// allocates nothing. `Send`: build and use it on the slow thread.
#[derive(Debug)]
pub struct Placement {
    pub(super) options: PlacementOptions,
    pub(super) key: StructureKey,
    pub(super) model_id: u64,
    pub(super) n: usize,
    pub(super) m: usize,
    pub(super) m_eq: usize,
    pub(super) eval: Evaluation,
    pub(super) factor: NormalFactor,
    pub(super) low: LowRank,
    /// Objective weights W (1 by default), their inverses (the q block of
    /// the Hessian is W, Eq. 8), and whether any differ from 1.
    pub(super) w: Vec<f64>,
    pub(super) hinv: Vec<f64>,
    pub(super) weighted: bool,
    pub(super) stats: PlacementStats,
    /// Multipliers at the current iterate and of the step being tried.
    pub(super) lambda: Vec<f64>,
    pub(super) lambda_new: Vec<f64>,
    /// Slacks Y (one per inequality row), their Hessian, step and trial.
    pub(super) y: Vec<f64>,
    pub(super) hy: Vec<f64>,
    pub(super) dy: Vec<f64>,
    pub(super) y_trial: Vec<f64>,
    /// Extended residual g, the normal right-hand side, extra diagonal of S.
    pub(super) g: Vec<f64>,
    pub(super) rhs: Vec<f64>,
    pub(super) diag: Vec<f64>,
    /// The extra diagonal of N (without F²), and refinement scratch.
    pub(super) diag_n: Vec<f64>,
    pub(super) tmp_m: Vec<f64>,
    pub(super) tmp_n: Vec<f64>,
    /// q − q_ref, the q step, the trial q.
    pub(super) d: Vec<f64>,
    /// H⁻¹W(q − q_ref).
    pub(super) sd: Vec<f64>,
    pub(super) dq: Vec<f64>,
    pub(super) q_trial: Vec<f64>,
    pub(super) history: Vec<IterationRecord>,
}

// The slow thread builds and keeps analyses; the session may move them.
const _: () = {
    const fn assert_send<T: Send>() {}
    assert_send::<Placement>();
};

impl Placement {
    /// Symbolic phase, once per constraint structure: validates `options`,
    /// splits off dense columns, computes the pattern of J Jᵀ and its
    /// fill plan, runs faer's AMD ordering and symbolic Cholesky, and
    /// allocates every buffer `solve` needs. Allocates; slow thread only.
    pub fn analyze(model: &Model, options: &PlacementOptions) -> Result<Self, PlacementError> {
        let (n, m) = (model.n_coords(), model.n_rows());
        options.validate(n)?;
        if n == 0 || m == 0 {
            return Err(PlacementError::Empty);
        }
        let eval = Evaluation::new(model);
        let jac = eval.jacobian();
        let raw = pattern::analyse(jac, options.dense_column_threshold);
        let low = LowRank::new(jac, &raw.dense_cols, &raw.f_rows);
        let factor =
            NormalFactor::analyze(&raw, low.dense_columns()).ok_or(PlacementError::Symbolic)?;
        let stats = PlacementStats {
            rows: m,
            coords: n,
            jacobian_nnz: jac.nnz(),
            normal_nnz: raw.lower.row_idx().len(),
            factor_nnz: factor.factor_nnz(),
            factor_flops: factor.factor_flops(),
            supernodal: factor.supernodal(),
            dense_columns: low.dense_columns(),
            low_rank: low.rank(),
        };
        let m_eq = model.equality_rows().end;
        let m_in = m - m_eq;
        let w = options.weights.clone().unwrap_or_else(|| vec![1.0; n]);

        Ok(Self {
            options: options.clone(),
            key: StructureKey::of(model),
            model_id: model.id,
            n,
            m,
            m_eq,
            eval,
            factor,
            low,
            hinv: w.iter().map(|v| 1.0 / v).collect(),
            weighted: options.weights.is_some(),
            w,
            stats,
            lambda: vec![0.0; m],
            lambda_new: vec![0.0; m],
            y: vec![0.0; m_in],
            hy: vec![0.0; m_in],
            dy: vec![0.0; m_in],
            y_trial: vec![0.0; m_in],
            g: vec![0.0; m],
            rhs: vec![0.0; m],
            diag: vec![0.0; m],
            diag_n: vec![0.0; m],
            tmp_m: vec![0.0; m],
            tmp_n: vec![0.0; n],
            d: vec![0.0; n],
            sd: vec![0.0; n],
            dq: vec![0.0; n],
            q_trial: vec![0.0; n],
            history: Vec::with_capacity(options.max_iterations as usize + 1),
        })
    }

    /// The structure this analysis serves.
    pub fn structure_key(&self) -> StructureKey {
        self.key
    }

    /// The options it was analysed with.
    pub fn options(&self) -> &PlacementOptions {
        &self.options
    }

    /// Sizes of the analysis: J, J Jᵀ, L, the dense-column split.
    pub fn stats(&self) -> PlacementStats {
        self.stats
    }

    /// λ at the last solve's returned q, one per row of C in model row order,
    /// with the fast loop's sign convention (Nelson & Cohen Eq. 1):
    /// W(q − q_ref) + C_qᵀλ = 0. An active inequality pushes: λ_j ≤ 0; an
    /// inactive one has λ_j = 0. After a [`LeastSquares`](super::SolveStatus::LeastSquares)
    /// outcome λ ≈ C/μ (large but finite).
    pub fn multipliers(&self) -> &[f64] {
        &self.lambda
    }

    /// Slack Y_j of each inequality row (C_j = Y_j² at convergence), in
    /// [`Model::inequality_rows`] order. Y_j = 0 marks an active row.
    pub fn slacks(&self) -> &[f64] {
        &self.y
    }

    /// The accepted iterations of the last solve (capacity preallocated).
    pub fn history(&self) -> &[IterationRecord] {
        &self.history
    }

    /// Sets the witness table of `model`'s contact rows (its first
    /// `table.len()` slots, [`Evaluation::witnesses`]) for the next
    /// [`solve`](Self::solve) on `model`: a placement that respects
    /// non-penetration (Choi & Cremer §3.2 inside §4.3's modes,
    /// `crate::place`). Binds to `model` first (same structure required).
    pub fn set_witnesses(
        &mut self,
        model: &Model,
        table: &[crate::constraint::witness::Witness],
    ) -> Result<(), PlacementError> {
        self.bind(model)?;
        let slots = self.eval.witnesses_mut();
        if table.len() > slots.len() {
            return Err(PlacementError::StructureMismatch);
        }
        slots[..table.len()].copy_from_slice(table);
        Ok(())
    }

    /// Binds to `model`: same structure required; a different model object of
    /// that structure (e.g. a contact set that changed back) gets a fresh
    /// [`Evaluation`] (one allocation, not per iteration).
    pub(super) fn bind(&mut self, model: &Model) -> Result<(), PlacementError> {
        if model.id == self.model_id {
            return Ok(());
        }
        if StructureKey::of(model) != self.key
            || model.n_coords() != self.n
            || model.n_rows() != self.m
        {
            return Err(PlacementError::StructureMismatch);
        }
        self.eval = Evaluation::new(model);
        self.model_id = model.id;
        Ok(())
    }
}
