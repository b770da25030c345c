//! The multilevel (aggregation, algebraic-multigrid style) preconditioner
//! of A_JJ (`ForceSolver::Multilevel`), applied as one symmetric V-cycle.
//!
//! - **Finest level**: A_JJ by dense blocks, one node per constraint (a
//!   joint's rows together); two joints are coupled when they share a
//!   moving body.
//! - **Coarsening** (`coarsen`): nodes are aggregated greedily over that
//!   graph (a joint and the joints that share a body with it, i.e. the
//!   bodies around it form a cluster); each aggregate keeps up to `modes`
//!   coarse unknowns, the lowest eigenvectors of its own Jacobi-scaled
//!   diagonal block: the force patterns its joints barely resist, those a
//!   smoother cannot reduce (around a loop, the self-stresses). T is built
//!   from the values of the first factorisation and kept; the coarse
//!   operators Tᵀ A T are recomputed from the tick's A at every
//!   factorisation (no allocation).
//! - **Smoother**: one block Gauss–Seidel sweep per constraint / aggregate
//!   block (forward before the coarse correction, backward after it, so
//!   the V-cycle is a symmetric operator and serves conjugate gradients).
//! - **Coarsest level** (at most `COARSEST` rows, or when coarsening
//!   stalls): a dense Cholesky factor.

use super::super::gram::Gram;
use super::super::small::substitute;
use super::super::solve::FactorError;
use super::block::{BlockMat, dense_cholesky};
use super::coarsen::Coarsening;

/// Coarse unknowns per aggregate.
pub(crate) const MODES: usize = 6;
/// How T is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Prolongation {
    /// Lowest eigenvectors of each aggregate's scaled diagonal block.
    Eigen,
    /// Relaxed test vectors (this many symmetric sweeps; measured, not
    /// the tick's: BENCHMARKS.md).
    #[cfg_attr(not(test), allow(dead_code))]
    Relaxed(usize),
}
/// The tick's prolongation.
pub(crate) const PROLONGATION: Prolongation = Prolongation::Eigen;

/// Rows at which coarsening stops (a dense factor below).
const COARSEST: usize = 96;

/// One level above the coarsest: its matrix, the map to the next level,
/// and its V-cycle buffers.
#[derive(Debug, Clone)]
struct Level {
    a: BlockMat,
    down: Coarsening,
    x: Vec<f64>,
    b: Vec<f64>,
    r: Vec<f64>,
}

/// The preconditioner: levels fine to coarse, the coarsest dense.
#[derive(Debug, Clone)]
pub(crate) struct Multilevel {
    levels: Vec<Level>,
    coarsest: BlockMat,
    dense: Vec<f64>,
    xc: Vec<f64>,
    /// Per J row: its row at the finest level.
    perm: Vec<usize>,
    /// Per value of A_JJ's lower triangle: its one or two places in the
    /// finest level's blocks (usize::MAX: none) and its row and column.
    map: Vec<(usize, usize)>,
    rc: Vec<(u32, u32)>,
    w: Vec<f64>,
    /// T has been built (from the first factorisation's values).
    built: bool,
    /// How T is built.
    pub prolongation: Prolongation,
}

/// The preconditioner's shape and its projected steps' iterations
/// ([`Program::multilevel_stats`](crate::Program::multilevel_stats)).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MultilevelStats {
    /// Rows per level, finest (n_J) to coarsest.
    pub rows: Vec<usize>,
    /// Nodes (constraints, then aggregates) per level.
    pub nodes: Vec<usize>,
    /// Stored values of every level's blocks (both triangles).
    pub values: usize,
    /// Conjugate-gradient iterations of every projected step so far.
    pub step_iterations: u64,
}

impl Multilevel {
    /// The levels of `gram`'s A_JJ pattern; `group[j]`: the constraint of
    /// J row j. Allocates.
    pub fn new(gram: &Gram, group: &[usize], modes: usize) -> Self {
        let (finest, perm, map, rc) = finest(gram, group);
        let mut levels = Vec::new();
        let mut a = finest;
        while a.rows() > COARSEST {
            let (down, coarse) = Coarsening::new(&a, modes.max(1));
            if coarse.rows() * 10 > a.rows() * 9 {
                break;
            }
            let n = a.rows();
            levels.push(Level {
                a,
                down,
                x: vec![0.0; n],
                b: vec![0.0; n],
                r: vec![0.0; n],
            });
            a = coarse;
        }
        let n = a.rows();
        let w = levels
            .iter()
            .map(|l| l.a.max_size() * (l.a.max_size().max(modes)))
            .chain([a.max_size()])
            .max()
            .unwrap_or(1);
        Self {
            levels,
            dense: vec![0.0; n * n],
            xc: vec![0.0; n],
            coarsest: a,
            perm,
            map,
            rc,
            w: vec![0.0; w.max(1)],
            built: false,
            prolongation: PROLONGATION,
        }
    }

