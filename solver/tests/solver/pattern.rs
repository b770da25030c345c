//! The sparse pattern: products agree with a dense nalgebra reference, the
//! transposed index and the faer view describe the same matrix, and wrong
//! lengths are refused.

use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{Model, ShapeError};
use nalgebra::DVector;

use crate::common::{state, state_len};

fn pseudo_random(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

fn check_products(model: &Model) {
    let (q, targets) = state(model, &pseudo_random(state_len(model), 7));
    let mut ev = model.evaluation();
    ev.evaluate(model, &q, &targets).unwrap();
    let j = ev.jacobian();
    let dense = j.to_dense();
    let x = pseudo_random(j.ncols(), 11);
    let v = pseudo_random(j.nrows(), 13);
    let scale = dense.abs().max() * 10.0;

    let mut y = vec![f64::NAN; j.nrows()];
    j.mul_vec(&x, &mut y).unwrap();
    let reference = &dense * DVector::from_column_slice(&x);
    for (a, b) in y.iter().zip(reference.iter()) {
        assert!((a - b).abs() <= 1e-14 * scale, "J·x: {a} vs {b}");
    }

    let mut z = vec![f64::NAN; j.ncols()];
    j.mul_t_vec(&v, &mut z).unwrap();
    let reference = dense.transpose() * DVector::from_column_slice(&v);
    for (a, b) in z.iter().zip(reference.iter()) {
        assert!((a - b).abs() <= 1e-14 * scale, "Jᵀ·v: {a} vs {b}");
    }

    // y += α Jᵀ v starting from x.
    let mut w = x.clone();
    j.mul_t_vec_add(-0.5, &v, &mut w).unwrap();
    for ((a, x0), b) in w.iter().zip(&x).zip(reference.iter()) {
        assert!((a - (x0 - 0.5 * b)).abs() <= 1e-14 * scale);
    }

    // Transposed index: same entries, rows ascending within each column.
    for c in 0..j.ncols() {
        let range = j.col_ptr()[c]..j.col_ptr()[c + 1];
        let rows = &j.col_rows()[range.clone()];
        assert!(rows.windows(2).all(|w| w[0] < w[1]));
        for k in range {
            let p = j.col_value_index()[k];
            assert_eq!(j.col_idx()[p], c);
            assert_eq!(dense[(j.col_rows()[k], c)], j.values()[p]);
        }
    }
    assert_eq!(j.col_ptr()[j.ncols()], j.nnz());

    // The faer view is the same matrix.
    let f = j.as_faer();
    assert_eq!((f.nrows(), f.ncols()), (j.nrows(), j.ncols()));
    for t in f.triplet_iter() {
        assert_eq!(dense[(t.row, t.col)], *t.val);
    }
}

#[test]
fn products_match_dense_reference_four_bar() {
    check_products(&four_bar());
}

#[test]
fn products_match_dense_reference_stewart() {
    check_products(&stewart());
}

#[test]
fn products_match_dense_reference_sphere_toy() {
    check_products(&sphere_toy());
}

#[test]
fn wrong_lengths_are_refused() {
    let m = four_bar();
    let ev = m.evaluation();
    let j = ev.jacobian();
    let mut y = vec![0.0; j.nrows()];
    assert_eq!(
        j.mul_vec(&[0.0; 3], &mut y),
        Err(ShapeError {
            expected: j.ncols(),
            got: 3
        })
    );
    let mut z = vec![0.0; j.ncols() + 1];
    assert_eq!(
        j.mul_t_vec(&y, &mut z),
        Err(ShapeError {
            expected: j.ncols(),
            got: j.ncols() + 1
        })
    );
}

#[test]
fn pattern_has_dense_constraint_blocks() {
    // Each row of a constraint touches the same sorted columns: rows of the
    // four-bar's spherical joint (crank, coupler) have 14 entries each.
    let m = four_bar();
    let ev = m.evaluation();
    let j = ev.jacobian();
    let rows = m.constraints()[1].rows.clone();
    let first = &j.col_idx()[j.row_ptr()[rows.start]..j.row_ptr()[rows.start + 1]];
    assert_eq!(first.len(), 14);
    assert!(first.windows(2).all(|w| w[0] < w[1]));
    for r in rows {
        assert_eq!(&j.col_idx()[j.row_ptr()[r]..j.row_ptr()[r + 1]], first);
    }
}
