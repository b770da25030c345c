//! A symmetric matrix stored by dense blocks (block CSR, both triangles):
//! one level of the multilevel preconditioner (`precond::multilevel`).
//! Rows come in nodes (a joint's rows at the finest level, an aggregate's
//! coarse unknowns above it), each node's rows contiguous; every coupled
//! pair of nodes stores its dense block, row-major.

use super::super::small::substitute;

/// The matrix, its diagonal blocks' factors and the node layout.
#[derive(Debug, Clone)]
pub(crate) struct BlockMat {
    /// Per node: its first row (len nodes + 1).
    pub start: Vec<usize>,
    /// Per node: its blocks' range in `col` / `off` (len nodes + 1).
    pub ptr: Vec<usize>,
    /// Per block: the column node.
    pub col: Vec<usize>,
    /// Per block: its first value in `vals`.
    pub off: Vec<usize>,
    /// The blocks' values.
    pub vals: Vec<f64>,
    /// Per node: its diagonal block's index.
    diag: Vec<usize>,
    /// Per node: the lower Cholesky factor of its diagonal block, dense.
    fac: Vec<f64>,
    /// Per node: its factor's first value in `fac`.
    fac_off: Vec<usize>,
}

impl BlockMat {
    /// The block pattern of `pairs` (node pairs, sorted, unique, both
    /// triangles and every diagonal) over nodes whose rows start at
    /// `start`. Values zero. Allocates.
    pub fn new(start: Vec<usize>, pairs: &[(usize, usize)]) -> Self {
        let nodes = start.len() - 1;
        let size = |n: usize| start[n + 1] - start[n];
        let mut ptr = vec![0; nodes + 1];
        let (mut col, mut off, mut diag) = (Vec::new(), Vec::new(), vec![0; nodes]);
        let mut len = 0;
        for &(r, c) in pairs {
            ptr[r + 1] += 1;
            if r == c {
                diag[r] = col.len();
            }
            col.push(c);
            off.push(len);
            len += size(r) * size(c);
        }
        for n in 0..nodes {
            ptr[n + 1] += ptr[n];
        }
        let mut fac_off = Vec::with_capacity(nodes);
        let mut flen = 0;
        for n in 0..nodes {
            fac_off.push(flen);
            flen += size(n) * size(n);
        }
        Self {
            start,
            ptr,
            col,
            off,
            vals: vec![0.0; len],
            diag,
            fac: vec![0.0; flen],
            fac_off,
        }
    }

    /// Nodes.
    pub fn nodes(&self) -> usize {
        self.start.len() - 1
    }

    /// Rows.
    pub fn rows(&self) -> usize {
        self.start[self.nodes()]
    }

    /// Rows of node `n`.
    pub fn size(&self, n: usize) -> usize {
        self.start[n + 1] - self.start[n]
    }

    /// Largest node.
    pub fn max_size(&self) -> usize {
        (0..self.nodes()).map(|n| self.size(n)).max().unwrap_or(0)
    }

    /// Block `b` of row node `n` as (values, rows, columns).
    #[inline]
    pub fn block(&self, n: usize, b: usize) -> (&[f64], usize, usize) {
        let (sr, sc) = (self.size(n), self.size(self.col[b]));
        (&self.vals[self.off[b]..self.off[b] + sr * sc], sr, sc)
    }

    /// Factors every diagonal block (dense Cholesky, pivots floored at
    /// 1e-10 of the block's largest diagonal: a preconditioner only).
    ///
    /// # Real-time
    /// No allocation.
    pub fn factor_diag(&mut self) {
        for n in 0..self.nodes() {
            let s = self.size(n);
            let src = self.off[self.diag[n]];
            let f = &mut self.fac[self.fac_off[n]..self.fac_off[n] + s * s];
            f.copy_from_slice(&self.vals[src..src + s * s]);
            dense_cholesky(f, s);
        }
    }

    /// y = A x.
    ///
    /// # Real-time
    /// No allocation; O(stored values).
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        for n in 0..self.nodes() {
            let yn = &mut y[self.start[n]..self.start[n + 1]];
            yn.fill(0.0);
            for b in self.ptr[n]..self.ptr[n + 1] {
                let m = self.col[b];
                let (v, sr, sc) = self.block(n, b);
                let xm = &x[self.start[m]..self.start[m] + sc];
                for i in 0..sr {
                    yn[i] += dot(&v[i * sc..(i + 1) * sc], xm);
                }
            }
        }
    }

    /// One block Gauss–Seidel sweep on A x = b (forward in node order or
    /// backward); `w` holds at least `max_size` values.
    ///
    /// # Real-time
    /// No allocation; O(stored values).
    pub fn gauss_seidel(&self, b: &[f64], x: &mut [f64], w: &mut [f64], forward: bool) {
        let nodes = self.nodes();
        for k in 0..nodes {
            let n = if forward { k } else { nodes - 1 - k };
            let (s0, s) = (self.start[n], self.size(n));
            let w = &mut w[..s];
            w.copy_from_slice(&b[s0..s0 + s]);
            for bi in self.ptr[n]..self.ptr[n + 1] {
                let m = self.col[bi];
                if m == n {
                    continue;
                }
                let (v, sr, sc) = self.block(n, bi);
                let xm = &x[self.start[m]..self.start[m] + sc];
                for i in 0..sr {
                    w[i] -= dot(&v[i * sc..(i + 1) * sc], xm);
                }
            }
            substitute(&self.fac[self.fac_off[n]..self.fac_off[n] + s * s], w);
            x[s0..s0 + s].copy_from_slice(w);
        }
    }
}

#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// In-place lower Cholesky of the dense row-major s × s `a` (its upper
/// triangle is left as it was and not read afterwards); a pivot below
/// 1e-10 of the largest diagonal is raised to that floor (and to 1 when the
/// matrix is zero). Solve with it by [`substitute`].
pub(crate) fn dense_cholesky(a: &mut [f64], s: usize) {
    let top = (0..s).map(|i| a[i * s + i].abs()).fold(0.0, f64::max);
    let floor = if top > 0.0 && top.is_finite() {
        1e-10 * top
    } else {
        1.0
    };
    for j in 0..s {
        let mut d = a[j * s + j];
        for k in 0..j {
            d -= a[j * s + k] * a[j * s + k];
        }
        let d = if d > floor { d.sqrt() } else { floor.sqrt() };
        a[j * s + j] = d;
        for i in j + 1..s {
            let mut v = a[i * s + j];
            for k in 0..j {
                v -= a[i * s + k] * a[j * s + k];
            }
            a[i * s + j] = v / d;
        }
    }
}