    /// Its shape; `step_iterations` from the caller.
    pub fn stats(&self, step_iterations: u64) -> MultilevelStats {
        let mats = self.levels.iter().map(|l| &l.a).chain([&self.coarsest]);
        MultilevelStats {
            rows: mats.clone().map(|a| a.rows()).collect(),
            nodes: mats.clone().map(|a| a.nodes()).collect(),
            values: mats.map(|a| a.vals.len()).sum(),
            step_iterations,
        }
    }

    /// Takes A_JJ's values from `gram` (rows the assembly switched off
    /// become unit rows), builds T on the first call, and forms every
    /// level's operator, smoother and the coarsest factor.
    ///
    /// # Real-time
    /// No allocation. O(nnz(A) · modes) for the Galerkin products plus the
    /// coarsest dense factor; the first call also runs the aggregates'
    /// eigensolves.
    pub fn factor(&mut self, gram: &Gram) -> Result<(), FactorError> {
        let off = &gram.decoupled;
        let a0 = match self.levels.first_mut() {
            Some(l) => &mut l.a,
            None => &mut self.coarsest,
        };
        a0.vals.fill(0.0);
        for ((&(p1, p2), &(r, c)), &v) in self.map.iter().zip(&self.rc).zip(&gram.values) {
            let (r, c) = (r as usize, c as usize);
            let v = if off[r] || off[c] {
                if r == c { 1.0 } else { 0.0 }
            } else {
                v
            };
            if !v.is_finite() {
                return Err(FactorError);
            }
            a0.vals[p1] = v;
            if p2 != usize::MAX {
                a0.vals[p2] = v;
            }
        }
        // T needs an assembled A (a factorisation before the first
        // assembly sees zeros): built at the first one with values.
        let build = !self.built && a0.vals.iter().any(|v| *v != 0.0);
        for i in 0..self.levels.len() {
            let (l, rest) = self.levels[i..].split_first_mut().expect("level");
            let next = match rest.first_mut() {
                Some(n) => &mut n.a,
                None => &mut self.coarsest,
            };
            l.a.factor_diag();
            if build {
                match self.prolongation {
                    Prolongation::Eigen => l.down.build_t(&l.a),
                    Prolongation::Relaxed(sweeps) => {
                        l.down.build_t_relaxed(&l.a, sweeps, &mut self.w)
                    }
                }
            }
            l.down.galerkin(&l.a, next, &mut self.w);
        }
        self.built |= build;
        let n = self.coarsest.rows();
        let d = &mut self.dense;
        d.fill(0.0);
        let a = &self.coarsest;
        for g in 0..a.nodes() {
            for b in a.ptr[g]..a.ptr[g + 1] {
                let (v, sr, sc) = a.block(g, b);
                let (r0, c0) = (a.start[g], a.start[a.col[b]]);
                for i in 0..sr {
                    d[(r0 + i) * n + c0..(r0 + i) * n + c0 + sc]
                        .copy_from_slice(&v[i * sc..(i + 1) * sc]);
                }
            }
        }
        dense_cholesky(d, n);
        Ok(())
    }

    /// x ← M⁻¹ x for `k` columns of n_J entries (column-major): one
    /// V-cycle per column.
    ///
    /// # Real-time
    /// No allocation; per column about two passes over every level's
    /// blocks plus the coarsest triangular solves.
    pub fn apply(&mut self, x: &mut [f64], k: usize) {
        let n = self.perm.len();
        for col in x.chunks_exact_mut(n).take(k) {
            let b = match self.levels.first_mut() {
                Some(l) => &mut l.b,
                None => &mut self.xc,
            };
            for (j, &p) in self.perm.iter().enumerate() {
                b[p] = col[j];
            }
            vcycle(
                &mut self.levels,
                &self.coarsest,
                &self.dense,
                &mut self.xc,
                &mut self.w,
            );
            let xs = match self.levels.first() {
                Some(l) => &l.x,
                None => &self.xc,
            };
            for (j, &p) in self.perm.iter().enumerate() {
                col[j] = xs[p];
            }
        }
    }
}

/// levels[0].x ← V-cycle(levels[0].b); the coarsest (`coarsest`'s
/// layout, `dense` its factor) solves `xc` in place.
fn vcycle(levels: &mut [Level], coarsest: &BlockMat, dense: &[f64], xc: &mut [f64], w: &mut [f64]) {
    let Some((l, rest)) = levels.split_first_mut() else {
        substitute(dense, xc);
        return;
    };
    l.x.fill(0.0);
    l.a.gauss_seidel(&l.b, &mut l.x, w, true);
    l.a.mul(&l.x, &mut l.r);
    for (r, b) in l.r.iter_mut().zip(&l.b) {
        *r = b - *r;
    }
    match rest.first_mut() {
        Some(next) => {
            l.down.restrict(&l.a, &next.a.start, &l.r, &mut next.b);
            vcycle(rest, coarsest, dense, xc, w);
            let next = &rest[0];
            l.down.prolong_add(&l.a, &next.a.start, &next.x, &mut l.x);
        }
        None => {
            l.down.restrict(&l.a, &coarsest.start, &l.r, xc);
            substitute(dense, xc);
            l.down.prolong_add(&l.a, &coarsest.start, xc, &mut l.x);
        }
    }
    l.a.gauss_seidel(&l.b, &mut l.x, w, false);
}

