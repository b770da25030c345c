//! Redundant constraint rows: found once per program at q0 (off the fast
//! thread) and left out of every solve, the way multibody codes remove
//! redundant constraints (Adams: "redundant constraint removal").
//!
//! **Why.** A planar loop built from spatial revolutes has more joint rows
//! than it can have independent ones: each revolute also pins the out-of-plane
//! height and the two out-of-plane tilts, and around a closed loop those pins
//! repeat each other. The Peaucellier linkage (7 links, 10 revolutes) has 57
//! equality rows on 49 coordinates and rank 48: 9 rows, the three out-of-plane
//! rows of each of the three loop-closing joints, are dependent everywhere.
//! Then A = D C_q M̃⁻¹ C_qᵀ D is singular and its Cholesky runs on round-off
//! pivots. At an assembled q the right-hand sides stay in A's range and
//! nothing shows; away from the manifold (C is nonlinear) they pick up
//! components in C_q's left null space, which come back as enormous
//! multipliers y, and C_qᵀ y turns round-off into a step of hundreds of metres
//! in one tick (measured: BENCHMARKS.md). Tikhonov regularisation only trades
//! the blow-up for bias. Leaving the dependent rows out makes A positive
//! definite without changing anything the remaining rows determine: near q0
//! the kept rows imply the masked ones, and the finger's Schur complement
//! only sees the span of the rows, which is the same.
//!
//! **How.** Each row is a vector b_i = ℓ_i C_i M̃^{-1/2} in the kinetic-energy
//! metric (the one A is built in; design-variable columns, frozen in Eq. 7,
//! are left out). Equality rows (joints, quaternion norms; not fingers) are
//! taken **in model order**: a row is kept iff its distance from the span of
//! the rows kept before it is more than [`REDUNDANCY_TOLERANCE`] × its own
//! length (Householder QR without pivoting that skips such columns). Model
//! order, rather than column pivoting by size, keeps whole joints: on a
//! planar loop it masks the out-of-plane rows of the joints that close
//! cycles, so the kept rows are those of a spanning tree, which pin the
//! out-of-plane motion at every planar configuration, not only at q0.
//!
//! The test runs as a sparse Cholesky of A (scaled to a unit diagonal) in
//! model order: row j's pivot is its squared distance from the span of the
//! rows before it, and a pivot at round-off is replaced (dynamic
//! regularisation), which drops the row from the rest of the factorisation as
//! the QR skips it. A dense Householder QR with the same criterion, O(n m r)
//! (n body coordinates, m equality rows, r the rank; a 241-body ladder of
//! loops took 1.08 s), remains as the fallback if faer fails. So
//! [`RedundancyCheck::Auto`] first estimates the smallest eigenvalue of A
//! (equality rows) by inverse iteration with its sparse factor, a few sparse
//! solves: a singular A shows as λ_min ≤ 1e-10 × max diag (the factor's
//! dynamic regularisation) or a round-off pivot below that (measured: 4e-12
//! on the Peaucellier linkage, 1.5e-11 on a planar four-bar), while the
//! full-rank built-in mechanisms give 5.8e-5 (four-bar), 7.0e-5 (Stewart)
//! and 5.6e-4 (sphere toy). Only below [`PRETEST_RATIO`] does the dense QR
//! run.
//!
//! **Before A exists: rows dependent within their body pair.** A is built
//! over the rows that survive a first, local pass: equality rows are grouped
//! by the moving bodies they touch (one or two: at most 14 columns) and, in
//! model order within each group, a row within [`REDUNDANCY_TOLERANCE`] of the
//! span of the group's earlier rows (same metric) is dependent. Such a row is
//! dependent on the earlier rows of the whole model too, so the ordered check
//! would mask it anyway; finding it first keeps it out of A's pattern. Without
//! it, many joints between the same two bodies (each row coupled to every
//! other through the shared body) made A a dense m × m matrix: 1000 revolutes
//! cost minutes and gigabytes at `Program::new`; with it the pass is
//! O(m · 14²) and A keeps at most 14 such rows per pair (BENCHMARKS.md).
//!
//! **Inequality rows** (limits, contacts) are tested one by one against the
//! kept equality rows (one sparse solve each: the residual of the projection
//! on their span, computed as a vector, not by cancelling squares): a
//! dependent one (a contact the joints already enforce) is masked for good.
//! Inequality rows dependent on *other* inequality rows (a slider's lower and
//! upper limit) are never active together, so they are kept.
//!
//! **Tolerance.** [`REDUNDANCY_TOLERANCE`] = 1e-8 relative: structurally
//! dependent rows come out at ≤ 2e-15 at an assembled q0 (round-off; a q0
//! violated by δ over a lever L would show about δ/L), while no independent
//! row of the built-in mechanisms or the planar test linkages comes closer
//! than 0.096 to the span of the rows before it (measured). A row within
//! 1e-8 of the others' span is numerically redundant at q0 anyway.
//!
//! **What it does not cover.** The dependent set is fixed at q0. At a singular
//! pose (a linkage at toggle, two active limits that say the same thing) the
//! kept rows can lose rank as the mechanism moves; the Cholesky's dynamic
//! regularisation then keeps the factor alive, the projected rule stops a
//! chord iteration that diverges (`Program::tick`), and the tick's
//! divergence guard (`TickOutcome::Diverged`) refuses any absurd step,
//! multiplier or violation that remains, so the session can re-project. A new
//! program (a new active set, `Model::with_inequalities`) runs the check again.

