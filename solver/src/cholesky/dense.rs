//! A dense path for small matrices: the same factorisation as the
//! supernodal one (same order, same tail, same regularised-pivot rule), on
//! one dense column-major n × n array instead of supernode blocks.
//!
//! The question it answers: below a few dozen rows, do the supernodal
//! kernels' bookkeeping (per supernode a loop over its updates, each with
//! its destination rows and scatter indices; per solve a kernel call per
//! supernode) cost more than plain dense arithmetic? (The four-bar's and
//! Bennett's Eq. 7 matrix has 23 rows and 4 leading supernodes.) Measured:
//! no, see [`DENSE_MAX`]; the fast loop does not take this path. Here the
//! factor is right-looking:
//! column j is scaled by its reciprocal pivot, then every later column k with
//! L_kj ≠ 0 takes the update L_kj · L_{k..n, j}, a contiguous multiply-add
//! that vectorises. An entry L_kj that is exactly zero updates nothing, so
//! the work follows the sparsity of L without any index list; the result
//! equals the supernodal factor's up to the order of each entry's sum.
//!
//! Layout of the values: the n × n column-major factor (lower triangle; the
//! tail's block ends as the Schur complement A_TT − L_TL L_TLᵀ), then a copy
//! of that complement as a t × t row-major lower triangle (the upper half
//! zero), the form `Cholesky::tail_block` hands out.
//!
//! # Real-time
//! `factor`, `forward` and `backward` allocate nothing; their time is fixed
//! by n and the zeros of L.

use super::{NotPositive, Regularization, kernels::pivot};

/// Largest order (tail included) that takes the dense path in the fast
/// loop: 0, none. Measured against the supernodal kernels on the four-bar
/// and Bennett (order 23), Peaucellier (51) and Stewart (103), it was
/// slower on every one (the four-bar's factor 0.97 against 0.63 µs, a solve
/// 0.53 against 0.28 µs, the tick 1.16×; BENCHMARKS.md, "Issue 23 — the
/// small linkages' tick, third pass"): at these orders L is nearly dense
/// already and the supernodal kernels' fixed-width unrolling beats ~250
/// short variable-length multiply-adds. Kept, tested against the
/// supernodal factor, for a faster dense kernel to be measured against.
pub(crate) const DENSE_MAX: usize = 0;

/// The dense path's layout and load map for one pattern.
#[derive(Debug, Clone)]
pub(super) struct Dense {
    n: usize,
    tail: usize,
    /// (value index in the input, position in the column-major factor) of
    /// every entry of the lower triangle, in the factor's order.
    load: Vec<(u32, u32)>,
}

impl Dense {
    /// The layout for the n × n matrix whose lower triangle's entries are
    /// (row, column, value index), the last `tail` rows unfactored,
    /// permuted by `iperm` (original → factor order, the tail last).
    /// Allocates.
    pub fn new(n: usize, tail: usize, iperm: &[u32], entries: &[(usize, usize, usize)]) -> Self {
        let load = entries
            .iter()
            .map(|&(r, c, v)| {
                let (pr, pc) = (iperm[r] as usize, iperm[c] as usize);
                let (row, col) = (pr.max(pc), pr.min(pc));
                (v as u32, (col * n + row) as u32)
            })
            .collect();
        Self { n, tail, load }
    }

    /// Stored values: the factor and the tail's copy.
    pub fn len_values(&self) -> usize {
        self.n * self.n + self.tail * self.tail
    }

