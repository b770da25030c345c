//! The pivoted shortcut of the finger solve (`pivoted`) against the
//! eigensolve it stands in for (`small::min_norm_solve` under
//! `eigensolve_only`): random rank-deficient symmetric positive
//! semi-definite 3 × 3 and 6 × 6 blocks of every rank, with round-off sized
//! rests as the sparse solve leaves them.

use super::pivoted::{PivotedTally, eigensolve_only, pivoted_solve, pivoted_tally};
use super::small::{full_rank_solve, min_norm_solve, symmetric_eigen};

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
    let fast =
        pivoted_solve(a, b, &mut x, &mut l, reference, f64::INFINITY).map(|r| (r, x.clone()));
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
/// the rank-deficient ones, never on a full-rank one (the full-rank
/// shortcut's).
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
                        if r == n {
                            assert_eq!(fast, None, "n {n}: full rank taken");
                            continue;
                        }
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
        assert_eq!(
            pivoted_solve(&near_zero, &b, &mut x, &mut l, 0.0, f64::INFINITY),
            None
        );
        // Kept eigenvalues down to about 1e-8 of the largest (spread 1e4).
        let near_kept = rank_deficient(&mut g, 6, 3, 1e4, 0.0);
        assert_eq!(
            pivoted_solve(&near_kept, &b, &mut x, &mut l, 0.0, f64::INFINITY),
            None
        );
        let small = rank_deficient(&mut g, 6, 3, 1.0, 0.0);
        let (fast, rank, _) = both(&small, &b, 1e13);
        assert_eq!((fast.map(|f| f.0), rank), (Some(0), 0));
    }
    let mut bad = rank_deficient(&mut g, 6, 3, 1.0, 0.0);
    bad[7] = f64::NAN;
    assert_eq!(
        pivoted_solve(&bad, &b, &mut x, &mut l, 0.0, f64::INFINITY),
        None
    );
}

/// ‖a⁻¹‖₁ as the full-rank shortcut leaves it for the precheck (∞ where its
/// factor fails), or `None` where the shortcut takes the block.
fn full_rank_bound(a: &[f64], reference: f64) -> Option<f64> {
    let n = (a.len() as f64).sqrt() as usize;
    let (mut x, mut v) = (vec![0.0; n], vec![0.0; n * n]);
    full_rank_solve(a, &vec![1.0; n], &mut x, &mut v, reference).err()
}

/// The precheck refuses no block the certificate accepts: on random blocks
/// of every rank, condition 1 to 1e8 (past the shortcuts' reach), rests up
/// to 1e-11 and references from 0 to 1e6, wherever the full-rank shortcut
/// refuses, the pivoted solve with its bound gives the solve without it bit
/// for bit (or both refuse). And it refuses where it should, by the
/// eigensolve's eigenvalues: where the precheck refuses, the smallest is
/// above τ_low (no eigenvalue near the dropped side); where the smallest is
/// above √n τ_low (so 1/‖a⁻¹‖₁ ≥ λ_min/√n is above τ_low), it refuses.
#[test]
fn the_precheck_refuses_only_what_the_certificate_refuses() {
    let mut g = Lcg(29);
    let (mut prechecked, mut taken, mut cases) = (0, 0, 0);
    for n in [3usize, 6] {
        for r in 1..=n {
            for &spread in &[1.0, 1e2, 1e3, 1e4] {
                for &rest in &[0.0, 1e-14, 1e-11] {
                    for &reference in &[0.0, 1e2, 1e6] {
                        for _ in 0..4 {
                            let a = rank_deficient(&mut g, n, r, spread, rest);
                            let b: Vec<f64> = (0..n).map(|_| g.next()).collect();
                            let Some(bound) = full_rank_bound(&a, reference) else {
                                continue;
                            };
                            cases += 1;
                            let what =
                                format!("n {n} r {r} spread {spread} rest {rest} ref {reference}");
                            let (with, was_prechecked) =
                                precheck_agrees(&a, &b, reference, bound, &what);
                            taken += usize::from(with.is_some());
                            prechecked += usize::from(was_prechecked);
                            let (mut e, mut v) = (a.clone(), vec![0.0; n * n]);
                            symmetric_eigen(&mut e, &mut v, n);
                            let smallest =
                                (0..n).map(|i| e[i * n + i]).fold(f64::INFINITY, f64::min);
                            let max_diag = (0..n).map(|i| a[i * n + i]).fold(0.0, f64::max);
                            let low = 1e-9 * max_diag.max(reference);
                            if was_prechecked {
                                assert!(smallest > low, "{what}: λ_min {smallest:e} ≤ {low:e}");
                            } else {
                                let above = smallest > 1.01 * (n as f64).sqrt() * low;
                                assert!(!above, "{what}: λ_min {smallest:e}, τ_low {low:e}");
                            }
                        }
                    }
                }
            }
        }
    }
    eprintln!("precheck: {prechecked} of {cases} refused by it, {taken} taken");
    assert!(
        taken > 100 && prechecked > 50,
        "{taken} taken, {prechecked} prechecked"
    );
}

