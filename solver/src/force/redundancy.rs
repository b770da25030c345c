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

use nalgebra::{Vector3, Vector4};

use super::gram::Gram;
use super::inertia::BodyMass;
use super::solve::MultiplierSolve;
use crate::al::RedundancyCheck;
use crate::al::scaling::{Role, Scaling};
use crate::rotation::BodyFrame;
use crate::{Evaluation, Model};

mod factored;
mod ordered;
#[cfg(test)]
mod tests;

use factored::Factored;
use ordered::dependent_in_order;

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

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[inline]
fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}
