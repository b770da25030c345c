//! Branch-induced sparsity (Featherstone, *Rigid Body Dynamics
//! Algorithms*, §6.5): with the joint coordinates numbered parent before
//! child, H_ij ≠ 0 only when one of i, j is an ancestor of the other, and
//! the factorisation H = Lᵀ L done from the leaves up fills nothing: L_ij
//! (j < i) is nonzero only for j an ancestor of i. Each kernel runs over a
//! coordinate's ancestors ([`Paths`], from `parent`: per coordinate the
//! previous coordinate on its path to the ground, [`ROOT`] at the top; a
//! multi-dof joint's coordinates chain), on the caller's dense row-major
//! n × n storage (only L's ancestor entries are read or written). No
//! allocation.
//!
//! ```text
//! H = Lᵀ L,   H⁻¹ x = L⁻¹ L⁻ᵀ x,   L⁻ᵀ x stays within the ancestors of x's nonzeros
//! ```

use super::tree::JointTree;

/// No parent: the coordinate's joint hangs from the ground.
pub(crate) const ROOT: usize = usize::MAX;

/// Per joint coordinate, the previous coordinate on its path to the
/// ground (a weld's child takes its parent's last coordinate). Allocates.
pub(crate) fn dof_parents(tree: &JointTree) -> Vec<usize> {
    let mut last = vec![ROOT; tree.joints.len()];
    let mut parent = vec![ROOT; tree.dofs];
    for (k, j) in tree.joints.iter().enumerate() {
        let mut above = j.parent_joint.map_or(ROOT, |p| last[p]);
        for (d, p) in parent
            .iter_mut()
            .enumerate()
            .skip(j.dof)
            .take(j.freedom.dofs())
        {
            *p = above;
            above = d;
        }
        last[k] = above;
    }
    parent
}

/// Per coordinate, its ancestors nearest first, as flat index lists (the
/// kernels' inner loops run over slices, not a linked parent walk).
#[derive(Debug, Clone)]
pub(crate) struct Paths {
    /// Per coordinate, the previous one on its path ([`dof_parents`]).
    pub parent: Vec<usize>,
    at: Vec<usize>,
    anc: Vec<usize>,
}

impl Paths {
    /// The lists for `parent`. Allocates.
    pub(crate) fn new(parent: Vec<usize>) -> Self {
        let (mut at, mut anc) = (vec![0], Vec::new());
        for &p in &parent {
            let mut j = p;
            while j != ROOT {
                anc.push(j);
                j = parent[j];
            }
            at.push(anc.len());
        }
        Self { parent, at, anc }
    }

    /// Coordinate i's ancestors, nearest first.
    #[inline]
    pub(crate) fn of(&self, i: usize) -> &[usize] {
        &self.anc[self.at[i]..self.at[i + 1]]
    }

    /// Coordinates.
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.parent.len()
    }
}

/// Factors H (lower triangle of `h`, n × n row-major, n = paths.len()) in
/// place into L with H = Lᵀ L, from the leaves up. False if a pivot is not
/// positive (or not finite).
pub(crate) fn factor_ltl(h: &mut [f64], paths: &Paths) -> bool {
    let n = paths.len();
    for k in (0..n).rev() {
        let d = h[k * n + k];
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        h[k * n + k] = d;
        let (hk, rest) = {
            let (lo, hi) = h.split_at_mut(k * n);
            (&mut hi[..n], lo)
        };
        for &i in paths.of(k) {
            hk[i] /= d;
        }
        for &i in paths.of(k) {
            let lki = hk[i];
            let hi = &mut rest[i * n..(i + 1) * n];
            hi[i] -= lki * hk[i];
            for &j in paths.of(i) {
                hi[j] -= lki * hk[j];
            }
        }
    }
    true
}

