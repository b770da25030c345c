//! The sparse tests: the Gram matrix and its factor at q0 for one set of
//! row scales.

use std::cmp::Ordering;

use super::{INVERSE_ITERATIONS, ORDERED_PIVOT, dot, norm};
use crate::al::scaling::{Role, Scaling};
use crate::force::gram::Gram;
use crate::force::inertia::BodyMass;
use crate::force::solve::MultiplierSolve;
use crate::{Evaluation, Jacobian, Model};

/// The Gram matrix and its factor at q0 for one set of row scales, and the
/// scratch of the sparse tests.
pub(super) struct Factored<'a> {
    q: &'a [f64],
    jac: &'a Jacobian,
    gram: &'a mut Gram,
    solve: &'a mut MultiplierSolve,
    masses: &'a [BodyMass],
    /// n: right-hand side of the assembly (zero), M̃⁻¹ g, C_qᵀ u.
    zero: Vec<f64>,
    w: Vec<f64>,
    g: Vec<f64>,
    /// m: a row combination, C_q w.
    u: Vec<f64>,
    cw: Vec<f64>,
    /// n_J.
    x: Vec<f64>,
    /// Per model row: a quaternion-norm row?
    norm_rows: Vec<bool>,
}

impl<'a> Factored<'a> {
    pub(super) fn new(
        model: &'a Model,
        ev: &'a Evaluation,
        gram: &'a mut Gram,
        solve: &'a mut MultiplierSolve,
        masses: &'a [BodyMass],
    ) -> Self {
        let (n, m, n_j) = (model.n_coords(), model.n_rows(), gram.n_j);
        Self {
            q: model.q0(),
            jac: ev.jacobian(),
            gram,
            solve,
            masses,
            zero: vec![0.0; n],
            w: vec![0.0; n],
            g: vec![0.0; n],
            u: vec![0.0; m],
            cw: vec![0.0; m],
            x: vec![0.0; n_j],
            norm_rows: model
                .rows()
                .iter()
                .map(|r| {
                    model.constraints()[r.constraint.index()].kind
                        == crate::constraint::ConstraintKind::QuaternionNorm
                })
                .collect(),
        }
    }

    /// Assembles A with `scale` (0 drops a row: unit diagonal) and factors
    /// it; false if the factorisation failed.
    pub(super) fn factor(&mut self, scale: &[f64]) -> bool {
        let g = &mut *self.gram;
        g.assemble(
            self.q,
            self.jac,
            scale,
            self.masses,
            &self.zero,
            &mut self.w,
        );
        for j in 0..g.n_j {
            if scale[g.j_rows[j]] == 0.0 {
                g.values[g.diag[j]] = 1.0;
            }
        }
        self.solve.factor(g).is_ok()
    }

    /// The ordered test of the module docs without dense reflectors: with A
    /// assembled for `scale` (as [`factor`](Self::factor) leaves it), scale A
    /// to a unit diagonal and factor it in model order (identity ordering,
    /// simplicial LLᵀ). Row j's pivot is its squared distance from the span of
    /// the rows before it, relative to its own length; a pivot at or below
    /// [`ORDERED_PIVOT`] is replaced by 4 (faer's dynamic regularisation), so
    /// the dependent row drops out of the rest of the factorisation exactly as
    /// the QR skips it, and shows as a diagonal of L ≥ 1.5, which no kept row
    /// can have (its pivot is at most its unit diagonal). Fill follows the
    /// model's order, so banded structures (chains, ladders, lattices written
    /// row by row) cost linear time. `None` if faer fails (the caller falls
    /// back to the dense QR).
    pub(super) fn dependent_in_order_sparse(
        &mut self,
        scale: &[f64],
        s: &Scaling,
    ) -> Option<Vec<usize>> {
        let g = &*self.gram;
        let at = self.elimination_order();
        let (cp, ri, vals) = self.ordered_upper(&at);
        let pivots = ordered_pivots(g.n_j, cp, ri, &vals)?;
        let mut dependent = Vec::new();
        for (j, &row) in g.j_rows.iter().enumerate() {
            if pivots[at[j]] >= 1.5 && scale[row] != 0.0 && s.role[row] == Role::Equality {
                dependent.push(row);
            }
        }
        dependent.sort_unstable();
        Some(dependent)
    }

