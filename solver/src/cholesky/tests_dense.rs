//! The dense path against the supernodal factor of the same pattern: the
//! tail's Schur complement, solves through the tail and leading-block
//! solves agree to round-off, and a regularised pivot is replaced in both
//! (random SPD matrices with a body-clique pattern and a dense tail; the
//! fast loop's own matrices are compared in `force::tests_dense`).

use super::tests::{Lcg, gram_like};
use super::*;
use nalgebra::DMatrix;

/// (row, column, value index) of the lower triangle of `a` where it is
/// nonzero (diagonal always), and the values.
fn entries(a: &DMatrix<f64>) -> (Vec<(usize, usize, usize)>, Vec<f64>) {
    let n = a.nrows();
    let (mut e, mut v) = (Vec::new(), Vec::new());
    for c in 0..n {
        for r in c..n {
            if r == c || a[(r, c)] != 0.0 {
                e.push((r, c, v.len()));
                v.push(a[(r, c)]);
            }
        }
    }
    (e, v)
}

fn both(a: &DMatrix<f64>, tail: usize) -> (Cholesky, Cholesky, Vec<f64>) {
    let (e, v) = entries(a);
    let n = a.nrows();
    let sparse = Cholesky::analyze_small_dense(n, tail, &e, &[], &[], 1, 0, None).unwrap();
    let dense = Cholesky::analyze_small_dense(n, tail, &e, &[], &[], 1, usize::MAX, None).unwrap();
    assert!(dense.is_dense() && !sparse.is_dense());
    (sparse, dense, v)
}

fn rel(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / scale
}

/// Random SPD matrices of order 5–32 with the Eq. 7 pattern (cliques of
/// rows sharing a body) and tails of 0, 3 and 6 rows: the tail block, a
/// solve through it (the tail solved by a dense reference) and a
/// leading-block solve agree with the supernodal factor's to 1e-12.
#[test]
fn the_dense_path_agrees_with_the_supernodal_factor() {
    let reg = Regularization {
        epsilon: 1e-14,
        delta: 1e-10,
    };
    let mut rng = Lcg(11);
    let mut worst = 0.0f64;
    for (edges, rows) in [
        (vec![(0, 1), (1, 2)], 3),
        (vec![(0, 1), (1, 2), (2, 3), (3, 0)], 5),
        (vec![(0, 1), (1, 2), (2, 3), (3, 4), (4, 0), (1, 3)], 4),
        (
            vec![(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0), (0, 3)],
            4,
        ),
        (vec![(0, 1), (0, 2), (0, 3), (0, 4), (0, 5), (0, 6)], 5),
    ] {
        let bodies = 1 + edges.iter().map(|&(a, b)| a.max(b)).max().unwrap();
        let a = gram_like(&edges, rows, bodies, 3 + edges.len() as u64);
        let n = a.nrows();
        for tail in [0, 3, 6].into_iter().filter(|&t| t + 3 <= n) {
            let (mut sp, mut de, v) = both(&a, tail);
            sp.factor(&v, reg).unwrap();
            de.factor(&v, reg).unwrap();
            worst = worst.max(rel(sp.tail_block(), de.tail_block()));
            let b: Vec<f64> = (0..n).map(|_| rng.next() - 0.5).collect();
            let solve_tail = |block: &[f64], s: &mut [f64]| {
                let t = s.len();
                if t == 0 {
                    return;
                }
                let m = DMatrix::from_fn(t, t, |i, j| block[i.max(j) * t + i.min(j)]);
                let x = m
                    .lu()
                    .solve(&nalgebra::DVector::from_column_slice(s))
                    .unwrap();
                s.copy_from_slice(x.as_slice());
            };
            let (mut xs, mut xd) = (b.clone(), b.clone());
            sp.solve_with_tail(&mut xs, solve_tail);
            de.solve_with_tail(&mut xd, solve_tail);
            worst = worst.max(rel(&xs, &xd));
            // And both solve A x = b.
            let ax = &a * nalgebra::DVector::from_column_slice(&xd);
            assert!(rel(&b, ax.as_slice()) < 1e-10, "n {n}, tail {tail}");
            let lead = n - tail;
            let k = 3;
            let mut ys: Vec<f64> = (0..lead * k).map(|_| rng.next() - 0.5).collect();
            let mut yd = ys.clone();
            sp.solve(&mut ys, k);
            de.solve(&mut yd, k);
            worst = worst.max(rel(&ys, &yd));
        }
    }
    assert!(worst < 1e-12, "worst relative difference {worst:e}");
}

/// A zero pivot (two equal rows) is replaced by δ on both paths, counted
/// once, and a matrix with a NaN pivot fails on both at the same
/// column.
#[test]
fn the_dense_path_regularises_and_fails_as_the_supernodal_one() {
    let a = gram_like(&[(0, 1), (1, 2), (2, 0)], 3, 3, 5);
    let n = a.nrows();
    let mut sing = a.clone();
    for c in 0..n {
        sing[(1, c)] = sing[(0, c)];
    }
    for r in 0..n {
        sing[(r, 1)] = sing[(r, 0)];
    }
    let reg = Regularization {
        epsilon: 1e-9 * sing.amax(),
        delta: 1.0,
    };
    let (mut sp, mut de, v) = both(&sing, 2);
    sp.factor(&v, reg).unwrap();
    de.factor(&v, reg).unwrap();
    assert_eq!(sp.regularized, 1);
    assert_eq!(de.regularized, sp.regularized);
    assert!(rel(sp.tail_block(), de.tail_block()) < 1e-9);
    let mut neg = a.clone();
    neg[(4, 4)] = f64::NAN;
    let (mut sp, mut de, v) = both(&neg, 2);
    let (es, ed) = (sp.factor(&v, reg), de.factor(&v, reg));
    assert!(es.is_err());
    assert_eq!(es, ed);
}
