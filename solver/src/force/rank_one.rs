//! The minimum-norm solve of a finger Schur complement that is rank one to
//! round-off, in closed form: a 1-DOF mechanism held by a point finger
//! (the four-bar, Bennett, Peaucellier) has S = σ u uᵀ + E with E at 1e-14
//! of σ, and the Jacobi eigensolve spent its sweeps finding u.
//!
//! With k the largest diagonal entry and s = S e_k, S's rank-one part is
//! s sᵀ / S_kk and its pseudo-inverse s sᵀ S_kk / |s|⁴. The shortcut is taken
//! only where the rest, R = S − s sᵀ / S_kk, has ‖R‖_F ≤ 1e-12 σ: then every
//! other eigenvalue of S is at most 1e-12 σ (Weyl), so the eigensolve would
//! drop them too ([`RANK_TOLERANCE`] is 1e-9), and the two solutions agree to
//! about 1e-12 relative. Anything else goes to the eigensolve.

use super::small::RANK_TOLERANCE;
use std::cmp::Ordering;

/// ‖R‖_F over σ above which the shortcut is refused.
const REST_TOLERANCE: f64 = 1e-12;

/// x = S⁺ b for the symmetric n × n `a` (row-major, left intact) when it is
/// rank one to round-off (module docs); false (x unspecified) otherwise.
/// `reference`: the scale below which an eigenvalue counts as zero, as in
/// `min_norm_solve`; a σ within three decades of that threshold is refused.
///
/// # Real-time
/// No allocation; O(n²).
pub(crate) fn rank_one_solve(a: &[f64], b: &[f64], x: &mut [f64], reference: f64) -> bool {
    let n = b.len();
    if n == 0 {
        return false;
    }
    let mut k = 0;
    for i in 1..n {
        if a[i * n + i] > a[k * n + k] {
            k = i;
        }
    }
    let skk = a[k * n + k];
    if !(skk > 0.0 && skk.is_finite()) {
        return false;
    }
    let s = |i: usize| a[i * n + k];
    let s2: f64 = (0..n).map(|i| s(i) * s(i)).sum();
    let sigma = s2 / skk;
    // NaN-safe: an incomparable σ is refused too.
    if sigma.partial_cmp(&(1e3 * RANK_TOLERANCE * reference)) != Some(Ordering::Greater) {
        return false;
    }
    let inv = 1.0 / skk;
    let mut rest2 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let r = a[i * n + j] - s(i) * s(j) * inv;
            rest2 += r * r;
        }
    }
    let limit = REST_TOLERANCE * sigma;
    if !matches!(
        rest2.partial_cmp(&(limit * limit)),
        Some(Ordering::Less | Ordering::Equal)
    ) {
        return false;
    }
    let sb: f64 = (0..n).map(|i| s(i) * b[i]).sum();
    let c = sb * skk / (s2 * s2);
    for (i, xi) in x.iter_mut().enumerate() {
        *xi = s(i) * c;
    }
    x.iter().all(|t| t.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::force::small::min_norm_solve;

    /// u uᵀ σ plus a rest of relative size `eps` on every entry.
    fn rank_one_plus(u: &[f64], sigma: f64, eps: f64) -> Vec<f64> {
        let n = u.len();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                let noise = eps * sigma * (((i + j) % 3) as f64 - 1.0);
                a[i * n + j] = sigma * u[i] * u[j] + noise;
            }
        }
        a
    }

    /// Where the shortcut is taken it agrees with the Jacobi eigensolve to
    /// 1e-11 relative, on 3 × 3 and 6 × 6; it is refused where a second
    /// eigenvalue is within reach of the rank threshold, where the matrix is
    /// not rank one, and where σ itself is round-off against the reference.
    #[test]
    fn the_rank_one_shortcut_agrees_with_the_eigensolve() {
        let u3 = [0.6, -0.8, 0.0];
        let u6 = [0.1, 0.5, -0.3, 0.7, 0.2, -0.33];
        let b = [1.0, -2.0, 0.5, 0.25, 3.0, -1.0];
        for u in [&u3[..], &u6[..]] {
            let n = u.len();
            for eps in [0.0, 1e-15, 1e-14] {
                let a0 = rank_one_plus(u, 2.5, eps);
                let mut x = vec![0.0; n];
                assert!(rank_one_solve(&a0, &b[..n], &mut x, 1.0), "{n}, {eps:e}");
                let (mut a, mut y, mut v) = (a0.clone(), vec![0.0; n], vec![0.0; n * n]);
                assert_eq!(min_norm_solve(&mut a, &b[..n], &mut y, &mut v, 1.0), 1);
                let big = y.iter().map(|t| t.abs()).fold(0.0, f64::max);
                for (xi, yi) in x.iter().zip(&y) {
                    assert!((xi - yi).abs() <= 1e-11 * big, "{n}, {eps:e}: {x:?} {y:?}");
                }
            }
            // A second eigenvalue at 1e-10 of σ: dropped by the eigensolve,
            // but too close to its threshold for the shortcut.
            let mut x = vec![0.0; n];
            assert!(!rank_one_solve(
                &rank_one_plus(u, 2.5, 1e-10),
                &b[..n],
                &mut x,
                1.0
            ));
            // σ at round-off of a large reference: the eigensolve says rank 0.
            assert!(!rank_one_solve(
                &rank_one_plus(u, 2.5, 0.0),
                &b[..n],
                &mut x,
                1e12
            ));
        }
        // Full rank: refused.
        let a = [4.0, 1.0, 0.5, 1.0, 3.0, -0.2, 0.5, -0.2, 2.0];
        assert!(!rank_one_solve(&a, &b[..3], &mut [0.0; 3], 0.0));
    }
}
