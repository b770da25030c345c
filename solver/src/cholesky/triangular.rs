//! The triangular solves through a factor: forward (L⁻¹) and backward
//! (L⁻ᵀ) substitution over the supernodes, with kernels unrolled for widths
//! 1–16 and for up to 8 interleaved right-hand sides; compiled a second
//! time for AVX2 and FMA as the factorisation's kernels are (`kernels`).

use super::symbolic::Symbolic;

/// work ← L⁻¹ work over the leading block's columns (`k` interleaved
/// right-hand sides): the tail entries end as r_T − L_TL w. `simd`:
/// `kernels::simd_available` said so.
/// `diagonal[s]`: supernode s's factor is diagonal (see
/// `kernels::numeric`); its columns are only scaled.
pub(super) fn forward(
    sym: &Symbolic,
    values: &[f64],
    work: &mut [f64],
    k: usize,
    simd: bool,
    diagonal: &[bool],
) {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` is true only where the CPU reported AVX2 and FMA.
        return unsafe { forward_avx2(sym, values, work, k, diagonal) };
    }
    let _ = simd;
    forward_in(sym, values, work, k, diagonal);
}

/// work ← L⁻ᵀ work over the leading block's columns, with the tail
/// entries as they are (subtracting L_TLᵀ x_T).
pub(super) fn backward(
    sym: &Symbolic,
    values: &[f64],
    work: &mut [f64],
    k: usize,
    simd: bool,
    diagonal: &[bool],
) {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: as in `forward`.
        return unsafe { backward_avx2(sym, values, work, k, diagonal) };
    }
    let _ = simd;
    backward_in(sym, values, work, k, diagonal);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn forward_avx2(sym: &Symbolic, values: &[f64], work: &mut [f64], k: usize, diagonal: &[bool]) {
    forward_in(sym, values, work, k, diagonal);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn backward_avx2(sym: &Symbolic, values: &[f64], work: &mut [f64], k: usize, diagonal: &[bool]) {
    backward_in(sym, values, work, k, diagonal);
}

/// work ← L⁻¹ work over the leading block's columns (`k` interleaved
/// right-hand sides): the tail entries end as r_T − L_TL w.
#[inline(always)]
fn forward_in(sym: &Symbolic, values: &[f64], work: &mut [f64], k: usize, diagonal: &[bool]) {
    match k {
        1 => forward_one(sym, values, work, diagonal),
        2 => forward_k::<2>(sym, values, work),
        3 => forward_k::<3>(sym, values, work),
        4 => forward_k::<4>(sym, values, work),
        5 => forward_k::<5>(sym, values, work),
        6 => forward_k::<6>(sym, values, work),
        7 => forward_k::<7>(sym, values, work),
        _ => forward_k::<8>(sym, values, work),
    }
}

/// work ← L⁻ᵀ work over the leading block's columns, with the tail
/// entries as they are (subtracting L_TLᵀ x_T).
#[inline(always)]
fn backward_in(sym: &Symbolic, values: &[f64], work: &mut [f64], k: usize, diagonal: &[bool]) {
    match k {
        1 => backward_one(sym, values, work, diagonal),
        2 => backward_k::<2>(sym, values, work),
        3 => backward_k::<3>(sym, values, work),
        4 => backward_k::<4>(sym, values, work),
        5 => backward_k::<5>(sym, values, work),
        6 => backward_k::<6>(sym, values, work),
        7 => backward_k::<7>(sym, values, work),
        _ => backward_k::<8>(sym, values, work),
    }
}

/// [`forward`] for one right-hand side: per supernode a
/// kernel of its width (1–16 unrolled at compile time).
#[inline(always)]
fn forward_one(sym: &Symbolic, values: &[f64], work: &mut [f64], diagonal: &[bool]) {
    for (s, sn) in sym.supernodes[..sym.lead_supernodes].iter().enumerate() {
        let (c0, w) = (sn.c0 as usize, sn.w as usize);
        let block = &values[sn.val as usize..sn.val as usize + (w + sn.nrows as usize) * w];
        if diagonal[s] {
            scale_diagonal(block, c0, w, work);
            continue;
        }
        let below = &sym.rows[sn.rows as usize..(sn.rows + sn.nrows) as usize];
        macro_rules! fixed {
            ($($n:literal)*) => {
                match w {
                    $($n => forward_fixed::<$n>(block, below, c0, work),)*
                    _ => forward_any(block, below, c0, w, work),
                }
            };
        }
        fixed!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
    }
}

/// [`backward`] for one right-hand side.
#[inline(always)]
fn backward_one(sym: &Symbolic, values: &[f64], work: &mut [f64], diagonal: &[bool]) {
    let lead = &sym.supernodes[..sym.lead_supernodes];
    for (s, sn) in lead.iter().enumerate().rev() {
        let (c0, w) = (sn.c0 as usize, sn.w as usize);
        let block = &values[sn.val as usize..sn.val as usize + (w + sn.nrows as usize) * w];
        if diagonal[s] {
            scale_diagonal(block, c0, w, work);
            continue;
        }
        let below = &sym.rows[sn.rows as usize..(sn.rows + sn.nrows) as usize];
        macro_rules! fixed {
            ($($n:literal)*) => {
                match w {
                    $($n => backward_fixed::<$n>(block, below, c0, work),)*
                    _ => backward_any(block, below, c0, w, work),
                }
            };
        }
        fixed!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
    }
}

/// A diagonal supernode's part of either substitution: x_c ← x_c / L_cc
/// (nothing below it to update).
#[inline(always)]
fn scale_diagonal(block: &[f64], c0: usize, w: usize, work: &mut [f64]) {
    for c in 0..w {
        work[c0 + c] /= block[c * w + c];
    }
}

#[inline(always)]
fn forward_k<const K: usize>(sym: &Symbolic, values: &[f64], work: &mut [f64]) {
    for sn in &sym.supernodes[..sym.lead_supernodes] {
        let (c0, w) = (sn.c0 as usize, sn.w as usize);
        let block = &values[sn.val as usize..sn.val as usize + (w + sn.nrows as usize) * w];
        let (head, tail) = work.split_at_mut((c0 + w) * K);
        let xs = &mut head[c0 * K..];
        for jj in 0..w {
            let row = &block[jj * w..jj * w + w];
            let mut acc = [0.0; K];
            acc.copy_from_slice(&xs[jj * K..jj * K + K]);
            for (l, &lv) in row[..jj].iter().enumerate() {
                let xl = &xs[l * K..l * K + K];
                for t in 0..K {
                    acc[t] -= lv * xl[t];
                }
            }
            let inv = 1.0 / row[jj];
            for t in 0..K {
                xs[jj * K + t] = acc[t] * inv;
            }
        }
        let below = &sym.rows[sn.rows as usize..(sn.rows + sn.nrows) as usize];
        let base = c0 + w;
        for (row, &r) in block[w * w..].chunks_exact(w).zip(below) {
            let mut acc = [0.0; K];
            for (l, &lv) in row.iter().enumerate() {
                let xl = &xs[l * K..l * K + K];
                for t in 0..K {
                    acc[t] += lv * xl[t];
                }
            }
            let at = (r as usize - base) * K;
            let xr = &mut tail[at..at + K];
            for t in 0..K {
                xr[t] -= acc[t];
            }
        }
    }
}

#[inline(always)]
fn backward_k<const K: usize>(sym: &Symbolic, values: &[f64], work: &mut [f64]) {
    for sn in sym.supernodes[..sym.lead_supernodes].iter().rev() {
        let (c0, w) = (sn.c0 as usize, sn.w as usize);
        let block = &values[sn.val as usize..sn.val as usize + (w + sn.nrows as usize) * w];
        let below = &sym.rows[sn.rows as usize..(sn.rows + sn.nrows) as usize];
        let base = c0 + w;
        let (head, tail) = work.split_at_mut(base * K);
        let xs = &mut head[c0 * K..];
        for (row, &r) in block[w * w..].chunks_exact(w).zip(below) {
            let at = (r as usize - base) * K;
            let mut xr = [0.0; K];
            xr.copy_from_slice(&tail[at..at + K]);
            for (l, &lv) in row.iter().enumerate() {
                let xl = &mut xs[l * K..l * K + K];
                for t in 0..K {
                    xl[t] -= lv * xr[t];
                }
            }
        }
        for jj in (0..w).rev() {
            let row = &block[jj * w..jj * w + w];
            let inv = 1.0 / row[jj];
            let mut xj = [0.0; K];
            for t in 0..K {
                xj[t] = xs[jj * K + t] * inv;
                xs[jj * K + t] = xj[t];
            }
            for (l, &lv) in row[..jj].iter().enumerate() {
                let xl = &mut xs[l * K..l * K + K];
                for t in 0..K {
                    xl[t] -= lv * xj[t];
                }
            }
        }
    }
}

/// One supernode of the forward substitution, width `W`: x_S ← L_SS⁻¹ x_S,
/// then x_r −= L_rS x_S for each row r below.
#[inline(always)]
fn forward_fixed<const W: usize>(block: &[f64], below: &[u32], c0: usize, work: &mut [f64]) {
    let (rows, _) = block.as_chunks::<W>();
    let (diag, under) = rows.split_at(W);
    let mut xs: [f64; W] = work[c0..c0 + W].try_into().expect("W entries");
    // Column by column: x_j final, then subtracted from every later entry.
    // Each entry sees the same subtractions in the same order as a row's
    // dot product would give it (the result is the same to the last bit),
    // but the chain between two pivots is one multiply-add, not a dot
    // product (issue 23).
    for j in 0..W {
        xs[j] /= diag[j][j];
        let xj = xs[j];
        for i in j + 1..W {
            xs[i] -= diag[i][j] * xj;
        }
    }
    work[c0..c0 + W].copy_from_slice(&xs);
    for (row, &r) in under.iter().zip(below) {
        let mut s = 0.0;
        for l in 0..W {
            s += row[l] * xs[l];
        }
        work[r as usize] -= s;
    }
}

/// [`forward_fixed`] for any width.
#[inline(always)]
fn forward_any(block: &[f64], below: &[u32], c0: usize, w: usize, work: &mut [f64]) {
    for jj in 0..w {
        let row = &block[jj * w..jj * w + w];
        let mut s = work[c0 + jj];
        for (l, &lv) in row[..jj].iter().enumerate() {
            s -= lv * work[c0 + l];
        }
        work[c0 + jj] = s / row[jj];
    }
    for (row, &r) in block[w * w..].chunks_exact(w).zip(below) {
        let xs = &work[c0..c0 + w];
        let s: f64 = row.iter().zip(xs).map(|(a, b)| a * b).sum();
        work[r as usize] -= s;
    }
}

/// One supernode of the backward substitution, width `W`:
/// x_S ← L_SS⁻ᵀ (x_S − Σ_r L_rSᵀ x_r).
#[inline(always)]
fn backward_fixed<const W: usize>(block: &[f64], below: &[u32], c0: usize, work: &mut [f64]) {
    let (rows, _) = block.as_chunks::<W>();
    let (diag, under) = rows.split_at(W);
    let mut xs: [f64; W] = work[c0..c0 + W].try_into().expect("W entries");
    for (row, &r) in under.iter().zip(below) {
        let xr = work[r as usize];
        for l in 0..W {
            xs[l] -= row[l] * xr;
        }
    }
    for j in (0..W).rev() {
        xs[j] /= diag[j][j];
        let xj = xs[j];
        for l in 0..j {
            xs[l] -= diag[j][l] * xj;
        }
    }
    work[c0..c0 + W].copy_from_slice(&xs);
}

/// [`backward_fixed`] for any width.
#[inline(always)]
fn backward_any(block: &[f64], below: &[u32], c0: usize, w: usize, work: &mut [f64]) {
    for (row, &r) in block[w * w..].chunks_exact(w).zip(below) {
        let xr = work[r as usize];
        for (l, &lv) in row.iter().enumerate() {
            work[c0 + l] -= lv * xr;
        }
    }
    for jj in (0..w).rev() {
        let row = &block[jj * w..jj * w + w];
        work[c0 + jj] /= row[jj];
        let xj = work[c0 + jj];
        for (l, &lv) in row[..jj].iter().enumerate() {
            work[c0 + l] -= lv * xj;
        }
    }
}
