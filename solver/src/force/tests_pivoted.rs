//! The pivoted shortcut of the finger solve (`pivoted`) against the
//! eigensolve it stands in for (`small::min_norm_solve` under
//! `eigensolve_only`): random rank-deficient symmetric positive
//! semi-definite 3 × 3 and 6 × 6 blocks of every rank, with round-off sized
//! rests as the sparse solve leaves them.

use super::pivoted::{eigensolve_only, pivoted_solve};
use super::small::min_norm_solve;

/// A deterministic generator of numbers in [-0.5, 0.5).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }
}

/// B Bᵀ for a random n × r B whose column k is scaled by
/// `spread`^(−k/(r − 1)) (condition of the kept part about `spread`²), plus a symmetric rest of
/// relative size `rest`.
fn rank_deficient(g: &mut Lcg, n: usize, r: usize, spread: f64, rest: f64) -> Vec<f64> {
    let b: Vec<f64> = (0..n * r)
        .map(|k| g.next() * spread.powf(-((k % r) as f64) / (r.max(2) - 1) as f64))
        .collect();
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let v: f64 = (0..r).map(|k| b[i * r + k] * b[j * r + k]).sum();
            let e = rest * g.next();
            a[i * n + j] = v + e;
            a[j * n + i] = v + e;
        }
    }
    a
}

/// The shortcut's solve (if taken) and the eigensolve's.
type Both = (Option<(usize, Vec<f64>)>, usize, Vec<f64>);

/// Both solves on `a`, and the eigensolve's eigenvalues.
fn both_with_eigenvalues(a: &[f64], b: &[f64], reference: f64) -> (Both, Vec<f64>) {
    let n = b.len();
    let (mut x, mut l) = (vec![0.0; n], vec![0.0; n * n]);
    let fast = pivoted_solve(a, b, &mut x, &mut l, reference).map(|r| (r, x.clone()));
    let (mut a2, mut y, mut v) = (a.to_vec(), vec![0.0; n], vec![0.0; n * n]);
    let rank = eigensolve_only(|| min_norm_solve(&mut a2, b, &mut y, &mut v, reference));
    let eigenvalues = (0..n).map(|i| a2[i * n + i]).collect();
    ((fast, rank, y), eigenvalues)
}

/// [`both_with_eigenvalues`] without the eigenvalues.
fn both(a: &[f64], b: &[f64], reference: f64) -> Both {
    both_with_eigenvalues(a, b, reference).0
}

/// Every rank 1..n of 3 × 3 and 6 × 6 blocks, well and badly conditioned,
/// with rests from 0 to 1e-14: where the shortcut is taken its rank is the
/// eigensolve's and its solution within 1e-10 of the eigensolve's (relative
/// to the solution's size), or within ten times the first-order size of
/// their difference where that is larger: n (‖E‖ + ε λ_max) λ_max / λ_r²
/// (b's part in the dropped directions turned into the kept ones by an
/// angle ‖E‖/λ_r, then divided by λ_r, over a solution of size at least
/// |b|/λ_max; a rest of 1e-14 on a kept eigenvalue 1e-4 of the largest
/// moves the solution by 1e-8 relative, as it moves both solutions from the
/// rest-free block's pseudo-inverse). The shortcut is taken on most of
/// them.
#[test]
fn the_pivoted_solve_agrees_with_the_eigensolve_on_every_rank() {
    let mut g = Lcg(17);
    let (mut taken, mut cases, mut worst) = (0, 0, 0.0f64);
    for n in [3usize, 6] {
        for r in 1..=n {
            for &spread in &[1.0, 10.0, 1e2] {
                for &rest in &[0.0, 1e-15, 1e-14] {
                    for _ in 0..20 {
                        let a = rank_deficient(&mut g, n, r, spread, rest);
                        let b: Vec<f64> = (0..n).map(|_| g.next()).collect();
                        let ((fast, rank, y), eig) = both_with_eigenvalues(&a, &b, 0.0);
                        cases += 1;
                        let Some((r2, x)) = fast else { continue };
                        taken += 1;
                        assert_eq!(r2, rank, "n {n} r {r} spread {spread} rest {rest}");
                        assert_eq!(r2, r, "n {n} r {r}");
                        let size = y.iter().map(|t| t * t).sum::<f64>().sqrt();
                        let d = x
                            .iter()
                            .zip(&y)
                            .map(|(u, v)| (u - v) * (u - v))
                            .sum::<f64>();
                        let rel = d.sqrt() / size.max(1e-300);
                        let top = eig.iter().fold(0.0f64, |m, e| m.max(*e));
                        let kept = eig.iter().filter(|e| **e > 1e-9 * top);
                        let low = kept.fold(top, |m, e| m.min(*e));
                        let first_order =
                            n as f64 * (rest + f64::EPSILON * top) * top / (low * low);
                        let bound = (10.0 * first_order).max(1e-10);
                        worst = worst.max(rel / bound);
                        assert!(
                            rel <= bound,
                            "n {n} r {r} spread {spread}: {rel:e} > {bound:e}"
                        );
                    }
                }
            }
        }
    }
    eprintln!("pivoted: {taken} of {cases} taken, worst difference over its bound {worst:e}");
    assert!(taken * 10 >= cases * 9, "{taken} of {cases}");
}

/// The shortcut refuses where the decision is near the threshold: a rest
/// within three decades of it (1e-11 of the largest eigenvalue, threshold
/// 1e-9), a kept eigenvalue within three decades above it, a reference that
/// puts every eigenvalue below it (then the eigensolve's rank 0 is proved),
/// and non-finite input.
#[test]
fn the_pivoted_solve_refuses_near_the_rank_threshold() {
    let mut g = Lcg(5);
    let b = [0.3, -0.1, 0.2, 0.5, -0.4, 0.1];
    let (mut x, mut l) = ([0.0; 6], [0.0; 36]);
    for _ in 0..20 {
        let near_zero = rank_deficient(&mut g, 6, 3, 1.0, 1e-11);
        assert_eq!(pivoted_solve(&near_zero, &b, &mut x, &mut l, 0.0), None);
        // Kept eigenvalues down to about 1e-8 of the largest (spread 1e4).
        let near_kept = rank_deficient(&mut g, 6, 3, 1e4, 0.0);
        assert_eq!(pivoted_solve(&near_kept, &b, &mut x, &mut l, 0.0), None);
        let small = rank_deficient(&mut g, 6, 3, 1.0, 0.0);
        let (fast, rank, _) = both(&small, &b, 1e13);
        assert_eq!((fast.map(|f| f.0), rank), (Some(0), 0));
    }
    let mut bad = rank_deficient(&mut g, 6, 3, 1.0, 0.0);
    bad[7] = f64::NAN;
    assert_eq!(pivoted_solve(&bad, &b, &mut x, &mut l, 0.0), None);
}