    /// Each J index's place in the elimination order of
    /// [`dependent_in_order_sparse`](Self::dependent_in_order_sparse): the
    /// quaternion-norm rows first, then every other row in model order. A
    /// norm row constrains |e|, which no joint row sees (R(e) is invariant
    /// to scaling e), so it is never dependent on joint rows and its place
    /// does not change which joint rows are; put first, eliminating it only
    /// couples rows that already share its body, whereas left in body order
    /// it links bodies far apart in the model and the factor fills in.
    fn elimination_order(&self) -> Vec<usize> {
        let g = &*self.gram;
        let n = g.n_j;
        let norm = |j: usize| {
            let row = g.j_rows[j];
            self.norm_rows[row]
        };
        let mut order: Vec<usize> = (0..n).filter(|&j| norm(j)).collect();
        order.extend((0..n).filter(|&j| !norm(j)));
        let mut at = vec![0usize; n];
        for (k, &j) in order.iter().enumerate() {
            at[j] = k;
        }
        at
    }

    /// A scaled to a unit diagonal, its upper triangle in the elimination
    /// order `at`, CSC: column pointers, row indices (sorted), values.
    fn ordered_upper(&self, at: &[usize]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let g = &*self.gram;
        let n = g.n_j;
        let (lcp, lri) = (g.pattern.col_ptr(), g.pattern.row_idx());
        let d: Vec<f64> = (0..n)
            .map(|j| g.values[g.diag[j]].max(f64::MIN_POSITIVE))
            .collect();
        // Entry (a, b), a ≤ b, goes to column b (rows sorted below).
        let mut cp = vec![0usize; n + 1];
        for c in 0..n {
            for &r in &lri[lcp[c]..lcp[c + 1]] {
                cp[at[r].max(at[c]) + 1] += 1;
            }
        }
        for j in 0..n {
            cp[j + 1] += cp[j];
        }
        let mut next = cp.clone();
        let mut entries = vec![(0usize, 0.0f64); cp[n]];
        for c in 0..n {
            let span = lcp[c]..lcp[c + 1];
            for (&r, &v) in lri[span.clone()].iter().zip(&g.values[span]) {
                let (a, b) = (at[r].min(at[c]), at[r].max(at[c]));
                entries[next[b]] = (a, v / (d[r] * d[c]).sqrt());
                next[b] += 1;
            }
        }
        for b in 0..n {
            entries[cp[b]..cp[b + 1]].sort_unstable_by_key(|e| e.0);
        }
        let ri: Vec<usize> = entries.iter().map(|e| e.0).collect();
        let vals: Vec<f64> = entries.iter().map(|e| e.1).collect();
        (cp, ri, vals)
    }
    /// λ_min / max diag over the rows with a non-zero scale, by inverse
    /// iteration from a fixed pseudo-random start.
    pub(super) fn min_eigen_ratio(&mut self, scale: &[f64]) -> f64 {
        let g = &*self.gram;
        let active: Vec<bool> = g.j_rows.iter().map(|&r| scale[r] != 0.0).collect();
        let max_diag = (0..g.n_j)
            .filter(|&j| active[j])
            .map(|j| g.values[g.diag[j]])
            .fold(0.0, f64::max);
        if max_diag <= 0.0 {
            return 1.0;
        }
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        for (x, &a) in self.x.iter_mut().zip(&active) {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            *x = if a {
                0.5 + (seed >> 11) as f64 / (1u64 << 53) as f64
            } else {
                0.0
            };
        }
        let mut lambda = f64::INFINITY;
        for _ in 0..INVERSE_ITERATIONS {
            let before = norm(&self.x);
            if before == 0.0 || !before.is_finite() {
                return 0.0;
            }
            self.solve.solve_joint(&mut self.x);
            for (x, &a) in self.x.iter_mut().zip(&active) {
                if !a {
                    *x = 0.0;
                }
            }
            let after = norm(&self.x);
            if !(after.is_finite() && after > 0.0) {
                return 0.0;
            }
            lambda = before / after;
            for x in &mut self.x {
                *x /= after;
            }
        }
        lambda / max_diag
    }