/// The pivoted solve of `a` with the full-rank shortcut's `bound` and
/// without (∞): the same answer, bit for bit. Returns it and whether the
/// precheck refused.
fn precheck_agrees(
    a: &[f64],
    b: &[f64],
    reference: f64,
    bound: f64,
    what: &str,
) -> (Option<usize>, bool) {
    let n = b.len();
    let (mut x1, mut x2, mut l) = (vec![0.0; n], vec![0.0; n], vec![0.0; n * n]);
    let before = pivoted_tally();
    let with = pivoted_solve(a, b, &mut x1, &mut l, reference, bound);
    let was_prechecked = pivoted_tally().prechecked > before.prechecked;
    let without = pivoted_solve(a, b, &mut x2, &mut l, reference, f64::INFINITY);
    assert_eq!(with, without, "{what}");
    if with.is_some() {
        let bits = |x: &[f64]| x.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&x1), bits(&x2), "{what}");
    }
    (with, was_prechecked)
}

/// A rigid grasp of `sit-on-chair` as its force stage met it (6 × 6,
/// reference 720, recorded from `bench sit-on-chair`): full rank, smallest
/// eigenvalue 2.9e-5 against the largest 14, between the eigensolve's
/// threshold 7.2e-7 and the full-rank shortcut's bound 7.2e-4. Its
/// refusal is known in advance: `min_norm_solve` counts one precheck, no
/// factor, no served solve, and returns the eigensolve's rank 6 and
/// solution bit for bit.
#[test]
fn a_full_rank_ill_conditioned_grasp_is_refused_before_the_factor() {
    #[rustfmt::skip]
    let a = [
        11.500719219207836, 2.2800375437225374e-6, 4.354949248981659e-6, 2.2575292275752584e-11, 9.370245166204187e-6, 2.05207659372244e-6,
        2.2800375437225374e-6, 7.164717720130357, -1.6407801406047468e-12, -8.211617533100792e-5, -1.6834093518883804e-9, -3.9148910573823055,
        4.354949248981659e-6, -1.6407801406047468e-12, 6.30792649501617e-5, -9.680073483524753e-15, 3.725621714888148e-8, 1.2112986732605307e-11,
        2.2575292275752584e-11, -8.211617533100792e-5, -9.680073483524753e-15, 0.00014598303927942333, -8.414464225078003e-11, 8.775725354961268e-5,
        9.370245166204187e-6, -1.6834093518883804e-9, 3.725621714888148e-8, -8.414464225078003e-11, 0.0004667889764652269, 5.014072825553215e-9,
        2.05207659372244e-6, -3.9148910573823055, 1.2112986732605307e-11, 8.775725354961268e-5, 5.014072825553215e-9, 11.724992522891988,
    ];
    let reference = 7.20155709342411e2;
    let b = [0.3, -0.1, 0.2, 0.5, -0.4, 0.1];
    let (mut a1, mut x, mut v) = (a, [0.0; 6], [0.0; 36]);
    let before = pivoted_tally();
    let rank = min_norm_solve(&mut a1, &b, &mut x, &mut v, reference);
    let after = pivoted_tally();
    let step = PivotedTally {
        prechecked: after.prechecked - before.prechecked,
        refused: after.refused - before.refused,
        served: after.served - before.served,
    };
    let one_precheck = PivotedTally {
        prechecked: 1,
        ..PivotedTally::default()
    };
    assert_eq!(step, one_precheck);
    let (mut a2, mut y) = (a, [0.0; 6]);
    let rank2 = eigensolve_only(|| min_norm_solve(&mut a2, &b, &mut y, &mut v, reference));
    assert_eq!((rank, rank2), (6, 6));
    assert_eq!(x.map(f64::to_bits), y.map(f64::to_bits));
    assert_eq!(
        a1.map(f64::to_bits),
        a2.map(f64::to_bits),
        "the eigenvalues"
    );
    // Between the two bounds: what makes it the eigensolve's.
    let smallest = (0..6).map(|i| a2[i * 7]).fold(f64::INFINITY, f64::min);
    assert!(
        smallest > 1e-9 * reference && smallest < 1e-6 * reference,
        "{smallest:e}"
    );
    // Without the precheck the factor runs, and refuses too.
    let mut l = [0.0; 36];
    let before = pivoted_tally();
    assert_eq!(
        pivoted_solve(&a, &b, &mut x, &mut l, reference, f64::INFINITY),
        None
    );
    assert_eq!(pivoted_tally().refused, before.refused + 1);
}
