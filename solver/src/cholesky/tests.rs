//! The supernodal factor against dense linear algebra on patterns like the
//! fast loop's (cliques of rows sharing a body, chains, arrows, forests) and
//! on random ones.

use super::*;
use nalgebra::{DMatrix, DVector};

/// Deterministic pseudo-random numbers in [0, 1).
pub(super) struct Lcg(pub(super) u64);
impl Lcg {
    pub(super) fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Lower CSC (with diagonal) of the symmetric matrix `a`, keeping the
/// entries where `keep` (a symmetric pattern) holds.
fn lower_csc(a: &DMatrix<f64>, keep: &DMatrix<bool>) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let n = a.nrows();
    let (mut cp, mut ri, mut v) = (vec![0], Vec::new(), Vec::new());
    for c in 0..n {
        for r in c..n {
            if r == c || keep[(r, c)] {
                ri.push(r);
                v.push(a[(r, c)]);
            }
        }
        cp.push(ri.len());
    }
    (cp, ri, v)
}

/// A = G Gᵀ + shift·I for a sparse G whose rows are the "rows of C" and
/// whose columns are grouped in bodies: rows touching a common body couple,
/// as in the Eq. 7 matrix.
pub(super) fn gram_like(
    edges: &[(usize, usize)],
    rows_per_edge: usize,
    bodies: usize,
    seed: u64,
) -> DMatrix<f64> {
    let mut rng = Lcg(seed);
    let n = edges.len() * rows_per_edge;
    let mut g = DMatrix::zeros(n, 7 * bodies);
    for (e, &(b0, b1)) in edges.iter().enumerate() {
        for r in 0..rows_per_edge {
            for b in [b0, b1] {
                for c in 0..7 {
                    g[(e * rows_per_edge + r, 7 * b + c)] = rng.next() - 0.5;
                }
            }
        }
    }
    &g * g.transpose() + DMatrix::identity(n, n) * 0.1
}

/// Factors `a` and solves k right-hand sides with the baseline kernels and
/// (where the CPU has them) the AVX2 + FMA kernels, each against nalgebra's
/// dense Cholesky.
fn check(a: &DMatrix<f64>, k: usize) {
    let n = a.nrows();
    let keep = a.map(|x| x != 0.0);
    let (cp, ri, v) = lower_csc(a, &keep);
    let mut f = Cholesky::analyze(n, &cp, &ri, 3).unwrap();
    let reg = Regularization {
        epsilon: 0.0,
        delta: 0.0,
    };
    let chol = a.clone().cholesky().expect("SPD");
    let mut rng = Lcg(7);
    let b: Vec<f64> = (0..n * k).map(|_| rng.next() - 0.5).collect();
    for simd in [false, true] {
        f.set_simd(simd);
        f.factor(&v, reg).unwrap();
        assert_eq!(f.regularized, 0);
        let mut x = b.clone();
        f.solve(&mut x, k);
        for t in 0..k {
            let want = chol.solve(&DVector::from_column_slice(&b[t * n..(t + 1) * n]));
            let got = DVector::from_column_slice(&x[t * n..(t + 1) * n]);
            let err = (&got - &want).amax() / want.amax().max(1e-300);
            assert!(
                err < 1e-10,
                "n {n}, rhs {t}, simd {simd}: relative error {err:e}"
            );
        }
    }
}

#[test]
fn chains_rings_and_lattices_of_bodies_solve_exactly() {
    // A chain of 12 bodies (tree), a ring (one loop), a 6 × 5 lattice
    // (many loops), each with 3 or 4 rows per joint.
    let chain: Vec<_> = (0..11).map(|i| (i, i + 1)).collect();
    let ring: Vec<_> = (0..12).map(|i| (i, (i + 1) % 12)).collect();
    let mut lattice = Vec::new();
    for y in 0..5 {
        for x in 0..6 {
            let b = y * 6 + x;
            if x + 1 < 6 {
                lattice.push((b, b + 1));
            }
            if y + 1 < 5 {
                lattice.push((b, b + 6));
            }
        }
    }
    check(&gram_like(&chain, 3, 12, 1), 1);
    check(&gram_like(&ring, 4, 12, 2), 2);
    check(&gram_like(&lattice, 3, 30, 3), 4);
    check(&gram_like(&lattice, 4, 30, 4), 7);
}