    /// The tail's Schur complement (t × t row-major lower triangle) of the
    /// last factorisation in `values`.
    pub fn tail_block<'a>(&self, values: &'a [f64]) -> &'a [f64] {
        &values[self.n * self.n..self.len_values()]
    }

    /// Factors the leading block of the matrix whose values are `a` into
    /// `values`, leaving the tail's Schur complement. Returns the number
    /// of regularised pivots; the error names the column (factor order) of
    /// a pivot that stayed not positive.
    pub fn factor(
        &self,
        values: &mut [f64],
        a: &[f64],
        reg: Regularization,
        simd: bool,
    ) -> Result<usize, NotPositive> {
        #[cfg(target_arch = "x86_64")]
        if simd {
            // SAFETY: `simd` is true only where the CPU reported AVX2 and
            // FMA (`kernels::simd_available`).
            return unsafe { factor_avx2(self, values, a, reg) };
        }
        let _ = simd;
        factor_in(self, values, a, reg)
    }

    /// work ← L⁻¹ work (factor order, one right-hand side) over the leading
    /// columns: the tail's entries end as r_T − L_TL w.
    pub fn forward(&self, values: &[f64], work: &mut [f64], simd: bool) {
        #[cfg(target_arch = "x86_64")]
        if simd {
            // SAFETY: as in `factor`.
            return unsafe { forward_avx2(self, values, work) };
        }
        let _ = simd;
        forward_in(self, values, work);
    }

    /// work ← L⁻ᵀ work over the leading columns, the tail's entries as
    /// they are (subtracting L_TLᵀ x_T).
    pub fn backward(&self, values: &[f64], work: &mut [f64], simd: bool) {
        #[cfg(target_arch = "x86_64")]
        if simd {
            // SAFETY: as in `factor`.
            return unsafe { backward_avx2(self, values, work) };
        }
        let _ = simd;
        backward_in(self, values, work);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn factor_avx2(
    d: &Dense,
    values: &mut [f64],
    a: &[f64],
    reg: Regularization,
) -> Result<usize, NotPositive> {
    factor_in(d, values, a, reg)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn forward_avx2(d: &Dense, values: &[f64], work: &mut [f64]) {
    forward_in(d, values, work);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn backward_avx2(d: &Dense, values: &[f64], work: &mut [f64]) {
    backward_in(d, values, work);
}

/// The load, the right-looking factor of the leading columns, and the
/// tail's copy (see the module docs).
#[inline(always)]
fn factor_in(
    d: &Dense,
    values: &mut [f64],
    a: &[f64],
    reg: Regularization,
) -> Result<usize, NotPositive> {
    let (n, t) = (d.n, d.tail);
    let lead = n - t;
    let (l, copy) = values[..d.len_values()].split_at_mut(n * n);
    l.fill(0.0);
    for &(src, dst) in &d.load {
        l[dst as usize] += a[src as usize];
    }
    let mut replaced = 0;
    for j in 0..lead {
        let (done, rest) = l.split_at_mut((j + 1) * n);
        let col = &mut done[j * n..];
        let (p, r) = pivot(col[j], reg, j)?;
        replaced += r;
        col[j] = p.sqrt();
        let inv = 1.0 / col[j];
        for v in &mut col[j + 1..] {
            *v *= inv;
        }
        for k in j + 1..n {
            let lkj = col[k];
            if lkj == 0.0 {
                continue;
            }
            let target = &mut rest[(k - j - 1) * n + k..(k - j) * n];
            for (x, y) in target.iter_mut().zip(&col[k..]) {
                *x -= lkj * y;
            }
        }
    }
    for f in 0..t {
        for g in 0..t {
            copy[f * t + g] = if g <= f {
                l[(lead + g) * n + lead + f]
            } else {
                0.0
            };
        }
    }
    Ok(replaced)
}

#[inline(always)]
fn forward_in(d: &Dense, values: &[f64], work: &mut [f64]) {
    let n = d.n;
    let work = &mut work[..n];
    for j in 0..n - d.tail {
        let col = &values[j * n..(j + 1) * n];
        let xj = work[j] / col[j];
        work[j] = xj;
        if xj == 0.0 {
            continue;
        }
        for (x, l) in work[j + 1..].iter_mut().zip(&col[j + 1..]) {
            *x -= xj * l;
        }
    }
}

#[inline(always)]
fn backward_in(d: &Dense, values: &[f64], work: &mut [f64]) {
    let n = d.n;
    let work = &mut work[..n];
    for j in (0..n - d.tail).rev() {
        let col = &values[j * n + j + 1..(j + 1) * n];
        let x = &work[j + 1..];
        let mut acc = [0.0f64; 4];
        let (cc, cx) = (col.chunks_exact(4), x.chunks_exact(4));
        let (rc, rx) = (cc.remainder(), cx.remainder());
        for (p, q) in cc.zip(cx) {
            for i in 0..4 {
                acc[i] += p[i] * q[i];
            }
        }
        let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
        for (p, q) in rc.iter().zip(rx) {
            s += p * q;
        }
        work[j] = (work[j] - s) / values[j * n + j];
    }
}