/// x ← L⁻ᵀ x for the factor of [`factor_ltl`]. Zero entries of x are
/// skipped (their updates are exact zeros), so the work is the ancestors
/// of x's nonzeros.
#[inline]
pub(crate) fn solve_lt(l: &[f64], paths: &Paths, x: &mut [f64]) {
    let n = paths.len();
    for i in (0..n).rev() {
        if x[i] == 0.0 {
            continue;
        }
        let v = x[i] / l[i * n + i];
        x[i] = v;
        let li = &l[i * n..(i + 1) * n];
        for &j in paths.of(i) {
            x[j] -= li[j] * v;
        }
    }
}

/// x ← L⁻¹ x for the factor of [`factor_ltl`].
#[inline]
pub(crate) fn solve_l(l: &[f64], paths: &Paths, x: &mut [f64]) {
    let n = paths.len();
    for i in 0..n {
        let li = &l[i * n..(i + 1) * n];
        let mut v = x[i];
        for &j in paths.of(i) {
            v -= li[j] * x[j];
        }
        x[i] = v / li[i];
    }
}

/// x ← H⁻¹ x = L⁻¹ L⁻ᵀ x.
#[inline]
pub(crate) fn solve(l: &[f64], paths: &Paths, x: &mut [f64]) {
    solve_lt(l, paths, x);
    solve_l(l, paths, x);
}

/// The ascending positions of x's nonzeros into `to`; their count.
#[inline]
pub(crate) fn support(x: &[f64], to: &mut [u32]) -> usize {
    let mut k = 0;
    for (i, v) in x.iter().enumerate() {
        if *v != 0.0 {
            to[k] = i as u32;
            k += 1;
        }
    }
    k
}

/// a · b over `s`, positions where a may be nonzero (ascending).
#[inline]
pub(crate) fn sparse_dot(s: &[u32], a: &[f64], b: &[f64]) -> f64 {
    let mut v = 0.0;
    for &i in s {
        v += a[i as usize] * b[i as usize];
    }
    v
}

/// Multiply-adds of the branch-sparse kernels on one tick's shapes
/// (`program::joint_cost`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BranchWork {
    /// H = Lᵀ L: Σ over coordinates k of Σ over k's ancestors i of i's depth.
    pub factor: f64,
    /// One solve with L or Lᵀ: Σ over coordinates of their depth (P).
    pub path: f64,
    /// Y's rows (Σ over each row's nonzeros of their depth) and W = YᵀY
    /// (Σ over row pairs of the shorter support).
    pub gram: f64,
    /// g = Y t: Σ of the rows' supports.
    pub rows: f64,
}

impl BranchWork {
    /// The counts for `parent` and Y's row supports (lengths `supports`).
    pub(crate) fn new(parent: &[usize], supports: &[(usize, &[u32])]) -> Self {
        let mut depth = vec![0usize; parent.len()];
        let (mut factor, mut path) = (0, 0);
        for (k, &p) in parent.iter().enumerate() {
            depth[k] = 1 + if p == ROOT { 0 } else { depth[p] };
            path += depth[k];
            let mut i = p;
            while i != ROOT {
                factor += depth[i];
                i = parent[i];
            }
        }
        let (mut gram, mut rows) = (0, 0);
        for (a, &(la, sa)) in supports.iter().enumerate() {
            rows += la;
            gram += sa[..la].iter().map(|&i| depth[i as usize]).sum::<usize>();
            gram += supports[..=a]
                .iter()
                .map(|&(lb, _)| la.min(lb))
                .sum::<usize>();
        }
        Self {
            factor: factor as f64,
            path: path as f64,
            gram: gram as f64,
            rows: rows as f64,
        }
    }
}

impl super::tick::JointTick {
    /// The branch kernels' work on this tick's tree and Y's row supports at
    /// its last factor (at build: q0, no limit active). Allocates.
    pub(crate) fn branch_work(&self) -> BranchWork {
        let st = &self.stage;
        let n = st.paths.len();
        let supports: Vec<(usize, &[u32])> = (0..self.rows.len())
            .map(|i| (st.supp_len[i], &st.supp[i * n..(i + 1) * n]))
            .collect();
        BranchWork::new(&st.paths.parent, &supports)
    }
}

#[cfg(test)]
#[path = "branch_tests.rs"]
mod tests;