use std::cmp::Ordering;

use nalgebra::{Matrix4, Vector3, Vector4};

use super::gram::Gram;
use super::inertia::BodyMass;
use super::solve::MultiplierSolve;
use crate::al::RedundancyCheck;
use crate::al::scaling::{Role, Scaling};
use crate::rotation::BodyFrame;
use crate::{Evaluation, Jacobian, Model};

/// A row whose distance from the span of the kept rows, in the
/// kinetic-energy metric, is at most this × its own length is redundant.
pub const REDUNDANCY_TOLERANCE: f64 = 1e-8;

/// The pretest's threshold on λ_min(A) / max diag(A) (A over the equality
/// rows at q0) below which the dense QR runs: an eigenvalue ratio of 1e-8 is
/// a singular-value ratio of 1e-4, far above a singular A's (≤ 1e-10 after
/// the factor's regularisation) and below the built-in mechanisms' (≥ 5.8e-5).
pub const PRETEST_RATIO: f64 = 1e-8;

/// The ordered sparse test's pivot threshold, relative to a row's own squared
/// length: a squared distance of 1e-12 (distance 1e-6). The factorisation
/// squares the distances, so it resolves about √ε ≈ 1.5e-8 of a row's length:
/// the dense QR's 1e-8 ([`REDUNDANCY_TOLERANCE`]) is below that resolution,
/// while dependent rows come out at round-off (≤ 1e-14 squared) and no
/// independent row of the built-in or test mechanisms is closer than 0.096
/// (9e-3 squared): 1e-12 separates the two by orders of magnitude each way.
const ORDERED_PIVOT: f64 = 1e-12;

/// Inverse iterations of the pretest. Each multiplies the weight of an
/// eigenvalue ≤ 1e-10 relative by ≥ 1e6 over any eigenvalue ≥ 1e-4.
const INVERSE_ITERATIONS: usize = 8;

/// What the redundancy check of [`Program::new`](crate::Program::new) found
/// ([`Program::redundancy`](crate::Program::redundancy)).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Redundancy {
    /// Masked rows (model row indices, ascending): evaluated and reported,
    /// left out of every update and force solve (multiplier 0).
    pub rows: Vec<usize>,
    /// Equality rows tested (joints and quaternion norms; finger rows are
    /// penalties and never tested).
    pub equality_rows: usize,
    /// Inequality rows tested against the kept equality rows.
    pub inequality_rows: usize,
    /// λ_min(A) / max diag(A) of the scaled C_q M̃⁻¹ C_qᵀ over the equality
    /// rows at q0, by inverse iteration (`None`: check off).
    pub conditioning: Option<f64>,
    /// Whether the dense ordered QR ran.
    pub dense: bool,
    /// Of `rows`, those the per-body-pair pass found before A was built.
    pub local: usize,
}