#[test]
fn arrows_forests_and_tiny_matrices_solve_exactly() {
    // An arrow (one row coupled to all), a diagonal (a forest of single
    // nodes), 1 × 1 and 2 × 2.
    let n = 20;
    let mut arrow = DMatrix::identity(n, n) * 30.0;
    for i in 1..n {
        arrow[(i, 0)] = 1.0;
        arrow[(0, i)] = 1.0;
    }
    check(&arrow, 2);
    check(&(DMatrix::identity(9, 9) * 2.0), 3);
    check(&DMatrix::from_element(1, 1, 4.0), 1);
    check(&DMatrix::from_row_slice(2, 2, &[4.0, 1.0, 1.0, 3.0]), 2);
}

#[test]
fn random_sparse_patterns_solve_exactly() {
    for seed in 0..20u64 {
        let mut rng = Lcg(seed + 100);
        let n = 5 + (rng.next() * 60.0) as usize;
        let mut a = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            for j in 0..i {
                if rng.next() < 0.08 {
                    let v = rng.next() - 0.5;
                    a[(i, j)] = v;
                    a[(j, i)] = v;
                }
            }
        }
        // Diagonally dominant: SPD.
        for i in 0..n {
            a[(i, i)] = 1.0 + a.row(i).iter().map(|v| v.abs()).sum::<f64>();
        }
        check(&a, 1 + seed as usize % 5);
    }
}

/// A singular matrix factors through the regularisation (the replaced
/// pivots are counted) and a NaN fails with the pivot's index.
#[test]
fn pivots_follow_faers_dynamic_regularisation() {
    let a = DMatrix::from_row_slice(3, 3, &[1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 2.0]);
    let keep = a.map(|x| x != 0.0);
    let (cp, ri, mut v) = lower_csc(&a, &keep);
    let mut f = Cholesky::analyze(3, &cp, &ri, 1).unwrap();
    let reg = Regularization {
        epsilon: 1e-14,
        delta: 1e-10,
    };
    f.factor(&v, reg).unwrap();
    assert_eq!(f.regularized, 1);
    let mut x = vec![1.0, 1.0, 4.0];
    f.solve(&mut x, 1);
    assert!(x.iter().all(|v| v.is_finite()));
    assert!((x[2] - 2.0).abs() < 1e-12);
    let none = Regularization {
        epsilon: 0.0,
        delta: 0.0,
    };
    v[0] = f64::NAN;
    assert!(f.factor(&v, none).is_err());
    v[0] = -1.0;
    assert!(f.factor(&v, none).is_err());
}

#[test]
fn supernodes_group_the_rows_of_a_joint() {
    // A chain of bodies joined by 4-row joints: every joint's rows share
    // their pattern, so no supernode is narrower than a joint.
    let chain: Vec<_> = (0..11).map(|i| (i, i + 1)).collect();
    let a = gram_like(&chain, 4, 12, 9);
    let keep = a.map(|x| x != 0.0);
    let (cp, ri, _) = lower_csc(&a, &keep);
    let f = Cholesky::analyze(a.nrows(), &cp, &ri, 1).unwrap();
    assert!(
        f.sym.supernodes.iter().all(|s| s.w >= 4),
        "{:?}",
        f.sym.supernodes.iter().map(|s| s.w).collect::<Vec<_>>()
    );
}

/// Entries (row, column, value index) of the lower triangle of `a` where it
/// is non-zero (diagonal always), indexing a row-major copy of `a`.
fn entries_of(a: &DMatrix<f64>) -> (Vec<(usize, usize, usize)>, Vec<f64>) {
    let n = a.nrows();
    let mut e = Vec::new();
    for r in 0..n {
        for c in 0..=r {
            if r == c || a[(r, c)] != 0.0 {
                e.push((r, c, r * n + c));
            }
        }
    }
    let values = (0..n * n).map(|k| a[(k / n, k % n)]).collect();
    (e, values)
}

