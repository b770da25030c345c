//! One coarsening step of the multilevel preconditioner
//! (`precond::multilevel`): greedy aggregation of a level's nodes over its
//! block graph, the tentative prolongation T (per aggregate, the lowest
//! eigenvectors of its Jacobi-scaled diagonal block: the force patterns
//! the aggregate's own couplings barely resist, of which the loops'
//! self-stresses are made), and the Galerkin product Tᵀ A T.

use super::super::small::symmetric_eigen;
use super::block::{BlockMat, dot};

/// The map from a level to the next coarser one.
#[derive(Debug, Clone)]
pub(crate) struct Coarsening {
    /// Per fine node: its aggregate (the coarse node).
    pub agg: Vec<usize>,
    /// Per fine node: its first row among its aggregate's rows.
    pub agg_off: Vec<usize>,
    /// Per aggregate: its rows (fine) and columns (coarse unknowns).
    pub t_rows: Vec<usize>,
    pub t_cols: Vec<usize>,
    /// Per aggregate: its T (t_rows × t_cols, row-major) in `t`.
    pub t_off: Vec<usize>,
    pub t: Vec<f64>,
    /// Per fine block: the coarse block it adds into.
    gal: Vec<usize>,
    /// Scratch: a dense aggregate block and its eigenvectors.
    dense: Vec<f64>,
    vecs: Vec<f64>,
    scale: Vec<f64>,
    /// Scratch: the relaxed test vectors (rows × modes, column-major) and
    /// a zero right-hand side.
    tests: Vec<f64>,
    zero: Vec<f64>,
}

/// Greedy aggregation (smoothed-aggregation style) over `a`'s block
/// graph: a node whose neighbours are all free roots an aggregate of
/// itself and them; the rest join a neighbour's aggregate (or stand alone).
/// Returns per node its aggregate, and the count. Allocates.
pub(crate) fn aggregate(a: &BlockMat) -> (Vec<usize>, usize) {
    const FREE: usize = usize::MAX;
    let nodes = a.nodes();
    let mut agg = vec![FREE; nodes];
    let mut count = 0;
    let nbrs = |n: usize| a.col[a.ptr[n]..a.ptr[n + 1]].iter().copied();
    for n in 0..nodes {
        if agg[n] == FREE && nbrs(n).all(|m| agg[m] == FREE) {
            for m in nbrs(n) {
                agg[m] = count;
            }
            agg[n] = count;
            count += 1;
        }
    }
    let rooted = agg.clone();
    for (n, g) in agg.iter_mut().enumerate() {
        if *g == FREE {
            if let Some(m) = nbrs(n).find(|&m| rooted[m] != FREE) {
                *g = rooted[m];
            } else {
                *g = count;
                count += 1;
            }
        }
    }
    (agg, count)
}