    /// Distance of row `row` (scaled by `ell`) from the span of the rows with
    /// a non-zero `scale`, relative to its length, in the kinetic-energy
    /// metric: r = b − Bᵀ (B Bᵀ)⁻¹ B b formed as a vector, so a dependent row
    /// gives round-off, not the square root of a cancellation.
    pub(super) fn relative_distance(&mut self, row: usize, ell: f64, scale: &[f64]) -> f64 {
        let (jac, g) = (self.jac, &*self.gram);
        self.u.fill(0.0);
        self.u[row] = ell;
        let _ = jac.mul_t_vec(&self.u, &mut self.g);
        g.apply_inverse_mass(self.masses, &self.g, &mut self.w);
        let own = dot(&self.g, &self.w);
        if own.partial_cmp(&0.0) != Some(Ordering::Greater) {
            return 0.0;
        }
        let _ = jac.mul_vec(&self.w, &mut self.cw);
        for (x, &r) in self.x.iter_mut().zip(&g.j_rows) {
            *x = scale[r] * self.cw[r];
        }
        self.solve.solve_joint(&mut self.x);
        for (x, &r) in self.x.iter().zip(&g.j_rows) {
            self.u[r] -= scale[r] * x;
        }
        let _ = jac.mul_t_vec(&self.u, &mut self.g);
        g.apply_inverse_mass(self.masses, &self.g, &mut self.w);
        (dot(&self.g, &self.w).max(0.0) / own).sqrt()
    }
}

/// The diagonal of L, by elimination position, of the simplicial LLᵀ of the
/// `n`×`n` upper triangle (`cp`, `ri`, `vals`, CSC) in identity order, with
/// pivots at or below [`ORDERED_PIVOT`] replaced by 4
/// ([`Factored::dependent_in_order_sparse`]). `None` if faer fails.
fn ordered_pivots(n: usize, cp: Vec<usize>, ri: Vec<usize>, vals: &[f64]) -> Option<Vec<f64>> {
    use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
    use faer::linalg::cholesky::llt::factor::LltRegularization;
    use faer::sparse::linalg::SupernodalThreshold;
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
    };
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
    use faer::{Par, Side};

    let pattern = SymbolicSparseColMat::new_checked(n, n, cp, None, ri);
    // faer: Identity ordering reads the upper triangle (crate-api-notes §1).
    let symbolic = factorize_symbolic_cholesky(
        pattern.as_ref(),
        Side::Upper,
        SymmetricOrdering::Identity,
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        },
    )
    .ok()?;
    let SymbolicCholeskyRaw::Simplicial(simplicial) = symbolic.raw() else {
        return None;
    };
    let mut mem = MemBuffer::new(StackReq::any_of(&[
        symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
    ]));
    let mut l = vec![0.0; symbolic.len_val()];
    symbolic
        .factorize_numeric_llt::<f64>(
            &mut l,
            SparseColMatRef::new(pattern.as_ref(), vals),
            Side::Upper,
            LltRegularization {
                dynamic_regularization_delta: 4.0,
                dynamic_regularization_epsilon: ORDERED_PIVOT,
            },
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .ok()?;
    let (col_ptr, row_idx) = (simplicial.col_ptr(), simplicial.row_idx());
    (0..n)
        .map(|k| {
            (col_ptr[k]..col_ptr[k + 1])
                .find(|&p| row_idx[p] == k)
                .map(|p| l[p])
        })
        .collect()
}
