//! [`small`](super::small)'s full-rank finger solve for an m_f known at
//! compile time (3: a point finger, 6: a rigid grasp or two points).
//!
//! The generic code indexes `a[i * n + k]` with n known only at run time:
//! every access is bounds-checked and no loop unrolls, so the 6 × 6
//! Cholesky and its seven pairs of triangular solves (six for ‖A⁻¹‖₁) were
//! a sixth of the Stewart tick. Here each loop is the generic one's, with
//! the same operations in the same order on `[[f64; N]; N]` rows: the
//! result, and the full-rank decision, are the generic path's bit for bit
//! (`tests::the_fixed_size_solve_equals_the_generic_one_bit_for_bit`).

use super::small::RANK_TOLERANCE;

/// [`small::full_rank_solve`](super::small) for n = `N` (`b.len()` = N,
/// `a`, `v` at least N × N).
///
/// # Real-time
/// No allocation; N³/6 + 7 N² multiply-adds.
pub(super) fn full_rank_solve<const N: usize>(
    a: &[f64],
    b: &[f64],
    x: &mut [f64],
    v: &mut [f64],
    reference: f64,
) -> Result<(), f64> {
    let a: &[[f64; N]] = &a.as_chunks::<N>().0[..N];
    let l: &mut [[f64; N]] = &mut v.as_chunks_mut::<N>().0[..N];
    let b: &[f64; N] = b.try_into().expect("N right-hand sides");
    let x: &mut [f64; N] = x.try_into().expect("N unknowns");
    l.copy_from_slice(a);
    let norm = (0..N)
        .map(|c| (0..N).map(|r| a[r][c].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    if !factor::<N>(l) {
        return Err(f64::INFINITY);
    }
    let mut inv_norm = 0.0f64;
    for c in 0..N {
        *x = [0.0; N];
        x[c] = 1.0;
        substitute::<N>(l, x);
        inv_norm = inv_norm.max(x.iter().map(|t| t.abs()).sum());
    }
    if !(inv_norm.is_finite() && inv_norm * 1e3 * RANK_TOLERANCE * norm.max(reference) < 1.0) {
        return Err(inv_norm);
    }
    *x = *b;
    substitute::<N>(l, x);
    x.iter()
        .all(|t| t.is_finite())
        .then_some(())
        .ok_or(inv_norm)
}

/// `small::factor_in_place` on N × N rows (its index loops kept as they
/// are, so the two read alike).
#[inline(always)]
#[allow(clippy::needless_range_loop)]
fn factor<const N: usize>(a: &mut [[f64; N]]) -> bool {
    for j in 0..N {
        let mut d = a[j][j];
        for k in 0..j {
            d -= a[j][k] * a[j][k];
        }
        if d.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return false;
        }
        let d = d.sqrt();
        a[j][j] = d;
        for i in j + 1..N {
            let mut v = a[i][j];
            for k in 0..j {
                v -= a[i][k] * a[j][k];
            }
            a[i][j] = v / d;
        }
    }
    true
}

/// `small::substitute` on N × N rows.
#[inline(always)]
fn substitute<const N: usize>(l: &[[f64; N]], b: &mut [f64; N]) {
    for i in 0..N {
        let mut v = b[i];
        for k in 0..i {
            v -= l[i][k] * b[k];
        }
        b[i] = v / l[i][i];
    }
    for i in (0..N).rev() {
        let mut v = b[i];
        for k in i + 1..N {
            v -= l[k][i] * b[k];
        }
        b[i] = v / l[i][i];
    }
}

#[cfg(test)]
mod tests {
    use super::super::small::full_rank_solve_generic;

    /// A symmetric positive definite N × N matrix from a seed: B Bᵀ + c I.
    fn spd(n: usize, seed: u64, c: f64) -> Vec<f64> {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let m: Vec<f64> = (0..n * n).map(|_| next()).collect();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = (0..n).map(|k| m[i * n + k] * m[j * n + k]).sum::<f64>();
            }
            a[i * n + i] += c;
        }
        a
    }

    fn compare<const N: usize>(a: &[f64], b: &[f64], reference: f64) -> bool {
        let (mut x1, mut v1) = (vec![0.0; N], vec![0.0; N * N]);
        let (mut x2, mut v2) = (vec![0.0; N], vec![0.0; N * N]);
        let fixed = super::full_rank_solve::<N>(a, b, &mut x1, &mut v1, reference);
        let generic = full_rank_solve_generic(a, b, &mut x2, &mut v2, reference);
        let bound = |r: Result<(), f64>| r.map_err(f64::to_bits);
        assert_eq!(bound(fixed), bound(generic), "the two paths decide alike");
        let fixed = fixed.is_ok();
        if fixed {
            let bits = |x: &[f64]| x.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&x1), bits(&x2), "N = {N}");
            assert_eq!(bits(&v1), bits(&v2), "the factors, N = {N}");
        }
        fixed
    }

    /// The fixed-size path against the generic loops: well-conditioned
    /// matrices (taken, same bits), nearly singular ones and a rank-deficient
    /// one (refused by both), a non-positive pivot (refused by both).
    #[test]
    fn the_fixed_size_solve_equals_the_generic_one_bit_for_bit() {
        let mut taken = 0;
        for seed in 0..40u64 {
            for &c in &[1.0, 1e-3, 1e-8, 0.0] {
                let b3: Vec<f64> = (0..3).map(|k| 0.3 * k as f64 - 0.2 + seed as f64).collect();
                let b6: Vec<f64> = (0..6).map(|k| 0.1 * k as f64 - 0.4 - seed as f64).collect();
                taken += usize::from(compare::<3>(&spd(3, seed, c), &b3, 0.0));
                taken += usize::from(compare::<6>(&spd(6, seed, c), &b6, 0.0));
                // A reference far above the matrix's scale refuses it.
                assert!(!compare::<6>(&spd(6, seed, c), &b6, 1e12));
            }
        }
        // Well-conditioned ones take the path (c = 1 always does).
        assert!(taken >= 80, "taken {taken}");
        let mut singular = spd(6, 7, 0.0);
        for j in 0..6 {
            singular[5 * 6 + j] = singular[4 * 6 + j];
            singular[j * 6 + 5] = singular[j * 6 + 4];
        }
        assert!(!compare::<6>(&singular, &[1.0; 6], 0.0));
        let mut indefinite = spd(3, 3, 1.0);
        indefinite[0] = -1.0;
        assert!(!compare::<3>(&indefinite, &[1.0; 3], 0.0));
    }
}