/// Equality rows dependent on earlier rows touching the same moving bodies
/// (see the module docs), ascending. O(rows × 14²). Allocates.
pub(crate) fn locally_dependent(
    model: &Model,
    ev: &Evaluation,
    s: &Scaling,
    masses: &[BodyMass],
) -> Vec<usize> {
    let q = model.q0();
    let jac = ev.jacobian();
    let mut block = vec![usize::MAX; model.n_coords()];
    let mut halves = Vec::with_capacity(masses.len());
    for (k, m) in masses.iter().enumerate() {
        let o = m.offset;
        block[o..o + 7].fill(k);
        let e = Vector4::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
        halves.push(
            BodyFrame::new(Vector3::new(q[o], q[o + 1], q[o + 2]), e.into())
                .and_then(|f| m.inv_rotational_mass(&f, &e).cholesky())
                .map(|c| (1.0 / m.mass.sqrt(), c.l().transpose())),
        );
    }
    let mut groups: std::collections::BTreeMap<(usize, usize), Vec<[f64; 14]>> =
        std::collections::BTreeMap::new();
    let mut dependent = Vec::new();
    'rows: for i in (0..model.n_rows()).filter(|&i| s.role[i] == Role::Equality) {
        let span = jac.row_ptr()[i]..jac.row_ptr()[i + 1];
        let (mut b0, mut b1) = (usize::MAX, usize::MAX);
        for p in span.clone() {
            let b = block[jac.col_idx()[p]];
            if b == usize::MAX || halves[b].is_none() {
                continue 'rows; // a design variable or an unfactorable body
            }
            if b0 == usize::MAX || b0 == b {
                b0 = b;
            } else if b1 == usize::MAX || b1 == b {
                b1 = b;
            } else {
                continue 'rows;
            }
        }
        if b0 == usize::MAX {
            continue;
        }
        let key = (b0.min(b1), b0.max(b1));
        let mut raw = [0.0; 14];
        for p in span {
            let c = jac.col_idx()[p];
            let b = block[c];
            let half = if b == key.0 { 0 } else { 7 };
            raw[half + c - masses[b].offset] = s.ell[i] * jac.values()[p];
        }
        let mut v = [0.0; 14];
        for (half, b) in [(0, key.0), (7, key.1)] {
            if let Some(Some((inv_sqrt_m, lt))) = halves.get(b) {
                for c in 0..3 {
                    v[half + c] = raw[half + c] * inv_sqrt_m;
                }
                let ce =
                    lt * Vector4::new(raw[half + 3], raw[half + 4], raw[half + 5], raw[half + 6]);
                v[half + 3..half + 7].copy_from_slice(ce.as_slice());
            }
        }
        let own = norm(&v);
        let basis = groups.entry(key).or_default();
        for _ in 0..2 {
            for u in basis.iter() {
                let t = dot(&v, u);
                for (x, y) in v.iter_mut().zip(u) {
                    *x -= t * y;
                }
            }
        }
        let tail = norm(&v);
        if tail.partial_cmp(&(REDUNDANCY_TOLERANCE * own)) != Some(Ordering::Greater)
            || basis.len() == 14
        {
            dependent.push(i);
        } else {
            basis.push(v.map(|x| x / tail));
        }
    }
    dependent
}

/// Runs the check of `mode` for `model` at q0 (`ev` evaluated there) with the
/// force solve's pattern and factor. Leaves `gram` and `solve` holding
/// matrices of the check; the caller refactors. Allocates.
pub(crate) fn detect(
    model: &Model,
    ev: &Evaluation,
    s: &Scaling,
    mode: RedundancyCheck,
    gram: &mut Gram,
    solve: &mut MultiplierSolve,
    masses: &[BodyMass],
) -> Redundancy {
    let equality: Vec<usize> = (0..model.n_rows())
        .filter(|&i| s.role[i] == Role::Equality)
        .collect();
    let inequality: Vec<usize> = (0..model.n_rows())
        .filter(|&i| s.role[i] == Role::Inequality)
        .collect();
    let mut out = Redundancy {
        equality_rows: equality.len(),
        inequality_rows: inequality.len(),
        ..Redundancy::default()
    };
    if mode == RedundancyCheck::Off {
        return out;
    }
    let mut f = Factored::new(model, ev, gram, solve, masses);
    // Equality and finger rows in, inequality rows out.
    let mut scale: Vec<f64> = (0..model.n_rows())
        .map(|i| match s.role[i] {
            Role::Inequality
            | Role::Redundant
            | Role::Contact
            | Role::Friction
            | Role::DesignBound
            | Role::DesignPin => 0.0,
            Role::Equality | Role::Finger | Role::Coupling => s.ell[i],
        })
        .collect();
    let ratio = if f.factor(&scale) {
        f.min_eigen_ratio(&scale)
    } else {
        0.0
    };
    out.conditioning = Some(ratio);
    if mode == RedundancyCheck::Dense
        || ratio.partial_cmp(&PRETEST_RATIO) != Some(Ordering::Greater)
    {
        out.dense = true;
        out.rows = match f.dependent_in_order_sparse(&scale, s) {
            Some(rows) => rows,
            None => dependent_in_order(model, ev, masses, &s.ell, &equality),
        };
        for &i in &out.rows {
            scale[i] = 0.0;
        }
        f.factor(&scale);
    }
    for &i in &inequality {
        if f.relative_distance(i, s.ell[i], &scale) <= REDUNDANCY_TOLERANCE {
            out.rows.push(i);
        }
    }
    out.rows.sort_unstable();
    out
}

