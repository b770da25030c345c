//! The dense arithmetic of the numeric factorisation: each supernode's
//! incoming updates (row dot products over contiguous memory, to
//! precomputed destinations) and its dense factor, with kernels unrolled for
//! widths 1–16.
//!
//! **Vector instructions.** The crate is built for the x86-64 baseline
//! (SSE2: two f64 lanes, no fused multiply-add). Where the CPU has AVX2 and
//! FMA (checked once, when a factor is analysed), the same kernels run
//! compiled for them: four lanes and one rounding per multiply-add. The
//! result then differs from the baseline build's in the last bits, and is
//! still the same run to run on one machine. BENCHMARKS.md has both.

use super::symbolic::Symbolic;
use super::{NotPositive, Regularization};

/// Whether this CPU runs the AVX2 + FMA kernels.
pub(super) fn simd_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// One numeric factorisation into `values` (the supernodes' blocks) of the
/// matrix whose values are `a`: the load, then per supernode its updates
/// and (leading supernodes only) its dense factor. Returns the number of
/// regularised pivots. `simd`: [`simd_available`] said so.
///
/// # Real-time
/// No allocation; time fixed by the pattern.
pub(super) fn numeric(
    sym: &Symbolic,
    values: &mut [f64],
    inv: &mut [f64],
    a: &[f64],
    reg: Regularization,
    simd: bool,
    decoupled: &[bool],
) -> Result<usize, NotPositive> {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` is true only where the CPU reported AVX2 and FMA
        // (`simd_available`), the features `numeric_avx2` is compiled for.
        return unsafe { numeric_avx2(sym, values, inv, a, reg, decoupled) };
    }
    let _ = simd;
    numeric_in(sym, values, inv, a, reg, decoupled)
}

/// [`numeric_in`] compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn numeric_avx2(
    sym: &Symbolic,
    values: &mut [f64],
    inv: &mut [f64],
    a: &[f64],
    reg: Regularization,
    decoupled: &[bool],
) -> Result<usize, NotPositive> {
    numeric_in(sym, values, inv, a, reg, decoupled)
}

/// `decoupled[s]`: every column of supernode s has A's entries zero off
/// the diagonal (rows a force solve switched off), so its L is diagonal,
/// √A_jj, and it neither gives nor takes an update (see
/// `Cholesky::factor_decoupled`).
#[inline(always)]
fn numeric_in(
    sym: &Symbolic,
    v: &mut [f64],
    inv: &mut [f64],
    a: &[f64],
    reg: Regularization,
    decoupled: &[bool],
) -> Result<usize, NotPositive> {
    v.fill(0.0);
    for &(src, dst) in &sym.load {
        v[dst as usize] += a[src as usize];
    }
    let mut regularized = 0;
    for s in 0..sym.supernodes.len() {
        let sn = &sym.supernodes[s];
        let (before, rest) = v.split_at_mut(sn.val as usize);
        let w = sn.w as usize;
        let block = &mut rest[..(w + sn.nrows as usize) * w];
        if decoupled[s] {
            regularized += diagonal_factor(block, w, sn.c0 as usize, reg)?;
            continue;
        }
        for u in &sym.updates[sn.updates.0 as usize..sn.updates.1 as usize] {
            if decoupled[u.src as usize] {
                // Its rows below the diagonal are zero: no update.
                continue;
            }
            let d = &sym.supernodes[u.src as usize];
            let wd = d.w as usize;
            let (a0, m) = (u.a as usize, u.m as usize);
            let slab = &before[d.val as usize + (wd + a0) * wd..][..m * wd];
            let cols = &sym.rows[d.rows as usize + a0..][..(u.b - u.a) as usize];
            let rel = &sym.rel[u.rel as usize..][..m];
            update(block, w, sn.c0 as usize, slab, wd, cols, rel);
        }
        if s < sym.lead_supernodes {
            regularized += dense_factor(block, w, sn.c0 as usize, reg, inv)?;
        }
    }
    Ok(regularized)
}

/// Σ aᵢ bᵢ over the shorter of the two.
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ta, tb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ta.iter().zip(tb) {
        s += x * y;
    }
    s
}

/// The four dot products of rows a0, a1 with rows b0, b1 (all of length
/// `b0.len()`): [a0·b0, a0·b1, a1·b0, a1·b1], two lanes each.
#[inline(always)]
fn dot2x2(a0: &[f64], a1: &[f64], b0: &[f64], b1: &[f64]) -> [f64; 4] {
    let n = b0.len();
    let (a0, a1, b1) = (&a0[..n], &a1[..n], &b1[..n]);
    let mut s = [[0.0f64; 2]; 4];
    let pairs = n / 2;
    for p in 0..pairs {
        let k = 2 * p;
        for l in 0..2 {
            s[0][l] += a0[k + l] * b0[k + l];
            s[1][l] += a0[k + l] * b1[k + l];
            s[2][l] += a1[k + l] * b0[k + l];
            s[3][l] += a1[k + l] * b1[k + l];
        }
    }
    let mut out = [
        s[0][0] + s[0][1],
        s[1][0] + s[1][1],
        s[2][0] + s[2][1],
        s[3][0] + s[3][1],
    ];
    if n % 2 == 1 {
        let k = n - 1;
        out[0] += a0[k] * b0[k];
        out[1] += a0[k] * b1[k];
        out[2] += a1[k] * b0[k];
        out[3] += a1[k] * b1[k];
    }
    out
}

/// Subtracts from the target `block` (width `w`, first column `c0`) the
/// update of one earlier supernode: `slab` holds that supernode's rows from
/// its first row in the target's columns on (row-major, width `wd`); the
/// first `cols.len()` of them fall in the target's columns `cols`, and row
/// `ri` lands at the target's local row `rel[ri]`. Lower triangle only,
/// two rows by two columns at a time.
#[inline(always)]
fn update(
    block: &mut [f64],
    w: usize,
    c0: usize,
    slab: &[f64],
    wd: usize,
    cols: &[u32],
    rel: &[u32],
) {
    // A source supernode's width is its rows' length: with it known at
    // compile time the dot products unroll (widths 1–16 cover the built-in
    // mechanisms' supernodes but the sphere toys' largest few).
    macro_rules! fixed {
        ($($n:literal)*) => {
            match wd {
                $($n => update_fixed::<$n>(block, w, c0, slab, cols, rel),)*
                _ => update_any(block, w, c0, slab, wd, cols, rel),
            }
        };
    }
    fixed!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// [`update`] for a source of width `W`.
#[inline(always)]
fn update_fixed<const W: usize>(
    block: &mut [f64],
    w: usize,
    c0: usize,
    slab: &[f64],
    cols: &[u32],
    rel: &[u32],
) {
    let rows: &[[f64; W]] = as_rows(slab);
    let (nb, m) = (cols.len(), rel.len());
    let dot = |a: &[f64; W], b: &[f64; W]| {
        let mut s = 0.0;
        for k in 0..W {
            s += a[k] * b[k];
        }
        s
    };
    for ci in 0..nb {
        let col = cols[ci] as usize - c0;
        let b = &rows[ci];
        let mut ri = ci;
        while ri + 2 <= m {
            let (r0, r1) = (&rows[ri], &rows[ri + 1]);
            let (mut s0, mut s1) = (0.0, 0.0);
            for k in 0..W {
                s0 += r0[k] * b[k];
                s1 += r1[k] * b[k];
            }
            block[rel[ri] as usize * w + col] -= s0;
            block[rel[ri + 1] as usize * w + col] -= s1;
            ri += 2;
        }
        if ri < m {
            block[rel[ri] as usize * w + col] -= dot(&rows[ri], b);
        }
    }
}

/// `slab` (a whole number of rows of `W`) as rows.
#[inline(always)]
fn as_rows<const W: usize>(slab: &[f64]) -> &[[f64; W]] {
    let (rows, rest) = slab.as_chunks::<W>();
    debug_assert!(rest.is_empty());
    rows
}

/// [`update`] for any width.
#[inline(always)]
fn update_any(
    block: &mut [f64],
    w: usize,
    c0: usize,
    slab: &[f64],
    wd: usize,
    cols: &[u32],
    rel: &[u32],
) {
    let (nb, m) = (cols.len(), rel.len());
    let row = |i: usize| &slab[i * wd..i * wd + wd];
    let mut ci = 0;
    while ci < nb {
        let two = ci + 1 < nb;
        let col0 = cols[ci] as usize - c0;
        let col1 = if two {
            cols[ci + 1] as usize - c0
        } else {
            col0
        };
        let (b0, b1) = (row(ci), if two { row(ci + 1) } else { row(ci) });
        let mut ri = ci;
        while ri + 1 < m {
            let t = dot2x2(row(ri), row(ri + 1), b0, b1);
            let (d0, d1) = (rel[ri] as usize * w, rel[ri + 1] as usize * w);
            block[d0 + col0] -= t[0];
            if two && ri > ci {
                block[d0 + col1] -= t[1];
            }
            block[d1 + col0] -= t[2];
            if two {
                block[d1 + col1] -= t[3];
            }
            ri += 2;
        }
        if ri < m {
            let r = row(ri);
            let d0 = rel[ri] as usize * w;
            block[d0 + col0] -= dot(r, b0);
            if two && ri > ci {
                block[d0 + col1] -= dot(r, b1);
            }
        }
        ci += 2;
    }
}

/// A pivot d before its square root: replaced by `reg.delta` (counted, 1)
/// when at or below `reg.epsilon`; an error naming column `index` when it
/// is still not positive and finite.
#[inline(always)]
pub(super) fn pivot(
    d: f64,
    reg: Regularization,
    index: usize,
) -> Result<(f64, usize), NotPositive> {
    let (d, replaced) = if d <= reg.epsilon {
        (reg.delta, 1)
    } else {
        (d, 0)
    };
    if !(d > 0.0 && d.is_finite()) {
        return Err(NotPositive { index });
    }
    Ok((d, replaced))
}

/// [`dense_factor`] of a block that is diagonal (its off-diagonal entries,
/// below rows included, are zero and stay zero): √ of each pivot, with the
/// same regularisation.
fn diagonal_factor(
    block: &mut [f64],
    w: usize,
    c0: usize,
    reg: Regularization,
) -> Result<usize, NotPositive> {
    let mut replaced = 0;
    for i in 0..w {
        let (d, r) = pivot(block[i * w + i], reg, c0 + i)?;
        replaced += r;
        block[i * w + i] = d.sqrt();
    }
    Ok(replaced)
}

/// Factors one supernode's block in place (its updates already applied):
/// the w × w diagonal part column by column ([`diagonal_by_columns`]), then
/// the rows below it two at a time (independent rows, so their dependency
/// chains interleave). Returns the number of regularised pivots. `c0`: the
/// block's first column (for the error's index); `inv`: scratch of at
/// least w.
#[inline(always)]
pub(super) fn dense_factor(
    block: &mut [f64],
    w: usize,
    c0: usize,
    reg: Regularization,
    inv: &mut [f64],
) -> Result<usize, NotPositive> {
    let inv = &mut inv[..w];
    let (diag, below) = block.split_at_mut(w * w);
    let replaced = diagonal_by_columns(diag, w, c0, reg, inv)?;
    below_rows(diag, below, w, inv);
    Ok(replaced)
}

/// The w × w diagonal part of a block factored column by column: the pivot
/// of column j, then every later row's entry in column j, each an
/// independent dot product of the row's first j entries with row j's, so
/// their dependency chains overlap in the pipeline instead of each entry
/// waiting for the one before it in its row. Each entry is the same
/// expression as in the row order ([`rows_order`]), only computed in
/// another order: bit-identical to it (a test checks). Fills `inv` with
/// the reciprocal pivots.
#[inline(always)]
fn diagonal_by_columns(
    diag: &mut [f64],
    w: usize,
    c0: usize,
    reg: Regularization,
    inv: &mut [f64],
) -> Result<usize, NotPositive> {
    let mut replaced = 0;
    for j in 0..w {
        let (pivot, later) = diag[j * w..].split_at_mut(w);
        let (d, r) = self::pivot(pivot[j] - dot(&pivot[..j], &pivot[..j]), reg, c0 + j)?;
        replaced += r;
        pivot[j] = d.sqrt();
        inv[j] = 1.0 / pivot[j];
        let p = &pivot[..j];
        for r in later.chunks_exact_mut(w) {
            r[j] = (r[j] - dot(&r[..j], p)) * inv[j];
        }
    }
    Ok(replaced)
}

/// The rows below a factored w × w diagonal part: unrolled for widths
/// 1–16 ([`below_fixed`]), else [`below_any`].
#[inline(always)]
fn below_rows(diag: &[f64], below: &mut [f64], w: usize, inv: &[f64]) {
    macro_rules! fixed {
        ($($n:literal)*) => {
            match w {
                $($n => below_fixed::<$n>(diag, below, inv),)*
                _ => below_any(diag, below, w, inv),
            }
        };
    }
    fixed!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// The rows below a factored diagonal block: each row x ← x L⁻ᵀ, two rows
/// at a time, width `W` known at compile time.
#[inline(always)]
fn below_fixed<const W: usize>(diag: &[f64], below: &mut [f64], inv: &[f64]) {
    let l: &[[f64; W]] = as_rows(diag);
    let (rows, _) = below.as_chunks_mut::<W>();
    let mut pairs = rows.chunks_exact_mut(2);
    for pair in &mut pairs {
        let (ra, rb) = pair.split_at_mut(1);
        let (ra, rb) = (&mut ra[0], &mut rb[0]);
        for j in 0..W {
            let (mut sa, mut sb) = (ra[j], rb[j]);
            for k in 0..j {
                sa -= ra[k] * l[j][k];
                sb -= rb[k] * l[j][k];
            }
            ra[j] = sa * inv[j];
            rb[j] = sb * inv[j];
        }
    }
    for r in pairs.into_remainder() {
        for j in 0..W {
            let mut s = r[j];
            for k in 0..j {
                s -= r[k] * l[j][k];
            }
            r[j] = s * inv[j];
        }
    }
}

/// The row order [`dense_factor`] replaced (each row of the diagonal part
/// in turn, every entry waiting for the one before it in its row): kept as
/// the reference its column order is tested against bit for bit.
#[cfg(test)]
pub(super) fn rows_order(
    block: &mut [f64],
    w: usize,
    c0: usize,
    reg: Regularization,
    inv: &mut [f64],
) -> Result<usize, NotPositive> {
    let mut replaced = 0;
    let inv = &mut inv[..w];
    for i in 0..w {
        let (done, row) = block.split_at_mut(i * w);
        let row = &mut row[..w];
        for j in 0..i {
            let rj = &done[j * w..j * w + w];
            row[j] = (row[j] - dot(&row[..j], &rj[..j])) * inv[j];
        }
        let (d, r) = pivot(row[i] - dot(&row[..i], &row[..i]), reg, c0 + i)?;
        replaced += r;
        row[i] = d.sqrt();
        inv[i] = 1.0 / row[i];
    }
    let (diag, below) = block.split_at_mut(w * w);
    below_rows(diag, below, w, inv);
    Ok(replaced)
}

/// The rows below a factored diagonal block: each row x ← x L⁻ᵀ, two
/// rows at a time.
#[inline(always)]
fn below_any(diag: &[f64], below: &mut [f64], w: usize, inv: &[f64]) {
    let mut pairs = below.chunks_exact_mut(2 * w);
    for pair in &mut pairs {
        let (ra, rb) = pair.split_at_mut(w);
        for j in 0..w {
            let rj = &diag[j * w..j * w + j];
            let t = dot2x2(&ra[..j], &rb[..j], rj, rj);
            ra[j] = (ra[j] - t[0]) * inv[j];
            rb[j] = (rb[j] - t[2]) * inv[j];
        }
    }
    let rest = pairs.into_remainder();
    if !rest.is_empty() {
        for j in 0..w {
            let rj = &diag[j * w..j * w + j];
            rest[j] = (rest[j] - dot(&rest[..j], rj)) * inv[j];
        }
    }
}