impl Coarsening {
    /// The aggregation of `a` with up to `modes` coarse unknowns per
    /// aggregate, and the coarse level's block pattern (values zero).
    /// Allocates.
    pub fn new(a: &BlockMat, modes: usize) -> (Self, BlockMat) {
        let (agg, count) = aggregate(a);
        let (mut agg_off, mut t_rows) = (vec![0; a.nodes()], vec![0; count]);
        for n in 0..a.nodes() {
            agg_off[n] = t_rows[agg[n]];
            t_rows[agg[n]] += a.size(n);
        }
        // An aggregate coupled to nothing else (a decoupled quaternion-norm
        // row) is solved exactly by its block smoother: no coarse unknown.
        let mut coupled = vec![false; count];
        for n in 0..a.nodes() {
            coupled[agg[n]] |= a.col[a.ptr[n]..a.ptr[n + 1]].iter().any(|&m| m != n);
        }
        let t_cols: Vec<usize> = (t_rows.iter().zip(&coupled))
            .map(|(&s, &c)| if c { s.min(modes) } else { 0 })
            .collect();
        let mut t_off = Vec::with_capacity(count);
        let mut len = 0;
        for (r, c) in t_rows.iter().zip(&t_cols) {
            t_off.push(len);
            len += r * c;
        }
        let mut start = vec![0; count + 1];
        for g in 0..count {
            start[g + 1] = start[g] + t_cols[g];
        }
        let mut pairs = Vec::new();
        for n in 0..a.nodes() {
            for b in a.ptr[n]..a.ptr[n + 1] {
                pairs.push((agg[n], agg[a.col[b]]));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let coarse = BlockMat::new(start, &pairs);
        let mut gal = Vec::with_capacity(a.col.len());
        for n in 0..a.nodes() {
            let g = agg[n];
            let row = &coarse.col[coarse.ptr[g]..coarse.ptr[g + 1]];
            for b in a.ptr[n]..a.ptr[n + 1] {
                let k = row.binary_search(&agg[a.col[b]]).expect("coarse pattern");
                gal.push(coarse.ptr[g] + k);
            }
        }
        let big = t_rows.iter().copied().max().unwrap_or(0);
        let this = Self {
            agg,
            agg_off,
            t_rows,
            t_cols,
            t_off,
            t: vec![0.0; len],
            gal,
            dense: vec![0.0; big * big],
            vecs: vec![0.0; big * big],
            scale: vec![0.0; big],
            tests: vec![0.0; a.rows() * modes],
            zero: vec![0.0; a.rows()],
        };
        (this, coarse)
    }

    /// T from `a`'s values: per aggregate, the eigenvectors of its
    /// diagonal block D^{-1/2} A_gg D^{-1/2} with the smallest eigenvalues,
    /// scaled back by D^{-1/2}.
    ///
    /// # Real-time
    /// No allocation; cyclic Jacobi sweeps on each aggregate's dense block
    /// (O(Σ rows³) a sweep): a refresh, not every solve.
    pub fn build_t(&mut self, a: &BlockMat) {
        for g in 0..self.t_rows.len() {
            let s = self.t_rows[g];
            let d = &mut self.dense[..s * s];
            d.fill(0.0);
            // Gather A_gg.
            for n in (0..a.nodes()).filter(|&n| self.agg[n] == g) {
                let on = self.agg_off[n];
                for b in a.ptr[n]..a.ptr[n + 1] {
                    let m = a.col[b];
                    if self.agg[m] != g {
                        continue;
                    }
                    let om = self.agg_off[m];
                    let (v, sr, sc) = a.block(n, b);
                    for i in 0..sr {
                        d[(on + i) * s + om..(on + i) * s + om + sc]
                            .copy_from_slice(&v[i * sc..(i + 1) * sc]);
                    }
                }
            }
            let sc = &mut self.scale[..s];
            for i in 0..s {
                let di = d[i * s + i];
                sc[i] = if di > 0.0 && di.is_finite() {
                    1.0 / di.sqrt()
                } else {
                    1.0
                };
            }
            for i in 0..s {
                for j in 0..s {
                    d[i * s + j] *= sc[i] * sc[j];
                }
            }
            let v = &mut self.vecs[..s * s];
            symmetric_eigen(d, v, s);
            // The c smallest eigenvalues' columns, by selection.
            let c = self.t_cols[g];
            let t = &mut self.t[self.t_off[g]..self.t_off[g] + s * c];
            let mut last = f64::NEG_INFINITY;
            let mut last_idx = usize::MAX;
            for k in 0..c {
                // The next smallest after (last, last_idx) in (value, index) order.
                let mut best = usize::MAX;
                for i in 0..s {
                    let key = (d[i * s + i], i);
                    let after = key.0 > last || (key.0 == last && i > last_idx);
                    if after && (best == usize::MAX || key.0 < d[best * s + best]) {
                        best = i;
                    }
                }
                last = d[best * s + best];
                last_idx = best;
                for i in 0..s {
                    t[i * c + k] = v[i * s + best] * sc[i];
                }
            }
        }
    }

    /// T from `a`'s values by relaxed test vectors: `modes` pseudo-random
    /// vectors smoothed by `sweeps` symmetric block Gauss–Seidel sweeps on
    /// A v = 0 (what survives them is the error the smoother cannot
    /// reduce: A's near-null space), then per aggregate the orthonormal
    /// basis of their restrictions (modified Gram–Schmidt). `a`'s diagonal
    /// blocks must be factored; `w` holds `a.max_size()` values.
    ///
    /// # Real-time
    /// No allocation; O(modes · sweeps · stored values): a refresh, not
    /// every solve.
    pub fn build_t_relaxed(&mut self, a: &BlockMat, sweeps: usize, w: &mut [f64]) {
        let n = a.rows();
        let k = self.tests.len() / n.max(1);
        let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
        for v in self.tests.iter_mut() {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            *v = (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
        }
        self.zero.fill(0.0);
        for v in self.tests.chunks_exact_mut(n) {
            for _ in 0..sweeps {
                a.gauss_seidel(&self.zero, v, w, true);
                a.gauss_seidel(&self.zero, v, w, false);
            }
            let top = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            if top > 0.0 {
                v.iter_mut().for_each(|x| *x /= top);
            }
        }
        for g in 0..self.t_rows.len() {
            let (s, c) = (self.t_rows[g], self.t_cols[g]);
            // Q (s × c) from the first c test vectors' rows of aggregate g.
            let t = &mut self.t[self.t_off[g]..self.t_off[g] + s * c];
            for nd in (0..a.nodes()).filter(|&nd| self.agg[nd] == g) {
                let on = self.agg_off[nd];
                for i in 0..a.size(nd) {
                    for col in 0..c.min(k) {
                        t[(on + i) * c + col] = self.tests[col * n + a.start[nd] + i];
                    }
                }
            }
            for col in 0..c {
                for prev in 0..col {
                    let d: f64 = (0..s).map(|i| t[i * c + col] * t[i * c + prev]).sum();
                    for i in 0..s {
                        t[i * c + col] -= d * t[i * c + prev];
                    }
                }
                let norm = (0..s).map(|i| t[i * c + col].powi(2)).sum::<f64>().sqrt();
                let inv = if norm > 1e-10 { 1.0 / norm } else { 0.0 };
                for i in 0..s {
                    t[i * c + col] *= inv;
                }
            }
        }
    }

    /// coarse ← Tᵀ A T from `a`'s values; `w` holds at least
    /// max node size × max aggregate columns values.
    ///
    /// # Real-time
    /// No allocation; per stored block of A two small dense products.
    pub fn galerkin(&self, a: &BlockMat, coarse: &mut BlockMat, w: &mut [f64]) {
        coarse.vals.fill(0.0);
        for n in 0..a.nodes() {
            let (g, on) = (self.agg[n], self.agg_off[n]);
            let ca = self.t_cols[g];
            let ta = &self.t[self.t_off[g]..];
            for b in a.ptr[n]..a.ptr[n + 1] {
                let m = a.col[b];
                let (h, om) = (self.agg[m], self.agg_off[m]);
                let cb = self.t_cols[h];
                let tb = &self.t[self.t_off[h]..];
                let (v, sr, sc) = a.block(n, b);
                // W = B T_b[om.., :] (sr × cb).
                let w = &mut w[..sr * cb];
                w.fill(0.0);
                for i in 0..sr {
                    for j in 0..sc {
                        let bij = v[i * sc + j];
                        if bij != 0.0 {
                            let trow = &tb[(om + j) * cb..(om + j + 1) * cb];
                            for (wk, tk) in w[i * cb..(i + 1) * cb].iter_mut().zip(trow) {
                                *wk += bij * tk;
                            }
                        }
                    }
                }
                // C += T_a[on.., :]ᵀ W (ca × cb).
                let off = coarse.off[self.gal[b]];
                let cblk = &mut coarse.vals[off..off + ca * cb];
                for i in 0..sr {
                    let arow = &ta[(on + i) * ca..(on + i + 1) * ca];
                    let wrow = &w[i * cb..(i + 1) * cb];
                    for (p, &tp) in arow.iter().enumerate() {
                        for (c, &wq) in cblk[p * cb..(p + 1) * cb].iter_mut().zip(wrow) {
                            *c += tp * wq;
                        }
                    }
                }
            }
        }
    }

    /// xc ← Tᵀ r (fine residual to coarse right-hand side).
    ///
    /// # Real-time
    /// No allocation.
    pub fn restrict(&self, a: &BlockMat, cstart: &[usize], r: &[f64], xc: &mut [f64]) {
        xc.fill(0.0);
        for n in 0..a.nodes() {
            let (g, on) = (self.agg[n], self.agg_off[n]);
            let c = self.t_cols[g];
            let cs = cstart[g];
            let t = &self.t[self.t_off[g]..];
            for i in 0..a.size(n) {
                let ri = r[a.start[n] + i];
                for (x, tk) in xc[cs..cs + c]
                    .iter_mut()
                    .zip(&t[(on + i) * c..(on + i + 1) * c])
                {
                    *x += tk * ri;
                }
            }
        }
    }

    /// x += T xc (coarse correction back to the fine level).
    ///
    /// # Real-time
    /// No allocation.
    pub fn prolong_add(&self, a: &BlockMat, cstart: &[usize], xc: &[f64], x: &mut [f64]) {
        for n in 0..a.nodes() {
            let (g, on) = (self.agg[n], self.agg_off[n]);
            let c = self.t_cols[g];
            let cs = cstart[g];
            let t = &self.t[self.t_off[g]..];
            for i in 0..a.size(n) {
                x[a.start[n] + i] += dot(&t[(on + i) * c..(on + i + 1) * c], &xc[cs..cs + c]);
            }
        }
    }
}