/// The Gram matrix and its factor at q0 for one set of row scales, and the
/// scratch of the sparse tests.
struct Factored<'a> {
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
    fn new(
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
    fn factor(&mut self, scale: &[f64]) -> bool {
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
    fn dependent_in_order_sparse(&mut self, scale: &[f64], s: &Scaling) -> Option<Vec<usize>> {
        use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
        use faer::linalg::cholesky::llt::factor::LltRegularization;
        use faer::sparse::linalg::SupernodalThreshold;
        use faer::sparse::linalg::cholesky::{
            CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
            factorize_symbolic_cholesky,
        };
        use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
        use faer::{Par, Side};

        let g = &*self.gram;
        let n = g.n_j;
        let (lcp, lri) = (g.pattern.col_ptr(), g.pattern.row_idx());
        // Elimination order: the quaternion-norm rows first, then every other
        // row in model order. A norm row constrains |e|, which no joint row
        // sees (R(e) is invariant to scaling e), so it is never dependent on
        // joint rows and its place does not change which joint rows are; put
        // first, eliminating it only couples rows that already share its body,
        // whereas left in body order it links bodies far apart in the model
        // and the factor fills in.
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
        let d: Vec<f64> = (0..n)
            .map(|j| g.values[g.diag[j]].max(f64::MIN_POSITIVE))
            .collect();
        // Upper triangle in the elimination order, CSC: entry (a, b), a ≤ b,
        // goes to column b (rows sorted below).
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
                SparseColMatRef::new(pattern.as_ref(), &vals),
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
        let mut dependent = Vec::new();
        for (j, &row) in g.j_rows.iter().enumerate() {
            let k = at[j];
            let diag = (col_ptr[k]..col_ptr[k + 1]).find(|&p| row_idx[p] == k)?;
            if l[diag] >= 1.5 && scale[row] != 0.0 && s.role[row] == Role::Equality {
                dependent.push(row);
            }
        }
        dependent.sort_unstable();
        Some(dependent)
    }

    /// λ_min / max diag over the rows with a non-zero scale, by inverse
    /// iteration from a fixed pseudo-random start.
    fn min_eigen_ratio(&mut self, scale: &[f64]) -> f64 {
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
    fn relative_distance(&mut self, row: usize, ell: f64, scale: &[f64]) -> f64 {
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

/// The rows of `rows` (model order) that are dependent on the rows before
/// them: Householder QR of B's columns b_i = ℓ_i M̃^{-1/2} C_iᵀ without
/// pivoting, skipping (and reporting) a column whose part outside the kept
/// span is at most [`REDUNDANCY_TOLERANCE`] × its length. Dense: O(n m r).
fn dependent_in_order(
    model: &Model,
    ev: &Evaluation,
    masses: &[BodyMass],
    ell: &[f64],
    rows: &[usize],
) -> Vec<usize> {
    let q = model.q0();
    let jac = ev.jacobian();
    let nb0 = model.layout().body_coords();
    // Auxiliary blocks (flexible deformations, surface parameters) take
    // part with their metric: Lᵀ with L Lᵀ = H⁻¹, after the bodies'.
    let aux: Vec<(usize, usize, nalgebra::DMatrix<f64>)> = model
        .layout()
        .aux_blocks()
        .iter()
        .filter_map(|b| {
            let inv = nalgebra::DMatrix::from_row_slice(b.width, b.width, &b.inv_metric);
            Some((b.offset, b.width, inv.cholesky()?.l().transpose()))
        })
        .collect();
    let nb = nb0 + aux.iter().map(|a| a.1).sum::<usize>();
    // M̃^{-1/2} per body: 1/√m on r, Lᵀ with L Lᵀ = M̃_e⁻¹ on e.
    let halves: Vec<(usize, f64, Matrix4<f64>)> = masses
        .iter()
        .filter_map(|m| {
            let o = m.offset;
            let e = Vector4::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
            let frame = BodyFrame::new(Vector3::new(q[o], q[o + 1], q[o + 2]), e.into())?;
            let l = m.inv_rotational_mass(&frame, &e).cholesky()?.l();
            Some((o, 1.0 / m.mass.sqrt(), l.transpose()))
        })
        .collect();
    let mut col = vec![0.0; nb];
    let mut raw = vec![0.0; model.n_coords()];
    // Reflectors: v_j lives in reflectors[j * nb + j..(j + 1) * nb].
    let mut reflectors: Vec<f64> = Vec::new();
    let mut betas: Vec<f64> = Vec::new();
    let mut dependent = Vec::new();
    for &i in rows {
        raw.fill(0.0);
        let span = jac.row_ptr()[i]..jac.row_ptr()[i + 1];
        for p in span {
            raw[jac.col_idx()[p]] = ell[i] * jac.values()[p];
        }
        col.fill(0.0);
        for (o, inv_sqrt_m, lt) in &halves {
            for c in 0..3 {
                col[o + c] = raw[o + c] * inv_sqrt_m;
            }
            let ce = lt * Vector4::new(raw[o + 3], raw[o + 4], raw[o + 5], raw[o + 6]);
            col[o + 3..o + 7].copy_from_slice(ce.as_slice());
        }
        let mut at = nb0;
        for (o, w, lt) in &aux {
            let c = lt * nalgebra::DVector::from_column_slice(&raw[*o..o + w]);
            col[at..at + w].copy_from_slice(c.as_slice());
            at += w;
        }
        let own = norm(&col);
        let kept = betas.len();
        for (j, &beta) in betas.iter().enumerate() {
            let v = &reflectors[j * nb + j..(j + 1) * nb];
            let t = beta * dot(v, &col[j..]);
            for (c, vk) in col[j..].iter_mut().zip(v) {
                *c -= t * vk;
            }
        }
        let tail = norm(&col[kept..]);
        let independent =
            tail.partial_cmp(&(REDUNDANCY_TOLERANCE * own)) == Some(Ordering::Greater);
        if !independent || kept == nb {
            dependent.push(i);
            continue;
        }
        let alpha = if col[kept] >= 0.0 { -tail } else { tail };
        let mut v = vec![0.0; nb];
        v[kept..].copy_from_slice(&col[kept..]);
        v[kept] -= alpha;
        let vv = dot(&v[kept..], &v[kept..]);
        reflectors.extend_from_slice(&v);
        betas.push(2.0 / vv);
    }
    dependent
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[inline]
fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BodySpec, JointKind, JointSpec, ModelBuilder, SolverSettings};

    /// A beam welded to the ground at one end and pinned (spherical) at the
    /// other: 9 rows on a rigid body's 6 motions, so a rigid beam's three
    /// pin rows depend on the weld's; a flexible beam's two transverse ones
    /// do not (they hold its bending), its axial one still does (the beam
    /// bends, it does not stretch). The dense QR and the sparse ordered
    /// test must both see the deformation columns.
    fn clamped_pinned(flexible: bool) -> Model {
        let mut b = ModelBuilder::new();
        b.body(BodySpec::fixed("ground"));
        let mut beam = BodySpec::new("beam").mass(0.05).inertia([1e-6, 2e-4, 2e-4]);
        if flexible {
            beam = beam.flexible(crate::flexible::BeamSpec::new([0.0, 0.2], 0.05, 3));
        }
        b.body(beam);
        b.joint(JointSpec::new(JointKind::Fixed, "ground", "beam").named("clamp"));
        b.joint(
            JointSpec::new(JointKind::Spherical, "beam", "ground")
                .named("pin")
                .anchors([0.2, 0.0, 0.0], [0.2, 0.0, 0.0]),
        );
        b.build().unwrap()
    }

    #[test]
    fn deformation_columns_make_a_clamped_pinned_beam_independent() {
        for (flexible, masked) in [(false, 3), (true, 1)] {
            let model = clamped_pinned(flexible);
            let mut ev = model.evaluation();
            ev.evaluate(&model, model.q0(), &[]).unwrap();
            let s = Scaling::new(&model, &SolverSettings::default());
            let masses = BodyMass::of_model(&model);
            let rows: Vec<usize> = (0..model.n_rows())
                .filter(|&i| s.role[i] == Role::Equality)
                .collect();
            let dense = dependent_in_order(&model, &ev, &masses, &s.ell, &rows);
            assert_eq!(dense.len(), masked, "flexible {flexible}: dense {dense:?}");
            let p = crate::Program::new(
                std::sync::Arc::new(model),
                SolverSettings {
                    redundancy: RedundancyCheck::Dense,
                    ..SolverSettings::default()
                },
            )
            .unwrap();
            assert_eq!(p.redundancy().rows.len(), masked, "flexible {flexible}");
        }
    }
}
