//! The factor with decoupled rows skipped (`Cholesky::factor_decoupled`)
//! against the full factorisation of the same pattern and against dense
//! linear algebra: rows switched off (unit diagonal, nothing off it), in
//! supernodes of their own by `analyze_grouped`, as the force solve's
//! inactive contact pairs are.

use super::tests::{Lcg, gram_like};
use super::*;
use nalgebra::{DMatrix, DVector};

/// The lower triangle's entries (row, column, value slot) on `pattern`'s
/// nonzeros and the diagonal, with the values of `a` there.
fn lower_entries(
    pattern: &DMatrix<f64>,
    a: &DMatrix<f64>,
) -> (Vec<(usize, usize, usize)>, Vec<f64>) {
    let n = pattern.nrows();
    let mut entries = Vec::new();
    let mut values = Vec::new();
    for c in 0..n {
        for r in c..n {
            if r == c || pattern[(r, c)] != 0.0 {
                entries.push((r, c, values.len()));
                values.push(a[(r, c)]);
            }
        }
    }
    (entries, values)
}

#[test]
fn skipping_decoupled_rows_gives_the_same_factor_and_solves() {
    // A table (body 0) under a row of objects touching their neighbours.
    let bodies = 12;
    let mut edges: Vec<(usize, usize)> = (1..bodies).map(|b| (0, b)).collect();
    edges.extend((1..bodies - 1).map(|b| (b, b + 1)));
    let per = 4;
    let full = gram_like(&edges, per, bodies, 11);
    let n = full.nrows();
    // The pattern is the full matrix's (it is fixed per program); the
    // values have every third pair switched off, as the assembly leaves it.
    let off: Vec<bool> = (0..edges.len()).map(|e| e % 3 != 1).collect();
    let decoupled: Vec<bool> = (0..n).map(|i| off[i / per]).collect();
    let mut a = full.clone();
    for i in 0..n {
        for j in 0..n {
            if (decoupled[i] || decoupled[j]) && i != j {
                a[(i, j)] = 0.0;
            }
        }
        if decoupled[i] {
            a[(i, i)] = 1.0;
        }
    }
    let (entries, values) = lower_entries(&full, &a);
    let groups: Vec<u32> = (0..n).map(|i| (i / per) as u32).collect();
    let reg = Regularization {
        epsilon: 0.0,
        delta: 0.0,
    };
    let dense = a.clone().cholesky().expect("SPD");
    let mut rng = Lcg(5);
    let b: Vec<f64> = (0..n * 3).map(|_| rng.next() - 0.5).collect();
    let mut grouped = Cholesky::analyze_grouped(n, 0, &entries, &[], &groups, 3).unwrap();
    let mut plain = Cholesky::analyze_with_tail(n, 0, &entries, &[], 3).unwrap();
    for simd in [false, true] {
        grouped.set_simd(simd);
        plain.set_simd(simd);
        grouped.factor_decoupled(&values, reg, &decoupled).unwrap();
        plain.factor(&values, reg).unwrap();
        // Every switched-off pair is a supernode of its own, skipped.
        let skipped = grouped.diagonal_supernodes();
        let pairs_off = off.iter().filter(|&&o| o).count();
        assert!(skipped >= pairs_off, "{skipped} < {pairs_off}");
        for k in [1, 3] {
            let (mut x, mut y) = (b[..n * k].to_vec(), b[..n * k].to_vec());
            grouped.solve(&mut x, k);
            plain.solve(&mut y, k);
            for t in 0..k {
                let col = &b[t * n..(t + 1) * n];
                let reference = dense.solve(&DVector::from_column_slice(col));
                for i in 0..n {
                    let (xi, yi, ri) = (x[t * n + i], y[t * n + i], reference[i]);
                    let scale = 1.0 + ri.abs();
                    assert!((xi - ri).abs() <= 1e-9 * scale, "{i}: {xi} vs dense {ri}");
                    assert!((xi - yi).abs() <= 1e-12 * scale, "{i}: {xi} vs full {yi}");
                }
            }
        }
        // The full factorisation after a skipped one: nothing skipped.
        grouped.factor(&values, reg).unwrap();
        assert_eq!(grouped.diagonal_supernodes(), 0);
    }
}

#[test]
fn a_mask_of_another_length_skips_nothing() {
    let full = gram_like(&[(0, 1), (1, 2)], 3, 3, 11);
    let n = full.nrows();
    let (entries, values) = lower_entries(&full, &full);
    let reg = Regularization {
        epsilon: 0.0,
        delta: 0.0,
    };
    let mut f = Cholesky::analyze_grouped(n, 0, &entries, &[], &[0, 0, 0, 1, 1, 1], 1).unwrap();
    f.factor_decoupled(&values, reg, &[true; 2]).unwrap();
    assert_eq!(f.diagonal_supernodes(), 0);
    let dense = full.clone().cholesky().expect("SPD");
    let mut x = vec![1.0; n];
    f.solve(&mut x, 1);
    let r = dense.solve(&DVector::from_element(n, 1.0));
    for i in 0..n {
        assert!((x[i] - r[i]).abs() <= 1e-10 * (1.0 + r[i].abs()));
    }
}