/// With the last t rows as an unfactored tail: the tail block is the Schur
/// complement, and a solve through it (here a dense Cholesky of it) solves
/// the whole system.
#[test]
fn a_tail_leaves_its_schur_complement_and_solves_through_it() {
    let mut lattice = Vec::new();
    for y in 0..4 {
        for x in 0..5 {
            let b = y * 5 + x;
            if x + 1 < 5 {
                lattice.push((b, b + 1));
            }
            if y + 1 < 4 {
                lattice.push((b, b + 5));
            }
        }
    }
    // The last edge's 3 rows (a "finger" on bodies 18, 19) are the tail;
    // and a 6-row tail on two different edges.
    for (rows, t) in [(3, 3), (3, 6)] {
        let a = gram_like(&lattice, rows, 20, 11);
        let n = a.nrows();
        let l = n - t;
        let (entries, values) = entries_of(&a);
        let mut f = Cholesky::analyze_with_tail(n, t, &entries, &[], 1).unwrap();
        let reg = Regularization {
            epsilon: 0.0,
            delta: 0.0,
        };
        f.factor(&values, reg).unwrap();
        let all = a.view((0, 0), (l, l)).into_owned();
        let a_tl = a.view((l, 0), (t, l)).into_owned();
        let schur = a.view((l, l), (t, t)).into_owned()
            - &a_tl * all.clone().cholesky().unwrap().solve(&a_tl.transpose());
        let block = f.tail_block();
        for r in 0..t {
            for c in 0..=r {
                let err = (block[r * t + c] - schur[(r, c)]).abs();
                assert!(err < 1e-10 * schur.amax(), "S[{r},{c}] off by {err:e}");
            }
        }
        let b: Vec<f64> = (0..n).map(|i| (i % 5) as f64 - 2.0).collect();
        let mut x = b.clone();
        let ok = f.solve_with_tail(&mut x, |s, xt| {
            let sm = DMatrix::from_fn(t, t, |r, c| s[r.max(c) * t + r.min(c)]);
            let sol = sm
                .cholesky()
                .unwrap()
                .solve(&DVector::from_column_slice(xt));
            xt.copy_from_slice(sol.as_slice());
            true
        });
        assert!(ok);
        let want = a
            .clone()
            .cholesky()
            .unwrap()
            .solve(&DVector::from_vec(b.clone()));
        let err = (DVector::from_vec(x) - &want).amax() / want.amax();
        assert!(err < 1e-10, "tail {t}: relative error {err:e}");
        // The leading block alone.
        let mut y = b[..l].to_vec();
        f.solve(&mut y, 1);
        let want = all
            .cholesky()
            .unwrap()
            .solve(&DVector::from_column_slice(&b[..l]));
        let err = (DVector::from_vec(y) - &want).amax() / want.amax();
        assert!(err < 1e-10, "leading block: relative error {err:e}");
    }
}

/// A nested dissection order (forced, small leaves) is a permutation and
/// factors exactly: the solve through it equals a dense Cholesky's, on a
/// lattice of bodies whose cliques are given, with a finger-like tail.
#[test]
fn a_nested_dissection_order_solves_exactly() {
    let (w, h) = (9, 7);
    let mut lattice = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let b = y * w + x;
            if x + 1 < w {
                lattice.push((b, b + 1));
            }
            if y + 1 < h {
                lattice.push((b, b + w));
            }
        }
    }
    let rows = 3;
    let a = gram_like(&lattice, rows, w * h, 21);
    let n = a.nrows();
    let t = rows;
    let mut cliques = vec![Vec::new(); w * h];
    for (e, &(b0, b1)) in lattice.iter().enumerate() {
        for r in 0..rows {
            let i = e * rows + r;
            if i < n - t {
                cliques[b0].push(i);
                cliques[b1].push(i);
            }
        }
    }
    let (entries, values) = entries_of(&a);
    for leaf in [6, 20, 60] {
        let mut f = Cholesky::dissected(n, t, &entries, &cliques, leaf);
        assert_eq!(f.shape().ordering, Ordering::Dissection);
        let mut seen = vec![false; n];
        for &p in &f.sym.iperm {
            assert!(!seen[p as usize], "leaf {leaf}: {p} twice");
            seen[p as usize] = true;
        }
        f.factor(
            &values,
            Regularization {
                epsilon: 0.0,
                delta: 0.0,
            },
        )
        .unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i % 7) as f64 - 3.0).collect();
        let mut x = b.clone();
        f.solve_with_tail(&mut x, |s, xt| {
            let sm = DMatrix::from_fn(t, t, |r, c| s[r.max(c) * t + r.min(c)]);
            let sol = sm
                .cholesky()
                .unwrap()
                .solve(&DVector::from_column_slice(xt));
            xt.copy_from_slice(sol.as_slice());
        });
        let want = a.clone().cholesky().unwrap().solve(&DVector::from_vec(b));
        let err = (DVector::from_vec(x) - &want).amax() / want.amax();
        assert!(err < 1e-10, "leaf {leaf}: relative error {err:e}");
    }
}