/// The finest level's block pattern from A_JJ's (one node per constraint,
/// its rows in J order), each J row's place in it, and each stored value's
/// place(s) and (row, column). Allocates.
#[allow(clippy::type_complexity)]
fn finest(
    gram: &Gram,
    group: &[usize],
) -> (BlockMat, Vec<usize>, Vec<(usize, usize)>, Vec<(u32, u32)>) {
    let n = gram.n_j;
    let mut node_of_group = std::collections::HashMap::new();
    let mut node = vec![0; n];
    for j in 0..n {
        let next = node_of_group.len();
        node[j] = *node_of_group.entry(group[j]).or_insert(next);
    }
    let nodes = node_of_group.len();
    let mut start = vec![0; nodes + 1];
    for &g in &node {
        start[g + 1] += 1;
    }
    for g in 0..nodes {
        start[g + 1] += start[g];
    }
    let mut fill = start.clone();
    let mut perm = vec![0; n];
    for j in 0..n {
        perm[j] = fill[node[j]];
        fill[node[j]] += 1;
    }
    let (cp, ri) = (gram.pattern.col_ptr(), gram.pattern.row_idx());
    let mut pairs: Vec<(usize, usize)> = (0..nodes).map(|g| (g, g)).collect();
    for c in 0..n {
        for &r in &ri[cp[c]..cp[c + 1]] {
            pairs.push((node[r], node[c]));
            pairs.push((node[c], node[r]));
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    let a = BlockMat::new(start, &pairs);
    let place = |r: usize, c: usize| {
        let (nr, nc) = (node[r], node[c]);
        let row = &a.col[a.ptr[nr]..a.ptr[nr + 1]];
        let b = a.ptr[nr] + row.binary_search(&nc).expect("block pattern");
        a.off[b] + (perm[r] - a.start[nr]) * a.size(nc) + (perm[c] - a.start[nc])
    };
    let (mut map, mut rc) = (Vec::new(), Vec::new());
    for c in 0..n {
        for &r in &ri[cp[c]..cp[c + 1]] {
            let p2 = if r == c { usize::MAX } else { place(c, r) };
            map.push((place(r, c), p2));
            rc.push((r as u32, c as u32));
        }
    }
    (a, perm, map, rc)
}

/// The multilevel preconditioner of `model`'s A_JJ (one finest node per
/// constraint), as the tick's [`Precond`](super::Precond). Allocates.
pub(crate) fn for_model(model: &crate::model::Model, gram: &Gram) -> super::Precond {
    let group: Vec<usize> = (gram.j_rows.iter())
        .map(|&r| model.rows()[r].constraint.index())
        .collect();
    super::Precond::Multilevel(Box::new(Multilevel::new(gram, &group, MODES)))
}

#[cfg(test)]
impl Multilevel {
    /// Levels, the coarsest included.
    pub fn depth(&self) -> usize {
        self.levels.len() + 1
    }

    /// Level `l`'s operator, dense row-major in its own row order (the
    /// finest's: `perm`), and its rows.
    pub fn dense_level(&self, l: usize) -> (Vec<f64>, usize) {
        let a = self.levels.get(l).map_or(&self.coarsest, |x| &x.a);
        let n = a.rows();
        let mut d = vec![0.0; n * n];
        for g in 0..a.nodes() {
            for b in a.ptr[g]..a.ptr[g + 1] {
                let (v, sr, sc) = a.block(g, b);
                let (r0, c0) = (a.start[g], a.start[a.col[b]]);
                for i in 0..sr {
                    for j in 0..sc {
                        d[(r0 + i) * n + c0 + j] = v[i * sc + j];
                    }
                }
            }
        }
        (d, n)
    }

    /// The prolongation from level `l` to level `l + 1`, dense
    /// (rows_l × rows_{l+1}, row-major).
    pub fn dense_t(&self, l: usize) -> Vec<f64> {
        let (a, down) = (&self.levels[l].a, &self.levels[l].down);
        let next = self.levels.get(l + 1).map_or(&self.coarsest, |x| &x.a);
        let (n, nc) = (a.rows(), next.rows());
        let mut t = vec![0.0; n * nc];
        for g in 0..a.nodes() {
            let (h, on, c) = (down.agg[g], down.agg_off[g], down.t_cols[down.agg[g]]);
            for i in 0..a.size(g) {
                for k in 0..c {
                    t[(a.start[g] + i) * nc + next.start[h] + k] =
                        down.t[down.t_off[h] + (on + i) * c + k];
                }
            }
        }
        t
    }

    /// Per J row: its row at the finest level.
    pub fn perm(&self) -> &[usize] {
        &self.perm
    }
}
